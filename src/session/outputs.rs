//! Outputs as a table. Every message the simulation produces is described once, in
//! [`OUTPUTS`]: its name, scope (global, per object or per handle), topic, message type
//! and QoS, whether the markers' rate limit applies, when a scene and a run want it, and
//! the producer that makes it from a state. A session's [`OutputTable`] is that list
//! instantiated for its scene (a row per object or handle where the scope says so);
//! a [`Frame`] holds one encoded message per row. DDS, the bag, Foxglove and replay
//! iterate over the rows and never name an output.
//!
//! Adding an output is one producer (a function from [`Produce`] to a message) and one
//! entry in [`OUTPUTS`].

use bytes::Bytes;

use crate::scene::Scene;
use crate::wire::cdr::{self, CdrError};
use crate::wire::introspect::{to_value, Value};
use crate::wire::msgs::{
    CameraInfo, Clock, GraspState, Image, MarkerArray, PointCloud2, RosMessage, SimStatus,
    SingularPoints, TFMessage, Time, WrenchStamped,
};
use crate::wire::qos::Qos;

use super::names::{NameError, NodeNames};
use super::produce::Produce;
pub use super::produce::Scope;
use super::sensor::{self as cam, CameraView};
use super::{frames, markers, status};

/// How many rows an output kind has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScopeKind {
    /// One for the scene.
    Global,
    /// One per object (`{object}` in its topic).
    PerObject,
    /// One per handle (`{handle}` in its topic; `{object}` is the handle's object).
    PerHandle,
    /// One per object and handle (`{object}` and `{handle}` in its topic).
    PerObjectHandle,
    /// One per camera (`{camera}` in its topic): made from the camera's drawn frames
    /// beside the tick (`session::camera`), not from a state.
    PerCamera,
}

/// Whether a row is published (DDS, Foxglove) and whether it is recorded in bags.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Want {
    pub published: bool,
    pub recorded: bool,
}

impl Want {
    /// Published and recorded alike (most outputs).
    const fn both(on: bool) -> Want {
        Want {
            published: on,
            recorded: on,
        }
    }
}

/// What a run decides about outputs beyond the scene file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RunOutputs {
    /// The node owns time (publishes `/clock`); false under use_sim_time.
    pub own_clock: bool,
    /// The run records a bag: rows recorded but not published are made only then.
    pub recording: bool,
    /// The bag records the cameras' images and clouds too (`--record-cameras`; they are
    /// big: 6.4 MB a 640 x 480 frame). Their camera_info is always recorded: the
    /// ledger of the frames drawn.
    pub record_cameras: bool,
}

/// The message type of an output and how a producer's message becomes CDR bytes.
pub trait Producer: Sync + std::fmt::Debug {
    /// `package/msg/Type`.
    fn type_name(&self) -> &'static str;
    /// REP-2011 type hash, as rosbag2 records it.
    fn type_hash(&self) -> &'static str;
    /// The `ros2msg` schema (the bags' and Foxglove's).
    fn schema(&self) -> String;
    /// The row's message for this state, CDR-encoded (None: nothing this state, e.g. a
    /// mesh that is not finite).
    fn produce(&self, p: &Produce, scope: Scope) -> Option<Result<Bytes, CdrError>>;
    /// A message of this type, decoded into a field-by-field value (replay compares
    /// recorded and recomputed messages this way).
    fn value(&self, cdr: &[u8]) -> Result<Value, String>;
    /// A camera row's message for a drawn frame, CDR-encoded (None: not a camera row,
    /// or the frame was not drawn and the message carries pixels).
    fn camera(&self, _view: &CameraView) -> Option<Result<Bytes, CdrError>> {
        None
    }
    /// Whether a camera row's message carries the pixels (its frames must be drawn).
    fn draws(&self) -> bool {
        false
    }
}

/// A producer function of messages `M`.
pub struct Typed<M: 'static>(pub fn(&Produce, Scope) -> Option<M>);

impl<M> std::fmt::Debug for Typed<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Typed<{}>", std::any::type_name::<M>())
    }
}

impl<M: RosMessage> Producer for Typed<M> {
    fn type_name(&self) -> &'static str {
        M::TYPE
    }
    fn type_hash(&self) -> &'static str {
        M::HASH
    }
    fn schema(&self) -> String {
        M::schema()
    }
    fn produce(&self, p: &Produce, scope: Scope) -> Option<Result<Bytes, CdrError>> {
        (self.0)(p, scope).map(|m| cdr::encode(&m).map(Bytes::from))
    }
    fn value(&self, bytes: &[u8]) -> Result<Value, String> {
        decoded_value::<M>(bytes)
    }
}

/// The CDR message `bytes` of type `M` as a value tree (replay's comparisons).
fn decoded_value<M: RosMessage>(bytes: &[u8]) -> Result<Value, String> {
    let m: M = cdr::decode(bytes).map_err(|e| format!("{}: {e}", M::TYPE))?;
    to_value(&m).map_err(|e| format!("{}: {e}", M::TYPE))
}

/// A camera row's message made from a drawn frame, CDR-encoded (None: not made).
pub type MakeCameraMessage = fn(&CameraView) -> Option<Result<Vec<u8>, CdrError>>;

/// The producer of a camera row: a message of type `M` from a [`CameraView`], encoded
/// (the frame's rows are made beside the tick, not from a state: [`Producer::produce`]
/// makes nothing).
pub struct Drawn<M: 'static> {
    /// The message carries the pixels (a capture must copy what the camera sees).
    pub draws: bool,
    pub make: MakeCameraMessage,
    pub message: std::marker::PhantomData<fn() -> M>,
}

impl<M> std::fmt::Debug for Drawn<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Drawn<{}>", std::any::type_name::<M>())
    }
}

impl<M: RosMessage> Producer for Drawn<M> {
    fn type_name(&self) -> &'static str {
        M::TYPE
    }
    fn type_hash(&self) -> &'static str {
        M::HASH
    }
    fn schema(&self) -> String {
        M::schema()
    }
    fn produce(&self, _: &Produce, _: Scope) -> Option<Result<Bytes, CdrError>> {
        None
    }
    fn value(&self, bytes: &[u8]) -> Result<Value, String> {
        decoded_value::<M>(bytes)
    }
    fn camera(&self, view: &CameraView) -> Option<Result<Bytes, CdrError>> {
        (self.make)(view).map(|r| r.map(Bytes::from))
    }
    fn draws(&self) -> bool {
        self.draws
    }
}

/// One kind of output: an entry of [`OUTPUTS`].
#[derive(Debug)]
pub struct OutputKind {
    /// Stable name, recorded in bags to route a topic back to its row.
    pub name: &'static str,
    pub scope: ScopeKind,
    /// The topic before resolution: relative names live in the node's namespace,
    /// `{object}` and `{handle}` are the row's object and handle names.
    pub topic: &'static str,
    pub qos: Qos,
    /// Published at most `markers_rate` times a second (recorded every state).
    pub throttled: bool,
    /// Made only when what it says changed (and for an initial state): a latched
    /// state such as a handle's grasp.
    pub on_change: bool,
    /// Whether the scene and the run want the row.
    pub want: fn(&Scene, RunOutputs, Scope) -> Want,
    pub producer: &'static dyn Producer,
}

/// Every output the simulation can produce, in publication and recording order within a
/// frame (the statuses first: they name the state the other messages belong to).
pub const OUTPUTS: &[OutputKind] = &[
    OutputKind {
        name: "status",
        scope: ScopeKind::PerObject,
        topic: "{object}/status",
        qos: Qos::DATA,
        throttled: false,
        on_change: false,
        // always recorded: the statuses are the ledger of steps a replay follows
        want: |s, _, _| Want {
            published: s.outputs.status,
            recorded: true,
        },
        producer: &Typed::<SimStatus>(status::status),
    },
    OutputKind {
        name: "clock",
        scope: ScopeKind::Global,
        topic: "/clock",
        qos: Qos::CLOCK,
        throttled: false,
        on_change: false,
        want: |s, run, _| Want::both(s.outputs.clock && run.own_clock),
        producer: &Typed::<Clock>(status::clock),
    },
    OutputKind {
        name: "markers",
        scope: ScopeKind::PerObject,
        topic: "{object}/markers",
        qos: Qos::MARKERS,
        throttled: true,
        on_change: false,
        want: |s, _, _| Want::both(s.outputs.markers),
        producer: &Typed::<MarkerArray>(markers::object_markers),
    },
    OutputKind {
        name: "singular_points",
        scope: ScopeKind::PerObject,
        topic: "{object}/singular_points",
        qos: Qos::DATA,
        throttled: false,
        on_change: false,
        want: |s, _, _| Want::both(s.outputs.singular_points),
        producer: &Typed::<SingularPoints>(status::singular_points),
    },
    OutputKind {
        name: "colliders",
        scope: ScopeKind::Global,
        topic: "colliders",
        qos: Qos::MARKERS,
        throttled: false,
        on_change: false,
        want: |s, _, _| {
            let has = !s.world.colliders().is_empty();
            // a robot's links arrive at run time
            Want::both(s.outputs.markers && (has || s.robot.is_some()))
        },
        producer: &Typed::<MarkerArray>(markers::colliders),
    },
    OutputKind {
        name: "tf",
        scope: ScopeKind::Global,
        topic: "/tf",
        qos: Qos::TF,
        throttled: false,
        on_change: false,
        want: |s, _, _| Want::both(s.outputs.tf),
        producer: &Typed::<TFMessage>(frames::tf),
    },
    OutputKind {
        name: "grasp_state",
        scope: ScopeKind::PerHandle,
        topic: "handles/{handle}/state",
        qos: Qos::LATCHED,
        throttled: false,
        on_change: true,
        want: |s, _, _| Want::both(s.outputs.grasp_state),
        producer: &Typed::<GraspState>(status::grasp_state),
    },
    OutputKind {
        name: "wrench",
        scope: ScopeKind::PerObjectHandle,
        topic: "{object}/{handle}/wrench",
        qos: Qos::DATA,
        throttled: false,
        on_change: false,
        want: |s, _, _| Want::both(s.outputs.wrench),
        producer: &Typed::<WrenchStamped>(status::wrench),
    },
    OutputKind {
        name: "points",
        scope: ScopeKind::PerObject,
        topic: "{object}/points",
        qos: Qos::DATA,
        throttled: false,
        on_change: false,
        want: |s, _, _| Want::both(s.outputs.points),
        producer: &Typed::<PointCloud2>(cam::mesh_points),
    },
    OutputKind {
        name: "camera_frames",
        scope: ScopeKind::Global,
        topic: "/tf_static",
        qos: Qos::TF_STATIC,
        throttled: false,
        on_change: true,
        want: |s, _, _| Want::both(!s.cameras.is_empty()),
        producer: &Typed::<TFMessage>(cam::optical_frames),
    },
    // the RealSense topics, one identical header.stamp on a frame's five messages
    OutputKind {
        name: "camera_color",
        scope: ScopeKind::PerCamera,
        topic: "{camera}/color/image_raw",
        qos: Qos::CAMERA,
        throttled: false,
        on_change: false,
        want: camera_pixels,
        producer: &Drawn::<Image> {
            draws: true,
            make: cam::color,
            message: std::marker::PhantomData,
        },
    },
    OutputKind {
        name: "camera_color_info",
        scope: ScopeKind::PerCamera,
        topic: "{camera}/color/camera_info",
        qos: Qos::CAMERA,
        throttled: false,
        on_change: false,
        want: |_, _, _| Want::both(true),
        producer: &Drawn::<CameraInfo> {
            draws: false,
            make: cam::camera_info,
            message: std::marker::PhantomData,
        },
    },
    OutputKind {
        name: "camera_depth",
        scope: ScopeKind::PerCamera,
        topic: "{camera}/aligned_depth_to_color/image_raw",
        qos: Qos::CAMERA,
        throttled: false,
        on_change: false,
        want: camera_pixels,
        producer: &Drawn::<Image> {
            draws: true,
            make: cam::depth,
            message: std::marker::PhantomData,
        },
    },
    OutputKind {
        name: "camera_depth_info",
        scope: ScopeKind::PerCamera,
        topic: "{camera}/aligned_depth_to_color/camera_info",
        qos: Qos::CAMERA,
        throttled: false,
        on_change: false,
        want: |_, _, _| Want::both(true),
        producer: &Drawn::<CameraInfo> {
            draws: false,
            make: cam::camera_info,
            message: std::marker::PhantomData,
        },
    },
    OutputKind {
        name: "camera_points",
        scope: ScopeKind::PerCamera,
        topic: "{camera}/depth/color/points",
        qos: Qos::CAMERA,
        throttled: false,
        on_change: false,
        want: camera_pixels,
        producer: &Drawn::<PointCloud2> {
            draws: true,
            make: cam::cloud,
            message: std::marker::PhantomData,
        },
    },
];

/// A camera's images and cloud: always published, recorded with `--record-cameras`.
fn camera_pixels(_: &Scene, run: RunOutputs, _: Scope) -> Want {
    Want {
        published: true,
        recorded: run.record_cameras,
    }
}

/// The kind named `name` (as bags record it).
pub fn kind_named(name: &str) -> Option<&'static OutputKind> {
    OUTPUTS.iter().find(|k| k.name == name)
}

/// One output of a session: a kind at a scope, on a resolved topic.
#[derive(Clone, Debug)]
pub struct OutputRow {
    pub kind: &'static OutputKind,
    pub scope: Scope,
    pub topic: String,
    pub want: Want,
}

impl OutputRow {
    pub fn type_name(&self) -> &'static str {
        self.kind.producer.type_name()
    }
}

/// The outputs of one session, in [`OUTPUTS`] order, each scope in index order. Rows
/// neither published nor recorded are not in it (nothing is built that nobody wants).
#[derive(Clone, Debug, Default)]
pub struct OutputTable {
    pub rows: Vec<OutputRow>,
}

impl OutputTable {
    /// The rows `scene` and `run` want, with topics resolved by `names`.
    pub fn for_scene(
        scene: &Scene,
        names: &NodeNames,
        run: RunOutputs,
    ) -> Result<OutputTable, NameError> {
        let mut rows = Vec::new();
        for kind in OUTPUTS {
            for scope in scopes(scene, kind.scope) {
                let mut want = (kind.want)(scene, run, scope);
                want.recorded &= run.recording;
                if !(want.published || want.recorded) {
                    continue;
                }
                let topic = names.resolve_name(&topic_of(scene, kind, scope))?;
                rows.push(OutputRow {
                    kind,
                    scope,
                    topic,
                    want,
                });
            }
        }
        Ok(OutputTable { rows })
    }

    /// The row of `kind` at `scope`, if the table has it.
    pub fn find(&self, kind: &str, scope: Scope) -> Option<usize> {
        self.rows
            .iter()
            .position(|r| r.kind.name == kind && r.scope == scope)
    }
}

/// Every scope of `kind` in `scene`.
fn scopes(scene: &Scene, kind: ScopeKind) -> Vec<Scope> {
    match kind {
        ScopeKind::Global => vec![Scope::Global],
        ScopeKind::PerObject => (0..scene.world.object_names().len())
            .map(Scope::Object)
            .collect(),
        ScopeKind::PerHandle => (0..scene.world.handles().len())
            .map(Scope::Handle)
            .collect(),
        ScopeKind::PerObjectHandle => {
            let objects = scene.world.object_names().len();
            let handles = scene.world.handles().len();
            (0..objects)
                .flat_map(|o| (0..handles).map(move |h| Scope::ObjectHandle(o, h)))
                .collect()
        }
        ScopeKind::PerCamera => (0..scene.cameras.len()).map(Scope::Camera).collect(),
    }
}

/// The unresolved topic of `kind` at `scope`: `{object}` and `{handle}` replaced.
fn topic_of(scene: &Scene, kind: &OutputKind, scope: Scope) -> String {
    let world = &scene.world;
    let (object, handle) = match scope {
        Scope::Global => (None, None),
        Scope::Object(o) => (Some(o), None),
        Scope::Handle(h) => (world.handles().get(h).map(|s| s.object), Some(h)),
        Scope::ObjectHandle(o, h) => (Some(o), Some(h)),
        Scope::Camera(c) => {
            let name = scene.cameras.get(c).map_or("", |cam| cam.name.as_str());
            return kind.topic.replace("{camera}", name);
        }
    };
    let mut topic = kind.topic.to_string();
    if let Some(o) = object.and_then(|o| world.object_names().get(o)) {
        topic = topic.replace("{object}", o);
    }
    if let Some(h) = handle.and_then(|h| world.handles().get(h)) {
        topic = topic.replace("{handle}", &h.name);
    }
    topic
}

/// Every message produced by one state of the world (after a step, or step 0): one
/// entry per row of the session's [`OutputTable`] (None: not made for this state).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Simulation time of the state.
    pub stamp: Time,
    /// CDR bytes (with the encapsulation header), as DDS sends them and bags hold them.
    pub messages: Vec<Option<Bytes>>,
}

impl Frame {
    /// The message of row `row`, decoded as `M`.
    pub fn decode<M: RosMessage>(&self, row: usize) -> Option<Result<M, CdrError>> {
        let bytes = self.messages.get(row)?.as_ref()?;
        Some(cdr::decode(bytes))
    }
}
