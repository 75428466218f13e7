//! The node's latency samples, ms: the simulator step, tick -> markers and accepted
//! input -> markers over the whole run, and the same in 10 s windows (with the memory
//! in use) so that a drift over a long run shows.

use std::time::{Duration, Instant};

use crate::ros::node_stats::{rss_kib, LatencyStats, NodeStats, Window};

/// Length of a statistics window, s of wall time.
const WINDOW: Duration = Duration::from_secs(10);

pub(super) struct Latency {
    step_ms: Vec<f64>,
    tick_ms: Vec<f64>,
    input_ms: Vec<f64>,
    window_start: Instant,
    window_tick: Vec<f64>,
    window_input: Vec<f64>,
    window_steps: u64,
    pub(super) window_inputs: u64,
    pub(super) started: Instant,
}

impl Latency {
    pub(super) fn new() -> Self {
        Latency {
            step_ms: Vec::new(),
            tick_ms: Vec::new(),
            input_ms: Vec::new(),
            window_start: Instant::now(),
            window_tick: Vec::new(),
            window_input: Vec::new(),
            window_steps: 0,
            window_inputs: 0,
            started: Instant::now(),
        }
    }

    /// The run starts now (the first window too).
    pub(super) fn start(&mut self) {
        self.started = Instant::now();
        self.window_start = self.started;
    }

    /// A step of the simulator took `step_s` seconds.
    pub(super) fn step(&mut self, step_s: f64) {
        self.step_ms.push(step_s * 1e3);
        self.window_steps += 1;
    }

    /// Markers went out at `published_at` for a tick started at `trigger`, and for the
    /// inputs accepted at `inputs` since the last tick.
    pub(super) fn published(
        &mut self,
        published_at: Instant,
        trigger: Instant,
        inputs: impl Iterator<Item = Instant>,
    ) {
        let ms = published_at.duration_since(trigger).as_secs_f64() * 1e3;
        self.tick_ms.push(ms);
        self.window_tick.push(ms);
        for at in inputs {
            let ms = published_at.duration_since(at).as_secs_f64() * 1e3;
            self.input_ms.push(ms);
            self.window_input.push(ms);
        }
    }

    /// Closes the current window into `stats` when it is 10 s old (or `last`).
    pub(super) fn roll_window(&mut self, stats: &mut NodeStats, last: bool) {
        let elapsed = self.window_start.elapsed();
        if elapsed < WINDOW && !last {
            return;
        }
        if elapsed.is_zero() {
            return;
        }
        stats.windows.push(Window {
            end_s: self.started.elapsed().as_secs_f64(),
            rss_kib: rss_kib(),
            steps: self.window_steps,
            inputs: self.window_inputs,
            tick_to_markers: LatencyStats::of(&self.window_tick),
            input_to_markers: LatencyStats::of(&self.window_input),
        });
        self.window_tick.clear();
        self.window_input.clear();
        self.window_steps = 0;
        self.window_inputs = 0;
        self.window_start = Instant::now();
    }

    /// The run's latency statistics into `stats`.
    pub(super) fn finish(&self, stats: &mut NodeStats) {
        stats.wall_s = self.started.elapsed().as_secs_f64();
        stats.step = LatencyStats::of(&self.step_ms);
        stats.tick_to_markers = LatencyStats::of(&self.tick_ms);
        let beyond: Vec<f64> = self
            .tick_ms
            .iter()
            .zip(&self.step_ms)
            .map(|(tick, step)| tick - step)
            .collect();
        stats.tick_beyond_step = LatencyStats::of(&beyond);
        stats.input_to_markers = LatencyStats::of(&self.input_ms);
    }
}
