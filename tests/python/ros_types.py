"""ROS 2 message types for the PyPI `cyclonedds` package, named as ROS 2 names them on
DDS (`pkg::msg::dds_::Type_`), so a Cyclone participant talks to the node exactly as an
rclpy node on rmw_cyclonedds would. Field order follows the .msg definitions."""


from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl import types as t


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: t.int32 = 0
    nanosec: t.uint32 = 0


@dataclass
class Duration(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: t.int32 = 0
    nanosec: t.uint32 = 0


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class ColorRGBA(IdlStruct, typename="std_msgs::msg::dds_::ColorRGBA_"):
    r: t.float32 = 0.0
    g: t.float32 = 0.0
    b: t.float32 = 0.0
    a: t.float32 = 0.0


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0
    w: t.float64 = 1.0


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@dataclass
class CompressedImage(IdlStruct, typename="sensor_msgs::msg::dds_::CompressedImage_"):
    header: Header = field(default_factory=Header)
    format: str = ""
    data: t.sequence[t.uint8] = field(default_factory=list)


@dataclass
class UVCoordinate(IdlStruct, typename="visualization_msgs::msg::dds_::UVCoordinate_"):
    u: t.float32 = 0.0
    v: t.float32 = 0.0


@dataclass
class MeshFile(IdlStruct, typename="visualization_msgs::msg::dds_::MeshFile_"):
    filename: str = ""
    data: t.sequence[t.uint8] = field(default_factory=list)


@dataclass
class Marker(IdlStruct, typename="visualization_msgs::msg::dds_::Marker_"):
    header: Header = field(default_factory=Header)
    ns: str = ""
    id: t.int32 = 0
    type: t.int32 = 0
    action: t.int32 = 0
    pose: Pose = field(default_factory=Pose)
    scale: Vector3 = field(default_factory=Vector3)
    color: ColorRGBA = field(default_factory=ColorRGBA)
    lifetime: Duration = field(default_factory=Duration)
    frame_locked: bool = False
    points: t.sequence[Point] = field(default_factory=list)
    colors: t.sequence[ColorRGBA] = field(default_factory=list)
    texture_resource: str = ""
    texture: CompressedImage = field(default_factory=CompressedImage)
    uv_coordinates: t.sequence[UVCoordinate] = field(default_factory=list)
    text: str = ""
    mesh_resource: str = ""
    mesh_file: MeshFile = field(default_factory=MeshFile)
    mesh_use_embedded_materials: bool = False


@dataclass
class MarkerArray(IdlStruct, typename="visualization_msgs::msg::dds_::MarkerArray_"):
    markers: t.sequence[Marker] = field(default_factory=list)


@dataclass
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    clock: Time = field(default_factory=Time)


@dataclass
class SingularPoint(IdlStruct, typename="developable_sim::msg::dds_::SingularPoint_"):
    id: t.uint64 = 0
    position: Point = field(default_factory=Point)
    material: t.array[t.float64, 2] = field(default_factory=lambda: [0.0, 0.0])


@dataclass
class SingularPoints(IdlStruct, typename="developable_sim::msg::dds_::SingularPoints_"):
    header: Header = field(default_factory=Header)
    object_name: str = ""
    points: t.sequence[SingularPoint] = field(default_factory=list)


@dataclass
class HandleStatus(IdlStruct, typename="developable_sim::msg::dds_::HandleStatus_"):
    name: str = ""
    topic: str = ""
    external: bool = False
    target: Pose = field(default_factory=Pose)
    last_stamp: Time = field(default_factory=Time)
    accepted: t.uint64 = 0
    normalized: t.uint64 = 0
    rejected_non_finite: t.uint64 = 0
    rejected_zero_quaternion: t.uint64 = 0
    rejected_stale_stamp: t.uint64 = 0
    rejected_unknown_frame: t.uint64 = 0
    rejected_future_stamp: t.uint64 = 0
    tf_frame: str = ""
    rejected_tf_lookup: t.uint64 = 0
    attached: bool = False
    object: str = ""
    material_point: t.array[t.float64, 2] = field(default_factory=lambda: [0.0, 0.0])
    grasp_changed: Time = field(default_factory=Time)


@dataclass
class GraspState(IdlStruct, typename="developable_sim::msg::dds_::GraspState_"):
    header: Header = field(default_factory=Header)
    handle: str = ""
    attached: bool = False
    object: str = ""
    material_point: t.array[t.float64, 2] = field(default_factory=lambda: [0.0, 0.0])
    changed: Time = field(default_factory=Time)


@dataclass
class SimStatus(IdlStruct, typename="developable_sim::msg::dds_::SimStatus_"):
    header: Header = field(default_factory=Header)
    object_name: str = ""
    scene_name: str = ""
    sim_time: t.float64 = 0.0
    step: t.uint64 = 0
    episode: t.uint32 = 0
    dt: t.float64 = 0.0
    paused: bool = False
    step_duration: t.float64 = 0.0
    solver_iterations: t.uint32 = 0
    outer_iterations: t.uint32 = 0
    converged: bool = False
    kept_previous_state: bool = False
    kinetic_energy: t.float64 = 0.0
    elastic_energy: t.float64 = 0.0
    gravity_energy: t.float64 = 0.0
    external_energy: t.float64 = 0.0
    total_energy: t.float64 = 0.0
    isometry_error: t.float64 = 0.0
    constraint_violation: t.float64 = 0.0
    singular_point_count: t.uint32 = 0
    compression_mean_pct: t.float64 = 0.0
    compressed_edges_pct: t.float64 = 0.0
    strain_mean_pct: t.float64 = 0.0
    strain_max_pct: t.float64 = 0.0
    strained_edges_pct: t.float64 = 0.0
    overrun_ticks: t.uint64 = 0
    dropped_publications: t.uint64 = 0
    camera_frames_skipped: t.uint64 = 0
    rejected_inputs: t.uint64 = 0
    unconverged_steps: t.uint64 = 0
    rejected_steps: t.uint64 = 0
    real_time_factor: t.float64 = 0.0
    clock_resets: t.uint32 = 0
    handles: t.sequence[HandleStatus] = field(default_factory=list)


@dataclass
class MarkerArrayHead(IdlStruct, typename="visualization_msgs::msg::dds_::MarkerArray_"):
    """The head of a MarkerArray on the wire: the marker count and the first marker's
    header (the rest of the sample is not decoded). Decoding whole meshes in Python
    costs more than the node takes to make them, and a reader that falls behind would
    measure itself, not the node."""

    count: t.uint32 = 0
    header: Header = field(default_factory=Header)


@dataclass
class ImageHead(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    """The head of an Image on the wire (the pixels are not decoded), as MarkerArrayHead:
    a reader that counts camera frames without spending the CPU it measures."""

    header: Header = field(default_factory=Header)


@dataclass
class PointCloud2Head(IdlStruct, typename="sensor_msgs::msg::dds_::PointCloud2_"):
    """The head of a PointCloud2 on the wire (see ImageHead)."""

    header: Header = field(default_factory=Header)


# Services on the rmw_cyclonedds wire format: every request and reply starts with a
# header {client guid (8 bytes), sequence number (int64)}.


@dataclass
class TriggerRequest(IdlStruct, typename="std_srvs::srv::dds_::Trigger_Request_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    structure_needs_at_least_one_member: t.uint8 = 0


@dataclass
class TriggerResponse(IdlStruct, typename="std_srvs::srv::dds_::Trigger_Response_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    success: bool = False
    message: str = ""


@dataclass
class SetBoolRequest(IdlStruct, typename="std_srvs::srv::dds_::SetBool_Request_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    data: bool = False


@dataclass
class SetBoolResponse(IdlStruct, typename="std_srvs::srv::dds_::SetBool_Response_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    success: bool = False
    message: str = ""


@dataclass
class GraspRequest(IdlStruct, typename="developable_sim::srv::dds_::Grasp_Request_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    handle: str = ""
    object: str = ""
    by_material_point: bool = False
    material_point: t.array[t.float64, 2] = field(default_factory=lambda: [0.0, 0.0])
    world_point: Point = field(default_factory=Point)
    max_distance: t.float64 = 0.0
    hold: str = ""


@dataclass
class GraspResponse(IdlStruct, typename="developable_sim::srv::dds_::Grasp_Response_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    success: bool = False
    message: str = ""
    material_point: t.array[t.float64, 2] = field(default_factory=lambda: [0.0, 0.0])
    distance: t.float64 = 0.0


@dataclass
class ReleaseRequest(IdlStruct, typename="developable_sim::srv::dds_::Release_Request_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    handle: str = ""


@dataclass
class ReleaseResponse(IdlStruct, typename="developable_sim::srv::dds_::Release_Response_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    success: bool = False
    message: str = ""


@dataclass
class Wrench(IdlStruct, typename="geometry_msgs::msg::dds_::Wrench_"):
    force: Vector3 = field(default_factory=Vector3)
    torque: Vector3 = field(default_factory=Vector3)


@dataclass
class WrenchStamped(IdlStruct, typename="geometry_msgs::msg::dds_::WrenchStamped_"):
    header: Header = field(default_factory=Header)
    wrench: Wrench = field(default_factory=Wrench)


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: t.sequence[TransformStamped] = field(default_factory=list)


# sensor_msgs of the camera (`data` decodes to a list of ints: numpy takes it from
# there).


@dataclass
class Image(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    header: Header = field(default_factory=Header)
    height: t.uint32 = 0
    width: t.uint32 = 0
    encoding: str = ""
    is_bigendian: t.uint8 = 0
    step: t.uint32 = 0
    data: t.sequence[t.uint8] = field(default_factory=list)


@dataclass
class RegionOfInterest(IdlStruct, typename="sensor_msgs::msg::dds_::RegionOfInterest_"):
    x_offset: t.uint32 = 0
    y_offset: t.uint32 = 0
    height: t.uint32 = 0
    width: t.uint32 = 0
    do_rectify: bool = False


@dataclass
class CameraInfo(IdlStruct, typename="sensor_msgs::msg::dds_::CameraInfo_"):
    header: Header = field(default_factory=Header)
    height: t.uint32 = 0
    width: t.uint32 = 0
    distortion_model: str = ""
    d: t.sequence[t.float64] = field(default_factory=list)
    k: t.array[t.float64, 9] = field(default_factory=lambda: [0.0] * 9)
    r: t.array[t.float64, 9] = field(default_factory=lambda: [0.0] * 9)
    p: t.array[t.float64, 12] = field(default_factory=lambda: [0.0] * 12)
    binning_x: t.uint32 = 0
    binning_y: t.uint32 = 0
    roi: RegionOfInterest = field(default_factory=RegionOfInterest)


@dataclass
class PointField(IdlStruct, typename="sensor_msgs::msg::dds_::PointField_"):
    name: str = ""
    offset: t.uint32 = 0
    datatype: t.uint8 = 0
    count: t.uint32 = 0


@dataclass
class PointCloud2(IdlStruct, typename="sensor_msgs::msg::dds_::PointCloud2_"):
    header: Header = field(default_factory=Header)
    height: t.uint32 = 0
    width: t.uint32 = 0
    fields: t.sequence[PointField] = field(default_factory=list)
    is_bigendian: bool = False
    point_step: t.uint32 = 0
    row_step: t.uint32 = 0
    data: t.sequence[t.uint8] = field(default_factory=list)
    is_dense: bool = False


@dataclass
class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    """std_msgs/msg/String (a robot description's URDF)."""

    data: str = ""


# rcl_interfaces (parameter services), on the rmw_cyclonedds service wire format


@dataclass
class ParameterValue(IdlStruct, typename="rcl_interfaces::msg::dds_::ParameterValue_"):
    type: t.uint8 = 0
    bool_value: bool = False
    integer_value: t.int64 = 0
    double_value: t.float64 = 0.0
    string_value: str = ""
    byte_array_value: t.sequence[t.uint8] = field(default_factory=list)
    bool_array_value: t.sequence[bool] = field(default_factory=list)
    integer_array_value: t.sequence[t.int64] = field(default_factory=list)
    double_array_value: t.sequence[t.float64] = field(default_factory=list)
    string_array_value: t.sequence[str] = field(default_factory=list)


@dataclass
class Parameter(IdlStruct, typename="rcl_interfaces::msg::dds_::Parameter_"):
    name: str = ""
    value: ParameterValue = field(default_factory=ParameterValue)


@dataclass
class FloatingPointRange(IdlStruct, typename="rcl_interfaces::msg::dds_::FloatingPointRange_"):
    from_value: t.float64 = 0.0
    to_value: t.float64 = 0.0
    step: t.float64 = 0.0


@dataclass
class IntegerRange(IdlStruct, typename="rcl_interfaces::msg::dds_::IntegerRange_"):
    from_value: t.int64 = 0
    to_value: t.int64 = 0
    step: t.uint64 = 0


@dataclass
class ParameterDescriptor(IdlStruct, typename="rcl_interfaces::msg::dds_::ParameterDescriptor_"):
    name: str = ""
    type: t.uint8 = 0
    description: str = ""
    additional_constraints: str = ""
    read_only: bool = False
    dynamic_typing: bool = False
    floating_point_range: t.sequence[FloatingPointRange, 1] = field(default_factory=list)
    integer_range: t.sequence[IntegerRange, 1] = field(default_factory=list)


@dataclass
class SetParametersResult(IdlStruct, typename="rcl_interfaces::msg::dds_::SetParametersResult_"):
    successful: bool = False
    reason: str = ""


@dataclass
class ListParametersResult(IdlStruct, typename="rcl_interfaces::msg::dds_::ListParametersResult_"):
    names: t.sequence[str] = field(default_factory=list)
    prefixes: t.sequence[str] = field(default_factory=list)


@dataclass
class ListParametersRequest(IdlStruct, typename="rcl_interfaces::srv::dds_::ListParameters_Request_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    prefixes: t.sequence[str] = field(default_factory=list)
    depth: t.uint64 = 0


@dataclass
class ListParametersResponse(IdlStruct, typename="rcl_interfaces::srv::dds_::ListParameters_Response_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    result: ListParametersResult = field(default_factory=ListParametersResult)


@dataclass
class GetParametersRequest(IdlStruct, typename="rcl_interfaces::srv::dds_::GetParameters_Request_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    names: t.sequence[str] = field(default_factory=list)


@dataclass
class GetParametersResponse(IdlStruct, typename="rcl_interfaces::srv::dds_::GetParameters_Response_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    values: t.sequence[ParameterValue] = field(default_factory=list)


@dataclass
class SetParametersRequest(IdlStruct, typename="rcl_interfaces::srv::dds_::SetParameters_Request_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    parameters: t.sequence[Parameter] = field(default_factory=list)


@dataclass
class SetParametersResponse(IdlStruct, typename="rcl_interfaces::srv::dds_::SetParameters_Response_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    results: t.sequence[SetParametersResult] = field(default_factory=list)


@dataclass
class DescribeParametersRequest(IdlStruct, typename="rcl_interfaces::srv::dds_::DescribeParameters_Request_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    names: t.sequence[str] = field(default_factory=list)


@dataclass
class DescribeParametersResponse(IdlStruct, typename="rcl_interfaces::srv::dds_::DescribeParameters_Response_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    descriptors: t.sequence[ParameterDescriptor] = field(default_factory=list)


@dataclass
class GetParameterTypesRequest(IdlStruct, typename="rcl_interfaces::srv::dds_::GetParameterTypes_Request_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    names: t.sequence[str] = field(default_factory=list)


@dataclass
class GetParameterTypesResponse(IdlStruct, typename="rcl_interfaces::srv::dds_::GetParameterTypes_Response_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    types: t.sequence[t.uint8] = field(default_factory=list)


# simulation_interfaces 1.5.1 (src/wire/interfaces/simulation_interfaces/), on the
# rmw_cyclonedds service wire format


@dataclass
class SimResult(IdlStruct, typename="simulation_interfaces::msg::dds_::Result_"):
    result: t.uint8 = 0
    error_message: str = ""


@dataclass
class SimulationState(IdlStruct, typename="simulation_interfaces::msg::dds_::SimulationState_"):
    state: t.uint8 = 0


@dataclass
class SimulatorFeatures(IdlStruct, typename="simulation_interfaces::msg::dds_::SimulatorFeatures_"):
    features: t.sequence[t.uint16] = field(default_factory=list)
    spawn_formats: t.sequence[str] = field(default_factory=list)
    custom_info: str = ""


@dataclass
class GetSimulatorFeaturesRequest(
    IdlStruct, typename="simulation_interfaces::srv::dds_::GetSimulatorFeatures_Request_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    structure_needs_at_least_one_member: t.uint8 = 0


@dataclass
class GetSimulatorFeaturesResponse(
    IdlStruct, typename="simulation_interfaces::srv::dds_::GetSimulatorFeatures_Response_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    features: SimulatorFeatures = field(default_factory=SimulatorFeatures)


@dataclass
class ResetSimulationRequest(
    IdlStruct, typename="simulation_interfaces::srv::dds_::ResetSimulation_Request_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    scope: t.uint8 = 0


@dataclass
class ResetSimulationResponse(
    IdlStruct, typename="simulation_interfaces::srv::dds_::ResetSimulation_Response_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    result: SimResult = field(default_factory=SimResult)


@dataclass
class StepSimulationRequest(
    IdlStruct, typename="simulation_interfaces::srv::dds_::StepSimulation_Request_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    steps: t.uint64 = 1


@dataclass
class StepSimulationResponse(
    IdlStruct, typename="simulation_interfaces::srv::dds_::StepSimulation_Response_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    result: SimResult = field(default_factory=SimResult)


@dataclass
class GetSimulationStateRequest(
    IdlStruct, typename="simulation_interfaces::srv::dds_::GetSimulationState_Request_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    structure_needs_at_least_one_member: t.uint8 = 0


@dataclass
class GetSimulationStateResponse(
    IdlStruct, typename="simulation_interfaces::srv::dds_::GetSimulationState_Response_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    state: SimulationState = field(default_factory=SimulationState)
    result: SimResult = field(default_factory=SimResult)


@dataclass
class SetSimulationStateRequest(
    IdlStruct, typename="simulation_interfaces::srv::dds_::SetSimulationState_Request_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    state: SimulationState = field(default_factory=SimulationState)


@dataclass
class SetSimulationStateResponse(
    IdlStruct, typename="simulation_interfaces::srv::dds_::SetSimulationState_Response_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    result: SimResult = field(default_factory=SimResult)


# simulation_interfaces/action/SimulateSteps (1.5.1) and the action_msgs parts of every
# action, as rosidl generates them and rmw_cyclonedds carries them: the three services
# (request header client_guid + sequence_number) and the feedback and status topics.


@dataclass
class UUID(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    uuid: t.array[t.uint8, 16] = field(default_factory=lambda: [0] * 16)


@dataclass
class GoalInfo(IdlStruct, typename="action_msgs::msg::dds_::GoalInfo_"):
    goal_id: UUID = field(default_factory=UUID)
    stamp: Time = field(default_factory=Time)


@dataclass
class GoalStatus(IdlStruct, typename="action_msgs::msg::dds_::GoalStatus_"):
    goal_info: GoalInfo = field(default_factory=GoalInfo)
    status: t.int8 = 0


@dataclass
class GoalStatusArray(IdlStruct, typename="action_msgs::msg::dds_::GoalStatusArray_"):
    status_list: t.sequence[GoalStatus] = field(default_factory=list)


@dataclass
class CancelGoalRequest(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Request_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    goal_info: GoalInfo = field(default_factory=GoalInfo)


@dataclass
class CancelGoalResponse(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Response_"):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    return_code: t.int8 = 0
    goals_canceling: t.sequence[GoalInfo] = field(default_factory=list)


@dataclass
class SimulateStepsGoal(IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_Goal_"):
    steps: t.uint64 = 0


@dataclass
class SimulateStepsResult(
    IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_Result_"
):
    result: SimResult = field(default_factory=SimResult)


@dataclass
class SimulateStepsFeedback(
    IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_Feedback_"
):
    completed_steps: t.uint64 = 0
    remaining_steps: t.uint64 = 0


@dataclass
class SimulateStepsSendGoalRequest(
    IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_SendGoal_Request_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    goal_id: UUID = field(default_factory=UUID)
    goal: SimulateStepsGoal = field(default_factory=SimulateStepsGoal)


@dataclass
class SimulateStepsSendGoalResponse(
    IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_SendGoal_Response_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    accepted: bool = False
    stamp: Time = field(default_factory=Time)


@dataclass
class SimulateStepsGetResultRequest(
    IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_GetResult_Request_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    goal_id: UUID = field(default_factory=UUID)


@dataclass
class SimulateStepsGetResultResponse(
    IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_GetResult_Response_"
):
    client_guid: t.uint64 = 0
    sequence_number: t.int64 = 0
    status: t.int8 = 0
    result: SimulateStepsResult = field(default_factory=SimulateStepsResult)


@dataclass
class SimulateStepsFeedbackMessage(
    IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_FeedbackMessage_"
):
    goal_id: UUID = field(default_factory=UUID)
    feedback: SimulateStepsFeedback = field(default_factory=SimulateStepsFeedback)
