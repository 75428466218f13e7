//! The simulated RGB-D cameras of a session (issue 48): when each camera's ticks fall
//! due, the frames captured for drawing, and the messages of a drawn frame (the
//! RealSense topics), plus the optical frames on `/tf_static` and each object's ground
//! truth on `/<object>/points`.
//!
//! A camera never delays a step: a capture copies what the camera sees
//! ([`Snapshot`]) and the drawing happens elsewhere (the node's camera threads,
//! `replay`, `run --record`). Which ticks were captured is a command
//! ([`super::Command::Capture`]): the node captures a tick's frame when the camera is
//! done drawing the previous one, and a tick that finds it still drawing is skipped and
//! counted (`SimStatus.camera_frames_skipped`). Replaying the recorded captures
//! reproduces the same frames, bit for bit: a frame depends on the captured state, the
//! pose it is drawn from and its noise key (scene seed, camera, tick), nothing else.

use std::collections::VecDeque;
use std::marker::PhantomData;

use bytes::Bytes;

use crate::camera::truth::{fill_mesh_points, TRUTH_FIELDS, TRUTH_POINT_STEP};
use crate::camera::{self, Snapshot, CLOUD_FIELDS, CLOUD_POINT_STEP};
use crate::geometry::Pose;
use crate::scene::{CameraMount, Scene, SceneCamera};
use crate::wire::cdr::{self, CdrError};
use crate::wire::convert::to_transform;
use crate::wire::introspect::{to_value, Value};
use crate::wire::msgs::{
    float32_fields, CameraInfo, Header, ImageRef, PointCloud2, PointCloud2Ref, RosMessage,
    TFMessage, Time, TransformStamped,
};

use super::outputs::{Frame, OutputRow, Producer};
use super::produce::{Produce, Scope};

/// The newest tick of a camera at `rate` Hz that the state at time `t` (s) of a
/// simulation stepping `dt` (s) has reached: tick k, at k / rate, belongs to the first
/// state with t >= k / rate - dt / 2 (the state nearest to it, the earlier one on a
/// tie). At most one frame a state: ticks faster than the steps are passed over.
pub fn reached_tick(t: f64, dt: f64, rate: f64) -> u64 {
    let k = ((t + 0.5 * dt) * rate).floor();
    if k > 0.0 {
        k as u64
    } else {
        0
    }
}

/// A camera frame captured for drawing.
#[derive(Clone, Debug, PartialEq)]
pub struct Capture {
    /// The camera's index in the scene.
    pub camera: usize,
    /// Its tick k (at k / rate s of simulated time since the last reset): the noise
    /// key's frame.
    pub frame: u64,
    /// Simulated time of the captured state: the `header.stamp` of every message of
    /// the frame.
    pub stamp: Time,
    /// Steps taken to the captured state (since the last reset).
    pub step: u64,
    /// The pose it is drawn from (`world_from_optical`, m).
    pub world_from_optical: Pose,
    /// What it sees (None: no row of the session needs the pixels, only camera_info).
    pub snapshot: Option<Snapshot>,
}

impl Capture {
    /// The noise key of this frame in a scene seeded with `seed`.
    pub fn noise_key(&self, cam: &SceneCamera, seed: u64) -> camera::NoiseKey {
        cam.noise_key(seed, self.frame)
    }
}

/// The cameras' ticks and captures of a session.
#[derive(Clone, Debug, Default)]
pub struct Cameras {
    /// Per camera: the first tick not reached yet.
    next_tick: Vec<u64>,
    /// Per camera: the tick due at the current state, not captured yet.
    due: Vec<Option<u64>>,
    /// Per camera: captured frames not handed out yet, oldest first.
    pending: Vec<VecDeque<Capture>>,
    /// Per camera: whether a row of the session carries its pixels (a capture then
    /// copies what it sees).
    draws: Vec<bool>,
    /// Snapshots handed back after drawing, reused by the next captures.
    spare: Vec<Snapshot>,
}

impl Cameras {
    /// The cameras of `scene` with the outputs `rows` (a camera with no row is never
    /// due).
    pub fn new(scene: &Scene, rows: &[OutputRow]) -> Cameras {
        let n = scene.cameras.len();
        let has = |c: usize, draws: bool| {
            rows.iter().any(|r| {
                r.scope == Scope::Camera(c) && (!draws || r.kind.producer.draws())
            })
        };
        Cameras {
            next_tick: (0..n).map(|c| if has(c, false) { 0 } else { u64::MAX }).collect(),
            due: vec![None; n],
            pending: vec![VecDeque::new(); n],
            draws: (0..n).map(|c| has(c, true)).collect(),
            spare: Vec::new(),
        }
    }

    /// A new state of `scene`: the ticks it reaches fall due. Returns how many due ticks
    /// went without a capture (skipped).
    pub fn on_state(&mut self, scene: &Scene) -> u64 {
        let (t, dt) = (scene.world.time(), scene.world.dt());
        let mut skipped = 0;
        for (c, cam) in scene.cameras.iter().enumerate() {
            skipped += u64::from(self.due[c].take().is_some());
            if self.next_tick[c] == u64::MAX {
                continue;
            }
            let k = reached_tick(t, dt, cam.rate);
            if k >= self.next_tick[c] {
                self.due[c] = Some(k);
                self.next_tick[c] = k + 1;
            }
        }
        skipped
    }

    /// Back to t = 0: tick 0 comes again. Returns the due ticks skipped.
    pub fn restart(&mut self) -> u64 {
        let mut skipped = 0;
        for (next, due) in self.next_tick.iter_mut().zip(&mut self.due) {
            skipped += u64::from(due.take().is_some());
            if *next != u64::MAX {
                *next = 0;
            }
        }
        skipped
    }

    /// The tick of camera `camera` due at the current state, if not captured yet.
    pub fn due(&self, camera: usize) -> Option<u64> {
        self.due.get(camera).copied().flatten()
    }

    /// Capture the due frame of camera `camera` of `scene`, seen from
    /// `world_from_optical`; returns its tick (None: no tick of it is due).
    pub fn capture(
        &mut self,
        scene: &Scene,
        camera: usize,
        world_from_optical: &Pose,
    ) -> Option<u64> {
        let frame = self.due.get_mut(camera)?.take()?;
        let snapshot = self.draws[camera].then(|| {
            let mut s = self.spare.pop().unwrap_or_default();
            s.capture(&scene.world);
            s
        });
        self.pending[camera].push_back(Capture {
            camera,
            frame,
            stamp: Time::from_secs(scene.world.time()),
            step: scene.world.steps_taken(),
            world_from_optical: *world_from_optical,
            snapshot,
        });
        Some(frame)
    }

    /// The oldest captured frame of camera `camera` not handed out yet.
    pub fn take(&mut self, camera: usize) -> Option<Capture> {
        self.pending.get_mut(camera)?.pop_front()
    }

    /// Captured frames not handed out yet, all cameras.
    pub fn pending(&self) -> usize {
        self.pending.iter().map(VecDeque::len).sum()
    }

    /// A snapshot drawn from, for the next captures to reuse.
    pub fn recycle(&mut self, snapshot: Snapshot) {
        // one per camera in flight is all the node needs
        if self.spare.len() < 2 * self.draws.len() {
            self.spare.push(snapshot);
        }
    }
}

/// The fixed `world_from_optical` of `cam` (None: a camera carried by a TF frame, looked
/// up when it captures).
pub fn fixed_pose(cam: &SceneCamera) -> Option<Pose> {
    match &cam.mount {
        CameraMount::Fixed(p) => Some(*p),
        CameraMount::TfFrame(_) => None,
    }
}

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

/// The producer of a camera row: a message of type `M` from a [`CameraView`], encoded
/// (the frame's rows are made beside the tick, not from a state: [`Producer::produce`]
/// makes nothing).
pub struct Drawn<M: 'static> {
    /// The message carries the pixels (a capture must copy what the camera sees).
    pub draws: bool,
    pub make: fn(&CameraView) -> Option<Result<Vec<u8>, CdrError>>,
    pub message: PhantomData<fn() -> M>,
}

impl<M> std::fmt::Debug for Drawn<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Drawn<{}>", std::any::type_name::<M>())
    }
}

impl<M: RosMessage> Producer for Drawn<M> {
    fn type_name(&self) -> &'static str {
        M::TYPE
    }
    fn type_hash(&self) -> &'static str {
        M::HASH
    }
    fn schema(&self) -> String {
        M::schema()
    }
    fn produce(&self, _: &Produce, _: Scope) -> Option<Result<Bytes, CdrError>> {
        None
    }
    fn value(&self, bytes: &[u8]) -> Result<Value, String> {
        let m: M = cdr::decode(bytes).map_err(|e| format!("{}: {e}", M::TYPE))?;
        to_value(&m).map_err(|e| format!("{}: {e}", M::TYPE))
    }
    fn camera(&self, view: &CameraView) -> Option<Result<Bytes, CdrError>> {
        (self.make)(view).map(|r| r.map(Bytes::from))
    }
    fn draws(&self) -> bool {
        self.draws
    }
}

/// The messages of camera `camera`'s frame `view`: one per row of `rows` that belongs
/// to it, in a frame of every row (the others empty).
pub fn camera_frame(rows: &[OutputRow], camera: usize, view: &CameraView) -> Result<Frame, CdrError> {
    let mut messages = Vec::with_capacity(rows.len());
    for row in rows {
        let m = match row.scope == Scope::Camera(camera) {
            true => row.kind.producer.camera(view).transpose()?,
            false => None,
        };
        messages.push(m);
    }
    Ok(Frame {
        stamp: view.stamp,
        messages,
    })
}

/// Draw `capture` of camera `cam` with `renderer` (when it carries a snapshot: the
/// noise of its tick in a scene seeded with `seed`) and encode its messages for `rows`
/// (see [`camera_frame`]). Draws on the calling thread's rayon pool: the bytes do not
/// depend on its size.
pub fn draw_frame(
    renderer: &mut camera::Renderer,
    (cam, seed): (&SceneCamera, u64),
    rows: &[OutputRow],
    capture: &Capture,
) -> Result<Frame, CdrError> {
    let key = capture.noise_key(cam, seed);
    let drawn = match &capture.snapshot {
        Some(s) => Some(&*renderer.render(s, &capture.world_from_optical, &key)),
        None => None,
    };
    let view = CameraView {
        camera: cam,
        stamp: capture.stamp,
        drawn,
    };
    camera_frame(rows, capture.camera, &view)
}

/// A renderer for camera `cam` of `scene` (the scene's colliders copied in).
pub fn renderer(scene: &Scene, cam: &SceneCamera) -> camera::Renderer {
    camera::Renderer::new(cam.camera, camera::world_colliders(&scene.world))
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
