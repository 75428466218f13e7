//! Real-time honesty: the real-time factor (simulated over wall time, over the last
//! second) for `SimStatus.real_time_factor`, and one line on stderr when the node stays
//! below 0.95 of its target for a second (and one when it is back). The target is the
//! `real_time_factor` parameter when the node owns time and paces in real time, the
//! clock's own rate under use_sim_time; as fast as possible, lock-step and paused
//! have none (the factor is still reported). The line changes only when the factor has
//! been on the other side of the threshold for a whole second, so a factor hovering at
//! 0.95 does not fill stderr.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// The factor is measured over this much wall time.
pub(super) const WINDOW: Duration = Duration::from_secs(1);
/// Below this share of its target, the node says it cannot keep up.
pub(super) const SLOW: f64 = 0.95;

/// Cumulative values sampled at wall times, kept for one [`WINDOW`].
#[derive(Default)]
struct Window {
    /// (wall time, cumulative value, cumulative step wall time s, steps)
    samples: VecDeque<(Instant, f64, f64, u64)>,
}

impl Window {
    fn push(&mut self, now: Instant, value: f64, step_s: f64, steps: u64) {
        self.samples.push_back((now, value, step_s, steps));
        // keep one sample at least WINDOW old, so the span is a full window
        while self.samples.len() > 2 && now.duration_since(self.samples[1].0) >= WINDOW {
            self.samples.pop_front();
        }
    }

    fn span(&self) -> Option<f64> {
        let (first, last) = (self.samples.front()?, self.samples.back()?);
        let s = last.0.duration_since(first.0).as_secs_f64();
        (s > 0.0).then_some(s)
    }

    /// Value per wall second over the window (None: under two samples apart in time).
    fn rate(&self) -> Option<f64> {
        let (first, last) = (self.samples.front()?, self.samples.back()?);
        Some((last.1 - first.1) / self.span()?)
    }

    /// Mean step wall time over the window, s.
    fn mean_step(&self) -> Option<f64> {
        let (first, last) = (self.samples.front()?, self.samples.back()?);
        let n = last.3.checked_sub(first.3).filter(|n| *n > 0)?;
        Some((last.2 - first.2) / n as f64)
    }

    fn full(&self) -> bool {
        self.span().is_some_and(|s| s >= WINDOW.as_secs_f64())
    }

    fn restart(&mut self, now: Instant) {
        let last = self.samples.back().copied();
        self.samples.clear();
        if let Some((_, v, s, n)) = last {
            self.samples.push_back((now, v, s, n));
        }
    }
}

/// The node's real-time factor and whether it was said to be slow.
#[derive(Default)]
pub(super) struct RealTimeWatch {
    steps: Window,
    clock: Window,
    /// Simulated time stepped since start-up, s, and the steps' wall time, s.
    simulated: f64,
    step_wall: f64,
    count: u64,
    slow: bool,
    /// Since when the factor has been on the other side of the threshold (None: it is
    /// on the side `slow` says).
    flipping_since: Option<Instant>,
}

/// What the node is trying to keep up with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Target {
    /// Nothing (as fast as possible, lock-step, paused).
    None,
    /// This many simulated seconds per wall second, ticking every `period`.
    Factor { factor: f64, period: Duration },
    /// The external clock's rate, stepping `dt` at a time.
    Clock { dt: f64 },
}

impl RealTimeWatch {
    /// Start (or start again after a pause, a change of target or a clock jump): the
    /// window restarts now, so time spent not trying to keep up is not counted.
    pub(super) fn restart(&mut self, now: Instant) {
        if self.steps.samples.is_empty() {
            self.steps.push(now, 0.0, 0.0, 0);
        }
        self.steps.restart(now);
        self.clock.restart(now);
    }

    /// A step of `dt` (s) that took `step_s` of wall time ended at `now`.
    pub(super) fn step(&mut self, now: Instant, dt: f64, step_s: f64) {
        self.simulated += dt;
        self.step_wall += step_s;
        self.count += 1;
        self.steps
            .push(now, self.simulated, self.step_wall, self.count);
    }

    /// The external clock read `clock_s` at `now`.
    pub(super) fn clock(&mut self, now: Instant, clock_s: f64) {
        self.clock.push(now, clock_s, 0.0, 0);
    }

    /// Simulated over wall time over the last second (0 before two samples).
    pub(super) fn factor(&self) -> f64 {
        self.steps.rate().unwrap_or(0.0)
    }

    /// The line to say at `now`, if the node has been below [`SLOW`] of `target` for a
    /// second (over full windows), or back above it for a second.
    pub(super) fn judge(&mut self, now: Instant, target: Target) -> Option<String> {
        let factor = self.factor();
        let (wanted, period) = match target {
            Target::None => {
                self.flipping_since = None;
                return None;
            }
            Target::Factor { factor, period } => (factor, period.as_secs_f64()),
            Target::Clock { dt } => {
                let rate = self.clock.rate().filter(|r| *r > 0.0)?;
                (rate, dt / rate)
            }
        };
        if !self.steps.full() {
            return None;
        }
        let below = factor < SLOW * wanted;
        if below == self.slow {
            self.flipping_since = None;
            return None;
        }
        let since = *self.flipping_since.get_or_insert(now);
        if now.duration_since(since) < WINDOW {
            return None;
        }
        self.flipping_since = None;
        self.slow = below;
        Some(if below {
            let step_ms = self.steps.mean_step().unwrap_or(0.0) * 1e3;
            format!(
                "warning: slower than real time: {factor:.2}x over the last second, target \
                 {wanted:.2}x: a step takes {step_ms:.1} ms of wall time, the tick period is \
                 {:.1} ms (SimStatus.real_time_factor follows it)",
                period * 1e3
            )
        } else {
            format!("keeping up again: {factor:.2}x over the last second, target {wanted:.2}x")
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    #[test]
    fn factor_over_the_last_second_and_the_slow_line_once_then_recovery() {
        let t0 = Instant::now();
        let mut w = RealTimeWatch::default();
        w.restart(t0);
        let target = Target::Factor {
            factor: 1.0,
            period: ms(10),
        };
        // 10 ms of simulated time every 20 ms of wall time: 0.5x, each step 18 ms; said
        // once the window is full (1 s) and it stayed slow for a second more
        let mut said = Vec::new();
        for k in 1..=150u64 {
            let now = t0 + ms(20 * k);
            w.step(now, 0.01, 0.018);
            said.extend(w.judge(now, target));
            assert_eq!(said.is_empty(), k < 100, "{k}");
        }
        assert!((w.factor() - 0.5).abs() < 1e-9, "{}", w.factor());
        assert_eq!(said.len(), 1, "{said:?}");
        assert!(
            said[0].contains("0.50x") && said[0].contains("18.0 ms"),
            "{}",
            said[0]
        );
        assert!(said[0].contains("tick period is 10.0 ms"), "{}", said[0]);
        // then real time: after a full second of it, one recovery line
        let t1 = t0 + ms(3000);
        for k in 1..=300u64 {
            let now = t1 + ms(10 * k);
            w.step(now, 0.01, 0.002);
            said.extend(w.judge(now, target));
        }
        assert!((w.factor() - 1.0).abs() < 1e-9, "{}", w.factor());
        assert_eq!(said.len(), 2, "{said:?}");
        assert!(
            said[1].starts_with("keeping up again: 1.00x"),
            "{}",
            said[1]
        );
        // hovering at the threshold says nothing more: 0.6 s at 0.90x, 0.6 s at 1x, so
        // the factor over the last second swings between 0.94x and 0.96x, below 0.95x
        // for about 0.6 s at a time
        let t2 = t1 + ms(3000);
        for k in 1..=480u64 {
            let now = t2 + ms(10 * k);
            let dt = if (k / 60) % 2 == 0 { 0.009 } else { 0.010 };
            w.step(now, dt, 0.002);
            said.extend(w.judge(now, target));
        }
        assert_eq!(said.len(), 2, "{said:?}");
    }

    #[test]
    fn nothing_is_said_before_a_full_second_or_without_a_target() {
        let t0 = Instant::now();
        let mut w = RealTimeWatch::default();
        w.restart(t0);
        let target = Target::Factor {
            factor: 1.0,
            period: ms(10),
        };
        for k in 1..=40u64 {
            let now = t0 + ms(20 * k);
            w.step(now, 0.01, 0.018);
            assert_eq!(w.judge(now, target), None, "{k}");
        }
        for k in 41..=200u64 {
            let now = t0 + ms(20 * k);
            w.step(now, 0.01, 0.018);
            assert_eq!(w.judge(now, Target::None), None, "{k}");
        }
        // a pause restarts the window: the paused time does not count
        let t1 = t0 + ms(10_000);
        w.restart(t1);
        w.step(t1 + ms(10), 0.01, 0.002);
        assert!((w.factor() - 1.0).abs() < 1e-9, "{}", w.factor());
    }

    #[test]
    fn under_an_external_clock_the_target_is_the_clocks_rate() {
        let t0 = Instant::now();
        let mut w = RealTimeWatch::default();
        w.restart(t0);
        let target = Target::Clock { dt: 0.01 };
        let mut said = Vec::new();
        // the clock runs at 2x; the node follows at 2x, then at 1x
        for k in 1..=200u64 {
            let now = t0 + ms(10 * k);
            w.clock(now, 100.0 + 0.02 * k as f64);
            w.step(now, 0.02, 0.004);
            said.extend(w.judge(now, target));
        }
        assert!(said.is_empty(), "{said:?}");
        for k in 201..=500u64 {
            let now = t0 + ms(10 * k);
            w.clock(now, 100.0 + 0.02 * k as f64);
            w.step(now, 0.01, 0.009);
            said.extend(w.judge(now, target));
        }
        assert_eq!(said.len(), 1, "{said:?}");
        assert!(said[0].contains("1.00x") && said[0].contains("target 2.00x"));
        // the tick period under a clock: dt at the clock's rate
        assert!(said[0].contains("tick period is 5.0 ms"), "{}", said[0]);
    }
}
