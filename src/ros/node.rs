//! The ROS 2 node over real DDS (ros2-client / RustDDS).
//!
//! One thread runs the simulation loop: it waits (mio poll) until the next tick, a
//! pose, a service request or a stop request, takes every pending input, steps,
//! publishes and records. A second thread runs ros2-client's spinner (discovery,
//! graph). Nothing in the loop blocks on a subscriber: outputs use non-blocking
//! publication (a full reliable window drops the sample and counts it).
//!
//! Modes: real time (a tick every `dt / real_time_factor` of wall time; late ticks are
//! skipped and counted, never run in a burst), as fast as possible, lock-step on a
//! handle (one step per accepted pose on its topic) or on the `step` service.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use ros2_client::dds::rustdds::mio1::{Events, Interest, Poll, Token, Waker};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    Context, ContextOptions, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher,
    QosProfile, Subscription,
};
use serde::Serialize;

use super::foxglove::{Advertised, FoxgloveConfig, FoxgloveOut};
use super::graph::{tf_pose, ClockIn, TfIn};
use super::input::InputPolicy;
use super::msgs::{
    Clock, MarkerArray, PoseStamped, RosMessage, SetBoolResponse, SimStatus, SingularPoints,
    TFMessage, TriggerResponse,
};
use super::names::NodeNames;
pub use super::node_stats::{rss_kib, LatencyStats, NodeStats, Window};
use super::param_msgs::{
    DescribeParametersResponse, GetParameterTypesResponse, GetParametersResponse,
    ListParametersResponse, SetParametersResponse, SetParametersResult,
};
use super::param_server::ParamTable;
use super::params::{ParamValue, Params};
use super::reply::Flushed;
use super::services::Services;
use super::session::{Frame, FrameContent, MarkerStyle, Session};
use crate::record::bag::BagOptions;
use crate::record::metadata::Qos;
use crate::record::recorder::{recorded_content, SessionRecorder};
use crate::scene::Scene;
use crate::sim::{ReachWatch, StepReport};

/// How ticks are paced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pacing {
    /// A tick every `dt / factor` seconds of wall time.
    RealTime { factor: f64 },
    /// Step as fast as possible.
    AsFastAsPossible,
}

/// What drives steps.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Lockstep {
    /// Ticks (see [`Pacing`]).
    Off,
    /// One step per `~/step` call.
    Service,
    /// One step per pose accepted on this handle's topic (handle index).
    Handle(usize),
}

/// Everything the node needs, resolved and validated.
pub struct NodeConfig {
    pub scene: Scene,
    pub names: NodeNames,
    pub domain_id: u16,
    pub record: Option<(std::path::PathBuf, BagOptions)>,
    /// Stop after this much simulated time, s.
    pub duration: Option<f64>,
    pub pacing: Pacing,
    pub lockstep: Lockstep,
    pub start_paused: bool,
    pub policy: InputPolicy,
    pub style: MarkerStyle,
    /// Follow an external `/clock` (and publish none) instead of owning time.
    pub use_sim_time: bool,
    /// s, a TF lookup at most this long after a chain's newest transform takes the newest.
    pub tf_max_lag: f64,
    /// The parameters as read (the parameter services report them; the node's own
    /// settings above win where they differ).
    pub params: Params,
    /// The live Foxglove WebSocket server (None: off).
    pub foxglove: Option<FoxgloveConfig>,
}

/// A problem starting or running the node.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    #[error("DDS: {0}")]
    Dds(String),
    #[error("{0}")]
    Record(#[from] crate::record::RecordError),
    #[error("poll: {0}")]
    Poll(#[from] std::io::Error),
    /// Settings that cannot work together (found before anything starts).
    #[error("{0}")]
    Config(String),
    #[error("{0}")]
    Foxglove(#[from] super::foxglove::FoxgloveStartError),
}

pub(super) fn dds<E: std::fmt::Debug>(what: &str) -> impl Fn(E) -> NodeError + '_ {
    move |e| NodeError::Dds(format!("{what}: {e:?}"))
}

const WAKE: Token = Token(usize::MAX - 1);
const SERVICE_TOKEN_BASE: usize = 1 << 20;
const GRAPH_TOKEN_BASE: usize = 1 << 21;
/// Under use_sim_time, at most this many catch-up steps run between two polls (inputs
/// and services stay served while the node catches up with a clock far ahead).
const CATCH_UP_BATCH: usize = 100;

struct ObjectPubs {
    markers: Option<Publisher<MarkerArray>>,
    singular_points: Option<Publisher<SingularPoints>>,
    status: Option<Publisher<SimStatus>>,
}

/// The running node.
pub struct SimNode {
    // field order = drop order: DDS entities, then the node, then the context
    /// (handle index, its pose subscription); TF-driven handles have none.
    subs: Vec<(usize, Subscription<PoseStamped>)>,
    pubs: Vec<ObjectPubs>,
    clock: Option<Publisher<Clock>>,
    /// TF in (a scene with handles), TF out (`outputs.tf`), an external clock.
    tf_in: Option<TfIn>,
    tf_out: Option<Publisher<TFMessage>>,
    clock_in: Option<ClockIn>,
    /// (handle index, TF frame) of the handles that follow TF frames.
    tf_handles: Vec<(usize, String)>,
    /// Per TF handle: whether its last lookup failed (said once, and when it recovers).
    tf_failing: Vec<bool>,
    /// s of simulated time between two published markers (None: every tick), and when
    /// the last went out.
    markers_period: Option<f64>,
    last_markers: Option<f64>,
    /// The colliders' markers (only for a scene with colliders and markers on).
    colliders: Option<Publisher<MarkerArray>>,
    /// The same outputs to Foxglove WebSocket clients (`--foxglove PORT`).
    foxglove: Option<FoxgloveOut>,
    services: Services,
    /// The parameters as the parameter services report them.
    params: ParamTable,
    node: Option<Node>,
    spinner: Option<std::thread::JoinHandle<()>>,
    _context: Context,
    poll: Poll,
    waker: Arc<Waker>,
    session: Session,
    recorder: Option<SessionRecorder>,
    published: FrameContent,
    cfg_duration: Option<f64>,
    pacing: Pacing,
    lockstep: Lockstep,
    names: NodeNames,
    // state
    /// Says when a handle target goes out of reach and when it is reached again.
    reach: ReachWatch,
    last_report: Option<StepReport>,
    last_step_duration: f64,
    pending_input: Vec<Option<Instant>>,
    stats: NodeStats,
    step_ms: Vec<f64>,
    tick_ms: Vec<f64>,
    input_ms: Vec<f64>,
    window_start: Instant,
    window_tick: Vec<f64>,
    window_input: Vec<f64>,
    window_steps: u64,
    window_inputs: u64,
    started: Instant,
}

/// Lock-step on a handle steps once per pose accepted on its topic. A handle that
/// follows a TF frame has no pose topic: its target is looked up at each tick, and /tf
/// carries every frame of the robot at the broadcasters' rates, so "one step per TF
/// message" would tie the simulation to unrelated frames. Refused, with the ways out.
fn lockstep_needs_a_pose_topic(cfg: &NodeConfig) -> Result<(), NodeError> {
    let Lockstep::Handle(h) = cfg.lockstep else {
        return Ok(());
    };
    match cfg.scene.handle_tf_frames.get(h) {
        Some(Some(frame)) => Err(NodeError::Config(format!(
            "--lockstep {name}: handle `{name}` follows TF frame `{frame}` (tf_frame in the \
             scene), so it has no pose topic to step on; use `--lockstep service` (one step \
             per ~/step call) or drive the handle from its pose topic",
            name = cfg
                .scene
                .world
                .handles()
                .get(h)
                .map_or("?", |s| s.name.as_str()),
        ))),
        _ => Ok(()),
    }
}

/// A topic for one of the node's writers whose history is bounded by its QoS depth.
///
/// RustDDS keeps every sample a reliable writer published until all matched readers
/// acknowledged it, and with no reader matched it keeps them up to its 8192-sample
/// backstop (rustdds 0.15 `remove_all_acked_changes_but_keep_depth`): 8192 meshes of
/// ~20 kB each, memory that grows for minutes. A `KeepLast(depth)` writer owes nobody
/// more than its last `depth` samples, so the topic carries resource limits of
/// `depth` samples (ros2-client's `QosProfile` has no resource limits; the writer
/// inherits them from the topic).
fn writer_topic(
    context: &Context,
    node_name: &NodeName,
    topic: &Name,
    type_name: MessageTypeName,
    q: Qos,
) -> Result<ros2_client::dds::rustdds::Topic, ros2_client::dds::rustdds::dds::CreateError> {
    use ros2_client::dds::rustdds::{policy, QosPolicies, QosPolicyBuilder, TopicKind};
    let depth = q.depth.max(1) as i32;
    let limits = QosPolicyBuilder::new()
        .resource_limits(policy::ResourceLimits {
            max_samples: depth,
            max_instances: 1,
            max_samples_per_instance: depth,
        })
        .build();
    let dds_qos = QosPolicies::from(qos(q)).modify_by(&limits);
    context.domain_participant().create_topic(
        topic.to_dds_name("rt", node_name, ""),
        type_name.dds_msg_type(),
        &dds_qos,
        TopicKind::NoKey,
    )
}

/// A publisher on `topic` (a resolved ROS name) whose writer history is bounded by its
/// QoS depth (see [`writer_topic`]). `what` names it in errors.
pub(super) fn bounded_publisher<M: RosMessage + Serialize>(
    node: &mut Node,
    context: &Context,
    node_name: &NodeName,
    topic: &str,
    q: Qos,
    what: &str,
) -> Result<Publisher<M>, NodeError> {
    let name = Name::parse(topic).map_err(dds("topic name"))?;
    let t = writer_topic(context, node_name, &name, topic_type::<M>(), q)
        .map_err(|e| NodeError::Dds(format!("{what} topic: {e:?}")))?;
    node.create_publisher(&t, Some(qos(q)))
        .map_err(|e| NodeError::Dds(format!("{what} publisher: {e:?}")))
}

/// The DDS QoS of a recorded-QoS description. Reliable writers never block the loop:
/// a full window fails the publication (counted) instead.
pub(super) fn qos(q: Qos) -> QosProfile {
    let p = QosProfile::subscription_default().history(History::KeepLast {
        depth: q.depth as usize,
    });
    let p = if q.reliable {
        p.reliability_reliable(WhenFull::Fail)
    } else {
        p.reliability_best_effort()
    };
    p.durability(if q.transient_local {
        Durability::TransientLocal
    } else {
        Durability::Volatile
    })
}

pub(super) fn topic_type<M: RosMessage>() -> MessageTypeName {
    let mut parts = M::TYPE.split('/');
    let pkg = parts.next().unwrap_or("");
    let ty = parts.nth(1).unwrap_or("");
    MessageTypeName::new(pkg, ty)
}

impl SimNode {
    /// Join the DDS domain and create every topic, service and the bag.
    pub fn new(cfg: NodeConfig) -> Result<SimNode, NodeError> {
        lockstep_needs_a_pose_topic(&cfg)?;
        let context = Context::with_options(ContextOptions::new().domain_id(cfg.domain_id))
            .map_err(dds("creating the DDS participant"))?;
        let node_name =
            NodeName::new(&cfg.names.namespace, &cfg.names.node).map_err(dds("node name"))?;
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

        let scene = cfg.scene;
        let outputs = scene.outputs;
        let published = FrameContent {
            markers: outputs.markers,
            singular_points: outputs.singular_points,
            status: outputs.status,
        };
        let names = cfg.names;
        let name = |s: &str| Name::parse(s).map_err(dds("topic name"));
        let poll = Poll::new()?;
        let waker = Arc::new(Waker::new(poll.registry(), WAKE)?);

        let mut subs = Vec::new();
        let tf_handles: Vec<(usize, String)> = scene
            .handle_tf_frames
            .iter()
            .enumerate()
            .filter_map(|(i, f)| f.clone().map(|f| (i, f)))
            .collect();
        for (i, t) in names.handles.iter().enumerate() {
            if tf_handles.iter().any(|(h, _)| *h == i) {
                continue;
            }
            let topic = node
                .create_topic(
                    &name(t)?,
                    topic_type::<PoseStamped>(),
                    &qos(Qos::SENSOR_DATA),
                )
                .map_err(dds("handle topic"))?;
            let mut sub = node
                .create_subscription::<PoseStamped>(&topic, Some(qos(Qos::SENSOR_DATA)))
                .map_err(dds("handle subscription"))?;
            poll.registry()
                .register(&mut sub, Token(i), Interest::READABLE)?;
            subs.push((i, sub));
        }
        // TF in for every scene with handles: TF-driven handles, and poses in another
        // frame of the tree
        let tf_in = (!names.handles.is_empty())
            .then(|| {
                TfIn::new(
                    &mut node,
                    &names.tf,
                    &names.tf_static,
                    &poll,
                    GRAPH_TOKEN_BASE,
                    Duration::from_secs_f64(cfg.tf_max_lag),
                )
            })
            .transpose()?;
        let clock_in = cfg
            .use_sim_time
            .then(|| ClockIn::new(&mut node, &names.clock, &poll, GRAPH_TOKEN_BASE + 2))
            .transpose()?;
        let tf_out = outputs
            .tf
            .then(|| {
                bounded_publisher(
                    &mut node,
                    &context,
                    &node_name,
                    &names.tf,
                    super::graph::TF_QOS,
                    "tf",
                )
            })
            .transpose()?;
        let mut pubs = Vec::new();
        for o in &names.objects {
            let markers = outputs
                .markers
                .then(|| {
                    bounded_publisher(
                        &mut node,
                        &context,
                        &node_name,
                        &o.markers,
                        Qos::MARKERS,
                        "markers",
                    )
                })
                .transpose()?;
            let singular_points = outputs
                .singular_points
                .then(|| {
                    bounded_publisher(
                        &mut node,
                        &context,
                        &node_name,
                        &o.singular_points,
                        Qos::DATA,
                        "singular points",
                    )
                })
                .transpose()?;
            let status = outputs
                .status
                .then(|| {
                    bounded_publisher(
                        &mut node,
                        &context,
                        &node_name,
                        &o.status,
                        Qos::DATA,
                        "status",
                    )
                })
                .transpose()?;
            pubs.push(ObjectPubs {
                markers,
                singular_points,
                status,
            });
        }
        // under use_sim_time another node owns /clock
        let clock = (outputs.clock && !cfg.use_sim_time)
            .then(|| {
                bounded_publisher(
                    &mut node,
                    &context,
                    &node_name,
                    &names.clock,
                    Qos::CLOCK,
                    "clock",
                )
            })
            .transpose()?;
        let has_colliders = scene
            .world
            .contact_stage()
            .is_some_and(|s| !s.colliders().is_empty());
        let colliders = (outputs.markers && has_colliders)
            .then(|| {
                bounded_publisher(
                    &mut node,
                    &context,
                    &node_name,
                    &names.colliders,
                    Qos::MARKERS,
                    "colliders",
                )
            })
            .transpose()?;
        let services = Services::new(&mut node, &node_name, &names, &poll, SERVICE_TOKEN_BASE)?;
        let foxglove = match &cfg.foxglove {
            Some(f) => {
                let what = Advertised {
                    content: published,
                    colliders: colliders.is_some(),
                    tf: tf_out.is_some(),
                };
                let out = FoxgloveOut::start(f, &names, what)?;
                eprintln!(
                    "[developable_sim] Foxglove: open ws://{}:{} in Foxglove",
                    f.bind,
                    out.port()
                );
                Some(out)
            }
            None => None,
        };

        let mut handle_topics = names.handles.clone();
        for (h, _) in &tf_handles {
            handle_topics[*h] = names.tf.clone();
        }
        let mut session = Session::new(scene, cfg.policy, handle_topics);
        session.style = cfg.style;
        session.paused = cfg.start_paused;
        let recorder = match &cfg.record {
            Some((dir, options)) => Some(SessionRecorder::create(
                dir,
                options.clone(),
                &session,
                &names,
                published,
                outputs.clock && !cfg.use_sim_time,
            )?),
            None => None,
        };
        let n_handles = names.handles.len();
        let stats = NodeStats {
            scene: session.scene.name.clone(),
            mode: match (&cfg.lockstep, cfg.pacing) {
                (Lockstep::Service, _) => "lockstep:service".into(),
                (Lockstep::Handle(h), _) => format!("lockstep:{}", names.handles[*h]),
                (Lockstep::Off, Pacing::AsFastAsPossible) => "as_fast_as_possible".into(),
                (Lockstep::Off, Pacing::RealTime { factor }) => format!("real_time x{factor}"),
            },
            dt: session.scene.world.dt(),
            ..NodeStats::default()
        };
        let mut params = ParamTable::new(&cfg.params);
        // the parameters in effect (flags and the scene may have set them)
        let markers_rate = match cfg.params.double("markers_rate") {
            Some(r) => r,
            None => outputs.markers_rate.unwrap_or(0.0),
        };
        params.store("markers_rate", ParamValue::Double(markers_rate));
        params.store("paused", ParamValue::Bool(cfg.start_paused));
        params.store("start_paused", ParamValue::Bool(cfg.start_paused));
        params.store("use_sim_time", ParamValue::Bool(cfg.use_sim_time));
        params.store("tf_max_lag", ParamValue::Double(cfg.tf_max_lag));
        if let Pacing::RealTime { factor } = cfg.pacing {
            params.store("real_time_factor", ParamValue::Double(factor));
        }
        let markers_period = (markers_rate > 0.0).then(|| 1.0 / markers_rate);
        Ok(SimNode {
            subs,
            pubs,
            clock,
            tf_in,
            tf_out,
            clock_in,
            tf_failing: vec![false; tf_handles.len()],
            tf_handles,
            markers_period,
            last_markers: None,
            colliders,
            foxglove,
            services,
            params,
            node: Some(node),
            spinner: Some(spinner),
            _context: context,
            poll,
            waker,
            session,
            recorder,
            published,
            cfg_duration: cfg.duration,
            pacing: cfg.pacing,
            lockstep: cfg.lockstep,
            names,
            reach: ReachWatch::default(),
            last_report: None,
            last_step_duration: 0.0,
            pending_input: vec![None; n_handles],
            stats,
            step_ms: Vec::new(),
            tick_ms: Vec::new(),
            input_ms: Vec::new(),
            window_start: Instant::now(),
            window_tick: Vec::new(),
            window_input: Vec::new(),
            window_steps: 0,
            window_inputs: 0,
            started: Instant::now(),
        })
    }

    /// Wakes the loop (for a signal handler: set the stop flag, then wake).
    pub fn waker(&self) -> Arc<Waker> {
        Arc::clone(&self.waker)
    }

    /// The resolved names (for the start-up banner).
    pub fn names(&self) -> &NodeNames {
        &self.names
    }

    fn period(&self) -> Duration {
        let dt = self.session.scene.world.dt();
        match self.pacing {
            Pacing::RealTime { factor } => Duration::from_secs_f64(dt / factor),
            Pacing::AsFastAsPossible => Duration::ZERO,
        }
    }

    fn done(&self) -> bool {
        match self.cfg_duration {
            Some(d) => self.session.scene.world.time() >= d - 0.5 * self.session.scene.world.dt(),
            None => false,
        }
    }

    /// Run until `stop` is set (then woken) or the duration is reached.
    pub fn run(mut self, stop: &AtomicBool) -> Result<NodeStats, NodeError> {
        self.started = Instant::now();
        self.window_start = self.started;
        let frame = self.session.frame(None, 0.0, self.content());
        self.emit(&frame, None);
        let mut next_tick = Instant::now() + self.period();
        let mut events = Events::with_capacity(64);
        // under use_sim_time the external clock drives the steps
        let free_running = self.lockstep == Lockstep::Off && self.clock_in.is_none();
        let mut behind_clock = false;
        while !stop.load(Ordering::SeqCst) && !self.done() {
            let now = Instant::now();
            let timeout = if behind_clock {
                Duration::ZERO
            } else if free_running && !self.session.paused {
                next_tick.saturating_duration_since(now)
            } else {
                Duration::from_millis(200)
            };
            // held service replies are re-checked every SETTLE
            let timeout = if self.replies_waiting() {
                timeout.min(super::reply::SETTLE)
            } else {
                timeout
            };
            if let Err(e) = self.poll.poll(&mut events, Some(timeout)) {
                if e.kind() != std::io::ErrorKind::Interrupted {
                    return Err(e.into());
                }
            }
            // edge-triggered sources: drain all of them whatever woke us
            self.drain_graph();
            self.drain_inputs();
            self.drain_services(&mut next_tick);
            if stop.load(Ordering::SeqCst) || self.done() {
                break;
            }
            if self.lockstep == Lockstep::Off {
                behind_clock = self.follow_clock();
            }
            let now = Instant::now();
            if free_running && !self.session.paused && now >= next_tick {
                // real_time_factor may change at run time
                let period = self.period();
                self.tick(now);
                next_tick += period;
                let after = Instant::now();
                if period > Duration::ZERO && after > next_tick + period {
                    let behind = after.duration_since(next_tick).as_secs_f64();
                    let missed = (behind / period.as_secs_f64()).floor() as u64;
                    self.session.overrun_ticks += missed;
                    next_tick += period * missed as u32;
                }
                if period == Duration::ZERO {
                    next_tick = after;
                }
            }
            self.roll_window(false);
        }
        self.roll_window(true);
        Ok(self.finish())
    }

    fn content(&self) -> FrameContent {
        if self.recorder.is_some() {
            let r = recorded_content(self.published);
            FrameContent {
                markers: r.markers,
                singular_points: r.singular_points,
                status: true,
            }
        } else {
            self.published
        }
    }

    /// TF and the external clock: take what arrived.
    fn drain_graph(&mut self) {
        if let Some(tf) = &mut self.tf_in {
            tf.drain();
        }
        if let Some(c) = &mut self.clock_in {
            c.drain();
        }
    }

    /// Under use_sim_time: step (at most [`CATCH_UP_BATCH`] times) while the next state's
    /// time is not after the external clock. Returns whether the node is still behind.
    fn follow_clock(&mut self) -> bool {
        let Some(clock_ns) = self.clock_in.as_ref().and_then(|c| c.now_ns) else {
            return false;
        };
        let world = &self.session.scene.world;
        let (dt, clock) = (world.dt(), clock_ns as f64 * 1e-9);
        let due = |w: &crate::sim::World| w.time() + 0.5 * dt <= clock;
        for _ in 0..CATCH_UP_BATCH {
            if self.session.paused || self.done() || !due(&self.session.scene.world) {
                return false;
            }
            self.tick(Instant::now());
        }
        due(&self.session.scene.world)
    }

    /// The time TF is looked up at for the state a tick computes, ns: the wall clock when
    /// the node owns time (everyone else stamps in wall time), the state's simulated time
    /// under use_sim_time (the graph's clock; see `graph`).
    fn lookup_time_ns(&self) -> u64 {
        if self.clock_in.is_some() {
            let w = &self.session.scene.world;
            ((w.time() + w.dt()) * 1e9).round().max(0.0) as u64
        } else {
            crate::record::bag::now_ns()
        }
    }

    /// The targets of TF-driven handles for the coming step: each frame looked up in the
    /// scene frame, offered (and recorded) as a pose of its handle; a failed lookup is
    /// counted and the handle keeps its last target.
    fn offer_tf_targets(&mut self) {
        let Some(tf) = &self.tf_in else {
            return;
        };
        if self.tf_handles.is_empty() {
            return;
        }
        let at = self.lookup_time_ns();
        let scene_frame = self.session.scene.frame_id.clone();
        let looked_up: Vec<_> = self
            .tf_handles
            .iter()
            .map(|(h, frame)| (*h, tf_pose(tf, &scene_frame, frame, at)))
            .collect();
        for (k, (h, result)) in looked_up.into_iter().enumerate() {
            let frame = &self.tf_handles[k].1;
            match result {
                Ok(msg) => {
                    if self.tf_failing[k] {
                        eprintln!(
                            "[developable_sim] handle {}: TF frame {frame} found again",
                            self.session.scene.world.handles()[h].name
                        );
                        self.tf_failing[k] = false;
                    }
                    let arrival_ns = self.arrival_ns();
                    self.record(|r| r.record_input(h, &msg, arrival_ns, None));
                    if self.session.offer(h, &msg, arrival_ns).is_err() {
                        self.stats.inputs_rejected += 1;
                    }
                }
                Err(e) => {
                    if !self.tf_failing[k] {
                        eprintln!(
                            "[developable_sim] warning: handle {}: TF frame {frame} in {scene_frame}: {e}; the handle keeps its last target",
                            self.session.scene.world.handles()[h].name
                        );
                        self.tf_failing[k] = true;
                    }
                    let what = super::msgs::PoseStamped {
                        header: super::msgs::Header {
                            stamp: super::msgs::Time::from_nanos(at as i64),
                            frame_id: frame.clone(),
                        },
                        pose: super::msgs::Pose::default(), // identity
                    };
                    let arrival_ns = self.arrival_ns();
                    self.record(|r| r.record_tf_failure(h, &what, arrival_ns));
                    self.session.reject_tf(h);
                    self.stats.inputs_rejected += 1;
                }
            }
        }
    }

    /// The arrival time of an input: the recorder's (strictly increasing, it is the
    /// input's log time in the bag) when recording, else the wall clock, ns.
    fn arrival_ns(&mut self) -> u64 {
        self.recorder
            .as_mut()
            .map_or_else(crate::record::bag::now_ns, |r| r.arrival_ns())
    }

    /// One step now; `trigger` is when the tick started or the lock-step input came.
    fn tick(&mut self, trigger: Instant) {
        self.offer_tf_targets();
        let (report, step_s) = self.session.step();
        let world = &self.session.scene.world;
        for m in self
            .reach
            .update(&report, world.object_names(), world.handles())
        {
            eprintln!("[developable_sim] {m}");
        }
        self.step_ms.push(step_s * 1e3);
        self.stats.steps += 1;
        self.window_steps += 1;
        let frame = self.session.frame(Some(&report), step_s, self.content());
        self.last_report = Some(report);
        self.last_step_duration = step_s;
        self.emit(&frame, Some(trigger));
    }

    /// Publish a frame (clock, markers, singular points, status), then record it.
    fn emit(&mut self, frame: &Frame, trigger: Option<Instant>) {
        let mut dropped = 0u64;
        if let Some(c) = &self.clock {
            dropped += c.publish(frame.clock).is_err() as u64;
        }
        let t = self.session.scene.world.time();
        let markers_due = match (self.markers_period, self.last_markers) {
            (Some(period), Some(last)) => t - last >= period - 0.5 * self.session.scene.world.dt(),
            _ => true,
        };
        if markers_due && frame.objects.iter().any(|o| o.markers.is_some()) {
            self.last_markers = Some(t);
        }
        for (o, p) in frame.objects.iter().zip(&self.pubs) {
            if let (Some(m), Some(publisher), true) = (&o.markers, &p.markers, markers_due) {
                dropped += publisher.publish(m.clone()).is_err() as u64;
            }
        }
        let tf =
            (self.tf_out.is_some()).then(|| super::frames::tf_message(&self.session, frame.stamp));
        if let (Some(publisher), Some(tf)) = (&self.tf_out, &tf) {
            dropped += publisher.publish(tf.clone()).is_err() as u64;
        }
        if let (Some(m), Some(publisher)) = (&frame.colliders, &self.colliders) {
            dropped += publisher.publish(m.clone()).is_err() as u64;
        }
        let published_at = Instant::now();
        if let Some(t) = trigger {
            let ms = published_at.duration_since(t).as_secs_f64() * 1e3;
            self.tick_ms.push(ms);
            self.window_tick.push(ms);
            for p in self.pending_input.iter_mut() {
                if let Some(at) = p.take() {
                    let ms = published_at.duration_since(at).as_secs_f64() * 1e3;
                    self.input_ms.push(ms);
                    self.window_input.push(ms);
                }
            }
        }
        for (o, p) in frame.objects.iter().zip(&self.pubs) {
            if let (Some(s), Some(publisher)) = (&o.singular_points, &p.singular_points) {
                dropped += publisher.publish(s.clone()).is_err() as u64;
            }
            if let (Some(s), Some(publisher)) = (&o.status, &p.status) {
                dropped += publisher.publish(s.clone()).is_err() as u64;
            }
        }
        self.stats.dropped_publications += dropped;
        if let Some(f) = self.foxglove.as_mut() {
            f.emit(frame, markers_due, tf.as_ref());
        }
        self.record(|r| r.record_frame(frame));
    }

    fn record(
        &mut self,
        f: impl FnOnce(&mut SessionRecorder) -> Result<(), crate::record::RecordError>,
    ) {
        let Some(r) = self.recorder.as_mut() else {
            return;
        };
        if let Err(e) = f(r) {
            eprintln!(
                "[developable_sim] error: recording stopped: {e}; the simulation goes on \
                 without recording"
            );
            self.stats.record_error = Some(e.to_string());
            if let Some(r) = self.recorder.take() {
                self.stats.recorded = r.counts();
                match r.close() {
                    Ok(n) => eprintln!("[developable_sim] bag closed with {n} messages"),
                    Err(e) => eprintln!("[developable_sim] bag closed after an error: {e}"),
                }
            }
        }
    }

    fn drain_inputs(&mut self) {
        for k in 0..self.subs.len() {
            let h = self.subs[k].0;
            loop {
                let taken = match self.subs[k].1.take() {
                    Ok(Some(x)) => x,
                    Ok(None) => break,
                    Err(e) => {
                        eprintln!(
                            "[developable_sim] warning: {}: {e:?}",
                            self.names.handles[h]
                        );
                        self.stats.inputs_rejected += 1;
                        break;
                    }
                };
                let received = Instant::now();
                let (msg, info) = taken;
                // a pose in another frame of the TF tree, in the scene frame at its stamp
                let msg = match self
                    .tf_in
                    .as_ref()
                    .map(|tf| tf.to_scene(&self.session.scene.frame_id, &msg))
                {
                    Some(Ok(Some(transformed))) => transformed,
                    Some(Err(
                        super::tf::LookupError::TooOld { .. }
                        | super::tf::LookupError::TooNew { .. },
                    )) => {
                        self.stats.inputs_received += 1;
                        self.stats.inputs_rejected += 1;
                        let arrival_ns = self.arrival_ns();
                        self.record(|r| r.record_tf_failure(h, &msg, arrival_ns));
                        self.session.reject_tf(h);
                        continue;
                    }
                    // unknown frames are the input filter's to reject
                    _ => msg,
                };
                self.stats.inputs_received += 1;
                self.window_inputs += 1;
                let publish_ns = info
                    .source_timestamp()
                    .map(|t| t.to_nanos())
                    .filter(|t| *t > 0)
                    .map(|t| t as u64);
                let arrival_ns = self
                    .recorder
                    .as_mut()
                    .map_or_else(crate::record::bag::now_ns, |r| r.arrival_ns());
                self.record(|r| r.record_input(h, &msg, arrival_ns, publish_ns));
                match self.session.offer(h, &msg, arrival_ns) {
                    Ok(()) => {
                        self.pending_input[h] = Some(received);
                        if self.lockstep == Lockstep::Handle(h) && !self.session.paused {
                            self.tick(received);
                            if self.done() {
                                return;
                            }
                        }
                    }
                    Err(_) => self.stats.inputs_rejected += 1,
                }
            }
        }
    }

    fn drain_services(&mut self, next_tick: &mut Instant) {
        while let Some((id, _req)) = self.services.reset.receive() {
            self.session.reset();
            self.reach.clear();
            self.last_markers = None;
            self.last_report = None;
            self.last_step_duration = 0.0;
            for p in &mut self.pending_input {
                *p = None;
            }
            let frame = self.session.frame(None, 0.0, self.content());
            self.emit(&frame, None);
            *next_tick = Instant::now() + self.period();
            let resp = TriggerResponse {
                success: true,
                message: format!("reset to t = 0 s (episode {})", self.session.episode),
            };
            self.services.reset.reply(id, resp);
        }
        while let Some((id, req)) = self.services.set_paused.receive() {
            self.set_paused(req.data, next_tick);
            let t = self.session.scene.world.time();
            let resp = SetBoolResponse {
                success: true,
                message: if req.data {
                    format!("paused at t = {t:.6} s")
                } else {
                    format!("running from t = {t:.6} s")
                },
            };
            self.services.set_paused.reply(id, resp);
        }
        while let Some((id, _req)) = self.services.step.receive() {
            let resp = if self.lockstep == Lockstep::Service || self.session.paused {
                self.tick(Instant::now());
                TriggerResponse {
                    success: true,
                    message: format!(
                        "stepped to t = {:.6} s (step {})",
                        self.session.scene.world.time(),
                        self.session.scene.world.steps_taken()
                    ),
                }
            } else {
                TriggerResponse {
                    success: false,
                    message: "the simulation is running: pause it first (~/set_paused true) \
                              or start the node with --lockstep service"
                        .into(),
                }
            };
            self.services.step.reply(id, resp);
        }
        self.drain_parameter_services(next_tick);
        self.flush_replies();
    }

    fn replies_waiting(&self) -> bool {
        self.services.waiting()
    }

    /// Pause or resume; a change sends a fresh status so subscribers see `paused`.
    fn set_paused(&mut self, paused: bool, next_tick: &mut Instant) {
        let was = self.session.paused;
        self.session.paused = paused;
        self.params.store("paused", ParamValue::Bool(paused));
        if was && !paused {
            *next_tick = Instant::now() + self.period();
        }
        if was != paused {
            let content = FrameContent {
                markers: false,
                singular_points: false,
                status: true,
            };
            let frame =
                self.session
                    .frame(self.last_report.as_ref(), self.last_step_duration, content);
            self.emit(&frame, None);
        }
    }

    /// Answer the rcl_interfaces parameter services; apply what `set_parameters` changed.
    fn drain_parameter_services(&mut self, next_tick: &mut Instant) {
        let s = &mut self.services;
        while let Some((id, req)) = s.list_parameters.receive() {
            let result = self.params.list(&req);
            s.list_parameters
                .reply(id, ListParametersResponse { result });
        }
        while let Some((id, req)) = s.get_parameters.receive() {
            let values = self.params.values(&req.names);
            s.get_parameters.reply(id, GetParametersResponse { values });
        }
        while let Some((id, req)) = s.describe_parameters.receive() {
            let descriptors = self.params.describe(&req.names);
            s.describe_parameters
                .reply(id, DescribeParametersResponse { descriptors });
        }
        while let Some((id, req)) = s.get_parameter_types.receive() {
            let types = self.params.types(&req.names);
            s.get_parameter_types
                .reply(id, GetParameterTypesResponse { types });
        }
        while let Some((id, req)) = self.services.set_parameters.receive() {
            let results = req
                .parameters
                .iter()
                .map(|p| match self.params.check(p) {
                    Ok(v) => {
                        self.apply_parameter(&p.name, &v, next_tick);
                        self.params.store(&p.name, v);
                        SetParametersResult {
                            successful: true,
                            reason: String::new(),
                        }
                    }
                    Err(reason) => SetParametersResult {
                        successful: false,
                        reason,
                    },
                })
                .collect();
            self.services
                .set_parameters
                .reply(id, SetParametersResponse { results });
        }
    }

    /// Make a checked run-time parameter take effect (see `param_server::RUNTIME`).
    fn apply_parameter(&mut self, name: &str, v: &ParamValue, next_tick: &mut Instant) {
        let (b, x) = match v {
            ParamValue::Bool(b) => (*b, 0.0),
            ParamValue::Double(x) => (false, *x),
            _ => (false, 0.0),
        };
        match name {
            "paused" => self.set_paused(b, next_tick),
            "markers_rate" => self.markers_period = (x > 0.0).then(|| 1.0 / x),
            "accept_empty_frame_id" => self.session.policy.accept_empty_frame_id = b,
            "max_stamp_lead" => self.session.policy.max_stamp_lead = x,
            "tf_max_lag" => {
                if let Some(tf) = &mut self.tf_in {
                    tf.max_lag = Duration::from_secs_f64(x);
                }
            }
            "real_time_factor" => {
                if let Pacing::RealTime { factor } = &mut self.pacing {
                    *factor = x;
                    *next_tick = Instant::now() + self.period();
                }
            }
            "marker.line_width" => self.session.style.line_width = x,
            "marker.sphere_diameter" => self.session.style.sphere_diameter = x,
            _ => {}
        }
    }

    /// Send the held replies whose clients can receive them (see `reply`).
    fn flush_replies(&mut self) {
        let participant = self._context.domain_participant();
        let Flushed {
            sent,
            sent_unseen,
            failed,
        } = self.services.flush(&participant, Instant::now());
        self.stats.service_replies += sent + sent_unseen;
        self.stats.service_replies_unseen += sent_unseen + failed;
        if sent_unseen + failed > 0 {
            eprintln!(
                "[developable_sim] warning: {} service repl{} sent although the \
                 client's reply reader was not discovered within {} s, {failed} failed \
                 (is the client on the Cyclone DDS service mapping?)",
                sent_unseen,
                if sent_unseen == 1 { "y" } else { "ies" },
                super::reply::GIVE_UP.as_secs()
            );
        }
    }

    fn roll_window(&mut self, last: bool) {
        let elapsed = self.window_start.elapsed();
        if elapsed < Duration::from_secs(10) && !last {
            return;
        }
        if elapsed.is_zero() {
            return;
        }
        self.stats.windows.push(Window {
            end_s: self.started.elapsed().as_secs_f64(),
            rss_kib: rss_kib(),
            steps: self.window_steps,
            inputs: self.window_inputs,
            tick_to_markers: LatencyStats::of(&self.window_tick),
            input_to_markers: LatencyStats::of(&self.window_input),
        });
        self.window_tick.clear();
        self.window_input.clear();
        self.window_steps = 0;
        self.window_inputs = 0;
        self.window_start = Instant::now();
    }

    fn finish(mut self) -> NodeStats {
        // replies still held for clients not yet discovered get a short grace
        let grace = Instant::now() + Duration::from_millis(250);
        while self.replies_waiting() && Instant::now() < grace {
            std::thread::sleep(super::reply::SETTLE);
            self.flush_replies();
        }
        let mut stats = std::mem::take(&mut self.stats);
        stats.sim_time = self.session.scene.world.time();
        stats.wall_s = self.started.elapsed().as_secs_f64();
        stats.overrun_ticks = self.session.overrun_ticks;
        stats.step = LatencyStats::of(&self.step_ms);
        stats.tick_to_markers = LatencyStats::of(&self.tick_ms);
        let beyond: Vec<f64> = self
            .tick_ms
            .iter()
            .zip(&self.step_ms)
            .map(|(tick, step)| tick - step)
            .collect();
        stats.tick_beyond_step = LatencyStats::of(&beyond);
        stats.input_to_markers = LatencyStats::of(&self.input_ms);
        if let Some(r) = self.recorder.take() {
            stats.recorded = r.counts();
            let dir = r.dir().to_path_buf();
            match r.close() {
                Ok(n) => eprintln!(
                    "[developable_sim] bag {} closed: {n} messages",
                    dir.display()
                ),
                Err(e) => {
                    eprintln!("[developable_sim] error: closing the bag: {e}");
                    stats.record_error = Some(e.to_string());
                }
            }
        }
        stats
    }
}

impl Drop for SimNode {
    fn drop(&mut self) {
        // shutdown order: DDS entities and the node (stops the spinner), then the
        // spinner thread, then the context (field order)
        self.subs.clear();
        self.pubs.clear();
        self.clock = None;
        self.tf_in = None;
        self.tf_out = None;
        self.clock_in = None;
        drop(self.node.take());
        if let Some(s) = self.spinner.take() {
            let _ = s.join();
        }
    }
}
