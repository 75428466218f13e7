//! The `simulation_interfaces/action/SimulateSteps` action server `~/simulate_steps` on
//! the Cyclone DDS service mapping (as rclpy on rmw_cyclonedds calls it): ros2-client's
//! synchronous [`ActionServer`] (its goal, cancel and result services, its feedback and
//! status topics), with every reply of the three services held until the client's reply
//! reader is matched ([`crate::ros::reply`]), as the node's other services do.
//!
//! This module is the transport only: which goals run, how they step and when they end
//! is the node's (`node/simulate_steps.rs`).

use std::time::Instant;

use ros2_client::action::{
    ActionServer, CancelGoalRequest, CancelGoalResponse, GetResultRequest, GetResultResponse,
    GoalId, SendGoalRequest, SendGoalResponse,
};
use ros2_client::action_msgs::GoalStatusArray;
use ros2_client::dds::rustdds::mio1::{Interest, Poll, Token};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{ActionTypeName, Name, Node, NodeName, QosProfile, RmwRequestId};

use crate::ros::dds::{dds, NodeError};
use crate::ros::reply::{receive_request, ClientWriters, Flushed, HeldReplies};
use crate::wire::sim_interfaces::{SimulateStepsFeedback, SimulateStepsGoal, SimulateStepsResult};

type Server = ActionServer<SimulateStepsGoal, SimulateStepsResult, SimulateStepsFeedback>;
pub type StepsResultResponse = GetResultResponse<SimulateStepsResult>;

/// The SimulateSteps action server and the replies it holds.
pub struct StepsAction {
    server: Server,
    goal_replies: HeldReplies<SendGoalResponse>,
    cancel_replies: HeldReplies<CancelGoalResponse>,
    result_replies: HeldReplies<StepsResultResponse>,
    /// The action's ROS name, for warnings.
    name: String,
    /// Per service (goal, cancel, result): requests keep failing to read.
    failing: [bool; 3],
}

/// The poll tokens an action takes (its three request readers).
pub const TOKENS: usize = 3;

impl StepsAction {
    /// The action `name` (e.g. `/developable_sim/simulate_steps`); its request readers
    /// wake `poll` on tokens `token..token + TOKENS`.
    pub fn new(
        node: &mut Node,
        node_name: &NodeName,
        name: &str,
        poll: &Poll,
        token: usize,
    ) -> Result<Self, NodeError> {
        let n = Name::parse(name).map_err(dds("action name"))?;
        // rclpy / rcl_action defaults: services and feedback reliable, volatile, keep
        // last 10; status reliable, transient local, keep last 1 (a late client sees it)
        let service = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::Fail)
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 10 });
        let status = service
            .clone()
            .durability(Durability::TransientLocal)
            .history(History::KeepLast { depth: 1 });
        let qos = ros2_client::action::ActionServerQosPolicies {
            goal_service: service.clone(),
            result_service: service.clone(),
            cancel_service: service.clone(),
            feedback_publisher: service,
            status_publisher: status,
        };
        let mut server: Server = node
            .create_action_server(
                ros2_client::ServiceMapping::Cyclone,
                &n,
                &ActionTypeName::new("simulation_interfaces", "SimulateSteps"),
                qos,
            )
            .map_err(|e| NodeError::Dds(format!("simulate_steps action: {e:?}")))?;
        let reg = poll.registry();
        reg.register(server.goal_server(), Token(token), Interest::READABLE)?;
        reg.register(server.cancel_server(), Token(token + 1), Interest::READABLE)?;
        reg.register(server.result_server(), Token(token + 2), Interest::READABLE)?;
        let topic = |service: &str| -> Result<String, NodeError> {
            let s = Name::parse(&format!("{name}/_action/{service}")).map_err(dds("action"))?;
            Ok(s.to_dds_name("rq", node_name, "Request"))
        };
        Ok(StepsAction {
            server,
            goal_replies: HeldReplies::new(topic("send_goal")?),
            cancel_replies: HeldReplies::new(topic("cancel_goal")?),
            result_replies: HeldReplies::new(topic("get_result")?),
            name: name.to_string(),
            failing: [false; 3],
        })
    }

    pub fn receive_goal(&mut self) -> Option<(RmwRequestId, SendGoalRequest<SimulateStepsGoal>)> {
        let what = format!("{}/_action/send_goal", self.name);
        receive_request(self.server.goal_server(), &what, &mut self.failing[0])
    }

    pub fn receive_cancel(&mut self) -> Option<(RmwRequestId, CancelGoalRequest)> {
        let what = format!("{}/_action/cancel_goal", self.name);
        receive_request(self.server.cancel_server(), &what, &mut self.failing[1])
    }

    pub fn receive_result_request(&mut self) -> Option<(RmwRequestId, GetResultRequest)> {
        let what = format!("{}/_action/get_result", self.name);
        receive_request(self.server.result_server(), &what, &mut self.failing[2])
    }

    /// Hold the goal reply until its client can receive it.
    pub fn reply_goal(&mut self, id: RmwRequestId, response: SendGoalResponse) {
        self.goal_replies.hold(id, response);
    }

    pub fn reply_cancel(&mut self, id: RmwRequestId, response: CancelGoalResponse) {
        self.cancel_replies.hold(id, response);
    }

    pub fn reply_result(&mut self, id: RmwRequestId, response: StepsResultResponse) {
        self.result_replies.hold(id, response);
    }

    /// Publish feedback (best effort: a lost feedback sample is superseded by the next;
    /// the error says why for the caller to count).
    pub fn feedback(&self, goal: GoalId, feedback: SimulateStepsFeedback) -> Result<(), String> {
        self.server
            .send_feedback(goal, feedback)
            .map_err(|e| format!("{e:?}"))
    }

    /// Publish the status of every goal the server knows.
    pub fn statuses(&self, statuses: GoalStatusArray) -> Result<(), String> {
        self.server
            .send_goal_statuses(statuses)
            .map_err(|e| format!("{e:?}"))
    }

    pub fn waiting(&self) -> bool {
        !(self.goal_replies.is_empty()
            && self.cancel_replies.is_empty()
            && self.result_replies.is_empty())
    }

    /// Send the held replies whose clients can receive them (goal replies first, so a
    /// client learns its goal was accepted before it learns the result).
    pub fn flush(&mut self, node: &Node, w: &ClientWriters, now: Instant) -> [Flushed; 3] {
        let s = &mut self.server;
        [
            self.goal_replies.flush(s.goal_server(), node, w, now),
            self.cancel_replies.flush(s.cancel_server(), node, w, now),
            self.result_replies.flush(s.result_server(), node, w, now),
        ]
    }
}
