//! Process CPU time per camera frame (issue 48), for a shared machine where wall times
//! depend on the load: 100 frames of each scene's camera (640 x 480, colour + depth +
//! cloud) on a rayon pool of THREADS threads (default 1), split into
//! `Renderer::prepare` and `Renderer::draw`. CPU time still grows somewhat with the
//! load (caches); print `cat /proc/loadavg` beside it.
//!
//! Run: `cargo run --release --example camera_cpu -- [THREADS]`

use std::path::Path;

use developable_sim::camera::{world_colliders, Renderer, Snapshot};
use developable_sim::scene::{self, CameraMount};

/// A camera over paper_crumple's 10 cm sheet (as benches/camera.rs adds it).
const PAPER_CAMERA: &str =
    "cameras=[{name: camera, position: [0.05, -0.09, 0.12], look_at: [0.05, 0.05, 0.0]}]";

/// CPU time of the whole process (every thread), s.
fn cpu_seconds() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes the timespec it is given and nothing else
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

fn main() {
    let threads: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("THREADS: a number"))
        .unwrap_or(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    let runs: [(&str, &str, Option<&str>, usize); 4] = [
        ("ribbon_gripper", "", None, 300),
        (
            "ribbon_gripper_push",
            " noise none",
            Some("cameras.0.noise=none"),
            60,
        ),
        (
            "ribbon_gripper_push",
            " noise d435",
            Some("cameras.0.noise=d435"),
            60,
        ),
        ("paper_crumple", "", Some(PAPER_CAMERA), 30),
    ];
    let frames = 100;
    for (name, label, set, warm) in runs {
        let sets: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("config/scenes/{name}.yaml"));
        let mut s = scene::load(&path, &sets).expect("scene");
        for _ in 0..warm {
            s.world.step(&[]);
        }
        let cam = s.cameras[0].clone();
        let CameraMount::Fixed(pose) = cam.mount else {
            panic!("{name}: a fixed camera")
        };
        let mut snapshot = Snapshot::default();
        snapshot.capture(&s.world);
        let mut r = Renderer::new(cam.camera, world_colliders(&s.world));
        let key = cam.noise_key(s.source.seed, 3);
        pool.install(|| r.render(&snapshot, &pose, &key));
        let start = cpu_seconds();
        for _ in 0..frames {
            pool.install(|| r.prepare(&snapshot, &pose));
        }
        let prepare = (cpu_seconds() - start) / frames as f64;
        let start = cpu_seconds();
        for _ in 0..frames {
            pool.install(|| {
                r.draw(&key);
            });
        }
        let draw = (cpu_seconds() - start) / frames as f64;
        println!(
            "{name}{label}, {threads} thread(s): prepare {:.3} ms, draw {:.3} ms CPU a frame",
            prepare * 1e3,
            draw * 1e3
        );
    }
}
