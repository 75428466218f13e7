//! The projection baseline (`contact.method: projection`, Pan et al. sec. 5.2): no
//! vertex ends a step inside a collider or another ribbon, the developability error
//! after contact does not accumulate, results do not depend on the thread count. (The
//! default, contact inside the step, is tested in `contact_barrier.rs`.)
//!
//! Separation is measured independently of the contact stage's own detection: parry's
//! point projection on each collider solid and on a parry `TriMesh` of every other
//! ribbon. A ribbon is a shell of thickness h (`contact.thickness`): its mid-surface
//! must stay h/2 from a collider surface and h from another ribbon's mid-surface. The
//! accepted slack is 1e-4 m (the bound); the stage resolves to 1e-6 m.

use std::path::Path;

use developable_sim::geometry::{Point3, Pose};
use developable_sim::ribbon::RibbonSim;
use developable_sim::scene::{self, Scene};
use developable_sim::sim::StepReport;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::TriMesh;

mod common;
use common::{load, lowest_z};

/// Accepted overlap of thickened surfaces, m.
const SLACK: f64 = 1e-4;

/// The method these tests run.
const PROJECTION: &str = "contact.method=projection";

/// The smallest separation margin over all vertices, m: min over colliders of
/// (signed distance - h/2) and over other ribbons of (distance - h). Negative means
/// overlap.
fn separation_margin(scene: &Scene) -> (f64, String) {
    let world = &scene.world;
    let stage = world.contact_stage().expect("a contact scene");
    let h = stage.settings().thickness;
    let targets: Vec<Pose> = world.current_targets().to_vec();
    let mut worst = (f64::INFINITY, String::new());
    let n = world.objects().len();
    for o in 0..n {
        for (vi, v) in world.mesh(o).vertices.iter().enumerate() {
            for k in 0..stage.colliders().len() {
                if let Some((sd, _)) = stage.collider_signed_distance(k, &targets, &v.coords) {
                    let m = sd - 0.5 * h;
                    if m < worst.0 {
                        worst = (m, format!("object {o} vertex {vi} vs collider {k}"));
                    }
                }
            }
        }
    }
    let meshes: Vec<TriMesh> = (0..n)
        .map(|o| {
            let m = world.mesh(o);
            TriMesh::new(m.vertices.clone(), m.triangles.clone()).expect("a valid mesh")
        })
        .collect();
    for o in 0..n {
        for (p, other) in meshes.iter().enumerate() {
            if p == o {
                continue;
            }
            for (vi, v) in world.mesh(o).vertices.iter().enumerate() {
                let d = other.distance_to_local_point(v, false);
                if d - h < worst.0 {
                    worst = (d - h, format!("object {o} vertex {vi} vs object {p}"));
                }
            }
        }
    }
    worst
}

/// Step a scene for its duration (with overrides), checking separation after every
/// step; returns the reports.
fn run_checked(name: &str, sets: &[&str]) -> (Scene, Vec<StepReport>) {
    let mut sets = sets.to_vec();
    sets.push(PROJECTION);
    let mut s = load(name, &sets);
    let steps = (s.duration / s.world.dt()).round() as usize;
    let mut reports = Vec::new();
    let mut contacts = 0;
    for step in 0..steps {
        let r = s.world.step(&[]);
        let c = r.contact.expect("a contact report");
        assert!(c.report.resolved, "{name} step {step}: {:?}", c.report);
        assert!(
            c.report.penetration_max <= SLACK,
            "{name} step {step}: {:?}",
            c.report
        );
        for o in 0..s.world.objects().len() {
            assert!(
                s.world.mesh(o).is_finite(),
                "{name} step {step}: object {o} not finite"
            );
        }
        let (margin, where_) = separation_margin(&s);
        assert!(
            margin >= -SLACK,
            "{name} step {step}: {where_} overlaps by {:.3e} m",
            -margin
        );
        contacts += c.report.contacts;
        reports.push(r);
    }
    assert!(contacts > 0, "{name}: the run never touched anything");
    (s, reports)
}

#[test]
fn falling_ribbon_stays_above_the_ground_and_its_correction_does_not_accumulate() {
    let (s, reports) = run_checked("ribbon_falling", &["duration=0.6"]);
    // it has landed: the lowest vertex rests at h/2
    let h = s.world.contact_stage().unwrap().settings().thickness;
    let zmin = lowest_z(s.world.mesh(0));
    assert!((zmin - 0.5 * h).abs() < 1e-5, "lowest vertex at {zmin} m");
    // the developability error after contact (|X - X~|) of the resting steps is the
    // one-step gravity sag g h^2 ~ 1e-3 m, bounded, not growing with time
    let corr: Vec<f64> = reports
        .iter()
        .map(|r| r.contact.unwrap().report.correction_max)
        .collect();
    let tail = &corr[corr.len() - 10..];
    let g_h2 = 9.81 * 0.01 * 0.01;
    assert!(
        tail.iter().all(|&c| c < 4.0 * g_h2),
        "correction of resting steps {tail:?} m"
    );
    // the next optimization restarts from the developable reconstruction: the
    // ribbon's own frames stay isometric whatever the correction did
    let r = s
        .world
        .object_as::<RibbonSim>(0)
        .expect("the falling scene holds a ribbon");
    let f = r.frames();
    for j in 0..f.rim_bottom.len() - 1 {
        let len = (f.rim_bottom[j + 1] - f.rim_bottom[j]).norm();
        let rest = r.strip().length / r.strip().segments as f64;
        // bottom rim segments are l/n - w (c_{j+1} - c_j) / 2 long in the flat pattern
        let c = &r.coordinates().crease_direction;
        let want = rest - r.strip().width * (c[j + 1] - c[j]) / 2.0;
        assert!(
            (len - want).abs() < 1e-9,
            "rim segment {j}: {len} vs {want}"
        );
    }
}

#[test]
fn double_chain_impact_keeps_every_loop_apart() {
    run_checked("ribbon_double_chain", &["duration=0.2"]);
}

#[test]
fn mobius_chain_landing_keeps_every_loop_apart() {
    run_checked("ribbon_mobius_chain", &["duration=0.25"]);
}

#[test]
fn gripper_pushes_the_ribbon_without_entering_it() {
    let (s, _) = run_checked("ribbon_gripper_push", &["duration=0.8"]);
    // the finger swept 0.15 m by t = 0.8 s and carried the ribbon's far end along
    let far = s.world.mesh(0).vertices.last().unwrap();
    assert!(far.y > 0.05, "the ribbon was not pushed: far end at {far}");
}

/// A ribbon lying on a plane tilted by `angle` (rad) about x with Coulomb friction mu:
/// the displacement of its centroid after `t` s.
fn slide(angle: f64, mu: f64, t: f64) -> f64 {
    let h = 0.002;
    // lift the mid-surface h/2 (+ 10 um) along the plane normal
    let n = [0.0, -angle.sin(), angle.cos()];
    let lift = 0.5 * h + 1e-5;
    let yaml = format!(
        "duration: {t}\ndt: 0.01\nribbon:\n  segments: 20\n  base: {{mode: floating, position: [{}, {}, {}], rotation: [{angle}, 0, 0]}}\ncolliders:\n  - {{kind: plane, rotation: [{angle}, 0, 0], friction: {mu}}}\ncontact: {{thickness: {h}, method: projection}}\n",
        n[0] * lift,
        n[1] * lift,
        n[2] * lift
    );
    let mut s = scene::load_str(&yaml, Path::new("slope.yaml"), &[]).expect("valid scene");
    let centroid = |s: &Scene| {
        let v = &s.world.mesh(0).vertices;
        v.iter().fold(Point3::origin().coords, |a, p| a + p.coords) / v.len() as f64
    };
    let start = centroid(&s);
    let steps = (t / 0.01_f64).round() as usize;
    for _ in 0..steps {
        let r = s.world.step(&[]);
        assert!(r.contact.unwrap().report.resolved);
    }
    (centroid(&s) - start).norm()
}

#[test]
fn friction_holds_below_the_friction_angle_and_slides_above() {
    let mu: f64 = 0.5; // friction angle atan(0.5) = 26.6 deg
    let t = 0.5;
    let held = slide(20f64.to_radians(), mu, t);
    eprintln!("20 deg: {held} m");
    assert!(held < 1e-3, "slid {held} m on a 20 deg slope with mu = 0.5");
    let angle = 35f64.to_radians();
    let slid = slide(angle, mu, t);
    eprintln!("35 deg: {slid} m");
    // Coulomb: a = g (sin - mu cos); implicit Euler adds O(h) to 1/2 a t^2
    let a = 9.81 * (angle.sin() - mu * angle.cos());
    let want = 0.5 * a * t * t;
    assert!(
        slid > 0.7 * want && slid < 1.3 * want,
        "slid {slid} m on a 35 deg slope, Coulomb predicts {want} m"
    );
    // frictionless: the full g sin
    let free = slide(angle, 0.0, t);
    eprintln!("35 deg frictionless: {free} m");
    let want_free = 0.5 * 9.81 * angle.sin() * t * t;
    assert!(
        free > 0.7 * want_free && free < 1.3 * want_free,
        "slid {free} m without friction, {want_free} m expected"
    );
}

/// The same scene stepped in rayon pools of 1 and 2 threads gives bit-identical meshes.
#[test]
fn results_do_not_depend_on_the_thread_count() {
    let run = |threads: usize| {
        common::on_threads(threads, || {
            let mut s = load("ribbon_double_chain", &["duration=0.15", PROJECTION]);
            let steps = (s.duration / s.world.dt()).round() as usize;
            let mut contacts = 0;
            for _ in 0..steps {
                contacts += s.world.step(&[]).contact.unwrap().report.contacts;
            }
            (common::vertex_bits(&s), contacts)
        })
    };
    let (one, contacts) = run(1);
    let (two, _) = run(2);
    assert!(
        contacts > 0,
        "the chains must have met for this to test the contact stage"
    );
    assert_eq!(one.len(), two.len());
    let differing = one.iter().zip(&two).filter(|(a, b)| a != b).count();
    assert_eq!(
        differing, 0,
        "{differing} coordinates differ between 1 and 2 threads"
    );
}
