//! What a session records and in which order.
//!
//! Topics: every handle input (as received, rejected ones included: replay runs them
//! through the same filter), and every output the node publishes, plus each object's
//! status even when the scene does not publish it (it is the step ledger replay
//! follows). Order in the file: the inputs taken before a step, then that step's
//! frame: statuses first, then `/clock`, markers and singular points. A
//! `developable_sim` MCAP metadata record at the start holds the scene (YAML after
//! overrides) and the input policy, so `replay` rebuilds the same simulation.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::bag::{now_ns, BagOptions, BagWriter, TopicId};
use super::metadata::Qos;
use super::RecordError;
use crate::ros::input::InputPolicy;
use crate::ros::msgs::{Clock, MarkerArray, PoseStamped, SimStatus, SingularPoints};
use crate::ros::names::NodeNames;
use crate::ros::session::{Frame, FrameContent, Session};
use crate::runner::{ObserverError, StepObserver};
use crate::scene::Scene;
use crate::sim::StepReport;

fn default_max_stamp_lead() -> f64 {
    crate::ros::input::DEFAULT_MAX_STAMP_LEAD
}

/// Name of the MCAP metadata record describing the session.
pub const SESSION_RECORD: &str = "developable_sim";

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
    pub clock_topic: Option<String>,
    /// The colliders' markers, when recorded (bags from before it existed have none).
    #[serde(default)]
    pub colliders_topic: Option<String>,
    /// Per object: (markers, singular points, status); None when not recorded.
    pub object_topics: Vec<(Option<String>, Option<String>, String)>,
    /// Per handle: the input topic its status reports (`/tf` for a TF-driven handle);
    /// bags from before it existed: `handle_topics`.
    #[serde(default)]
    pub status_handle_topics: Vec<String>,
    /// Per handle: the bag topic of its failed TF lookups (see
    /// [`SessionRecorder::record_tf_failure`]); bags from before it existed have none.
    #[serde(default)]
    pub tf_failure_topics: Vec<String>,
}

/// The bag topic of a handle's failed TF lookups: beside its input topic, so it reads as
/// "what became of that handle's input".
fn tf_failure_topic(handle_topic: &str) -> String {
    format!("{handle_topic}/tf_lookup_failed")
}

impl SessionInfo {
    fn to_record(&self) -> BTreeMap<String, String> {
        let mut m = BTreeMap::new();
        m.insert("format".into(), "1".into());
        m.insert("version".into(), env!("CARGO_PKG_VERSION").into());
        m.insert("scene_name".into(), self.scene_name.clone());
        m.insert(
            "session".into(),
            serde_json::to_string(self).unwrap_or_default(),
        );
        m
    }

    pub fn from_record(values: &BTreeMap<String, String>) -> Result<SessionInfo, String> {
        let json = values
            .get("session")
            .ok_or("the developable_sim record has no `session` entry")?;
        serde_json::from_str(json).map_err(|e| format!("unreadable session description: {e}"))
    }
}

struct ObjectIds {
    markers: Option<TopicId>,
    singular_points: Option<TopicId>,
    status: TopicId,
}

/// Records a session into a bag.
pub struct SessionRecorder {
    bag: BagWriter,
    handles: Vec<TopicId>,
    /// Per handle: its TF-failure topic, created at the first failure.
    tf_failure_topics: Vec<String>,
    tf_failures: Vec<Option<TopicId>>,
    clock: Option<TopicId>,
    colliders: Option<TopicId>,
    objects: Vec<ObjectIds>,
    last_ns: u64,
}

impl SessionRecorder {
    /// Create the bag `dir` for `session`. `published`: the outputs published (and so
    /// recorded); statuses are always recorded. `clock`: whether `/clock` is published.
    pub fn create(
        dir: &Path,
        options: BagOptions,
        session: &Session,
        names: &NodeNames,
        published: FrameContent,
        clock: bool,
    ) -> Result<SessionRecorder, RecordError> {
        let mut options = options;
        options
            .custom_data
            .insert("developable_sim.scene".into(), session.scene.name.clone());
        let mut bag = BagWriter::create(dir, options)?;
        let scene = &session.scene;
        let info = SessionInfo {
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
            clock_topic: clock.then(|| names.clock.clone()),
            colliders_topic: (published.markers && session.has_colliders())
                .then(|| names.colliders.clone()),
            object_topics: names
                .objects
                .iter()
                .map(|o| {
                    (
                        published.markers.then(|| o.markers.clone()),
                        published.singular_points.then(|| o.singular_points.clone()),
                        o.status.clone(),
                    )
                })
                .collect(),
            status_handle_topics: session.handle_topics.clone(),
            tf_failure_topics: names.handles.iter().map(|t| tf_failure_topic(t)).collect(),
        };
        bag.write_metadata(SESSION_RECORD, info.to_record())?;
        let mut handles = Vec::new();
        for t in &names.handles {
            handles.push(bag.add_topic::<PoseStamped>(t, Qos::SENSOR_DATA)?);
        }
        let clock = if clock {
            Some(bag.add_topic::<Clock>(&names.clock, Qos::CLOCK)?)
        } else {
            None
        };
        let colliders = match &info.colliders_topic {
            Some(t) => Some(bag.add_topic::<MarkerArray>(t, Qos::MARKERS)?),
            None => None,
        };
        let mut objects = Vec::new();
        for (m, s, st) in &info.object_topics {
            objects.push(ObjectIds {
                markers: match m {
                    Some(t) => Some(bag.add_topic::<MarkerArray>(t, Qos::MARKERS)?),
                    None => None,
                },
                singular_points: match s {
                    Some(t) => Some(bag.add_topic::<SingularPoints>(t, Qos::DATA)?),
                    None => None,
                },
                status: bag.add_topic::<SimStatus>(st, Qos::DATA)?,
            });
        }
        Ok(SessionRecorder {
            bag,
            handles,
            tf_failures: vec![None; info.tf_failure_topics.len()],
            tf_failure_topics: info.tf_failure_topics,
            clock,
            colliders,
            objects,
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

    /// Record a pose taken from handle `handle`'s topic at `arrival_ns` (from
    /// [`Self::arrival_ns`]). `publish_ns`: its source timestamp (ns since the epoch),
    /// if known.
    pub fn record_input(
        &mut self,
        handle: usize,
        msg: &PoseStamped,
        arrival_ns: u64,
        publish_ns: Option<u64>,
    ) -> Result<(), RecordError> {
        let Some(id) = self.handles.get(handle).copied() else {
            return Ok(());
        };
        let t = arrival_ns;
        let data = crate::ros::cdr::encode(msg)?;
        self.bag.write_raw(id, t, publish_ns.unwrap_or(t), &data)
    }

    /// Record a failed TF lookup for handle `handle` at `arrival_ns`: `what` is the
    /// handle's TF frame at the lookup time (a TF-driven handle; identity pose) or the
    /// pose that could not be brought into the scene frame (a pose in another frame of
    /// the tree, older than the buffer or too far ahead). `replay` counts it as the node
    /// did (`rejected_tf_lookup`; the handle keeps its target): the TF tree itself is not
    /// in the bag, so the lookup's outcome is.
    pub fn record_tf_failure(
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
        let data = crate::ros::cdr::encode(what)?;
        self.bag.write_raw(id, arrival_ns, arrival_ns, &data)
    }

    /// Record a frame: statuses, then clock, markers and singular points.
    pub fn record_frame(&mut self, frame: &Frame) -> Result<(), RecordError> {
        for i in 0..frame.objects.len().min(self.objects.len()) {
            if let Some(s) = &frame.objects[i].status {
                let t = self.stamp();
                self.bag.write(self.objects[i].status, t, s)?;
            }
        }
        if let Some(c) = self.clock {
            let t = self.stamp();
            self.bag.write(c, t, &frame.clock)?;
        }
        for i in 0..frame.objects.len().min(self.objects.len()) {
            let (markers, singular) = (self.objects[i].markers, self.objects[i].singular_points);
            if let (Some(id), Some(m)) = (markers, &frame.objects[i].markers) {
                let t = self.stamp();
                self.bag.write(id, t, m)?;
            }
            if let (Some(id), Some(s)) = (singular, &frame.objects[i].singular_points) {
                let t = self.stamp();
                self.bag.write(id, t, s)?;
            }
        }
        if let (Some(id), Some(m)) = (self.colliders, &frame.colliders) {
            let t = self.stamp();
            self.bag.write(id, t, m)?;
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

/// What a recorded frame must contain given the scene's outputs: statuses always.
pub fn recorded_content(published: FrameContent) -> FrameContent {
    FrameContent {
        status: true,
        ..published
    }
}

/// Records a headless run (`run --record`) exactly as the node would publish it with
/// nobody driving the handles: a [`crate::runner::StepObserver`].
pub struct RunRecorder {
    session: Session,
    recorder: Option<SessionRecorder>,
    content: FrameContent,
}

impl RunRecorder {
    /// Create the bag and record the initial state of `scene`.
    pub fn create(
        scene: &Scene,
        dir: &Path,
        options: BagOptions,
    ) -> Result<RunRecorder, RecordError> {
        let names = NodeNames::resolve(scene, "developable_sim", "/", &[]).map_err(|e| {
            RecordError::Bag {
                path: dir.to_path_buf(),
                message: e.to_string(),
            }
        })?;
        let policy = InputPolicy {
            frame_id: scene.frame_id.clone(),
            accept_empty_frame_id: false,
            max_stamp_lead: crate::ros::input::DEFAULT_MAX_STAMP_LEAD,
        };
        let session = Session::new(scene.clone(), policy, names.handles.clone());
        let published = FrameContent {
            markers: scene.outputs.markers,
            singular_points: scene.outputs.singular_points,
            status: scene.outputs.status,
        };
        let mut recorder = SessionRecorder::create(
            dir,
            options,
            &session,
            &names,
            published,
            scene.outputs.clock,
        )?;
        let content = recorded_content(published);
        recorder.record_frame(&session.frame(None, 0.0, content))?;
        Ok(RunRecorder {
            session,
            recorder: Some(recorder),
            content,
        })
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
    fn after_step(
        &mut self,
        scene: &Scene,
        report: &StepReport,
        step_ms: f64,
    ) -> Result<(), ObserverError> {
        // the runner's scene, not a copy: cloning the world each step cost a deep copy
        // of every object (meshes, histories, the contact stage)
        let frame = self
            .session
            .frame_of(scene, Some(report), step_ms * 1e-3, self.content);
        if let Some(r) = self.recorder.as_mut() {
            r.record_frame(&frame)?;
        }
        Ok(())
    }
}
