//! Executes one planned run (an edge: it loads scene files and measures wall and CPU
//! time) and keeps its surface at the sample times.

use std::path::Path;
use std::time::Instant;

use super::plan::{overrides, Method, RunSpec, SceneDefaults, SceneKind};
use super::report_error::ReportError;
use crate::baseline::{ConformingFem, ConformingFemParams};
use crate::geometry::SurfaceMesh;
use crate::ribbon::RibbonSim;
use crate::runner::{self, StepObserver};
use crate::scene::{self, Scene};
use crate::sim::StepReport;
use crate::stats::percentiles;

/// What a run produced: its surfaces at the sample times and its cost.
#[derive(Clone, Debug)]
pub struct RunOutput {
    pub spec: RunSpec,
    /// World surface at each sample time (object 0).
    pub samples: Vec<SurfaceMesh>,
    pub steps: usize,
    /// Wall time of the whole run, s.
    pub wall_s: f64,
    /// CPU time of the process (every thread) during the run, s: the run time the
    /// report compares, since it does not count the time other processes take from a
    /// shared machine. Equals `wall_s` on an idle machine with one thread.
    pub cpu_s: f64,
    /// Median wall time of a step, ms.
    pub step_ms_median: f64,
    /// Median process CPU time of a step, ms.
    pub step_cpu_ms_median: f64,
    /// Median solver iterations per step (ribbon: inner iterations summed over
    /// augmented-Lagrangian rounds; FEM and paper: Newton iterations).
    pub iterations_median: f64,
    pub unconverged_steps: usize,
    /// Ribbon steps whose solver stopped unconverged after at most one iteration: it
    /// found no step from its start and kept it (the start is the previous state unless
    /// `solver.extrapolate`, so such a step zeroes the velocity). A subset of
    /// `unconverged_steps`; a reference with any is not a converged solution. 0 for the
    /// FEM and paper methods (not counted).
    pub stuck_steps: usize,
    /// Max over steps of the relative edge-length error (dimensionless).
    pub isometry_error_max: f64,
    /// Max over steps of the handle / constraint violation, m.
    pub constraint_violation_max: f64,
    pub finite: bool,
}

/// The scene's kind and the defaults the sweeps start from (`duration` replaces the
/// scene's when given).
pub fn scene_defaults(file: &Path, duration: Option<f64>) -> Result<SceneDefaults, ReportError> {
    let scene = scene::load(file, &[])?;
    let objects = scene.world.objects();
    if objects.len() != 1 || scene.world.has_contact() {
        return Err(ReportError::Invalid(format!(
            "{}: the report runs scenes with one object and no contact",
            file.display()
        )));
    }
    let (kind, resolution, tolerance) = match scene.world.object_as::<RibbonSim>(0) {
        Some(r) => (
            SceneKind::Ribbon,
            r.params.segments as f64,
            r.params.solver.tolerance,
        ),
        None => {
            let p = scene.source.paper.as_ref().ok_or_else(|| {
                ReportError::Invalid(format!(
                    "a {} object: the report runs ribbons and paper",
                    objects[0].kind()
                ))
            })?;
            (SceneKind::Paper, p.boundary_density, p.newton_tolerance)
        }
    };
    Ok(SceneDefaults {
        kind,
        duration: duration.unwrap_or(scene.duration),
        resolution,
        tolerance,
    })
}

/// Overrides that keep a ribbon's initial shape when the run changes its resolution:
/// a `helix` start gives every crease the same bending angle psi (rad), so n creases
/// bend by n psi in all; a run with `n` elements instead of the scene's `n0` gets psi
/// n0 / n, the same curve (same curvature psi n / l, same ruling angle), not a helix
/// with n / n0 times as many turns.
fn same_shape_overrides(
    file: &Path,
    kind: SceneKind,
    spec: &RunSpec,
) -> Result<Vec<String>, ReportError> {
    if kind != SceneKind::Ribbon || spec.method == Method::ConformingFem {
        return Ok(Vec::new());
    }
    let scene = scene::load(file, &[])?;
    let Some(ribbon) = &scene.source.ribbon else {
        return Ok(Vec::new());
    };
    let shape = &ribbon.initial_shape;
    let n0 = ribbon.segments as f64;
    let n = spec.resolution.round();
    Ok(
        if shape.kind.as_deref() == Some("helix") && n != n0 && n > 0.0 {
            vec![format!(
                "ribbon.initial_shape.bending_angle={}",
                shape.bending_angle * n0 / n
            )]
        } else {
            Vec::new()
        },
    )
}

/// Keeps the surface at the sample times (the step landing on a sample time, or the
/// nearest one: dt values are chosen to divide the sample interval).
struct Sampler<'a> {
    times: &'a [f64],
    next: usize,
    samples: Vec<SurfaceMesh>,
    iterations: Vec<f64>,
    /// Process CPU time at the start of the run and after the last step, s.
    cpu_start: f64,
    cpu_last: f64,
    /// Wall clock at the start of the run and its reading after the last step.
    wall_start: Instant,
    wall_last: Instant,
    /// CPU time of each step (from the previous step's end), ms.
    step_cpu_ms: Vec<f64>,
    /// See [`RunOutput::stuck_steps`].
    stuck_steps: usize,
}

/// CPU time consumed by this process so far (all threads), s.
pub fn process_cpu_s() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes one timespec through a valid pointer to a local;
    // CLOCK_PROCESS_CPUTIME_ID is supported on every Linux and macOS.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    if rc != 0 {
        return f64::NAN;
    }
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

impl<'a> Sampler<'a> {
    fn new(times: &'a [f64]) -> Self {
        let cpu = process_cpu_s();
        let now = Instant::now();
        Sampler {
            times,
            next: 0,
            samples: Vec::new(),
            iterations: Vec::new(),
            cpu_start: cpu,
            cpu_last: cpu,
            wall_start: now,
            wall_last: now,
            step_cpu_ms: Vec::new(),
            stuck_steps: 0,
        }
    }

    /// Start the clocks (the run's first step follows).
    fn start(&mut self) {
        self.cpu_start = process_cpu_s();
        self.cpu_last = self.cpu_start;
        self.wall_start = Instant::now();
        self.wall_last = self.wall_start;
    }

    /// Count a step that stopped unconverged within one iteration (see
    /// [`RunOutput::stuck_steps`]).
    fn solver_done(&mut self, iterations: u32, converged: bool) {
        self.stuck_steps += usize::from(!converged && iterations <= 1);
    }

    /// Read the clocks after a step.
    fn step_done(&mut self) {
        let cpu = process_cpu_s();
        self.step_cpu_ms.push((cpu - self.cpu_last) * 1e3);
        self.cpu_last = cpu;
        self.wall_last = Instant::now();
    }

    /// (wall s, CPU s) from the start to the last step's end.
    fn elapsed(&self) -> (f64, f64) {
        (
            (self.wall_last - self.wall_start).as_secs_f64(),
            self.cpu_last - self.cpu_start,
        )
    }
}

impl Sampler<'_> {
    /// Keep `mesh` for every sample time reached (before the step's clocks are read:
    /// the copy is part of the run's cost either way, and small).
    fn offer(&mut self, time: f64, dt: f64, mesh: &SurfaceMesh) {
        while self.next < self.times.len() && time >= self.times[self.next] - 0.5 * dt {
            self.samples.push(mesh.clone());
            self.next += 1;
        }
    }
}

impl StepObserver for Sampler<'_> {
    type Error = std::convert::Infallible;
    fn after_step(
        &mut self,
        scene: &Scene,
        report: &StepReport,
        _: f64,
    ) -> Result<(), Self::Error> {
        let dt = scene.world.dt();
        self.offer(report.time, dt, scene.world.mesh(0));
        for (o, object) in report.objects.iter().zip(scene.world.objects()) {
            if object.downcast_ref::<RibbonSim>().is_some() {
                self.solver_done(o.iterations, o.converged);
            }
        }
        self.step_done();
        Ok(())
    }
}

/// Run `spec` on the scene `file` for `duration` s, sampling at `times`.
pub fn execute(
    file: &Path,
    kind: SceneKind,
    duration: f64,
    spec: &RunSpec,
    times: &[f64],
) -> Result<RunOutput, ReportError> {
    execute_with(file, kind, duration, spec, times, &[])
}

/// [`execute`] with `extra` `--set` overrides applied after the plan's.
pub fn execute_with(
    file: &Path,
    kind: SceneKind,
    duration: f64,
    spec: &RunSpec,
    times: &[f64],
    extra: &[String],
) -> Result<RunOutput, ReportError> {
    let mut set = overrides(kind, duration, spec);
    set.extend(same_shape_overrides(file, kind, spec)?);
    set.extend(extra.iter().cloned());
    let mut scene = scene::load(file, &set)?;
    let mut sampler = Sampler::new(times);
    if spec.method == Method::ConformingFem {
        return execute_fem(&scene, spec, duration, sampler);
    }
    sampler.start();
    let Ok(stats) = runner::run(&mut scene, &mut sampler, &|| false);
    let (wall_s, cpu_s) = sampler.elapsed();
    Ok(RunOutput {
        spec: spec.clone(),
        samples: sampler.samples,
        steps: stats.steps,
        wall_s,
        cpu_s,
        step_ms_median: stats.step_ms.median,
        step_cpu_ms_median: percentiles(&sampler.step_cpu_ms).median,
        iterations_median: stats.solver.iterations_median,
        unconverged_steps: stats.solver.unconverged_steps,
        stuck_steps: sampler.stuck_steps,
        isometry_error_max: stats.isometry_error_max,
        constraint_violation_max: stats.constraint_violation_max,
        finite: stats.finite,
    })
}

fn execute_fem(
    scene: &Scene,
    spec: &RunSpec,
    duration: f64,
    mut sampler: Sampler<'_>,
) -> Result<RunOutput, ReportError> {
    let params = ConformingFemParams {
        along: spec.resolution.round() as usize,
        newton_tolerance: spec.tolerance,
        ..ConformingFemParams::default()
    };
    let mut fem = ConformingFem::from_world(&scene.world, params).map_err(|e| {
        let what = format!("{}: conforming FEM baseline", scene.file.display());
        ReportError::in_run(what, e.into())
    })?;
    // a pre-bent start (helix) is first relaxed to the FEM's own near-isometric state
    // (untimed: the ribbon's equivalent is its exact reconstruction)
    fem.relax_initial_stretch(1e-6, 200);
    let steps = (duration / fem.dt()).round().max(1.0) as usize;
    let mut step_ms = Vec::with_capacity(steps);
    let (mut isometry, mut constraint, mut unconverged) = (0.0_f64, 0.0_f64, 0);
    sampler.start();
    for _ in 0..steps {
        let start = Instant::now();
        let r = fem.step();
        step_ms.push(start.elapsed().as_secs_f64() * 1e3);
        sampler.iterations.push(r.iterations as f64);
        isometry = isometry.max(r.isometry_error);
        constraint = constraint.max(r.constraint_violation);
        unconverged += usize::from(!r.converged);
        sampler.offer(fem.time(), fem.dt(), fem.mesh());
        sampler.step_done();
    }
    let (wall_s, cpu_s) = sampler.elapsed();
    Ok(RunOutput {
        spec: spec.clone(),
        steps,
        wall_s,
        cpu_s,
        step_ms_median: percentiles(&step_ms).median,
        step_cpu_ms_median: percentiles(&sampler.step_cpu_ms).median,
        iterations_median: percentiles(&sampler.iterations).median,
        unconverged_steps: unconverged,
        stuck_steps: 0,
        isometry_error_max: isometry,
        constraint_violation_max: constraint,
        finite: fem.mesh().is_finite(),
        samples: sampler.samples,
    })
}
