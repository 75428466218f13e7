//! What a session records and in which order.
//!
//! A bag holds the commands the node applied, in order, and the frames they produced.
//! Commands: every handle pose as received, on the handle's topic (rejected ones
//! included: replay runs them through the same filter), a handle's failed TF lookups on
//! `<handle topic>/tf_lookup_failed`, a robot description as received on its topic and
//! the robot links' TF lookups on `~/robot_link_poses` (`robot_colliders:`), and every
//! other command (steps, resets, pauses, parameter changes) as a
//! `developable_sim/msg/SimCommand` on `~/commands`. Frames:
//! every recorded row of the session's outputs table (each object's status even when
//! the scene does not publish it), statuses first. A `developable_sim` MCAP metadata
//! record at the start holds the scene (YAML after overrides), the input policy and the
//! recorded outputs, so `replay` rebuilds the same session.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::bag::{BagOptions, BagWriter, TopicId};
use super::metadata::Qos;
use super::RecordError;
use crate::camera::Renderer;
use crate::runner::StepObserver;
use crate::scene::Scene;
use crate::session::camera::{draw_frame, fixed_pose, renderer};
use crate::session::command::Names;
use crate::session::input::InputPolicy;
use crate::session::names::NodeNames;
use crate::session::outputs::{kind_named, OutputRow, Want};
use crate::session::{Command, Content, Frame, OutputTable, RunOutputs, Scope, Session};
use crate::sim::StepReport;
use crate::wire::clock::now_ns;
use crate::wire::msgs::{PoseStamped, SimCommand, StringMsg, TFMessage, Time};

fn default_max_stamp_lead() -> f64 {
    crate::session::input::DEFAULT_MAX_STAMP_LEAD
}

/// Name of the MCAP metadata record describing the session.
pub const SESSION_RECORD: &str = "developable_sim";

/// The recording format this build writes and reads: 2 records the commands
/// (`~/commands`) and the outputs table; 1 (before 2026-12-07) had neither.
pub const FORMAT: u32 = 2;

/// One recorded output: its kind (`session::outputs::OUTPUTS` names), scope and topic.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecordedOutput {
    pub kind: String,
    /// `global`, `object`, `handle`, `object_handle` or `camera`.
    pub scope: String,
    /// The object's or handle's index (0 for global; the object's for object_handle).
    #[serde(default)]
    pub index: usize,
    /// The handle's index of an `object_handle` output.
    #[serde(default)]
    pub handle: usize,
    pub topic: String,
}

impl RecordedOutput {
    fn of(row: &OutputRow) -> RecordedOutput {
        let (scope, index, handle) = match row.scope {
            Scope::Global => ("global", 0, 0),
            Scope::Object(o) => ("object", o, 0),
            Scope::Handle(h) => ("handle", h, 0),
            Scope::ObjectHandle(o, h) => ("object_handle", o, h),
            Scope::Camera(c) => ("camera", c, 0),
        };
        RecordedOutput {
            kind: row.kind.name.to_string(),
            scope: scope.to_string(),
            index,
            handle,
            topic: row.topic.clone(),
        }
    }

    /// The row this output is in a replay (recorded, not published).
    pub fn row(&self) -> Result<OutputRow, String> {
        let kind =
            kind_named(&self.kind).ok_or_else(|| format!("unknown output `{}`", self.kind))?;
        let scope = match self.scope.as_str() {
            "global" => Scope::Global,
            "object" => Scope::Object(self.index),
            "handle" => Scope::Handle(self.index),
            "object_handle" => Scope::ObjectHandle(self.index, self.handle),
            "camera" => Scope::Camera(self.index),
            s => return Err(format!("unknown scope `{s}` of output `{}`", self.kind)),
        };
        Ok(OutputRow {
            kind,
            scope,
            topic: self.topic.clone(),
            want: Want {
                published: false,
                recorded: true,
            },
        })
    }
}

/// The session description stored in the bag (values of the metadata record).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionInfo {
    pub scene_name: String,
    pub scene_file: String,
    /// The scene as parsed after overrides (YAML).
    pub scene_yaml: String,
    pub frame_id: String,
    pub accept_empty_frame_id: bool,
    /// s; bags recorded before it existed replay with the default.
    #[serde(default = "default_max_stamp_lead")]
    pub max_stamp_lead: f64,
    pub line_width: f64,
    pub sphere_diameter: f64,
    pub handle_topics: Vec<String>,
    /// Per handle: the input topic its status reports (`/tf` for a TF-driven handle);
    /// bags from before it existed: `handle_topics`.
    #[serde(default)]
    pub status_handle_topics: Vec<String>,
    /// Per handle: the bag topic of its failed TF lookups (see
    /// [`SessionRecorder::record_command`]); bags from before it existed have none.
    #[serde(default)]
    pub tf_failure_topics: Vec<String>,
    /// The commands' topic.
    pub commands_topic: String,
    /// With `robot_colliders:`: the robot descriptions' topic (std_msgs/msg/String, as
    /// received) and the bag topic of the links' TF lookups (tf2_msgs/msg/TFMessage,
    /// see [`Command::LinkPoses`]).
    #[serde(default)]
    pub robot_description_topic: Option<String>,
    #[serde(default)]
    pub robot_link_poses_topic: Option<String>,
    /// Whether the session started paused.
    pub start_paused: bool,
    /// The recorded rows of the outputs table, in the session's order.
    pub outputs: Vec<RecordedOutput>,
    /// The node followed an external `/clock` (use_sim_time, no `/clock` row): it
    /// published nothing before the first clock sample set the time origin.
    #[serde(default)]
    pub waits_for_clock: bool,
}

/// The bag topic of a handle's failed TF lookups: beside its input topic, so it reads as
/// "what became of that handle's input".
fn tf_failure_topic(handle_topic: &str) -> String {
    format!("{handle_topic}/tf_lookup_failed")
}

impl SessionInfo {
    fn to_record(&self) -> BTreeMap<String, String> {
        let mut m = BTreeMap::new();
        m.insert("format".into(), FORMAT.to_string());
        m.insert("version".into(), env!("CARGO_PKG_VERSION").into());
        m.insert("scene_name".into(), self.scene_name.clone());
        m.insert(
            "session".into(),
            serde_json::to_string(self).unwrap_or_default(),
        );
        m
    }

    /// The description, from a recording of this build's format.
    pub fn from_record(values: &BTreeMap<String, String>) -> Result<SessionInfo, String> {
        let json = values
            .get("session")
            .ok_or("the developable_sim record has no `session` entry")?;
        let format = match values.get("format") {
            Some(f) => f
                .parse::<u32>()
                .map_err(|_| format!("unreadable recording format `{f}`"))?,
            None => 1,
        };
        if format != FORMAT {
            return Err(format!(
                "recording format {format}, this build reads format {FORMAT} (format 1, before \
                 2026-12-07, recorded no commands): replay it with the developable_sim that \
                 recorded it"
            ));
        }
        serde_json::from_str(json).map_err(|e| format!("unreadable session description: {e}"))
    }

    /// The session `session` (its scene, policy, style and recorded outputs) as a bag
    /// describes it; `names`: the node's resolved names.
    fn of(session: &Session, names: &NodeNames, dir: &Path) -> Result<SessionInfo, RecordError> {
        let scene = &session.scene;
        Ok(SessionInfo {
            scene_name: scene.name.clone(),
            scene_file: scene.file.display().to_string(),
            scene_yaml: serde_yaml::to_string(&scene.source).map_err(|e| RecordError::Bag {
                path: dir.to_path_buf(),
                message: format!("cannot serialize the scene: {e}"),
            })?,
            frame_id: session.policy.frame_id.clone(),
            accept_empty_frame_id: session.policy.accept_empty_frame_id,
            max_stamp_lead: session.policy.max_stamp_lead,
            line_width: session.style.line_width,
            sphere_diameter: session.style.sphere_diameter,
            handle_topics: names.handles.clone(),
            status_handle_topics: session.handle_topics.clone(),
            tf_failure_topics: names.handles.iter().map(|t| tf_failure_topic(t)).collect(),
            commands_topic: names.commands.clone(),
            robot_description_topic: scene
                .robot
                .is_some()
                .then(|| names.robot_description.clone()),
            robot_link_poses_topic: scene
                .robot
                .is_some()
                .then(|| names.robot_link_poses.clone()),
            start_paused: session.paused,
            outputs: session
                .table
                .rows
                .iter()
                .filter(|r| r.want.recorded)
                .map(RecordedOutput::of)
                .collect(),
            waits_for_clock: !session.table.rows.iter().any(|r| r.kind.name == "clock"),
        })
    }
}

/// Records a session into a bag.
pub struct SessionRecorder {
    bag: BagWriter,
    handles: Vec<TopicId>,
    /// Per handle: its TF-failure topic, created at the first failure.
    tf_failure_topics: Vec<String>,
    tf_failures: Vec<Option<TopicId>>,
    commands: TopicId,
    /// The robot description and link-pose topics (with `robot_colliders:`), created at
    /// their first message.
    robot_topics: Option<(String, String)>,
    robot_ids: (Option<TopicId>, Option<TopicId>),
    /// The scene's handle and object names (commands name them).
    handle_names: Vec<String>,
    object_names: Vec<String>,
    camera_names: Vec<String>,
    /// Per row of the session's outputs table: its bag topic (None: not recorded).
    outputs: Vec<Option<TopicId>>,
    last_ns: u64,
}

impl SessionRecorder {
    /// Create the bag `dir` for `session` (the rows of its outputs table marked
    /// recorded), whose topics and services `names` resolved.
    pub fn create(
        dir: &Path,
        options: BagOptions,
        session: &Session,
        names: &NodeNames,
    ) -> Result<SessionRecorder, RecordError> {
        let mut options = options;
        options
            .custom_data
            .insert("developable_sim.scene".into(), session.scene.name.clone());
        let mut bag = BagWriter::create(dir, options)?;
        let info = SessionInfo::of(session, names, dir)?;
        bag.write_metadata(SESSION_RECORD, info.to_record())?;
        let mut handles = Vec::new();
        for t in &names.handles {
            handles.push(bag.add_topic::<PoseStamped>(t, Qos::SENSOR_DATA)?);
        }
        let commands = bag.add_topic::<SimCommand>(&names.commands, Qos::DATA)?;
        let mut outputs = Vec::new();
        for row in &session.table.rows {
            let p = row.kind.producer;
            outputs.push(match row.want.recorded {
                true => Some(bag.add_topic_of(
                    &row.topic,
                    (p.type_name(), p.type_hash(), &|| p.schema()),
                    row.kind.qos,
                )?),
                false => None,
            });
        }
        let robot_topics = info
            .robot_description_topic
            .clone()
            .zip(info.robot_link_poses_topic.clone());
        Ok(SessionRecorder {
            bag,
            handles,
            robot_topics,
            robot_ids: (None, None),
            tf_failures: vec![None; info.tf_failure_topics.len()],
            tf_failure_topics: info.tf_failure_topics,
            commands,
            handle_names: session
                .scene
                .world
                .handles()
                .iter()
                .map(|h| h.name.clone())
                .collect(),
            object_names: session.scene.world.object_names().to_vec(),
            camera_names: session
                .scene
                .cameras
                .iter()
                .map(|c| c.name.clone())
                .collect(),
            outputs,
            last_ns: 0,
        })
    }

    /// Strictly increasing wall-clock log times (readers sort by log time; equal times
    /// could reorder a frame).
    fn stamp(&mut self) -> u64 {
        self.last_ns = now_ns().max(self.last_ns + 1);
        self.last_ns
    }

    /// The arrival time of an input about to be recorded (ns since the epoch, strictly
    /// increasing): the node judges the pose's stamp against it and records it as the
    /// message's log time, so a replay judges it against the same instant.
    pub fn arrival_ns(&mut self) -> u64 {
        self.stamp()
    }

    /// Record a command about to be applied to the state at simulated time `stamp`: a
    /// pose on its handle's topic at its arrival time (from [`Self::arrival_ns`]), a
    /// failed TF lookup on the handle's failure topic (created at the first one), every
    /// other command on `~/commands`.
    pub fn record_command(&mut self, command: &Command, stamp: Time) -> Result<(), RecordError> {
        match command {
            Command::Pose {
                handle,
                pose,
                arrival_ns,
                publish_ns,
            } => {
                let Some(id) = self.handles.get(*handle).copied() else {
                    return Ok(());
                };
                let data = crate::wire::cdr::encode(pose)?;
                let t = *arrival_ns;
                self.bag.write_raw(id, t, publish_ns.unwrap_or(t), &data)
            }
            Command::TfLookupFailed {
                handle,
                what,
                arrival_ns,
            } => self.record_tf_failure(*handle, what, *arrival_ns),
            Command::RobotDescription {
                urdf, arrival_ns, ..
            } => self.record_robot(true, *arrival_ns, &StringMsg { data: urdf.clone() }),
            Command::LinkPoses {
                transforms,
                arrival_ns,
            } => {
                let m = TFMessage {
                    transforms: transforms.clone(),
                };
                self.record_robot(false, *arrival_ns, &m)
            }
            other => match other.to_msg(stamp, &self.names()) {
                Some(m) => {
                    let t = self.stamp();
                    self.bag.write(self.commands, t, &m)
                }
                None => Ok(()),
            },
        }
    }

    fn names(&self) -> Names<'_> {
        Names {
            handles: &self.handle_names,
            objects: &self.object_names,
            cameras: &self.camera_names,
        }
    }

    /// A failed TF lookup for handle `handle` at `arrival_ns` (see
    /// [`Command::TfLookupFailed`]); `replay` counts it as the node did.
    fn record_tf_failure(
        &mut self,
        handle: usize,
        what: &PoseStamped,
        arrival_ns: u64,
    ) -> Result<(), RecordError> {
        let Some(topic) = self.tf_failure_topics.get(handle) else {
            return Ok(());
        };
        let id = match self.tf_failures[handle] {
            Some(id) => id,
            None => {
                let id = self.bag.add_topic::<PoseStamped>(topic, Qos::DATA)?;
                self.tf_failures[handle] = Some(id);
                id
            }
        };
        let data = crate::wire::cdr::encode(what)?;
        self.bag.write_raw(id, arrival_ns, arrival_ns, &data)
    }

    /// A robot description as received (`description`) or the links' TF lookups, on
    /// its topic (created at its first message), log time `arrival_ns`.
    fn record_robot<M: crate::wire::msgs::RosMessage>(
        &mut self,
        description: bool,
        arrival_ns: u64,
        m: &M,
    ) -> Result<(), RecordError> {
        let Some((d, l)) = &self.robot_topics else {
            return Ok(());
        };
        let (slot, topic, qos) = match description {
            true => (&mut self.robot_ids.0, d, Qos::LATCHED),
            false => (&mut self.robot_ids.1, l, Qos::DATA),
        };
        let id = match *slot {
            Some(id) => id,
            None => *slot.insert(self.bag.add_topic::<M>(topic, qos)?),
        };
        let data = crate::wire::cdr::encode(m)?;
        self.bag.write_raw(id, arrival_ns, arrival_ns, &data)
    }

    /// Record a frame: every recorded row that has a message, in table order.
    pub fn record_frame(&mut self, frame: &Frame) -> Result<(), RecordError> {
        for k in 0..self.outputs.len().min(frame.messages.len()) {
            if let (Some(id), Some(m)) = (self.outputs[k], &frame.messages[k]) {
                let t = self.stamp();
                self.bag.write_raw(id, t, t, m)?;
            }
        }
        Ok(())
    }

    pub fn dir(&self) -> &Path {
        self.bag.dir()
    }

    /// Messages written per topic.
    pub fn counts(&self) -> Vec<(String, u64)> {
        self.bag.counts()
    }

    /// Finish the bag (MCAP summary, metadata.yaml).
    pub fn close(mut self) -> Result<u64, RecordError> {
        let m = self.bag.close()?;
        Ok(m.rosbag2_bagfile_information.message_count)
    }
}

/// Records a headless run (`run --record`) exactly as the node would with nobody
/// driving the handles: a step command, then the step's frame (a
/// [`crate::runner::StepObserver`]).
pub struct RunRecorder {
    session: Session,
    recorder: Option<SessionRecorder>,
    /// Simulated time of the state the next step starts from.
    stamp: Time,
    /// Per camera: its renderer, made at its first frame.
    renderers: Vec<Option<Renderer>>,
}

impl RunRecorder {
    /// Create the bag and record the initial state of `scene`.
    pub fn create(
        scene: &Scene,
        dir: &Path,
        options: BagOptions,
    ) -> Result<RunRecorder, RecordError> {
        let bag_error = |message: String| RecordError::Bag {
            path: dir.to_path_buf(),
            message,
        };
        let names = NodeNames::resolve(scene, "developable_sim", "/", &[])
            .map_err(|e| bag_error(e.to_string()))?;
        let policy = InputPolicy {
            frame_id: scene.frame_id.clone(),
            accept_empty_frame_id: false,
            max_stamp_lead: crate::session::input::DEFAULT_MAX_STAMP_LEAD,
        };
        let run = RunOutputs {
            own_clock: true,
            recording: true,
            record_cameras: options.record_cameras,
        };
        let table =
            OutputTable::for_scene(scene, &names, run).map_err(|e| bag_error(e.to_string()))?;
        let mut session = Session::new(scene.clone(), policy, names.handles.clone(), table);
        let mut recorder = SessionRecorder::create(dir, options, &session, &names)?;
        recorder.record_frame(&session.frame(Content::All)?)?;
        let mut run = RunRecorder {
            stamp: session.stamp(),
            renderers: vec![None; scene.cameras.len()],
            session,
            recorder: Some(recorder),
        };
        run.capture_cameras(scene)?;
        Ok(run)
    }

    /// Capture, draw (on this thread's rayon pool) and record the frame of every camera
    /// due at the state of `scene`, as the node does when its cameras keep up. A camera
    /// carried by a TF frame has no TF in a headless run: its ticks are skipped (and
    /// counted in the statuses).
    fn capture_cameras(&mut self, scene: &Scene) -> Result<(), RecordError> {
        for (c, cam) in scene.cameras.iter().enumerate() {
            let Some(recorder) = self.recorder.as_mut() else {
                return Ok(());
            };
            let Some(pose) = fixed_pose(cam) else {
                continue;
            };
            if self.session.cameras.due(c).is_none() {
                continue;
            }
            let command = Command::Capture {
                camera: c,
                world_from_optical: pose,
            };
            recorder.record_command(&command, self.stamp)?;
            self.session.capture_of(scene, c, &pose);
            let Some(capture) = self.session.cameras.take(c) else {
                continue;
            };
            let renderer = self.renderers[c].get_or_insert_with(|| renderer(scene, cam));
            let rows = &self.session.table.rows;
            let frame = draw_frame(renderer, (cam, scene.source.seed), rows, &capture)?;
            recorder.record_frame(&frame)?;
            if let Some(s) = capture.snapshot {
                self.session.cameras.recycle(s);
            }
        }
        Ok(())
    }

    /// Finish the bag; returns the number of messages recorded.
    pub fn close(mut self) -> Result<u64, RecordError> {
        match self.recorder.take() {
            Some(r) => r.close(),
            None => Ok(0),
        }
    }
}

impl StepObserver for RunRecorder {
    type Error = RecordError;
    fn after_step(
        &mut self,
        scene: &Scene,
        report: &StepReport,
        step_ms: f64,
    ) -> Result<(), RecordError> {
        // the runner's scene, not a copy: cloning the world each step cost a deep copy
        // of every object (meshes, histories, the contact stage)
        let before = std::mem::replace(&mut self.stamp, Time::from_secs(report.time));
        self.session.note_state_of(scene);
        let frame = self
            .session
            .frame_of(scene, Some(report), step_ms * 1e-3, Content::All)?;
        if let Some(r) = self.recorder.as_mut() {
            r.record_command(&Command::Step, before)?;
            r.record_frame(&frame)?;
        }
        self.capture_cameras(scene)
    }
}
