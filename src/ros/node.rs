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
    QosProfile, Server, ServiceMapping, ServiceTypeName, Subscription,
};
use serde::Serialize;

use super::input::InputPolicy;
use super::msgs::{
    Clock, MarkerArray, PoseStamped, RosMessage, SetBoolRequest, SetBoolResponse, SimStatus,
    SingularPoints, TriggerRequest, TriggerResponse,
};
use super::names::NodeNames;
pub use super::node_stats::{rss_kib, LatencyStats, NodeStats, Window};
use super::reply::{ClientReaders, Flushed, HeldReplies};
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
}

fn dds<E: std::fmt::Debug>(what: &str) -> impl Fn(E) -> NodeError + '_ {
    move |e| NodeError::Dds(format!("{what}: {e:?}"))
}

const WAKE: Token = Token(usize::MAX - 1);
const SERVICE_TOKEN_BASE: usize = 1 << 20;

struct ObjectPubs {
    markers: Option<Publisher<MarkerArray>>,
    singular_points: Option<Publisher<SingularPoints>>,
    status: Option<Publisher<SimStatus>>,
}

/// The running node.
pub struct SimNode {
    // field order = drop order: DDS entities, then the node, then the context
    subs: Vec<Subscription<PoseStamped>>,
    pubs: Vec<ObjectPubs>,
    clock: Option<Publisher<Clock>>,
    /// The colliders' markers (only for a scene with colliders and markers on).
    colliders: Option<Publisher<MarkerArray>>,
    reset_srv: Server<TriggerRequest, TriggerResponse>,
    pause_srv: Server<SetBoolRequest, SetBoolResponse>,
    step_srv: Server<TriggerRequest, TriggerResponse>,
    reset_replies: HeldReplies<TriggerResponse>,
    pause_replies: HeldReplies<SetBoolResponse>,
    step_replies: HeldReplies<TriggerResponse>,
    client_readers: ClientReaders,
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
fn bounded_publisher<M: RosMessage + Serialize>(
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
fn qos(q: Qos) -> QosProfile {
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

fn topic_type<M: RosMessage>() -> MessageTypeName {
    let mut parts = M::TYPE.split('/');
    let pkg = parts.next().unwrap_or("");
    let ty = parts.nth(1).unwrap_or("");
    MessageTypeName::new(pkg, ty)
}

impl SimNode {
    /// Join the DDS domain and create every topic, service and the bag.
    pub fn new(cfg: NodeConfig) -> Result<SimNode, NodeError> {
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
        for (i, t) in names.handles.iter().enumerate() {
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
            subs.push(sub);
        }
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
        let clock = outputs
            .clock
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
        let srv_qos = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::Fail)
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 10 });
        let trigger = ServiceTypeName::new("std_srvs", "Trigger");
        let held = |s: &str| -> Result<_, NodeError> {
            let n = name(s)?;
            Ok(HeldReplies::new(
                n.to_dds_name("rq", &node_name, "Request"),
                n.to_dds_name("rr", &node_name, "Reply"),
            ))
        };
        let reset_replies = held(&names.reset)?;
        let pause_replies = held(&names.set_paused)?;
        let step_replies = held(&names.step)?;
        let mut reset_srv = node
            .create_server::<TriggerRequest, TriggerResponse>(
                ServiceMapping::Cyclone,
                &name(&names.reset)?,
                &trigger,
                srv_qos.clone(),
                srv_qos.clone(),
            )
            .map_err(dds("reset service"))?;
        let mut pause_srv = node
            .create_server::<SetBoolRequest, SetBoolResponse>(
                ServiceMapping::Cyclone,
                &name(&names.set_paused)?,
                &ServiceTypeName::new("std_srvs", "SetBool"),
                srv_qos.clone(),
                srv_qos.clone(),
            )
            .map_err(dds("set_paused service"))?;
        let mut step_srv = node
            .create_server::<TriggerRequest, TriggerResponse>(
                ServiceMapping::Cyclone,
                &name(&names.step)?,
                &trigger,
                srv_qos.clone(),
                srv_qos,
            )
            .map_err(dds("step service"))?;
        poll.registry().register(
            &mut reset_srv,
            Token(SERVICE_TOKEN_BASE),
            Interest::READABLE,
        )?;
        poll.registry().register(
            &mut pause_srv,
            Token(SERVICE_TOKEN_BASE + 1),
            Interest::READABLE,
        )?;
        poll.registry().register(
            &mut step_srv,
            Token(SERVICE_TOKEN_BASE + 2),
            Interest::READABLE,
        )?;

        let mut session = Session::new(scene, cfg.policy, names.handles.clone());
        session.style = cfg.style;
        session.paused = cfg.start_paused;
        let recorder = match &cfg.record {
            Some((dir, options)) => Some(SessionRecorder::create(
                dir,
                options.clone(),
                &session,
                &names,
                published,
                outputs.clock,
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
        Ok(SimNode {
            subs,
            pubs,
            clock,
            colliders,
            reset_srv,
            pause_srv,
            step_srv,
            reset_replies,
            pause_replies,
            step_replies,
            client_readers: ClientReaders::default(),
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
        let period = self.period();
        let mut next_tick = Instant::now() + period;
        let mut events = Events::with_capacity(64);
        let free_running = self.lockstep == Lockstep::Off;
        while !stop.load(Ordering::SeqCst) && !self.done() {
            let now = Instant::now();
            let timeout = if free_running && !self.session.paused {
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
            self.drain_inputs();
            self.drain_services(&mut next_tick);
            if stop.load(Ordering::SeqCst) || self.done() {
                break;
            }
            let now = Instant::now();
            if free_running && !self.session.paused && now >= next_tick {
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

    /// One step now; `trigger` is when the tick started or the lock-step input came.
    fn tick(&mut self, trigger: Instant) {
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
        for (o, p) in frame.objects.iter().zip(&self.pubs) {
            if let (Some(m), Some(publisher)) = (&o.markers, &p.markers) {
                dropped += publisher.publish(m.clone()).is_err() as u64;
            }
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
        for h in 0..self.subs.len() {
            loop {
                let taken = match self.subs[h].take() {
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
        while let Ok(Some((id, _req))) = self.reset_srv.receive_request() {
            self.session.reset();
            self.reach.clear();
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
            self.reset_replies.hold(id, resp);
        }
        while let Ok(Some((id, req))) = self.pause_srv.receive_request() {
            let was = self.session.paused;
            self.session.paused = req.data;
            if was && !req.data {
                *next_tick = Instant::now() + self.period();
            }
            if was != req.data {
                // a fresh status so subscribers see `paused` change
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
            let t = self.session.scene.world.time();
            let resp = SetBoolResponse {
                success: true,
                message: if req.data {
                    format!("paused at t = {t:.6} s")
                } else {
                    format!("running from t = {t:.6} s")
                },
            };
            self.pause_replies.hold(id, resp);
        }
        while let Ok(Some((id, _req))) = self.step_srv.receive_request() {
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
            self.step_replies.hold(id, resp);
        }
        self.flush_replies();
    }

    fn replies_waiting(&self) -> bool {
        !(self.reset_replies.is_empty()
            && self.pause_replies.is_empty()
            && self.step_replies.is_empty())
    }

    /// Send the held replies whose clients can receive them (see `reply`).
    fn flush_replies(&mut self) {
        if !self.replies_waiting() {
            return;
        }
        let now = Instant::now();
        self.client_readers
            .refresh(&self._context.domain_participant(), now);
        let r = &self.client_readers;
        let done = [
            self.reset_replies.flush(&self.reset_srv, r, now),
            self.pause_replies.flush(&self.pause_srv, r, now),
            self.step_replies.flush(&self.step_srv, r, now),
        ];
        for d in done {
            let Flushed {
                sent,
                sent_unseen,
                failed,
            } = d;
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
        drop(self.node.take());
        if let Some(s) = self.spinner.take() {
            let _ = s.join();
        }
    }
}
