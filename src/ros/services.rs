//! The node's services on the Cyclone DDS service mapping (as rclpy on rmw_cyclonedds
//! calls them): `~/reset`, `~/set_paused`, `~/step` (std_srvs) and the parameter
//! services `~/list_parameters`, `~/get_parameters`, `~/set_parameters`,
//! `~/describe_parameters`, `~/get_parameter_types` (rcl_interfaces). Every reply is
//! held until the client's reply reader is matched ([`crate::ros::reply`]).
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

use crate::ros::dds::{dds, NodeError};
use crate::ros::reply::{ClientWriters, Flushed, HeldReplies};
use crate::session::names::NodeNames;
use crate::wire::msgs::{
    GraspRequest, GraspResponse, ReleaseRequest, ReleaseResponse, SetBoolRequest, SetBoolResponse,
    TriggerRequest, TriggerResponse,
};
use crate::wire::param_msgs::*;

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

/// Requests a single `receive` skips past when they fail to read (deserialize or
/// unwrap), so one bad sample does not stall the good ones queued behind it until
/// the next wake, yet a reader that fails forever cannot spin the loop.
const MAX_UNREADABLE_PER_CALL: usize = 16;

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

    /// The next request, if any. A request that cannot be read is reported on stderr
    /// (once per run of failures, naming the service) and skipped, never dropped
    /// silently: a client waiting on it would otherwise see only a missing reply.
    pub fn receive(&mut self) -> Option<(RmwRequestId, Req)> {
        for _ in 0..MAX_UNREADABLE_PER_CALL {
            match self.server.receive_request() {
                Ok(next) => {
                    self.failing = false;
                    return next;
                }
                Err(e) => {
                    if !self.failing {
                        eprintln!(
                            "warning: service {}: unreadable request dropped: {e:?}",
                            self.name
                        );
                    }
                    self.failing = true;
                }
            }
        }
        None
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
    client_writers: ClientWriters,
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
            && self.handle_grasp.iter().all(|s| s.replies.is_empty()))
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
        let shortcuts: Vec<Flushed> = self
            .handle_grasp
            .iter_mut()
            .map(|s| s.flush(node, w, now))
            .collect();
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
