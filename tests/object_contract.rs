//! The object contract (`sim::ObjectSim`) as the world uses it: every kind of object
//! steps, reports and offers (or not) a contact body through the trait, and the
//! world's one rule for non-finite handle targets covers the objects and the colliders
//! a handle carries.

use developable_sim::geometry::Pose;
use developable_sim::scene::Scene;

mod common;
use common::load;

/// Bits of every mesh vertex of the world.
fn mesh_bits(s: &Scene) -> Vec<u64> {
    (0..s.world.objects().len())
        .flat_map(|o| s.world.mesh(o).vertices.clone())
        .flat_map(|v| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()])
        .collect()
}

fn nan_pose() -> Pose {
    Pose::translation(f64::NAN, 0.0, f64::INFINITY)
}

/// Steps `s` `steps` times; during steps `bad` handle `handle` gets `target(step)`.
fn run(
    mut s: Scene,
    steps: usize,
    handle: usize,
    bad: std::ops::Range<usize>,
    target: &dyn Fn(&Scene, usize) -> Pose,
) -> Scene {
    let n = s.world.handles().len();
    for step in 0..steps {
        let mut targets = vec![None; n];
        if bad.contains(&step) {
            targets[handle] = Some(target(&s, step));
        }
        let report = s.world.step(&targets);
        assert!(
            report.objects.iter().all(|o| !o.kept_previous_state),
            "step {step} was rejected"
        );
    }
    s
}

/// A non-finite target is the handle's last target: for a gripper finger that only
/// carries a collider pressing on a ribbon (ribbon_gripper_push), NaN targets during
/// steps 30-39 give bit for bit what holding the last target (the world's, at the end
/// of step 29) gives, and holding it differs from following the script (so the test
/// sees the finger).
#[test]
fn a_non_finite_target_holds_the_last_one_for_a_carried_collider() {
    let base = load("ribbon_gripper_push", &[]);
    assert!(!base.world.colliders().is_empty());
    let with_nan = run(base.clone(), 45, 0, 30..40, &|_, _| nan_pose());
    let holding = run(base.clone(), 45, 0, 30..40, &|s, _| {
        s.world.current_targets()[0]
    });
    let scripted = run(base, 45, 0, 0..0, &|_, _| unreachable!());
    assert!(with_nan.world.mesh(0).is_finite());
    assert_eq!(
        with_nan.world.current_targets()[0],
        scripted.world.current_targets()[0],
        "the script resumes after the bad targets"
    );
    assert!(
        mesh_bits(&with_nan) == mesh_bits(&holding),
        "NaN targets must act as the last valid target"
    );
    assert!(
        mesh_bits(&holding) != mesh_bits(&scripted),
        "the held finger must change the run, or this test cannot see the rule"
    );
}

/// The same rule for a paper sheet's handle (paper_cylinder_then_bend).
#[test]
fn a_non_finite_target_holds_the_last_one_for_a_paper_handle() {
    let base = load("paper_cylinder_then_bend", &[]);
    let with_nan = run(base.clone(), 20, 0, 10..15, &|_, _| nan_pose());
    let holding = run(base.clone(), 20, 0, 10..15, &|s, _| {
        s.world.current_targets()[0]
    });
    let scripted = run(base, 20, 0, 0..0, &|_, _| unreachable!());
    assert!(with_nan.world.mesh(0).is_finite());
    assert!(mesh_bits(&with_nan) == mesh_bits(&holding));
    assert!(mesh_bits(&holding) != mesh_bits(&scripted));
}

/// What each kind says through the trait: its scene section, its solver, whether it
/// is a contact body, and energies that match the step report.
#[test]
fn every_kind_answers_through_the_trait() {
    for (scene, kind, solver, contact) in [
        ("ribbon_extreme_torsion", "ribbon", "chain", true),
        ("paper_cylinder_then_bend", "paper", "paper_newton", false),
    ] {
        let mut s = load(scene, &[]);
        let report = s.world.step(&[]);
        let object = s.world.object(0);
        assert_eq!(object.kind(), kind);
        assert_eq!(object.solver_name(), solver);
        assert_eq!(object.contact_body().is_some(), contact, "{scene}");
        assert_eq!(object.energies(), report.objects[0].energies, "{scene}");
        assert_eq!(
            object.singular_points().len(),
            report.objects[0].singular_points
        );
    }
}

/// A reset restores the initial objects (boxed clones taken at construction).
#[test]
fn reset_restores_the_initial_objects() {
    let mut s = load("ribbon_extreme_torsion", &[]);
    let start = mesh_bits(&s);
    for _ in 0..5 {
        s.world.step(&[]);
    }
    assert!(mesh_bits(&s) != start);
    s.world.reset();
    assert!(mesh_bits(&s) == start);
    assert_eq!(s.world.steps_taken(), 0);
}
