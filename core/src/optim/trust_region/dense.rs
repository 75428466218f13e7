//! The dense Newton matrix as a trust-region model: for small problems and the tests
//! (O(n^3) a factorization, an eigendecomposition for the direction of negative
//! curvature; it allocates per factorization).

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

use super::ModelMatrix;
use crate::optim::Dense;

/// What [`Dense`] keeps of its last [`ModelMatrix::factor_free`].
#[derive(Clone, Debug, Default)]
pub(crate) struct DenseModel {
    /// The free unknowns, in order.
    index: Vec<usize>,
    /// The factorized matrix on them (kept for the eigendecomposition).
    reduced: Option<DMatrix<f64>>,
    factor: Option<Cholesky<f64, Dyn>>,
}

impl ModelMatrix for Dense {
    fn multiply(&mut self, v: &[f64], out: &mut [f64]) {
        let product = &self.matrix * DVector::from_column_slice(v);
        out.copy_from_slice(product.as_slice());
    }

    fn factor_free(
        &mut self,
        free: &[bool],
        shift: f64,
        face: Option<(std::ops::Range<usize>, f64)>,
    ) -> bool {
        let model = &mut self.model;
        model.index.clear();
        model.index.extend((0..free.len()).filter(|&i| free[i]));
        let idx = &model.index;
        let m = idx.len();
        let reduced = DMatrix::from_fn(m, m, |r, c| {
            let (i, j) = (idx[r], idx[c]);
            let mut v = self.matrix[(i, j)] + if r == c { shift } else { 0.0 };
            if let Some((range, rho)) = &face {
                if range.contains(&i) && range.contains(&j) {
                    v += rho;
                }
            }
            v
        });
        model.factor = reduced.clone().cholesky();
        model.reduced = Some(reduced);
        model.factor.is_some()
    }

    fn failed_pivot(&self) -> Option<f64> {
        if self.model.factor.is_some() {
            return None;
        }
        let reduced = self.model.reduced.clone()?;
        Some(reduced.symmetric_eigen().eigenvalues.min())
    }

    fn solve_free(&mut self, rhs: &[f64], out: &mut [f64]) -> bool {
        let model = &self.model;
        let Some(factor) = &model.factor else {
            return false;
        };
        let b = DVector::from_iterator(model.index.len(), model.index.iter().map(|&i| rhs[i]));
        let x = factor.solve(&b);
        out.fill(0.0);
        for (r, &i) in model.index.iter().enumerate() {
            out[i] = x[r];
        }
        out.iter().all(|v| v.is_finite())
    }
}
