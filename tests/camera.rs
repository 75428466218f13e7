//! The simulated RGB-D camera of a scene file (issue 48): the `cameras:` section, a
//! frame of a default scene bit-identical at any thread count, colliders carried by a
//! handle seen where the handle put them, bad sections named by key, and
//! `render --camera` writing its two pictures.

use std::path::{Path, PathBuf};
use std::process::Command;

use developable_sim::camera::{
    look_at, world_colliders, Frame, Noise, NoiseKey, Renderer, Snapshot,
};
use developable_sim::contact::ColliderShape;
use developable_sim::geometry::{Point3, Pose, Vector3};
use developable_sim::scene::{self, CameraMount, Scene};

mod common;
use common::{load, scene_path, scratch};

fn fixed_pose(s: &Scene, camera: usize) -> Pose {
    match &s.cameras[camera].mount {
        CameraMount::Fixed(p) => *p,
        other => panic!("a fixed camera, got {other:?}"),
    }
}

/// Camera `camera` of `s` now, with `threads` rayon threads.
fn frame_in_pool(s: &Scene, camera: usize, threads: usize) -> Frame {
    let cam = &s.cameras[camera];
    let mut snapshot = Snapshot::default();
    snapshot.capture(&s.world);
    let mut r = Renderer::new(cam.camera, world_colliders(&s.world));
    let key = cam.noise_key(s.source.seed, s.world.steps_taken());
    common::on_threads(threads, || {
        r.render(&snapshot, &fixed_pose(s, camera), &key).clone()
    })
}

#[test]
fn the_default_scenes_declare_their_cameras() {
    let s = load("ribbon_gripper", &[]);
    assert_eq!(s.cameras.len(), 1);
    let c = &s.cameras[0];
    assert_eq!(c.name, "camera");
    assert_eq!(c.optical_frame(), "camera_color_optical_frame");
    let i = c.camera.intrinsics;
    assert_eq!(
        (i.width, i.height, i.fov_y, i.near, i.far),
        (640, 480, 0.75, 0.1, 4.0)
    );
    assert_eq!((c.rate, c.camera.noise), (15.0, Noise::None));
    let expected = look_at(Vector3::new(0.45, -0.95, 0.35), Vector3::new(0.4, 0.0, 0.0)).unwrap();
    assert_eq!(fixed_pose(&s, 0), expected);
    let push = load("ribbon_gripper_push", &[]);
    assert_eq!(push.cameras[0].camera.noise, Noise::D435);
    // a scene without the section has no camera
    assert!(load("ribbon_falling", &[]).cameras.is_empty());
}

#[test]
fn a_scene_frame_is_bit_identical_with_one_and_two_threads() {
    let mut s = load("ribbon_gripper_push", &[]);
    for _ in 0..30 {
        s.world.step(&[]);
    }
    let one = frame_in_pool(&s, 0, 1);
    let two = frame_in_pool(&s, 0, 2);
    assert!(one == two, "1 and 2 threads differ");
    // the ribbon, the table and the finger are all in view: depth in most pixels
    let hits = one
        .depth
        .chunks_exact(4)
        .filter(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]).is_finite())
        .count();
    assert!(hits > 600 * 400, "{hits} pixels with depth");
    // negative: one step later the frame differs (the check can fail)
    s.world.step(&[]);
    assert!(frame_in_pool(&s, 0, 2) != one);
}

#[test]
fn a_collider_carried_by_a_handle_is_seen_where_its_handle_is() {
    let mut s = load("ribbon_gripper_push", &["cameras.0.noise=none"]);
    let finger = world_colliders(&s.world)
        .iter()
        .position(|c| matches!(c.shape, ColliderShape::Cuboid { .. }))
        .expect("the finger");
    let pose = fixed_pose(&s, 0);
    let intr = s.cameras[0].camera.intrinsics;
    // the centre of the finger's top face, at t = 0 and after the sweep began
    let mut seen = Vec::new();
    for steps in [0, 60] {
        for _ in 0..steps {
            s.world.step(&[]);
        }
        let mut snapshot = Snapshot::default();
        snapshot.capture(&s.world);
        let c = &world_colliders(&s.world)[finger];
        let world_from_box = c.world_pose(s.world.current_targets());
        assert_eq!(snapshot.collider_poses[finger], world_from_box);
        let ColliderShape::Cuboid { half_extents: h } = c.shape else {
            unreachable!()
        };
        let top = world_from_box * Point3::new(0.0, 0.0, h.z);
        let [u, v] = intr.project(&(pose.inverse() * top)).expect("in front");
        let (i, j) = (u.round() as u32, v.round() as u32);
        let frame = frame_in_pool(&s, 0, 2);
        // depth where pixel (i, j)'s ray meets the top face's plane (normal: the box's z)
        let ray = pose.rotation * intr.ray(i as f64, j as f64);
        let n = world_from_box.rotation * Vector3::z();
        let t = n.dot(&(top.coords - pose.translation.vector)) / n.dot(&ray);
        let got = frame.depth_at(i, j) as f64;
        assert!(
            (got - t).abs() <= t * (2f64.powi(-24) + 1e-12),
            "{got} vs {t}"
        );
        seen.push((i, j));
    }
    // the sweep moved the finger across the picture
    assert!(
        seen[0].0.abs_diff(seen[1].0) + seen[0].1.abs_diff(seen[1].1) > 20,
        "{seen:?}"
    );
}

const BASE: &str =
    "duration: 0.05\ndt: 0.01\nribbon:\n  length: 1.0\n  width: 0.05\n  segments: 10\n";

fn load_err(text: &str, sets: &[&str]) -> String {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    match scene::load_str(text, &PathBuf::from("bad.yaml"), &sets) {
        Ok(_) => panic!("scene accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_camera_sections_name_the_file_and_the_key() {
    let cam = "cameras:\n  - {name: cam, position: [0, -1, 1], look_at: [0.5, 0, 0]}\n";
    let good = format!("{BASE}{cam}");
    assert_eq!(
        scene::load_str(&good, Path::new("ok.yaml"), &[])
            .unwrap()
            .cameras
            .len(),
        1
    );
    for (sets, expected) in [
        (
            vec!["cameras.0.fov_y=4"],
            "`cameras.0.fov_y`: must be < pi rad",
        ),
        (
            vec!["cameras.0.far=0.01"],
            "`cameras.0.far`: must be > near",
        ),
        (
            vec!["cameras.0.noise=d415"],
            "`cameras.0.noise`: unknown value `d415`",
        ),
        (
            vec!["cameras.0.tf_frame=tool0"],
            "`cameras.0.tf_frame`: give either",
        ),
        (
            vec!["cameras.0.look_at=[0, -1, 1]"],
            "`cameras.0.look_at`: look_at must differ",
        ),
        (vec!["cameras.0.fov=1"], "unknown field `fov`"),
        (vec!["cameras.0.width=-3"], "width"),
    ] {
        let msg = load_err(&good, &sets);
        assert!(
            msg.contains("bad.yaml") && msg.contains(expected),
            "{sets:?}: {msg}"
        );
    }
    let msg = load_err(&format!("{BASE}cameras:\n  - {{name: cam}}\n"), &[]);
    assert!(msg.contains("`cameras.0.position`: required"), "{msg}");
}

fn render(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_developable_sim"))
        .arg("render")
        .args(args)
        .output()
        .expect("runs")
}

fn png_size(path: &Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let reader = decoder.read_info().unwrap();
    (reader.info().width, reader.info().height)
}

#[test]
fn render_camera_writes_the_colour_and_the_depth_picture() {
    let dir = scratch("render_camera");
    let out = dir.join("cam.png");
    let scene = scene_path("ribbon_gripper_push");
    let scene = scene.to_str().unwrap();
    let o = render(&[
        scene,
        "--camera",
        "camera",
        "--time",
        "0.05",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "cameras.0.width=320",
        "--set",
        "cameras.0.height=200",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(png_size(&out), (320, 200));
    assert_eq!(png_size(&dir.join("cam_depth.png")), (320, 200));
    assert!(String::from_utf8_lossy(&o.stdout).contains("depth"));
    // an unknown camera, a TF-carried one, and --view with --camera are refused
    for (args, expected) in [
        (
            vec!["--camera", "nope"],
            "no camera `nope` (its cameras: camera)",
        ),
        (
            vec![
                "--camera",
                "camera",
                "--set",
                "cameras=[{name: camera, tf_frame: tool0}]",
            ],
            "follows the TF frame `tool0`",
        ),
        (
            vec!["--camera", "camera", "--view=0,0,-1"],
            "cannot be used with",
        ),
    ] {
        let mut a = vec![scene, "--time", "0.01", "--out", out.to_str().unwrap()];
        a.extend(args);
        let o = render(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(expected),
            "{a:?}: {err}"
        );
    }
}

#[test]
fn the_noise_key_of_a_frame_replays() {
    // the same scene, seed and tick give the same noisy frame; another seed does not
    let mut s = load("ribbon_gripper_push", &[]);
    for _ in 0..5 {
        s.world.step(&[]);
    }
    let a = frame_in_pool(&s, 0, 2);
    assert!(a == frame_in_pool(&s, 0, 1));
    let mut reseeded = load("ribbon_gripper_push", &["seed=1"]);
    for _ in 0..5 {
        reseeded.world.step(&[]);
    }
    assert!(a != frame_in_pool(&reseeded, 0, 2));
    assert_eq!(
        s.cameras[0].noise_key(s.source.seed, 5),
        NoiseKey {
            seed: 0,
            camera: 0,
            frame: 5
        }
    );
}
