//! The interior-point method on problems with known minimizers (those of the trust
//! region's tests): a convex quadratic in a box against its KKT point, an indefinite
//! quadratic whose minimizer has an active bound (inertia correction needed at the
//! start), the slab's face, and negative controls.

use nalgebra::{DMatrix, DVector};

use super::InteriorPoint;
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

/// A symmetric 4x4 matrix with eigenvalues `eigenvalues` in a fixed rotated basis.
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

/// The minimizer of ½ x^T H x + b^T x with x_0 held at `x0` (H's reduced block on
/// x_1..x_3 positive definite: checked).
fn held_minimizer(h: &DMatrix<f64>, b: &DVector<f64>, x0: f64) -> DVector<f64> {
    let f = [1, 2, 3];
    let h_ff = DMatrix::from_fn(3, 3, |r, c| h[(f[r], f[c])]);
    let rhs = DVector::from_fn(3, |r, _| -(b[f[r]] + h[(f[r], 0)] * x0));
    let x_f = h_ff
        .cholesky()
        .expect("the reduced matrix is positive definite")
        .solve(&rhs);
    DVector::from_row_slice(&[x0, x_f[0], x_f[1], x_f[2]])
}

#[test]
fn a_convex_quadratic_in_a_box_reaches_its_kkt_point() {
    // the unconstrained minimizer has x_0 beyond its upper bound 0.1: the KKT point
    // holds x_0 = 0.1 with a positive multiplier -(H x + b)_0 and the rest stationary
    let h = coupled([0.5, 1.0, 3.0, 10.0]);
    let b = DVector::from_row_slice(&[-2.0, 1.0, 0.5, -0.3]);
    let free_min = -h.clone().lu().solve(&b).unwrap();
    assert!(
        free_min[0] > 0.1,
        "x_0 must want to leave the box: {free_min}"
    );
    let expected = held_minimizer(&h, &b, 0.1);
    let multiplier = -(&h * &expected + &b)[0];
    assert!(multiplier > 0.1, "the bound binds: {multiplier}");
    let mut problem = Quadratic { h, b };
    let lower = [-5.0; 4];
    let upper = [0.1, 5.0, 5.0, 5.0];
    let mut ipm = InteriorPoint::<Dense>::new();
    let mut x = [0.0; 4];
    let r = ipm.minimize(&mut problem, &mut x, &lower, &upper, None, &options());
    assert!(r.converged, "{r:?}");
    assert!(r.projected_gradient_inf <= 1e-12, "{r:?}");
    // strictly inside, within pgtol of the bound (the projected gradient's x_0
    // component is the slack there), the rest stationary: |x - x*| <= pg / λ_min(H)
    // = 2e-12 (λ_min = 0.5); measured 3.5e-14
    assert!(x[0] < 0.1 && 0.1 - x[0] <= 1e-12, "{x:?}");
    for i in 0..4 {
        assert!((x[i] - expected[i]).abs() < 2e-12, "{x:?} vs {expected}");
    }
    // the bound's dual converged to the KKT multiplier (measured 2e-14 relative; its
    // error is H's row times x's, 10 x 2e-12 at most)
    assert!(
        (ipm.zu[0] - multiplier).abs() < 2e-11,
        "{} vs {multiplier}",
        ipm.zu[0]
    );
}

/// Eigenvalues -2, 1, 2, 5, the negative one's direction with a large x_0 component;
/// x_0 in [-1, 1].
fn indefinite() -> Quadratic {
    Quadratic {
        h: coupled([-2.0, 1.0, 2.0, 5.0]),
        b: DVector::from_row_slice(&[0.3, -0.4, 0.2, 0.1]),
    }
}

#[test]
fn an_indefinite_quadratic_ends_on_the_bound_its_negative_curvature_points_to() {
    // H is indefinite at every x, and H + Σ is at the start (Σ = μ/s^2 is small in
    // the middle of the box): the inertia correction must act; the minimizer holds
    // x_0 on a bound, the others at the reduced (positive definite) minimizer
    let q = indefinite();
    assert!(q.h.clone().symmetric_eigen().eigenvalues.min() < -1.9);
    let lower = [-1.0, -10.0, -10.0, -10.0];
    let upper = [1.0, 10.0, 10.0, 10.0];
    for start in [[0.05, 0.0, 0.0, 0.0], [-0.05, 0.0, 0.0, 0.0]] {
        let mut ipm = InteriorPoint::<Dense>::new();
        let mut x = start;
        let r = ipm.minimize(&mut indefinite(), &mut x, &lower, &upper, None, &options());
        assert!(r.converged, "{r:?}");
        assert!(
            ipm.counts.corrected > 0,
            "no inertia correction: {:?}",
            ipm.counts
        );
        let bound = x[0].signum();
        assert!((x[0] - bound).abs() <= 1e-12, "x_0 not at a bound: {x:?}");
        let expected = held_minimizer(&q.h, &q.b, bound);
        // |x - x*| <= pg / λ_min(H_FF) = 1e-12 (λ_min(H_FF) >= 1 by interlacing) plus
        // x_0's slack, 1e-12; measured 1.4e-14
        for i in 0..4 {
            assert!((x[i] - expected[i]).abs() < 2e-12, "{x:?} vs {expected}");
        }
        // the bound's multiplier has the sign of a minimizer (pushes outward)
        let g0 = (&q.h * &expected + &q.b)[0];
        assert!(g0 * bound < 0.0, "a saddle, not a minimizer: g_0 = {g0}");
    }
}

/// A convex quadratic whose unconstrained minimizer has x_1 + x_2 + x_3 = 2.9 > 1, its
/// minimizer on the face a.x = 1, and the slab |x_1 + x_2 + x_3| <= 1.
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
fn the_slab_ends_at_the_face_minimizer() {
    // the slab's two inequalities as barrier terms, their rank-one term ρ a a^T in
    // the factorization (the dense matrix's here, the chain's terminal penalty on
    // the ribbon)
    let (mut problem, expected, slab) = slab_problem();
    let mut ipm = InteriorPoint::<Dense>::new();
    let mut x = [0.0; 4];
    let r = ipm.minimize(
        &mut problem,
        &mut x,
        &[-10.0; 4],
        &[10.0; 4],
        Some(slab.clone()),
        &options(),
    );
    assert!(r.converged, "{r:?}");
    let sum = slab.sum(&x);
    assert!(sum < 1.0 && 1.0 - sum <= 1e-12, "{sum}");
    // pg / λ_min(H) = 2e-12 plus the slab's slack; measured 1.7e-15
    for i in 0..4 {
        assert!((x[i] - expected[i]).abs() < 3e-12, "{x:?} vs {expected}");
    }
    // negative control: without the slab the same solve ends outside it
    let mut y = [0.0; 4];
    let r = InteriorPoint::<Dense>::new().minimize(
        &mut problem,
        &mut y,
        &[-10.0; 4],
        &[10.0; 4],
        None,
        &options(),
    );
    assert!(r.converged, "{r:?}");
    assert!(slab.sum(&y) > 2.8, "{}", slab.sum(&y));
}

#[test]
fn a_warm_start_from_the_last_solution_takes_fewer_iterations() {
    // the time-stepper's case: the same problem solved again from its own solution
    // (pushed inside, the duals kept): fewer iterations than from the middle
    let (mut problem, _, slab) = slab_problem();
    let mut ipm = InteriorPoint::<Dense>::new();
    let mut x = [0.0; 4];
    let bounds = ([-10.0; 4], [10.0; 4]);
    let cold = ipm.minimize(
        &mut problem,
        &mut x,
        &bounds.0,
        &bounds.1,
        Some(slab.clone()),
        &options(),
    );
    let warm = ipm.minimize(
        &mut problem,
        &mut x,
        &bounds.0,
        &bounds.1,
        Some(slab),
        &options(),
    );
    assert!(cold.converged && warm.converged, "{cold:?} {warm:?}");
    assert!(warm.iterations < cold.iterations, "{warm:?} vs {cold:?}");
}
