//! Following an external `/clock` (use_sim_time): what each sample means for the
//! simulation. Pure: the node passes each sample's clock time and the wall time it was
//! published at; the events become recorded commands (`Command::SetTimeOrigin`,
//! `Command::ResetAt`), so a replay does what the node did.
//!
//! The rules (docs/ros2_interop.md, "Time and parameters"):
//! - the first sample is where simulated time starts;
//! - a sample older than the newest is a jump backwards (a bag played in a loop, a
//!   simulator reset): the simulation resets there;
//! - a sample whose advance over the previous one exceeds the wall time between their
//!   publications by more than `max_jump` is a jump forward: the origin moves by the
//!   advance instead of the gap being simulated. Measured against the wall time so that
//!   a node that polls the clock seldom (a slow step; the subscription keeps only the
//!   newest sample) does not take a clock running at its normal rate for a jump.

/// What a `/clock` sample asks of the simulation (times in ns on the clock).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClockEvent {
    /// The first sample: simulated time 0 is at `at_ns`.
    Start { at_ns: i64 },
    /// The clock went back from `from_ns` to `to_ns`: reset with the initial state at
    /// `to_ns`.
    Backwards { from_ns: i64, to_ns: i64 },
    /// The clock leapt from `from_ns` to `to_ns`: move the origin by `to_ns - from_ns`.
    Forward { from_ns: i64, to_ns: i64 },
}

/// The newest `/clock` sample and the jump rules.
#[derive(Clone, Debug)]
pub struct ClockFollower {
    /// (clock ns, wall ns when published) of the newest sample.
    newest: Option<(i64, i64)>,
    /// ns: a forward jump larger than the wall time between two samples by more than
    /// this moves the origin (the `max_clock_jump` parameter).
    pub max_jump_ns: i64,
}

impl ClockFollower {
    /// `max_jump`: s, > 0.
    pub fn new(max_jump: f64) -> ClockFollower {
        ClockFollower {
            newest: None,
            max_jump_ns: secs_to_ns(max_jump),
        }
    }

    /// The newest clock time, ns (None: no sample yet).
    pub fn now_ns(&self) -> Option<i64> {
        self.newest.map(|(c, _)| c)
    }

    /// Take a sample: clock time `clock_ns`, published at wall time `wall_ns` (both ns).
    pub fn sample(&mut self, clock_ns: i64, wall_ns: i64) -> Option<ClockEvent> {
        let previous = self.newest.replace((clock_ns, wall_ns));
        let (from_ns, from_wall) = match previous {
            None => return Some(ClockEvent::Start { at_ns: clock_ns }),
            Some(p) => p,
        };
        if clock_ns < from_ns {
            return Some(ClockEvent::Backwards {
                from_ns,
                to_ns: clock_ns,
            });
        }
        let advance = clock_ns - from_ns;
        let wall = (wall_ns - from_wall).max(0);
        (advance - wall > self.max_jump_ns).then_some(ClockEvent::Forward {
            from_ns,
            to_ns: clock_ns,
        })
    }
}

/// s -> ns, rounded; non-finite or negative -> 0.
pub fn secs_to_ns(s: f64) -> i64 {
    if s.is_finite() && s > 0.0 {
        (s * 1e9).round().min(i64::MAX as f64) as i64
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: i64 = 1_000_000_000;

    #[test]
    fn the_first_sample_starts_time_wherever_it_is() {
        for start in [0, 100 * S, 1_700_000_000 * S + 123] {
            let mut c = ClockFollower::new(1.0);
            assert_eq!(c.now_ns(), None);
            assert_eq!(
                c.sample(start, 5 * S),
                Some(ClockEvent::Start { at_ns: start })
            );
            assert_eq!(c.now_ns(), Some(start));
        }
    }

    #[test]
    fn a_clock_at_its_rate_is_followed_and_a_repeat_is_nothing() {
        let mut c = ClockFollower::new(1.0);
        c.sample(100 * S, 0);
        // 10 ms samples at the wall rate, one repeated
        for k in 1..=300 {
            assert_eq!(c.sample(100 * S + k * S / 100, k * S / 100), None);
        }
        assert_eq!(c.sample(103 * S, 3 * S), None);
        // polled seldom (a slow step): 20 s of clock in 20 s of wall time is no jump
        assert_eq!(c.sample(123 * S, 23 * S), None);
    }

    #[test]
    fn backwards_resets_and_a_gap_beyond_max_jump_moves_the_origin() {
        let mut c = ClockFollower::new(1.0);
        c.sample(100 * S, 0);
        c.sample(101 * S, S);
        assert_eq!(
            c.sample(100 * S, S + S / 100),
            Some(ClockEvent::Backwards {
                from_ns: 101 * S,
                to_ns: 100 * S
            })
        );
        // 5 s of clock in 10 ms of wall time
        let w = S + 2 * S / 100;
        assert_eq!(
            c.sample(105 * S, w),
            Some(ClockEvent::Forward {
                from_ns: 100 * S,
                to_ns: 105 * S
            })
        );
        // just within the allowance: 1 s more than the wall time is not a jump, a
        // nanosecond more is
        assert_eq!(c.sample(106 * S + S / 2, w + S / 2), None);
        assert_eq!(
            c.sample(107 * S + S / 2 + 1, w + S / 2),
            Some(ClockEvent::Forward {
                from_ns: 106 * S + S / 2,
                to_ns: 107 * S + S / 2 + 1
            })
        );
    }
}
