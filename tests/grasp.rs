//! Grasp, release and the wrench a handle feels, against exact references: a ribbon
//! hung from one clamping handle under gravity (the force is its weight; the torque is
//! the heavy cantilever's root moment from the elastica, at second order in n), a strip
//! buckled between two clamping handles (the axial force is the elastica's), and a
//! swinging ribbon whose handle force plus gravity is its rate of change of momentum.
//! Then the run-time mechanics: no snap at a grasp, a released end falls, idempotent
//! grasps and releases, refusals, and a sheet grasped where it had no vertex.

use std::path::Path;

use developable_sim::geometry::{Point2, Point3, Vector3};
use developable_sim::metrics::elastica::{clamped_buckled, heavy_cantilever, PlanarCurve};
use developable_sim::ribbon::RibbonSim;
use developable_sim::scene::{self, Scene};
use developable_sim::sim::{GraspAt, GraspError, Hold};

const G: f64 = 9.81;

fn load(yaml: &str) -> Scene {
    scene::load_str(yaml, Path::new("test.yaml"), &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// A floating ribbon (1 m x 0.05 m, n segments, rho 0.1 kg/m^2, alpha `alpha` J) lying
/// along +x from the origin, quasi-static, with `handles` (YAML list items) and
/// gravity `gz` (m/s^2 along z).
fn floating(n: usize, alpha: f64, gz: f64, handles: &str, duration: f64) -> String {
    format!(
        "duration: {duration}\ndt: 0.01\ngravity: [0.0, 0.0, {gz}]\n\
         solver: {{tolerance: 1.0e-10, constraint_tolerance: 1.0e-10}}\n\
         ribbon:\n  length: 1.0\n  width: 0.05\n  segments: {n}\n  density: 0.1\n\
         \x20 bending_stiffness: {alpha}\n  kinetic: quasi_static\n\
         \x20 base: {{mode: floating, position: [0.0, 0.0, 0.0]}}\n\
         handles:\n{handles}"
    )
}

fn run(s: &mut Scene) {
    let steps = (s.duration / s.world.dt()).round() as usize;
    for _ in 0..steps {
        s.world.step(&[]);
    }
}

/// The moment about the clamp of the weight q (N/m) of the exact curve: q ∫ x(s) ds
/// (Simpson, 2000 intervals: far below the comparison's tolerance).
fn weight_moment(curve: &PlanarCurve, q: f64) -> f64 {
    let m = 2000;
    let h = curve.length / m as f64;
    let x = |k: usize| curve.at(k as f64 * h)[0];
    let mut sum = x(0) + x(m);
    for k in 1..m {
        sum += x(k) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    q * sum * h / 3.0
}

/// Relative error of the torque a clamping handle at the end of a hanging ribbon
/// feels, against the heavy cantilever's root moment; asserts the force is the weight.
fn cantilever_torque_error(n: usize) -> f64 {
    let clamp = "  - {name: clamp, point: [0.0, 0.0], orientation: full}\n";
    let (alpha, w, rho, l) = (0.05, 0.05, 0.1, 1.0);
    let mut s = load(&floating(n, alpha, -G, clamp, 0.03));
    run(&mut s);
    let wrench = s.world.handle_wrench(0).expect("a step was taken");
    let weight = rho * w * l * G;
    // what the ribbon exerts on the gripper: its weight, straight down
    let want = Vector3::new(0.0, 0.0, -weight);
    // (measured 3e-12 relative on 2026-12-07: the balance of forces holds to the
    // solver's tolerance; the issue asks for 1e-6)
    assert!(
        (wrench.force - want).norm() < 1e-10 * weight,
        "n = {n}: force {} against the weight {want}",
        wrench.force
    );
    // and the moment of that weight about the clamp: + y for a ribbon along + x
    let exact = weight_moment(
        &heavy_cantilever(l, 2.0 * alpha * w, rho * w * G),
        rho * w * G,
    );
    assert!(
        wrench.torque.x.abs() < 1e-9 && wrench.torque.z.abs() < 1e-9,
        "{}",
        wrench.torque
    );
    (wrench.torque.y - exact).abs() / exact
}

#[test]
fn a_clamping_handle_feels_the_weight_and_the_heavy_cantilevers_root_moment() {
    let errors: Vec<f64> = [25, 50, 100]
        .iter()
        .map(|&n| cantilever_torque_error(n))
        .collect();
    // measured 2.9e-3, 7.1e-4, 1.8e-4 at n = 25, 50, 100 (2026-12-07); the bound
    // at n = 50 is 5e-3
    assert!(errors[1] < 1e-3, "{errors:?}");
    // second order in n: halving the element quarters the error (a first-order clamp
    // gives 2)
    for pair in errors.windows(2) {
        let ratio = pair[0] / pair[1];
        assert!((3.0..5.5).contains(&ratio), "orders {errors:?}");
    }
}

#[test]
fn a_strip_buckled_between_two_clamping_handles_feels_the_elastica_load() {
    let (alpha, w, l, d) = (0.1, 0.05, 1.0, 0.9);
    let handles = format!(
        "  - {{name: near, point: [0.0, 0.0], orientation: full}}\n\
         \x20 - {{name: far, point: [1.0, 0.0], orientation: full, trajectory: {{initial: \
         {{position: [{d}, 0.0, 0.0]}}}}}}\n"
    );
    let mut yaml = floating(50, alpha, 0.0, &handles, 0.05);
    // start bulging up (the first mode), as the exact-solution scene does
    yaml = yaml.replace(
        "  base: {mode: floating, position: [0.0, 0.0, 0.0]}\n",
        "  base: {mode: floating, position: [0.0, 0.0, 0.0]}\n  initial_shape: {kind: helix, \
         crease_direction: 0.0, bending_angle: -0.004}\n",
    );
    let mut s = load(&yaml);
    run(&mut s);
    let exact = clamped_buckled(l, 2.0 * alpha * w, d).load;
    let near = s.world.handle_wrench(0).expect("stepped");
    let far = s.world.handle_wrench(1).expect("stepped");
    // the strip pushes both grippers outwards: -x on the near one, +x on the far one
    for (wrench, sign) in [(near, -1.0), (far, 1.0)] {
        // measured 9.7e-4 at n = 50 (2026-12-07); the bound is 1e-2
        let err = (sign * wrench.force.x - exact).abs() / exact;
        assert!(
            err < 2e-3,
            "axial force {} against {exact} N",
            wrench.force.x
        );
        let across = wrench.force.y.abs().max(wrench.force.z.abs());
        assert!(across < 1e-6 * exact, "{}", wrench.force);
    }
}

/// A ribbon swinging down from a pinching handle (position held, orientation free):
/// every step, the handle's force on the ribbon plus gravity is the change of its
/// momentum over the step (implicit Euler: (P^{n+1} - P^n) / h = F^{n+1}). The
/// swing stays in the x-z plane with c = 0, so the material points and the masses do
/// not change and the momentum is sum m_i v_i over the rim points.
#[test]
fn the_handle_force_plus_gravity_is_the_rate_of_change_of_momentum() {
    let pinch = "  - {name: pinch, point: [0.0, 0.0]}\n";
    let yaml = floating(20, 0.02, -G, pinch, 0.2).replace("kinetic: quasi_static", "kinetic: full");
    let mut s = load(&yaml);
    let h = s.world.dt();
    let weight = Vector3::new(0.0, 0.0, -0.1 * 0.05 * 1.0 * G);
    let momentum = |s: &Scene| s.world.object_as::<RibbonSim>(0).unwrap().momentum();
    let mut before = momentum(&s);
    let mut largest: f64 = 0.0;
    for _ in 0..20 {
        s.world.step(&[]);
        let after = momentum(&s);
        // the gripper feels the opposite of what it does to the ribbon
        let on_ribbon = -s.world.handle_wrench(0).unwrap().force;
        let residual = (after - before) / h - (on_ribbon + weight);
        largest = largest.max(residual.norm() / weight.norm());
        assert!(after.norm() > 0.0);
        before = after;
    }
    // the balance holds to the solver's tolerance (a wrong sign or a missing term is
    // off by the weight itself)
    // (measured 3e-12 of the weight on 2026-12-07)
    assert!(
        largest < 1e-10,
        "momentum balance off by {largest} of the weight"
    );
}

/// A scene with a ribbon hanging from a clamp at u = 0 and a free gripper `picker`
/// starting at the far end, open.
fn picker_scene() -> Scene {
    let handles = "  - {name: clamp, point: [0.0, 0.0], orientation: full}\n\
                   \x20 - {name: picker, point: [1.0, 0.0], attached: false, \
                   trajectory: {initial: {position: [0.6, 0.0, -0.2]}}}\n";
    let yaml =
        floating(30, 0.02, -G, handles, 1.0).replace("kinetic: quasi_static", "kinetic: full");
    load(&yaml)
}

#[test]
fn a_grasp_holds_the_point_where_it_is_and_a_release_lets_it_fall() {
    let mut s = picker_scene();
    assert!(!s.world.handles()[1].attached);
    for _ in 0..30 {
        s.world.step(&[]);
    }
    // the picker closes on the far end where it is now, 0.4 m or more from the gripper
    let end = Point2::new(1.0, 0.0);
    let before = s
        .world
        .object(0)
        .grasp_pose(&end)
        .unwrap()
        .translation
        .vector;
    let g = s.world.grasp(1, 0, GraspAt::Material(end), None).unwrap();
    assert!(g.changed && g.distance == 0.0);
    let gripper = s.world.current_targets()[1].translation.vector;
    assert!(
        (before - gripper).norm() > 0.1,
        "the point is away from the gripper"
    );
    // no snap: with the gripper still, the point stays where it was grasped
    for _ in 0..20 {
        s.world.step(&[]);
    }
    let held = s
        .world
        .object(0)
        .grasp_pose(&end)
        .unwrap()
        .translation
        .vector;
    assert!(
        (held - before).norm() < 1e-4,
        "moved {} m",
        (held - before).norm()
    );
    assert!(s.world.handle_wrench(1).is_some());
    // the same grasp again changes nothing
    let again = s.world.grasp(1, 0, GraspAt::Material(end), None).unwrap();
    assert!(!again.changed);
    // release: the end falls
    assert_eq!(s.world.release(1), Ok(true));
    assert_eq!(s.world.release(1), Ok(false));
    assert!(s.world.handle_wrench(1).is_none());
    for _ in 0..20 {
        s.world.step(&[]);
    }
    let fallen = s
        .world
        .object(0)
        .grasp_pose(&end)
        .unwrap()
        .translation
        .vector;
    assert!(fallen.z < held.z - 0.01, "{} -> {}", held.z, fallen.z);
}

#[test]
fn grasps_that_cannot_hold_are_refused_and_change_nothing() {
    let mut s = picker_scene();
    s.world.step(&[]);
    let off = s
        .world
        .grasp(1, 0, GraspAt::Material(Point2::new(1.2, 0.0)), None);
    assert!(matches!(off, Err(GraspError::NotGraspable(_))), "{off:?}");
    let far = GraspAt::Nearest {
        point: Point3::new(0.0, 5.0, 0.0),
        max_distance: 0.05,
    };
    assert!(matches!(
        s.world.grasp(1, 0, far, None),
        Err(GraspError::TooFar { .. })
    ));
    assert_eq!(
        s.world
            .grasp(7, 0, GraspAt::Material(Point2::new(0.5, 0.0)), None),
        Err(GraspError::UnknownHandle(7))
    );
    assert_eq!(
        s.world
            .grasp(1, 3, GraspAt::Material(Point2::new(0.5, 0.0)), None),
        Err(GraspError::UnknownObject(3))
    );
    assert!(!s.world.handles()[1].attached && s.world.handles()[1].generation == 0);
    // the nearest point, within reach: on the surface, at the distance said
    let p = s
        .world
        .object(0)
        .grasp_pose(&Point2::new(0.7, 0.01))
        .unwrap();
    let probe = Point3::from(p.translation.vector + Vector3::new(0.0, 0.0, 0.003));
    let at = GraspAt::Nearest {
        point: probe,
        max_distance: 0.01,
    };
    let g = s.world.grasp(1, 0, at, Some(Hold::Position)).unwrap();
    assert!(
        (g.material_point - Point2::new(0.7, 0.01)).norm() < 1e-3,
        "{g:?}"
    );
    assert!((g.distance - 0.003).abs() < 1e-4, "{g:?}");
}

/// A sheet grasped on its boundary where S_P had no vertex gets one there (nothing
/// moves), and an interior point is refused (Schreck et al. hold the boundary).
#[test]
fn a_sheet_is_grasped_on_its_boundary_only() {
    let mut s = developable_sim::scene::load(
        Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/config/scenes/paper_unload.yaml"
        )),
        &[],
    )
    .unwrap();
    s.world.step(&[]);
    let h = 0;
    let interior = s
        .world
        .grasp(h, 0, GraspAt::Material(Point2::new(0.03, 0.03)), None);
    assert!(
        matches!(interior, Err(GraspError::NotGraspable(_))),
        "{interior:?}"
    );
    // a boundary point between the existing vertices
    let edge = Point2::new(0.0317, 0.0);
    let old = s.world.mesh(0).clone();
    assert!(!old.material.iter().any(|m| (m - edge).norm() < 1e-9));
    let g = s.world.grasp(h, 0, GraspAt::Material(edge), None).unwrap();
    assert!(g.changed && (g.material_point - edge).norm() < 1e-12);
    let mesh = s.world.mesh(0);
    assert!(
        mesh.material.iter().any(|m| (m - edge).norm() < 1e-9),
        "a vertex there"
    );
    // S_P was rebuilt around it with positions interpolated: every vertex the old and
    // the new S_P share kept its place
    let mut shared = 0;
    for (m, p) in old.material.iter().zip(&old.vertices) {
        if let Some(k) = mesh.material.iter().position(|x| (x - m).norm() < 1e-12) {
            shared += 1;
            assert!((mesh.vertices[k] - p).norm() < 1e-12, "{m} moved");
        }
    }
    assert!(
        shared > old.vertices.len() / 2,
        "{shared} of {}",
        old.vertices.len()
    );
}

/// What `ribbon_pick_and_place.yaml` did, run with `contact.method` = `method`.
struct PickAndPlace {
    grasped_at: Option<f64>,
    released_at: Option<f64>,
    /// The held end's offset from the picker's target when it closed, and at 2.1 s
    /// (lifted 0.2 m), m.
    offset: Vector3,
    lifted: Vector3,
    /// The mesh when the picker opened.
    at_release: Vec<Point3>,
    /// The largest rise of the total energy from one step to the next after the
    /// release, J (nothing does work on the ribbon then).
    largest_rise_after_release: f64,
    scene: Scene,
}

fn pick_and_place(method: &str) -> PickAndPlace {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("config/scenes/ribbon_pick_and_place.yaml");
    let set = [format!("contact.method={method}")];
    let mut s = scene::load(&path, &set).unwrap_or_else(|e| panic!("{e}"));
    let end = Point2::new(0.6, 0.0);
    let steps = (s.duration / s.world.dt()).round() as usize;
    let (mut grasped_at, mut released_at) = (None, None);
    let (mut offset, mut lifted) = (None, None);
    let mut at_release = Vec::new();
    let mut largest_rise_after_release = f64::NEG_INFINITY;
    // where the end and the picker's target were after the previous step
    let mut before = (Vector3::zeros(), Vector3::zeros());
    let mut energy_before = 0.0;
    for _ in 0..steps {
        let r = s.world.step(&[]);
        let energy = s.world.object(0).energies().total();
        if released_at.is_some() {
            largest_rise_after_release = largest_rise_after_release.max(energy - energy_before);
        }
        for c in &r.scripted {
            assert_eq!(c.result, Ok(true), "{c:?}");
            if c.grasp {
                grasped_at = Some(r.time);
                offset = Some(before.0 - before.1);
            } else {
                released_at = Some(r.time);
                at_release = s.world.mesh(0).vertices.clone();
            }
        }
        energy_before = energy;
        let at = s
            .world
            .object(0)
            .grasp_pose(&end)
            .unwrap()
            .translation
            .vector;
        let target = s.world.current_targets()[0].translation.vector;
        if (r.time - 2.1).abs() < 1e-9 {
            lifted = Some(at - target);
        }
        before = (at, target);
    }
    PickAndPlace {
        grasped_at,
        released_at,
        offset: offset.unwrap(),
        lifted: lifted.unwrap(),
        at_release,
        largest_rise_after_release,
        scene: s,
    }
}

/// The box of `ribbon_pick_and_place.yaml` (x -0.1..1.1, y 0.2..0.4, top at 0.08 m).
fn in_box(p: &Point3) -> bool {
    (-0.1..=1.1).contains(&p.x) && (0.2..=0.4).contains(&p.y) && p.z < 0.08
}

/// `ribbon_pick_and_place.yaml` (barrier contact): the open gripper closes on the far
/// end at 1 s (found within its grasp radius), lifts it 0.2 m, carries it across the
/// box, lowers it beyond and opens at 4.6 s with the ribbon draped across the box. Let
/// go, the ribbon slides off the box towards its longer far side (2026-12-07: the total
/// energy falls from 2.18e-3 J at the release to 2.8e-5 J on the table at 6.4 s, one
/// rise of 6.0e-8 J on the way) and comes to rest on the table beyond it by the end of
/// the scene (7 s).
#[test]
fn the_pick_and_place_scene_picks_carries_drapes_and_releases_the_ribbon() {
    let run = pick_and_place("barrier");
    // a scripted change acts at the start of the step that ends at its time
    assert_eq!(run.grasped_at.map(|t| (t * 100.0).round()), Some(100.0));
    assert_eq!(run.released_at.map(|t| (t * 100.0).round()), Some(460.0));
    let s = &run.scene;
    assert!(!s.world.handles()[0].attached);
    // no snap: the end is held where it lay, 1.5 mm under the target that was coming
    // down, and keeps that offset while lifted 0.2 m (measured 1.8e-8 m off: the handle's
    // augmented-Lagrangian constraint; the projection moved the mesh 7.1e-5 m)
    assert!(
        run.offset.norm() > 1e-3 && run.offset.norm() < 2e-3,
        "{}",
        run.offset
    );
    let drift = (run.lifted - run.offset).norm();
    assert!(drift < 5e-8, "{} vs {}", run.lifted, run.offset);
    // draped at the release: on the box top (within 1 cm of it) and on both sides
    let on_top = |p: &&Point3| (0.2..=0.4).contains(&p.y) && (0.08..0.09).contains(&p.z);
    let draped = run.at_release.iter().filter(on_top).count();
    assert!(draped >= 4, "{draped} vertices on the box top");
    assert!(run.at_release.iter().any(|p| p.y < 0.2) && run.at_release.iter().any(|p| p.y > 0.4));
    // nothing does work after the release: the energy only falls (barrier and lagged
    // friction may add round-off; measured largest rise 6.0e-8 J of 2.2e-3 J)
    assert!(
        run.largest_rise_after_release < 1e-7,
        "energy rose {:.3e} J in one step after the release",
        run.largest_rise_after_release
    );
    // at rest on the table beyond the box and never inside it
    let mesh = s.world.mesh(0);
    assert!(mesh
        .vertices
        .iter()
        .all(|p| !in_box(p) && p.z > 0.0 && p.z < 2e-3));
    assert!(mesh.vertices.iter().all(|p| p.y > 0.4));
}

/// The negative test of the energy check: with the post-step projection (Pan et al.
/// sec. 5.2) the released ribbon gains energy (measured 262 rises after the release,
/// the largest 4.7e-5 J, 2026-12-07).
#[test]
fn the_projection_adds_energy_after_the_release_the_check_sees_it() {
    let run = pick_and_place("projection");
    assert!(
        run.largest_rise_after_release > 1e-5,
        "{:.3e}",
        run.largest_rise_after_release
    );
}
