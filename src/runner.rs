//! Headless runs: step a scene for its duration, time each step, collect statistics.
//! An edge module (it measures wall time); the CLI, tests and the report use it.

use std::time::Instant;

use crate::scene::Scene;
use crate::sim::{Phase, PhaseClock, StepReport};
use crate::stats::{RunStats, StatsCollector};

/// Called after every step with the world and the report (recording, progress). An
/// observer that can fail (a recorder on a full disk) names its error type; the run
/// stops at its first error (the statistics up to there are lost; a recorder's bag
/// stays readable up to the failure). Observers that cannot fail use `Infallible`.
pub trait StepObserver {
    type Error;
    fn after_step(
        &mut self,
        scene: &Scene,
        report: &StepReport,
        step_ms: f64,
    ) -> Result<(), Self::Error>;
}

impl StepObserver for () {
    type Error = std::convert::Infallible;
    fn after_step(&mut self, _: &Scene, _: &StepReport, _: f64) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// Run `scene` from its current state to its duration. `should_stop` is polled
/// between steps (Ctrl-C).
pub fn run<O: StepObserver + ?Sized>(
    scene: &mut Scene,
    observer: &mut O,
    should_stop: &dyn Fn() -> bool,
) -> Result<RunStats, O::Error> {
    let solver_kind = scene
        .world
        .objects()
        .first()
        .map_or("none", |o| o.solver_name());
    let mut stats = StatsCollector::new(&scene.name, &scene.world, solver_kind);
    let steps = (scene.duration / scene.world.dt()).round().max(1.0) as usize;
    let wall = Instant::now();
    for _ in 0..steps {
        if should_stop() {
            break;
        }
        let clock = PhaseTimer::default();
        let start = Instant::now();
        let report = scene.world.step_with_clock(&[], &clock);
        let step_ms = start.elapsed().as_secs_f64() * 1e3;
        stats.record(&scene.world, &report, step_ms);
        let phases = clock.ms();
        if phases.paper {
            stats.record_phases([phases.simulation, phases.remesh, phases.isometry]);
        }
        if let Some(ms) = phases.contact {
            stats.record_contact_ms(ms);
        }
        observer.after_step(scene, &report, step_ms)?;
    }
    let wall_s = wall.elapsed().as_secs_f64();
    let gradient_us = gradient_cost_us(scene);
    Ok(stats.finish(&scene.world, gradient_us, wall_s))
}

/// Wall time of each phase of one step, ms, summed over objects (they step in
/// parallel, so the sum is CPU time, not the step's wall time).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    pub simulation: f64,
    pub remesh: f64,
    pub isometry: f64,
    /// The contact stage, when the scene has one.
    pub contact: Option<f64>,
    /// True when a phase other than the simulation ran for an object (a paper object).
    pub paper: bool,
}

/// Times the phases of a step (a [`PhaseClock`] shared by the objects' threads).
#[derive(Debug, Default)]
pub struct PhaseTimer {
    times: std::sync::Mutex<PhaseTimes>,
}

impl PhaseTimer {
    pub fn ms(&self) -> PhaseTimes {
        *self.times.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl PhaseClock for PhaseTimer {
    fn time(&self, _object: Option<usize>, phase: Phase, work: &mut dyn FnMut()) {
        let start = Instant::now();
        work();
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let mut t = self.times.lock().unwrap_or_else(|e| e.into_inner());
        match phase {
            Phase::Simulation => t.simulation += ms,
            Phase::Remesh => t.remesh += ms,
            Phase::Isometry => t.isometry += ms,
            Phase::Contact => *t.contact.get_or_insert(0.0) += ms,
        }
        t.paper |= matches!(phase, Phase::Remesh | Phase::Isometry);
    }
}

/// Median wall time of one objective + adjoint gradient evaluation, microseconds.
fn gradient_cost_us(scene: &mut Scene) -> f64 {
    let mut samples = Vec::new();
    let mut g = Vec::new();
    for object in scene.world.objects_mut() {
        // warm the buffers; objects without a step objective are not sampled
        if object.evaluate_gradient(&mut g).is_none() {
            continue;
        }
        for _ in 0..31 {
            let t = Instant::now();
            let f = object.evaluate_gradient(&mut g);
            samples.push(t.elapsed().as_secs_f64() * 1e6);
            std::hint::black_box(f);
        }
    }
    crate::stats::percentiles(&samples).median
}
