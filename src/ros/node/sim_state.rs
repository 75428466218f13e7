//! The simulation_interfaces services' own state (the rest is the session's: paused,
//! the world); the services are in `simulation`.

use std::collections::VecDeque;

use ros2_client::RmwRequestId;

/// The services' own state.
#[derive(Default)]
pub(super) struct SimInterfaces {
    /// STOPPED: reset and paused by SetSimulationState, not played, paused or stepped
    /// since.
    pub(super) stopped: bool,
    /// QUITTING was asked: the node stops after the reply.
    pub(super) quitting: bool,
    /// StepSimulation requests: (request, steps asked, steps done), oldest first.
    pub(super) stepping: VecDeque<(RmwRequestId, u64, u64)>,
}

impl SimInterfaces {
    /// Whether steps are waiting to run (the loop must not sleep).
    pub(super) fn busy(&self) -> bool {
        !self.stepping.is_empty()
    }
}
