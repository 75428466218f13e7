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

/// A `geometry_msgs/Pose` that [`pose`] wrote, back as the rigid transform it came
/// from, bit for bit (the quaternion is taken as it is, not normalized again).
pub fn from_pose(p: &Pose) -> SimPose {
    let o = &p.orientation;
    SimPose::from_parts(
        nalgebra::Translation3::new(p.position.x, p.position.y, p.position.z),
        nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(o.w, o.x, o.y, o.z)),
    )
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pose_comes_back_bit_for_bit() {
        let p = SimPose::new(
            nalgebra::Vector3::new(0.45, -0.95, 0.35),
            nalgebra::Vector3::new(1.3, -0.2, 0.7),
        );
        let back = from_pose(&pose(&p));
        assert_eq!(back.translation.vector, p.translation.vector);
        assert_eq!(back.rotation.coords, p.rotation.coords);
        // normalizing again would not always be the identity: the exact way is needed
        assert_ne!(back, SimPose::identity());
    }
}
