//! What Ctrl-C and SIGTERM do to `run` and `node`.
//!
//! The first signal asks for a clean stop: the run or node stops after its current step
//! (or tick) and closes its bag. A second signal exits at once: one step can take long
//! (up to 0.8 s on the extreme torsion at n = 1600, 2026-12-06; minutes in an unlanded
//! contact experiment, docs/contact.md), and a user who asks twice wants the process
//! gone. The bag is then left as after `kill -9`: readable by streaming readers up to its
//! last flush, and `developable_sim bag reindex DIR` completes it (docs/ros2_interop.md).

use std::sync::atomic::{AtomicBool, Ordering};

/// The exit status after a second stop signal (128 + SIGINT, as shells report it).
pub const FORCED_EXIT_STATUS: i32 = 130;

/// What one stop signal asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopAction {
    /// The first signal: finish the current step, close the bag, exit normally.
    Stop,
    /// A later one: exit now.
    ExitNow,
}

/// Record a stop signal in `requested` (set by the first) and say what it asks for.
pub fn on_stop_signal(requested: &AtomicBool) -> StopAction {
    if requested.swap(true, Ordering::SeqCst) {
        StopAction::ExitNow
    } else {
        StopAction::Stop
    }
}

/// The line printed on stderr for `action`.
pub fn stop_message(action: StopAction) -> &'static str {
    match action {
        StopAction::Stop => {
            "[developable_sim] stopping after the current step; a second Ctrl-C exits at once"
        }
        StopAction::ExitNow => {
            "[developable_sim] second stop signal: exiting now, the bag left unclosed (`developable_sim bag reindex DIR` completes it)"
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_signal_stops_cleanly_and_every_later_one_exits_now() {
        let requested = AtomicBool::new(false);
        assert_eq!(on_stop_signal(&requested), StopAction::Stop);
        assert!(requested.load(Ordering::SeqCst));
        assert_eq!(on_stop_signal(&requested), StopAction::ExitNow);
        assert_eq!(on_stop_signal(&requested), StopAction::ExitNow);
        assert!(stop_message(StopAction::ExitNow).contains("bag reindex"));
    }
}
