//! The 2x2 pivots of the chain's sweep: the inverse of a positive definite one, and
//! issue 47's saddle-free variant (`solver.saddle_free`), which replaces a pivot that
//! is not positive definite by its eigenvalues' absolute values instead of failing.

use nalgebra::Matrix2;

use super::ChainModel;

impl ChainModel {
    /// Saddle-free pivots in the next factorizations (issue 47): a crease's 2x2 pivot
    /// whose least eigenvalue is below `floor` times its stage's scale (the largest
    /// entry of its pivot and coupling rows) is replaced by its eigenvalues' absolute
    /// values, floored there, instead of failing the factorization. 0: off.
    pub fn set_saddle_free(&mut self, floor: f64) {
        self.saddle_floor = floor;
    }
}

/// The inverse of |m| with its eigenvalues floored at `floor`: m = V diag(λ) V^T ->
/// V diag(1 / max(|λ|, floor)) V^T (m's own inverse where its least eigenvalue is
/// above `floor`). None if not finite.
pub(super) fn saddle_free_inverse_2x2(m: &Matrix2<f64>, floor: f64) -> Option<Matrix2<f64>> {
    let (a, b, d) = (m[(0, 0)], m[(0, 1)], m[(1, 1)]);
    let half = 0.5 * (a - d);
    let root = (half * half + b * b).sqrt();
    let mean = 0.5 * (a + d);
    let least = mean - root;
    if least > floor {
        return spd_inverse_2x2(m);
    }
    if !(least.is_finite() && floor.is_finite()) {
        return None;
    }
    let eigen = m.symmetric_eigen();
    let mut inv = Matrix2::zeros();
    for i in 0..2 {
        let v = eigen.eigenvectors.column(i);
        let l = eigen.eigenvalues[i].abs().max(floor).max(f64::MIN_POSITIVE);
        inv += v * v.transpose() / l;
    }
    Some(inv)
}

/// The inverse of a symmetric 2x2 matrix if it is positive definite (both Cholesky
/// pivots positive), else None.
pub(super) fn spd_inverse_2x2(m: &Matrix2<f64>) -> Option<Matrix2<f64>> {
    let (a, b, d) = (m[(0, 0)], m[(0, 1)], m[(1, 1)]);
    let det = a * d - b * b;
    if !(a > 0.0 && det > 0.0 && det.is_finite()) {
        return None;
    }
    Some(Matrix2::new(d, -b, -b, a) / det)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_saddle_free_pivot_is_the_inverse_of_its_absolute_value() {
        // m = R diag(-2, 3) R^T (R a rotation by 0.3 rad): |m|^-1 = R diag(1/2, 1/3) R^T
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let r = Matrix2::new(c, -s, s, c);
        let m = r * Matrix2::new(-2.0, 0.0, 0.0, 3.0) * r.transpose();
        assert!(spd_inverse_2x2(&m).is_none(), "m is indefinite");
        let expected = r * Matrix2::new(0.5, 0.0, 0.0, 1.0 / 3.0) * r.transpose();
        let inv = saddle_free_inverse_2x2(&m, 1e-6).expect("finite");
        // a 2x2 eigendecomposition: a few ulp of entries of order 1
        assert!((inv - expected).amax() < 1e-15, "{inv} vs {expected}");
        // the floor: a pivot with eigenvalues 1e-9 and 3 gets 1e-6 for the first
        let tiny = r * Matrix2::new(1e-9, 0.0, 0.0, 3.0) * r.transpose();
        let inv = saddle_free_inverse_2x2(&tiny, 1e-6).expect("finite");
        let floored = r * Matrix2::new(1e6, 0.0, 0.0, 1.0 / 3.0) * r.transpose();
        assert!((inv - floored).amax() < 1e-9, "{inv} vs {floored}");
        // negative control: a positive definite pivot above the floor is inverted as is
        let spd = r * Matrix2::new(2.0, 0.0, 0.0, 3.0) * r.transpose();
        assert_eq!(saddle_free_inverse_2x2(&spd, 1e-6), spd_inverse_2x2(&spd));
        assert!(
            (saddle_free_inverse_2x2(&m, 1e-6).unwrap() - m.try_inverse().unwrap()).amax() > 0.1
        );
    }
}
