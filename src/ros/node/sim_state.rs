//! The simulation_interfaces services' own state (the rest is the session's: paused,
//! the world); the services are in `simulation`, the SimulateSteps action in
//! `simulate_steps`.

use std::collections::VecDeque;

use ros2_client::action::{GoalId, GoalStatusEnum};
use ros2_client::builtin_interfaces::Time;
use ros2_client::RmwRequestId;

use crate::wire::sim_interfaces::SimulateStepsResult;

/// Who asked for steps: a StepSimulation request or a SimulateSteps goal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum StepJob {
    Service(RmwRequestId),
    Goal(GoalId),
}

/// A SimulateSteps goal the action server knows (running or ended).
pub(super) struct StepsGoal {
    pub(super) id: GoalId,
    /// When it was accepted (the node's stamp).
    pub(super) accepted: Time,
    pub(super) status: GoalStatusEnum,
    /// Set when the goal ends.
    pub(super) result: Option<SimulateStepsResult>,
    /// GetResult requests waiting for the end.
    pub(super) result_requests: Vec<RmwRequestId>,
}

/// Ended goals kept for late GetResult requests and the status topic (rcl_action keeps
/// them for a time-out instead; a count bounds memory without a clock).
pub(super) const ENDED_GOALS_KEPT: usize = 16;

/// The services' own state.
#[derive(Default)]
pub(super) struct SimInterfaces {
    /// STOPPED: reset and paused by SetSimulationState, not played, paused or stepped
    /// since.
    pub(super) stopped: bool,
    /// QUITTING was asked: the node stops after the reply.
    pub(super) quitting: bool,
    /// StepSimulation requests and SimulateSteps goals: (who, steps asked, steps done),
    /// oldest first.
    pub(super) stepping: VecDeque<(StepJob, u64, u64)>,
    /// SimulateSteps goals, oldest first: the running ones and the last
    /// [`ENDED_GOALS_KEPT`] ended.
    pub(super) goals: Vec<StepsGoal>,
}

impl SimInterfaces {
    /// Whether steps are waiting to run (the loop must not sleep).
    pub(super) fn busy(&self) -> bool {
        !self.stepping.is_empty()
    }
}
