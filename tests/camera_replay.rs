//! The camera in bags (issue 48): a recording with `--record-cameras` replays its images
//! and clouds bit for bit at any thread count; the frames a camera skipped are skipped
//! again; one changed pixel, or a capture removed, is a difference; without
//! `--record-cameras` only camera_info is recorded (the ledger of the frames drawn).

use std::path::{Path, PathBuf};

use developable_sim::record::bag::BagOptions;
use developable_sim::record::read::BagMessage;
use developable_sim::record::recorder::{RunRecorder, SessionRecorder};
use developable_sim::record::replay::{replay, ReplayOptions, ReplayReport, TopicReport};
use developable_sim::runner;
use developable_sim::scene::Scene;
use developable_sim::session::camera::{draw_frame, fixed_pose, renderer};
use developable_sim::session::input::InputPolicy;
use developable_sim::session::names::NodeNames;
use developable_sim::session::{Command, Content, OutputTable, RunOutputs, Session};
use developable_sim::wire::cdr;
use developable_sim::wire::msgs::{Image, SimCommand, SimStatus};

mod common;
use common::{load, metadata, rewrite, scratch};

const COLOR: &str = "/camera/color/image_raw";
const CAMERA_TOPICS: [&str; 5] = [
    "/camera/color/image_raw",
    "/camera/color/camera_info",
    "/camera/aligned_depth_to_color/image_raw",
    "/camera/aligned_depth_to_color/camera_info",
    "/camera/depth/color/points",
];

/// The pushed ribbon: a table, a finger, D435 noise; a 320 x 240 camera keeps the bags
/// small.
fn push() -> Scene {
    load(
        "ribbon_gripper_push",
        &[
            "duration=0.3",
            "cameras.0.width=320",
            "cameras.0.height=240",
        ],
    )
}

/// `run --record` of [`push`] into `dir/bag` (with the images: `record_cameras`).
fn record(dir: &Path, record_cameras: bool) -> PathBuf {
    let bag = dir.join("bag");
    let mut s = push();
    let options = BagOptions {
        record_cameras,
        ..BagOptions::default()
    };
    let mut rec = RunRecorder::create(&s, &bag, options).unwrap();
    runner::run(&mut s, &mut rec, &|| false).unwrap();
    rec.close().unwrap();
    bag
}

fn topic<'a>(r: &'a ReplayReport, name: &str) -> &'a TopicReport {
    r.topics
        .iter()
        .find(|t| t.topic == name)
        .unwrap_or_else(|| panic!("no {name} in {r:?}"))
}

/// Replay `bag` with the camera drawn on a rayon pool of `threads`.
fn replay_on(bag: &Path, threads: usize) -> ReplayReport {
    common::on_threads(threads, || replay(bag, &ReplayOptions::default()).unwrap())
}

#[test]
fn recorded_frames_replay_bit_for_bit_at_any_thread_count() {
    let dir = scratch("identical");
    let bag = record(&dir, true);
    // 0.3 s at 15 Hz: ticks 0..=4 (t = 0, 0.07, 0.13, 0.2, 0.27)
    for threads in [1, 3] {
        let r = replay_on(&bag, threads);
        assert!(r.identical, "{threads} threads: {r:?}");
        for t in CAMERA_TOPICS {
            assert_eq!(topic(&r, t).compared, 5, "{t}");
        }
        assert_eq!(topic(&r, "/tf_static").compared, 1);
    }
    let counts = metadata(&bag)
        .rosbag2_bagfile_information
        .topics_with_message_count;
    let images = counts
        .iter()
        .find(|t| t.topic_metadata.name == COLOR)
        .unwrap();
    assert_eq!(images.message_count, 5);
}

#[test]
fn without_record_cameras_only_camera_info_is_recorded() {
    let dir = scratch("info_only");
    let bag = record(&dir, false);
    let counts = metadata(&bag)
        .rosbag2_bagfile_information
        .topics_with_message_count;
    let count = |name: &str| {
        counts
            .iter()
            .find(|t| t.topic_metadata.name == name)
            .map(|t| t.message_count)
    };
    assert_eq!(count("/camera/color/camera_info"), Some(5));
    assert_eq!(count("/camera/aligned_depth_to_color/camera_info"), Some(5));
    for t in [COLOR, "/camera/depth/color/points"] {
        assert_eq!(count(t), None, "{t}");
    }
    let r = replay(&bag, &ReplayOptions::default()).unwrap();
    assert!(r.identical, "{r:?}");
    assert_eq!(topic(&r, "/camera/color/camera_info").compared, 5);
}

#[test]
fn one_changed_pixel_is_a_difference() {
    let dir = scratch("pixel");
    let bag = record(&dir, true);
    let tampered = dir.join("tampered");
    let mut frame = 0;
    rewrite(&bag, &tampered, |m: &BagMessage| {
        if m.topic != COLOR {
            return Some(m.data.clone());
        }
        frame += 1;
        let mut img: Image = cdr::decode(&m.data).unwrap();
        if frame == 3 {
            img.data[1000] ^= 1;
        }
        Some(cdr::encode(&img).unwrap())
    });
    let r = replay(&tampered, &ReplayOptions::default()).unwrap();
    assert!(!r.identical);
    let color = topic(&r, COLOR);
    assert_eq!((color.compared, color.differing), (5, 1), "{color:?}");
    assert_eq!(color.max_abs_difference, 1.0);
    assert!(color.first_difference.contains("data[1000]"), "{color:?}");
    for t in &CAMERA_TOPICS[1..] {
        assert_eq!(topic(&r, t).differing, 0, "{t}");
    }
}

#[test]
fn a_capture_removed_from_the_bag_is_a_difference() {
    let dir = scratch("no_capture");
    let bag = record(&dir, false);
    let tampered = dir.join("tampered");
    let mut captures = 0;
    rewrite(&bag, &tampered, |m: &BagMessage| {
        if m.topic.ends_with("/commands") {
            let c: SimCommand = cdr::decode(&m.data).unwrap();
            if c.kind == SimCommand::CAPTURE {
                captures += 1;
                if captures == 2 {
                    return None;
                }
            }
        }
        Some(m.data.clone())
    });
    assert_eq!(captures, 5);
    let r = replay(&tampered, &ReplayOptions::default()).unwrap();
    assert!(!r.identical, "{r:?}");
    // tick 1 was not captured in the replay: its recorded frame has no counterpart, and
    // the statuses count the tick skipped from then on
    let info = topic(&r, "/camera/color/camera_info");
    assert_eq!((info.compared, info.differing), (5, 1), "{info:?}");
    assert_eq!(
        info.first_difference,
        "recorded, not captured by the replay"
    );
    let status = topic(&r, "/ribbon/status");
    assert!(status.differing > 0, "{status:?}");
    assert!(
        status.first_difference.ends_with("camera_frames_skipped"),
        "{status:?}"
    );
}

/// A node whose camera skips tick 1 (still drawing) and publishes each frame two steps
/// after its capture, recorded as the node records: replayed identical, the skip
/// counted in the statuses alike.
#[test]
fn a_skipped_tick_replays_skipped_and_late_frames_match_their_captures() {
    let dir = scratch("skipped");
    let bag = dir.join("bag");
    let scene = push();
    let names = NodeNames::resolve(&scene, "developable_sim", "/", &[]).unwrap();
    let run = RunOutputs {
        own_clock: true,
        recording: true,
        record_cameras: true,
    };
    let table = OutputTable::for_scene(&scene, &names, run).unwrap();
    let policy = InputPolicy {
        frame_id: scene.frame_id.clone(),
        accept_empty_frame_id: false,
        max_stamp_lead: 1.0,
    };
    let mut s = Session::new(scene.clone(), policy, names.handles.clone(), table);
    let mut rec = SessionRecorder::create(&bag, BagOptions::default(), &s, &names).unwrap();
    rec.record_frame(&s.frame(Content::All).unwrap()).unwrap();
    let cam = scene.cameras[0].clone();
    let mut r = renderer(&scene, &cam);
    let mut in_flight = Vec::new();
    for step in 0..=30u64 {
        if step > 0 {
            rec.record_command(&Command::Step, s.stamp()).unwrap();
            let applied = s.apply(&Command::Step);
            rec.record_frame(&s.frame_after(&applied).unwrap().unwrap())
                .unwrap();
        }
        // frames captured two steps ago go out now
        while in_flight.first().is_some_and(|(at, _)| at + 2 <= step) {
            let (_, capture) = in_flight.remove(0);
            let f = draw_frame(&mut r, (&cam, scene.source.seed), &s.table.rows, &capture);
            rec.record_frame(&f.unwrap()).unwrap();
        }
        if s.cameras.due(0).is_some_and(|k| k != 1) {
            let pose = fixed_pose(&cam).unwrap();
            let c = Command::Capture {
                camera: 0,
                world_from_optical: pose,
            };
            rec.record_command(&c, s.stamp()).unwrap();
            s.apply(&c);
            in_flight.push((step, s.cameras.take(0).unwrap()));
        }
    }
    for (_, capture) in in_flight {
        let f = draw_frame(&mut r, (&cam, scene.source.seed), &s.table.rows, &capture);
        rec.record_frame(&f.unwrap()).unwrap();
    }
    rec.close().unwrap();
    let rep = replay(&bag, &ReplayOptions::default()).unwrap();
    assert!(rep.identical, "{rep:?}");
    assert_eq!(topic(&rep, COLOR).compared, 4, "ticks 0, 2, 3, 4");
    let last = s.frame(Content::Statuses).unwrap();
    let status: SimStatus = last
        .decode(
            s.table
                .find("status", developable_sim::session::Scope::Object(0))
                .unwrap(),
        )
        .unwrap()
        .unwrap();
    assert_eq!(status.camera_frames_skipped, 1);
}
