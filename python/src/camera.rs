//! `Simulation.render_depth(camera)`: a scene camera's colour, depth and points as
//! NumPy arrays, rendered by the core's camera (`developable_core::camera`,
//! docs/camera.md) exactly as `developable_sim render --camera` and the node do.

use developable_sim::camera::{self, world_colliders, Frame, Renderer, Snapshot};
use developable_sim::geometry::Pose;
use developable_sim::scene::{CameraMount, Scene as LoadedScene};
use developable_sim::sim::World;
use numpy::prelude::*;
use numpy::{PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;

use crate::state::matrix;

/// One rendered frame (docs/camera.md has the conventions).
#[pyclass(module = "developable_sim", name = "CameraFrame", frozen, get_all)]
pub struct CameraFrame {
    /// The camera's name in the scene.
    camera: String,
    /// Simulation time of the frame, s.
    time: f64,
    /// Index of the frame in the camera's stream, floor(time rate): the noise key.
    index: u64,
    /// (H, W, 3) uint8 colour, rows from the top, `rgb8`.
    color: Py<PyArray3<u8>>,
    /// (H, W) float32 depth along the optical axis, m; NaN where nothing is hit or
    /// outside [near, far].
    depth: Py<PyArray2<f32>>,
    /// (H, W, 3) float32 points in the optical frame (x right, y down, z forward), m:
    /// the depth back-projected through K; NaN where the depth is.
    points: Py<PyArray3<f32>>,
    /// (3, 3) intrinsics K (row-major, as ROS `camera_info`), px.
    k: Py<PyArray2<f64>>,
    /// (4, 4) `world_from_optical` (homogeneous, m).
    world_from_optical: Py<PyArray2<f64>>,
}

/// Renderers of a simulation's cameras, built on first use (the colliders' shapes are
/// copied in, so they are rebuilt after a reset), and the snapshot they draw from.
#[derive(Default)]
pub struct Cameras {
    renderers: Vec<Option<Renderer>>,
    snapshot: Snapshot,
}

impl Clone for Cameras {
    /// A fresh cache: renderers are rebuilt on first use.
    fn clone(&self) -> Self {
        Cameras::default()
    }
}

/// What a render is asked for, resolved before the GIL is released.
pub struct Request {
    pub index: usize,
    pub world_from_optical: Pose,
}

impl Cameras {
    /// Forget the renderers (after a reset: the colliders may differ).
    pub fn clear(&mut self) {
        self.renderers.clear();
    }

    /// Which camera `name` is and where it looks from: its fixed mount, or
    /// `world_from_body` (a REP 103 body frame: x forward, y left, z up) when given,
    /// which a camera mounted on a TF frame needs.
    pub fn request(
        scene: &LoadedScene,
        name: &str,
        world_from_body: Option<Pose>,
    ) -> Result<Request, String> {
        let Some(index) = scene.cameras.iter().position(|c| c.name == name) else {
            let known: Vec<&str> = scene.cameras.iter().map(|c| c.name.as_str()).collect();
            return Err(format!(
                "no camera `{name}` in this scene (cameras: {})",
                if known.is_empty() {
                    "none".into()
                } else {
                    known.join(", ")
                }
            ));
        };
        let world_from_optical = match (world_from_body, &scene.cameras[index].mount) {
            (Some(body), _) => body * camera::body_from_optical(),
            (None, CameraMount::Fixed(pose)) => *pose,
            (None, CameraMount::TfFrame(frame)) => {
                return Err(format!(
                    "camera `{name}` rides on the TF frame `{frame}`: pass its pose, \
                     render_depth(\"{name}\", pose=(position, quaternion))"
                ))
            }
        };
        Ok(Request {
            index,
            world_from_optical,
        })
    }

    /// Render the request's camera at the world's current state (the GIL is released
    /// around this): the frame index floor(t rate) keys the noise, with the scene's
    /// seed, as `render --camera` does.
    pub fn render(&mut self, scene: &LoadedScene, world: &World, r: &Request) -> (u64, &Frame) {
        let cam = &scene.cameras[r.index];
        if self.renderers.len() < scene.cameras.len() {
            self.renderers.resize_with(scene.cameras.len(), || None);
        }
        let renderer = self.renderers[r.index]
            .get_or_insert_with(|| Renderer::new(cam.camera, world_colliders(world)));
        self.snapshot.capture(world);
        // a tick lands on t = k / rate: a nanosecond's slack for the rounding of t
        let index = (world.time() * cam.rate + 1e-9).floor().max(0.0) as u64;
        let key = cam.noise_key(scene.source.seed, index);
        (
            index,
            renderer.render(&self.snapshot, &r.world_from_optical, &key),
        )
    }
}

/// A rendered frame as NumPy arrays.
pub fn frame_to_py(
    py: Python<'_>,
    scene: &LoadedScene,
    r: &Request,
    time: f64,
    index: u64,
    frame: &Frame,
) -> PyResult<CameraFrame> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let f32s = |bytes: &[u8], stride: usize, take: usize| -> Vec<f32> {
        bytes
            .chunks_exact(stride)
            .flat_map(|p| {
                (0..take).map(move |c| {
                    f32::from_le_bytes([p[4 * c], p[4 * c + 1], p[4 * c + 2], p[4 * c + 3]])
                })
            })
            .collect()
    };
    let depth = f32s(&frame.depth, 4, 1);
    let points = f32s(&frame.cloud, camera::CLOUD_POINT_STEP, 3);
    let k = scene.cameras[r.index].camera.intrinsics.k().to_vec();
    let m = r.world_from_optical.to_homogeneous();
    let m: Vec<f64> = (0..4)
        .flat_map(|i| (0..4).map(move |j| m[(i, j)]))
        .collect();
    Ok(CameraFrame {
        camera: scene.cameras[r.index].name.clone(),
        time,
        index,
        color: PyArray1::from_slice(py, &frame.color)
            .reshape([h, w, 3])?
            .unbind(),
        depth: matrix(py, depth, w)?,
        points: PyArray1::from_vec(py, points).reshape([h, w, 3])?.unbind(),
        k: matrix(py, k, 3)?,
        world_from_optical: matrix(py, m, 4)?,
    })
}

#[pymethods]
impl CameraFrame {
    fn __repr__(&self, py: Python<'_>) -> String {
        let shape = self.depth.bind(py).shape().to_vec();
        format!(
            "CameraFrame(camera={:?}, time={}, index={}, shape={:?})",
            self.camera, self.time, self.index, shape
        )
    }
}
