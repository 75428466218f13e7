//! The stiff and extreme stress cases (issue 6) as tests: each runs at the extreme time
//! steps with the `--quick` lengths of `developable_sim stress` and must stay finite,
//! keep its total energy under the work bound (see `developable_sim::stress`), report
//! the violation it cannot avoid, and count its unconverged steps.

use std::path::PathBuf;

use developable_sim::geometry::{Point2, Pose, SurfaceMesh};
use developable_sim::scene;
use developable_sim::sim::{Energies, ObjectSim, ObjectStepReport, SingularPoint, StepContext};
use developable_sim::stress::{self, Allowance, CaseResult, Expectation, RunTweaks, StressCase};

/// Agreement of a case's margins with the same case moved by (10, -5, 3) m: rise /
/// allowance within this (the verdict's threshold is 1), energies and work within this
/// share. Not bit-identical: coordinates 10 m from the origin round differently, and the
/// solvers stop at a relative tolerance of 1e-6 (measured 2026-12-02: 6e-5 on the rise /
/// allowance of bending_x1e-4 at dt 0.01 s, whose rise is a small negative number).
const MARGIN_TOLERANCE: f64 = 1e-3;

fn config() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("config")
}

fn case(name: &str) -> StressCase {
    stress::cases()
        .into_iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no stress case {name}"))
}

/// Run `c` at `dt` with the `--quick` length and `tweaks`: the one call the suite's own
/// negative tests vary.
fn quick_with(c: &StressCase, dt: f64, tweaks: RunTweaks) -> CaseResult {
    stress::run_case_with(c, dt, true, None, &config(), tweaks).unwrap()
}

/// One inner iteration in one augmented-Lagrangian round per step: no step can converge.
fn one_iteration() -> Vec<String> {
    vec![
        "solver.max_iterations=1".to_string(),
        "solver.max_outer_iterations=1".to_string(),
    ]
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
fn a_stretched_paper_sheet_fails_the_suite() {
    // the paper's own length restoration (sec. 6.3) leaves edges next to the held
    // corners strained by 10-50 %: the suite names the strain, not only the energy
    let c = case("paper_crumple");
    let sets = vec!["paper.length_restoration=paper".to_string()];
    let r = quick_with(
        &c,
        0.1,
        RunTweaks {
            sets,
            ..Default::default()
        },
    );
    assert!(!r.pass, "{r:#?}");
    assert!(r.reason.contains("an edge strained by"), "{}", r.reason);
    assert!(
        r.strain_max_pct.unwrap() > stress::PAPER_STRAIN_MAX_PCT,
        "{r:#?}"
    );
    // the table shows the strain beside the verdict
    let shown = format!(
        "{:.2} %; {:.1} %",
        r.strain_max_pct.unwrap(),
        r.strained_edges_pct.unwrap()
    );
    let md = stress::markdown(&stress::StressReport {
        quick: true,
        energy_relative_tolerance: stress::ENERGY_RELATIVE_TOLERANCE,
        paper_energy_relative_tolerance: stress::PAPER_ENERGY_RELATIVE_TOLERANCE,
        energy_absolute_tolerance_j: stress::ENERGY_ABSOLUTE_TOLERANCE,
        unconverged_fraction: stress::UNCONVERGED_FRACTION,
        passed: 0,
        failed: 1,
        results: vec![r],
        wall_s: 0.0,
    });
    assert!(md.contains(&shown), "{shown} in {md}");
    // and the default keeps every edge within its 0.5 % limit
    let r = quick_with(&c, 0.1, RunTweaks::default());
    assert!(r.strain_max_pct.unwrap() < 1.0, "{r:#?}");
    assert!(r.pass, "{r:#?}");
}

#[test]
fn unconverged_steps_are_counted_not_hidden() {
    // no step can converge: every step must be counted
    let path = config().join("scenes/ribbon_two_grippers.yaml");
    let sets = [vec!["duration=0.05".to_string()], one_iteration()].concat();
    let mut s = scene::load(&path, &sets).unwrap();
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
    use developable_sim::session::input::InputPolicy;
    use developable_sim::session::names::NodeNames;
    use developable_sim::session::{Command, Content, OutputTable, RunOutputs, Session};
    use developable_sim::wire::msgs::SimStatus;
    let path = config().join("scenes/ribbon_two_grippers.yaml");
    let s = scene::load(&path, &one_iteration()).unwrap();
    let policy = InputPolicy {
        frame_id: s.frame_id.clone(),
        accept_empty_frame_id: false,
        max_stamp_lead: developable_sim::session::input::DEFAULT_MAX_STAMP_LEAD,
    };
    let names = NodeNames::resolve(&s, "developable_sim", "/", &[]).unwrap();
    let run = RunOutputs {
        own_clock: true,
        recording: false,
        record_cameras: false,
    };
    let table = OutputTable::for_scene(&s, &names, run).unwrap();
    let status_row = table.find("status", developable_sim::session::Scope::Object(0));
    let mut session = Session::new(s, policy, names.handles.clone(), table);
    let mut last: Option<SimStatus> = None;
    for _ in 0..3 {
        session.apply(&Command::Step);
        let frame = session.frame(Content::Statuses).unwrap();
        last = frame
            .decode(status_row.expect("a status row"))
            .map(|r| r.unwrap());
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
        unconverged_fraction: stress::UNCONVERGED_FRACTION,
        passed: 1,
        failed: 0,
        results,
        wall_s: 0.0,
    };
    let md = stress::markdown(&report);
    assert!(md.contains("| handle_jump | 0.1 |"), "{md}");
    // a ribbon has no edge strain column value
    assert!(md.contains("| - |"), "{md}");
    assert!(md.contains("| pass |"), "{md}");
    assert!(md.contains("W(t)"), "the bound is stated: {md}");
}

/// A solver that never moves: every step keeps the state and says it stopped on its
/// iteration limit (what a step with no iterations would report), or, with `rejected`,
/// that its result was not finite and the previous state was kept.
#[derive(Debug)]
struct Frozen(Box<dyn ObjectSim>, bool);

impl ObjectSim for Frozen {
    fn kind(&self) -> &'static str {
        self.0.kind()
    }
    fn solver_name(&self) -> &'static str {
        "frozen"
    }
    fn step(&mut self, _: &StepContext<'_>) -> ObjectStepReport {
        ObjectStepReport {
            converged: false,
            kept_previous_state: self.1,
            constraint_violation: if self.1 { f64::NAN } else { 0.0 },
            energies: self.0.energies(),
            isometry_error: self.0.mesh().isometry_error(),
            ..ObjectStepReport::default()
        }
    }
    fn mesh(&self) -> &SurfaceMesh {
        self.0.mesh()
    }
    fn singular_points(&self) -> &[SingularPoint] {
        self.0.singular_points()
    }
    fn energies(&self) -> Energies {
        self.0.energies()
    }
    fn material_pose(&self, m: &Point2) -> Pose {
        self.0.material_pose(m)
    }
    fn handles_changed(&mut self, index: usize, handles: &[developable_sim::sim::HandleSpec]) {
        self.0.handles_changed(index, handles)
    }
    fn graspable(&self, m: &Point2) -> Result<Point2, String> {
        self.0.graspable(m)
    }
    fn clone_box(&self) -> Box<dyn ObjectSim> {
        Box::new(Frozen(self.0.clone_box(), self.1))
    }
}

fn freeze(world: &mut developable_sim::sim::World) {
    for o in world.objects_mut() {
        let inner = o.clone_box();
        *o = Box::new(Frozen(inner, false));
    }
}

/// Every step's result rejected (non-finite), the state kept.
fn reject(world: &mut developable_sim::sim::World) {
    for o in world.objects_mut() {
        let inner = o.clone_box();
        *o = Box::new(Frozen(inner, true));
    }
}

#[test]
fn a_solver_that_never_moves_fails_every_case() {
    for c in stress::cases() {
        let r = quick_with(
            &c,
            0.1,
            RunTweaks {
                world_hook: Some(&mut freeze),
                ..RunTweaks::default()
            },
        );
        // the energy stays flat, so the energy bound alone would pass it
        assert!(r.finite && r.energy_ratio_max <= 1.0, "{r:#?}");
        assert_eq!(r.unconverged_steps, r.object_steps, "{r:#?}");
        assert!(!r.pass, "{}: a frozen solver passed: {r:#?}", c.name);
        assert!(r.reason.contains("unconverged"), "{r:#?}");
    }
}

#[test]
fn a_solver_held_to_one_iteration_fails_the_suite() {
    // every step stops on the iteration limit
    let c = case("handle_jump");
    let r = quick_with(
        &c,
        0.01,
        RunTweaks {
            sets: one_iteration(),
            ..RunTweaks::default()
        },
    );
    assert!(!r.pass && r.reason.contains("unconverged"), "{r:#?}");
    // the threshold is the stated share: with an allowance of every step, it passes
    // that criterion (whatever else it fails is named separately)
    let lenient = StressCase {
        allowance: Allowance {
            unconverged_fraction: 1.0,
            rejected_steps: 0,
            reason: "test",
        },
        ..c
    };
    let r = quick_with(
        &lenient,
        0.01,
        RunTweaks {
            sets: one_iteration(),
            ..RunTweaks::default()
        },
    );
    assert!(!r.reason.contains("unconverged"), "{r:#?}");
}

#[test]
fn rejected_steps_fail_a_run_unless_the_case_expects_them() {
    // no scene drives our ribbon solver to a non-finite step (1e300 N and 1e308 m/s^2
    // leave it unconverged, not rejected: it backs off non-finite iterates), so a
    // stand-in rejects every step
    let c = case("handle_jump");
    let run = |c: &StressCase| {
        quick_with(
            c,
            0.1,
            RunTweaks {
                world_hook: Some(&mut reject),
                ..RunTweaks::default()
            },
        )
    };
    let r = run(&c);
    assert_eq!(r.rejected_steps, r.steps, "{r:#?}");
    assert!(r.finite, "{r:#?}");
    assert!(!r.pass && r.reason.contains("rejected"), "{r:#?}");
    let expected = StressCase {
        allowance: Allowance {
            unconverged_fraction: 1.0,
            rejected_steps: r.rejected_steps,
            reason: "test",
        },
        ..c
    };
    let r = run(&expected);
    assert!(!r.reason.contains("rejected"), "{r:#?}");
    assert!(!r.reason.contains("unconverged"), "{r:#?}");
}

#[test]
fn injected_energy_fails_the_suite_at_the_stated_bound() {
    // a real run, then the same run with energy added to its last step: just above the
    // allowance it fails, just below it passes
    let c = case("handle_jump");
    let mut totals = Vec::new();
    let mut record = |r: &mut developable_sim::sim::StepReport| {
        totals.push(r.objects.iter().map(|o| o.energies.total()).sum::<f64>());
    };
    let base = quick_with(
        &c,
        0.1,
        RunTweaks {
            report_hook: Some(&mut record),
            ..RunTweaks::default()
        },
    );
    assert!(base.pass, "{base:#?}");
    let last = *totals.last().unwrap();
    let allowance = base.work_bound
        + base.energy_tolerance * (base.energy_initial_stored + base.work_bound)
        + stress::ENERGY_ABSOLUTE_TOLERANCE;
    let headroom = allowance - (last - base.energy_initial);
    assert!(headroom > 0.0, "{base:#?}");
    let steps = base.steps;
    let inject = |extra: f64| {
        let mut n = 0;
        let mut hook = move |r: &mut developable_sim::sim::StepReport| {
            n += 1;
            if n == steps {
                r.objects[0].energies.kinetic += extra;
            }
        };
        quick_with(
            &c,
            0.1,
            RunTweaks {
                report_hook: Some(&mut hook),
                ..RunTweaks::default()
            },
        )
    };
    let above = inject(headroom + 1e-3 * allowance);
    assert!(
        !above.pass && above.reason.contains("energy rose"),
        "{above:#?}"
    );
    assert!(above.energy_ratio_max > 1.0, "{above:#?}");
    let below = inject(headroom - 1e-3 * allowance);
    assert!(below.pass, "{below:#?}");
}

#[test]
fn a_translated_case_gives_the_same_verdict_and_margins() {
    // gravity (its potential) and a point force (its potential) both depend on where
    // the scene sits; the bound does not
    for (name, dt) in [
        ("bending_x1e-4", 0.01),
        ("extreme_drag", 0.1),
        ("handle_jump", 0.1),
    ] {
        let c = case(name);
        let here = stress::run_case(&c, dt, true, None, &config()).unwrap();
        let moved = quick_with(
            &c,
            dt,
            RunTweaks {
                offset: Some([10.0, -5.0, 3.0]),
                ..RunTweaks::default()
            },
        );
        // the move is real: E(0) changed (by m g 3 m for gravity, -F . d for the force)
        assert!(
            (moved.energy_initial - here.energy_initial).abs() > 1e-3,
            "{name}: {here:#?} {moved:#?}"
        );
        assert_eq!(here.pass, moved.pass, "{name}");
        assert_eq!(here.steps, moved.steps, "{name}");
        assert_eq!(here.unconverged_steps, moved.unconverged_steps, "{name}");
        eprintln!(
            "{name} dt {dt}: rise / allowance {:e} here, {:e} moved; E(0) {:e} J here, {:e} J moved",
            here.energy_ratio_max, moved.energy_ratio_max, here.energy_initial, moved.energy_initial
        );
        assert!(
            (here.energy_ratio_max - moved.energy_ratio_max).abs() <= MARGIN_TOLERANCE,
            "{name}: rise / allowance {:e} here, {:e} moved",
            here.energy_ratio_max,
            moved.energy_ratio_max
        );
        let scale = here.work_bound + here.energy_initial_stored;
        let close = |a: f64, b: f64, what: &str| {
            assert!(
                (a - b).abs() <= MARGIN_TOLERANCE * scale.max(a.abs()) + 1e-9,
                "{name} {what}: {a:e} here, {b:e} moved"
            );
        };
        close(here.energy_rise_max, moved.energy_rise_max, "energy rise");
        close(here.work_bound, moved.work_bound, "work bound");
        close(
            here.energy_initial_stored,
            moved.energy_initial_stored,
            "S(0)",
        );
    }
}

/// The contact cases (issue 46): contact inside the step keeps every published frame
/// isometric and nothing overlapping at both quick time steps, within the energy bound
/// that counts the moving finger's work.
#[test]
fn contact_cases_keep_every_frame_exact_and_apart() {
    for name in [
        "contact_falling_n600",
        "contact_falling_stiff",
        "contact_fast_push",
        "contact_chain_impact",
    ] {
        for &dt in case(name).quick_dts {
            let r = check(name, dt);
            assert_eq!(r.expectation, Expectation::ExactContact);
        }
    }
}

/// ... and the same cases with the paper's projection after the step fail them: its
/// published frames are not isometric (the check's teeth).
#[test]
fn a_contact_case_run_with_the_projection_fails_the_suite() {
    for name in [
        "contact_falling_n600",
        "contact_falling_stiff",
        "contact_fast_push",
        "contact_chain_impact",
    ] {
        let r = quick_with(
            &case(name),
            0.01,
            RunTweaks {
                sets: vec!["contact.method=projection".to_string()],
                ..Default::default()
            },
        );
        assert!(!r.pass, "{name} passed with the projection: {r:#?}");
        assert!(r.reason.contains("off isometric"), "{name}: {}", r.reason);
    }
}

/// `stress` writes index.html beside stress.md: per case its energy over time against
/// its bound as an inline SVG plot whose legend names both lines of every time step and
/// whose text does not overlap; the series ends at the run's last step, where its
/// largest rise is the reported one.
#[test]
fn the_suite_page_plots_each_case_against_its_bound() {
    use developable_sim::plot::svg_check::{missing_entries, overlapping, text_boxes};
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("stress_page");
    let _ = std::fs::remove_dir_all(&out);
    let options = stress::SuiteOptions {
        quick: true,
        only: Some("twist_8pi".into()),
        dt: None,
        max_steps: Some(8),
    };
    let report = stress::run_suite(&config(), &out, &options).unwrap();
    assert_eq!(report.results.len(), 3);
    for r in &report.results {
        let series = &r.energy_series;
        assert_eq!(series.len(), r.steps, "{}: one sample a step", r.dt);
        assert!((series.last().unwrap().t_s - r.duration).abs() < 1e-9);
        let rise = series.iter().map(|e| e.rise_j).fold(f64::MIN, f64::max);
        assert_eq!(rise, r.energy_rise_max);
    }
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>") && html.ends_with("</html>\n"));
    assert!(html.contains("<h2 id=\"twist_8pi\">twist_8pi</h2>"));
    let start = html.find("<svg").expect("an inline plot");
    let end = html[start..].find("</svg>").unwrap() + start;
    let boxes = text_boxes(&html[start..end]).unwrap();
    let overlaps = overlapping(&boxes);
    assert!(overlaps.is_empty(), "{overlaps:#?}");
    let legend = [
        "dt = 1 ms: E(t) - E(0)",
        "dt = 1 ms: its bound W(t) + tol(t)",
        "dt = 10 ms: E(t) - E(0)",
        "dt = 0.1 s: its bound W(t) + tol(t)",
        "Solid: the rise of the total energy",
    ];
    let missing = missing_entries(&boxes, &legend);
    assert!(missing.is_empty(), "{missing:?}");
    let md = std::fs::read_to_string(out.join("stress.md")).unwrap();
    assert!(md.contains("`index.html`"), "{md}");
}
