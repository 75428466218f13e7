//! The cameras' drawing threads (issue 48): one per camera, each with a one-thread
//! rayon pool of its own at a lower OS priority than the simulation loop; a capture in,
//! its five messages drawn and encoded out (see `camera` for when the loop captures).

use std::sync::mpsc;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use ros2_client::dds::rustdds::mio1::Waker;

use crate::camera::Snapshot;
use crate::scene::Scene;
use crate::session::camera::{draw_frame, renderer, Capture};
use crate::session::{Frame, OutputRow, Scope};
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
    pub(super) tf_failing: Vec<bool>,
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
                        let frame =
                            pool.install(|| draw_frame(&mut r, (&cam, seed), &rows, &capture));
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

    /// Whether camera `c` is drawing (a capture handed over has not come back).
    pub(super) fn busy(&self, c: usize) -> bool {
        self.workers.get(c).is_some_and(|w| w.busy)
    }

    /// Hand `capture` to its camera's thread; false when the camera has none.
    pub(super) fn send(&mut self, capture: Capture) -> bool {
        let Some(w) = self.workers.get_mut(capture.camera) else {
            return false;
        };
        let sent = w.jobs.as_ref().is_some_and(|j| j.send(capture).is_ok());
        w.busy |= sent;
        sent
    }

    /// A frame drawn since the last call, if any.
    pub(super) fn try_take(&mut self) -> Option<Drawn> {
        let d = self.results.try_recv().ok()?;
        self.workers[d.camera].busy = false;
        Some(d)
    }

    /// Close the threads after their last frame; returns the frames not taken yet.
    pub(super) fn finish(&mut self) -> Vec<Drawn> {
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
