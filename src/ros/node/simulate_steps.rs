//! The SimulateSteps action (`~/simulate_steps`): a goal of N steps runs through the
//! same queue as StepSimulation (`simulation`), a batch per loop iteration, each step
//! the node's step command (recorded, replayed); feedback (completed, remaining) after
//! every step, as the .action says. A goal is accepted whenever it is well formed; one
//! that may not run now (playing, `steps` = 0, the duration reached) ends at once as
//! ABORTED with RESULT_OPERATION_FAILED and the reason, the .action's "calling with
//! simulation unpaused will return OPERATION_FAILED and error message" (a rejected goal
//! could carry no reason). A cancel stops it between two batches: CANCELED, with
//! RESULT_OPERATION_FAILED and "canceled after k of N steps".

use ros2_client::action::{CancelGoalResponse, GoalId, GoalInfo, GoalStatusEnum, SendGoalResponse};
use ros2_client::action_msgs::{CancelGoalResponseEnum, GoalStatus, GoalStatusArray};
use ros2_client::builtin_interfaces::Time;
use ros2_client::RmwRequestId;

use super::sim_state::{StepJob, StepsGoal, ENDED_GOALS_KEPT};
use super::SimNode;
use crate::ros::action::StepsResultResponse;
use crate::wire::sim_interfaces::{SimResult, SimulateStepsFeedback, SimulateStepsResult};

fn active(status: GoalStatusEnum) -> bool {
    matches!(
        status,
        GoalStatusEnum::Accepted | GoalStatusEnum::Executing | GoalStatusEnum::Canceling
    )
}

impl SimNode {
    /// Answer the action's goal, cancel and result requests.
    pub(super) fn drain_simulate_steps(&mut self) {
        while let Some((id, req)) = self.io.services.simulation.simulate_steps.receive_goal() {
            self.new_goal(id, req.goal_id, req.goal.steps);
        }
        while let Some((id, req)) = self.io.services.simulation.simulate_steps.receive_cancel() {
            let info = req.goal_info().clone();
            self.cancel_goals(id, &info);
        }
        let action = &mut self.io.services.simulation.simulate_steps;
        while let Some((id, req)) = action.receive_result_request() {
            match self.sim_if.goals.iter_mut().find(|g| g.id == req.goal_id) {
                Some(g) => match &g.result {
                    Some(result) => action.reply_result(id, result_response(g.status, result)),
                    None => g.result_requests.push(id),
                },
                // as rcl_action: an unknown goal's result is STATUS_UNKNOWN, empty
                None => action.reply_result(
                    id,
                    result_response(GoalStatusEnum::Unknown, &Default::default()),
                ),
            }
        }
    }

    fn now_stamp(&self) -> Time {
        let t = self.session.stamp();
        Time::new(t.sec, t.nanosec)
    }

    fn new_goal(&mut self, id: RmwRequestId, goal: GoalId, steps: u64) {
        let stamp = self.now_stamp();
        let action = &mut self.io.services.simulation.simulate_steps;
        // a goal id already in use is refused, as rcl_action does
        let accepted = !self.sim_if.goals.iter().any(|g| g.id == goal);
        action.reply_goal(id, SendGoalResponse { accepted, stamp });
        if !accepted {
            return;
        }
        self.sim_if.goals.push(StepsGoal {
            id: goal,
            accepted: stamp,
            status: GoalStatusEnum::Executing,
            result: None,
            result_requests: Vec::new(),
        });
        match self.may_step(steps) {
            Ok(()) => {
                self.sim_if.stopped = false;
                self.sim_if
                    .stepping
                    .push_back((StepJob::Goal(goal), steps, 0));
                self.publish_goal_statuses();
            }
            Err(result) => self.end_goal(goal, GoalStatusEnum::Aborted, result),
        }
    }

    /// The cancel policy of action_msgs/srv/CancelGoal: a goal id (zero: none) and a
    /// stamp (zero: none; else every goal accepted at or before it); both zero: all.
    fn cancel_goals(&mut self, id: RmwRequestId, info: &GoalInfo) {
        let zero_id = info.goal_id == GoalId::ZERO;
        let zero_stamp = info.stamp == Time::ZERO;
        let matches = |g: &StepsGoal| {
            (zero_id && zero_stamp)
                || (!zero_id && g.id == info.goal_id)
                || (!zero_stamp && g.accepted <= info.stamp)
        };
        let canceled: Vec<GoalInfo> = (self.sim_if.goals.iter())
            .filter(|g| active(g.status) && matches(g))
            .map(|g| GoalInfo {
                goal_id: g.id,
                stamp: g.accepted,
            })
            .collect();
        let return_code = if !canceled.is_empty() {
            CancelGoalResponseEnum::None
        } else if zero_id {
            CancelGoalResponseEnum::Rejected
        } else if self.sim_if.goals.iter().any(|g| g.id == info.goal_id) {
            CancelGoalResponseEnum::GoalTerminated
        } else {
            CancelGoalResponseEnum::UnknownGoal
        };
        for g in &canceled {
            let pos = (self.sim_if.stepping.iter())
                .position(|(job, _, _)| *job == StepJob::Goal(g.goal_id));
            let (asked, done) = match pos.and_then(|p| self.sim_if.stepping.remove(p)) {
                Some((_, asked, done)) => (asked, done),
                None => (0, 0),
            };
            let why = format!("canceled after {done} of {asked} steps");
            let result = SimResult::failed(SimResult::OPERATION_FAILED, why);
            self.end_goal(g.goal_id, GoalStatusEnum::Canceled, result);
        }
        let resp = CancelGoalResponse {
            return_code,
            goals_canceling: canceled,
        };
        self.io
            .services
            .simulation
            .simulate_steps
            .reply_cancel(id, resp);
    }

    /// Feedback after a goal's step (a lost sample is counted as a dropped publication;
    /// the next one supersedes it).
    pub(super) fn goal_feedback(&mut self, goal: GoalId, done: u64, asked: u64) {
        let feedback = SimulateStepsFeedback {
            completed_steps: done,
            remaining_steps: asked - done,
        };
        let action = &self.io.services.simulation.simulate_steps;
        if let Err(e) = action.feedback(goal, feedback) {
            self.note_dropped(vec![("simulate_steps/_action/feedback".into(), e)]);
        }
    }

    /// End a goal in `status` (SUCCEEDED, CANCELED, ABORTED) with `result`; its waiting
    /// GetResult requests are answered and the status published.
    pub(super) fn end_goal(&mut self, goal: GoalId, status: GoalStatusEnum, result: SimResult) {
        let action = &mut self.io.services.simulation.simulate_steps;
        if let Some(g) = self.sim_if.goals.iter_mut().find(|g| g.id == goal) {
            let result = SimulateStepsResult { result };
            for id in g.result_requests.drain(..) {
                action.reply_result(id, result_response(status, &result));
            }
            g.status = status;
            g.result = Some(result);
        }
        // forget the oldest ended goals beyond the kept number
        let ended = self
            .sim_if
            .goals
            .iter()
            .filter(|g| !active(g.status))
            .count();
        let mut excess = ended.saturating_sub(ENDED_GOALS_KEPT);
        self.sim_if.goals.retain(|g| {
            let drop = excess > 0 && !active(g.status);
            excess -= usize::from(drop);
            !drop
        });
        self.publish_goal_statuses();
    }

    fn publish_goal_statuses(&mut self) {
        let status_list = (self.sim_if.goals.iter())
            .map(|g| GoalStatus {
                goal_info: GoalInfo {
                    goal_id: g.id,
                    stamp: g.accepted,
                },
                status: g.status,
            })
            .collect();
        let action = &self.io.services.simulation.simulate_steps;
        if let Err(e) = action.statuses(GoalStatusArray { status_list }) {
            self.note_dropped(vec![("simulate_steps/_action/status".into(), e)]);
        }
    }
}

fn result_response(status: GoalStatusEnum, result: &SimulateStepsResult) -> StepsResultResponse {
    StepsResultResponse {
        status,
        result: result.clone(),
    }
}
