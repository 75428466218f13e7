//! `developable_sim stress`: stiff and extreme cases, each run over time steps from
//! 0.001 s to 0.1 s, judged on stability and written as a pass/fail table
//! (`stress.md`, `stress.json`).
//!
//! An edge module (reads scene files, measures wall time, writes files); the cases are
//! the repository's scenes (`config/scenes`, `config/stress`) plus `--set` overrides.
//!
//! A run passes when
//! - every state is finite;
//! - the total energy is bounded by the work done on the objects: at every step
//!   `E(t) - E(0) <= W(t) + tol(t)`, where E is kinetic + elastic + gravity + external
//!   energy (the gravitational potential is part of E, so gravity's work is not added
//!   separately), W(t) the running sum of [`ObjectStepReport::work_bound`] (force at
//!   the end of a step times the displacement of the point it acts on, |F| |Δx|, for
//!   handle constraints, normal guides and point forces) and
//!   `tol(t) = r * (S(0) + W(t)) + ENERGY_ABSOLUTE_TOLERANCE`, r =
//!   [`ENERGY_RELATIVE_TOLERANCE`] (ribbons) or [`PAPER_ENERGY_RELATIVE_TOLERANCE`],
//!   S(0) the kinetic + elastic energy of the initial state. Everything in the bound is
//!   measured relative to the initial state: E(t) - E(0), W and S(0) do not change when
//!   the scene is moved relative to the world origin (the gravity and external
//!   potentials in E(0) do, which is why they are not in the tolerance). Implicit Euler
//!   dissipates energy, so a healthy step never exceeds the bound; the tolerance covers
//!   what the discrete identity does not: the non-convex bending energy and, for
//!   paper, the remeshing and isometry projection between FEM steps;
//! - at most [`UNCONVERGED_FRACTION`] of its object steps stopped on the solver's
//!   iteration limit, and none was rejected (non-finite, previous state kept), unless
//!   the case states a larger [`Allowance`] and why;
//! - the case's own expectation holds (over-stretch: the violation is reported);
//! - a paper sheet stays isometric to its pattern: no S_P edge strained by more than
//!   [`PAPER_STRAIN_MAX_PCT`] in any frame, and at most [`PAPER_STRAINED_EDGES_PCT`] of
//!   its edges strained over 1 % either way on the final frame.
//!
//! [`ObjectStepReport::work_bound`]: crate::sim::ObjectStepReport::work_bound

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

mod output;

pub use output::markdown;

use crate::runner::{self, StepObserver};
use crate::scene::{self, Scene};
use crate::sim::{StepReport, World};

/// Share of |E(0)| + W(t) the energy may exceed the work bound by (see the module doc):
/// ribbons, whose step is one implicit-Euler minimization.
pub const ENERGY_RELATIVE_TOLERANCE: f64 = 0.05;
/// The same for paper: after each FEM step the remeshing rebuilds S_P and the isometry
/// step (Schreck et al. sec. 6) moves its vertices to restore lengths, with no energy
/// balance; at dt 0.001 s this adds about 13 % of W in heavy crumpling (measured).
pub const PAPER_ENERGY_RELATIVE_TOLERANCE: f64 = 0.25;
/// Largest |l / L - 1| any S_P edge of a paper run may reach in any frame, %: an edge
/// 10 % longer or shorter than in the pattern is a sheet that is not paper any more
/// (issue 20).
pub const PAPER_STRAIN_MAX_PCT: f64 = 10.0;
/// Largest share of S_P edges strained by more than 1 % either way on the final frame,
/// %: Schreck et al.'s table IV share of edges compressed over 1 % in their heaviest
/// crumpling (fig. 22, 11 %), counting stretch as well.
pub const PAPER_STRAINED_EDGES_PCT: f64 = 11.0;
/// Absolute energy allowance, J (round-off of energies near zero).
pub const ENERGY_ABSOLUTE_TOLERANCE: f64 = 1e-6;
/// The time steps of every case, s.
const TIME_STEPS: [f64; 3] = [0.001, 0.01, 0.1];
/// Share of a run's object steps that may stop on the solver's iteration limit (the
/// best finite iterate is kept): a healthy case converges nearly everywhere; a solver
/// that never moves (every step on the limit) fails.
pub const UNCONVERGED_FRACTION: f64 = 0.05;

/// How many unconverged and rejected steps a case may have, and why.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Allowance {
    /// Largest share of object steps that stop on the iteration limit, in [0, 1].
    pub unconverged_fraction: f64,
    /// Rejected steps (non-finite result, previous state kept) the case expects.
    pub rejected_steps: usize,
    /// Why the case needs more than the suite's default (empty for the default).
    pub reason: &'static str,
}

/// The suite's default: [`UNCONVERGED_FRACTION`], no rejected step.
const DEFAULT_ALLOWANCE: Allowance = Allowance {
    unconverged_fraction: UNCONVERGED_FRACTION,
    rejected_steps: 0,
    reason: "",
};

/// What a case checks beyond finiteness and the energy bound.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Expectation {
    /// Nothing more.
    Stable,
    /// The constraint cannot be met: the reported violation must reach this, m.
    ViolationAtLeast(f64),
}

/// One stress case: a scene, overrides and how long to run it.
#[derive(Clone, Debug)]
pub struct StressCase {
    pub name: &'static str,
    /// What it stresses (one line for the table).
    pub description: &'static str,
    /// Scene file relative to the config folder.
    pub scene: &'static str,
    /// `--set` overrides for a run of `duration` s with step `dt` s.
    pub overrides: fn(duration: f64, dt: f64) -> Vec<String>,
    /// Simulated time of a full run, s.
    pub duration: f64,
    /// Simulated time of a `--quick` run, s.
    pub quick_duration: f64,
    /// Most steps a run takes (a dt of 0.001 s shortens the run), full and quick.
    pub max_steps: usize,
    pub quick_max_steps: usize,
    /// Time steps a quick run uses (a full run uses [`TIME_STEPS`]).
    pub quick_dts: &'static [f64],
    pub expectation: Expectation,
    /// Relative energy tolerance of the bound.
    pub energy_tolerance: f64,
    /// Unconverged and rejected steps the case may have.
    pub allowance: Allowance,
}

impl StressCase {
    /// Simulated time of a run with step `dt`: the case's duration, cut to the step
    /// limit (`max_steps` replaces the case's), and at least three steps.
    fn duration_for(&self, dt: f64, quick: bool, max_steps: Option<usize>) -> f64 {
        let (d, max) = if quick {
            (self.quick_duration, self.quick_max_steps)
        } else {
            (self.duration, self.max_steps)
        };
        let max = max_steps.unwrap_or(max);
        let steps = ((d / dt).round() as usize).clamp(3, max.max(3));
        steps as f64 * dt
    }

    pub fn dts(&self, quick: bool) -> &'static [f64] {
        if quick {
            self.quick_dts
        } else {
            &TIME_STEPS
        }
    }
}

fn none(_: f64, _: f64) -> Vec<String> {
    Vec::new()
}

/// The suite (issue 6): bending stiffness x1e4 and x1e-4 of the default (0.1 J),
/// an 8 pi twist, extreme drag, a 0.5 m handle jump in one tick, two handles pulled
/// apart beyond the ribbon's length, a 500-element ribbon, heavy paper crumpling and
/// 50 % paper compression.
pub fn cases() -> Vec<StressCase> {
    let mut cases = bending_cases();
    cases.extend(loading_cases());
    cases.push(resolution_case());
    cases.extend(paper_cases());
    cases
}

/// Every time step of a full run (the quick runs of most cases use them all).
const ALL: &[f64] = &TIME_STEPS;

/// Ribbon bending stiffness alpha far from the default 0.1 J: x1e4 and x1e-4.
fn bending_cases() -> Vec<StressCase> {
    vec![
        StressCase {
            name: "bending_x1e4",
            description: "two grippers, bending stiffness 1e4 x default (1000 J)",
            scene: "scenes/ribbon_two_grippers.yaml",
            overrides: |_, _| vec!["ribbon.bending_stiffness=1000.0".into()],
            duration: 2.0,
            quick_duration: 0.5,
            max_steps: 1000,
            quick_max_steps: 60,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
        StressCase {
            name: "bending_x1e-4",
            description: "two grippers, bending stiffness 1e-4 x default (1e-5 J)",
            scene: "scenes/ribbon_two_grippers.yaml",
            overrides: |_, _| vec!["ribbon.bending_stiffness=1.0e-5".into()],
            duration: 2.0,
            quick_duration: 0.5,
            max_steps: 1000,
            quick_max_steps: 60,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
    ]
}

/// Ribbons loaded hard by their handles or a force: an 8 pi twist, a drag of 400 x the
/// loop's weight, a 0.5 m handle jump within one tick, handles pulled apart beyond the
/// ribbon's length.
fn loading_cases() -> Vec<StressCase> {
    vec![
        StressCase {
            name: "twist_8pi",
            description: "one end twisted by 8 pi over the run",
            scene: "scenes/ribbon_extreme_torsion.yaml",
            overrides: |d, _| {
                vec![
                    format!("handles.0.trajectory.motions.0.end={d}"),
                    format!(
                        "handles.0.trajectory.motions.0.angle={}",
                        8.0 * std::f64::consts::PI
                    ),
                ]
            },
            duration: 2.0,
            quick_duration: 1.0,
            max_steps: 1000,
            quick_max_steps: 100,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
        StressCase {
            name: "extreme_drag",
            description: "looped ribbon dragged by 10 x the paper's force (400 x its weight)",
            scene: "scenes/ribbon_extreme_dragging.yaml",
            overrides: |_, _| vec!["forces.0.force=[20.0, 0.0, -10.0]".into()],
            duration: 1.0,
            quick_duration: 0.3,
            max_steps: 1000,
            quick_max_steps: 40,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: Allowance {
                unconverged_fraction: 0.1,
                rejected_steps: 0,
                reason:
                    "at dt 0.001 s the 20 N drag on the closed loop leaves 3 of 40 quick steps \
                         (10, 18, 19; 2026-12-02) with one augmented-Lagrangian round on the \
                         200-iteration inner limit short of the 1e-6 gradient reduction, the loop \
                         closed to 1e-6 m and the energy bound met",
            },
        },
        StressCase {
            name: "handle_jump",
            description: "gripper target jumps 0.5 m within one tick",
            scene: "stress/ribbon_handle_jump.yaml",
            overrides: |d, dt| {
                // half a step after the step nearest a third of the run: the jump
                // falls inside one step, clear of the step boundaries
                let start = ((d / 3.0 / dt).round() + 0.5) * dt;
                vec![
                    format!("handles.0.trajectory.motions.0.start={start}"),
                    format!("handles.0.trajectory.motions.0.end={}", start + 1e-9),
                ]
            },
            duration: 1.0,
            quick_duration: 0.4,
            max_steps: 1000,
            quick_max_steps: 60,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
        StressCase {
            name: "over_stretch",
            description: "two handles pulled to 1.5 m apart on a 1 m inextensible ribbon",
            scene: "stress/ribbon_over_stretch.yaml",
            overrides: |d, _| {
                vec![
                    format!("handles.0.trajectory.motions.0.end={}", d / 2.0),
                    format!("handles.1.trajectory.motions.0.end={}", d / 2.0),
                ]
            },
            duration: 1.0,
            quick_duration: 0.4,
            max_steps: 1000,
            quick_max_steps: 60,
            quick_dts: ALL,
            // grasp points at most l = 1 m apart, targets 1.5 m: the larger of the two
            // violations is at least (1.5 - 1) / 2 m (less a round-off margin)
            expectation: Expectation::ViolationAtLeast(0.25 - 1e-6),
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
    ]
}

/// A fine ribbon: 500 elements.
fn resolution_case() -> StressCase {
    StressCase {
        name: "segments_500",
        description: "two grippers, 500 elements",
        scene: "scenes/ribbon_two_grippers.yaml",
        overrides: |_, _| vec!["ribbon.segments=500".into()],
        duration: 1.0,
        quick_duration: 0.3,
        max_steps: 200,
        // about 1 s per step at dt 0.1 (dense Newton on 1000 unknowns)
        quick_max_steps: 3,
        quick_dts: &[0.001, 0.1],
        expectation: Expectation::Stable,
        energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
        allowance: DEFAULT_ALLOWANCE,
    }
}

/// Paper: heavy crumpling and 50 % compression.
fn paper_cases() -> Vec<StressCase> {
    vec![
        StressCase {
            name: "paper_crumple",
            description: "paper, heavy crumpling (Schreck et al. fig. 22)",
            scene: "scenes/paper_crumple.yaml",
            overrides: none,
            duration: 3.0,
            quick_duration: 1.0,
            max_steps: 1000,
            quick_max_steps: 30,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: PAPER_ENERGY_RELATIVE_TOLERANCE,
            // the suite's default: with the strain-limited length restoration the FEM
            // of step 1 starts each frame from an isometric sheet and converges at dt
            // 0.1 s too (the paper's restoration needed 20 % in 2026-12-02's runs)
            allowance: DEFAULT_ALLOWANCE,
        },
        StressCase {
            name: "paper_compression_50",
            description: "paper, compressed to 50 % of its width",
            scene: "stress/paper_compression.yaml",
            overrides: |d, _| {
                vec![
                    format!("handles.0.trajectory.motions.0.end={d}"),
                    format!("handles.1.trajectory.motions.0.end={d}"),
                ]
            },
            duration: 1.0,
            quick_duration: 1.0,
            max_steps: 1000,
            quick_max_steps: 30,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: PAPER_ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
    ]
}

/// The result of one case at one time step.
#[derive(Clone, Debug, Serialize)]
pub struct CaseResult {
    pub case: String,
    pub description: String,
    /// s
    pub dt: f64,
    pub steps: usize,
    /// Simulated time, s.
    pub duration: f64,
    pub finite: bool,
    /// Total energy at t = 0, J (depends on where the scene sits: not in the bound).
    pub energy_initial: f64,
    /// S(0): kinetic + elastic energy at t = 0, J (the tolerance's scale with W).
    pub energy_initial_stored: f64,
    /// Largest E(t) - E(0) over the run, J.
    pub energy_rise_max: f64,
    /// W at the end of the run: summed work bound of handles and forces, J.
    pub work_bound: f64,
    /// Largest (E(t) - E(0)) / (W(t) + tol(t)) over the run: <= 1 passes.
    pub energy_ratio_max: f64,
    /// Largest handle / loop constraint violation reported, m.
    pub constraint_violation_max: f64,
    pub unconverged_steps: usize,
    /// Object steps of the run (steps x objects): the base of the unconverged share.
    pub object_steps: usize,
    pub rejected_steps: usize,
    pub expectation: Expectation,
    pub allowance: Allowance,
    /// Relative tolerance of the energy bound.
    pub energy_tolerance: f64,
    pub pass: bool,
    /// Paper: the largest |strain| of an S_P edge over all frames and the share of edges
    /// strained over 1 % on the final frame, % (None for ribbons).
    pub strain_max_pct: Option<f64>,
    pub strained_edges_pct: Option<f64>,
    /// Why it failed (empty when it passed).
    pub reason: String,
    /// Wall time of the run, s.
    pub wall_s: f64,
    /// E(t) - E(0) against its bound over the run (at most [`SERIES_POINTS`] samples;
    /// where steps are dropped, the one nearest the bound in each run of steps is kept).
    pub energy_series: Vec<EnergySample>,
}

/// Most samples of a run's energy over time kept in [`CaseResult::energy_series`].
pub const SERIES_POINTS: usize = 250;

/// The energy and its bound after one step.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct EnergySample {
    /// Simulated time, s.
    pub t_s: f64,
    /// E(t) - E(0), J.
    pub rise_j: f64,
    /// W(t) + tol(t), J: the run fails where `rise_j` exceeds it.
    pub allowance_j: f64,
}

/// `series` thinned to at most `max` samples: in each of `max` runs of consecutive
/// steps the sample nearest its bound (largest rise - allowance; a NaN counts as
/// nearest), and always the last one.
fn thin(series: &[EnergySample], max: usize) -> Vec<EnergySample> {
    if series.len() <= max || max < 2 {
        return series.to_vec();
    }
    let chunk = series.len().div_ceil(max - 1);
    let margin = |s: &EnergySample| {
        let m = s.rise_j - s.allowance_j;
        if m.is_nan() {
            f64::INFINITY
        } else {
            m
        }
    };
    let mut out: Vec<EnergySample> = series[..series.len() - 1]
        .chunks(chunk)
        .filter_map(|c| {
            c.iter()
                .max_by(|a, b| margin(a).total_cmp(&margin(b)))
                .copied()
        })
        .collect();
    out.extend(series.last().copied());
    out
}

/// The energy bound, checked after every step.
struct EnergyWatch<'a> {
    /// E(0), J.
    initial: f64,
    /// S(0): kinetic + elastic energy at t = 0, J.
    stored: f64,
    tolerance: f64,
    work: f64,
    rise_max: f64,
    ratio_max: f64,
    /// Every step's E(t) - E(0) and allowance.
    series: Vec<EnergySample>,
    hook: Option<&'a mut dyn FnMut(&mut StepReport)>,
}

impl<'a> EnergyWatch<'a> {
    /// The watch of a run starting from `world`: E(0) and S(0) summed over its
    /// objects, J; `tolerance` relative; `hook` sees each step's report first.
    fn at_start(
        world: &World,
        tolerance: f64,
        hook: Option<&'a mut dyn FnMut(&mut StepReport)>,
    ) -> Self {
        let initial: f64 = world.objects().iter().map(|o| o.energies().total()).sum();
        let stored: f64 = world
            .objects()
            .iter()
            .map(|o| {
                let e = o.energies();
                e.kinetic + e.elastic
            })
            .sum();
        EnergyWatch {
            initial,
            stored,
            tolerance,
            work: 0.0,
            rise_max: f64::NEG_INFINITY,
            ratio_max: f64::NEG_INFINITY,
            series: Vec::new(),
            hook,
        }
    }
}

impl StepObserver for EnergyWatch<'_> {
    type Error = std::convert::Infallible;
    fn after_step(&mut self, _: &Scene, report: &StepReport, _: f64) -> Result<(), Self::Error> {
        let tampered;
        let report = match self.hook.as_mut() {
            Some(hook) => {
                let mut r = report.clone();
                hook(&mut r);
                tampered = r;
                &tampered
            }
            None => report,
        };
        self.work += report.objects.iter().map(|o| o.work_bound).sum::<f64>();
        let e: f64 = report.objects.iter().map(|o| o.energies.total()).sum();
        let rise = e - self.initial;
        let allowance =
            self.work + self.tolerance * (self.stored + self.work) + ENERGY_ABSOLUTE_TOLERANCE;
        self.rise_max = self.rise_max.max(rise);
        // a NaN energy must fail, not vanish in max()
        let ratio = if rise.is_finite() {
            rise / allowance
        } else {
            f64::INFINITY
        };
        self.ratio_max = self.ratio_max.max(ratio);
        self.series.push(EnergySample {
            t_s: report.time,
            rise_j: rise,
            allowance_j: allowance,
        });
        Ok(())
    }
}

/// Which runs of the suite to make.
#[derive(Clone, Debug, Default)]
pub struct SuiteOptions {
    /// Shorter runs (and fewer time steps for the costly cases).
    pub quick: bool,
    /// Only the cases whose name contains this.
    pub only: Option<String>,
    /// Only this time step, s.
    pub dt: Option<f64>,
    /// Replace every case's step limit.
    pub max_steps: Option<usize>,
}

/// Changes to one run, for tests of the suite itself (the suite uses the default).
#[derive(Default)]
pub struct RunTweaks<'a> {
    /// `--set` overrides after the case's own (e.g. `solver.max_iterations=0`).
    pub sets: Vec<String>,
    /// Move the whole scene by this, m (the ribbon's base or the paper's placement;
    /// handle motions are relative to the grasp points).
    pub offset: Option<[f64; 3]>,
    /// Sees each step's report before the suite judges it (a test injects energy).
    pub report_hook: Option<&'a mut dyn FnMut(&mut StepReport)>,
    /// Changes the world once it is built (a test swaps in a solver that never moves).
    pub world_hook: Option<&'a mut dyn FnMut(&mut World)>,
}

/// Why a stress case or the suite could not run (a failed case is a result, not an error).
#[derive(Debug, thiserror::Error)]
pub enum StressError {
    /// The case's scene (with its overrides) does not load.
    #[error("stress case {case} (dt {dt} s)")]
    Scene {
        case: String,
        dt: f64,
        #[source]
        source: scene::SceneError,
    },
    /// The case cannot be moved by an offset (see [`RunTweaks::offset`]).
    #[error("stress case {case} (dt {dt} s): {reason}")]
    CannotMove {
        case: String,
        dt: f64,
        reason: &'static str,
    },
    /// The output folder or a report file could not be written.
    #[error("{message}")]
    Io {
        message: String,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// A plot of index.html could not be drawn.
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
}

/// The override that moves a single-object scene (`source`) by `offset`, m, or why
/// the scene cannot be moved.
fn offset_override(source: &scene::SceneFile, offset: [f64; 3]) -> Result<String, &'static str> {
    let moved = |p: [f64; 3]| {
        format!(
            "[{:?}, {:?}, {:?}]",
            p[0] + offset[0],
            p[1] + offset[1],
            p[2] + offset[2]
        )
    };
    if !(source.ribbons.is_empty() && source.colliders.is_empty()) {
        return Err("moving a scene with a `ribbons:` list or colliders is not supported");
    }
    match (&source.ribbon, &source.paper) {
        (Some(r), None) => Ok(format!("ribbon.base.position={}", moved(r.base.position))),
        (None, Some(p)) => {
            let at = p.placement.as_ref().map_or([0.0; 3], |x| x.position);
            Ok(format!("paper.placement.position={}", moved(at)))
        }
        _ => Err("moving a scene needs exactly one ribbon or paper"),
    }
}

/// Run `case` with step `dt`; scene paths are relative to `config` (the repository's
/// `config/` folder). `max_steps` replaces the case's step limit.
pub fn run_case(
    case: &StressCase,
    dt: f64,
    quick: bool,
    max_steps: Option<usize>,
    config: &Path,
) -> Result<CaseResult, StressError> {
    run_case_with(case, dt, quick, max_steps, config, RunTweaks::default())
}

/// [`run_case`] with `tweaks`.
pub fn run_case_with(
    case: &StressCase,
    dt: f64,
    quick: bool,
    max_steps: Option<usize>,
    config: &Path,
    tweaks: RunTweaks,
) -> Result<CaseResult, StressError> {
    let RunTweaks {
        sets,
        offset,
        report_hook,
        world_hook,
    } = tweaks;
    let duration = case.duration_for(dt, quick, max_steps);
    let mut scene = load_case(case, dt, duration, config, sets, offset)?;
    if let Some(hook) = world_hook {
        hook(&mut scene.world);
    }
    let mut watch = EnergyWatch::at_start(&scene.world, case.energy_tolerance, report_hook);
    let wall = Instant::now();
    let Ok(stats) = runner::run(&mut scene, &mut watch, &|| false);
    let wall_s = wall.elapsed().as_secs_f64();
    let object_steps = stats.steps * scene.world.objects().len();
    let reasons = failure_reasons(case, &stats, &watch, object_steps);
    Ok(CaseResult {
        case: case.name.to_string(),
        description: case.description.to_string(),
        dt,
        steps: stats.steps,
        duration: stats.duration,
        finite: stats.finite,
        energy_initial: watch.initial,
        energy_initial_stored: watch.stored,
        energy_rise_max: watch.rise_max,
        work_bound: watch.work,
        energy_ratio_max: watch.ratio_max,
        constraint_violation_max: stats.constraint_violation_max,
        unconverged_steps: stats.solver.unconverged_steps,
        object_steps,
        rejected_steps: stats.solver.rejected_steps,
        expectation: case.expectation,
        allowance: case.allowance,
        energy_tolerance: case.energy_tolerance,
        strain_max_pct: stats.edge_strain.as_ref().map(|e| e.max.strain_max_pct),
        strained_edges_pct: stats
            .edge_strain
            .as_ref()
            .map(|e| e.final_frame.strained_edges_pct),
        pass: reasons.is_empty(),
        reason: reasons.join("; "),
        wall_s,
        energy_series: thin(&watch.series, SERIES_POINTS),
    })
}

/// The scene of `case` at step `dt`, s, and `duration`, s, with the case's overrides,
/// then `extra` (`--set`s) and, if asked, moved by `offset`, m.
fn load_case(
    case: &StressCase,
    dt: f64,
    duration: f64,
    config: &Path,
    extra: Vec<String>,
    offset: Option<[f64; 3]>,
) -> Result<Scene, StressError> {
    let mut sets = vec![format!("dt={dt}"), format!("duration={duration}")];
    sets.extend((case.overrides)(duration, dt));
    sets.extend(extra);
    let path = config.join(case.scene);
    let load = |sets: &[String]| {
        scene::load(&path, sets).map_err(|source| StressError::Scene {
            case: case.name.to_string(),
            dt,
            source,
        })
    };
    let mut scene = load(&sets)?;
    if let Some(offset) = offset {
        let moved =
            offset_override(&scene.source, offset).map_err(|reason| StressError::CannotMove {
                case: case.name.to_string(),
                dt,
                reason,
            })?;
        sets.push(moved);
        scene = load(&sets)?;
    }
    Ok(scene)
}

/// Why a finished run of `case` fails (empty: it passes): a non-finite state, energy
/// above the work bound, more unconverged or rejected steps than allowed, a
/// constraint violation below the one it is expected to report, or a paper sheet
/// strained beyond [`PAPER_STRAIN_MAX_PCT`] or [`PAPER_STRAINED_EDGES_PCT`].
fn failure_reasons(
    case: &StressCase,
    stats: &crate::stats::RunStats,
    watch: &EnergyWatch,
    object_steps: usize,
) -> Vec<String> {
    let mut reasons = Vec::new();
    if !stats.finite {
        reasons.push("non-finite state".to_string());
    }
    // ratio_max is +inf after a non-finite energy (see EnergyWatch)
    if watch.ratio_max > 1.0 {
        reasons.push(format!(
            "energy rose {:.3e} J, above the work bound {:.3e} J + tolerance",
            watch.rise_max, watch.work
        ));
    }
    let allowed = case.allowance;
    let unconverged = stats.solver.unconverged_steps;
    if unconverged as f64 > allowed.unconverged_fraction * object_steps as f64 {
        reasons.push(format!(
            "{unconverged} of {object_steps} steps unconverged, more than {} %",
            allowed.unconverged_fraction * 100.0
        ));
    }
    if stats.solver.rejected_steps > allowed.rejected_steps {
        reasons.push(format!(
            "{} steps rejected (non-finite, previous state kept), {} expected",
            stats.solver.rejected_steps, allowed.rejected_steps
        ));
    }
    if let Expectation::ViolationAtLeast(v) = case.expectation {
        if stats.constraint_violation_max.is_nan() || stats.constraint_violation_max < v {
            reasons.push(format!(
                "constraint violation reported {:.3e} m, expected at least {v:.3e} m",
                stats.constraint_violation_max
            ));
        }
    }
    if let Some(e) = &stats.edge_strain {
        // NaN fails too
        if !(e.max.strain_max_pct <= PAPER_STRAIN_MAX_PCT) {
            reasons.push(format!(
                "an edge strained by {:.1} %, more than {PAPER_STRAIN_MAX_PCT} %",
                e.max.strain_max_pct
            ));
        }
        if !(e.final_frame.strained_edges_pct <= PAPER_STRAINED_EDGES_PCT) {
            reasons.push(format!(
                "{:.1} % of the edges strained over 1 % at the end, more than \
                 {PAPER_STRAINED_EDGES_PCT} %",
                e.final_frame.strained_edges_pct
            ));
        }
    }
    reasons
}

/// The whole suite's outcome (`stress.json`).
#[derive(Clone, Debug, Serialize)]
pub struct StressReport {
    pub quick: bool,
    /// Relative energy tolerance of ribbon and paper cases.
    pub energy_relative_tolerance: f64,
    pub paper_energy_relative_tolerance: f64,
    pub energy_absolute_tolerance_j: f64,
    /// Default share of unconverged steps a run may have.
    pub unconverged_fraction: f64,
    pub results: Vec<CaseResult>,
    pub passed: usize,
    pub failed: usize,
    /// Wall time of the suite, s.
    pub wall_s: f64,
}

/// Run every case selected by `options` at each of its time steps, print one line
/// per run, and write `out/stress.md`, `out/stress.json` and `out/index.html` (each
/// case's energy over time against its bound).
pub fn run_suite(
    config: &Path,
    out: &Path,
    options: &SuiteOptions,
) -> Result<StressReport, StressError> {
    let quick = options.quick;
    std::fs::create_dir_all(out).map_err(|source| StressError::Io {
        message: format!("cannot create the output folder {}", out.display()),
        source,
    })?;
    let wall = Instant::now();
    let mut results = Vec::new();
    for case in cases() {
        if options
            .only
            .as_ref()
            .is_some_and(|f| !case.name.contains(f.as_str()))
        {
            continue;
        }
        let dts: Vec<f64> = match options.dt {
            Some(dt) => vec![dt],
            None => case.dts(quick).to_vec(),
        };
        for dt in dts {
            let r = run_case(&case, dt, quick, options.max_steps, config)?;
            println!(
                "{:<22} dt {:<6} {:>5} steps  {}  {:.1} s{}",
                r.case,
                r.dt,
                r.steps,
                if r.pass { "pass" } else { "FAIL" },
                r.wall_s,
                if r.pass {
                    String::new()
                } else {
                    format!(": {}", r.reason)
                }
            );
            results.push(r);
        }
    }
    let failed = results.iter().filter(|r| !r.pass).count();
    let report = StressReport {
        quick,
        energy_relative_tolerance: ENERGY_RELATIVE_TOLERANCE,
        paper_energy_relative_tolerance: PAPER_ENERGY_RELATIVE_TOLERANCE,
        energy_absolute_tolerance_j: ENERGY_ABSOLUTE_TOLERANCE,
        unconverged_fraction: UNCONVERGED_FRACTION,
        passed: results.len() - failed,
        failed,
        results,
        wall_s: wall.elapsed().as_secs_f64(),
    };
    let json = out.join("stress.json");
    let write = |path: &Path, text: String| {
        std::fs::write(path, text).map_err(|source| StressError::Io {
            message: format!("writing {}", path.display()),
            source,
        })
    };
    write(&json, serde_json::to_string_pretty(&report)?)?;
    write(&out.join("stress.md"), markdown(&report))?;
    write(&out.join("index.html"), output::index(&report)?)?;
    Ok(report)
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;

    fn config() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("config")
    }

    fn first_case() -> StressCase {
        cases()
            .into_iter()
            .next()
            .expect("at least one stress case")
    }

    /// Thinning keeps the last sample and, in each run of steps, the one nearest the
    /// bound: a spike above it is never dropped.
    #[test]
    fn thinning_keeps_the_sample_nearest_the_bound() {
        let series: Vec<EnergySample> = (0..1000)
            .map(|k| EnergySample {
                t_s: k as f64 * 1e-3,
                rise_j: if k == 537 { 2.0 } else { 0.0 },
                allowance_j: 1.0,
            })
            .collect();
        let thinned = thin(&series, SERIES_POINTS);
        assert!(thinned.len() <= SERIES_POINTS, "{}", thinned.len());
        assert!(thinned.iter().any(|s| s.rise_j == 2.0));
        assert_eq!(thinned.last(), series.last());
        assert_eq!(thin(&series[..10], SERIES_POINTS).len(), 10);
    }

    #[test]
    fn offset_moves_a_single_ribbon_and_refuses_a_ribbons_list() {
        let one = scene::load(&config().join("scenes/ribbon_extreme_torsion.yaml"), &[]).unwrap();
        let moved = offset_override(&one.source, [1.0, 0.0, 0.0]).unwrap();
        assert!(moved.starts_with("ribbon.base.position=["), "{moved}");
        let list = scene::load(&config().join("scenes/ribbon_double_chain.yaml"), &[]).unwrap();
        let err = offset_override(&list.source, [1.0, 0.0, 0.0]).unwrap_err();
        assert!(err.contains("`ribbons:` list"), "{err}");
    }

    #[test]
    fn a_bad_override_names_the_case_and_the_scene_error() {
        let case = first_case();
        let tweaks = RunTweaks {
            sets: vec!["no_such_key=1".into()],
            ..RunTweaks::default()
        };
        let err = run_case_with(&case, 0.01, true, Some(3), &config(), tweaks).unwrap_err();
        assert!(matches!(err, StressError::Scene { .. }), "{err:?}");
        let text = format!("{:#}", anyhow::Error::from(err));
        assert!(
            text.starts_with(&format!("stress case {} (dt 0.01 s): ", case.name)),
            "{text}"
        );
        assert!(text.contains("no_such_key"), "{text}");
    }
}
