//! The messages of the simulated RGB-D cameras (issue 48), RealSense-style: what a
//! drawn frame becomes (`rgb8` colour, `32FC1` depth aligned to it, their camera_info,
//! the organized x y z rgb cloud), the optical frames on `/tf_static`, and each
//! object's ground truth on `/<object>/points`. The producers of the camera rows of
//! [`super::outputs::OUTPUTS`]; `session::camera` says when frames are captured and
//! drawn.

use crate::camera::truth::{fill_mesh_points, TRUTH_FIELDS, TRUTH_POINT_STEP};
use crate::camera::{self, CLOUD_FIELDS, CLOUD_POINT_STEP};
use crate::scene::{CameraMount, SceneCamera};
use crate::wire::cdr::{self, CdrError};
use crate::wire::convert::to_transform;
use crate::wire::msgs::{
    float32_fields, CameraInfo, Header, ImageRef, PointCloud2, PointCloud2Ref, TFMessage, Time,
    TransformStamped,
};

use super::produce::{Produce, Scope};

/// What a camera row's message is made from: the camera, the stamp of the captured
/// state and the drawn frame (None: not drawn; the rows carrying pixels are left out).
pub struct CameraView<'a> {
    pub camera: &'a SceneCamera,
    pub stamp: Time,
    pub drawn: Option<&'a camera::Frame>,
}

impl CameraView<'_> {
    fn header(&self) -> Header {
        Header {
            stamp: self.stamp,
            frame_id: self.camera.optical_frame(),
        }
    }
}

/// Room for a message of `data` bytes: the header and fields fit in 256 bytes.
fn sized(data: usize) -> usize {
    data + 256
}

/// `/<camera>/color/image_raw`: `rgb8`, 3 bytes a pixel.
pub fn color(v: &CameraView) -> Option<Result<Vec<u8>, CdrError>> {
    let f = v.drawn?;
    image(v, "rgb8", 3, &f.color)
}

/// `/<camera>/aligned_depth_to_color/image_raw`: `32FC1`, m along the optical axis,
/// NaN where nothing is hit.
pub fn depth(v: &CameraView) -> Option<Result<Vec<u8>, CdrError>> {
    let f = v.drawn?;
    image(v, "32FC1", 4, &f.depth)
}

fn image(
    v: &CameraView,
    encoding: &str,
    bytes_per_pixel: u32,
    data: &[u8],
) -> Option<Result<Vec<u8>, CdrError>> {
    let i = v.camera.camera.intrinsics;
    let header = v.header();
    let m = ImageRef {
        header: &header,
        height: i.height,
        width: i.width,
        encoding,
        is_bigendian: 0,
        step: bytes_per_pixel * i.width,
        data,
    };
    Some(cdr::encode_sized(&m, sized(data.len())))
}

/// `/<camera>/depth/color/points`: organized (height x width), x y z rgb float32, NaN
/// points where the depth is NaN (`is_dense` false).
pub fn cloud(v: &CameraView) -> Option<Result<Vec<u8>, CdrError>> {
    let f = v.drawn?;
    let i = v.camera.camera.intrinsics;
    let header = v.header();
    let fields = float32_fields(&CLOUD_FIELDS);
    let m = PointCloud2Ref {
        header: &header,
        height: i.height,
        width: i.width,
        fields: &fields,
        is_bigendian: false,
        point_step: CLOUD_POINT_STEP as u32,
        row_step: CLOUD_POINT_STEP as u32 * i.width,
        data: &f.cloud,
        is_dense: false,
    };
    Some(cdr::encode_sized(&m, sized(f.cloud.len())))
}

/// `/<camera>/color/camera_info` and `/<camera>/aligned_depth_to_color/camera_info`
/// (the depth is aligned to the colour: one pinhole): K, P = [K | 0], R = I,
/// `plumb_bob` with D = 0.
pub fn camera_info(v: &CameraView) -> Option<Result<Vec<u8>, CdrError>> {
    let i = v.camera.camera.intrinsics;
    let k = i.k();
    let m = CameraInfo {
        header: v.header(),
        height: i.height,
        width: i.width,
        distortion_model: "plumb_bob".into(),
        d: vec![0.0; 5],
        k,
        r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        p: [
            k[0], k[1], k[2], 0.0, k[3], k[4], k[5], 0.0, k[6], k[7], k[8], 0.0,
        ],
        ..CameraInfo::default()
    };
    Some(cdr::encode(&m))
}

/// `/tf_static`: each camera's `<name>_color_optical_frame` (x right, y down, z
/// forward), in the initial state (start-up and after a reset; the topic is latched). A
/// fixed camera's parent is the scene frame; a camera carried by a TF frame has that
/// frame as parent with the constant `camera::body_from_optical`, as a RealSense's
/// `camera_link` -> `camera_color_optical_frame`.
pub fn optical_frames(p: &Produce, _: Scope) -> Option<TFMessage> {
    if p.report.is_some() || p.scene.cameras.is_empty() {
        return None;
    }
    let transforms = p
        .scene
        .cameras
        .iter()
        .map(|cam| {
            let (parent, pose) = match &cam.mount {
                CameraMount::Fixed(pose) => (p.scene.frame_id.clone(), *pose),
                CameraMount::TfFrame(f) => (f.clone(), camera::body_from_optical()),
            };
            TransformStamped {
                header: Header {
                    stamp: p.stamp(),
                    frame_id: parent,
                },
                child_frame_id: cam.optical_frame(),
                transform: to_transform(&pose),
            }
        })
        .collect();
    Some(TFMessage { transforms })
}

/// `/<object>/points`: the object's mesh vertices, x y z (scene frame) and u v
/// (material), float32, m: an unorganized cloud (height 1); none for a mesh that is not
/// finite.
pub fn mesh_points(p: &Produce, scope: Scope) -> Option<PointCloud2> {
    let Scope::Object(o) = scope else {
        return None;
    };
    let mesh = p.scene.world.mesh(o);
    if !mesh.is_finite() {
        return None;
    }
    let mut data = Vec::with_capacity(TRUTH_POINT_STEP * mesh.vertices.len());
    let n = fill_mesh_points(mesh, &mut data) as u32;
    Some(PointCloud2 {
        header: p.header(),
        height: 1,
        width: n,
        fields: float32_fields(&TRUTH_FIELDS),
        is_bigendian: false,
        point_step: TRUTH_POINT_STEP as u32,
        row_step: TRUTH_POINT_STEP as u32 * n,
        data,
        is_dense: true,
    })
}
