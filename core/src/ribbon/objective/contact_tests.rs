//! Finite-difference checks of the contact terms (docs/contact_barrier.md): the
//! gradient with ground, collider-feature, self and friction pairs active; the Newton
//! Hessian where it is exact (a plane: the gap's own curvature is zero, friction's is in
//! the model); the chain solve with pairs against the dense solve; the safe step of the
//! line search against a plane.

use std::sync::Arc;

use super::tests::problem;
use super::*;
use crate::contact::obstacles::{CellMesh, ContactEnv};
use crate::contact::{BarrierSettings, Collider, ColliderShape};
use crate::ribbon::params::KineticModel;
use rand::{Rng, SeedableRng};

/// The mesh triangles of an n-element ribbon (mesh vertex 2 j + top).
fn triangles(n: usize) -> Vec<[u32; 3]> {
    (0..n as u32)
        .flat_map(|e| {
            let (xb, yb, xn, yn) = (2 * e, 2 * e + 1, 2 * e + 2, 2 * e + 3);
            [[xb, xn, yn], [xb, yn, yb]]
        })
        .collect()
}

/// Contact terms against `colliders` (poses `poses`), no other body, with settings `s`,
/// for an n-element ribbon of area `area` per vertex.
fn terms_for(
    n: usize,
    s: BarrierSettings,
    colliders: &[Collider],
    poses: &[Pose],
    area: f64,
    h: f64,
) -> ContactTerms {
    let mut ct = ContactTerms::default();
    let vertices = 2 * (n + 1);
    ct.set_cells(Arc::new(CellMesh::new(&triangles(n), vertices)), vertices);
    let env = ContactEnv {
        settings: s,
        colliders,
        poses0: poses,
        poses1: poses,
        others: &[],
    };
    ct.obstacles.update(&env, 1.0, 0);
    ct.weight = s.stiffness() * area;
    ct.activation = s.activation_distance;
    ct.thickness = s.thickness;
    ct.skip = s.neighbour_skip();
    ct.self_contact = s.self_contact;
    ct.friction_slip = s.friction_velocity * h;
    ct
}

/// The rim vertices of q, mesh order.
fn mesh_at(obj: &Objective, q: &[f64]) -> Vec<Vector3> {
    let mut ws = Workspace::default();
    obj.prepare(q, &mut ws);
    let f = &ws.frames;
    f.rim_bottom
        .iter()
        .zip(&f.rim_top)
        .flat_map(|(b, t)| [b.coords, t.coords])
        .collect()
}

/// A plane (normal `normal`) just under the lowest vertex of q: that vertex at
/// ξ/2 + 0.3 ŝ, others inside the barrier as they happen to be. Its pose and collider.
fn ground_under(
    mesh: &[Vector3],
    normal: Vector3,
    s: &BarrierSettings,
    friction: f64,
) -> (Collider, Pose) {
    let low = mesh
        .iter()
        .map(|x| x.dot(&normal))
        .fold(f64::INFINITY, f64::min);
    let height = low - 0.5 * s.thickness - 0.3 * s.activation_distance;
    let rotation =
        nalgebra::UnitQuaternion::rotation_between(&Vector3::z(), &normal).expect("not opposite");
    let pose = Pose::from_parts((normal * height).into(), rotation);
    let collider = Collider {
        shape: ColliderShape::HalfSpace,
        pose,
        friction,
        attached_to: None,
    };
    (collider, pose)
}

/// Settings at the scale of the test problem (elements ~0.1 m): thickness 2 cm,
/// ŝ 8 mm, a pressure that makes the barrier comparable to the other terms.
fn settings() -> BarrierSettings {
    BarrierSettings {
        thickness: 0.02,
        activation_distance: 0.008,
        barrier_pressure: 50.0,
        friction_velocity: 0.5,
        body_friction: 0.0,
        self_contact: true,
    }
}

/// Lagged friction on the vertices inside the barrier: random μλ, tangents and shifts.
fn add_friction(ct: &mut ContactTerms, mesh: &[Vector3], normal: &Vector3, seed: u64) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let t1 = normal.cross(&Vector3::x()).normalize();
    let t2 = normal.cross(&t1);
    for v in (0..mesh.len()).step_by(3) {
        ct.friction.push(FrictionLag {
            vertex: v as u32,
            mu_lambda: rng.random_range(0.1..1.0),
            tangent: [t1, t2],
            shift: Vector3::new(
                rng.random_range(-0.01..0.01),
                rng.random_range(-0.01..0.01),
                0.0,
            ),
            source: crate::contact::barrier::PairSource::Collider(0),
        });
    }
}

/// The gradient of `obj` against central differences of its value.
fn check_gradient(obj: &Objective, q: &[f64]) {
    let mut ws = Workspace::default();
    let mut g = vec![0.0; q.len()];
    let f0 = obj.evaluate(q, &mut ws, Some((&mut g, GradientMode::Adjoint)), None);
    assert!(
        f0.is_finite() && ws.contact.active > 0,
        "{f0} {}",
        ws.contact.active
    );
    let scale = g.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let h = 1e-7;
    for a in 0..q.len() {
        let mut qp = q.to_vec();
        qp[a] += h;
        let fp = obj.evaluate(&qp, &mut ws, None, None);
        qp[a] -= 2.0 * h;
        let fm = obj.evaluate(&qp, &mut ws, None, None);
        let fd = (fp - fm) / (2.0 * h);
        // truncation h^2 |f'''| and round-off eps |f| / h, both far below 1e-6 of the
        // gradient's scale
        assert!(
            (fd - g[a]).abs() < 1e-6 * scale,
            "coordinate {a}: analytic {} vs fd {fd}",
            g[a]
        );
    }
}

#[test]
fn the_gradient_with_ground_and_friction_matches_finite_differences() {
    for floating in [true, false] {
        let (strip, terms, history, mut q, base) = problem(9, floating, KineticModel::Full, 51);
        if floating {
            q[0..3].copy_from_slice(&[0.0; 3]);
        }
        let s = settings();
        let plain = Objective::new(strip, floating, &terms, &history, base);
        let mesh = mesh_at(&plain, &q);
        let normal = Vector3::new(0.2, -0.1, 1.0).normalize();
        let (ground, pose) = ground_under(&mesh, normal, &s, 0.4);
        let mut ct = terms_for(9, s, &[ground], &[pose], 0.01, terms.h);
        add_friction(&mut ct, &mesh, &normal, 3);
        let obj = Objective::new(strip, floating, &terms, &history, base).with_contact(Some(&ct));
        check_gradient(&obj, &q);
    }
}

#[test]
fn the_newton_hessian_with_ground_and_friction_matches_finite_differences() {
    // a plane's gap has no curvature of its own and friction's 2x2 Hessian is exact:
    // the contact terms' Newton matrix (Gauss-Newton + geometric stiffness) is the
    // exact Hessian
    let (strip, mut terms, history, mut q, base) = problem(8, true, KineticModel::Full, 52);
    terms.crease_bound = 0.4;
    let lay = Layout {
        segments: 8,
        floating: true,
    };
    q[lay.c(7)] = 0.42;
    q[0..3].copy_from_slice(&[0.0; 3]);
    let s = settings();
    let plain = Objective::new(strip, true, &terms, &history, base);
    let mesh = mesh_at(&plain, &q);
    let normal = Vector3::new(-0.1, 0.3, 1.0).normalize();
    let (ground, pose) = ground_under(&mesh, normal, &s, 0.4);
    let mut ct = terms_for(8, s, &[ground], &[pose], 0.01, terms.h);
    add_friction(&mut ct, &mesh, &normal, 4);
    let all: Vec<usize> = (0..q.len()).collect();
    super::tests::check_hessian_with(&terms, &history, strip, base, &q, true, &all, Some(&ct));
}

/// A ribbon folded back on itself at crease 6 (12 elements, 0.3 rad between the two
/// layers), a cube's corner 0.6 ŝ beyond the thickness from the middle of triangle 5,
/// the ground under it: self, collider-feature and ground pairs inside the barrier, none
/// touching. Returns (strip, terms, history, q, base, contact terms).
fn folded() -> (Strip, StepTerms, RimHistory, Vec<f64>, Pose, ContactTerms) {
    let n = 12;
    let (strip, terms, history, mut q, base) = problem(n, true, KineticModel::Full, 53);
    let lay = Layout {
        segments: n,
        floating: true,
    };
    q.iter_mut().for_each(|x| *x = 0.0);
    q[lay.psi(6)] = std::f64::consts::PI - 0.3;
    let s = settings();
    let plain = Objective::new(strip, true, &terms, &history, base);
    let mesh = mesh_at(&plain, &q);
    // the cube: its (-1, -1, -1) corner on the normal of triangle 5's centroid
    let tri = triangles(n)[5].map(|v| mesh[v as usize]);
    let centroid = (tri[0] + tri[1] + tri[2]) / 3.0;
    let normal = (tri[1] - tri[0]).cross(&(tri[2] - tri[0])).normalize();
    let corner = centroid + normal * (0.5 * s.thickness + 0.6 * s.activation_distance);
    let half = 0.05;
    let diagonal = Vector3::new(1.0, 1.0, 1.0).normalize();
    let rotation =
        nalgebra::UnitQuaternion::rotation_between(&diagonal, &normal).expect("not opposite");
    let cube_pose = Pose::from_parts((corner + normal * (half * 3f64.sqrt())).into(), rotation);
    let cube = Collider {
        shape: ColliderShape::Cuboid {
            half_extents: Vector3::repeat(half),
        },
        pose: cube_pose,
        friction: 0.0,
        attached_to: None,
    };
    let (ground, ground_pose) = ground_under(&mesh, Vector3::z(), &s, 0.3);
    let ct = terms_for(
        n,
        s,
        &[cube, ground],
        &[cube_pose, ground_pose],
        0.01,
        terms.h,
    );
    (strip, terms, history, q, base, ct)
}

#[test]
fn the_gradient_with_self_and_collider_feature_pairs_matches_finite_differences() {
    let (strip, terms, history, q, base, ct) = folded();
    let obj = Objective::new(strip, true, &terms, &history, base).with_contact(Some(&ct));
    let mut ws = Workspace::default();
    let mut g = vec![0.0; q.len()];
    let mut h = DMatrix::zeros(q.len(), q.len());
    obj.evaluate(
        &q,
        &mut ws,
        Some((&mut g, GradientMode::Adjoint)),
        Some(&mut h),
    );
    assert!(!ws.contact.pairs.is_empty(), "no self pair in the fold");
    assert!(
        ws.contact.collider_force[0] > 0.0,
        "the cube's corner is not in the barrier"
    );
    check_gradient(&obj, &q);
}

#[test]
fn the_chain_solve_with_self_pairs_is_the_dense_solve() {
    // the pairs across the chain: merged per element pair and solved by Woodbury on the
    // sweep; the dense baseline adds B'' g g^T to its matrix. The two solve one system.
    let (strip, terms, history, q, base, ct) = folded();
    let obj = Objective::new(strip, true, &terms, &history, base).with_contact(Some(&ct));
    let mut ws = Workspace::default();
    let mut hq = DMatrix::zeros(q.len(), q.len());
    obj.evaluate(&q, &mut ws, None, Some(&mut hq));
    let pairs = ws.contact.pairs.len();
    assert!(pairs > 0);
    let nq = q.len();
    // A = dq/dz
    let lay = obj.layout;
    let mut a = DMatrix::identity(nq, nq);
    for k in 1..lay.segments {
        for i in 1..k {
            a[(lay.c(k), lay.c(i))] = 1.0;
        }
    }
    let hz = a.transpose() * &hq * &a;
    let mut model = chain::ChainModel::default();
    obj.chain_model(&mut ws, &mut model);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let rhs: Vec<f64> = (0..nq).map(|_| rng.random_range(-1.0..1.0)).collect();
    // the product H v (the trust region's model) with the pairs is the dense one
    let expected = &hz * nalgebra::DVector::from_column_slice(&rhs);
    let mut out = vec![f64::NAN; nq];
    model.multiply(&rhs, &mut out);
    let worst = (0..nq)
        .map(|j| (out[j] - expected[j]).abs())
        .fold(0.0, f64::max);
    eprintln!("H v: worst {worst:e} of |H| {:e}", hz.amax());
    // the two sums differ in order only: round-off of a few eps |H| |v|
    // (measured 8.4e-13 of |H| = 1.4e3; without the pairs' part, off by their B'' terms)
    assert!(
        worst <= 1e-14 * hz.amax(),
        "H v with {pairs} pairs: off by {worst}"
    );
    for (held, damping) in [
        (vec![], 1e-2),
        (vec![lay.c(3), lay.psi(8)], 1e-1),
        (vec![], 3.0),
    ] {
        let free: Vec<bool> = (0..nq).map(|j| !held.contains(&j)).collect();
        let shift: Vec<f64> = (0..nq).map(|j| damping * hz[(j, j)].abs() + 1e-9).collect();
        let idx: Vec<usize> = (0..nq).filter(|&j| free[j]).collect();
        let m = idx.len();
        let reduced = DMatrix::from_fn(m, m, |r, c| {
            hz[(idx[r], idx[c])] + if r == c { shift[idx[r]] } else { 0.0 }
        });
        let Some(dense) = reduced.cholesky() else {
            assert!(
                !model.factor(&free, &shift),
                "the chain accepted what the dense rejected"
            );
            continue;
        };
        assert!(
            model.factor(&free, &shift),
            "the chain rejected a positive definite matrix"
        );
        let expected = dense.solve(&nalgebra::DVector::from_fn(m, |r, _| rhs[idx[r]]));
        let mut out = vec![f64::NAN; nq];
        assert!(model.solve(&rhs, &mut out));
        let scale = expected.amax();
        for (r, &j) in idx.iter().enumerate() {
            // the pairs make the matrix stiff (B'' ~ 1e5 of the rest): 1e-8 of the
            // step's scale is the round-off of the Woodbury capacitance at that ratio
            assert!(
                (out[j] - expected[r]).abs() <= 1e-8 * scale,
                "unknown {j}: chain {} vs dense {} ({pairs} pairs, damping {damping})",
                out[j],
                expected[r]
            );
        }
    }
}

#[test]
fn the_safe_step_stops_a_falling_ribbon_a_tenth_of_its_gap_above_the_ground() {
    // a flat ribbon moved straight down by 0.1 m: the path is a straight line (no
    // curvature margin), the lowest rim stops where a tenth of its gap is left
    let (strip, terms, history, mut q, base) = problem(6, true, KineticModel::Full, 54);
    q.iter_mut().for_each(|x| *x = 0.0);
    let s = settings();
    let plain = Objective::new(strip, true, &terms, &history, base);
    let mesh = mesh_at(&plain, &q);
    let (ground, pose) = ground_under(&mesh, Vector3::z(), &s, 0.0);
    let ct = terms_for(6, s, &[ground], &[pose], 0.01, terms.h);
    let obj = Objective::new(strip, true, &terms, &history, base).with_contact(Some(&ct));
    let mut ws = Workspace::default();
    let q0 = q.clone();
    let alpha = obj.safe_step_fraction(&mut ws, &mut |a, out| {
        out.copy_from_slice(&q0);
        out[5] -= 0.1 * a;
    });
    let g0 = 0.3 * s.activation_distance;
    let floor = 0.1 * g0;
    let gap_at = |a: f64| g0 - 0.1 * a;
    assert!(
        gap_at(alpha) >= floor - 1e-12,
        "{alpha}: gap {}",
        gap_at(alpha)
    );
    assert!(
        gap_at(alpha) - floor < 1e-3 * (g0 - floor) + 1e-12,
        "{alpha}: gap {}",
        gap_at(alpha)
    );
    // moving up: free
    let up = obj.safe_step_fraction(&mut ws, &mut |a, out| {
        out.copy_from_slice(&q0);
        out[5] += 0.1 * a;
    });
    assert_eq!(up, 1.0);
}

/// f, the pairs inside the barrier and the gradient at q, from the last checked path's
/// candidates (`cached`) or the broad phase.
fn evaluated(
    obj: &Objective,
    ws: &mut Workspace,
    q: &[f64],
    cached: bool,
) -> (f64, usize, Vec<f64>) {
    let mut g = vec![0.0; q.len()];
    ws.set_on_checked_path(cached);
    let f = obj.evaluate(q, ws, Some((&mut g, GradientMode::Adjoint)), None);
    ws.set_on_checked_path(false);
    (f, ws.contact.active, g)
}

#[test]
fn evaluations_on_a_checked_path_read_the_broad_phases_pairs() {
    // the fold (self, collider-feature and ground pairs) moved along a random path of a
    // few cm: at every point of it up to the safe fraction the candidates give the same
    // pairs as the broad phase (only their summation order differs)
    let (strip, terms, history, q0, base, ct) = folded();
    let obj = Objective::new(strip, true, &terms, &history, base).with_contact(Some(&ct));
    let mut ws = Workspace::default();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(61);
    let d: Vec<f64> = (0..q0.len())
        .map(|_| rng.random_range(-0.05..0.05))
        .collect();
    let at = |a: f64| -> Vec<f64> { q0.iter().zip(&d).map(|(x, y)| x + a * y).collect() };
    let fraction = obj.safe_step_fraction(&mut ws, &mut |a, out| out.copy_from_slice(&at(a)));
    assert!(fraction > 0.0, "no step along the path");
    for k in 0..=8 {
        let q = at(fraction * k as f64 / 8.0);
        let (f_full, active_full, g_full) = evaluated(&obj, &mut ws, &q, false);
        let (f_cached, active_cached, g_cached) = evaluated(&obj, &mut ws, &q, true);
        assert!(active_full > 0, "point {k}: nothing inside the barrier");
        assert_eq!(active_cached, active_full, "point {k}: pairs");
        assert!(
            (f_cached - f_full).abs() <= 1e-12 * f_full.abs(),
            "point {k}: f"
        );
        let scale = g_full.iter().fold(0.0, |m: f64, x| m.max(x.abs()));
        let worst = g_full
            .iter()
            .zip(&g_cached)
            .fold(0.0, |m: f64, (a, b)| m.max((a - b).abs()));
        assert!(
            worst <= 1e-12 * scale,
            "point {k}: gradient off by {worst:.2e} of {scale:.2e}"
        );
    }
    // the check fails when the candidates are not the path's (none at all here)
    ws.candidates = Default::default();
    let (_, active_full, _) = evaluated(&obj, &mut ws, &q0, false);
    let (_, active_cached, _) = evaluated(&obj, &mut ws, &q0, true);
    assert!(
        active_cached < active_full,
        "{active_cached} against {active_full}"
    );
}
