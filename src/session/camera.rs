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

use crate::camera::{self, Snapshot};
use crate::contact::Collider;
use crate::geometry::Pose;
use crate::scene::{CameraMount, Scene, SceneCamera};
use crate::wire::cdr::CdrError;
use crate::wire::msgs::Time;

use super::outputs::{Frame, OutputRow};
use super::produce::Scope;
use super::sensor::CameraView;

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
    /// The world's colliders, when they changed since this camera's previous capture (a
    /// robot's links arrived or changed): its renderer is made anew with them.
    pub colliders: Option<Vec<Collider>>,
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
    /// Per camera: the colliders its renderer has (the world's at its last capture).
    colliders: Vec<Vec<Collider>>,
}

impl Cameras {
    /// The cameras of `scene` with the outputs `rows` (a camera with no row is never
    /// due).
    pub fn new(scene: &Scene, rows: &[OutputRow]) -> Cameras {
        let n = scene.cameras.len();
        let has = |c: usize, draws: bool| {
            rows.iter()
                .any(|r| r.scope == Scope::Camera(c) && (!draws || r.kind.producer.draws()))
        };
        Cameras {
            next_tick: (0..n)
                .map(|c| if has(c, false) { 0 } else { u64::MAX })
                .collect(),
            due: vec![None; n],
            pending: vec![VecDeque::new(); n],
            draws: (0..n).map(|c| has(c, true)).collect(),
            spare: Vec::new(),
            colliders: vec![camera::world_colliders(&scene.world).to_vec(); n],
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
    /// `world_from_optical` and stamped `stamp` (the state's, after the time origin of
    /// an external clock); returns its tick (None: no tick of it is due).
    pub fn capture(
        &mut self,
        scene: &Scene,
        camera: usize,
        world_from_optical: &Pose,
        stamp: Time,
    ) -> Option<u64> {
        let frame = self.due.get_mut(camera)?.take()?;
        let snapshot = self.draws[camera].then(|| {
            let mut s = self.spare.pop().unwrap_or_default();
            s.capture(&scene.world);
            s
        });
        let now = camera::world_colliders(&scene.world);
        let colliders = (snapshot.is_some() && self.colliders[camera] != now).then(|| {
            self.colliders[camera] = now.to_vec();
            self.colliders[camera].clone()
        });
        self.pending[camera].push_back(Capture {
            camera,
            frame,
            stamp,
            step: scene.world.steps_taken(),
            world_from_optical: *world_from_optical,
            snapshot,
            colliders,
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

/// The messages of camera `camera`'s frame `view`: one per row of `rows` that belongs
/// to it, in a frame of every row (the others empty).
pub fn camera_frame(
    rows: &[OutputRow],
    camera: usize,
    view: &CameraView,
) -> Result<Frame, CdrError> {
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
/// noise of its tick in a scene seeded with `seed`; the renderer made anew first when
/// the colliders changed) and encode its messages for `rows`
/// (see [`camera_frame`]). Draws on the calling thread's rayon pool: the bytes do not
/// depend on its size.
pub fn draw_frame(
    renderer: &mut camera::Renderer,
    (cam, seed): (&SceneCamera, u64),
    rows: &[OutputRow],
    capture: &Capture,
) -> Result<Frame, CdrError> {
    if let Some(colliders) = &capture.colliders {
        *renderer = camera::Renderer::new(cam.camera, colliders);
    }
    let key = capture.noise_key(cam, seed);
    let drawn =
        (capture.snapshot.as_ref()).map(|s| renderer.render(s, &capture.world_from_optical, &key));
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

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::session::names::NodeNames;
    use crate::session::outputs::{OutputTable, RunOutputs};
    use crate::wire::convert::to_transform;
    use crate::wire::msgs::{CameraInfo, Image, PointCloud2, TFMessage};

    fn scene(name: &str, sets: &[&str]) -> Scene {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("config/scenes")
            .join(format!("{name}.yaml"));
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        crate::scene::load(&path, &sets).unwrap()
    }

    fn table(s: &Scene, record_cameras: bool) -> OutputTable {
        let names = NodeNames::resolve(s, "developable_sim", "/", &[]).unwrap();
        let run = RunOutputs {
            own_clock: true,
            recording: true,
            record_cameras,
        };
        OutputTable::for_scene(s, &names, run).unwrap()
    }

    #[test]
    fn each_tick_falls_on_the_state_nearest_to_it() {
        // dt 0.01 s at 15 Hz: over 1 s ticks 0..=15, each once, within dt/2 of k / 15
        let dt = 0.01;
        let mut ticks: Vec<(u64, f64)> = Vec::new();
        for n in 0..=100 {
            let t = n as f64 * dt;
            let k = reached_tick(t, dt, 15.0);
            if ticks.last().is_none_or(|l| l.0 != k) {
                ticks.push((k, t));
            }
        }
        let ks: Vec<u64> = ticks.iter().map(|t| t.0).collect();
        assert_eq!(ks, (0..=15).collect::<Vec<_>>());
        for (k, t) in ticks {
            assert!((t - k as f64 / 15.0).abs() <= 0.5 * dt + 1e-12, "{k} {t}");
        }
        // faster than the steps: the newest tick of the state, the others passed over
        assert_eq!(reached_tick(0.1, 0.1, 25.0), 3);
        assert_eq!(reached_tick(-1.0, 0.01, 15.0), 0);
    }

    #[test]
    fn a_due_tick_without_a_capture_by_the_next_state_is_skipped() {
        let mut s = scene("ribbon_gripper", &[]);
        let t = table(&s, false);
        let mut cams = Cameras::new(&s, &t.rows);
        assert_eq!(cams.on_state(&s), 0);
        assert_eq!(cams.due(0), Some(0));
        let pose = fixed_pose(&s.cameras[0]).unwrap();
        assert_eq!(
            cams.capture(&s, 0, &pose, Time::from_secs(s.world.time())),
            Some(0)
        );
        assert_eq!(
            cams.capture(&s, 0, &pose, Time::from_secs(s.world.time())),
            None,
            "a tick is captured once"
        );
        // ticks 1 and 2 fall on steps 7 (t = 0.07) and 13 (0.13); tick 1 not captured
        let targets = vec![None; s.world.handles().len()];
        let (mut skipped, mut dues) = (0, Vec::new());
        for _ in 0..13 {
            s.world.step(&targets);
            skipped += cams.on_state(&s);
            if let Some(k) = cams.due(0) {
                dues.push((k, s.world.steps_taken()));
            }
        }
        // a due tick is captured at its state or never
        assert_eq!(dues, [(1, 7), (2, 13)]);
        assert_eq!(skipped, 1, "tick 1 went by without a capture");
        // the capture of tick 0 waits, with what the camera saw at t = 0
        let c = cams.take(0).unwrap();
        assert_eq!((c.frame, c.step, c.stamp), (0, 0, Time::default()));
        assert!(c.snapshot.is_some(), "the images are published: drawn");
        assert!(cams.take(0).is_none());
        // a reset: the due tick 2 is lost (skipped), tick 0 comes again
        assert_eq!(cams.restart(), 1);
        s.world.reset();
        assert_eq!(cams.on_state(&s), 0);
        assert_eq!(cams.due(0), Some(0));
    }

    #[test]
    fn a_camera_whose_pixels_no_row_wants_captures_no_snapshot() {
        let s = scene("ribbon_gripper", &[]);
        let t = table(&s, false);
        // a replay of a bag recorded without --record-cameras: camera_info rows only
        let infos: Vec<OutputRow> = (t.rows.iter())
            .filter(|r| r.scope == Scope::Camera(0) && !r.kind.producer.draws())
            .cloned()
            .collect();
        assert_eq!(infos.len(), 2);
        let mut cams = Cameras::new(&s, &infos);
        cams.on_state(&s);
        let pose = fixed_pose(&s.cameras[0]).unwrap();
        assert_eq!(
            cams.capture(&s, 0, &pose, Time::from_secs(s.world.time())),
            Some(0)
        );
        assert_eq!(cams.take(0).unwrap().snapshot, None);
        // no camera row at all: never due
        let mut none = Cameras::new(&s, &[]);
        none.on_state(&s);
        assert_eq!(none.due(0), None);
    }

    /// The frame of tick 0 of `s`'s first camera, drawn on a pool of `threads`.
    fn drawn(s: &Scene, rows: &[OutputRow], threads: usize) -> Frame {
        let mut cams = Cameras::new(s, rows);
        cams.on_state(s);
        let pose = fixed_pose(&s.cameras[0]).unwrap();
        cams.capture(s, 0, &pose, Time::from_secs(s.world.time()))
            .unwrap();
        let capture = cams.take(0).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut r = renderer(s, &s.cameras[0]);
        pool.install(|| draw_frame(&mut r, (&s.cameras[0], s.source.seed), rows, &capture))
            .unwrap()
    }

    #[test]
    fn the_five_messages_share_one_stamp_and_frame_and_carry_the_drawn_buffers() {
        let s = scene("ribbon_gripper_push", &[]);
        let t = table(&s, true);
        let f = drawn(&s, &t.rows, 2);
        let row = |kind: &str| t.find(kind, Scope::Camera(0)).unwrap();
        let color: Image = f.decode(row("camera_color")).unwrap().unwrap();
        let depth: Image = f.decode(row("camera_depth")).unwrap().unwrap();
        let info: CameraInfo = f.decode(row("camera_color_info")).unwrap().unwrap();
        let info_d: CameraInfo = f.decode(row("camera_depth_info")).unwrap().unwrap();
        let cloud: PointCloud2 = f.decode(row("camera_points")).unwrap().unwrap();
        let headers = [
            &color.header,
            &depth.header,
            &info.header,
            &info_d.header,
            &cloud.header,
        ];
        for h in headers {
            assert_eq!(h.frame_id, "camera_color_optical_frame");
            assert_eq!(h.stamp, f.stamp);
        }
        assert_eq!(info, info_d, "the depth is aligned to the colour");
        // draw the same state again, directly: the messages carry its buffers
        let mut r = renderer(&s, &s.cameras[0]);
        let mut snap = Snapshot::default();
        snap.capture(&s.world);
        let pose = fixed_pose(&s.cameras[0]).unwrap();
        let want = r.render(&snap, &pose, &s.cameras[0].noise_key(s.source.seed, 0));
        assert_eq!((color.encoding.as_str(), color.step), ("rgb8", 3 * 640));
        assert_eq!((depth.encoding.as_str(), depth.step), ("32FC1", 4 * 640));
        assert_eq!(
            (color.width, color.height, depth.width, depth.height),
            (640, 480, 640, 480)
        );
        assert_eq!(color.data, want.color);
        assert_eq!(depth.data, want.depth);
        assert_eq!(cloud.data, want.cloud);
        assert_eq!(
            (cloud.width, cloud.height, cloud.point_step, cloud.row_step),
            (640, 480, 16, 16 * 640)
        );
        let names: Vec<&str> = cloud.fields.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["x", "y", "z", "rgb"]);
        assert!(!cloud.is_dense && !cloud.is_bigendian);
        let k = s.cameras[0].camera.intrinsics.k();
        assert_eq!(info.k, k);
        assert_eq!(
            info.p,
            [k[0], 0.0, k[2], 0.0, 0.0, k[4], k[5], 0.0, 0.0, 0.0, 1.0, 0.0]
        );
        assert_eq!(
            (info.distortion_model.as_str(), info.d.as_slice()),
            ("plumb_bob", &[0.0; 5][..])
        );
        // not drawn: the camera_info only
        let view = CameraView {
            camera: &s.cameras[0],
            stamp: f.stamp,
            drawn: None,
        };
        let infos_only = camera_frame(&t.rows, 0, &view).unwrap();
        let made: Vec<usize> = (0..t.rows.len())
            .filter(|k| infos_only.messages[*k].is_some())
            .collect();
        assert_eq!(made, [row("camera_color_info"), row("camera_depth_info")]);
    }

    #[test]
    fn a_frame_is_the_same_bytes_at_any_thread_count() {
        // the D435 noise and the colliders too
        let s = scene(
            "ribbon_gripper_push",
            &["cameras.0.width=320", "cameras.0.height=240"],
        );
        let t = table(&s, true);
        let one = drawn(&s, &t.rows, 1);
        assert_eq!(one, drawn(&s, &t.rows, 3));
        assert_eq!(one.messages.iter().flatten().count(), 5);
        // and the check can fail: another tick's noise differs
        let other = scene(
            "ribbon_gripper_push",
            &["cameras.0.width=320", "cameras.0.height=240", "seed=1"],
        );
        assert_ne!(one, drawn(&other, &t.rows, 1));
    }

    #[test]
    fn colliders_that_arrive_later_are_drawn() {
        // a robot link (a ball in front of the camera) enters the world after start-up
        let mut s = scene(
            "ribbon_gripper_push",
            &["cameras.0.width=160", "cameras.0.height=120"],
        );
        let t = table(&s, true);
        let mut cams = Cameras::new(&s, &t.rows);
        let cam = s.cameras[0].clone();
        let pose = fixed_pose(&cam).unwrap();
        let mut r = renderer(&s, &cam);
        cams.on_state(&s);
        cams.capture(&s, 0, &pose, Time::from_secs(s.world.time()))
            .unwrap();
        let first = cams.take(0).unwrap();
        assert_eq!(
            first.colliders, None,
            "the colliders the renderer was made with"
        );
        draw_frame(&mut r, (&cam, s.source.seed), &t.rows, &first).unwrap();
        let link = Collider {
            shape: crate::contact::ColliderShape::Ball { radius: 0.1 },
            pose: Pose::identity(),
            friction: 0.0,
            attached_to: Some(0),
        };
        let at = Pose::translation(0.5, -0.5, 0.5);
        s.world
            .set_kinematic_colliders(vec![link], vec![at])
            .unwrap();
        let targets = vec![None; s.world.handles().len()];
        while cams.due(0).is_none() {
            s.world.step(&targets);
            cams.on_state(&s);
        }
        cams.capture(&s, 0, &pose, Time::from_secs(s.world.time()))
            .unwrap();
        let second = cams.take(0).unwrap();
        let now = camera::world_colliders(&s.world).to_vec();
        assert_eq!(second.colliders.as_ref(), Some(&now));
        let drawn = draw_frame(&mut r, (&cam, s.source.seed), &t.rows, &second).unwrap();
        // what a renderer made with the ball sees, not what the first one would
        let mut fresh = renderer(&s, &cam);
        let unchanged = Capture {
            colliders: None,
            ..second.clone()
        };
        assert_eq!(
            drawn,
            draw_frame(&mut fresh, (&cam, s.source.seed), &t.rows, &unchanged).unwrap()
        );
        let mut stale = renderer(
            &scene(
                "ribbon_gripper_push",
                &["cameras.0.width=160", "cameras.0.height=120"],
            ),
            &cam,
        );
        assert_ne!(
            drawn,
            draw_frame(&mut stale, (&cam, s.source.seed), &t.rows, &unchanged).unwrap()
        );
    }

    #[test]
    fn the_optical_frames_and_the_ground_truth() {
        let s = scene("ribbon_gripper", &["outputs.points=true"]);
        let t = table(&s, false);
        let mut session = crate::session::Session::new(
            s.clone(),
            crate::session::input::InputPolicy {
                frame_id: "world".into(),
                accept_empty_frame_id: false,
                max_stamp_lead: 1.0,
            },
            vec![],
            t.clone(),
        );
        let f = session.frame(crate::session::Content::All).unwrap();
        let tf: TFMessage = f
            .decode(t.find("camera_frames", Scope::Global).unwrap())
            .unwrap()
            .unwrap();
        assert_eq!(tf.transforms.len(), 1);
        let ts = &tf.transforms[0];
        assert_eq!(
            (ts.header.frame_id.as_str(), ts.child_frame_id.as_str()),
            ("world", "camera_color_optical_frame")
        );
        assert_eq!(
            ts.transform,
            to_transform(&fixed_pose(&s.cameras[0]).unwrap())
        );
        let truth: PointCloud2 = f
            .decode(t.find("points", Scope::Object(0)).unwrap())
            .unwrap()
            .unwrap();
        let mesh = s.world.mesh(0);
        assert_eq!(
            (truth.height, truth.width as usize),
            (1, mesh.vertices.len())
        );
        let at = |k: usize| f32::from_le_bytes(truth.data[4 * k..4 * k + 4].try_into().unwrap());
        let last = mesh.vertices.len() - 1;
        assert_eq!(at(5 * last), mesh.vertices[last].x as f32);
        assert_eq!(at(5 * last + 3), mesh.material[last].x as f32);
        // after a step the optical frames are not sent again (latched)
        session.apply(&crate::session::Command::Step);
        let g = session.frame(crate::session::Content::All).unwrap();
        assert!(g.messages[t.find("camera_frames", Scope::Global).unwrap()].is_none());
    }
}
