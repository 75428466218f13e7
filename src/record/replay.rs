//! `developable_sim replay BAG`: rebuild the recorded simulation, feed it the recorded
//! handle poses in recorded order (through the same input filter), step it whenever
//! the recording stepped (the statuses are the ledger: `step` counts steps since the
//! last reset, `episode` counts resets), and compare every recorded output with the
//! recomputed one bit for bit (`f64::to_bits`: -0.0 and +0.0 differ, and so do NaNs
//! with different bits). An output the replay produces for a state that the bag lacks
//! is a difference too (except in the last state of a bag cut short, or repaired by
//! `bag reindex` after it was). The same build
//! gives zero difference; otherwise the report names the largest difference per topic
//! and the first differing field, and `developable_sim replay` exits with code 1.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::read::{mcap_files, BagEvent, BagMessage, McapStream, REINDEX_LIBRARY_SUFFIX};
use super::recorder::{SessionInfo, SESSION_RECORD};
use super::RecordError;
use crate::ros::cdr;
use crate::ros::input::InputPolicy;
use crate::ros::introspect::{compare, to_value, Value};
use crate::ros::msgs::{Clock, MarkerArray, PoseStamped, RosMessage, SimStatus, SingularPoints};
use crate::ros::session::{Frame, FrameContent, Session};
use crate::sim::StepReport;

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

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Output {
    Clock,
    Markers(usize),
    Singular(usize),
    Status(usize),
    Colliders,
}

impl Output {
    fn type_name(self) -> &'static str {
        match self {
            Output::Clock => Clock::TYPE,
            Output::Markers(_) | Output::Colliders => MarkerArray::TYPE,
            Output::Singular(_) => SingularPoints::TYPE,
            Output::Status(_) => SimStatus::TYPE,
        }
    }

    /// Whether `frame` holds this output.
    fn in_frame(self, frame: &Frame) -> bool {
        match self {
            Output::Clock => true,
            Output::Markers(o) => frame.objects[o].markers.is_some(),
            Output::Singular(o) => frame.objects[o].singular_points.is_some(),
            Output::Status(o) => frame.objects[o].status.is_some(),
            Output::Colliders => frame.colliders.is_some(),
        }
    }
}

/// Count, per topic, the outputs `frame` (the state `step`) holds that the bag did not
/// record for that state (`seen`).
fn count_missing(
    frame: &Frame,
    step: u64,
    routes: &BTreeMap<String, Route>,
    seen: &std::collections::BTreeSet<Output>,
    per_topic: &mut BTreeMap<String, TopicReport>,
) {
    for (topic, route) in routes {
        let Route::Output(out) = *route else { continue };
        if seen.contains(&out) || !out.in_frame(frame) {
            continue;
        }
        let entry = topic_entry(per_topic, topic, out.type_name());
        entry.missing += 1;
        if entry.first_difference.is_empty() {
            entry.first_difference = format!("step {step}: produced by the replay, not in the bag");
        }
    }
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
        for event in stream.by_ref() {
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
                    r.message(dir, &m, &mut report)?;
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
    report.identical = report
        .topics
        .iter()
        .all(|t| t.differing == 0 && t.missing == 0 && t.structural.is_none());
    report.wall_s = start.elapsed().as_secs_f64();
    Ok(report)
}

/// The re-simulated session and its comparison with the bag so far.
struct Replayed {
    session: Session,
    /// What each recorded topic is to the replay.
    routes: BTreeMap<String, Route>,
    /// The outputs the bag recorded (the replay's frames make only these).
    content: FrameContent,
    /// The recorded state being compared: (episode, step).
    current: Option<(u32, u64)>,
    /// The replay's outputs for it.
    frame: Option<Frame>,
    /// The last step's report and its duration, s.
    last_step: Option<(StepReport, f64)>,
    /// Inputs were fed since `frame` was made.
    inputs_since_frame: bool,
    per_topic: BTreeMap<String, TopicReport>,
    /// The outputs recorded for the current state.
    seen: std::collections::BTreeSet<Output>,
}

impl Replayed {
    /// The session the bag's SESSION_RECORD `values` describe (see [`start_session`]).
    fn start(
        (dir, file): (&Path, &Path),
        values: &BTreeMap<String, String>,
        options: &ReplayOptions,
        report: &mut ReplayReport,
    ) -> Result<Self, RecordError> {
        let mut routes = BTreeMap::new();
        let mut content = FrameContent {
            markers: false,
            singular_points: false,
            status: true,
        };
        let (session, _info) = start_session(
            (dir, file),
            values,
            options,
            report,
            (&mut routes, &mut content),
        )?;
        Ok(Replayed {
            session,
            routes,
            content,
            current: None,
            frame: None,
            last_step: None,
            inputs_since_frame: false,
            per_topic: BTreeMap::new(),
            seen: std::collections::BTreeSet::new(),
        })
    }

    /// Feed a recorded input to the session, or compare a recorded output; messages on
    /// other topics are skipped.
    fn message(
        &mut self,
        dir: &Path,
        m: &BagMessage,
        report: &mut ReplayReport,
    ) -> Result<(), RecordError> {
        let Some(route) = self.routes.get(&m.topic).copied() else {
            return Ok(());
        };
        match route {
            Route::Input(h) => {
                let pose: PoseStamped = decode(dir, m)?;
                // the node judged the stamp against the arrival time it recorded as the
                // message's log time
                let _ = self.session.offer(h, &pose, m.log_time);
                report.inputs += 1;
                self.inputs_since_frame = true;
            }
            Route::TfFailure(h) => {
                // the node looked the handle's frame up and found no transform
                let _: PoseStamped = decode(dir, m)?;
                self.session.reject_tf(h);
                report.inputs += 1;
                self.inputs_since_frame = true;
            }
            Route::Output(out) => self.output(dir, m, out, report)?,
        }
        Ok(())
    }

    /// Compare the recorded output `m` with the replay's for the current state.
    fn output(
        &mut self,
        dir: &Path,
        m: &BagMessage,
        out: Output,
        report: &mut ReplayReport,
    ) -> Result<(), RecordError> {
        let recorded = match out {
            Output::Clock => to_value(&decode::<Clock>(dir, m)?),
            Output::Markers(_) | Output::Colliders => to_value(&decode::<MarkerArray>(dir, m)?),
            Output::Singular(_) => to_value(&decode::<SingularPoints>(dir, m)?),
            Output::Status(_) => {
                let st: SimStatus = decode(dir, m)?;
                self.status(dir, &m.topic, &st, report)?;
                to_value(&st)
            }
        }
        .map_err(|e| bag_error(dir, e.to_string()))?;
        let Some(f) = &self.frame else {
            return Err(bag_error(
                dir,
                format!("{}: output before the first status", m.topic),
            ));
        };
        let computed = match out {
            Output::Clock => Some(to_value(&f.clock)),
            Output::Markers(o) => f.objects[o].markers.as_ref().map(to_value),
            Output::Singular(o) => f.objects[o].singular_points.as_ref().map(to_value),
            Output::Status(o) => f.objects[o].status.as_ref().map(to_value),
            Output::Colliders => f.colliders.as_ref().map(to_value),
        }
        .transpose()
        .map_err(|e| bag_error(dir, e.to_string()))?;
        self.seen.insert(out);
        let entry = topic_entry(&mut self.per_topic, &m.topic, &m.type_name);
        let step = self.current.map(|c| c.1).unwrap_or(0);
        tally(entry, step, out, recorded, computed);
        Ok(())
    }

    /// A status names the recorded state it belongs to: a new state closes the current
    /// one (counting the outputs the bag lacks) and brings the session to it; the same
    /// state published again (pause toggled) carries the inputs taken since its frame.
    fn status(
        &mut self,
        dir: &Path,
        topic: &str,
        st: &SimStatus,
        report: &mut ReplayReport,
    ) -> Result<(), RecordError> {
        let key = (st.episode, st.step);
        if self.current != Some(key) {
            if let (Some(f), Some((_, step))) = (&self.frame, self.current) {
                count_missing(f, step, &self.routes, &self.seen, &mut self.per_topic);
            }
            self.seen.clear();
            advance(
                &mut self.session,
                self.current,
                key,
                self.content,
                &mut self.frame,
                &mut self.last_step,
                report,
            )
            .map_err(|e| bag_error(dir, format!("{topic} at {}: {e}", key.1)))?;
            self.current = Some(key);
            self.inputs_since_frame = false;
        } else if self.inputs_since_frame {
            // the same state published again (pause toggled):
            // its status carries the inputs taken since
            self.frame = Some(self.session.frame(
                self.last_step.as_ref().map(|(r, _)| r),
                self.last_step.as_ref().map_or(0.0, |(_, d)| *d),
                self.content,
            ));
            self.inputs_since_frame = false;
        }
        Ok(())
    }

    /// The comparison per topic, the last state's missing outputs counted unless the bag
    /// was `truncated` in it.
    fn finish(mut self, truncated: bool) -> Vec<TopicReport> {
        if let (Some(f), Some((_, step)), false) = (&self.frame, self.current, truncated) {
            count_missing(f, step, &self.routes, &self.seen, &mut self.per_topic);
        }
        self.per_topic.into_values().collect()
    }
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

/// The session a bag's SESSION_RECORD describes: its scene rebuilt (or the one given in
/// `options`), the topics routed to inputs and outputs, the outputs it recorded.
fn start_session(
    (dir, file): (&Path, &Path),
    values: &BTreeMap<String, String>,
    options: &ReplayOptions,
    report: &mut ReplayReport,
    (routes, content): (&mut BTreeMap<String, Route>, &mut FrameContent),
) -> Result<(Session, SessionInfo), RecordError> {
    let i = SessionInfo::from_record(values)
        .map_err(|m| bag_error(dir, format!("{}: {m}", file.display())))?;
    let scene = match &options.scene {
        Some(p) => crate::scene::load(p, &[]),
        None => crate::scene::load_str(&i.scene_yaml, Path::new(&i.scene_file), &[]),
    }
    .map_err(|e| bag_error(dir, format!("cannot rebuild the scene: {e}")))?;
    report.scene = scene.name.clone();
    if scene.world.handles().len() != i.handle_topics.len()
        || scene.world.object_names().len() != i.object_topics.len()
    {
        return Err(bag_error(
            dir,
            format!(
                "the scene has {} handles and {} objects, the bag {} and {}",
                scene.world.handles().len(),
                scene.world.object_names().len(),
                i.handle_topics.len(),
                i.object_topics.len()
            ),
        ));
    }
    let policy = InputPolicy {
        frame_id: i.frame_id.clone(),
        accept_empty_frame_id: i.accept_empty_frame_id,
        max_stamp_lead: i.max_stamp_lead,
    };
    let status_topics = if i.status_handle_topics.len() == i.handle_topics.len() {
        i.status_handle_topics.clone()
    } else {
        i.handle_topics.clone()
    };
    let mut s = Session::new(scene, policy, status_topics);
    s.style.line_width = i.line_width;
    s.style.sphere_diameter = i.sphere_diameter;
    for (h, t) in i.handle_topics.iter().enumerate() {
        routes.insert(t.clone(), Route::Input(h));
    }
    for (h, t) in i.tf_failure_topics.iter().enumerate() {
        routes.insert(t.clone(), Route::TfFailure(h));
    }
    if let Some(c) = &i.clock_topic {
        routes.insert(c.clone(), Route::Output(Output::Clock));
    }
    if let Some(c) = &i.colliders_topic {
        content.markers = true;
        routes.insert(c.clone(), Route::Output(Output::Colliders));
    }
    for (o, (m, sp, st)) in i.object_topics.iter().enumerate() {
        if let Some(m) = m {
            content.markers = true;
            routes.insert(m.clone(), Route::Output(Output::Markers(o)));
        }
        if let Some(sp) = sp {
            content.singular_points = true;
            routes.insert(sp.clone(), Route::Output(Output::Singular(o)));
        }
        routes.insert(st.clone(), Route::Output(Output::Status(o)));
    }
    Ok((s, i))
}

/// Count one recorded output against what the replay computed for it.
fn tally(
    entry: &mut TopicReport,
    step: u64,
    out: Output,
    recorded: Value,
    computed: Option<Value>,
) {
    entry.compared += 1;
    match computed {
        None => {
            entry.differing += 1;
            entry.structural.get_or_insert_with(|| {
                format!("step {step}: recorded but not produced by the replay")
            });
            if entry.first_difference.is_empty() {
                entry.first_difference =
                    format!("step {step}: recorded, not produced by the replay");
            }
        }
        Some(mut c) => {
            let mut r = recorded;
            if matches!(out, Output::Status(_)) {
                for f in WALL_CLOCK_STATUS_FIELDS {
                    r.zero_field(f);
                    c.zero_field(f);
                }
            }
            let d = compare(&r, &c);
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
    }
}

/// Status fields that depend on the wall clock or on the node's run state, not on the
/// simulation: not compared.
const WALL_CLOCK_STATUS_FIELDS: &[&str] = &[
    "step_duration",
    "overrun_ticks",
    "dropped_publications",
    "paused",
];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Route {
    Input(usize),
    /// A failed TF lookup of this handle.
    TfFailure(usize),
    Output(Output),
}

/// Bring the session to the recorded state `key` = (episode, step).
fn advance(
    s: &mut Session,
    current: Option<(u32, u64)>,
    key: (u32, u64),
    content: FrameContent,
    frame: &mut Option<Frame>,
    last_step: &mut Option<(StepReport, f64)>,
    report: &mut ReplayReport,
) -> Result<(), String> {
    let (episode, step) = key;
    match current {
        None if step == 0 => {
            *frame = Some(s.frame(None, 0.0, content));
        }
        None => {
            return Err(format!(
                "the recording starts at step {step}, not at the initial state"
            ))
        }
        Some((cur_episode, cur_step)) => {
            if step == 0 && episode > cur_episode {
                s.reset();
                while s.episode < episode {
                    s.episode += 1;
                }
                report.resets += 1;
                *last_step = None;
                *frame = Some(s.frame(None, 0.0, content));
            } else if episode == cur_episode && step == cur_step + 1 {
                let (r, d) = s.step();
                report.steps += 1;
                *frame = Some(s.frame(Some(&r), d, content));
                *last_step = Some((r, d));
            } else {
                return Err(format!(
                    "status (episode {episode}, step {step}) follows (episode {cur_episode}, step \
                     {cur_step}): messages are missing from the bag"
                ));
            }
        }
    }
    Ok(())
}
