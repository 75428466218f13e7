//! What an output's producer reads: one state of the session, borrowed. The session
//! builds it for each frame ([`super::Session::frame`]); producers
//! ([`super::outputs::OUTPUTS`]) turn it into messages.

use crate::scene::Scene;
use crate::sim::StepReport;
use crate::wire::msgs::{Header, Time};

use super::input::HandleInput;
use super::style::MarkerStyle;

/// Which object or handle a row is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Scope {
    Global,
    Object(usize),
    Handle(usize),
    /// A handle on an object (what handle `.1` feels from object `.0`).
    ObjectHandle(usize, usize),
    /// A camera of the scene (index in its `cameras:`).
    Camera(usize),
}

/// The session's counters that statuses report (all since start-up unless said).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Counters {
    /// Resets since start-up.
    pub episode: u32,
    /// Real-time ticks skipped because the simulation could not keep up.
    pub overrun_ticks: u64,
    /// Camera ticks whose frame was not captured: the camera was still drawing the
    /// previous one (all cameras; see `session::camera`).
    pub camera_frames_skipped: u64,
    /// Publications the node failed to send (all topics; the node counts them).
    pub dropped_publications: u64,
    /// Per object: steps whose solver stopped on an iteration limit.
    pub unconverged_steps: Vec<u64>,
    /// Per object: steps whose result was not finite (rejected, previous state kept).
    pub rejected_steps: Vec<u64>,
    /// Resets because the external clock (use_sim_time) jumped backwards.
    pub clock_resets: u32,
    /// Simulated over wall time over the last second (the node measures it; not a
    /// counter, and not reproduced by a replay).
    pub real_time_factor: f64,
}

/// One state of the session, as the producers see it.
pub struct Produce<'a> {
    pub scene: &'a Scene,
    pub style: &'a MarkerStyle,
    /// Per handle: its input filter's state (target, counters).
    pub inputs: &'a [HandleInput],
    /// Per handle: the input topic its status reports (`/tf` for a TF-driven handle).
    pub handle_topics: &'a [String],
    pub counters: &'a Counters,
    pub paused: bool,
    /// The step that made this state (None: the initial state, step 0).
    pub report: Option<&'a StepReport>,
    /// Per handle: the simulated time of its last grasp or release (zero: the scene's
    /// own hold), and whether it changed since the last frame was made.
    pub grasp_changed: &'a [Time],
    pub grasp_dirty: &'a [bool],
    /// Wall time of that step, s (0 for step 0).
    pub step_duration: f64,
    /// ns on the stamping clock where simulated time 0 is (see [`stamp_at`]).
    pub origin_ns: i64,
}

/// The stamp of simulated time `t` (s) when simulated time 0 is at `origin_ns` on the
/// stamping clock: 0 when the node owns time, the first `/clock` sample under
/// use_sim_time (moved by the clock's jumps). Integer ns, so an epoch origin (~1.7e9 s)
/// loses nothing to f64 (whose spacing there is 0.24 us).
pub fn stamp_at(origin_ns: i64, t: f64) -> Time {
    let t_ns = if t.is_finite() && t > 0.0 {
        (t * 1e9).round().min(i64::MAX as f64) as i64
    } else {
        0
    };
    Time::from_nanos(origin_ns.saturating_add(t_ns))
}

impl Produce<'_> {
    /// The stamp of the state: its simulated time after the origin.
    pub fn stamp(&self) -> Time {
        stamp_at(self.origin_ns, self.scene.world.time())
    }

    /// The header of every message of this state: its time, the scene frame.
    pub fn header(&self) -> Header {
        Header {
            stamp: self.stamp(),
            frame_id: self.scene.frame_id.clone(),
        }
    }
}
