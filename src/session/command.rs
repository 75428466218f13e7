//! Commands as data: every external action that changes the simulation is one value of
//! [`Command`]. The node turns each DDS event into one (a pose taken from a handle's
//! topic, a TF lookup's outcome, a service call, a parameter change), records it
//! (`record::SessionRecorder::record_command`) and applies it with
//! [`super::Session::apply`]; `replay` reads the same commands back from a bag and
//! applies them with the same function, so a replay does what the node did.

use crate::geometry::{Point2, Pose};
use crate::sim::Hold;
use crate::wire::msgs::{PoseStamped, SimCommand, Time, TransformStamped};

use super::params::ParamValue;
use super::robot::LoadedDescription;

/// One external action on the simulation.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// A pose for handle `handle` (index in the scene), taken from its topic or looked
    /// up in TF, arriving at `arrival_ns` (wall clock, ns since the Unix epoch; the
    /// input filter judges its stamp against it). `publish_ns`: its source timestamp,
    /// if known (recorded, not judged).
    Pose {
        handle: usize,
        pose: PoseStamped,
        arrival_ns: u64,
        publish_ns: Option<u64>,
    },
    /// A TF lookup for handle `handle` found no transform: `what` is the handle's TF
    /// frame at the lookup time (identity pose), or the pose that could not be brought
    /// into the scene frame. The handle keeps its target; the failure is counted. (The
    /// TF tree is not recorded, so the lookup's outcome is.)
    TfLookupFailed {
        handle: usize,
        what: PoseStamped,
        arrival_ns: u64,
    },
    /// A robot description (URDF) arrived on the `robot_colliders` topic at
    /// `arrival_ns`: `urdf` as received (what a bag keeps), `loaded` what the edge that
    /// received it made of it (`scene::urdf::RobotDescription::load`: the links' shapes,
    /// with mesh files read; or why it is not a URDF). Its links replace the robot's
    /// colliders before the next step.
    RobotDescription {
        urdf: String,
        loaded: LoadedDescription,
        arrival_ns: u64,
    },
    /// The robot's links looked up in TF for the coming step (the TF tree is not
    /// recorded, so the lookups' outcomes are): a transform from the scene frame to each
    /// link's TF frame (`child_frame_id`), stamped with the lookup time; an empty
    /// `header.frame_id` (identity transform) is a failed lookup, and that link stays
    /// where it is.
    LinkPoses {
        transforms: Vec<TransformStamped>,
        arrival_ns: u64,
    },
    /// One simulation step with the newest targets (a tick, a lock-step input, `~/step`).
    Step,
    /// Back to t = 0 (`~/reset`).
    Reset,
    /// Under an external clock (use_sim_time): back to t = 0 with the initial state
    /// stamped `origin_ns` (ns on the clock): a reset service called while the clock runs,
    /// or the clock jumped backwards (`clock_jump`, counted in `SimStatus.clock_resets`).
    ResetAt { origin_ns: i64, clock_jump: bool },
    /// Under an external clock: simulated time 0 is at `origin_ns` on the clock from now
    /// on (the first `/clock` sample; a forward jump beyond `max_clock_jump` moves it by
    /// the jump instead of simulating the gap). The current state is published again
    /// with its new stamp.
    SetTimeOrigin { origin_ns: i64 },
    /// Pause or resume (`~/set_paused`, the `paused` parameter).
    SetPaused(bool),
    /// A run-time parameter took a new value (`~/set_parameters`, already checked).
    SetParameter { name: String, value: ParamValue },
    /// Handle `handle` grasps object `object` at `material_point` (m, flat pattern,
    /// already resolved: the grasp services' nearest-point search happened before), held
    /// as `hold` (None: as the scene declared the handle).
    Grasp {
        handle: usize,
        object: usize,
        material_point: Point2,
        hold: Option<Hold>,
    },
    /// Handle `handle` lets go.
    Release { handle: usize },
    /// Camera `camera` (index in the scene) captures the frame of its tick due at the
    /// current state, drawn from `world_from_optical` (m; a TF-carried camera's pose as
    /// looked up). The node captures when the camera is done drawing its previous frame;
    /// a due tick without a capture is skipped (see `session::camera`).
    Capture {
        camera: usize,
        world_from_optical: Pose,
    },
}

/// The names a recorded grasp or release refers to by index.
pub struct Names<'a> {
    pub handles: &'a [String],
    pub objects: &'a [String],
    pub cameras: &'a [String],
}

/// A [`SimCommand`] that is not a command of this build (a newer bag, or damage).
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("not a command: {0}")]
pub struct UnknownCommand(pub String);

impl Command {
    /// The message a bag keeps for this command on `~/commands`, stamped with the
    /// simulated time `stamp` it was applied at. None for poses and failed TF lookups
    /// (recorded on their handle's topics), robot descriptions (on their topic) and link
    /// poses (on `~/robot_link_poses`).
    pub fn to_msg(&self, stamp: Time, names: &Names) -> Option<SimCommand> {
        let mut m = SimCommand {
            stamp,
            ..SimCommand::default()
        };
        match self {
            Command::Pose { .. }
            | Command::TfLookupFailed { .. }
            | Command::RobotDescription { .. }
            | Command::LinkPoses { .. } => return None,
            Command::Step => m.kind = SimCommand::STEP,
            Command::Reset => m.kind = SimCommand::RESET,
            Command::ResetAt {
                origin_ns,
                clock_jump,
            } => {
                m.kind = SimCommand::RESET_AT;
                (m.integer_value, m.bool_value) = (*origin_ns, *clock_jump);
            }
            Command::SetTimeOrigin { origin_ns } => {
                m.kind = SimCommand::TIME_ORIGIN;
                m.integer_value = *origin_ns;
            }
            Command::SetPaused(p) => {
                m.kind = SimCommand::SET_PAUSED;
                m.paused = *p;
            }
            Command::SetParameter { name, value } => {
                m.kind = SimCommand::SET_PARAMETER;
                m.parameter_name = name.clone();
                match value {
                    ParamValue::Bool(b) => {
                        (m.parameter_type, m.bool_value) = (SimCommand::PARAMETER_BOOL, *b)
                    }
                    ParamValue::Integer(i) => {
                        (m.parameter_type, m.integer_value) = (SimCommand::PARAMETER_INTEGER, *i)
                    }
                    ParamValue::Double(x) => {
                        (m.parameter_type, m.double_value) = (SimCommand::PARAMETER_DOUBLE, *x)
                    }
                    ParamValue::String(s) => {
                        m.parameter_type = SimCommand::PARAMETER_STRING;
                        m.string_value = s.clone();
                    }
                    ParamValue::StringArray(a) => {
                        m.parameter_type = SimCommand::PARAMETER_STRING_ARRAY;
                        m.string_array_value = a.clone();
                    }
                }
            }
            Command::Grasp {
                handle,
                object,
                material_point,
                hold,
            } => {
                m.kind = SimCommand::GRASP;
                m.handle = names.handles.get(*handle)?.clone();
                m.object = names.objects.get(*object)?.clone();
                m.material_point = [material_point.x, material_point.y];
                (m.hold, m.double_value) = match hold {
                    None => (String::new(), 0.0),
                    Some(Hold::Position) => ("position".into(), 0.0),
                    Some(Hold::Normal { stiffness }) => ("normal".into(), *stiffness),
                    Some(Hold::Full) => ("full".into(), 0.0),
                };
            }
            Command::Release { handle } => {
                m.kind = SimCommand::RELEASE;
                m.handle = names.handles.get(*handle)?.clone();
            }
            Command::Capture {
                camera,
                world_from_optical,
            } => {
                m.kind = SimCommand::CAPTURE;
                m.camera = names.cameras.get(*camera)?.clone();
                m.pose = crate::wire::convert::pose(world_from_optical);
            }
        }
        Some(m)
    }

    /// The command a recorded [`SimCommand`] holds.
    pub fn from_msg(m: &SimCommand, names: &Names) -> Result<Command, UnknownCommand> {
        let index = |list: &[String], name: &str, what: &str| {
            list.iter()
                .position(|n| n == name)
                .ok_or_else(|| UnknownCommand(format!("{what} `{name}` is not in the scene")))
        };
        Ok(match m.kind {
            SimCommand::STEP => Command::Step,
            SimCommand::RESET => Command::Reset,
            SimCommand::RESET_AT => Command::ResetAt {
                origin_ns: m.integer_value,
                clock_jump: m.bool_value,
            },
            SimCommand::TIME_ORIGIN => Command::SetTimeOrigin {
                origin_ns: m.integer_value,
            },
            SimCommand::SET_PAUSED => Command::SetPaused(m.paused),
            SimCommand::SET_PARAMETER => Command::SetParameter {
                name: m.parameter_name.clone(),
                value: match m.parameter_type {
                    SimCommand::PARAMETER_BOOL => ParamValue::Bool(m.bool_value),
                    SimCommand::PARAMETER_INTEGER => ParamValue::Integer(m.integer_value),
                    SimCommand::PARAMETER_DOUBLE => ParamValue::Double(m.double_value),
                    SimCommand::PARAMETER_STRING => ParamValue::String(m.string_value.clone()),
                    SimCommand::PARAMETER_STRING_ARRAY => {
                        ParamValue::StringArray(m.string_array_value.clone())
                    }
                    t => {
                        return Err(UnknownCommand(format!(
                            "parameter `{}` of type {t}",
                            m.parameter_name
                        )))
                    }
                },
            },
            SimCommand::GRASP => Command::Grasp {
                handle: index(names.handles, &m.handle, "handle")?,
                object: index(names.objects, &m.object, "object")?,
                material_point: Point2::new(m.material_point[0], m.material_point[1]),
                hold: match m.hold.as_str() {
                    "" => None,
                    "position" => Some(Hold::Position),
                    "normal" => Some(Hold::Normal {
                        stiffness: m.double_value,
                    }),
                    "full" => Some(Hold::Full),
                    h => return Err(UnknownCommand(format!("hold `{h}`"))),
                },
            },
            SimCommand::RELEASE => Command::Release {
                handle: index(names.handles, &m.handle, "handle")?,
            },
            SimCommand::CAPTURE => Command::Capture {
                camera: index(names.cameras, &m.camera, "camera")?,
                world_from_optical: crate::wire::convert::from_pose(&m.pose),
            },
            k => return Err(UnknownCommand(format!("kind {k}"))),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recorded_commands_read_back_as_themselves() {
        let stamp = Time { sec: 3, nanosec: 5 };
        let commands = [
            Command::Step,
            Command::Reset,
            Command::ResetAt {
                origin_ns: 1_700_000_123_456_789_012,
                clock_jump: true,
            },
            Command::ResetAt {
                origin_ns: 5,
                clock_jump: false,
            },
            Command::SetTimeOrigin {
                origin_ns: 100_000_000_000,
            },
            Command::SetPaused(true),
            Command::SetPaused(false),
            Command::SetParameter {
                name: "max_stamp_lead".into(),
                value: ParamValue::Double(1.5),
            },
            Command::SetParameter {
                name: "accept_empty_frame_id".into(),
                value: ParamValue::Bool(true),
            },
            Command::SetParameter {
                name: "x".into(),
                value: ParamValue::Integer(-7),
            },
            Command::SetParameter {
                name: "y".into(),
                value: ParamValue::String("s".into()),
            },
            Command::SetParameter {
                name: "z".into(),
                value: ParamValue::StringArray(vec!["a".into(), "b".into()]),
            },
        ];
        let (handles, objects) = (
            ["left".to_string(), "right".to_string()],
            ["ribbon".to_string()],
        );
        let cameras = ["camera".to_string()];
        let names = Names {
            handles: &handles,
            objects: &objects,
            cameras: &cameras,
        };
        let grasps = [
            Command::Grasp {
                handle: 1,
                object: 0,
                material_point: Point2::new(0.25, -0.01),
                hold: None,
            },
            Command::Grasp {
                handle: 0,
                object: 0,
                material_point: Point2::new(1.0, 0.0),
                hold: Some(Hold::Normal { stiffness: 2.5 }),
            },
            Command::Grasp {
                handle: 0,
                object: 0,
                material_point: Point2::new(0.5, 0.0),
                hold: Some(Hold::Full),
            },
            Command::Release { handle: 1 },
            Command::Capture {
                camera: 0,
                world_from_optical: Pose::new(
                    crate::geometry::Vector3::new(0.5, -0.8, 0.6),
                    crate::geometry::Vector3::new(-1.9, 0.1, 0.3),
                ),
            },
        ];
        for c in commands.into_iter().chain(grasps) {
            let m = c.to_msg(stamp, &names).expect("a ~/commands command");
            assert_eq!(m.stamp, stamp);
            assert_eq!(Command::from_msg(&m, &names), Ok(c));
        }
        // a handle the scene does not have is refused on reading
        let m = Command::Release { handle: 1 }
            .to_msg(stamp, &names)
            .unwrap();
        let fewer = Names {
            handles: &handles[..1],
            objects: &objects,
            cameras: &cameras,
        };
        assert!(Command::from_msg(&m, &fewer).is_err());
    }

    #[test]
    fn poses_are_not_commands_messages_and_unknown_kinds_are_refused() {
        let pose = Command::Pose {
            handle: 0,
            pose: PoseStamped::default(),
            arrival_ns: 1,
            publish_ns: None,
        };
        let names = Names {
            handles: &[],
            objects: &[],
            cameras: &[],
        };
        assert_eq!(pose.to_msg(Time::default(), &names), None);
        let unknown = SimCommand {
            kind: 200,
            ..SimCommand::default()
        };
        assert_eq!(
            Command::from_msg(&unknown, &names),
            Err(UnknownCommand("kind 200".into()))
        );
        let bad_type = SimCommand {
            kind: SimCommand::SET_PARAMETER,
            parameter_name: "p".into(),
            parameter_type: 7,
            ..SimCommand::default()
        };
        assert!(Command::from_msg(&bad_type, &names).is_err());
    }
}
