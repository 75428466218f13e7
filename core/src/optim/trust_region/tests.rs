//! The trust-region method on problems with known minimizers: a convex quadratic
//! (exact), an indefinite quadratic whose minimizer has an active bound while the
//! reduced model is positive definite, the slab held exactly, and Rosenbrock with its
//! exact (indefinite away from the valley) Hessian under a bound.

use nalgebra::{DMatrix, DVector};

use super::TrustRegion;
use crate::optim::{BoxProblem, Dense, NewtonOptions, Slab};

/// f = ½ x^T H x + b^T x.
struct Quadratic {
    h: DMatrix<f64>,
    b: DVector<f64>,
}

impl BoxProblem for Quadratic {
    type Matrix = Dense;
    fn dimension(&self) -> usize {
        self.b.len()
    }
    fn evaluate(&mut self, x: &[f64], g: Option<&mut [f64]>, h: Option<&mut Dense>) -> f64 {
        let x = DVector::from_column_slice(x);
        let hx = &self.h * &x;
        if let Some(g) = g {
            g.copy_from_slice((&hx + &self.b).as_slice());
        }
        if let Some(h) = h {
            h.matrix = self.h.clone();
        }
        0.5 * x.dot(&hx) + self.b.dot(&x)
    }
}

fn options() -> NewtonOptions {
    NewtonOptions {
        max_iterations: 100,
        pgtol: 1e-12,
        ftol: 0.0,
        pgtol_relative_to_start: None,
        reuse_factorization: false,
    }
}

/// A symmetric 4x4 matrix with eigenvalues `eigenvalues` in a fixed rotated basis (the
/// Q factor of a fixed full matrix), so that every unknown is coupled.
fn coupled(eigenvalues: [f64; 4]) -> DMatrix<f64> {
    let a = DMatrix::from_row_slice(
        4,
        4,
        &[
            1.0, 0.3, -0.2, 0.5, 0.4, 1.0, 0.1, -0.3, -0.6, 0.2, 1.0, 0.2, 0.1, -0.5, 0.3, 1.0,
        ],
    );
    let q = a.qr().q();
    &q * DMatrix::from_diagonal(&DVector::from_row_slice(&eigenvalues)) * q.transpose()
}

#[test]
fn a_convex_quadratic_in_a_box_reaches_its_exact_minimizer() {
    // unconstrained minimizer -H^-1 b, with x_0 beyond its upper bound 0.1 (checked):
    // the constrained one holds x_0 = 0.1 and solves H_FF x_F = -(b_F + H_F0 0.1)
    let h = coupled([0.5, 1.0, 3.0, 10.0]);
    let b = DVector::from_row_slice(&[-2.0, 1.0, 0.5, -0.3]);
    let free_min = -h.clone().lu().solve(&b).unwrap();
    assert!(
        free_min[0] > 0.1,
        "x_0 must want to leave the box: {free_min}"
    );
    let f = [1, 2, 3];
    let h_ff = DMatrix::from_fn(3, 3, |r, c| h[(f[r], f[c])]);
    let rhs = DVector::from_fn(3, |r, _| -(b[f[r]] + h[(f[r], 0)] * 0.1));
    let x_f = h_ff.cholesky().unwrap().solve(&rhs);
    let mut problem = Quadratic { h, b };
    let mut x = [0.0; 4];
    let lower = [-5.0; 4];
    let upper = [0.1, 5.0, 5.0, 5.0];
    let r = TrustRegion::<Dense>::new().minimize(
        &mut problem,
        &mut x,
        &lower,
        &upper,
        None,
        &options(),
    );
    assert!(r.converged, "{r:?}");
    assert_eq!(x[0], 0.1, "{x:?}");
    // the model is exact, so the last step is the exact Newton step on the free set:
    // agreement at the round-off of a 3x3 solve with condition number 20
    for (r, &i) in f.iter().enumerate() {
        assert!((x[i] - x_f[r]).abs() < 1e-13, "{x:?} vs {x_f}");
    }
    // an exact model: every step's ratio is 1, so none is rejected and the radius only
    // grows (0.1 doubling to the minimizer's distance, then one Newton step)
    assert_eq!(r.evaluations, r.iterations + 1, "{r:?}");
}

/// The indefinite quadratic of the next tests: eigenvalues -2, 1, 2, 5 (the negative
/// one's direction has a large x_0 component), x_0 in [-1, 1].
fn indefinite() -> Quadratic {
    Quadratic {
        h: coupled([-2.0, 1.0, 2.0, 5.0]),
        b: DVector::from_row_slice(&[0.3, -0.4, 0.2, 0.1]),
    }
}

/// The minimizer of `indefinite()` with x_0 held at `x0` (the reduced matrix is
/// positive definite: checked), and f there.
fn held_minimizer(x0: f64) -> (DVector<f64>, f64) {
    let mut q = indefinite();
    let f = [1, 2, 3];
    let h_ff = DMatrix::from_fn(3, 3, |r, c| q.h[(f[r], f[c])]);
    let rhs = DVector::from_fn(3, |r, _| -(q.b[f[r]] + q.h[(f[r], 0)] * x0));
    let x_f = h_ff
        .cholesky()
        .expect("the reduced matrix is positive definite")
        .solve(&rhs);
    let x = DVector::from_row_slice(&[x0, x_f[0], x_f[1], x_f[2]]);
    let value = q.evaluate(x.as_slice(), None, None);
    (x, value)
}

#[test]
fn an_indefinite_quadratic_ends_on_the_bound_its_negative_curvature_points_to() {
    // H stays indefinite at every x: the minimizer in the box has x_0 on a bound, the
    // others at the reduced model's (positive definite) minimizer. Of the two bounds,
    // both local minimizers, the solver must reach one exactly and be stationary there.
    let q = indefinite();
    assert!(q.h.clone().symmetric_eigen().eigenvalues.min() < -1.9);
    let lower = [-1.0, -10.0, -10.0, -10.0];
    let upper = [1.0, 10.0, 10.0, 10.0];
    for start in [[0.05, 0.0, 0.0, 0.0], [-0.05, 0.0, 0.0, 0.0]] {
        let mut x = start;
        let r = TrustRegion::<Dense>::new().minimize(
            &mut indefinite(),
            &mut x,
            &lower,
            &upper,
            None,
            &options(),
        );
        assert!(r.converged, "{r:?}");
        assert!(x[0] == 1.0 || x[0] == -1.0, "x_0 not on a bound: {x:?}");
        let (expected, value) = held_minimizer(x[0]);
        for i in 0..4 {
            assert!((x[i] - expected[i]).abs() < 1e-12, "{x:?} vs {expected}");
        }
        assert!(
            (r.f - value).abs() < 1e-13 * value.abs().max(1.0),
            "{r:?} vs {value}"
        );
    }
}

#[test]
fn the_slab_is_held_exactly_at_the_face_minimizer() {
    // a convex quadratic whose unconstrained minimizer (0.2, 1, 0.8, 1.1) has
    // x_1 + x_2 + x_3 = 2.9 > 1: the minimizer on the face a.x = 1 is
    // -H^-1 (b + lambda a) with lambda from a.x = 1
    let h = coupled([0.5, 1.0, 3.0, 10.0]);
    let b = -(&h * DVector::from_row_slice(&[0.2, 1.0, 0.8, 1.1]));
    let a = DVector::from_row_slice(&[0.0, 1.0, 1.0, 1.0]);
    let lu = h.clone().lu();
    let x_free = -lu.solve(&b).unwrap();
    assert!(a.dot(&x_free) > 1.5, "the slab must bind: {x_free}");
    let y = lu.solve(&a).unwrap();
    let lambda = (-1.0 - a.dot(&lu.solve(&b).unwrap())) / a.dot(&y);
    let expected = -lu.solve(&(&b + &a * lambda)).unwrap();
    let slab = Slab {
        range: 1..4,
        bound: 1.0,
    };
    let mut x = [0.0; 4];
    let r = TrustRegion::<Dense>::new().minimize(
        &mut Quadratic { h, b },
        &mut x,
        &[-10.0; 4],
        &[10.0; 4],
        Some(slab.clone()),
        &options(),
    );
    assert!(r.converged, "{r:?}");
    assert!(slab.sum(&x) <= 1.0, "outside the slab: {}", slab.sum(&x));
    assert!(
        (slab.sum(&x) - 1.0).abs() < 4.0 * f64::EPSILON,
        "{}",
        slab.sum(&x)
    );
    for i in 0..4 {
        assert!((x[i] - expected[i]).abs() < 1e-12, "{x:?} vs {expected}");
    }
}

/// Rosenbrock 100 (y - x^2)^2 + (1 - x)^2 with its exact Hessian (indefinite where
/// y > x^2 + 1/200).
struct Rosenbrock;

impl BoxProblem for Rosenbrock {
    type Matrix = Dense;
    fn dimension(&self) -> usize {
        2
    }
    fn evaluate(&mut self, x: &[f64], g: Option<&mut [f64]>, h: Option<&mut Dense>) -> f64 {
        let (a, b) = (x[0], x[1]);
        let r = b - a * a;
        if let Some(g) = g {
            g[0] = -400.0 * a * r - 2.0 * (1.0 - a);
            g[1] = 200.0 * r;
        }
        if let Some(h) = h {
            h.matrix = DMatrix::from_row_slice(
                2,
                2,
                &[
                    1200.0 * a * a - 400.0 * b + 2.0,
                    -400.0 * a,
                    -400.0 * a,
                    200.0,
                ],
            );
        }
        100.0 * r * r + (1.0 - a) * (1.0 - a)
    }
}

#[test]
fn rosenbrock_with_its_exact_hessian_reaches_the_bound_minimizer() {
    // from (-0.5, 1) the Hessian is indefinite (y > x^2 + 1/200 there: checked); with
    // x <= 0.5 the minimizer is (0.5, 0.25), on the bound, where y = x^2
    let mut h = Dense::default();
    Rosenbrock.evaluate(&[-0.5, 1.0], None, Some(&mut h));
    assert!(h.matrix.clone().symmetric_eigen().eigenvalues.min() < 0.0);
    let mut x = [-0.5, 1.0];
    let r = TrustRegion::<Dense>::new().minimize(
        &mut Rosenbrock,
        &mut x,
        &[-10.0, -10.0],
        &[0.5, 10.0],
        None,
        &options(),
    );
    assert!(r.converged, "{r:?}");
    assert_eq!(x[0], 0.5);
    // pg <= 1e-12 on the free y: |200 (y - 0.25)| <= 1e-12
    assert!((x[1] - 0.25).abs() < 1e-14, "{x:?}");
}

#[test]
fn the_damped_projected_newton_method_reaches_the_same_bound_minimizers() {
    // the baseline's globalization (Levenberg-Marquardt shift, line search) on the
    // problem that stays indefinite with an active bound, as the trust region above
    use crate::optim::ProjectedNewton;
    let lower = [-1.0, -10.0, -10.0, -10.0];
    let upper = [1.0, 10.0, 10.0, 10.0];
    for start in [[0.05, 0.0, 0.0, 0.0], [-0.05, 0.0, 0.0, 0.0]] {
        let mut x = start;
        let r = ProjectedNewton::<Dense>::new().minimize(
            &mut indefinite(),
            &mut x,
            &lower,
            &upper,
            &NewtonOptions {
                // above the 1e-9 relative damping's residue on the free unknowns
                pgtol: 1e-9,
                ..options()
            },
        );
        assert!(r.converged, "{r:?}");
        assert!(x[0] == 1.0 || x[0] == -1.0, "x_0 not on a bound: {x:?}");
        let (expected, _) = held_minimizer(x[0]);
        // |x - x*| <= pg / lambda_min(H_FF), lambda_min(H_FF) >= 1 (interlacing: the
        // reduced matrix's least eigenvalue is at least H's second, 1)
        for i in 0..4 {
            assert!((x[i] - expected[i]).abs() < 1e-9, "{x:?} vs {expected}");
        }
    }
}

/// The slab test's problem: a convex quadratic whose unconstrained minimizer has
/// x_1 + x_2 + x_3 = 2.9 > 1, and its minimizer on the face a.x = 1 (H x + b + λ a = 0,
/// a.x = 1), the slab |x_1 + x_2 + x_3| <= 1.
fn slab_problem() -> (Quadratic, DVector<f64>, Slab) {
    let h = coupled([0.5, 1.0, 3.0, 10.0]);
    let b = -(&h * DVector::from_row_slice(&[0.2, 1.0, 0.8, 1.1]));
    let a = DVector::from_row_slice(&[0.0, 1.0, 1.0, 1.0]);
    let lu = h.clone().lu();
    let y = lu.solve(&a).unwrap();
    let lambda = (-1.0 - a.dot(&lu.solve(&b).unwrap())) / a.dot(&y);
    let expected = -lu.solve(&(&b + &a * lambda)).unwrap();
    let slab = Slab {
        range: 1..4,
        bound: 1.0,
    };
    (Quadratic { h, b }, expected, slab)
}

#[test]
fn the_damped_projected_newton_method_holds_the_slab_at_the_face_minimizer() {
    // `solver.end_crease_exact` in the damped solver: the face held in the Newton step
    // (one more solve) and every trial projected onto box and slab
    use crate::optim::ProjectedNewton;
    let (mut problem, expected, slab) = slab_problem();
    let options = NewtonOptions {
        // above the 1e-12 relative damping's residue on the free unknowns
        pgtol: 1e-10,
        ..options()
    };
    let mut newton = ProjectedNewton::<Dense>::new();
    newton.set_slab(Some(slab.clone()));
    let mut x = [0.0; 4];
    let r = newton.minimize(&mut problem, &mut x, &[-10.0; 4], &[10.0; 4], &options);
    assert!(r.converged, "{r:?}");
    assert!(slab.sum(&x) <= 1.0, "outside the slab: {}", slab.sum(&x));
    assert!(
        (slab.sum(&x) - 1.0).abs() < 4.0 * f64::EPSILON,
        "{}",
        slab.sum(&x)
    );
    // |x - x*| <= pg / lambda_min of H on the face (>= 0.5, H's least eigenvalue) =
    // 2e-10 bounds it; measured 1.9e-12 (the last step is a Newton step on the face
    // at a damping of 1e-9 of the diagonal)
    for i in 0..4 {
        assert!((x[i] - expected[i]).abs() < 1e-11, "{x:?} vs {expected}");
    }
    // negative control: the same solver without the slab ends outside it, at the
    // unconstrained minimizer (so the checks above see whether the slab is held)
    let mut x = [0.0; 4];
    let r = ProjectedNewton::<Dense>::new().minimize(
        &mut problem,
        &mut x,
        &[-10.0; 4],
        &[10.0; 4],
        &options,
    );
    assert!(r.converged, "{r:?}");
    assert!(slab.sum(&x) > 2.8, "{}", slab.sum(&x));
}

#[test]
fn the_damped_method_with_the_slab_ends_on_a_bound_and_a_face_of_an_indefinite_quadratic() {
    // indefinite() (eigenvalues -2, 1, 2, 5) with x_0 in [-1, 1] and |x_1 + x_2 + x_3|
    // <= 0.05: x_0 ends on a bound (the negative curvature's), the others at the
    // minimizer of the reduced (positive definite) model on a face of the slab, from
    // the KKT system [[H_FF, a], [a^T, 0]] [x_F; λ] = [-(b_F + H_F0 x_0); ±0.05] with
    // the face's multiplier binding (H x + b + λ a = 0 with λ of the face's sign: the
    // reduced minimizer without the slab is beyond that face)
    use crate::optim::ProjectedNewton;
    let slab = Slab {
        range: 1..4,
        bound: 0.05,
    };
    let lower = [-1.0, -10.0, -10.0, -10.0];
    let upper = [1.0, 10.0, 10.0, 10.0];
    let kkt = |x0: f64, face: f64| -> (DVector<f64>, f64) {
        let q = indefinite();
        let mut k = DMatrix::zeros(4, 4);
        let mut rhs = DVector::zeros(4);
        for r in 0..3 {
            for c in 0..3 {
                k[(r, c)] = q.h[(r + 1, c + 1)];
            }
            k[(r, 3)] = 1.0;
            k[(3, r)] = 1.0;
            rhs[r] = -(q.b[r + 1] + q.h[(r + 1, 0)] * x0);
        }
        rhs[3] = face * 0.05;
        let s = k.lu().solve(&rhs).expect("the KKT matrix is regular");
        (DVector::from_row_slice(&[x0, s[0], s[1], s[2]]), s[3])
    };
    for start in [[0.05, 0.0, 0.0, 0.0], [-0.05, 0.0, 0.0, 0.0]] {
        let mut newton = ProjectedNewton::<Dense>::new();
        newton.set_slab(Some(slab.clone()));
        let mut x = start;
        let r = newton.minimize(
            &mut indefinite(),
            &mut x,
            &lower,
            &upper,
            &NewtonOptions {
                pgtol: 1e-10,
                ..options()
            },
        );
        assert!(r.converged, "{r:?}");
        assert!(x[0] == 1.0 || x[0] == -1.0, "x_0 not on a bound: {x:?}");
        let face = slab.face(&x);
        assert!(face != 0.0, "not on a face: {x:?}");
        let (expected, lambda) = kkt(x[0], face);
        assert!(lambda * face > 0.0, "the face does not bind: λ = {lambda}");
        // |x - x*| <= pg / lambda_min of the reduced matrix on the face (>= 1, by
        // interlacing), pg <= 1e-9 where the solve stops (its predicted decrease below
        // f's round-off): measured 3.5e-10
        for i in 0..4 {
            assert!((x[i] - expected[i]).abs() < 1e-9, "{x:?} vs {expected}");
        }
        // negative control: without the slab the same solve ends beyond it
        let mut y = start;
        ProjectedNewton::<Dense>::new().minimize(
            &mut indefinite(),
            &mut y,
            &lower,
            &upper,
            &options(),
        );
        assert!(slab.sum(&y).abs() > 0.1, "{y:?}");
    }
}
