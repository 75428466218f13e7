//! Handles (grippers) and their scripted trajectories.
//!
//! A handle grasps one object at a material point and drives it towards a target pose
//! `world_from_gripper`. Targets come from outside (a ROS topic) or, when nobody
//! publishes, from the scripted [`Trajectory`].

use crate::geometry::{Point2, Point3, Pose, Rotation, Vector3};

/// What a handle constrains on the object it holds.
///
/// A handle is a gripper: it always has a target (from outside, or its script). Whether
/// it holds an object, which one and where changes at run time ([`super::World::grasp`],
/// [`super::World::release`]); each grasp is a new attachment with its own
/// `generation`, so an object keeps a constraint's state (multipliers) across such edits
/// only while the same attachment lasts.
#[derive(Clone, Debug, PartialEq)]
pub struct HandleSpec {
    /// Name (the ROS topic default is `/handles/<name>`).
    pub name: String,
    /// Index of the object it holds (or held last) in the world.
    pub object: usize,
    /// Grasp point in the object's flat pattern, m.
    pub material_point: Point2,
    /// Which world axes of the grasp point position are held (x, y, z). All false: the
    /// handle does not constrain position.
    pub position_axes: [bool; 3],
    /// How the orientation is held.
    pub orientation: OrientationMode,
    /// Scripted target when no external target arrives.
    pub trajectory: Trajectory,
    /// Whether the handle holds its object now.
    pub attached: bool,
    /// `gripper_from_grasp`: where the grasp point's material frame sits in the gripper
    /// frame, fixed when a grasp happens at run time so that nothing snaps (the point is
    /// held where it was relative to the gripper). None: at the gripper's origin with
    /// its axes (a scene's handle, attached from t = 0).
    pub grasp_offset: Option<Pose>,
    /// Counts the attachments of this handle (0: the scene's own).
    pub generation: u64,
    /// The grasp shortcut's reach: a gripper that closes grasps the surface point nearest
    /// its target within this distance, m.
    pub grasp_radius: f64,
    /// Scripted grasps and releases, in time order; they act only while the handle
    /// follows its script (nobody drives it).
    pub script: Vec<GraspEvent>,
}

/// A scripted change of a handle's hold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GraspEvent {
    /// Simulated time, s: applied at the start of the first step that ends at or after it.
    pub time: f64,
    /// True: close on the surface point nearest the target (within `grasp_radius`);
    /// false: let go.
    pub grasp: bool,
}

impl HandleSpec {
    /// A handle named `name` holding `object` at `material_point` (all three position
    /// axes, orientation free), attached from t = 0, following `trajectory`.
    pub fn new(name: &str, object: usize, material_point: Point2, trajectory: Trajectory) -> Self {
        HandleSpec {
            name: name.to_string(),
            object,
            material_point,
            position_axes: [true; 3],
            orientation: OrientationMode::Free,
            trajectory,
            attached: true,
            grasp_offset: None,
            generation: 0,
            grasp_radius: DEFAULT_GRASP_RADIUS,
            script: Vec::new(),
        }
    }

    /// Whether the handle acts on object `object` now.
    pub fn holds(&self, object: usize) -> bool {
        self.attached && self.object == object
    }

    /// `world_from_grasp`: where the grasp point's material frame is held when the
    /// gripper is at `world_from_gripper`.
    pub fn grasp_frame(&self, world_from_gripper: &Pose) -> Pose {
        match &self.grasp_offset {
            Some(offset) => world_from_gripper * offset,
            None => *world_from_gripper,
        }
    }
}

/// Why a grasp or a release was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GraspError {
    #[error("no handle {0}")]
    UnknownHandle(usize),
    #[error("no object {0}")]
    UnknownObject(usize),
    /// The object cannot be held there (the object says why).
    #[error("{0}")]
    NotGraspable(String),
    #[error("the nearest graspable point is {distance:.4} m away, farther than {max:.4} m")]
    TooFar { distance: f64, max: f64 },
    #[error("the object has no surface to grasp (its mesh is empty or not finite)")]
    NoSurface,
    #[error("handle {0} drives the ribbon's prescribed base: it cannot let go")]
    DrivesBase(usize),
}

/// A scripted grasp or release as it happened.
#[derive(Clone, Debug, PartialEq)]
pub struct ScriptedChange {
    pub handle: usize,
    pub grasp: bool,
    /// Whether anything changed, or why the grasp failed (nothing within reach).
    pub result: Result<bool, GraspError>,
}

/// Default of [`HandleSpec::grasp_radius`], m.
pub const DEFAULT_GRASP_RADIUS: f64 = 0.02;

/// How a handle holds what it grasps (`position`, `normal` or `full` in the grasp
/// service and the scene files).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Hold {
    /// The grasp point's position, orientation free (a pinch).
    Position,
    /// Position and the surface normal by normal guiding of stiffness K, J.
    Normal { stiffness: f64 },
    /// Position and the whole frame (a clamp).
    Full,
}

impl Hold {
    /// The position axes and orientation mode of this hold.
    pub fn parts(self) -> ([bool; 3], OrientationMode) {
        let orientation = match self {
            Hold::Position => OrientationMode::Free,
            Hold::Normal { stiffness } => OrientationMode::Normal { stiffness },
            Hold::Full => OrientationMode::Full,
        };
        ([true; 3], orientation)
    }
}

/// How a handle holds the orientation of the element under its grasp point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OrientationMode {
    /// Orientation free (a pinch grasp that lets the object swivel).
    Free,
    /// Normal guiding (Pan et al. sec. 5.1): energy K/2 |n - n_target|^2 with
    /// `n_target = R_target * z`, `stiffness` K in J.
    Normal { stiffness: f64 },
    /// The whole element frame is held (hard constraint, augmented Lagrangian).
    Full,
}

/// One piece of a scripted motion: between `start` and `end` (s) the target is translated
/// by `translation` (m) and rotated by `angle` (rad) about `axis` through the target point,
/// linearly in time. Pieces compose in order, so an angle of 4*pi is a full 4*pi twist.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    pub start: f64,
    pub end: f64,
    pub translation: Vector3,
    pub axis: Vector3,
    pub angle: f64,
}

/// A scripted target: an initial pose, then motions.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// `world_from_gripper` at t = 0.
    pub initial: Pose,
    pub motions: Vec<Motion>,
}

impl Trajectory {
    /// A trajectory that stays at `initial`.
    pub fn fixed(initial: Pose) -> Self {
        Trajectory {
            initial,
            motions: Vec::new(),
        }
    }

    /// `world_from_gripper` at time `t` (s).
    pub fn pose_at(&self, t: f64) -> Pose {
        let mut position: Point3 = self.initial.translation.vector.into();
        let mut rotation: Rotation = self.initial.rotation;
        for m in &self.motions {
            let span = (m.end - m.start).max(1e-12);
            let s = ((t - m.start) / span).clamp(0.0, 1.0);
            if s <= 0.0 {
                continue;
            }
            position += m.translation * s;
            if m.angle != 0.0 && m.axis.norm() > 0.0 {
                let r = Rotation::from_scaled_axis(m.axis.normalize() * (m.angle * s));
                rotation = r * rotation;
            }
        }
        Pose::from_parts(position.coords.into(), rotation)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn motions_compose_linearly_in_time() {
        let traj = Trajectory {
            initial: Pose::translation(1.0, 0.0, 0.0),
            motions: vec![Motion {
                start: 1.0,
                end: 3.0,
                translation: Vector3::new(0.0, 2.0, 0.0),
                axis: Vector3::x(),
                angle: std::f64::consts::PI,
            }],
        };
        let p = traj.pose_at(2.0);
        assert!((p.translation.vector - Vector3::new(1.0, 1.0, 0.0)).norm() < 1e-12);
        assert!((p.rotation.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(traj.pose_at(0.0), traj.initial);
        assert!((traj.pose_at(10.0).translation.vector.y - 2.0).abs() < 1e-12);
    }
}
