//! The ROS 2 standard `simulation_interfaces` (release 1.5.1, the Jazzy line; the
//! definitions are vendored verbatim in `interfaces/simulation_interfaces/`): the
//! messages, service requests and responses and the SimulateSteps action's parts the
//! node serves, fields in definition order (CDR carries no names;
//! `tests/ros_interfaces.rs` checks them against the `.msg`/`.srv`/`.action` text).

use serde::{Deserialize, Serialize};

use super::msgs::{ros_message, RosMessage};

/// `simulation_interfaces/msg/Result`: every response's outcome.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename = "Result")]
pub struct SimResult {
    pub result: u8,
    pub error_message: String,
}
ros_message!(
    SimResult,
    "simulation_interfaces/msg/Result",
    "RIHS01_cf43a306adff3337a0a47143d8f5689933bc70a30478f13b077dc1fe3bc5ad17"
);

impl SimResult {
    pub const FEATURE_UNSUPPORTED: u8 = 0;
    pub const OK: u8 = 1;
    pub const NOT_FOUND: u8 = 2;
    pub const INCORRECT_STATE: u8 = 3;
    pub const OPERATION_FAILED: u8 = 4;

    pub fn ok() -> SimResult {
        SimResult {
            result: Self::OK,
            error_message: String::new(),
        }
    }

    pub fn failed(result: u8, why: impl Into<String>) -> SimResult {
        SimResult {
            result,
            error_message: why.into(),
        }
    }
}

/// `simulation_interfaces/msg/SimulationState`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SimulationState {
    pub state: u8,
}
ros_message!(
    SimulationState,
    "simulation_interfaces/msg/SimulationState",
    "RIHS01_bb9f87ccdd98fba113052a512d9801e84ce732d0a2b3c2b0cb281828de36e415"
);

impl SimulationState {
    pub const STOPPED: u8 = 0;
    pub const PLAYING: u8 = 1;
    pub const PAUSED: u8 = 2;
    pub const QUITTING: u8 = 3;
    pub const NO_WORLD: u8 = 4;
    pub const LOADING_WORLD: u8 = 5;
}

/// `simulation_interfaces/msg/SimulatorFeatures`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SimulatorFeatures {
    pub features: Vec<u16>,
    pub spawn_formats: Vec<String>,
    pub custom_info: String,
}
ros_message!(
    SimulatorFeatures,
    "simulation_interfaces/msg/SimulatorFeatures",
    "RIHS01_8b101c8529bc0ea3dcf056078254768f39832b9ef0adaf93bd5cea96c0de3305"
);

impl SimulatorFeatures {
    pub const SIMULATION_RESET: u16 = 20;
    pub const SIMULATION_RESET_TIME: u16 = 21;
    pub const SIMULATION_RESET_STATE: u16 = 22;
    pub const SIMULATION_RESET_SPAWNED: u16 = 23;
    pub const SIMULATION_STATE_GETTING: u16 = 24;
    pub const SIMULATION_STATE_SETTING: u16 = 25;
    pub const SIMULATION_STATE_PAUSE: u16 = 26;
    pub const STEP_SIMULATION_SINGLE: u16 = 31;
    pub const STEP_SIMULATION_MULTIPLE: u16 = 32;
    pub const STEP_SIMULATION_ACTION: u16 = 33;
}

/// `simulation_interfaces/srv/GetSimulatorFeatures` response (the request is empty:
/// [`super::msgs::EmptyMessage`]).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GetSimulatorFeaturesResponse {
    pub features: SimulatorFeatures,
}
impl ros2_client::Message for GetSimulatorFeaturesResponse {}

/// `simulation_interfaces/srv/ResetSimulation` request.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ResetSimulationRequest {
    pub scope: u8,
}
impl ros2_client::Message for ResetSimulationRequest {}

impl ResetSimulationRequest {
    pub const SCOPE_DEFAULT: u8 = 0;
    pub const SCOPE_TIME: u8 = 1;
    pub const SCOPE_STATE: u8 = 2;
    pub const SCOPE_SPAWNED: u8 = 4;
    pub const SCOPE_ALL: u8 = 255;
}

/// The response of ResetSimulation, StepSimulation and SetSimulationState: a
/// [`SimResult`] only.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ResultResponse {
    pub result: SimResult,
}
impl ros2_client::Message for ResultResponse {}

/// `simulation_interfaces/srv/StepSimulation` request.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StepSimulationRequest {
    pub steps: u64,
}
impl ros2_client::Message for StepSimulationRequest {}

/// `simulation_interfaces/srv/GetSimulationState` response (empty request).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GetSimulationStateResponse {
    pub state: SimulationState,
    pub result: SimResult,
}
impl ros2_client::Message for GetSimulationStateResponse {}

/// `simulation_interfaces/srv/SetSimulationState` request.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SetSimulationStateRequest {
    pub state: SimulationState,
}
impl ros2_client::Message for SetSimulationStateRequest {}

/// Results of SetSimulationState beyond [`SimResult`]'s (the .srv's constants).
pub const ALREADY_IN_TARGET_STATE: u8 = 101;
pub const STATE_TRANSITION_ERROR: u8 = 102;
pub const INCORRECT_TRANSITION: u8 = 103;

/// `simulation_interfaces/action/SimulateSteps` goal (`SimulateSteps_Goal`).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SimulateStepsGoal {
    pub steps: u64,
}
impl ros2_client::Message for SimulateStepsGoal {}

/// `simulation_interfaces/action/SimulateSteps` result (`SimulateSteps_Result`).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SimulateStepsResult {
    pub result: SimResult,
}
impl ros2_client::Message for SimulateStepsResult {}

/// `simulation_interfaces/action/SimulateSteps` feedback (`SimulateSteps_Feedback`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SimulateStepsFeedback {
    pub completed_steps: u64,
    pub remaining_steps: u64,
}
impl ros2_client::Message for SimulateStepsFeedback {}
