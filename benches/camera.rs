//! Criterion benchmarks of the simulated RGB-D camera (issue 48), 640 x 480 colour +
//! depth + organized cloud of the scenes with a camera, mid-motion:
//! - `frame`: one whole frame (`Renderer::render`: setup, then the parallel bands):
//!   ribbon_gripper, ribbon_gripper_push (ground plane, a box carried by the gripper,
//!   D435 noise) and paper_crumple (a camera added over the sheet: the most triangles);
//! - `phase`: its parts: `capture` (copying meshes and collider poses out of the world),
//!   `prepare` (the sequential setup, per triangle) and `draw` (the bands: every pixel's
//!   surfaces, then depth, noise and cloud);
//! - `noise`: ribbon_gripper_push's frame without and with the D435 model.
//!
//! The frames use rayon's global pool (all cores). Run: `cargo bench --bench camera`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use developable_sim::camera::{world_colliders, NoiseKey, Renderer, Snapshot};
use developable_sim::scene::{CameraMount, Scene};

// the shared helpers; this benchmark uses `warmed` only
#[allow(dead_code)]
mod common;
use common::warmed;

/// A camera over paper_crumple's 10 cm sheet (it declares none).
const PAPER_CAMERA: &str =
    "cameras=[{name: camera, position: [0.05, -0.09, 0.12], look_at: [0.05, 0.05, 0.0]}]";

/// The scenes, each with its warm-up steps and overrides.
fn scenes() -> Vec<(&'static str, Scene)> {
    vec![
        ("ribbon_gripper", warmed("ribbon_gripper", &[], 300)),
        (
            "ribbon_gripper_push",
            warmed("ribbon_gripper_push", &[], 60),
        ),
        (
            "paper_crumple",
            warmed("paper_crumple", &[PAPER_CAMERA.into()], 30),
        ),
    ]
}

/// The scene's first camera as a renderer, its pose, a snapshot and a noise key.
fn setup(
    s: &Scene,
) -> (
    Renderer,
    developable_sim::geometry::Pose,
    Snapshot,
    NoiseKey,
) {
    let cam = &s.cameras[0];
    let CameraMount::Fixed(pose) = cam.mount else {
        panic!("a fixed camera")
    };
    let mut snapshot = Snapshot::default();
    snapshot.capture(&s.world);
    let renderer = Renderer::new(cam.camera, world_colliders(&s.world));
    (renderer, pose, snapshot, cam.noise_key(s.source.seed, 7))
}

fn frame(c: &mut Criterion) {
    let mut group = c.benchmark_group("frame");
    group.sample_size(40);
    for (name, s) in scenes() {
        let (mut r, pose, snapshot, key) = setup(&s);
        group.bench_function(name, |b| {
            b.iter(|| {
                black_box(r.render(&snapshot, &pose, &key));
            })
        });
    }
    group.finish();
}

fn phase(c: &mut Criterion) {
    let mut group = c.benchmark_group("phase");
    group.sample_size(40);
    for (name, s) in scenes() {
        let (mut r, pose, mut snapshot, key) = setup(&s);
        group.bench_function(format!("capture/{name}"), |b| {
            b.iter(|| snapshot.capture(black_box(&s.world)))
        });
        group.bench_function(format!("prepare/{name}"), |b| {
            b.iter(|| r.prepare(black_box(&snapshot), &pose))
        });
        r.prepare(&snapshot, &pose);
        group.bench_function(format!("draw/{name}"), |b| {
            b.iter(|| {
                black_box(r.draw(&key));
            })
        });
    }
    group.finish();
}

fn noise(c: &mut Criterion) {
    let mut group = c.benchmark_group("noise");
    group.sample_size(40);
    for (label, noise) in [("none", "none"), ("d435", "d435")] {
        let set = format!("cameras.0.noise={noise}");
        let s = warmed("ribbon_gripper_push", &[set], 60);
        let (mut r, pose, snapshot, key) = setup(&s);
        group.bench_function(label, |b| {
            b.iter(|| {
                black_box(r.render(&snapshot, &pose, &key));
            })
        });
    }
    group.finish();
}

criterion_group!(benches, frame, phase, noise);
criterion_main!(benches);
