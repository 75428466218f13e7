//! The node's cameras (issue 48): each camera draws on a thread of its own, beside the
//! simulation loop, so a camera never delays a step.
//!
//! At a state where a camera's tick falls due the loop captures what it sees (a copy of
//! the meshes and collider poses, `Command::Capture`, recorded) and hands it to the
//! camera's thread, which draws it (in a one-thread rayon pool of its own, at a lower
//! OS priority than the simulation) and encodes the five RealSense messages; the loop
//! publishes them when they come back (the thread wakes the poll). A tick that finds
//! the camera still drawing its previous frame is skipped: nothing is captured, and the
//! session counts it (`SimStatus.camera_frames_skipped`). The frames do not depend on
//! the thread count or on timing: a frame's bytes depend on its capture only, which
//! `replay` re-applies.

use std::sync::mpsc;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use ros2_client::dds::rustdds::mio1::Waker;

use super::SimNode;
use crate::camera::Snapshot;
use crate::ros::graph::tf_pose;
use crate::scene::{CameraMount, Scene};
use crate::session::camera::{draw_frame, renderer, Capture};
use crate::session::{Applied, Command, Frame, OutputRow, Scope};
use crate::wire::cdr::CdrError;

/// Threads of a camera's rayon pool. One keeps a core for the simulation on a
/// two-core machine; a 640 x 480 frame takes 0.9 to 5 ms of CPU (docs/camera.md), well
/// within a 15 Hz period.
const DRAW_THREADS: usize = 1;

/// The OS nice value of the drawing threads (the loop runs at 0): when the cores are
/// short, the simulation goes first and the camera skips frames.
const DRAW_NICE: i32 = 10;

/// A frame drawn and encoded by a camera's thread.
pub(super) struct Drawn {
    pub(super) camera: usize,
    pub(super) frame: Result<Frame, CdrError>,
    /// The capture's snapshot, back for reuse.
    pub(super) snapshot: Option<Snapshot>,
    /// Wall time on the camera's thread (draw and encode), ms.
    pub(super) draw_ms: f64,
}

/// One camera's thread.
struct Worker {
    jobs: Option<mpsc::Sender<Capture>>,
    /// A capture was handed over and has not come back.
    busy: bool,
    thread: Option<JoinHandle<()>>,
}

/// The cameras' threads.
pub(super) struct CameraThreads {
    workers: Vec<Worker>,
    results: mpsc::Receiver<Drawn>,
    /// Per camera: whether its TF lookup is failing (said once, and when it recovers).
    tf_failing: Vec<bool>,
}

/// Lower this thread's OS priority (Linux: a thread's own nice value).
fn lower_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: setpriority on this thread's id; no memory is involved
    unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
        libc::setpriority(libc::PRIO_PROCESS, tid, DRAW_NICE);
    }
}

impl CameraThreads {
    /// A thread per camera of `scene` that has rows in `rows` (the session's outputs
    /// table); each wakes `waker` when a frame is ready.
    pub(super) fn start(
        scene: &Scene,
        rows: &[OutputRow],
        waker: &Arc<Waker>,
    ) -> std::io::Result<CameraThreads> {
        let (done, results) = mpsc::channel();
        let mut workers = Vec::new();
        for (c, cam) in scene.cameras.iter().enumerate() {
            if !rows.iter().any(|r| r.scope == Scope::Camera(c)) {
                workers.push(Worker {
                    jobs: None,
                    busy: false,
                    thread: None,
                });
                continue;
            }
            let (jobs, inbox) = mpsc::channel::<Capture>();
            let (mut r, cam, rows) = (renderer(scene, cam), cam.clone(), rows.to_vec());
            let (done, waker, seed) = (done.clone(), Arc::clone(waker), scene.source.seed);
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(DRAW_THREADS)
                .thread_name(move |i| format!("camera-{c}-{i}"))
                .start_handler(|_| lower_priority())
                .build()
                .map_err(std::io::Error::other)?;
            let thread = std::thread::Builder::new()
                .name(format!("camera-{c}"))
                .spawn(move || {
                    lower_priority();
                    for capture in inbox {
                        let start = Instant::now();
                        let frame = pool.install(|| draw_frame(&mut r, (&cam, seed), &rows, &capture));
                        let drawn = Drawn {
                            camera: c,
                            frame,
                            snapshot: capture.snapshot,
                            draw_ms: start.elapsed().as_secs_f64() * 1e3,
                        };
                        if done.send(drawn).is_err() {
                            return;
                        }
                        let _ = waker.wake();
                    }
                })?;
            workers.push(Worker {
                jobs: Some(jobs),
                busy: false,
                thread: Some(thread),
            });
        }
        Ok(CameraThreads {
            tf_failing: vec![false; workers.len()],
            workers,
            results,
        })
    }

    /// A frame drawn since the last call, if any.
    fn try_take(&mut self) -> Option<Drawn> {
        let d = self.results.try_recv().ok()?;
        self.workers[d.camera].busy = false;
        Some(d)
    }

    /// Close the threads after their last frame; returns the frames not taken yet.
    fn finish(&mut self) -> Vec<Drawn> {
        for w in &mut self.workers {
            w.jobs = None;
        }
        for w in &mut self.workers {
            if let Some(t) = w.thread.take() {
                let _ = t.join();
            }
        }
        std::iter::from_fn(|| self.try_take()).collect()
    }
}

impl Drop for CameraThreads {
    fn drop(&mut self) {
        self.finish();
    }
}

impl SimNode {
    /// Publish the frames the cameras drew since the last call.
    pub(super) fn drain_cameras(&mut self) {
        while let Some(d) = self.cameras.try_take() {
            self.emit_drawn(d);
        }
    }

    /// Publish, send to Foxglove and record a drawn frame; its snapshot goes back to the
    /// session for the next captures.
    fn emit_drawn(&mut self, d: Drawn) {
        self.stats.camera_frames += 1;
        self.camera_draw_ms.push(d.draw_ms);
        if let Some(s) = d.snapshot {
            self.session.cameras.recycle(s);
        }
        match d.frame {
            Ok(frame) => self.emit(&frame, None),
            Err(e) => self.encode_failed(&e),
        }
    }

    /// At a new state: every camera whose tick is due and which is done drawing
    /// captures it (a command, recorded) and hands it to its thread; a camera still
    /// drawing skips the tick (the session counts it).
    pub(super) fn capture_cameras(&mut self) {
        self.drain_cameras();
        for c in 0..self.session.scene.cameras.len() {
            if self.session.cameras.due(c).is_none() || self.cameras.workers[c].busy {
                continue;
            }
            let Some(world_from_optical) = self.camera_pose(c) else {
                continue;
            };
            let command = Command::Capture {
                camera: c,
                world_from_optical,
            };
            let Applied::Captured { frame: Some(_), .. } = self.command(command, None) else {
                continue;
            };
            let (Some(capture), Some(jobs)) = (
                self.session.cameras.take(c),
                self.cameras.workers[c].jobs.as_ref(),
            ) else {
                continue;
            };
            if jobs.send(capture).is_ok() {
                self.cameras.workers[c].busy = true;
            }
        }
    }

    /// `world_from_optical` of camera `c` now: fixed, or its TF frame looked up in the
    /// scene frame (None when the lookup fails: said once, the tick is skipped).
    fn camera_pose(&mut self, c: usize) -> Option<crate::geometry::Pose> {
        let scene = &self.session.scene;
        let cam = &scene.cameras[c];
        let frame = match &cam.mount {
            CameraMount::Fixed(p) => return Some(*p),
            CameraMount::TfFrame(f) => f,
        };
        let at = self.state_lookup_time_ns();
        let looked_up = match &self.io.tf_in {
            Some(tf) => tf_pose(tf, &scene.frame_id, frame, at).map_err(|e| e.to_string()),
            None => Err("no TF input".into()),
        };
        let failing = &mut self.cameras.tf_failing[c];
        match looked_up {
            Ok(msg) => {
                if *failing {
                    eprintln!("[developable_sim] camera {}: TF frame {frame} found again", cam.name);
                    *failing = false;
                }
                // a looked-up rotation is normalized here; the capture records the
                // pose exactly as drawn
                let (p, o) = (&msg.pose.position, &msg.pose.orientation);
                let world_from_frame = crate::geometry::Pose::from_parts(
                    nalgebra::Translation3::new(p.x, p.y, p.z),
                    nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                        o.w, o.x, o.y, o.z,
                    )),
                );
                Some(world_from_frame * crate::camera::body_from_optical())
            }
            Err(e) => {
                if !*failing {
                    eprintln!(
                        "[developable_sim] warning: camera {}: TF frame {frame} in {}: {e}; its \
                         ticks are skipped until it is found",
                        cam.name, scene.frame_id
                    );
                    *failing = true;
                }
                None
            }
        }
    }

    /// The time TF is looked up at for the current state, ns: the wall clock when the
    /// node owns time, the state's simulated time under use_sim_time (see
    /// `lookup_time_ns`).
    fn state_lookup_time_ns(&self) -> u64 {
        if self.io.clock_in.is_some() {
            (self.session.scene.world.time() * 1e9).round().max(0.0) as u64
        } else {
            crate::wire::clock::now_ns()
        }
    }

    /// Wait for the frames in flight and publish them (the node is stopping; the bag
    /// then holds every frame captured).
    pub(super) fn finish_cameras(&mut self) {
        for d in self.cameras.finish() {
            self.emit_drawn(d);
        }
    }
}
