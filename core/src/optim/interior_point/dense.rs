//! The dense Newton matrix as the interior-point method's (small problems, tests).

use nalgebra::{DMatrix, DVector};

use super::BarrierMatrix;
use crate::optim::Dense;

impl BarrierMatrix for Dense {
    fn factor_shifted(
        &mut self,
        shift: &[f64],
        face: Option<(std::ops::Range<usize>, f64)>,
    ) -> bool {
        let n = self.matrix.nrows();
        let m = DMatrix::from_fn(n, n, |i, j| {
            let mut v = self.matrix[(i, j)] + if i == j { shift[i] } else { 0.0 };
            if let Some((range, rho)) = &face {
                if range.contains(&i) && range.contains(&j) {
                    v += rho;
                }
            }
            v
        });
        self.barrier = m.cholesky();
        self.barrier.is_some()
    }

    fn solve_shifted(&mut self, rhs: &[f64], out: &mut [f64]) -> bool {
        let Some(factor) = &self.barrier else {
            return false;
        };
        let x = factor.solve(&DVector::from_column_slice(rhs));
        out.copy_from_slice(x.as_slice());
        out.iter().all(|v| v.is_finite())
    }
}
