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

use ros2_client::dds::rustdds::mio1::{Events, Waker};

use ros2_client::dds::rustdds::Timestamp;

use crate::foxglove::{FoxgloveConfig, FoxgloveOut};
use crate::record::bag::BagOptions;
use crate::record::recorder::SessionRecorder;
pub use crate::ros::dds::NodeError;
use crate::ros::dds::{sent, RawCdr};
use crate::ros::node_stats::DropLog;
pub use crate::ros::node_stats::NodeStats;
use crate::ros::param_server::ParamTable;
use crate::scene::Scene;
use crate::session::input::InputPolicy;
use crate::session::names::NodeNames;
use crate::session::params::{ParamValue, Params};
use crate::session::{
    Applied, Command, Content, Frame, MarkerStyle, OutputTable, RunOutputs, Session,
};
use crate::sim::ReachWatch;

mod camera;
mod control;
mod drawing;
mod endpoints;
mod grasp;
mod inputs;
mod latency;
mod realtime;
mod robot;
mod sim_state;
mod simulate_steps;
mod simulation;

use drawing::CameraThreads;
use endpoints::Endpoints;
use latency::Latency;
use realtime::{RealTimeWatch, Target};
use sim_state::SimInterfaces;

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
    /// s, under use_sim_time: a larger jump of the clock moves the time origin.
    pub max_clock_jump: f64,
    /// The parameters as read (the parameter services report them; the node's own
    /// settings above win where they differ).
    pub params: Params,
    /// The live Foxglove WebSocket server (None: off).
    pub foxglove: Option<FoxgloveConfig>,
}

/// Under use_sim_time, at most this many catch-up steps run between two polls (inputs
/// and services stay served while the node catches up with a clock far ahead).
const CATCH_UP_BATCH: usize = 100;
/// ... and for at most this much wall time.
const CATCH_UP_WALL: Duration = Duration::from_millis(100);

/// The running node.
pub struct SimNode {
    /// Every DDS entity (first: dropped first).
    io: Endpoints,
    /// (handle index, TF frame) of the handles that follow TF frames.
    tf_handles: Vec<(usize, String)>,
    /// Per TF handle: whether its last lookup failed (said once, and when it recovers).
    tf_failing: Vec<bool>,
    /// The robot links' TF frames whose last lookup failed (said once each).
    robot_failing: std::collections::BTreeSet<String>,
    /// s of simulated time between two published markers (None: every tick), and when
    /// the last went out.
    markers_period: Option<f64>,
    last_markers: Option<f64>,
    /// The same outputs to Foxglove WebSocket clients (`--foxglove PORT`).
    foxglove: Option<FoxgloveOut>,
    /// The parameters as the parameter services report them.
    params: ParamTable,
    session: Session,
    recorder: Option<SessionRecorder>,
    cfg_duration: Option<f64>,
    pacing: Pacing,
    lockstep: Lockstep,
    names: NodeNames,
    // state
    /// Says when a handle target goes out of reach and when it is reached again.
    reach: ReachWatch,
    /// When each handle's last accepted pose arrived (until markers go out).
    pending_input: Vec<Option<Instant>>,
    stats: NodeStats,
    /// Which topics' dropped publications were already said in this episode.
    drop_log: DropLog,
    latency: Latency,
    /// The real-time factor and the slow / back-to-real-time lines.
    realtime: RealTimeWatch,
    /// The simulation_interfaces services' state (stopped, quitting, pending steps).
    sim_if: SimInterfaces,
    /// The cameras' drawing threads, and each frame's drawing time, ms.
    cameras: CameraThreads,
    camera_draw_ms: Vec<f64>,
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

/// The Foxglove server for `cfg.foxglove`, advertising what the node publishes.
fn start_foxglove(
    cfg: &NodeConfig,
    outputs: &OutputTable,
) -> Result<Option<FoxgloveOut>, NodeError> {
    let Some(f) = &cfg.foxglove else {
        return Ok(None);
    };
    let out = FoxgloveOut::start(f, &cfg.names, outputs)?;
    eprintln!(
        "[developable_sim] Foxglove: open ws://{}:{} in Foxglove",
        f.bind,
        out.port()
    );
    Ok(Some(out))
}

/// What the node's settings decide about outputs beyond the scene file.
pub fn run_outputs(cfg: &NodeConfig) -> RunOutputs {
    RunOutputs {
        own_clock: !cfg.use_sim_time,
        recording: cfg.record.is_some(),
        record_cameras: cfg.record.as_ref().is_some_and(|(_, o)| o.record_cameras),
    }
}

/// The statistics' run mode, e.g. `real_time x1`, `lockstep:service`.
fn mode_name(lockstep: &Lockstep, pacing: Pacing, names: &NodeNames) -> String {
    match (lockstep, pacing) {
        (Lockstep::Service, _) => "lockstep:service".into(),
        (Lockstep::Handle(h), _) => format!("lockstep:{}", names.handles[*h]),
        (Lockstep::Off, Pacing::AsFastAsPossible) => "as_fast_as_possible".into(),
        (Lockstep::Off, Pacing::RealTime { factor }) => format!("real_time x{factor}"),
    }
}

/// The parameter table with the values in effect (flags and the scene may have set
/// them); returns it with the markers' rate, Hz (0: every tick).
fn param_table(cfg: &NodeConfig) -> (ParamTable, f64) {
    let mut params = ParamTable::new(&cfg.params);
    let markers_rate = match cfg.params.double("markers_rate") {
        Some(r) => r,
        None => cfg.scene.outputs.markers_rate.unwrap_or(0.0),
    };
    params.store("markers_rate", ParamValue::Double(markers_rate));
    params.store("paused", ParamValue::Bool(cfg.start_paused));
    params.store("start_paused", ParamValue::Bool(cfg.start_paused));
    params.store("use_sim_time", ParamValue::Bool(cfg.use_sim_time));
    params.store("tf_max_lag", ParamValue::Double(cfg.tf_max_lag));
    params.store("max_clock_jump", ParamValue::Double(cfg.max_clock_jump));
    if let Pacing::RealTime { factor } = cfg.pacing {
        params.store("real_time_factor", ParamValue::Double(factor));
    }
    (params, markers_rate)
}

impl SimNode {
    /// Join the DDS domain and create every topic, service and the bag.
    pub fn new(cfg: NodeConfig) -> Result<SimNode, NodeError> {
        lockstep_needs_a_pose_topic(&cfg)?;
        let tf_handles: Vec<(usize, String)> = cfg
            .scene
            .handle_tf_frames
            .iter()
            .enumerate()
            .filter_map(|(i, f)| f.clone().map(|f| (i, f)))
            .collect();
        // the outputs the scene and the node's settings ask for; recorded-only rows
        // (statuses not published) only when recording
        let run = run_outputs(&cfg);
        let table = OutputTable::for_scene(&cfg.scene, &cfg.names, run)
            .map_err(|e| NodeError::Config(e.to_string()))?;
        let tf_cameras = cfg
            .scene
            .cameras
            .iter()
            .any(|c| matches!(c.mount, crate::scene::CameraMount::TfFrame(_)));
        let io = Endpoints::open(
            cfg.domain_id,
            &cfg.names,
            &table,
            (cfg.use_sim_time, cfg.tf_max_lag, cfg.max_clock_jump),
            (&tf_handles, tf_cameras),
        )?;
        let cameras = CameraThreads::start(&cfg.scene, &table.rows, &io.waker)?;
        let (params, markers_rate) = param_table(&cfg);
        let foxglove = start_foxglove(&cfg, &table)?;
        let names = cfg.names;
        let mut handle_topics = names.handles.clone();
        for (h, _) in &tf_handles {
            handle_topics[*h] = names.tf.clone();
        }
        let mut session = Session::new(cfg.scene, cfg.policy, handle_topics, table);
        session.style = cfg.style;
        session.paused = cfg.start_paused;
        let recorder = match &cfg.record {
            Some((dir, options)) => Some(SessionRecorder::create(
                dir,
                options.clone(),
                &session,
                &names,
            )?),
            None => None,
        };
        let stats = NodeStats {
            scene: session.scene.name.clone(),
            mode: mode_name(&cfg.lockstep, cfg.pacing, &names),
            dt: session.scene.world.dt(),
            ..NodeStats::default()
        };
        Ok(SimNode {
            io,
            tf_failing: vec![false; tf_handles.len()],
            robot_failing: Default::default(),
            tf_handles,
            markers_period: (markers_rate > 0.0).then(|| 1.0 / markers_rate),
            last_markers: None,
            foxglove,
            params,
            session,
            recorder,
            cfg_duration: cfg.duration,
            pacing: cfg.pacing,
            lockstep: cfg.lockstep,
            pending_input: vec![None; names.handles.len()],
            names,
            reach: ReachWatch::default(),
            stats,
            drop_log: DropLog::default(),
            latency: Latency::new(),
            realtime: RealTimeWatch::default(),
            sim_if: SimInterfaces::default(),
            cameras,
            camera_draw_ms: Vec::new(),
        })
    }

    /// Wakes the loop (for a signal handler: set the stop flag, then wake).
    pub fn waker(&self) -> Arc<Waker> {
        Arc::clone(&self.io.waker)
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
        self.latency.start();
        self.realtime.restart(Instant::now());
        // under use_sim_time the first /clock sample sets the time: nothing goes out
        // before it (see `emit`)
        self.emit_current(Content::All, None);
        self.capture_cameras();
        let mut next_tick = Instant::now() + self.period();
        let mut events = Events::with_capacity(64);
        // under use_sim_time the external clock drives the steps
        let free_running = self.lockstep == Lockstep::Off && self.io.clock_in.is_none();
        let mut behind_clock = false;
        while !stop.load(Ordering::SeqCst) && !self.done() && !self.sim_if.quitting {
            let now = Instant::now();
            let timeout = if behind_clock || self.sim_if.busy() {
                Duration::ZERO
            } else if free_running && !self.session.paused {
                next_tick.saturating_duration_since(now)
            } else {
                Duration::from_millis(200)
            };
            // held service replies are re-checked every RECHECK
            let timeout = if self.replies_waiting() {
                timeout.min(crate::ros::reply::RECHECK)
            } else {
                timeout
            };
            if let Err(e) = self.io.poll.poll(&mut events, Some(timeout)) {
                if e.kind() != std::io::ErrorKind::Interrupted {
                    return Err(e.into());
                }
            }
            // edge-triggered sources: drain all of them whatever woke us
            self.drain_graph();
            self.drain_robot_description();
            self.drain_inputs();
            self.drain_services(&mut next_tick);
            self.drain_cameras();
            if stop.load(Ordering::SeqCst) || self.done() {
                break;
            }
            if self.lockstep == Lockstep::Off {
                behind_clock = self.follow_clock();
            }
            self.advance_step_requests();
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
                    self.session.counters.overrun_ticks += missed;
                    next_tick += period * missed as u32;
                }
                if period == Duration::ZERO {
                    next_tick = after;
                }
            }
            self.latency.roll_window(&mut self.stats, false);
        }
        self.latency.roll_window(&mut self.stats, true);
        if self.sim_if.quitting {
            eprintln!("[developable_sim] SetSimulationState STATE_QUITTING: stopping");
        }
        Ok(self.finish())
    }

    /// Record `command`, apply it to the session and publish what it produced: the
    /// one path of every external action (see `session::command`). `trigger`: when the
    /// tick started or the input that caused it arrived (latency).
    fn command(&mut self, command: Command, trigger: Option<Instant>) -> Applied {
        let stamp = self.session.stamp();
        self.record(|r| r.record_command(&command, stamp));
        let applied = self.session.apply(&command);
        if command == Command::Step {
            self.after_step();
        }
        match self.session.frame_after(&applied) {
            Some(Ok(frame)) => self.emit(&frame, trigger),
            Some(Err(e)) => self.encode_failed(&e),
            None => {}
        }
        // the first /clock sample republishes the state at t = 0: its camera tick is
        // captured then (see `capture_cameras`)
        if matches!(applied, Applied::NewState | Applied::TimeOrigin) {
            self.capture_cameras();
        }
        applied
    }

    /// Statistics, the real-time factor and the reach messages of the step just taken.
    fn after_step(&mut self) {
        self.stats.steps += 1;
        if let Some((_, step_s)) = self.session.last_step() {
            let dt = self.session.scene.world.dt();
            self.realtime.step(Instant::now(), dt, *step_s);
            self.session.counters.real_time_factor = self.realtime.factor();
            let target = self.realtime_target();
            if let Some(line) = self.realtime.judge(Instant::now(), target) {
                eprintln!("[developable_sim] {line}");
            }
        }
        if let Some((report, step_s)) = self.session.last_step() {
            self.latency.step(*step_s);
            let world = &self.session.scene.world;
            for m in self
                .reach
                .update(report, world.object_names(), world.handles())
            {
                eprintln!("[developable_sim] {m}");
            }
        }
    }

    /// What the real-time factor is judged against (see `realtime`).
    fn realtime_target(&self) -> Target {
        if self.session.paused || self.lockstep != Lockstep::Off {
            return Target::None;
        }
        if self.io.clock_in.is_some() {
            return Target::Clock {
                dt: self.session.scene.world.dt(),
            };
        }
        match self.pacing {
            Pacing::RealTime { factor } => Target::Factor {
                factor,
                period: self.period(),
            },
            Pacing::AsFastAsPossible => Target::None,
        }
    }

    /// Under use_sim_time, before the first /clock sample: no time yet, so nothing is
    /// published or recorded (a status stamped 0 would be in no one's time base).
    pub(super) fn waiting_for_clock(&self) -> bool {
        self.io
            .clock_in
            .as_ref()
            .is_some_and(|c| c.now_ns().is_none())
    }

    /// One step now; `trigger` is when the tick started or the lock-step input came.
    fn tick(&mut self, trigger: Instant) {
        self.offer_tf_targets();
        self.offer_link_poses();
        self.command(Command::Step, Some(trigger));
    }

    /// Publish the current state's `content` (start-up).
    fn emit_current(&mut self, content: Content, trigger: Option<Instant>) {
        match self.session.frame(content) {
            Ok(frame) => self.emit(&frame, trigger),
            Err(e) => self.encode_failed(&e),
        }
    }

    /// A message of ours that CDR cannot encode is a bug: said, counted as dropped.
    fn encode_failed(&mut self, e: &crate::wire::cdr::CdrError) {
        eprintln!("[developable_sim] error: a frame could not be encoded: {e}");
        self.note_dropped(vec![("(frame)".into(), e.to_string())]);
    }

    /// Publish a frame (every published row; the markers only when due), send it to
    /// Foxglove, then record it.
    fn emit(&mut self, frame: &Frame, trigger: Option<Instant>) {
        if self.waiting_for_clock() {
            return;
        }
        let t = self.session.scene.world.time();
        let markers_due = match (self.markers_period, self.last_markers) {
            (Some(period), Some(last)) => t - last >= period - 0.5 * self.session.scene.world.dt(),
            _ => true,
        };
        // (topic, why) of every publication that failed
        let mut failed: Vec<(String, String)> = Vec::new();
        let rows = &self.session.table.rows;
        let mut markers_sent = false;
        for ((row, msg), publisher) in rows.iter().zip(&frame.messages).zip(&self.io.pubs) {
            let (Some(msg), Some(publisher)) = (msg, publisher) else {
                continue;
            };
            if row.kind.throttled {
                if !markers_due {
                    continue;
                }
                markers_sent = true;
            }
            let written = publisher.write(RawCdr(msg.clone()), Some(Timestamp::now()));
            if let Err(e) = sent(written) {
                failed.push((row.topic.clone(), e));
            }
        }
        if markers_sent {
            self.last_markers = Some(t);
        }
        if let Some(t) = trigger {
            let inputs = self.pending_input.iter_mut().filter_map(|p| p.take());
            self.latency.published(Instant::now(), t, inputs);
        }
        self.note_dropped(failed);
        if let Some(f) = self.foxglove.as_mut() {
            f.emit(&self.session.table, frame, markers_due);
        }
        self.record(|r| r.record_frame(frame));
    }

    /// Counts failed publications (`SimStatus.dropped_publications` from the next
    /// frame on, `--stats`) and says the first one per topic and episode on stderr.
    fn note_dropped(&mut self, failed: Vec<(String, String)>) {
        self.stats.dropped_publications += failed.len() as u64;
        self.session.counters.dropped_publications += failed.len() as u64;
        let episode = self.session.counters.episode;
        for (topic, why) in failed {
            if self.drop_log.first(&topic, episode) {
                eprintln!(
                    "[developable_sim] warning: a publication on {topic} was dropped ({why}); \
                     further drops on {topic} in this episode are only counted \
                     (SimStatus dropped_publications)"
                );
            }
        }
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

    fn finish(mut self) -> NodeStats {
        // replies still held for clients not yet discovered get a short grace
        let grace = Instant::now() + Duration::from_millis(250);
        while self.replies_waiting() && Instant::now() < grace {
            std::thread::sleep(crate::ros::reply::RECHECK);
            self.flush_replies();
        }
        self.finish_cameras();
        let mut stats = std::mem::take(&mut self.stats);
        stats.camera_frames_skipped = self.session.counters.camera_frames_skipped;
        stats.camera_draw = crate::ros::node_stats::LatencyStats::of(&self.camera_draw_ms);
        stats.sim_time = self.session.scene.world.time();
        self.latency.finish(&mut stats);
        stats.overrun_ticks = self.session.counters.overrun_ticks;
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
