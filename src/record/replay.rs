//! `developable_sim replay BAG`: rebuild the recorded session, apply the recorded
//! commands in recorded order through the same function the node used
//! (`Session::apply`: poses through the same input filter, steps, resets, pauses,
//! parameter changes), and compare every recorded output with the recomputed one bit
//! for bit (`f64::to_bits`: -0.0 and +0.0 differ, and so do NaNs with different bits).
//! A bag recorded by a build whose messages differ (another type hash on a recorded
//! topic, or a recording format before commands were recorded) is refused with the
//! reason. An output the replay produces for a state that the bag lacks is a
//! difference too (except in the last state of a bag cut
//! short, or repaired by `bag reindex` after it was). The same build gives zero
//! difference; otherwise the report names the largest difference per topic and the
//! first differing field, and `developable_sim replay` exits with code 1.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::read::{mcap_files, BagEvent, BagMessage, McapStream, REINDEX_LIBRARY_SUFFIX};
use super::recorder::{RecordedOutput, SessionInfo, SESSION_RECORD};
use super::RecordError;
use crate::camera::Renderer;
use crate::session::camera::{draw_frame, renderer};
use crate::session::command::Names;
use crate::session::input::InputPolicy;
use crate::session::outputs::OutputRow;
use crate::session::{Command, Content, Frame, OutputTable, Scope, Session};
use crate::wire::cdr;
use crate::wire::introspect::{compare, Value};
use crate::wire::msgs::{PoseStamped, RosMessage, SimCommand, StringMsg, TFMessage};

/// Replay settings.
#[derive(Clone, Debug, Default)]
pub struct ReplayOptions {
    /// Simulate this scene file instead of the one stored in the bag.
    pub scene: Option<PathBuf>,
}

/// Comparison of one recorded topic.
#[derive(Clone, Debug, Default, Serialize)]
pub struct TopicReport {
    pub topic: String,
    pub type_name: String,
    /// Recorded messages compared.
    pub compared: u64,
    /// Messages that differ at all (one bit is enough).
    pub differing: u64,
    /// Outputs the replay produced for a state that has none in the bag.
    pub missing: u64,
    /// The first difference: `step <n>: <field path>` (also when its magnitude is 0,
    /// e.g. -0.0 vs +0.0).
    pub first_difference: String,
    /// Largest absolute difference of a numeric field.
    pub max_abs_difference: f64,
    /// Where it was: `step <n>: <field path>`.
    pub max_at: String,
    /// First structural difference (lengths, strings), if any.
    pub structural: Option<String>,
}

/// The result of a replay (`replay --stats OUT.json` writes it).
#[derive(Clone, Debug, Default, Serialize)]
pub struct ReplayReport {
    pub bag: String,
    pub scene: String,
    /// Steps re-simulated.
    pub steps: u64,
    /// Resets replayed.
    pub resets: u64,
    /// Handle poses fed (accepted or not).
    pub inputs: u64,
    pub topics: Vec<TopicReport>,
    /// Largest difference over all topics.
    pub max_abs_difference: f64,
    /// Every recorded output was reproduced bit for bit.
    pub identical: bool,
    /// Why reading stopped early (a bag cut short by a crash), if it did.
    pub truncated: Option<String>,
    /// Wall time of the re-simulation, s.
    pub wall_s: f64,
}

fn topic_entry<'a>(
    per_topic: &'a mut BTreeMap<String, TopicReport>,
    topic: &str,
    type_name: &str,
) -> &'a mut TopicReport {
    per_topic
        .entry(topic.to_string())
        .or_insert_with(|| TopicReport {
            topic: topic.to_string(),
            type_name: type_name.to_string(),
            ..TopicReport::default()
        })
}

/// Replay the bag folder `dir`.
pub fn replay(dir: &Path, options: &ReplayOptions) -> Result<ReplayReport, RecordError> {
    let start = std::time::Instant::now();
    let files = mcap_files(dir)?;
    let mut report = ReplayReport {
        bag: dir.display().to_string(),
        identical: true,
        ..ReplayReport::default()
    };
    let mut replayed: Option<Replayed> = None;
    let mut truncated = false;
    for file in &files {
        let mut stream = McapStream::open(file)?;
        while let Some(event) = stream.next() {
            match event? {
                BagEvent::Metadata { name, values } if name == SESSION_RECORD => {
                    if replayed.is_some() {
                        continue;
                    }
                    replayed = Some(Replayed::start((dir, file), &values, options, &mut report)?);
                }
                BagEvent::Metadata { .. } => {}
                BagEvent::Message(m) => {
                    let Some(r) = replayed.as_mut() else {
                        return Err(bag_error(
                            dir,
                            format!(
                                "{}: a message comes before the {SESSION_RECORD} record: not a \
                                 developable_sim recording",
                                file.display()
                            ),
                        ));
                    };
                    let hash = stream
                        .channel(m.channel)
                        .and_then(|c| c.metadata.get("topic_type_hash"))
                        .map(String::as_str);
                    r.message(dir, &m, hash, &mut report)?;
                }
            }
        }
        if let Some(t) = &stream.truncated {
            report.truncated = Some(format!("{}: {t}", file.display()));
        }
        // cut short now, or before `bag reindex` repaired it
        truncated = stream.truncated.is_some()
            || stream
                .library
                .as_deref()
                .is_some_and(|l| l.ends_with(REINDEX_LIBRARY_SUFFIX));
    }
    let Some(replayed) = replayed else {
        return Err(bag_error(
            dir,
            format!("no {SESSION_RECORD} metadata record: not a developable_sim recording"),
        ));
    };
    report.topics = replayed.finish(truncated);
    report.max_abs_difference = report
        .topics
        .iter()
        .map(|t| t.max_abs_difference)
        .fold(0.0, f64::max);
    // identical means reproduced: a bag with no readable output proves nothing
    let compared: u64 = report.topics.iter().map(|t| t.compared).sum();
    report.identical = compared > 0
        && report
            .topics
            .iter()
            .all(|t| t.differing == 0 && t.missing == 0 && t.structural.is_none());
    report.wall_s = start.elapsed().as_secs_f64();
    Ok(report)
}

/// What a recorded topic is to the replay.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Route {
    /// A handle's poses (commands).
    Input(usize),
    /// A handle's failed TF lookups (commands).
    TfFailure(usize),
    /// The other commands (`~/commands`).
    Commands,
    /// Robot descriptions as received, and the robot links' TF lookups (commands).
    RobotDescription,
    LinkPoses,
    /// A row of the outputs table.
    Output(usize),
}

/// The re-simulated session and its comparison with the bag so far.
struct Replayed {
    session: Session,
    routes: BTreeMap<String, Route>,
    /// The topics whose recorded type was checked against this build's.
    checked: std::collections::BTreeSet<String>,
    /// The replay's messages for the recorded state being compared, and its step.
    frame: Frame,
    frame_step: u64,
    per_topic: BTreeMap<String, TopicReport>,
    /// The rows the bag recorded for the current state.
    seen: std::collections::BTreeSet<usize>,
    /// Recorded under an external clock and no time origin set yet (see
    /// `SessionInfo::waits_for_clock`).
    waiting_for_clock: bool,
    /// Per camera: the frames drawn again (see [`CameraReplay`]).
    cameras: Vec<CameraReplay>,
}

impl Replayed {
    /// The session the bag's SESSION_RECORD `values` describe, at its initial state.
    fn start(
        (dir, file): (&Path, &Path),
        values: &BTreeMap<String, String>,
        options: &ReplayOptions,
        report: &mut ReplayReport,
    ) -> Result<Self, RecordError> {
        let info = SessionInfo::from_record(values)
            .map_err(|m| bag_error(dir, format!("{}: {m}", file.display())))?;
        let (mut session, routes) = start_session(&info, options, report)
            .map_err(|m| bag_error(dir, format!("{}: {m}", file.display())))?;
        let frame = session
            .frame(Content::All)
            .map_err(|e| bag_error(dir, e.to_string()))?;
        let session_cameras = session.scene.cameras.len();
        Ok(Replayed {
            session,
            routes,
            checked: std::collections::BTreeSet::new(),
            frame,
            frame_step: 0,
            per_topic: BTreeMap::new(),
            seen: std::collections::BTreeSet::new(),
            waiting_for_clock: info.waits_for_clock,
            cameras: vec![CameraReplay::default(); session_cameras],
        })
    }

    /// Apply a recorded command, or compare a recorded output; messages on other topics
    /// are skipped.
    fn message(
        &mut self,
        dir: &Path,
        m: &BagMessage,
        type_hash: Option<&str>,
        report: &mut ReplayReport,
    ) -> Result<(), RecordError> {
        let Some(route) = self.routes.get(&m.topic).copied() else {
            return Ok(());
        };
        self.check_type(dir, m, route, type_hash)?;
        let command = match route {
            Route::Input(handle) => Command::Pose {
                handle,
                pose: decode(dir, m)?,
                // the node judged the stamp against the arrival time it recorded as
                // the message's log time
                arrival_ns: m.log_time,
                publish_ns: None,
            },
            Route::TfFailure(handle) => Command::TfLookupFailed {
                handle,
                what: decode::<PoseStamped>(dir, m)?,
                arrival_ns: m.log_time,
            },
            Route::Commands => {
                let msg: SimCommand = decode(dir, m)?;
                let world = &self.session.scene.world;
                let handles: Vec<String> = world.handles().iter().map(|h| h.name.clone()).collect();
                let cameras: Vec<String> = (self.session.scene.cameras.iter())
                    .map(|c| c.name.clone())
                    .collect();
                let names = Names {
                    handles: &handles,
                    objects: world.object_names(),
                    cameras: &cameras,
                };
                Command::from_msg(&msg, &names)
                    .map_err(|e| bag_error(dir, format!("{}: {e}", m.topic)))?
            }
            Route::RobotDescription => {
                let urdf = decode::<StringMsg>(dir, m)?.data;
                // loaded again as the node loaded it (its mesh files read again)
                let loaded = crate::scene::urdf::load_for(&self.session.scene, &urdf);
                Command::RobotDescription {
                    urdf,
                    loaded,
                    arrival_ns: m.log_time,
                }
            }
            Route::LinkPoses => Command::LinkPoses {
                transforms: decode::<TFMessage>(dir, m)?.transforms,
                arrival_ns: m.log_time,
            },
            Route::Output(row) => return self.output(dir, m, row, report),
        };
        if matches!(route, Route::Input(_) | Route::TfFailure(_)) {
            report.inputs += 1;
        }
        self.apply(dir, &command, report)
    }

    /// Apply `command` as the node did; a new state (or the statuses of a pause
    /// toggled) becomes the frame the following outputs are compared with.
    fn apply(
        &mut self,
        dir: &Path,
        command: &Command,
        report: &mut ReplayReport,
    ) -> Result<(), RecordError> {
        let applied = self.session.apply(command);
        match command {
            Command::Step => report.steps += 1,
            Command::Reset | Command::ResetAt { .. } => report.resets += 1,
            _ => {}
        }
        if let Some(frame) = self.session.frame_after(&applied) {
            let frame = frame.map_err(|e| bag_error(dir, e.to_string()))?;
            // under use_sim_time the node publishes nothing before the first /clock
            // sample sets the time origin: what the replay makes before it is not missing
            if self.waiting_for_clock {
                self.seen.extend(0..self.session.table.rows.len());
            }
            if matches!(command, Command::SetTimeOrigin { .. }) {
                self.waiting_for_clock = false;
            }
            self.next_frame(frame);
        }
        Ok(())
    }

    /// `frame` is now the state compared: the outputs the current one produced and the
    /// bag lacks are counted first.
    fn next_frame(&mut self, frame: Frame) {
        self.count_missing();
        self.seen.clear();
        self.frame = frame;
        self.frame_step = self.session.scene.world.steps_taken();
    }

    /// Count, per topic, the outputs the current frame holds that the bag did not record
    /// for its state.
    fn count_missing(&mut self) {
        let step = self.frame_step;
        for (k, row) in self.session.table.rows.iter().enumerate() {
            if self.seen.contains(&k) || self.frame.messages.get(k).is_none_or(|m| m.is_none()) {
                continue;
            }
            let entry = topic_entry(&mut self.per_topic, &row.topic, row.type_name());
            entry.missing += 1;
            if entry.first_difference.is_empty() {
                entry.first_difference =
                    format!("step {step}: produced by the replay, not in the bag");
            }
        }
    }

    /// The recorded type of `m`'s topic is this build's (checked once per topic): a
    /// bag of another build's messages cannot be compared field by field.
    fn check_type(
        &mut self,
        dir: &Path,
        m: &BagMessage,
        route: Route,
        type_hash: Option<&str>,
    ) -> Result<(), RecordError> {
        if self.checked.contains(&m.topic) {
            return Ok(());
        }
        let (want_type, want_hash) = match route {
            Route::Input(_) | Route::TfFailure(_) => (PoseStamped::TYPE, PoseStamped::HASH),
            Route::Commands => (SimCommand::TYPE, SimCommand::HASH),
            Route::RobotDescription => (StringMsg::TYPE, StringMsg::HASH),
            Route::LinkPoses => (TFMessage::TYPE, TFMessage::HASH),
            Route::Output(row) => {
                let p = self.session.table.rows[row].kind.producer;
                (p.type_name(), p.type_hash())
            }
        };
        let hash = type_hash.unwrap_or("");
        if m.type_name != want_type || (!hash.is_empty() && hash != want_hash) {
            return Err(bag_error(
                dir,
                format!(
                    "{}: recorded as {} ({hash}), this build's is {want_type} ({want_hash}): the \
                     bag was recorded by another version of developable_sim; replay it with \
                     that version",
                    m.topic, m.type_name
                ),
            ));
        }
        self.checked.insert(m.topic.clone());
        Ok(())
    }

    /// Compare the recorded output `m` (row `row`) with the replay's for the current
    /// state.
    fn output(
        &mut self,
        dir: &Path,
        m: &BagMessage,
        row: usize,
        _report: &mut ReplayReport,
    ) -> Result<(), RecordError> {
        let kind = self.session.table.rows[row].kind;
        if let Scope::Camera(c) = self.session.table.rows[row].scope {
            return self.camera_output(dir, m, row, c);
        }
        let step = self.frame_step;
        let computed = self.frame.messages.get(row).cloned().flatten();
        let entry = topic_entry(&mut self.per_topic, &m.topic, &m.type_name);
        self.seen.insert(row);
        entry.compared += 1;
        let Some(computed) = computed else {
            entry.differing += 1;
            entry.structural.get_or_insert_with(|| {
                format!("step {step}: recorded but not produced by the replay")
            });
            if entry.first_difference.is_empty() {
                entry.first_difference =
                    format!("step {step}: recorded, not produced by the replay");
            }
            return Ok(());
        };
        if computed[..] == m.data[..] {
            return Ok(());
        }
        let value = |bytes: &[u8]| kind.producer.value(bytes).map_err(|e| bag_error(dir, e));
        let (mut r, mut c) = (value(&m.data)?, value(&computed)?);
        if kind.name == "status" {
            for f in WALL_CLOCK_STATUS_FIELDS {
                r.zero_field(f);
                c.zero_field(f);
            }
        }
        tally(entry, step, &r, &c);
        Ok(())
    }

    /// Compare the recorded output `m` (row `row` of camera `camera`) with the replay's
    /// frame: the current one, or the next captured frame drawn again when this row of
    /// the current one was seen already (a frame's messages are recorded together).
    fn camera_output(
        &mut self,
        dir: &Path,
        m: &BagMessage,
        row: usize,
        camera: usize,
    ) -> Result<(), RecordError> {
        let next = match &self.cameras[camera].current {
            Some(f) => f.seen.contains(&row),
            None => true,
        };
        if next {
            self.count_missing_camera(camera);
            self.cameras[camera].current = self.draw_next(camera)?;
        }
        let kind = self.session.table.rows[row].kind;
        let entry = topic_entry(&mut self.per_topic, &m.topic, &m.type_name);
        entry.compared += 1;
        let Some(current) = self.cameras[camera].current.as_mut() else {
            entry.differing += 1;
            entry
                .structural
                .get_or_insert_with(|| "recorded, no frame captured by the replay".into());
            if entry.first_difference.is_empty() {
                entry.first_difference = "recorded, not captured by the replay".into();
            }
            return Ok(());
        };
        current.seen.insert(row);
        let step = current.step;
        let Some(computed) = current.frame.messages.get(row).cloned().flatten() else {
            entry.differing += 1;
            entry.structural.get_or_insert_with(|| {
                format!("step {step}: recorded but not produced by the replay")
            });
            return Ok(());
        };
        if computed[..] == m.data[..] {
            return Ok(());
        }
        let value = |bytes: &[u8]| kind.producer.value(bytes).map_err(|e| bag_error(dir, e));
        tally(entry, step, &value(&m.data)?, &value(&computed)?);
        Ok(())
    }

    /// The next frame camera `camera` captured, drawn again (when a recorded row carries
    /// pixels) and encoded; None when the replay captured no more.
    fn draw_next(&mut self, camera: usize) -> Result<Option<CameraFrame>, RecordError> {
        let Some(capture) = self.session.cameras.take(camera) else {
            return Ok(None);
        };
        let scene = &self.session.scene;
        let cam = &scene.cameras[camera];
        let r = self.cameras[camera]
            .renderer
            .get_or_insert_with(|| renderer(scene, cam));
        let rows = &self.session.table.rows;
        let frame = draw_frame(r, (cam, scene.source.seed), rows, &capture)?;
        if let Some(s) = capture.snapshot {
            self.session.cameras.recycle(s);
        }
        Ok(Some(CameraFrame {
            frame,
            seen: std::collections::BTreeSet::new(),
            step: capture.step,
        }))
    }

    /// Count, per topic, the messages of camera `camera`'s current frame that the bag
    /// did not record.
    fn count_missing_camera(&mut self, camera: usize) {
        let Some(current) = self.cameras[camera].current.take() else {
            return;
        };
        for (k, row) in self.session.table.rows.iter().enumerate() {
            if current.seen.contains(&k)
                || current.frame.messages.get(k).is_none_or(|m| m.is_none())
            {
                continue;
            }
            let entry = topic_entry(&mut self.per_topic, &row.topic, row.type_name());
            entry.missing += 1;
            if entry.first_difference.is_empty() {
                entry.first_difference =
                    format!("step {}: drawn by the replay, not in the bag", current.step);
            }
        }
    }

    /// The comparison per topic, the last state's missing outputs counted unless the bag
    /// was `truncated` in it (the frames captured but not recorded too: the node
    /// records every frame it captured before it closes the bag).
    fn finish(mut self, truncated: bool) -> Vec<TopicReport> {
        if !truncated && !self.waiting_for_clock {
            self.count_missing();
            for c in 0..self.cameras.len() {
                self.count_missing_camera(c);
                while let Ok(Some(next)) = self.draw_next(c) {
                    self.cameras[c].current = Some(next);
                    self.count_missing_camera(c);
                }
            }
        }
        self.per_topic.into_values().collect()
    }
}

/// A camera's frames in a replay.
#[derive(Clone, Default)]
struct CameraReplay {
    /// Made at the first frame drawn again.
    renderer: Option<Renderer>,
    /// The frame the bag's messages are compared with.
    current: Option<CameraFrame>,
}

/// A camera frame drawn again and the rows of it the bag recorded so far.
#[derive(Clone)]
struct CameraFrame {
    frame: Frame,
    seen: std::collections::BTreeSet<usize>,
    /// Steps taken to the captured state.
    step: u64,
}

/// The CDR payload of the recorded message `m`, decoded.
fn decode<M: serde::de::DeserializeOwned>(dir: &Path, m: &BagMessage) -> Result<M, RecordError> {
    cdr::decode(&m.data)
        .map_err(|e| bag_error(dir, format!("{} message on {}: {e}", m.type_name, m.topic)))
}

fn bag_error(dir: &Path, message: String) -> RecordError {
    RecordError::Bag {
        path: dir.to_path_buf(),
        message,
    }
}

/// The session a bag's description rebuilds (its scene, or the one given in
/// `options`), with the recorded outputs as its table, and where each recorded topic
/// goes.
fn start_session(
    info: &SessionInfo,
    options: &ReplayOptions,
    report: &mut ReplayReport,
) -> Result<(Session, BTreeMap<String, Route>), String> {
    let scene = match &options.scene {
        Some(p) => crate::scene::load(p, &[]),
        None => crate::scene::load_str(&info.scene_yaml, Path::new(&info.scene_file), &[]),
    }
    .map_err(|e| format!("cannot rebuild the scene: {e}"))?;
    report.scene = scene.name.clone();
    let rows = info
        .outputs
        .iter()
        .map(RecordedOutput::row)
        .collect::<Result<Vec<_>, _>>()?;
    check_scopes(&scene, info, &rows)?;
    let policy = InputPolicy {
        frame_id: info.frame_id.clone(),
        accept_empty_frame_id: info.accept_empty_frame_id,
        max_stamp_lead: info.max_stamp_lead,
    };
    let status_topics = if info.status_handle_topics.len() == info.handle_topics.len() {
        info.status_handle_topics.clone()
    } else {
        info.handle_topics.clone()
    };
    let mut routes = BTreeMap::new();
    for (h, t) in info.handle_topics.iter().enumerate() {
        routes.insert(t.clone(), Route::Input(h));
    }
    for (h, t) in info.tf_failure_topics.iter().enumerate() {
        routes.insert(t.clone(), Route::TfFailure(h));
    }
    routes.insert(info.commands_topic.clone(), Route::Commands);
    if let Some(t) = &info.robot_description_topic {
        routes.insert(t.clone(), Route::RobotDescription);
    }
    if let Some(t) = &info.robot_link_poses_topic {
        routes.insert(t.clone(), Route::LinkPoses);
    }
    for (k, r) in rows.iter().enumerate() {
        routes.insert(r.topic.clone(), Route::Output(k));
    }
    let mut s = Session::new(scene, policy, status_topics, OutputTable { rows });
    s.style.line_width = info.line_width;
    s.style.sphere_diameter = info.sphere_diameter;
    s.paused = info.start_paused;
    Ok((s, routes))
}

/// The rebuilt scene has the handles and objects the bag's topics refer to.
fn check_scopes(
    scene: &crate::scene::Scene,
    info: &SessionInfo,
    rows: &[OutputRow],
) -> Result<(), String> {
    let (handles, objects) = (
        scene.world.handles().len(),
        scene.world.object_names().len(),
    );
    let out_of_range = rows.iter().any(|r| match r.scope {
        Scope::Global => false,
        Scope::Object(o) => o >= objects,
        Scope::Handle(h) => h >= handles,
        Scope::ObjectHandle(o, h) => o >= objects || h >= handles,
        Scope::Camera(c) => c >= scene.cameras.len(),
    });
    let recorded_objects = rows.iter().filter(|r| r.kind.name == "status").count();
    if handles != info.handle_topics.len() || out_of_range || recorded_objects != objects {
        return Err(format!(
            "the scene has {handles} handles and {objects} objects, the bag {} and {}",
            info.handle_topics.len(),
            recorded_objects
        ));
    }
    Ok(())
}

/// Count one recorded output `r` against what the replay computed for it, `c`.
fn tally(entry: &mut TopicReport, step: u64, r: &Value, c: &Value) {
    let d = compare(r, c);
    if !d.is_zero() {
        entry.differing += 1;
        if entry.first_difference.is_empty() {
            let at = d.structural.as_deref().unwrap_or(&d.first_path);
            entry.first_difference = format!("step {step}: {at}");
        }
    }
    if d.max_abs > entry.max_abs_difference {
        entry.max_abs_difference = d.max_abs;
        entry.max_at = format!("step {step}: {}", d.max_path);
    }
    if let Some(sd) = d.structural {
        entry
            .structural
            .get_or_insert_with(|| format!("step {step}: {sd}"));
    }
}

/// Status fields that depend on the wall clock or on the node's transport, not on the
/// simulation: not compared.
const WALL_CLOCK_STATUS_FIELDS: &[&str] = &[
    "step_duration",
    "overrun_ticks",
    "dropped_publications",
    "real_time_factor",
];
