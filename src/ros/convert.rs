//! Conversions between the simulation's geometry (nalgebra) and message types.

use crate::geometry::{Point3, Pose as SimPose};

use super::msgs::{Point, Pose, Quaternion};

/// A world point, m.
pub fn point(p: &Point3) -> Point {
    Point {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// A rigid transform as a `geometry_msgs/Pose` (unit quaternion).
pub fn pose(p: &SimPose) -> Pose {
    let q = p.rotation.quaternion();
    Pose {
        position: Point {
            x: p.translation.vector.x,
            y: p.translation.vector.y,
            z: p.translation.vector.z,
        },
        orientation: Quaternion {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        },
    }
}
