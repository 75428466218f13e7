//! The node's DDS entities: the participant and node (with the spinner thread), the
//! poll the loop waits on, the handle subscriptions, TF and clock inputs, every
//! publisher, and the services. Created together, dropped in a fixed order.

use std::sync::Arc;
use std::time::{Duration, Instant};

use ros2_client::dds::rustdds::mio1::{Interest, Poll, Token, Waker};
use ros2_client::Subscription;
use ros2_client::{Context, ContextOptions, Name, Node, NodeName, NodeOptions};

use crate::ros::dds::{dds, qos, raw_publisher, topic_type, NodeError, RawPublisher};
use crate::ros::graph::{ClockIn, TfIn};
use crate::ros::reply::Flushed;
use crate::ros::services::Services;
use crate::session::names::NodeNames;
use crate::session::OutputTable;
use crate::wire::msgs::{PoseStamped, StringMsg};
use crate::wire::qos::Qos;

/// Poll tokens: handle subscriptions use their handle index, then these.
const WAKE: Token = Token(usize::MAX - 1);
const SERVICE_TOKEN_BASE: usize = 1 << 20;
const GRAPH_TOKEN_BASE: usize = 1 << 21;

/// Every DDS entity of the node.
pub(super) struct Endpoints {
    // field order = drop order: DDS entities, then the node, then the context
    /// (handle index, its pose subscription); TF-driven handles have none.
    pub(super) subs: Vec<(usize, Subscription<PoseStamped>)>,
    /// One writer per row of the session's outputs table (None: a row that is
    /// recorded, not published).
    pub(super) pubs: Vec<Option<RawPublisher>>,
    /// TF in (a scene with handles), an external clock.
    pub(super) tf_in: Option<TfIn>,
    pub(super) clock_in: Option<ClockIn>,
    /// The robot description (`robot_colliders:`; reliable, transient local).
    pub(super) robot_description: Option<Subscription<StringMsg>>,
    pub(super) services: Services,
    node: Option<Node>,
    spinner: Option<std::thread::JoinHandle<()>>,
    pub(super) context: Context,
    pub(super) poll: Poll,
    pub(super) waker: Arc<Waker>,
}

/// Joins the DDS domain and starts the node with its spinner thread (discovery, graph).
fn start_node(
    domain_id: u16,
    names: &NodeNames,
) -> Result<(Context, NodeName, Node, std::thread::JoinHandle<()>), NodeError> {
    let context = Context::with_options(ContextOptions::new().domain_id(domain_id))
        .map_err(dds("creating the DDS participant"))?;
    let node_name = NodeName::new(&names.namespace, &names.node).map_err(dds("node name"))?;
    let mut node = context
        .new_node(
            node_name.clone(),
            NodeOptions::new()
                .enable_rosout(true)
                // ros2-client serves parameters only with the Enhanced (Fast DDS)
                // service mapping; rather than offer services Cyclone clients
                // cannot call, parameters come from the params file
                .start_parameter_services(false),
        )
        .map_err(dds("creating the node"))?;
    let spinner = node.spinner().map_err(dds("spinner"))?;
    let spinner = std::thread::Builder::new()
        .name("ros2-spinner".into())
        .spawn(move || {
            let _ = smol::block_on(spinner.spin());
        })
        .map_err(NodeError::Poll)?;
    Ok((context, node_name, node, spinner))
}

/// A pose subscription per handle not driven by TF, registered with `poll` under the
/// handle's index as token.
fn handle_subscriptions(
    node: &mut Node,
    names: &NodeNames,
    tf_handles: &[(usize, String)],
    poll: &Poll,
) -> Result<Vec<(usize, Subscription<PoseStamped>)>, NodeError> {
    let mut subs = Vec::new();
    for (i, t) in names.handles.iter().enumerate() {
        if tf_handles.iter().any(|(h, _)| *h == i) {
            continue;
        }
        let name = Name::parse(t).map_err(dds("topic name"))?;
        let topic = node
            .create_topic(&name, topic_type::<PoseStamped>(), &qos(Qos::SENSOR_DATA))
            .map_err(dds("handle topic"))?;
        let mut sub = node
            .create_subscription::<PoseStamped>(&topic, Some(qos(Qos::SENSOR_DATA)))
            .map_err(dds("handle subscription"))?;
        poll.registry()
            .register(&mut sub, Token(i), Interest::READABLE)?;
        subs.push((i, sub));
    }
    Ok(subs)
}

/// A subscription to a latched topic (reliable, transient local, keep last 1: a robot
/// description published before the node started still arrives).
fn latched_subscription(
    node: &mut Node,
    topic: &str,
    poll: &Poll,
    token: Token,
) -> Result<Subscription<StringMsg>, NodeError> {
    let name = Name::parse(topic).map_err(dds("topic name"))?;
    let t = node
        .create_topic(&name, topic_type::<StringMsg>(), &qos(Qos::LATCHED))
        .map_err(dds("robot description topic"))?;
    let mut sub = node
        .create_subscription::<StringMsg>(&t, Some(qos(Qos::LATCHED)))
        .map_err(dds("robot description subscription"))?;
    poll.registry()
        .register(&mut sub, token, Interest::READABLE)?;
    Ok(sub)
}

impl Endpoints {
    /// Send the held service replies whose clients can receive them (see `reply`).
    pub(super) fn flush_replies(&mut self, now: Instant) -> Flushed {
        let participant = self.context.domain_participant();
        match &self.node {
            Some(node) => self.services.flush(node, &participant, now),
            None => Flushed::default(),
        }
    }

    /// Create every entity the node's settings and outputs ask for (`use_sim_time`:
    /// follow an external clock; `tf_max_lag`, s; `max_clock_jump`, s); `tf_handles`: (handle, TF frame) of
    /// the handles that follow TF frames (they get no pose subscription); a writer for
    /// each published row of `outputs`.
    pub(super) fn open(
        domain_id: u16,
        names: &NodeNames,
        outputs: &OutputTable,
        (use_sim_time, tf_max_lag, max_clock_jump): (bool, f64, f64),
        (tf_handles, tf_cameras): (&[(usize, String)], bool),
    ) -> Result<Self, NodeError> {
        let (context, node_name, mut node, spinner) = start_node(domain_id, names)?;
        let poll = Poll::new()?;
        let waker = Arc::new(Waker::new(poll.registry(), WAKE)?);
        let subs = handle_subscriptions(&mut node, names, tf_handles, &poll)?;
        // TF in for every scene with handles (TF-driven handles, and poses in another
        // frame of the tree), a robot's links, or a camera carried by a TF frame
        let robot = !names.robot_description.is_empty();
        let tf_in = (!names.handles.is_empty() || robot || tf_cameras)
            .then(|| {
                let lag = Duration::from_secs_f64(tf_max_lag);
                TfIn::new(
                    &mut node,
                    &names.tf,
                    &names.tf_static,
                    &poll,
                    GRAPH_TOKEN_BASE,
                    lag,
                )
            })
            .transpose()?;
        let clock_in = use_sim_time
            .then(|| {
                let token = GRAPH_TOKEN_BASE + 2;
                ClockIn::new(&mut node, &names.clock, &poll, token, max_clock_jump)
            })
            .transpose()?;
        let robot_description = robot
            .then(|| {
                let token = Token(GRAPH_TOKEN_BASE + 3);
                latched_subscription(&mut node, &names.robot_description, &poll, token)
            })
            .transpose()?;
        let pubs = outputs
            .rows
            .iter()
            .map(|row| {
                row.want
                    .published
                    .then(|| {
                        raw_publisher(
                            &mut node,
                            &context,
                            &node_name,
                            (&row.topic, row.type_name()),
                            row.kind.qos,
                            row.kind.name,
                        )
                    })
                    .transpose()
            })
            .collect::<Result<Vec<_>, _>>()?;
        let services = Services::new(&mut node, &node_name, names, &poll, SERVICE_TOKEN_BASE)?;
        Ok(Endpoints {
            subs,
            pubs,
            tf_in,
            clock_in,
            robot_description,
            services,
            node: Some(node),
            spinner: Some(spinner),
            context,
            poll,
            waker,
        })
    }
}

impl Drop for Endpoints {
    fn drop(&mut self) {
        // shutdown order: DDS entities and the node (stops the spinner), then the
        // spinner thread, then the context (field order)
        self.subs.clear();
        self.pubs.clear();
        self.tf_in = None;
        self.clock_in = None;
        self.robot_description = None;
        drop(self.node.take());
        if let Some(s) = self.spinner.take() {
            let _ = s.join();
        }
    }
}
