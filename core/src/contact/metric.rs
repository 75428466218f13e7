//! The closeness measure of the impact-zone QP and its pre-factorized Hessian.
//!
//! E(X) = 1/2 ||X - X~||^2 + Σ_e K/2 ||(x_1 - x_2) - (x~_1 - x~_2)||^2 (Pan et al. sec.
//! 5.2) has the Hessian H = (I + K L) ⊗ I_3 with L the graph Laplacian of the mesh
//! edges: the same 1-D matrix H_s = I + K L acts on each coordinate. H_s depends only
//! on the topology, so it is factorized once per body (faer sparse Cholesky, AMD
//! ordering) when the contact stage is built; each QP then needs only sparse solves.
//! The plain measure of Harmon et al. (K = 0) has H = I and needs no solve.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, MatMut, Par, Side};

use super::ContactError;

/// H_s^-1 of one body: identity (plain closeness) or a sparse Cholesky factor.
// one per body, built once per contact solve: the size of the Identity arm costs
// nothing, a Box would cost an indirection on every use of the factor
#[allow(clippy::large_enum_variant)]
pub(crate) enum BodyMetric {
    Identity,
    Stiff {
        symbolic: SymbolicCholesky<usize>,
        values: Vec<f64>,
        stack: MemBuffer,
        /// How many right-hand sides `stack` is sized for.
        stack_columns: usize,
    },
}

impl std::fmt::Debug for BodyMetric {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BodyMetric::Identity => write!(f, "BodyMetric::Identity"),
            BodyMetric::Stiff { values, .. } => {
                write!(f, "BodyMetric::Stiff {{ nnz(L): {} }}", values.len())
            }
        }
    }
}

impl BodyMetric {
    /// H_s = I + K L for `vertices` vertices and `edges` (unique, i != j); `stiffness`
    /// K (dimensionless: relative to the unit weight of the closeness term). K = 0 gives
    /// the identity.
    pub(crate) fn new(
        vertices: usize,
        edges: &[[u32; 2]],
        stiffness: f64,
    ) -> Result<Self, ContactError> {
        if stiffness == 0.0 || vertices == 0 {
            return Ok(BodyMetric::Identity);
        }
        let mut diagonal = vec![1.0; vertices];
        let mut triplets = Vec::with_capacity(vertices + edges.len());
        for &[a, b] in edges {
            let (a, b) = (a as usize, b as usize);
            diagonal[a] += stiffness;
            diagonal[b] += stiffness;
            // lower triangle: row > column
            triplets.push(Triplet::new(a.max(b), a.min(b), -stiffness));
        }
        for (i, d) in diagonal.iter().enumerate() {
            triplets.push(Triplet::new(i, i, *d));
        }
        let h = SparseColMat::<usize, f64>::try_new_from_triplets(vertices, vertices, &triplets)
            .map_err(|e| ContactError::Factorization(format!("{e:?}")))?;
        let symbolic = factorize_symbolic_cholesky(
            h.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| ContactError::Factorization(format!("{e:?}")))?;
        let mut values = vec![0.0; symbolic.len_val()];
        let mut scratch = MemBuffer::new(
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        );
        symbolic
            .factorize_numeric_llt(
                &mut values,
                h.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut scratch),
                Default::default(),
            )
            .map_err(|e| ContactError::Factorization(format!("{e:?}")))?;
        let stack_columns = 16;
        let stack = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(stack_columns, Par::Seq));
        Ok(BodyMetric::Stiff {
            symbolic,
            values,
            stack,
            stack_columns,
        })
    }

    /// rhs <- H_s^-1 rhs for `columns` right-hand sides stored column-major (each of
    /// the body's vertex count).
    pub(crate) fn solve_in_place(&mut self, rhs: &mut [f64], columns: usize) {
        match self {
            BodyMetric::Identity => {}
            BodyMetric::Stiff {
                symbolic,
                values,
                stack,
                stack_columns,
            } => {
                if columns == 0 {
                    return;
                }
                let n = symbolic.nrows();
                if *stack_columns < columns {
                    *stack_columns = columns.next_power_of_two();
                    *stack = MemBuffer::new(
                        symbolic.solve_in_place_scratch::<f64>(*stack_columns, Par::Seq),
                    );
                }
                let llt = LltRef::new(symbolic, values);
                llt.solve_in_place_with_conj(
                    Conj::No,
                    MatMut::from_column_major_slice_mut(&mut rhs[..n * columns], n, columns),
                    Par::Seq,
                    MemStack::new(stack),
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stiff_metric_inverts_identity_plus_k_laplacian() {
        // a 4-vertex square with a diagonal
        let edges = [[0, 1], [1, 2], [2, 3], [0, 3], [0, 2]];
        let k = 100.0;
        let mut m = BodyMetric::new(4, &edges, k).unwrap();
        let mut h = nalgebra::DMatrix::<f64>::identity(4, 4);
        for [a, b] in edges {
            let (a, b) = (a as usize, b as usize);
            h[(a, a)] += k;
            h[(b, b)] += k;
            h[(a, b)] -= k;
            h[(b, a)] -= k;
        }
        let x = nalgebra::DMatrix::from_fn(4, 3, |r, c| (r * 3 + c) as f64 - 4.0);
        let mut rhs: Vec<f64> = (&h * &x).as_slice().to_vec();
        m.solve_in_place(&mut rhs, 3);
        for (got, want) in rhs.iter().zip(x.as_slice()) {
            assert!((got - want).abs() < 1e-10, "{got} vs {want}");
        }
        let mut id = BodyMetric::new(4, &edges, 0.0).unwrap();
        let mut v = vec![1.0, 2.0, 3.0, 4.0];
        id.solve_in_place(&mut v, 1);
        assert_eq!(v, [1.0, 2.0, 3.0, 4.0]);
    }
}
