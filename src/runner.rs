//! Headless runs: step a scene for its duration, time each step, collect statistics.
//! An edge module (it measures wall time); the CLI, tests and the report use it.

use std::time::Instant;

use crate::ribbon::objective::GradientMode;
use crate::scene::Scene;
use crate::sim::{SimObject, StepPhase, StepReport};
use crate::stats::{RunStats, StatsCollector};

/// Called after every step with the world and the report (recording, progress).
pub trait StepObserver {
    fn after_step(
        &mut self,
        scene: &Scene,
        report: &StepReport,
        step_ms: f64,
    ) -> anyhow::Result<()>;
}

impl StepObserver for () {
    fn after_step(&mut self, _: &Scene, _: &StepReport, _: f64) -> anyhow::Result<()> {
        Ok(())
    }
}

/// Run `scene` from its current state to its duration. `should_stop` is polled
/// between steps (Ctrl-C).
pub fn run(
    scene: &mut Scene,
    observer: &mut dyn StepObserver,
    should_stop: &dyn Fn() -> bool,
) -> anyhow::Result<RunStats> {
    let solver_kind = scene
        .world
        .objects()
        .iter()
        .map(|o| match o {
            SimObject::Ribbon(r) => match r.params.solver.kind {
                crate::ribbon::SolverKind::GaussNewton => "gauss_newton",
                crate::ribbon::SolverKind::Lbfgsb => "lbfgsb",
            },
        })
        .next()
        .unwrap_or("none");
    let mut stats = StatsCollector::new(&scene.name, &scene.world, solver_kind);
    let steps = (scene.duration / scene.world.dt()).round().max(1.0) as usize;
    let wall = Instant::now();
    for _ in 0..steps {
        if should_stop() {
            break;
        }
        let start = Instant::now();
        let mut contact_start = None;
        let mut contact_ms = None;
        let report = scene.world.step_observed(&[], &mut |phase| match phase {
            StepPhase::ContactStart => contact_start = Some(Instant::now()),
            StepPhase::ContactEnd => {
                contact_ms = contact_start.map(|s: Instant| s.elapsed().as_secs_f64() * 1e3)
            }
        });
        let step_ms = start.elapsed().as_secs_f64() * 1e3;
        stats.record(&scene.world, &report, step_ms);
        if let Some(ms) = contact_ms {
            stats.record_contact_ms(ms);
        }
        observer.after_step(scene, &report, step_ms)?;
    }
    let wall_s = wall.elapsed().as_secs_f64();
    let gradient_us = gradient_cost_us(scene);
    Ok(stats.finish(&scene.world, gradient_us, wall_s))
}

/// Median wall time of one objective + adjoint gradient evaluation, microseconds.
pub fn gradient_cost_us(scene: &mut Scene) -> f64 {
    let mut samples = Vec::new();
    let mut g = Vec::new();
    for object in scene.world.objects_mut() {
        let SimObject::Ribbon(r) = object;
        r.evaluate_gradient(GradientMode::Adjoint, &mut g); // warm the buffers
        for _ in 0..31 {
            let t = Instant::now();
            let f = r.evaluate_gradient(GradientMode::Adjoint, &mut g);
            samples.push(t.elapsed().as_secs_f64() * 1e6);
            std::hint::black_box(f);
        }
    }
    crate::stats::percentiles(&samples).median
}
