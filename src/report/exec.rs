//! Executes one planned run (an edge: it loads scene files and measures wall time) and
//! keeps its surface at the sample times.

use std::path::Path;
use std::time::Instant;

use anyhow::Context;

use super::plan::{overrides, Method, RunSpec, SceneDefaults, SceneKind};
use crate::baseline::{ConformingFem, ConformingFemParams};
use crate::geometry::SurfaceMesh;
use crate::runner::{self, StepObserver};
use crate::scene::{self, Scene};
use crate::sim::{SimObject, StepReport};
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
    /// Median wall time of a step, ms.
    pub step_ms_median: f64,
    /// Median solver iterations per step (ribbon: inner iterations summed over
    /// augmented-Lagrangian rounds; FEM and paper: Newton iterations).
    pub iterations_median: f64,
    pub unconverged_steps: usize,
    /// Max over steps of the relative edge-length error (dimensionless).
    pub isometry_error_max: f64,
    /// Max over steps of the handle / constraint violation, m.
    pub constraint_violation_max: f64,
    pub finite: bool,
}

/// The scene's kind and the defaults the sweeps start from (`duration` replaces the
/// scene's when given).
pub fn scene_defaults(file: &Path, duration: Option<f64>) -> anyhow::Result<SceneDefaults> {
    let scene = scene::load(file, &[])?;
    let objects = scene.world.objects();
    anyhow::ensure!(
        objects.len() == 1 && scene.world.contact_stage().is_none(),
        "{}: the report runs scenes with one object and no contact",
        file.display()
    );
    let (kind, resolution, tolerance) = match &objects[0] {
        SimObject::Ribbon(r) => (
            SceneKind::Ribbon,
            r.params.segments as f64,
            r.params.solver.tolerance,
        ),
        SimObject::Paper(_) => {
            let p = scene
                .source
                .paper
                .as_ref()
                .context("a paper object without a paper section")?;
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

/// Keeps the surface at the sample times (the step landing on a sample time, or the
/// nearest one: dt values are chosen to divide the sample interval).
struct Sampler<'a> {
    times: &'a [f64],
    next: usize,
    samples: Vec<SurfaceMesh>,
    iterations: Vec<f64>,
}

impl Sampler<'_> {
    fn offer(&mut self, time: f64, dt: f64, mesh: &SurfaceMesh) {
        while self.next < self.times.len() && time >= self.times[self.next] - 0.5 * dt {
            self.samples.push(mesh.clone());
            self.next += 1;
        }
    }
}

impl StepObserver for Sampler<'_> {
    fn after_step(&mut self, scene: &Scene, report: &StepReport, _: f64) -> anyhow::Result<()> {
        let dt = scene.world.dt();
        self.offer(report.time, dt, scene.world.mesh(0));
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
) -> anyhow::Result<RunOutput> {
    let mut scene = scene::load(file, &overrides(kind, duration, spec))?;
    let mut sampler = Sampler {
        times,
        next: 0,
        samples: Vec::new(),
        iterations: Vec::new(),
    };
    if spec.method == Method::ConformingFem {
        return execute_fem(&scene, spec, duration, sampler);
    }
    let stats = runner::run(&mut scene, &mut sampler, &|| false)?;
    Ok(RunOutput {
        spec: spec.clone(),
        samples: sampler.samples,
        steps: stats.steps,
        wall_s: stats.wall_s,
        step_ms_median: stats.step_ms.median,
        iterations_median: stats.solver.iterations_median,
        unconverged_steps: stats.solver.unconverged_steps,
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
) -> anyhow::Result<RunOutput> {
    let params = ConformingFemParams {
        along: spec.resolution.round() as usize,
        newton_tolerance: spec.tolerance,
        ..ConformingFemParams::default()
    };
    let mut fem = ConformingFem::from_world(&scene.world, params)
        .with_context(|| format!("{}: conforming FEM baseline", scene.file.display()))?;
    // a pre-bent start (helix) is first relaxed to the FEM's own near-isometric state
    // (untimed: the ribbon's equivalent is its exact reconstruction)
    fem.relax_initial_stretch(1e-6, 200);
    let steps = (duration / fem.dt()).round().max(1.0) as usize;
    let mut step_ms = Vec::with_capacity(steps);
    let (mut isometry, mut constraint, mut unconverged) = (0.0_f64, 0.0_f64, 0);
    let wall = Instant::now();
    for _ in 0..steps {
        let start = Instant::now();
        let r = fem.step();
        step_ms.push(start.elapsed().as_secs_f64() * 1e3);
        sampler.iterations.push(r.iterations as f64);
        isometry = isometry.max(r.isometry_error);
        constraint = constraint.max(r.constraint_violation);
        unconverged += usize::from(!r.converged);
        sampler.offer(fem.time(), fem.dt(), fem.mesh());
    }
    let wall_s = wall.elapsed().as_secs_f64();
    Ok(RunOutput {
        spec: spec.clone(),
        steps,
        wall_s,
        step_ms_median: percentiles(&step_ms).median,
        iterations_median: percentiles(&sampler.iterations).median,
        unconverged_steps: unconverged,
        isometry_error_max: isometry,
        constraint_violation_max: constraint,
        finite: fem.mesh().is_finite(),
        samples: sampler.samples,
    })
}
