//! Handles (grippers) and their scripted trajectories.
//!
//! A handle grasps one object at a material point and drives it towards a target pose
//! `world_from_gripper`. Targets come from outside (a ROS topic) or, when nobody
//! publishes, from the scripted [`Trajectory`].

use crate::geometry::{Point2, Point3, Pose, Rotation, Vector3};

/// What a handle constrains on the object it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct HandleSpec {
    /// Name (the ROS topic default is `/handles/<name>`).
    pub name: String,
    /// Index of the object it holds in the world.
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
