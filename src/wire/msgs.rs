//! Rust mirrors of every ROS 2 message and service the node publishes, subscribes or
//! serves: field for field, in `.msg` order (CDR carries no field names). Standard types
//! follow ROS 2 Jazzy (`src/ros/interfaces/`), ours follow `msg/*.msg`;
//! `tests/ros_interfaces.rs` and `tests/python/test_interfaces.py` keep them in step.
//!
//! These are plain data: conversions from the simulation live in [`crate::wire::convert`].

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// A ROS 2 message type: its name and Jazzy type hash.
pub trait RosMessage: Serialize + DeserializeOwned + Clone + Default + Send + 'static {
    /// `package/msg/Type`.
    const TYPE: &'static str;
    /// REP-2011 type hash (`RIHS01_<sha256>`), as rosbag2 Jazzy records it in
    /// `topic_type_hash` / `type_description_hash`.
    const HASH: &'static str;
    /// The `ros2msg` schema: this type's definition followed by every dependency (see
    /// [`crate::wire::schema`]).
    fn schema() -> String {
        crate::wire::schema::ros2msg_schema(Self::TYPE)
    }
}

macro_rules! ros_message {
    ($t:ty, $name:literal, $hash:literal) => {
        impl RosMessage for $t {
            const TYPE: &'static str = $name;
            const HASH: &'static str = $hash;
        }
        impl ros2_client::Message for $t {}
    };
}
pub(crate) use ros_message;

// sensor_msgs of the camera (Image, CameraInfo, PointCloud2): after the macro they use
#[path = "sensor_msgs.rs"]
mod sensor_msgs;
pub use sensor_msgs::*;

// ---------------------------------------------------------------- builtin_interfaces

/// `builtin_interfaces/msg/Time`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Time {
    pub sec: i32,
    pub nanosec: u32,
}

impl Time {
    /// From seconds (s), rounded to the nearest nanosecond; negative and non-finite
    /// times clamp to zero, times past 2038 saturate.
    pub fn from_secs(t: f64) -> Time {
        if !(t.is_finite() && t > 0.0) {
            return Time::default();
        }
        Time::from_nanos((t * 1e9).round().min(i64::MAX as f64) as i64)
    }

    /// From nanoseconds; clamps to the representable range.
    pub fn from_nanos(ns: i64) -> Time {
        let ns = ns.max(0);
        let sec = (ns / 1_000_000_000).min(i32::MAX as i64) as i32;
        Time {
            sec,
            nanosec: (ns % 1_000_000_000) as u32,
        }
    }

    /// Nanoseconds since the clock's epoch.
    pub fn nanos(&self) -> i64 {
        self.sec as i64 * 1_000_000_000 + self.nanosec as i64
    }
}

/// `builtin_interfaces/msg/Duration`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Duration {
    pub sec: i32,
    pub nanosec: u32,
}

// ---------------------------------------------------------------- std_msgs

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    pub stamp: Time,
    pub frame_id: String,
}

/// `std_msgs/msg/ColorRGBA` (components in [0, 1]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ColorRGBA {
    pub r: f32,
    pub g: f32,
    pub b: f32,
    pub a: f32,
}

impl ColorRGBA {
    pub const fn rgb(r: f32, g: f32, b: f32) -> Self {
        ColorRGBA { r, g, b, a: 1.0 }
    }
}

// ---------------------------------------------------------------- geometry_msgs

/// `geometry_msgs/msg/Point`, m.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// `geometry_msgs/msg/Vector3`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion` (x, y, z, w).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl Default for Quaternion {
    /// The identity rotation (ROS's default, w = 1).
    fn default() -> Self {
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

/// `geometry_msgs/msg/Pose`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub position: Point,
    pub orientation: Quaternion,
}

/// `geometry_msgs/msg/PoseStamped`: a handle target (`world_from_gripper`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseStamped {
    pub header: Header,
    pub pose: Pose,
}
ros_message!(
    PoseStamped,
    "geometry_msgs/msg/PoseStamped",
    "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8"
);

/// `geometry_msgs/msg/Transform`: `parent_from_child` (m, unit quaternion).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    pub translation: Vector3,
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`: `header.frame_id` is the parent frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    pub header: Header,
    pub child_frame_id: String,
    pub transform: Transform,
}

// ---------------------------------------------------------------- std_msgs

/// `std_msgs/msg/String`: a robot description (URDF) as `robot_state_publisher`
/// publishes it on `/robot_description`. (Named `String` to serde, as the definition
/// checks expect: the Rust name would shadow `std::string::String` here.)
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename = "String")]
pub struct StringMsg {
    pub data: String,
}
ros_message!(
    StringMsg,
    "std_msgs/msg/String",
    "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
);

// ---------------------------------------------------------------- tf2_msgs

/// `tf2_msgs/msg/TFMessage`: what `/tf` and `/tf_static` carry.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TFMessage {
    pub transforms: Vec<TransformStamped>,
}
ros_message!(
    TFMessage,
    "tf2_msgs/msg/TFMessage",
    "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"
);

// ---------------------------------------------------------------- sensor_msgs

/// `sensor_msgs/msg/CompressedImage` (a Marker field; always empty here).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CompressedImage {
    pub header: Header,
    pub format: String,
    pub data: Vec<u8>,
}

// ---------------------------------------------------------------- visualization_msgs

/// `visualization_msgs/msg/UVCoordinate`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct UVCoordinate {
    pub u: f32,
    pub v: f32,
}

/// `visualization_msgs/msg/MeshFile`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshFile {
    pub filename: String,
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/Marker`: all 19 fields of Humble / Jazzy.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    pub header: Header,
    pub ns: String,
    pub id: i32,
    #[serde(rename = "type")]
    pub type_: i32,
    pub action: i32,
    pub pose: Pose,
    pub scale: Vector3,
    pub color: ColorRGBA,
    pub lifetime: Duration,
    pub frame_locked: bool,
    pub points: Vec<Point>,
    pub colors: Vec<ColorRGBA>,
    pub texture_resource: String,
    pub texture: CompressedImage,
    pub uv_coordinates: Vec<UVCoordinate>,
    pub text: String,
    pub mesh_resource: String,
    pub mesh_file: MeshFile,
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    // `type`
    pub const CUBE: i32 = 1;
    pub const SPHERE: i32 = 2;
    pub const CYLINDER: i32 = 3;
    pub const LINE_LIST: i32 = 5;
    pub const SPHERE_LIST: i32 = 7;
    pub const TRIANGLE_LIST: i32 = 11;
    // `action`
    pub const ADD: i32 = 0;
    /// Deletes every marker of the namespace (`ns`).
    pub const DELETEALL: i32 = 3;
}

/// `visualization_msgs/msg/MarkerArray`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MarkerArray {
    pub markers: Vec<Marker>,
}
ros_message!(
    MarkerArray,
    "visualization_msgs/msg/MarkerArray",
    "RIHS01_86cb8800b6fb05b5eff1abd7a56f62a5641d3ae9a1c29e78e67e704f1d067dcf"
);

// ---------------------------------------------------------------- rosgraph_msgs

/// `rosgraph_msgs/msg/Clock`: the simulation time on `/clock`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Clock {
    pub clock: Time,
}
ros_message!(
    Clock,
    "rosgraph_msgs/msg/Clock",
    "RIHS01_692f7a66e93a3c83e71765d033b60349ba68023a8c689a79e48078bcb5c58564"
);

// ---------------------------------------------------------------- std_srvs

/// `std_srvs/srv/Empty` request and response (and `Trigger`'s request): an empty IDL
/// struct carries one placeholder byte on the wire.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct EmptyMessage {
    pub structure_needs_at_least_one_member: u8,
}
impl ros2_client::Message for EmptyMessage {}

/// `std_srvs/srv/Trigger` request.
pub type TriggerRequest = EmptyMessage;

/// `std_srvs/srv/Trigger` response (also `SetBool`'s).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TriggerResponse {
    pub success: bool,
    pub message: String,
}
impl ros2_client::Message for TriggerResponse {}

/// `std_srvs/srv/SetBool` request.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SetBoolRequest {
    pub data: bool,
}
impl ros2_client::Message for SetBoolRequest {}

/// `std_srvs/srv/SetBool` response.
pub type SetBoolResponse = TriggerResponse;

// ---------------------------------------------------------------- developable_sim (srv/)

/// `developable_sim/srv/Grasp` request (srv/Grasp.srv).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GraspRequest {
    pub handle: String,
    pub object: String,
    pub by_material_point: bool,
    pub material_point: [f64; 2],
    pub world_point: Point,
    pub max_distance: f64,
    pub hold: String,
}
impl ros2_client::Message for GraspRequest {}

/// `developable_sim/srv/Grasp` response.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GraspResponse {
    pub success: bool,
    pub message: String,
    pub material_point: [f64; 2],
    pub distance: f64,
}
impl ros2_client::Message for GraspResponse {}

/// `developable_sim/srv/Release` request (srv/Release.srv).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ReleaseRequest {
    pub handle: String,
}
impl ros2_client::Message for ReleaseRequest {}

/// `developable_sim/srv/Release` response.
pub type ReleaseResponse = TriggerResponse;

// ---------------------------------------------------------------- developable_sim (msg/)

/// `developable_sim/msg/SingularPoint` (msg/SingularPoint.msg).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SingularPoint {
    pub id: u64,
    pub position: Point,
    pub material: [f64; 2],
}

/// `developable_sim/msg/SingularPoints` (msg/SingularPoints.msg).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SingularPoints {
    pub header: Header,
    pub object_name: String,
    pub points: Vec<SingularPoint>,
}
ros_message!(
    SingularPoints,
    "developable_sim/msg/SingularPoints",
    "RIHS01_94e9c94c8c53afc04ae0ebed200821af0f6e3bd081898621059a294acbbdbb09"
);

/// `developable_sim/msg/HandleStatus` (msg/HandleStatus.msg).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct HandleStatus {
    pub name: String,
    pub topic: String,
    pub external: bool,
    pub target: Pose,
    pub last_stamp: Time,
    pub accepted: u64,
    pub normalized: u64,
    pub rejected_non_finite: u64,
    pub rejected_zero_quaternion: u64,
    pub rejected_stale_stamp: u64,
    pub rejected_unknown_frame: u64,
    pub rejected_future_stamp: u64,
    pub tf_frame: String,
    pub rejected_tf_lookup: u64,
    pub attached: bool,
    pub object: String,
    pub material_point: [f64; 2],
    pub grasp_changed: Time,
}

/// `developable_sim/msg/SimStatus` (msg/SimStatus.msg).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SimStatus {
    pub header: Header,
    pub object_name: String,
    pub scene_name: String,
    pub sim_time: f64,
    pub step: u64,
    pub episode: u32,
    pub dt: f64,
    pub paused: bool,
    pub step_duration: f64,
    pub solver_iterations: u32,
    pub outer_iterations: u32,
    pub converged: bool,
    pub kept_previous_state: bool,
    pub kinetic_energy: f64,
    pub elastic_energy: f64,
    pub gravity_energy: f64,
    pub external_energy: f64,
    pub total_energy: f64,
    pub isometry_error: f64,
    pub constraint_violation: f64,
    pub singular_point_count: u32,
    pub compression_mean_pct: f64,
    pub compressed_edges_pct: f64,
    pub strain_mean_pct: f64,
    pub strain_max_pct: f64,
    pub strained_edges_pct: f64,
    pub overrun_ticks: u64,
    pub dropped_publications: u64,
    pub camera_frames_skipped: u64,
    pub rejected_inputs: u64,
    pub unconverged_steps: u64,
    pub rejected_steps: u64,
    pub real_time_factor: f64,
    pub clock_resets: u32,
    pub handles: Vec<HandleStatus>,
}
ros_message!(
    SimStatus,
    "developable_sim/msg/SimStatus",
    "RIHS01_cab41c30751597604145f7f1a0a6c633ef6046ef54ddac8bc5866c99be527ce3"
);

/// `developable_sim/msg/SimCommand`: one external action on the simulation as the node
/// applied it (bags keep them on `~/commands`; see `msg/SimCommand.msg`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SimCommand {
    pub stamp: Time,
    pub kind: u8,
    pub paused: bool,
    pub parameter_name: String,
    pub parameter_type: u8,
    pub bool_value: bool,
    pub integer_value: i64,
    pub double_value: f64,
    pub string_value: String,
    pub string_array_value: Vec<String>,
    pub handle: String,
    pub object: String,
    pub material_point: [f64; 2],
    pub hold: String,
    pub camera: String,
    pub pose: Pose,
}
ros_message!(
    SimCommand,
    "developable_sim/msg/SimCommand",
    "RIHS01_80a5bb5e88ada42a59b8c9ef7236b85803b1a27644869d7bc542365d7d6fb8c6"
);

impl SimCommand {
    pub const STEP: u8 = 1;
    pub const RESET: u8 = 2;
    pub const SET_PAUSED: u8 = 3;
    pub const SET_PARAMETER: u8 = 4;
    pub const GRASP: u8 = 5;
    pub const RELEASE: u8 = 6;
    pub const RESET_AT: u8 = 7;
    pub const TIME_ORIGIN: u8 = 8;
    pub const CAPTURE: u8 = 9;
    pub const PARAMETER_BOOL: u8 = 1;
    pub const PARAMETER_INTEGER: u8 = 2;
    pub const PARAMETER_DOUBLE: u8 = 3;
    pub const PARAMETER_STRING: u8 = 4;
    pub const PARAMETER_STRING_ARRAY: u8 = 9;
}

/// `developable_sim/msg/GraspState`: what a handle holds (msg/GraspState.msg).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GraspState {
    pub header: Header,
    pub handle: String,
    pub attached: bool,
    pub object: String,
    pub material_point: [f64; 2],
    pub changed: Time,
}
ros_message!(
    GraspState,
    "developable_sim/msg/GraspState",
    "RIHS01_4cbd927ed15c6b9d8dad32a81d358796c9ac942d72b7426372e01311ece24984"
);

/// `geometry_msgs/msg/Wrench`: force (N) and torque (N m).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Wrench {
    pub force: Vector3,
    pub torque: Vector3,
}

/// `geometry_msgs/msg/WrenchStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WrenchStamped {
    pub header: Header,
    pub wrench: Wrench,
}
ros_message!(
    WrenchStamped,
    "geometry_msgs/msg/WrenchStamped",
    "RIHS01_8dc3deaf06b2ab281f9f9a742a8961c328ca7cec16e3fd6586d3a5c83fa78f77"
);
