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
    let scale = g.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for a in 0..q.len() {
        let mut qp = q.clone();
        qp[a] += h;
        let fp = obj.evaluate(&qp, &mut ws, None, None);
        qp[a] -= 2.0 * h;
        let fm = obj.evaluate(&qp, &mut ws, None, None);
        let fd = (fp - fm) / (2.0 * h);
        let err = (fd - g[a]).abs() / scale;
        // central differences: O(h^2) truncation ~ 1e-12 relative, round-off
        // ~ eps |f| / h ~ 1e-10 relative to the gradient scale.
        assert!(
            err < 1e-6,
            "coordinate {a} ({mode:?}, {kinetic:?}): analytic {} vs fd {fd}",
            g[a]
        );
    }
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
    check_hessian_with(terms, history, strip, base, q, floating, coords, None);
}

/// [`check_hessian`] of the objective with the contact terms `contact`.
#[allow(clippy::too_many_arguments)]
pub(super) fn check_hessian_with(
    terms: &StepTerms,
    history: &RimHistory,
    strip: Strip,
    base: Pose,
    q: &[f64],
    floating: bool,
    coords: &[usize],
    contact: Option<&ContactTerms>,
) {
    let obj = Objective::new(strip, floating, terms, history, base).with_contact(contact);
    let mut ws = Workspace::default();
    let mut hm = DMatrix::zeros(q.len(), q.len());
    let mut g = vec![0.0; q.len()];
    obj.evaluate(
        q,
        &mut ws,
        Some((&mut g, GradientMode::Adjoint)),
        Some(&mut hm),
    );
    check_hessian_against(
        terms,
        history,
        strip,
        base,
        q,
        (floating, contact),
        coords,
        &hm,
    );
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
    (floating, contact): (bool, Option<&ContactTerms>),
    coords: &[usize],
    hm: &DMatrix<f64>,
) {
    let obj = Objective::new(strip, floating, terms, history, base).with_contact(contact);
    let mut ws = Workspace::default();
    assert!(
        (hm - hm.transpose()).amax() <= 1e-12 * hm.amax(),
        "symmetric"
    );
    // columns of the finite-difference Hessian, Richardson-extrapolated from central
    // differences at h and h/2 ((4 D(h/2) - D(h)) / 3: truncation O(h^4), which the
    // contact barrier's large third derivative needs) and symmetrized (the standard
    // remedy for the O(h) asymmetry of differenced gradients)
    let nq = q.len();
    let central = |step: f64, ws: &mut Workspace| {
        let mut d = DMatrix::zeros(nq, nq);
        for &b in coords {
            let mut qp = q.to_vec();
            qp[b] += step;
            let mut gp = vec![0.0; nq];
            obj.evaluate(&qp, ws, Some((&mut gp, GradientMode::Adjoint)), None);
            qp[b] -= 2.0 * step;
            let mut gm = vec![0.0; nq];
            obj.evaluate(&qp, ws, Some((&mut gm, GradientMode::Adjoint)), None);
            for &a in coords {
                d[(a, b)] = (gp[a] - gm[a]) / (2.0 * step);
            }
        }
        d
    };
    let step = 1e-5;
    let fd = (central(step / 2.0, &mut ws) * 4.0 - central(step, &mut ws)) / 3.0;
    let fd = (&fd + fd.transpose()) * 0.5;
    // The error's spectral norm bounds how far any eigenvalue can move (Weyl), so the
    // check certifies the soft modes: on the extreme torsion (the design check,
    // docs/ribbon_chain_solver.md) they sit at 1e-4 J (positive) and -1e-3 J (negative)
    // against |H|max ~ 1e3, i.e. 1e-7 of the largest entry; the bound is a tenth of
    // that, so an error that moves the softest mode by 10 % of itself fails. The
    // differences' own error with h = 1e-5 extrapolated: round-off ~3 eps |g| / h
    // ~7e-11 |g|max per entry, truncation O(h^4); measured at most 1.7e-10 |H|max in
    // spectral norm over these tests (the quasi-static one; the barrier and friction
    // test 9e-11, where plain central differences at h = 1e-6 left 2.1e-7 from the
    // barrier's third derivative), 50x below the bound (2026-12-07).
    let m = coords.len();
    let error = DMatrix::from_fn(m, m, |r, c| {
        fd[(coords[r], coords[c])] - hm[(coords[r], coords[c])]
    });
    let spectral = error.clone().singular_values().max();
    let bound = 1e-8 * hm.amax();
    if std::env::var("HESSIAN_DEBUG").is_ok() {
        eprintln!("||fd - H||_2 = {spectral:.3e}, bound {bound:.3e}");
    }
    let worst = error.iamax_full();
    let (a, b) = (coords[worst.0], coords[worst.1]);
    assert!(
        spectral <= bound,
        "||fd - H||_2 = {spectral:.3e} > {bound:.3e}; worst H[{a},{b}] = {} vs fd {}",
        hm[(a, b)],
        fd[(a, b)]
    );
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
    check_hessian_against(&terms, &history, strip, base, &q, (true, None), &all, &hm);
}

/// ... and an error at the soft modes' scale: a rank-one error of 1e-7 |H|max (what
/// would move a soft mode of the extreme torsion by its own size) along a random
/// direction.
#[test]
#[should_panic(expected = "vs fd")]
fn hessian_check_sees_an_error_at_the_soft_modes_scale() {
    let (strip, mut terms, history, mut q, base) = problem(7, true, KineticModel::Full, 4);
    unclamped(&mut terms, &mut q, true);
    q[0..3].copy_from_slice(&[0.0; 3]);
    let all: Vec<usize> = (0..q.len()).collect();
    let obj = Objective::new(strip, true, &terms, &history, base);
    let mut ws = Workspace::default();
    let mut hm = DMatrix::zeros(q.len(), q.len());
    obj.evaluate(&q, &mut ws, None, Some(&mut hm));
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let v = nalgebra::DVector::from_fn(q.len(), |_, _| rng.random_range(-1.0..1.0)).normalize();
    let hm = &hm + &v * v.transpose() * (1e-7 * hm.amax());
    check_hessian_against(&terms, &history, strip, base, &q, (true, None), &all, &hm);
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

/// The dense counterpart of `ChainMatrix::factor_free`: H_z on the free unknowns,
/// plus shift I, plus rho (Σ d_i)^2 over the free crease differences (the slab's face).
fn shifted_reduced(
    hz: &DMatrix<f64>,
    idx: &[usize],
    lay: &Layout,
    shift: f64,
    face: Option<f64>,
) -> DMatrix<f64> {
    let on_face = |j: usize| (lay.c(1)..lay.c(lay.segments - 1) + 1).contains(&j);
    let m = idx.len();
    DMatrix::from_fn(m, m, |r, c| {
        let (a, b) = (idx[r], idx[c]);
        let rho = match face {
            Some(rho) if on_face(a) && on_face(b) => rho,
            _ => 0.0,
        };
        hz[(a, b)] + rho + if r == c { shift } else { 0.0 }
    })
}

/// What the near-singular checks compare: the chain's factorization at `shift` (+ the
/// slab's face) on the unknowns `free` against the dense Cholesky of the same matrix.
struct NearSingular<'a> {
    hz: &'a DMatrix<f64>,
    lay: Layout,
    free: Vec<bool>,
    idx: Vec<usize>,
    face: Option<f64>,
}

impl NearSingular<'_> {
    fn dense(&self, shift: f64) -> DMatrix<f64> {
        shifted_reduced(self.hz, &self.idx, &self.lay, shift, self.face)
    }

    fn range(&self) -> Option<(std::ops::Range<usize>, f64)> {
        let n = self.lay.segments;
        self.face
            .map(|rho| (self.lay.c(1)..self.lay.c(n - 1) + 1, rho))
    }

    /// Just above the least shift: the chain factorizes and solves `rhs` as the dense
    /// Cholesky does: relative residual (backward error) at most `backward`, and the
    /// solution within the condition number times that. False where the chain fails
    /// (the dense matrix is asserted positive definite).
    fn solves(
        &self,
        matrix: &mut chain::ChainMatrix,
        shift: f64,
        rhs: &[f64],
        backward: f64,
        what: &str,
    ) -> bool {
        use crate::optim::ModelMatrix;
        let dense = self.dense(shift);
        let eig = dense.clone().symmetric_eigen().eigenvalues;
        let kappa = eig.max() / eig.min();
        let cholesky = dense.clone().cholesky().expect("dense: positive definite");
        if !matrix.factor_free(&self.free, shift, self.range()) {
            return false;
        }
        let r = nalgebra::DVector::from_fn(self.idx.len(), |k, _| rhs[self.idx[k]]);
        let expected = cholesky.solve(&r);
        let mut out = vec![f64::NAN; rhs.len()];
        assert!(matrix.solve_free(rhs, &mut out), "{what}");
        let x = nalgebra::DVector::from_fn(self.idx.len(), |k, _| out[self.idx[k]]);
        let residual = (&dense * &x - &r).amax() / (dense.amax() * x.amax());
        let forward = (&x - &expected).amax() / expected.amax();
        assert!(residual <= backward, "{what}: residual {residual:.2e}");
        assert!(
            forward <= kappa * 2.0 * backward,
            "{what}: forward error {forward:.2e}, condition {kappa:.1e}"
        );
        for (j, &f) in self.free.iter().enumerate() {
            assert!(f || out[j] == 0.0, "{what}: a held unknown moves");
        }
        true
    }

    /// Just below it (one eigenvalue at -delta |H|): the chain fails, and on an open
    /// chain, the direction it returns has the curvature it reports (with a loop closure
    /// it is the chain's without the closure's coupling, see
    /// `ChainModel::negative_curvature`).
    fn fails(&self, matrix: &mut chain::ChainMatrix, shift: f64, open: bool, what: &str) {
        use crate::optim::ModelMatrix;
        assert!(
            !matrix.factor_free(&self.free, shift, self.range()),
            "chain passes: {what}"
        );
        let mut d = vec![f64::NAN; self.lay.len()];
        let direction = matrix.model.negative_curvature(&mut d);
        assert!(
            direction.is_some() || !open,
            "{what}: an open chain's sweep gives a direction"
        );
        if let Some(curvature) = direction.filter(|_| open) {
            let dv = nalgebra::DVector::from_fn(self.idx.len(), |k, _| d[self.idx[k]]);
            let dense = self.dense(shift);
            let exact = dv.dot(&(&dense * &dv));
            assert!(curvature <= 0.0, "{what}: {curvature}");
            assert!(
                (exact - curvature).abs() <= 1e-9 * dense.amax() * dv.norm_squared(),
                "{what}: d^T (H + S) d dense {exact:.6e} vs sweep {curvature:.6e}"
            );
        }
    }
}

/// The regime the solvers live in (docs/ribbon_chain_solver.md, the design check):
/// indefinite Newton matrices whose positive definite shifts are nearly singular. The
/// trust region's step takes the least shift sigma I that makes H_FF (+ the slab's
/// face) positive definite, i.e. sigma = -lambda_min + delta |H|; its soft modes on the
/// extreme torsion are 1e-4 J against |H| ~ 1e3 (delta ~ 1e-7), and the least-shift
/// search can land nearer (delta = 1e-11 here: 1e3 above the sweep's backward error
/// m eps). Just above, the chain must factorize and solve as the dense Cholesky does;
/// just below (one eigenvalue at -delta |H|) it must fail. Backward error: the sweep
/// is a block LDL^T, so m eps (m unknowns; measured at most 7e-16 on open chains);
/// the loop closures' Woodbury step is not backward stable: measured at most 2.0e-12
/// at delta = 1e-7, asserted at 1e-11, and at delta <= 1e-10 its capacitance misjudges
/// the inertia or loses the solve (residual 3e-5; docs/ribbon_chain_solver.md), so
/// the loops are checked at delta = 1e-7 only.
#[test]
fn chain_solve_is_the_dense_solve_where_nearly_singular_and_indefinite() {
    near_singular_cases(0.0);
}

/// The check has teeth: a chain matrix whose crease blocks are 1e-9 off (relative)
/// leaves a residual of ~1e-9 of their size, far above the sweep's m eps.
#[test]
#[should_panic(expected = "residual")]
fn near_singular_check_sees_a_matrix_1e_9_off() {
    near_singular_cases(1e-9);
}

/// [`chain_solve_is_the_dense_solve_where_nearly_singular_and_indefinite`] with the
/// chain's crease blocks scaled by 1 + `error` (0: exact).
fn near_singular_cases(error: f64) {
    use crate::optim::{ModelMatrix, NewtonMatrix};
    let closures = [
        None,
        Some(LoopKind::Orientable),
        Some(LoopKind::NonOrientable),
    ];
    let (mut cases, mut known_gap) = (0, 0);
    for (i, (floating, closure)) in [false, true]
        .into_iter()
        .flat_map(|f| closures.map(|c| (f, c)))
        .enumerate()
    {
        let n = 9 + i % 2;
        let (strip, mut terms, history, mut q, base) =
            problem(n, floating, KineticModel::Full, 60 + i as u64);
        with_closure(&mut terms, closure, 61);
        if floating {
            q[0..3].copy_from_slice(&[0.3, -0.1, 0.2]);
        }
        let obj = Objective::new(strip, floating, &terms, &history, base);
        let lay = obj.layout;
        let mut ws = Workspace::default();
        let mut hq = DMatrix::zeros(q.len(), q.len());
        obj.evaluate(&q, &mut ws, None, Some(&mut hq));
        let a = substitution(&lay);
        let hz = a.transpose() * &hq * &a;
        let mut matrix = chain::ChainMatrix::default();
        obj.chain_model(&mut ws, &mut matrix.model);
        if error != 0.0 {
            matrix.model.perturb_local_blocks(error);
        }
        let nq = q.len();
        let mut diagonal = vec![0.0; nq];
        matrix.diagonal(&mut diagonal); // cached, as the solver does
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(70 + i as u64);
        let rhs: Vec<f64> = (0..nq).map(|_| rng.random_range(-1.0..1.0)).collect();
        let amax = hz.amax();
        for (held, face) in [
            (vec![], None),
            (vec![lay.c(3), lay.psi(5)], None),
            (vec![], Some(1e2 * amax)),
            (vec![lay.c(2)], Some(amax)),
        ] {
            let free: Vec<bool> = (0..nq).map(|j| !held.contains(&j)).collect();
            let idx: Vec<usize> = (0..nq).filter(|&j| free[j]).collect();
            let check = NearSingular {
                hz: &hz,
                lay,
                free,
                idx,
                face,
            };
            let unshifted = check.dense(0.0);
            // |H| without the face's rho (which only stiffens the directions that cross it)
            let (lambda_min, scale) = (unshifted.symmetric_eigen().eigenvalues.min(), amax);
            assert!(lambda_min < -1e-2 * scale, "not indefinite: {lambda_min}");
            assert!(
                !matrix.factor_free(&check.free, 0.0, check.range()),
                "indefinite"
            );
            let (deltas, backward): (&[f64], f64) = match closure {
                None => (&[1e-7, 1e-11], check.idx.len() as f64 * f64::EPSILON),
                Some(_) => (&[1e-7], 1e-11),
            };
            for &delta in deltas {
                let what = format!("floating {floating}, {closure:?}, held {held:?}, face {face:?}, delta {delta:e}");
                cases += 1;
                let solved = check.solves(
                    &mut matrix,
                    -lambda_min + delta * scale,
                    &rhs,
                    backward,
                    &what,
                );
                if floating && closure == Some(LoopKind::Orientable) {
                    // Known gap: the sweep factorizes the chain without the closure's
                    // coupling (H0), which is indefinite here where H is not: the least
                    // shift the chain accepts is 1.35x the true one (45.3 vs 33.6)
                    assert!(!solved, "fixed? {what}: then drop this branch");
                    known_gap += 1;
                } else {
                    assert!(
                        solved,
                        "chain fails where the dense Cholesky passes: {what}"
                    );
                }
                check.fails(
                    &mut matrix,
                    -lambda_min - delta * scale,
                    closure.is_none(),
                    &what,
                );
            }
        }
    }
    assert_eq!((cases, known_gap), (32, 4));
}
