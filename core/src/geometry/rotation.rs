//! SO(3) helpers on rotation vectors (axis * angle, rad).

use super::{Matrix3, Vector3};

/// The cross-product matrix: `skew(a) * b == a.cross(&b)`.
pub fn skew(a: &Vector3) -> Matrix3 {
    Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

/// Rodrigues' formula: the rotation matrix of rotation vector `w` (rad).
pub fn exp_so3(w: &Vector3) -> Matrix3 {
    let theta2 = w.norm_squared();
    let k = skew(w);
    let (a, b) = if theta2 < 1e-12 {
        // Taylor series: sin(t)/t ~ 1 - t^2/6, (1-cos t)/t^2 ~ 1/2 - t^2/24.
        (1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0)
    } else {
        let theta = theta2.sqrt();
        (theta.sin() / theta, (1.0 - theta.cos()) / theta2)
    };
    Matrix3::identity() + k * a + k * k * b
}

/// Left Jacobian of SO(3): the world angular velocity is `left_jacobian_so3(w) * dw/dt`
/// for `R = exp_so3(w)`.
pub fn left_jacobian_so3(w: &Vector3) -> Matrix3 {
    let theta2 = w.norm_squared();
    let k = skew(w);
    let (a, b) = if theta2 < 1e-12 {
        (0.5 - theta2 / 24.0, 1.0 / 6.0 - theta2 / 120.0)
    } else {
        let theta = theta2.sqrt();
        (
            (1.0 - theta.cos()) / theta2,
            (theta - theta.sin()) / (theta2 * theta),
        )
    };
    Matrix3::identity() + k * a + k * k * b
}

/// Rotation vector of a rotation matrix (angle in [0, pi]).
pub fn log_so3(r: &Matrix3) -> Vector3 {
    let vee = Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    ) * 0.5;
    let cos = ((r.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
    let sin = vee.norm();
    if sin < 1e-6 && cos > 0.0 {
        // near identity: theta ~ sin, first-order series keeps full precision
        return vee * (1.0 + sin * sin / 6.0);
    }
    if cos < -0.99 {
        // near pi: the antisymmetric part vanishes; nalgebra takes the axis from the
        // symmetric part.
        return nalgebra::Rotation3::from_matrix_unchecked(*r).scaled_axis();
    }
    let theta = sin.atan2(cos);
    vee * (theta / sin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_matches_nalgebra_and_is_orthonormal() {
        for w in [
            Vector3::new(0.3, -0.2, 0.9),
            Vector3::new(1e-9, 0.0, 2e-9),
            Vector3::new(0.0, 3.0, 0.0),
        ] {
            let r = exp_so3(&w);
            let expected = nalgebra::Rotation3::new(w);
            assert!((r - expected.matrix()).norm() < 1e-12);
            assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-12);
            assert!((exp_so3(&log_so3(&r)) - r).norm() < 1e-12);
            if w.norm() > 1e-6 {
                assert!((log_so3(&r) - w).norm() < 1e-12);
            }
        }
    }

    #[test]
    fn left_jacobian_matches_finite_differences() {
        let w = Vector3::new(0.7, -1.1, 0.4);
        let r = exp_so3(&w);
        let jl = left_jacobian_so3(&w);
        let h = 1e-6;
        for i in 0..3 {
            let mut e = Vector3::zeros();
            e[i] = h;
            let dr = (exp_so3(&(w + e)) - exp_so3(&(w - e))) / (2.0 * h);
            // dR R^T = skew(omega)
            let omega_hat = dr * r.transpose();
            let omega = Vector3::new(omega_hat[(2, 1)], omega_hat[(0, 2)], omega_hat[(1, 0)]);
            assert!((omega - jl.column(i)).norm() < 1e-7, "column {i}");
        }
    }
}
