//! Small shared geometry: rigid frames, rotations, twists, triangle meshes.
//!
//! Everything here is in SI units (m, rad) and frame names follow
//! `target_from_source` (a `world_from_element` maps element coordinates to world).
//! Pure math: no I/O, no serde.

mod mesh;
mod rotation;
mod twist;

pub use mesh::{EdgeStrain, SurfaceMesh, SurfacePoint, VertexRegion, STRAIN_THRESHOLD};
pub use rotation::{exp_so3, left_jacobian_so3, log_so3, skew};
pub use twist::Twist;

/// A rigid transform (rotation + translation), metres.
pub type Pose = nalgebra::Isometry3<f64>;
pub type Point3 = nalgebra::Point3<f64>;
pub type Vector3 = nalgebra::Vector3<f64>;
pub type Point2 = nalgebra::Point2<f64>;
pub type Matrix3 = nalgebra::Matrix3<f64>;
pub type Rotation = nalgebra::UnitQuaternion<f64>;
