//! Finite-difference checks of the gradients (adjoint, chain rule) and the Hessian.

use super::*;
use crate::geometry::{Point2, Point3};
use crate::ribbon::params::LoopKind;
use rand::{Rng, SeedableRng};

/// A random but smooth-enough test problem: every term active, history perturbed so
/// no vertex sits exactly on a resampling kink.
pub(super) fn problem(
    n: usize,
    floating: bool,
    kinetic: KineticModel,
    seed: u64,
) -> (Strip, StepTerms, RimHistory, Vec<f64>, Pose) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let strip = Strip {
        length: 1.0,
        width: 0.08,
        segments: n,
    };
    let base = Pose::new(Vector3::new(0.1, 0.2, -0.1), Vector3::new(0.3, -0.2, 0.5));
    // previous state: random coordinates, random velocities
    let mut prev = Coordinates::flat(n, base);
    for k in 1..n {
        prev.crease_direction[k] = rng.random_range(-0.3..0.3);
        prev.bending_angle[k] = rng.random_range(-0.4..0.4);
    }
    let mut frames = Frames::default();
    reconstruct(&strip, &prev, &mut frames);
    let mut history = RimHistory::at_rest(&strip, &prev.crease_direction, &frames);
    for v in history.v_bottom.iter_mut().chain(history.v_top.iter_mut()) {
        *v = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
    }
    let equalities = vec![
        Equality::Position {
            material_point: Point2::new(0.63, 0.01),
            target: Point3::new(0.2, 0.3, 0.1),
            axes: [true, false, true],
        },
        Equality::Orientation {
            material_point: Point2::new(0.97, 0.0),
            target: *nalgebra::Rotation3::new(Vector3::new(0.2, 0.1, 0.3)).matrix(),
        },
        Equality::Loop(LoopKind::NonOrientable),
    ];
    let multipliers = equalities
        .iter()
        .map(|e| (0..e.rows()).map(|_| rng.random_range(-1.0..1.0)).collect())
        .collect();
    let terms = StepTerms {
        h: 0.01,
        kinetic,
        density: 0.3,
        // 0.02 J with a clamp-like weight on crease 1 (any positive weights work)
        crease_bending: (0..=n)
            .map(|k| match k {
                0 => 0.0,
                1 => 0.02 * n as f64 * 0.08 / 1.5,
                k if k == n => 0.0,
                _ => 0.02 * n as f64 * 0.08,
            })
            .collect(),
        crease_regularizer: 0.1,
        gravity: Vector3::new(0.0, 0.0, -9.81),
        normal_guides: vec![NormalGuide {
            material_point: Point2::new(0.41, -0.02),
            target: Vector3::new(0.0, 0.6, 0.8),
            stiffness: 3.0,
        }],
        forces: vec![PointForce {
            material_point: Point2::new(0.27, 0.03),
            force: Vector3::new(0.5, -1.0, 2.0),
        }],
        equalities,
        multipliers,
        end_crease_multipliers: [-0.3, 0.0],
        end_crease_exact: false,
        penalty: 50.0,
        crease_bound: 0.95 * 2.0 / (0.08 * n as f64),
    };
    // current q: near prev, perturbed
    let layout = Layout {
        segments: n,
        floating,
    };
    let mut q = vec![0.0; layout.len()];
    let mut cur = prev.clone();
    for k in 1..n {
        cur.crease_direction[k] += rng.random_range(-0.05..0.05);
        cur.bending_angle[k] += rng.random_range(-0.1..0.1);
    }
    // make the end-crease inequality active
    cur.crease_direction[n - 1] = 0.95 * 2.0 / (0.08 * n as f64) + 0.01;
    cur.base = Pose::new(
        Vector3::new(0.12, 0.18, -0.09),
        Vector3::new(0.31, -0.22, 0.48),
    );
    layout.pack(&cur, &base, &mut q);
    (strip, terms, history, q, base)
}

fn check_gradient(n: usize, floating: bool, kinetic: KineticModel, mode: GradientMode) {
    let (strip, terms, history, q, base) = problem(n, floating, kinetic, 11 + n as u64);
    let obj = Objective::new(strip, floating, &terms, &history, base);
    let mut ws = Workspace::default();
    let mut g = vec![0.0; q.len()];
    let f0 = obj.evaluate(&q, &mut ws, Some((&mut g, mode)), None);
    assert!(f0.is_finite());
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    let scale = g.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for a in 0..q.len() {
        let mut qp = q.clone();
        qp[a] += h;
        let fp = obj.evaluate(&qp, &mut ws, None, None);
        qp[a] -= 2.0 * h;
        let fm = obj.evaluate(&qp, &mut ws, None, None);
        let fd = (fp - fm) / (2.0 * h);
        let err = (fd - g[a]).abs() / scale;
        worst = worst.max(err);
        // central differences: O(h^2) truncation ~ 1e-12 relative, round-off
        // ~ eps |f| / h ~ 1e-10 relative to the gradient scale.
        assert!(
            err < 1e-6,
            "coordinate {a} ({mode:?}, {kinetic:?}): analytic {} vs fd {fd}",
            g[a]
        );
    }
    assert!(worst < 1e-6);
}

#[test]
fn adjoint_gradient_matches_finite_differences_fixed_base() {
    check_gradient(9, false, KineticModel::Full, GradientMode::Adjoint);
}
#[test]
fn adjoint_gradient_matches_finite_differences_floating_base() {
    check_gradient(8, true, KineticModel::Full, GradientMode::Adjoint);
}
#[test]
fn chain_rule_gradient_matches_finite_differences() {
    check_gradient(8, true, KineticModel::Full, GradientMode::ChainRule);
    check_gradient(7, false, KineticModel::Lumped, GradientMode::ChainRule);
}
#[test]
fn lumped_and_quasi_static_gradients_match_finite_differences() {
    check_gradient(10, true, KineticModel::Lumped, GradientMode::Adjoint);
    check_gradient(6, false, KineticModel::QuasiStatic, GradientMode::Adjoint);
}

#[test]
fn adjoint_and_chain_rule_agree() {
    let (strip, terms, history, q, base) = problem(30, true, KineticModel::Full, 5);
    let obj = Objective::new(strip, true, &terms, &history, base);
    let mut ws = Workspace::default();
    let mut ga = vec![0.0; q.len()];
    let mut gc = vec![0.0; q.len()];
    obj.evaluate(&q, &mut ws, Some((&mut ga, GradientMode::Adjoint)), None);
    obj.evaluate(&q, &mut ws, Some((&mut gc, GradientMode::ChainRule)), None);
    let scale = ga.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for (a, c) in ga.iter().zip(&gc) {
        assert!((a - c).abs() < 1e-10 * scale, "{a} vs {c}");
    }
}

/// Hessian against central differences of the analytic gradient.
fn check_hessian(
    terms: &StepTerms,
    history: &RimHistory,
    strip: Strip,
    base: Pose,
    q: &[f64],
    floating: bool,
    coords: &[usize],
) {
    let obj = Objective::new(strip, floating, terms, history, base);
    let mut ws = Workspace::default();
    let mut hm = DMatrix::zeros(q.len(), q.len());
    let mut g = vec![0.0; q.len()];
    obj.evaluate(
        q,
        &mut ws,
        Some((&mut g, GradientMode::Adjoint)),
        Some(&mut hm),
    );
    check_hessian_against(terms, history, strip, base, q, floating, coords, &hm);
}

/// `hm` against central differences of the analytic gradient of the objective of
/// `terms` at q, in the coordinates `coords`.
#[allow(clippy::too_many_arguments)]
fn check_hessian_against(
    terms: &StepTerms,
    history: &RimHistory,
    strip: Strip,
    base: Pose,
    q: &[f64],
    floating: bool,
    coords: &[usize],
    hm: &DMatrix<f64>,
) {
    let obj = Objective::new(strip, floating, terms, history, base);
    let mut ws = Workspace::default();
    assert!(
        (hm - hm.transpose()).amax() <= 1e-12 * hm.amax(),
        "symmetric"
    );
    // columns of the finite-difference Hessian, symmetrized (the standard remedy
    // for the O(h) asymmetry of differenced gradients)
    let step = 1e-6;
    let nq = q.len();
    let mut fd = DMatrix::zeros(nq, nq);
    for &b in coords {
        let mut qp = q.to_vec();
        qp[b] += step;
        let mut gp = vec![0.0; nq];
        obj.evaluate(&qp, &mut ws, Some((&mut gp, GradientMode::Adjoint)), None);
        qp[b] -= 2.0 * step;
        let mut gm = vec![0.0; nq];
        obj.evaluate(&qp, &mut ws, Some((&mut gm, GradientMode::Adjoint)), None);
        for &a in coords {
            fd[(a, b)] = (gp[a] - gm[a]) / (2.0 * step);
        }
    }
    let fd = (&fd + fd.transpose()) * 0.5;
    if std::env::var("HESSIAN_DEBUG").is_ok() {
        for &b in coords {
            for &a in coords {
                if (fd[(a, b)] - hm[(a, b)]).abs() >= 1e-6 * hm.amax() {
                    eprintln!("H[{a},{b}] = {} vs fd {}", hm[(a, b)], fd[(a, b)]);
                }
            }
        }
    }
    for &b in coords {
        for &a in coords {
            // truncation ~ h^2 times the third derivative, round-off ~ eps |g| / h
            // ~ 1e-10 |g|; 1e-6 of the largest entry is far above both and far below
            // any missing term.
            assert!(
                (fd[(a, b)] - hm[(a, b)]).abs() < 1e-6 * hm.amax(),
                "H[{a},{b}] = {} vs fd {}",
                hm[(a, b)],
                fd[(a, b)]
            );
        }
    }
}

#[test]
fn newton_hessian_matches_finite_differences_quasi_static() {
    // no kinetic term, no gravity: every term's Hessian is exact (bending unclamped
    // for c^2 < 1/3), in every coordinate including crease directions
    let (strip, mut terms, history, mut q, base) = problem(7, true, KineticModel::QuasiStatic, 3);
    terms.gravity = Vector3::zeros();
    let lay = Layout {
        segments: 7,
        floating: true,
    };
    q[lay.c(6)] = 0.05;
    q[0..3].copy_from_slice(&[0.0; 3]); // base rotation at its reference: exact curvature
    terms.end_crease_multipliers = [0.0, 0.0];
    let all: Vec<usize> = (0..lay.len()).collect();
    check_hessian(&terms, &history, strip, base, &q, true, &all);
}

/// A problem of `problem` with its loop closure replaced by `closure` (None: an open
/// strip held by the two handles only).
fn with_closure(terms: &mut StepTerms, closure: Option<LoopKind>, seed: u64) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    terms.equalities.retain(|e| !matches!(e, Equality::Loop(_)));
    if let Some(kind) = closure {
        terms.equalities.push(Equality::Loop(kind));
    }
    terms.multipliers = terms
        .equalities
        .iter()
        .map(|e| (0..e.rows()).map(|_| rng.random_range(-1.0..1.0)).collect())
        .collect();
}

/// Keep the end-crease inequality active at a crease direction where the bending block
/// is not clamped to PSD (c^2 < 1/3; `problem` puts c_{n-1} beyond the scene-like
/// bound, ~3): the Hessian is exact there, and the clamp is tested on its own.
fn unclamped(terms: &mut StepTerms, q: &mut [f64], floating: bool) {
    let n = terms.crease_bending.len() - 1;
    let lay = Layout {
        segments: n,
        floating,
    };
    terms.crease_bound = 0.4;
    q[lay.c(n - 1)] = 0.42;
}

#[test]
fn newton_hessian_matches_finite_differences_in_every_block_with_inertia_and_gravity() {
    // the full kinetic term (its mass depends on the crease differences Δc) and gravity
    // with the consistent mass: every block, crease directions included, floating and
    // prescribed base, Moebius, orientable and no loop
    let closures = [
        Some(LoopKind::NonOrientable),
        Some(LoopKind::Orientable),
        None,
    ];
    for (i, closure) in closures.into_iter().enumerate() {
        for floating in [true, false] {
            let n = 7 + i;
            let (strip, mut terms, history, mut q, base) =
                problem(n, floating, KineticModel::Full, 4 + i as u64);
            with_closure(&mut terms, closure, 40 + i as u64);
            unclamped(&mut terms, &mut q, floating);
            if floating {
                q[0..3].copy_from_slice(&[0.0; 3]);
            }
            let all: Vec<usize> = (0..q.len()).collect();
            check_hessian(&terms, &history, strip, base, &q, floating, &all);
        }
    }
}

#[test]
fn newton_hessian_matches_finite_differences_with_gravity_dominant() {
    // the consistent mass moves between the rims as Δc changes: with gravity the
    // leading term (no inertia, no handles, a heavy strip), that coupling is resolved
    for floating in [false, true] {
        let (strip, mut terms, history, mut q, base) =
            problem(8, floating, KineticModel::QuasiStatic, 12);
        terms.equalities.clear();
        terms.multipliers.clear();
        terms.density = 300.0;
        unclamped(&mut terms, &mut q, floating);
        if floating {
            q[0..3].copy_from_slice(&[0.0; 3]);
        }
        let all: Vec<usize> = (0..q.len()).collect();
        check_hessian(&terms, &history, strip, base, &q, floating, &all);
    }
}

#[test]
fn newton_hessian_matches_finite_differences_in_every_block_lumped() {
    for floating in [true, false] {
        let (strip, mut terms, history, mut q, base) =
            problem(9, floating, KineticModel::Lumped, 8);
        unclamped(&mut terms, &mut q, floating);
        if floating {
            q[0..3].copy_from_slice(&[0.0; 3]);
        }
        let all: Vec<usize> = (0..q.len()).collect();
        check_hessian(&terms, &history, strip, base, &q, floating, &all);
    }
}

#[test]
fn newton_hessian_matches_finite_differences_in_torsion() {
    // a strongly twisted state (bending angles ~1 rad, alternating crease directions up
    // to 0.5, inside the c^2 < 1/3 where the bending block is not clamped) with inertia
    let n = 10;
    let (strip, mut terms, history, mut q, base) = problem(n, true, KineticModel::Full, 21);
    unclamped(&mut terms, &mut q, true);
    let lay = Layout {
        segments: n,
        floating: true,
    };
    for k in 1..n - 1 {
        q[lay.c(k)] = if k % 2 == 0 { 0.5 } else { -0.45 };
        q[lay.psi(k)] = 1.0 - 0.1 * k as f64;
    }
    q[0..3].copy_from_slice(&[0.0; 3]);
    let all: Vec<usize> = (0..q.len()).collect();
    check_hessian(&terms, &history, strip, base, &q, true, &all);
}

/// The check has teeth: where the bending block is clamped to PSD (c_{n-1} ~ 3.4,
/// c^2 > 1/3, the one documented departure from the exact Hessian) it sees the
/// difference, a few 1e-5 of the largest entry.
#[test]
#[should_panic(expected = "vs fd")]
fn hessian_check_sees_the_bending_clamp() {
    let (strip, terms, history, mut q, base) = problem(7, true, KineticModel::Full, 4);
    q[0..3].copy_from_slice(&[0.0; 3]);
    let all: Vec<usize> = (0..q.len()).collect();
    check_hessian(&terms, &history, strip, base, &q, true, &all);
}

/// ... and it sees a kinetic term 1 % off (the Hessian of one density checked against
/// the gradient of another).
#[test]
#[should_panic(expected = "vs fd")]
fn hessian_check_sees_a_wrong_kinetic_term() {
    let (strip, mut terms, history, mut q, base) = problem(7, true, KineticModel::Full, 4);
    unclamped(&mut terms, &mut q, true);
    q[0..3].copy_from_slice(&[0.0; 3]);
    let all: Vec<usize> = (0..q.len()).collect();
    let obj = Objective::new(strip, true, &terms, &history, base);
    let mut ws = Workspace::default();
    let mut hm = DMatrix::zeros(q.len(), q.len());
    obj.evaluate(&q, &mut ws, None, Some(&mut hm));
    terms.density *= 1.01;
    check_hessian_against(&terms, &history, strip, base, &q, true, &all, &hm);
}

#[test]
fn the_clamped_bending_block_is_the_psd_projection() {
    // at c^2 > 1/3 the bending Hessian [[2 k psi^2, 4 k c psi], [4 k c psi, 2 k (1+c^2)]]
    // is indefinite; the model keeps its positive eigenpair only
    let (strip, terms, history, _q, base) = problem(7, false, KineticModel::Full, 4);
    let obj = Objective::new(strip, false, &terms, &history, base);
    let (c, psi, k) = (0.9, 0.7, 3);
    let bend = obj.bending_weight(k);
    let exact = nalgebra::Matrix2::new(
        2.0 * bend * psi * psi,
        4.0 * bend * c * psi,
        4.0 * bend * c * psi,
        2.0 * bend * (1.0 + c * c),
    );
    let eig = exact.symmetric_eigen();
    assert!(eig.eigenvalues.min() < 0.0, "indefinite at c^2 > 1/3");
    let i = if eig.eigenvalues[0] > eig.eigenvalues[1] {
        0
    } else {
        1
    };
    let v = eig.eigenvectors.column(i);
    let expected = v * v.transpose() * eig.eigenvalues[i];
    let clamped = obj.bending_block(c, psi, k);
    assert!(
        (clamped - expected).amax() < 1e-12 * exact.amax(),
        "{clamped} vs {expected}"
    );
    // and unclamped below c^2 = 1/3
    let c = 0.5;
    let exact = nalgebra::Matrix2::new(
        2.0 * bend * psi * psi,
        4.0 * bend * c * psi,
        4.0 * bend * c * psi,
        2.0 * bend * (1.0 + c * c),
    );
    assert_eq!(obj.bending_block(c, psi, k), exact);
}

/// A = dq/dz: c_k = z_1 + ... + z_k (the crease-difference substitution).
fn substitution(lay: &Layout) -> DMatrix<f64> {
    let nq = lay.len();
    let mut a = DMatrix::identity(nq, nq);
    for k in 1..lay.segments {
        for i in 1..k {
            a[(lay.c(k), lay.c(i))] = 1.0;
        }
    }
    a
}

#[test]
fn chain_solve_is_the_dense_solve() {
    // the chain factorization solves (H_z + diag(shift)) d = r on the free set exactly as
    // the dense Cholesky does, and fails exactly where it fails: open ribbons and both
    // loop closures (the Woodbury step), with the root unknowns held too
    let closures = [
        None,
        Some(LoopKind::Orientable),
        Some(LoopKind::NonOrientable),
    ];
    for (i, (floating, closure)) in [false, true]
        .into_iter()
        .flat_map(|f| closures.map(|c| (f, c)))
        .enumerate()
    {
        let n = 9 + i % 2;
        let (strip, mut terms, history, mut q, base) =
            problem(n, floating, KineticModel::Full, 30 + i as u64);
        with_closure(&mut terms, closure, 31);
        if floating {
            q[0..3].copy_from_slice(&[0.3, -0.1, 0.2]);
        }
        let obj = Objective::new(strip, floating, &terms, &history, base);
        let mut ws = Workspace::default();
        let mut hq = DMatrix::zeros(q.len(), q.len());
        obj.evaluate(&q, &mut ws, None, Some(&mut hq));
        let a = substitution(&obj.layout);
        let hz = a.transpose() * &hq * &a;
        let mut model = chain::ChainModel::default();
        obj.chain_model(&mut ws, &mut model);
        let nq = q.len();
        let diagonal = model.cached_diagonal().to_vec();
        for j in 0..nq {
            assert!(
                (diagonal[j] - hz[(j, j)]).abs() <= 1e-10 * hz.amax(),
                "diagonal {j}: chain {} vs dense {}",
                diagonal[j],
                hz[(j, j)]
            );
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let rhs: Vec<f64> = (0..nq).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut compared = 0;
        for (held, damping) in [
            (vec![], 1e-3),
            (vec![obj.layout.c(3), obj.layout.c(5)], 1e-1),
            (vec![obj.layout.psi(2)], 0.0),
            (vec![obj.layout.c(1), 0, 4], 1e-2),
            // heavily damped: positive definite, so these compare a solve
            (vec![], 3.0),
            (vec![obj.layout.c(2)], 10.0),
            (vec![obj.layout.psi(4), 1], 30.0),
        ] {
            let free: Vec<bool> = (0..nq).map(|j| !held.contains(&j)).collect();
            let shift: Vec<f64> = (0..nq).map(|j| damping * hz[(j, j)].abs() + 1e-9).collect();
            let idx: Vec<usize> = (0..nq).filter(|&j| free[j]).collect();
            let m = idx.len();
            let reduced = DMatrix::from_fn(m, m, |r, c| {
                hz[(idx[r], idx[c])] + if r == c { shift[idx[r]] } else { 0.0 }
            });
            let dense = reduced.clone().cholesky();
            let chain_ok = model.factor(&free, &shift);
            assert_eq!(
                chain_ok,
                dense.is_some(),
                "positive definite: chain {chain_ok} (held {held:?}, damping {damping})"
            );
            let Some(dense) = dense else { continue };
            compared += 1;
            let r = nalgebra::DVector::from_fn(m, |r, _| rhs[idx[r]]);
            let expected = dense.solve(&r);
            let mut out = vec![f64::NAN; nq];
            assert!(model.solve(&rhs, &mut out));
            let scale = expected.amax();
            for (r, &j) in idx.iter().enumerate() {
                assert!(
                    (out[j] - expected[r]).abs() <= 1e-9 * scale,
                    "unknown {j}: chain {} vs dense {} (floating {floating}, {closure:?}, held {held:?})",
                    out[j],
                    expected[r]
                );
            }
            for &j in &held {
                assert_eq!(out[j], 0.0);
            }
        }
        // a factorization that only ever fails would agree with a failing Cholesky
        // without comparing one solve
        assert!(
            compared >= 2,
            "only {compared} positive definite cases (floating {floating}, {closure:?})"
        );
    }
}

#[test]
fn chain_product_and_negative_curvature_are_the_dense_ones() {
    // H v of the chain model (two sweeps, O(n)) is the dense H_z v, and where the
    // factorization fails, the direction it returns has exactly the curvature it
    // reports, <= 0, under the same shift: open ribbons and both loop closures, fixed
    // and floating base
    let closures = [
        None,
        Some(LoopKind::Orientable),
        Some(LoopKind::NonOrientable),
    ];
    let mut directions = 0;
    for (i, (floating, closure)) in [false, true]
        .into_iter()
        .flat_map(|f| closures.map(|c| (f, c)))
        .enumerate()
    {
        let n = 9 + i % 2;
        let (strip, mut terms, history, mut q, base) =
            problem(n, floating, KineticModel::Full, 50 + i as u64);
        with_closure(&mut terms, closure, 51);
        if floating {
            q[0..3].copy_from_slice(&[0.3, -0.1, 0.2]);
        }
        let obj = Objective::new(strip, floating, &terms, &history, base);
        let mut ws = Workspace::default();
        let mut hq = DMatrix::zeros(q.len(), q.len());
        obj.evaluate(&q, &mut ws, None, Some(&mut hq));
        let a = substitution(&obj.layout);
        let hz = a.transpose() * &hq * &a;
        let mut model = chain::ChainModel::default();
        obj.chain_model(&mut ws, &mut model);
        let nq = q.len();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17 + i as u64);
        for _ in 0..3 {
            let v: Vec<f64> = (0..nq).map(|_| rng.random_range(-1.0..1.0)).collect();
            let expected = &hz * nalgebra::DVector::from_column_slice(&v);
            let mut out = vec![f64::NAN; nq];
            model.multiply(&v, &mut out);
            let scale = expected.amax();
            for j in 0..nq {
                // the two sums differ in order only: round-off of a few eps |H| |v|
                assert!(
                    (out[j] - expected[j]).abs() <= 1e-12 * scale.max(hz.amax()),
                    "(H v)[{j}]: chain {} vs dense {} (floating {floating}, {closure:?})",
                    out[j],
                    expected[j]
                );
            }
        }
        // a shift that makes the matrix indefinite: minus a fraction of its largest
        // diagonal entry, with some unknowns held
        let held = [obj.layout.psi(2), obj.layout.c(4)];
        let free: Vec<bool> = (0..nq).map(|j| !held.contains(&j)).collect();
        for fraction in [0.01, 0.1, 0.5] {
            let shift: Vec<f64> = (0..nq).map(|_| -fraction * hz.amax()).collect();
            if model.factor(&free, &shift) {
                continue;
            }
            let mut d = vec![f64::NAN; nq];
            let Some(curvature) = model.negative_curvature(&mut d) else {
                assert!(closure.is_some(), "no direction from an open chain's sweep");
                continue;
            };
            directions += 1;
            assert!(curvature <= 0.0, "{curvature}");
            for &j in &held {
                assert_eq!(d[j], 0.0, "a held unknown moves");
            }
            let dv = nalgebra::DVector::from_column_slice(&d);
            let dense =
                dv.dot(&(&hz * &dv)) + d.iter().zip(&shift).map(|(x, s)| s * x * x).sum::<f64>();
            assert!(
                (dense - curvature).abs() <= 1e-9 * hz.amax() * dv.norm_squared(),
                "d^T (H + S) d: dense {dense} vs sweep {curvature} (floating {floating}, {closure:?})"
            );
        }
    }
    assert!(directions >= 6, "only {directions} directions compared");
}
