//! Spatial twists: the velocity field of a rigid motion, `v(p) = angular × p + linear`.

use super::{Point3, Vector3};

/// A spatial twist in world coordinates: the velocity of world point `p` is
/// `angular.cross(p) + linear` (rad/s and m/s per unit of the generalized coordinate).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Twist {
    pub angular: Vector3,
    pub linear: Vector3,
}

impl Twist {
    /// Rotation with unit rate about the line through `point_in_world` along `axis`.
    pub fn rotation_about(axis: Vector3, point_in_world: &Point3) -> Twist {
        Twist {
            angular: axis,
            linear: point_in_world.coords.cross(&axis),
        }
    }

    /// The twist as a 6-vector `[angular; linear]`.
    #[inline]
    pub fn to_array(&self) -> [f64; 6] {
        [
            self.angular.x,
            self.angular.y,
            self.angular.z,
            self.linear.x,
            self.linear.y,
            self.linear.z,
        ]
    }
}
