//! Headless runs: step a scene for its duration, time each step, collect statistics.
//! An edge module (it measures wall time); the CLI, tests and the report use it.

use std::time::Instant;

use crate::ribbon::objective::GradientMode;
use crate::scene::Scene;
use crate::sim::{Phase, PhaseClock, SimObject, StepReport};
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
            SimObject::Paper(_) => "paper_newton",
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
        let mut clock = PhaseTimer::default();
        let start = Instant::now();
        let report = scene.world.step_with_clock(&[], &mut clock);
        let step_ms = start.elapsed().as_secs_f64() * 1e3;
        stats.record(&scene.world, &report, step_ms);
        if clock.paper {
            stats.record_phases(clock.ms);
        }
        observer.after_step(scene, &report, step_ms)?;
    }
    let wall_s = wall.elapsed().as_secs_f64();
    let gradient_us = gradient_cost_us(scene);
    Ok(stats.finish(&scene.world, gradient_us, wall_s))
}

/// Times the phases of the paper objects' frames (the ribbon's step is one phase).
#[derive(Clone, Copy, Debug, Default)]
pub struct PhaseTimer {
    /// Simulation, remesh, isometry, ms (summed over objects).
    pub ms: [f64; 3],
    /// True when a phase other than the simulation ran (a paper object).
    pub paper: bool,
}

impl PhaseClock for PhaseTimer {
    fn time(&mut self, _object: usize, phase: Phase, work: &mut dyn FnMut()) {
        let start = Instant::now();
        work();
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let k = match phase {
            Phase::Simulation => 0,
            Phase::Remesh => 1,
            Phase::Isometry => 2,
        };
        self.ms[k] += ms;
        self.paper |= phase != Phase::Simulation;
    }
}

/// Median wall time of one objective + adjoint gradient evaluation, microseconds.
pub fn gradient_cost_us(scene: &mut Scene) -> f64 {
    let mut samples = Vec::new();
    let mut g = Vec::new();
    for object in scene.world.objects_mut() {
        let SimObject::Ribbon(r) = object else {
            continue;
        };
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
