//! A simulated RGB-D camera, RealSense-style (issue 48): what a perception pipeline
//! (TrackDLO, CDCPD) sees of a scene.
//!
//! - [`Intrinsics`]: a pinhole with fx = fy from the vertical field of view and the
//!   principal point at the image centre, cx = (width - 1) / 2, cy = (height - 1) / 2:
//!   pixel (i, j) (column, row from the top left) has its centre at u = i, v = j, the
//!   convention of ROS `camera_info` K and OpenCV.
//! - Poses: [`look_at`] builds `world_from_optical` (optical frame: x right, y down, z
//!   forward; the image's up is the scene's +z projected); [`body_from_optical`] turns a
//!   REP 103 body frame (x forward, y left, z up, a `camera_link`) into the optical one.
//! - [`Renderer`]: a CPU z-buffer rasterizer of every object's surface mesh (both sides,
//!   in the tints of the offline pictures, [`tint`]) and of the colliders (half-spaces
//!   exactly per pixel by ray-plane intersection, balls and capsules exactly per pixel
//!   by ray casting, boxes and triangle meshes as triangles), split across threads by
//!   fixed bands of rows: bit-identical output for identical inputs at any thread
//!   count. Its [`Frame`] holds color (rgb8), depth (32FC1, m) and the organized point
//!   cloud (x y z rgb) in the byte layouts ROS messages carry.
//! - [`Noise`]: the RealSense D435 depth model, seeded per frame ([`NoiseKey`]).
//! - [`truth`]: an object's mesh vertices with their material (u, v), the ground truth a
//!   tracker is scored against.
//! - [`Snapshot`]: what a frame is rendered from (meshes and collider poses), copied
//!   from a [`World`](crate::sim::World) without allocating once warm, so rendering can
//!   run beside the simulation's next step.
//!
//! Pure: no I/O, no clocks; depth in metres, angles in radians.

mod frame;
mod noise;
mod prepare;
mod raster;
mod snapshot;
pub mod tint;
pub mod truth;

#[cfg(test)]
mod tests;

pub use frame::{Frame, CLOUD_FIELDS, CLOUD_POINT_STEP};
pub use noise::{Noise, NoiseKey, D435_BASELINE, D435_DROPOUT, D435_MIN_RANGE, D435_SUBPIXEL};
pub use raster::Renderer;
pub use snapshot::{world_colliders, Snapshot};

use crate::geometry::{Point3, Pose, Rotation, Vector3};

/// Why a camera could not be made.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CameraError {
    #[error("{0}")]
    Invalid(String),
}

/// The pinhole model and depth range of a camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intrinsics {
    /// Image width, px (1..=[`MAX_SIDE`]).
    pub width: u32,
    /// Image height, px (1..=[`MAX_SIDE`]).
    pub height: u32,
    /// Vertical field of view, rad, in (0, pi): from the top edge of the image to the
    /// bottom edge.
    pub fov_y: f64,
    /// Nearest depth, m (> 0): surfaces nearer are cut away, as a z-buffer's near plane.
    pub near: f64,
    /// Farthest depth, m (> near): depth beyond it is NaN (the colour still shows it).
    pub far: f64,
}

/// The largest image side accepted, px (as `render --size`; an 8192 x 8192 frame holds
/// 2 GB of buffers, 31 bytes a pixel).
pub const MAX_SIDE: u32 = 8192;

impl Intrinsics {
    /// Checked intrinsics (see the fields for the ranges).
    pub fn new(
        width: u32,
        height: u32,
        fov_y: f64,
        near: f64,
        far: f64,
    ) -> Result<Intrinsics, CameraError> {
        let bad = |m: String| Err(CameraError::Invalid(m));
        if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
            return bad(format!(
                "image size {width} x {height} px: each side must be in 1..={MAX_SIDE}"
            ));
        }
        if !(fov_y > 0.0 && fov_y < std::f64::consts::PI) {
            return bad(format!("fov_y {fov_y} rad must be in (0, pi)"));
        }
        if !(near > 0.0 && near.is_finite()) {
            return bad(format!("near {near} m must be > 0"));
        }
        if !(far > near && far.is_finite()) {
            return bad(format!("far {far} m must be finite and > near ({near} m)"));
        }
        Ok(Intrinsics {
            width,
            height,
            fov_y,
            near,
            far,
        })
    }

    /// Focal length f = fx = fy, px: the image height spans fov_y, so
    /// f = (height / 2) / tan(fov_y / 2).
    pub fn focal(&self) -> f64 {
        0.5 * self.height as f64 / (0.5 * self.fov_y).tan()
    }

    /// Principal point (cx, cy), px: the image centre, ((width - 1) / 2, (height - 1) / 2)
    /// in the convention where pixel i's centre is at u = i.
    pub fn principal_point(&self) -> [f64; 2] {
        [
            0.5 * (self.width as f64 - 1.0),
            0.5 * (self.height as f64 - 1.0),
        ]
    }

    /// The camera matrix K, row-major (`camera_info.k`); P is [K | 0] and R the identity
    /// (no distortion: `plumb_bob` with D = 0).
    pub fn k(&self) -> [f64; 9] {
        let f = self.focal();
        let [cx, cy] = self.principal_point();
        [f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0]
    }

    /// Where the optical-frame point `p` appears, (u, v) px; None when it is not in
    /// front of the camera (z <= 0).
    pub fn project(&self, p: &Point3) -> Option<[f64; 2]> {
        if !(p.z > 0.0) {
            return None;
        }
        let f = self.focal();
        let [cx, cy] = self.principal_point();
        Some([f * (p.x / p.z) + cx, f * (p.y / p.z) + cy])
    }

    /// The ray through (u, v) px, scaled to unit depth: (x / z, y / z, 1) in the optical
    /// frame. A point at depth z on it is z times this.
    pub fn ray(&self, u: f64, v: f64) -> Vector3 {
        let f = self.focal();
        let [cx, cy] = self.principal_point();
        Vector3::new((u - cx) / f, (v - cy) / f, 1.0)
    }
}

/// `world_from_optical` of a camera at `position` looking at `target` (both m, in the
/// world): the optical z axis points at the target, the image's up (-y) is the world's
/// +z projected onto the image plane; looking exactly along +z or -z, where that
/// projection vanishes, the image's up is the world's +y.
pub fn look_at(position: Vector3, target: Vector3) -> Result<Pose, CameraError> {
    if !position.iter().chain(target.iter()).all(|x| x.is_finite()) {
        return Err(CameraError::Invalid(
            "position and look_at must be finite".into(),
        ));
    }
    let forward = target - position;
    let len = forward.norm();
    if !(len > 0.0) {
        return Err(CameraError::Invalid(
            "look_at must differ from the position".into(),
        ));
    }
    let z = forward / len;
    let mut up = Vector3::z() - z * z.z;
    if up.norm() < 1e-9 {
        up = Vector3::y() - z * z.y;
    }
    let y = -up.normalize();
    let x = y.cross(&z);
    let m = nalgebra::Matrix3::from_columns(&[x, y, z]);
    Ok(Pose::from_parts(position.into(), orthonormal(m)))
}

/// `body_from_optical`: the fixed rotation from a camera's optical frame (x right, y
/// down, z forward) to its REP 103 body frame (x forward, y left, z up), as between a
/// RealSense's `camera_link` and `camera_color_optical_frame`. A camera mounted on TF
/// frame B has `world_from_optical = world_from_B * body_from_optical()`.
pub fn body_from_optical() -> Pose {
    // columns: the optical axes in the body frame (x_opt = -y_body, y_opt = -z_body,
    // z_opt = x_body)
    let m = nalgebra::Matrix3::from_columns(&[-Vector3::y(), -Vector3::z(), Vector3::x()]);
    Pose::from_parts(nalgebra::Translation3::identity(), orthonormal(m))
}

/// The rotation of a matrix whose columns are orthonormal by construction (exactly, not
/// by an iterative fit).
fn orthonormal(m: nalgebra::Matrix3<f64>) -> Rotation {
    Rotation::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(m))
}

/// A camera: its intrinsics and noise model (its pose is given per frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub intrinsics: Intrinsics,
    pub noise: Noise,
}

#[cfg(test)]
mod pose_tests {
    use super::*;

    #[test]
    fn intrinsics_follow_the_field_of_view_and_the_centre() {
        let c = Intrinsics::new(640, 480, 0.75, 0.1, 4.0).unwrap();
        let f = 240.0 / 0.375f64.tan();
        assert_eq!(c.focal(), f);
        assert_eq!(c.principal_point(), [319.5, 239.5]);
        assert_eq!(c.k(), [f, 0.0, 319.5, 0.0, f, 239.5, 0.0, 0.0, 1.0]);
        // the top edge of the image (v = -0.5) is fov_y / 2 above the axis
        let top = c.ray(319.5, -0.5);
        assert!((top.y.atan() + 0.375).abs() < 1e-15, "{}", top.y.atan());
        let p = Point3::new(0.2, -0.1, 2.0);
        let [u, v] = c.project(&p).unwrap();
        assert!((c.ray(u, v) * 2.0 - p.coords).norm() < 1e-15);
        assert_eq!(c.project(&Point3::new(0.0, 0.0, 0.0)), None);
    }

    #[test]
    fn bad_intrinsics_are_refused() {
        for (w, h, fov, near, far) in [
            (0, 480, 0.75, 0.1, 4.0),
            (640, 8193, 0.75, 0.1, 4.0),
            (640, 480, 0.0, 0.1, 4.0),
            (640, 480, 3.2, 0.1, 4.0),
            (640, 480, f64::NAN, 0.1, 4.0),
            (640, 480, 0.75, 0.0, 4.0),
            (640, 480, 0.75, 0.1, 0.1),
            (640, 480, 0.75, 0.1, f64::INFINITY),
        ] {
            assert!(
                Intrinsics::new(w, h, fov, near, far).is_err(),
                "{w} {h} {fov} {near} {far}"
            );
        }
    }

    #[test]
    fn look_at_points_z_at_the_target_with_the_world_up_on_top() {
        let eye = Vector3::new(0.5, -0.8, 0.6);
        let target = Vector3::new(0.5, 0.0, 0.1);
        let pose = look_at(eye, target).unwrap();
        let r = pose.rotation.to_rotation_matrix();
        let (x, y, z) = (
            r.matrix().column(0).into_owned(),
            r.matrix().column(1).into_owned(),
            r.matrix().column(2).into_owned(),
        );
        assert!((z - (target - eye).normalize()).norm() < 1e-15);
        // image up (-y) has a positive world z; right (x) is horizontal
        assert!(-y.z > 0.0 && x.z.abs() < 1e-15, "{x} {y}");
        // looking along +y with z up: right is +x
        assert!((x - Vector3::x()).norm() < 1e-15);
        assert!((x.cross(&y) - z).norm() < 1e-15);
        assert_eq!(pose.translation.vector, eye);
        // straight down: up is +y of the world
        let down = look_at(Vector3::new(0.0, 0.0, 1.0), Vector3::zeros()).unwrap();
        let y = down.rotation * Vector3::y();
        assert!((y + Vector3::y()).norm() < 1e-15, "{y}");
        assert!(look_at(eye, eye).is_err());
        assert!(look_at(eye, Vector3::new(f64::NAN, 0.0, 0.0)).is_err());
    }

    #[test]
    fn the_body_frame_looks_along_its_x() {
        let b = body_from_optical();
        assert!((b.rotation * Vector3::z() - Vector3::x()).norm() < 1e-15);
        assert!((b.rotation * Vector3::y() + Vector3::z()).norm() < 1e-15);
        assert!((b.rotation * Vector3::x() + Vector3::y()).norm() < 1e-15);
    }
}
