//! The stiff and extreme stress cases (issue 6) as tests: each runs at the extreme time
//! steps with the `--quick` lengths of `developable_sim stress` and must stay finite,
//! keep its total energy under the work bound (see `developable_sim::stress`), report
//! the violation it cannot avoid, and count its unconverged steps.

use std::path::PathBuf;

use developable_sim::scene;
use developable_sim::stress::{self, CaseResult, Expectation, StressCase};

fn config() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("config")
}

fn case(name: &str) -> StressCase {
    stress::cases()
        .into_iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no stress case {name}"))
}

/// Run `name` at `dt` (quick length) and assert the suite's criteria one by one, so a
/// failure names the one that broke.
fn check(name: &str, dt: f64) -> CaseResult {
    let r = stress::run_case(&case(name), dt, true, None, &config()).unwrap();
    assert!(r.steps >= 3, "{r:#?}");
    assert!(r.finite, "{name} dt {dt}: a state was not finite: {r:#?}");
    assert!(
        r.energy_ratio_max <= 1.0,
        "{name} dt {dt}: energy rose {:.3e} J above E(0), bound W = {:.3e} J: {r:#?}",
        r.energy_rise_max,
        r.work_bound
    );
    if let Expectation::ViolationAtLeast(v) = r.expectation {
        assert!(r.constraint_violation_max >= v, "{r:#?}");
    }
    assert!(r.pass, "{r:#?}");
    r
}

#[test]
fn stiff_bending_stays_finite_and_bounded_at_both_extreme_steps() {
    check("bending_x1e4", 0.001);
    check("bending_x1e4", 0.1);
}

#[test]
fn a_stiff_ribbon_follows_its_grippers() {
    // 1000 J bending stiffness, two grippers, 300 steps of 1 ms: the grasp points must
    // stay on their targets, as a robot expects. At the paper's fixed mu = 1e3 the
    // multiplier grew by only mu C per round while the stiff strip barely moved, so
    // ||dq|| fell below the outer tolerance with the grasp point 0.33 m behind (110 of
    // 300 steps on the round limit); the adaptive penalty keeps it within 1.2 mm. The
    // bound here, 1 cm, is half an element (l/n = 2 cm): a lag that size would show.
    let r = stress::run_case(&case("bending_x1e4"), 0.001, false, Some(300), &config()).unwrap();
    assert_eq!(r.steps, 300);
    assert!(r.finite && r.pass, "{r:#?}");
    assert!(r.constraint_violation_max < 1e-2, "{r:#?}");
    assert!(r.unconverged_steps <= 3, "{r:#?}");
}

#[test]
fn soft_bending_stays_finite_and_bounded_at_both_extreme_steps() {
    check("bending_x1e-4", 0.001);
    check("bending_x1e-4", 0.1);
}

#[test]
fn an_8pi_twist_stays_finite_and_bounded() {
    check("twist_8pi", 0.01);
    check("twist_8pi", 0.1);
}

#[test]
fn extreme_drag_stays_finite_and_bounded() {
    let r = check("extreme_drag", 0.01);
    // the drag force does work: the bound is not vacuous (W > 0 and the energy moves)
    assert!(r.work_bound > 0.0, "{r:#?}");
    check("extreme_drag", 0.1);
}

#[test]
fn a_half_metre_handle_jump_in_one_tick_stays_finite_and_bounded() {
    for dt in [0.001, 0.1] {
        let r = check("handle_jump", dt);
        // the jump injects energy through the handle, and the bound accounts for it
        assert!(r.energy_rise_max > 0.0 && r.work_bound > 0.0, "{r:#?}");
        // and the grasp point is on its target at the end of the jump step itself
        // (constraint tolerance 1e-6 m; at the paper's fixed mu, commit d7b920a, it
        // lagged 0.25 m at dt 0.001 s, a 1 mm bound would have caught it)
        assert!(r.constraint_violation_max < 1e-3, "{r:#?}");
    }
}

#[test]
fn over_stretched_handles_saturate_and_report_the_violation() {
    for dt in [0.01, 0.1] {
        let r = check("over_stretch", dt);
        // the violation is reported, and it is the geometric one, not a blow-up: at
        // most the targets' excess over the length (1.5 m - 1 m) plus the sag
        assert!(r.constraint_violation_max <= 0.5 + 0.1, "{r:#?}");
    }
}

#[test]
fn paper_crumpling_and_compression_stay_finite_and_bounded() {
    for dt in [0.001, 0.1] {
        check("paper_crumple", dt);
        check("paper_compression_50", dt);
    }
}

#[test]
fn unconverged_steps_are_counted_not_hidden() {
    // one inner iteration per step cannot converge: every step must be counted
    let path = config().join("scenes/ribbon_two_grippers.yaml");
    let mut s = scene::load(
        &path,
        &[
            "duration=0.05".into(),
            "solver.max_iterations=1".into(),
            "solver.max_outer_iterations=1".into(),
        ],
    )
    .unwrap();
    let stats = developable_sim::runner::run(&mut s, &mut (), &|| false).unwrap();
    assert_eq!(stats.steps, 5);
    assert_eq!(stats.solver.unconverged_steps, 5, "{:?}", stats.solver);
    assert!(stats.finite);
}

#[test]
fn an_absurd_force_never_yields_a_corrupt_state() {
    // 1e300 N overflows the objective: no step is accepted, the solver says so, and
    // the state stays the last valid (finite) one
    let path = config().join("scenes/ribbon_extreme_dragging.yaml");
    let mut s = scene::load(
        &path,
        &[
            "duration=0.03".into(),
            "forces.0.force=[1.0e300, 0.0, 0.0]".into(),
        ],
    )
    .unwrap();
    let before = s.world.mesh(0).vertices.clone();
    let stats = developable_sim::runner::run(&mut s, &mut (), &|| false).unwrap();
    assert!(stats.finite);
    assert_eq!(
        stats.solver.unconverged_steps + stats.solver.rejected_steps,
        3
    );
    assert!(stats.energy.last.is_finite());
    let moved = s
        .world
        .mesh(0)
        .vertices
        .iter()
        .zip(&before)
        .map(|(a, b)| (a - b).norm());
    assert!(moved.fold(0.0, f64::max) < 1e-6, "the state was kept");
}

#[test]
fn the_node_status_counts_unconverged_steps() {
    use developable_sim::ros::input::InputPolicy;
    use developable_sim::ros::session::{FrameContent, Session};
    let path = config().join("scenes/ribbon_two_grippers.yaml");
    let s = scene::load(
        &path,
        &[
            "solver.max_iterations=1".into(),
            "solver.max_outer_iterations=1".into(),
        ],
    )
    .unwrap();
    let policy = InputPolicy {
        frame_id: s.frame_id.clone(),
        accept_empty_frame_id: false,
        max_stamp_lead: developable_sim::ros::input::DEFAULT_MAX_STAMP_LEAD,
    };
    let topics = s.handle_topics.clone();
    let mut session = Session::new(s, policy, topics);
    let content = FrameContent {
        markers: false,
        singular_points: false,
        status: true,
    };
    let mut last = None;
    for _ in 0..3 {
        let (report, ms) = session.step();
        last = session.frame(Some(&report), ms, content).objects[0]
            .status
            .clone();
    }
    let status = last.expect("status asked for");
    assert!(!status.converged);
    assert_eq!((status.unconverged_steps, status.rejected_steps), (3, 0));
}

#[test]
fn the_suite_table_lists_every_run_with_its_verdict() {
    let results = vec![check("handle_jump", 0.1)];
    let report = stress::StressReport {
        quick: true,
        energy_relative_tolerance: stress::ENERGY_RELATIVE_TOLERANCE,
        paper_energy_relative_tolerance: stress::PAPER_ENERGY_RELATIVE_TOLERANCE,
        energy_absolute_tolerance_j: stress::ENERGY_ABSOLUTE_TOLERANCE,
        passed: 1,
        failed: 0,
        results,
        wall_s: 0.0,
    };
    let md = stress::markdown(&report);
    assert!(md.contains("| handle_jump | 0.1 |"), "{md}");
    assert!(md.contains("| pass |"), "{md}");
    assert!(md.contains("W(t)"), "the bound is stated: {md}");
}
