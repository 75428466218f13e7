//! Conversions between the simulation's geometry (nalgebra) and message types.

use crate::geometry::{Point3, Pose as SimPose};

use crate::wire::msgs::{Point, Pose, Quaternion, Transform, Vector3};

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

/// A pose as a transform message's translation and rotation.
pub fn to_transform(p: &SimPose) -> Transform {
    let q = p.rotation.quaternion();
    Transform {
        translation: Vector3 {
            x: p.translation.vector.x,
            y: p.translation.vector.y,
            z: p.translation.vector.z,
        },
        rotation: Quaternion {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        },
    }
}
