//! The node's services on the Cyclone DDS service mapping (as rclpy on rmw_cyclonedds
//! calls them): `~/reset`, `~/set_paused`, `~/step` (std_srvs) and the parameter
//! services `~/list_parameters`, `~/get_parameters`, `~/set_parameters`,
//! `~/describe_parameters`, `~/get_parameter_types` (rcl_interfaces), the
//! simulation_interfaces services and the SimulateSteps action ([`crate::ros::action`]).
//! Every reply is held until the client's reply reader is matched ([`crate::ros::reply`]).
//!
//! ros2-client's own parameter services are hard-wired to the Enhanced (Fast DDS)
//! mapping, which Cyclone clients cannot call; the node turns them off
//! (`start_parameter_services(false)`), so these are the only ones on those names.

use std::time::Instant;

use ros2_client::dds::rustdds::mio1::{Interest, Poll, Token};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    Message, Name, Node, NodeName, QosProfile, RmwRequestId, Server, ServiceMapping,
    ServiceTypeName,
};

use crate::ros::action::StepsAction;
use crate::ros::dds::{dds, NodeError};
use crate::ros::reply::{receive_request, ClientWriters, Flushed, HeldReplies};
use crate::session::names::NodeNames;
use crate::wire::msgs::{
    GraspRequest, GraspResponse, ReleaseRequest, ReleaseResponse, SetBoolRequest, SetBoolResponse,
    TriggerRequest, TriggerResponse,
};
use crate::wire::param_msgs::*;
use crate::wire::sim_interfaces::{
    GetSimulationStateResponse, GetSimulatorFeaturesResponse, ResetSimulationRequest,
    ResultResponse, SetSimulationStateRequest, StepSimulationRequest,
};

/// One server and the replies it holds.
pub struct Service<Req: Message + 'static, Resp: Message + 'static> {
    server: Server<Req, Resp>,
    replies: HeldReplies<Resp>,
    /// The service's ROS name, for the unreadable-request warning.
    name: String,
    /// True while requests keep failing to read: the warning is printed once per
    /// such episode, not once per request.
    failing: bool,
}

impl<Req: Message + Clone + 'static, Resp: Message + 'static> Service<Req, Resp> {
    fn new(
        ctx: &mut Ctx,
        name: &str,
        type_name: (&str, &str),
        what: &str,
    ) -> Result<Self, NodeError> {
        let n = Name::parse(name).map_err(dds("service name"))?;
        let qos = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::Fail)
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 10 });
        let mut server = ctx
            .node
            .create_server::<Req, Resp>(
                ServiceMapping::Cyclone,
                &n,
                &ServiceTypeName::new(type_name.0, type_name.1),
                qos.clone(),
                qos,
            )
            .map_err(|e| NodeError::Dds(format!("{what} service: {e:?}")))?;
        ctx.poll
            .registry()
            .register(&mut server, Token(ctx.token), Interest::READABLE)?;
        ctx.token += 1;
        let replies = HeldReplies::new(n.to_dds_name("rq", ctx.node_name, "Request"));
        Ok(Service {
            server,
            replies,
            name: name.to_string(),
            failing: false,
        })
    }

    /// The next request, if any (see [`receive_request`]).
    pub fn receive(&mut self) -> Option<(RmwRequestId, Req)> {
        receive_request(&self.server, &self.name, &mut self.failing)
    }

    /// Hold the reply to `id` until its client can receive it.
    pub fn reply(&mut self, id: RmwRequestId, response: Resp) {
        self.replies.hold(id, response);
    }

    fn flush(&mut self, node: &Node, writers: &ClientWriters, now: Instant) -> Flushed {
        self.replies.flush(&self.server, node, writers, now)
    }
}

struct Ctx<'a> {
    node: &'a mut Node,
    node_name: &'a NodeName,
    poll: &'a Poll,
    token: usize,
}

/// Every service of the node.
pub struct Services {
    pub reset: Service<TriggerRequest, TriggerResponse>,
    pub set_paused: Service<SetBoolRequest, SetBoolResponse>,
    pub step: Service<TriggerRequest, TriggerResponse>,
    pub list_parameters: Service<ListParametersRequest, ListParametersResponse>,
    pub get_parameters: Service<NamesRequest, GetParametersResponse>,
    pub set_parameters: Service<SetParametersRequest, SetParametersResponse>,
    pub describe_parameters: Service<NamesRequest, DescribeParametersResponse>,
    pub get_parameter_types: Service<NamesRequest, GetParameterTypesResponse>,
    pub grasp: Service<GraspRequest, GraspResponse>,
    pub release: Service<ReleaseRequest, ReleaseResponse>,
    /// Per handle: its open / close shortcut.
    pub handle_grasp: Vec<Service<SetBoolRequest, SetBoolResponse>>,
    pub simulation: SimulationServices,
    client_writers: ClientWriters,
}

/// The simulation_interfaces services.
pub struct SimulationServices {
    pub get_features: Service<TriggerRequest, GetSimulatorFeaturesResponse>,
    pub reset: Service<ResetSimulationRequest, ResultResponse>,
    pub step: Service<StepSimulationRequest, ResultResponse>,
    pub get_state: Service<TriggerRequest, GetSimulationStateResponse>,
    pub set_state: Service<SetSimulationStateRequest, ResultResponse>,
    /// The SimulateSteps action `~/simulate_steps`.
    pub simulate_steps: StepsAction,
}

impl SimulationServices {
    fn new(
        c: &mut Ctx,
        names: &crate::session::names::SimulationServices,
    ) -> Result<Self, NodeError> {
        let t = |n| ("simulation_interfaces", n);
        let simulate_steps =
            StepsAction::new(c.node, c.node_name, &names.simulate_steps, c.poll, c.token)?;
        c.token += crate::ros::action::TOKENS;
        Ok(SimulationServices {
            get_features: Service::new(
                c,
                &names.get_features,
                t("GetSimulatorFeatures"),
                "get_simulator_features",
            )?,
            reset: Service::new(c, &names.reset, t("ResetSimulation"), "reset_simulation")?,
            step: Service::new(c, &names.step, t("StepSimulation"), "step_simulation")?,
            get_state: Service::new(
                c,
                &names.get_state,
                t("GetSimulationState"),
                "get_simulation_state",
            )?,
            set_state: Service::new(
                c,
                &names.set_state,
                t("SetSimulationState"),
                "set_simulation_state",
            )?,
            simulate_steps,
        })
    }

    fn waiting(&self) -> bool {
        !(self.get_features.replies.is_empty()
            && self.reset.replies.is_empty()
            && self.step.replies.is_empty()
            && self.get_state.replies.is_empty()
            && self.set_state.replies.is_empty()
            && !self.simulate_steps.waiting())
    }

    fn flush(&mut self, node: &Node, w: &ClientWriters, now: Instant) -> [Flushed; 8] {
        let [goal, cancel, result] = self.simulate_steps.flush(node, w, now);
        [
            self.get_features.flush(node, w, now),
            self.reset.flush(node, w, now),
            self.step.flush(node, w, now),
            self.get_state.flush(node, w, now),
            self.set_state.flush(node, w, now),
            goal,
            cancel,
            result,
        ]
    }
}

impl Services {
    /// Create every server; they wake `poll` on tokens from `token` on.
    pub fn new(
        node: &mut Node,
        node_name: &NodeName,
        names: &NodeNames,
        poll: &Poll,
        token: usize,
    ) -> Result<Services, NodeError> {
        let mut c = Ctx {
            node,
            node_name,
            poll,
            token,
        };
        let trigger = ("std_srvs", "Trigger");
        let rcl = |t| ("rcl_interfaces", t);
        let p = &names.parameters;
        Ok(Services {
            reset: Service::new(&mut c, &names.reset, trigger, "reset")?,
            set_paused: Service::new(
                &mut c,
                &names.set_paused,
                ("std_srvs", "SetBool"),
                "set_paused",
            )?,
            step: Service::new(&mut c, &names.step, trigger, "step")?,
            list_parameters: Service::new(
                &mut c,
                &p.list,
                rcl("ListParameters"),
                "list_parameters",
            )?,
            get_parameters: Service::new(&mut c, &p.get, rcl("GetParameters"), "get_parameters")?,
            set_parameters: Service::new(&mut c, &p.set, rcl("SetParameters"), "set_parameters")?,
            describe_parameters: Service::new(
                &mut c,
                &p.describe,
                rcl("DescribeParameters"),
                "describe_parameters",
            )?,
            get_parameter_types: Service::new(
                &mut c,
                &p.get_types,
                rcl("GetParameterTypes"),
                "get_parameter_types",
            )?,
            grasp: Service::new(&mut c, &names.grasp, ("developable_sim", "Grasp"), "grasp")?,
            release: Service::new(
                &mut c,
                &names.release,
                ("developable_sim", "Release"),
                "release",
            )?,
            handle_grasp: names
                .handle_grasp
                .iter()
                .map(|n| Service::new(&mut c, n, ("std_srvs", "SetBool"), "handle grasp"))
                .collect::<Result<Vec<_>, _>>()?,
            simulation: SimulationServices::new(&mut c, &names.simulation)?,
            client_writers: ClientWriters::default(),
        })
    }

    /// Whether any reply is held.
    pub fn waiting(&self) -> bool {
        !(self.reset.replies.is_empty()
            && self.set_paused.replies.is_empty()
            && self.step.replies.is_empty()
            && self.list_parameters.replies.is_empty()
            && self.get_parameters.replies.is_empty()
            && self.set_parameters.replies.is_empty()
            && self.describe_parameters.replies.is_empty()
            && self.get_parameter_types.replies.is_empty()
            && self.grasp.replies.is_empty()
            && self.release.replies.is_empty()
            && self.handle_grasp.iter().all(|s| s.replies.is_empty())
            && !self.simulation.waiting())
    }

    /// Send the held replies whose clients can receive them; what was sent, summed.
    pub fn flush(
        &mut self,
        node: &Node,
        participant: &ros2_client::dds::rustdds::DomainParticipant,
        now: Instant,
    ) -> Flushed {
        if !self.waiting() {
            return Flushed::default();
        }
        self.client_writers.refresh(participant);
        let w = &self.client_writers;
        let mut shortcuts: Vec<Flushed> = self
            .handle_grasp
            .iter_mut()
            .map(|s| s.flush(node, w, now))
            .collect();
        shortcuts.extend(self.simulation.flush(node, w, now));
        let all = [
            self.grasp.flush(node, w, now),
            self.release.flush(node, w, now),
            self.reset.flush(node, w, now),
            self.set_paused.flush(node, w, now),
            self.step.flush(node, w, now),
            self.list_parameters.flush(node, w, now),
            self.get_parameters.flush(node, w, now),
            self.set_parameters.flush(node, w, now),
            self.describe_parameters.flush(node, w, now),
            self.get_parameter_types.flush(node, w, now),
        ];
        all.iter()
            .chain(&shortcuts)
            .fold(Flushed::default(), |a, d| Flushed {
                sent: a.sent + d.sent,
                sent_unseen: a.sent_unseen + d.sent_unseen,
                failed: a.failed + d.failed,
            })
    }
}
