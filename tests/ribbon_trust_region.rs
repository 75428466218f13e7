//! The trust-region solver (`solver.kind: trust_region`, issue 47) against the damped
//! chain solver it would replace: along the damped solver's trajectory over 0.3 s, one
//! step of each from the same state every step, the same step minimizer (RMS <= 1e-9
//! m at matched material points) where both converge, and the same singular-point
//! counts when each runs on its own. Where that holds (measured on every ribbon scene
//! at n = 50 and 100 by `examples/solver_agreement.rs`, docs/ribbon_chain_solver.md):
//! the three exact_* scenes (the vibrating cantilever and the buckled strip at n = 50
//! only) and the two gripper scenes. Elsewhere it does not; the extreme and wide
//! torsions are asserted below as the measured gaps.
//!
//! The interior-point method (`solver.kind: interior_point`, issue 47) against the same
//! baseline, where it reaches the damped minimizer (docs/ribbon_chain_solver.md,
//! 2026-12-07): the cantilevers and the gripper scenes without active bounds.

use developable_sim::metrics::{rms_distance, strip_samples};
use developable_sim::ribbon::{RibbonSim, SolverKind};
use developable_sim::scene::{self, Scene};
use developable_sim::sim::StepReport;

mod common;
use common::scene_path;

fn load(name: &str, n: usize) -> Scene {
    let sets = vec![format!("ribbon.segments={n}")];
    scene::load(&scene_path(name), &sets).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn set_kind(s: &mut Scene, kind: SolverKind, tolerance: Option<f64>) {
    for i in 0..s.world.objects().len() {
        if let Some(r) = s.world.object_as_mut::<RibbonSim>(i) {
            r.params.solver.kind = kind;
            if let Some(t) = tolerance {
                r.params.solver.tolerance = t;
            }
        }
    }
}

fn converged(r: &StepReport) -> bool {
    r.objects.iter().all(|o| o.converged)
}

fn singular(r: &StepReport) -> usize {
    r.objects.iter().map(|o| o.singular_points).sum()
}

/// What 0.3 s of a scene says about the two solvers.
#[derive(Debug)]
struct Agreement {
    steps: usize,
    /// Steps from the same state where both converged, and the largest RMS among them, m.
    both_converged: usize,
    largest_rms: f64,
    /// Steps whose singular-point counts differ, each solver on its own trajectory.
    singular_differ: usize,
}

/// The damped chain solver's trajectory over 0.3 s; at every step one trust-region
/// step (tolerance `tolerance`, or the scene's) from the same state; and the trust
/// region's own trajectory alongside.
fn agreement(name: &str, n: usize, tolerance: Option<f64>) -> Agreement {
    agreement_of(SolverKind::TrustRegion, name, n, tolerance)
}

/// [`agreement`] for another solver `kind` than the trust region's.
fn agreement_of(kind: SolverKind, name: &str, n: usize, tolerance: Option<f64>) -> Agreement {
    let mut damped = load(name, n);
    set_kind(&mut damped, SolverKind::Chain, None);
    let mut alone = damped.clone();
    set_kind(&mut alone, kind, tolerance);
    let steps = (0.3 / damped.world.dt()).round() as usize;
    let mut out = Agreement {
        steps,
        both_converged: 0,
        largest_rms: 0.0,
        singular_differ: 0,
    };
    for _ in 0..steps {
        let mut trust = damped.clone();
        set_kind(&mut trust, kind, tolerance);
        let rt = trust.world.step(&[]);
        let rd = damped.world.step(&[]);
        if converged(&rd) && converged(&rt) {
            out.both_converged += 1;
            for i in 0..damped.world.objects().len() {
                let strip = *damped
                    .world
                    .object_as::<RibbonSim>(i)
                    .expect("a ribbon")
                    .strip();
                let samples = strip_samples(strip.length, strip.width, 101, 3);
                let rms = rms_distance(damped.world.mesh(i), trust.world.mesh(i), &samples)
                    .expect("samples inside");
                out.largest_rms = out.largest_rms.max(rms);
            }
        }
        let ra = alone.world.step(&[]);
        out.singular_differ += usize::from(singular(&ra) != singular(&rd));
    }
    out
}

/// The target of issue 47. Both solvers stop on the same relative projected-gradient
/// tolerance (1e-6) and f-decrease test, so where the step's minimizer is isolated and
/// well conditioned they stop within round-off of each other; where it is not
/// (soft modes, bifurcations) the distance is set by the stopping test, not by 1e-9.
const SAME_MINIMIZER: f64 = 1e-9;

#[test]
fn trust_region_reaches_the_damped_minimizer_where_both_converge() {
    // measured (2026-12-07, a2e15ff): largest RMS 1.9e-10 m (heavy cantilever n = 50),
    // 6.6e-10 m (buckled strip n = 50), 8.4e-12 m (vibrating cantilever n = 50), below
    // 1e-15 m elsewhere; every step converged with both; no singular points on either
    for (name, n) in [
        ("exact_heavy_cantilever", 50),
        ("exact_heavy_cantilever", 100),
        ("exact_buckled_strip", 50),
        ("exact_vibrating_cantilever", 50),
        ("ribbon_gripper_push", 50),
        ("ribbon_gripper_push", 100),
        ("ribbon_pick_and_place", 50),
        ("ribbon_pick_and_place", 100),
    ] {
        let a = agreement(name, n, None);
        eprintln!("{name} n={n}: {a:?}");
        assert_eq!(
            a.both_converged, a.steps,
            "{name} n={n}: a step did not converge"
        );
        assert!(
            a.largest_rms <= SAME_MINIMIZER,
            "{name} n={n}: RMS {} m",
            a.largest_rms
        );
        assert_eq!(a.singular_differ, 0, "{name} n={n}: singular points");
    }
}

#[test]
fn the_agreement_check_sees_a_trust_region_stopped_early() {
    // negative control: the trust region at a relative tolerance of 1e-2 on the heavy
    // cantilever stops short of the minimizer the damped solver reaches
    let a = agreement("exact_heavy_cantilever", 50, Some(1e-2));
    eprintln!("tolerance 1e-2: {a:?}");
    assert!(a.both_converged > 0);
    assert!(a.largest_rms > SAME_MINIMIZER, "{a:?}");
}

#[test]
fn known_gap_the_torsions_reach_other_minimizers() {
    // Open (issue 47): from a flat strip twisted at one end (a bifurcation), the two
    // solvers converge to step minimizers millimetres apart in the first three steps of
    // the extreme torsion (4.7e-3 m at step 1, n = 50), then agree to 1e-10-1e-8 m
    // (their stopping tests); on the wide torsion they part at step 3 (5.9e-4 m) and
    // their own trajectories reach different singular-point counts in 10 of 30 steps
    // (at most 9 against 10). Asserted as measured so that a change shows here.
    let torsion = agreement("ribbon_extreme_torsion", 50, None);
    eprintln!("extreme torsion: {torsion:?}");
    assert_eq!(torsion.both_converged, torsion.steps);
    assert!(torsion.largest_rms > 1e-3, "fixed? {torsion:?}");
    assert_eq!(torsion.singular_differ, 0);
    let wide = agreement("ribbon_wide_torsion", 50, None);
    eprintln!("wide torsion: {wide:?}");
    assert_eq!(wide.both_converged, wide.steps);
    assert!(wide.largest_rms > 1e-4, "fixed? {wide:?}");
    assert!(wide.singular_differ > 0, "fixed? {wide:?}");
}

#[test]
fn interior_point_reaches_the_damped_minimizer_where_no_bound_is_active() {
    // measured (2026-12-07, 4b5c2e0): largest RMS 8.0e-11 m (heavy cantilever n = 50),
    // 3.2e-10 m (n = 100), 8.4e-12 m (vibrating cantilever), 1.9e-13 m (gripper push,
    // pick and place); every step converged with both, no singular points
    for (name, n) in [
        ("exact_heavy_cantilever", 50),
        ("exact_heavy_cantilever", 100),
        ("exact_vibrating_cantilever", 50),
        ("ribbon_gripper_push", 50),
        ("ribbon_pick_and_place", 50),
    ] {
        let a = agreement_of(SolverKind::InteriorPoint, name, n, None);
        eprintln!("{name} n={n}: {a:?}");
        assert_eq!(
            a.both_converged, a.steps,
            "{name} n={n}: a step did not converge"
        );
        assert!(
            a.largest_rms <= SAME_MINIMIZER,
            "{name} n={n}: RMS {} m",
            a.largest_rms
        );
        assert_eq!(a.singular_differ, 0, "{name} n={n}: singular points");
    }
}

#[test]
fn the_agreement_check_sees_an_interior_point_method_stopped_early() {
    // negative control: the interior-point method alone at a relative tolerance of
    // 1e-2 on the heavy cantilever stops short of the damped solver's minimizer
    // (measured 2.7e-5 m)
    let a = agreement_of(
        SolverKind::InteriorPoint,
        "exact_heavy_cantilever",
        50,
        Some(1e-2),
    );
    eprintln!("tolerance 1e-2: {a:?}");
    assert!(a.both_converged > 0);
    assert!(a.largest_rms > SAME_MINIMIZER, "{a:?}");
}
