//! Recording and replay: a recorded run replays bit for bit; a changed scene is
//! reported with its largest difference; a bag cut short (crash) or a full disk leaves a
//! bag that streaming readers, `reindex` and `replay` handle.

use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use developable_sim::record::bag::{BagOptions, BagWriter};
use developable_sim::record::read::{reindex, scan, BagMessage};
use developable_sim::record::recorder::RunRecorder;
use developable_sim::record::replay::{replay, ReplayOptions, ReplayReport, TopicReport};
use developable_sim::wire::cdr;
use developable_sim::wire::msgs::{Clock, SimStatus, Time};
use developable_sim::wire::qos::Qos;
use developable_sim::{runner, scene};

mod common;
use common::{metadata, rewrite, scratch, TORSION};

/// Record `duration` s of the torsion scene headless into `dir/bag`.
fn record(dir: &Path, duration: f64, options: BagOptions) -> PathBuf {
    let bag = dir.join("bag");
    let mut s = scene::load(Path::new(TORSION), &[format!("duration={duration}")]).unwrap();
    let mut rec = RunRecorder::create(&s, &bag, options).unwrap();
    runner::run(&mut s, &mut rec, &|| false).unwrap();
    rec.close().unwrap();
    bag
}

/// A fresh scratch folder `name` with 0.1 s (10 steps) of the torsion scene recorded in
/// it, where the tampering tests start: (folder, bag).
fn record_tenth(name: &str) -> (PathBuf, PathBuf) {
    let dir = scratch(name);
    let bag = record(&dir, 0.1, BagOptions::default());
    (dir, bag)
}

/// The comparison of `name` in a replay's report.
fn topic<'a>(r: &'a ReplayReport, name: &str) -> &'a TopicReport {
    r.topics
        .iter()
        .find(|t| t.topic == name)
        .unwrap_or_else(|| panic!("no {name} in {r:?}"))
}

#[test]
fn a_recorded_run_replays_bit_for_bit() {
    let dir = scratch("identical");
    let bag = record(&dir, 0.3, BagOptions::default());
    let meta = metadata(&bag);
    let info = &meta.rosbag2_bagfile_information;
    // 31 states (step 0..30) x (status, clock, markers, singular points), the 30 step
    // commands, the twisting handle's grasp state (at step 0, nothing changes after)
    // and its wrench (each step)
    assert_eq!(info.message_count, 31 * 4 + 30 + 1 + 30);
    let r = replay(&bag, &ReplayOptions::default()).unwrap();
    assert_eq!(r.steps, 30);
    assert_eq!(r.topics.len(), 6);
    for t in &r.topics {
        let want = match t.topic.as_str() {
            "/handles/twist_end/state" => 1,
            "/ribbon/twist_end/wrench" => 30,
            _ => 31,
        };
        assert_eq!(t.compared, want, "{t:?}");
    }
    assert!(r.identical, "{r:?}");
    assert_eq!(r.max_abs_difference, 0.0);
    assert!(r.truncated.is_none());
}

#[test]
fn replay_with_another_scene_reports_the_largest_difference() {
    let dir = scratch("different");
    let bag = record(&dir, 0.2, BagOptions::default());
    let text = std::fs::read_to_string(TORSION).unwrap();
    let stiffer = text.replace("bending_stiffness: 0.1", "bending_stiffness: 0.3");
    assert_ne!(stiffer, text);
    let scene_path = dir.join("stiffer.yaml");
    std::fs::write(&scene_path, stiffer).unwrap();
    let r = replay(
        &bag,
        &ReplayOptions {
            scene: Some(scene_path),
        },
    )
    .unwrap();
    assert!(!r.identical);
    assert!(r.max_abs_difference > 0.0 && r.max_abs_difference.is_finite());
    let status = topic(&r, "/ribbon/status");
    assert!(status.differing > 0);
    assert!(status.max_at.starts_with("step "), "{}", status.max_at);
    // the clock does not depend on the stiffness
    let clock = topic(&r, "/clock");
    assert_eq!(clock.differing, 0);
}

#[test]
fn a_bag_cut_short_is_streamed_replayed_and_repaired_by_reindex() {
    let dir = scratch("truncated");
    let bag = record(
        &dir,
        0.5,
        BagOptions {
            // small chunks: a crash loses little
            chunk_size: 16 * 1024,
            ..BagOptions::default()
        },
    );
    let file = std::fs::read_dir(&bag)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "mcap"))
        .unwrap();
    let total = metadata(&bag).rosbag2_bagfile_information.message_count;
    // cut the file in the middle of its data, as a killed recorder leaves it
    let len = std::fs::metadata(&file).unwrap().len();
    let f = std::fs::OpenOptions::new().write(true).open(&file).unwrap();
    f.set_len(len * 2 / 3).unwrap();
    drop(f);
    std::fs::remove_file(bag.join("metadata.yaml")).unwrap();

    let s = scan(&file).unwrap();
    assert!(!s.complete && s.truncated.is_some());
    let readable = s.message_count();
    assert!(readable > 0 && readable < total, "{readable} of {total}");

    let r = replay(&bag, &ReplayOptions::default()).unwrap();
    assert!(r.truncated.is_some());
    assert!(r.identical, "{r:?}");

    let report = reindex(&bag).unwrap();
    assert_eq!(report.repaired.len(), 1);
    assert!(report.repaired[0].1.exists(), "the original is kept");
    let after = scan(&file).unwrap();
    assert!(after.complete && after.truncated.is_none());
    assert_eq!(after.message_count(), readable);
    assert_eq!(
        metadata(&bag).rosbag2_bagfile_information.message_count,
        readable
    );
    // the repaired file is complete, but its last state may still lack outputs the cut
    // took: replay knows the file was repaired and compares up to there
    let r = replay(&bag, &ReplayOptions::default()).unwrap();
    assert!(r.truncated.is_none(), "{r:?}");
    assert!(r.identical, "{r:?}");
    // a complete bag: reindex only rewrites metadata.yaml
    let again = reindex(&bag).unwrap();
    assert!(again.repaired.is_empty());
}

/// A file that fails like a full disk after `quota` bytes.
struct QuotaFile {
    file: File,
    written: u64,
    quota: u64,
}

impl Write for QuotaFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.written + buf.len() as u64 > self.quota {
            return Err(std::io::Error::from_raw_os_error(28)); // ENOSPC
        }
        self.written += buf.len() as u64;
        self.file.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

impl Seek for QuotaFile {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.file.seek(pos)
    }
}

#[test]
fn a_full_disk_stops_the_recording_with_a_clear_error_and_a_readable_bag() {
    let dir = scratch("disk_full").join("bag");
    std::fs::create_dir_all(&dir).unwrap();
    let file = File::create(dir.join("bag_0.mcap")).unwrap();
    let sink = QuotaFile {
        file,
        written: 0,
        quota: 40_000,
    };
    let mut bag = BagWriter::with_sink(
        &dir,
        "bag_0.mcap",
        Box::new(sink),
        BagOptions {
            chunk_size: 4096,
            ..BagOptions::default()
        },
    )
    .unwrap();
    let clock = bag.add_topic::<Clock>("/clock", Qos::CLOCK).unwrap();
    let mut written = 0u64;
    let mut error = None;
    for i in 0..100_000u64 {
        let msg = Clock {
            clock: Time::from_nanos(i as i64 * 10_000_000),
        };
        match bag.write(clock, 1_000 + i, &msg) {
            Ok(()) => written += 1,
            Err(e) => {
                error = Some(e.to_string());
                break;
            }
        }
    }
    let error = error.expect("the quota must be hit");
    assert!(error.contains("bag_0.mcap"), "{error}");
    assert!(bag.failure().is_some());
    // later writes are refused, not silently lost
    assert!(bag.write(clock, 5, &Clock::default()).is_err());
    let closed = bag.close();
    assert!(closed.is_ok() || closed.is_err()); // either way metadata.yaml is written
    let meta = metadata(&dir);
    let s = scan(&dir.join("bag_0.mcap")).unwrap();
    assert_eq!(
        meta.rosbag2_bagfile_information.message_count,
        s.message_count()
    );
    assert!(s.message_count() > 0 && s.message_count() <= written);
}

#[test]
fn bags_are_never_written_over_and_unwritable_folders_fail_clearly() {
    let dir = scratch("folders");
    std::fs::write(dir.join("occupied"), "x").unwrap();
    let e = BagWriter::create(&dir, BagOptions::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("already exists"), "{e}");
    let under_a_file = dir.join("occupied").join("bag");
    let e = BagWriter::create(&under_a_file, BagOptions::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("cannot create it"), "{e}");
    assert!(e.contains(&under_a_file.display().to_string()), "{e}");
}

/// `developable_sim replay BAG` exits with `code` and says `verdict` on stdout.
fn replay_cli_says(bag: &Path, code: i32, verdict: &str) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_developable_sim"))
        .arg("replay")
        .arg(bag)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(code), "{stdout}");
    assert!(stdout.contains(verdict), "{stdout}");
}

/// The status of step `step` on `/ribbon/status`, decoded.
fn status_at(m: &BagMessage, step: u64) -> Option<SimStatus> {
    if m.topic != "/ribbon/status" {
        return None;
    }
    let s: SimStatus = cdr::decode(&m.data).unwrap();
    (s.step == step).then_some(s)
}

#[test]
fn an_untouched_copy_replays_identical_and_exits_0() {
    // the rewriting itself changes nothing: the tampering tests below see only their edit
    let (dir, bag) = record_tenth("copy");
    let copy = dir.join("copy");
    rewrite(&bag, &copy, |m| Some(m.data.clone()));
    let r = replay(&copy, &ReplayOptions::default()).unwrap();
    assert!(r.identical, "{r:?}");
    replay_cli_says(&copy, 0, "identical");
}

#[test]
fn a_zero_flipped_in_sign_is_a_difference_and_exits_1() {
    let (dir, bag) = record_tenth("signed_zero");
    let tampered = dir.join("tampered");
    let mut flipped = 0;
    rewrite(&bag, &tampered, |m| {
        let Some(mut s) = status_at(m, 3) else {
            return Some(m.data.clone());
        };
        // gravity is off in the torsion scene: its potential is a zero, whose sign we flip
        assert_eq!(s.gravity_energy, 0.0);
        s.gravity_energy = -s.gravity_energy;
        flipped += 1;
        Some(cdr::encode(&s).unwrap())
    });
    assert_eq!(flipped, 1);
    let r = replay(&tampered, &ReplayOptions::default()).unwrap();
    assert!(!r.identical, "{r:?}");
    let status = topic(&r, "/ribbon/status");
    assert_eq!(status.differing, 1, "{status:?}");
    assert_eq!(
        status.max_abs_difference, 0.0,
        "a sign of zero has no magnitude"
    );
    assert_eq!(
        status.first_difference, "step 3: gravity_energy",
        "{status:?}"
    );
    replay_cli_says(&tampered, 1, "DIFFERENT");
}

#[test]
fn a_nan_with_other_bits_is_a_difference() {
    // a NaN in place of a NaN with different bits (the sign): not identical
    let (dir, bag) = record_tenth("nan_bits");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let nan = |sign: f64| {
        move |m: &BagMessage| {
            let Some(mut s) = status_at(m, 2) else {
                return Some(m.data.clone());
            };
            s.isometry_error = f64::NAN.copysign(sign);
            Some(cdr::encode(&s).unwrap())
        }
    };
    rewrite(&bag, &a, nan(1.0));
    rewrite(&a, &b, nan(-1.0));
    // both differ from the replay, which computes a finite isometry error
    for bag in [&a, &b] {
        let r = replay(bag, &ReplayOptions::default()).unwrap();
        let status = topic(&r, "/ribbon/status");
        assert_eq!(status.differing, 1, "{status:?}");
        assert_eq!(status.max_abs_difference, f64::INFINITY);
    }
}

/// A bag with no output this build can read (here: its messages removed, the session
/// record kept) is not "identical": nothing was reproduced.
#[test]
fn a_bag_with_nothing_to_compare_is_not_identical() {
    let (dir, bag) = record_tenth("nothing");
    let empty = dir.join("empty");
    rewrite(&bag, &empty, |_| None);
    let r = replay(&empty, &ReplayOptions::default()).unwrap();
    assert!(
        !r.identical && r.topics.iter().all(|t| t.compared == 0),
        "{r:?}"
    );
    replay_cli_says(&empty, 1, "NOTHING COMPARED");
}

#[test]
fn an_output_missing_from_the_bag_is_a_difference_and_exits_1() {
    let (dir, bag) = record_tenth("missing");
    let tampered = dir.join("tampered");
    // drop the markers of step 4 (the statuses say which step a message belongs to)
    let mut step = 0;
    let mut dropped = 0;
    rewrite(&bag, &tampered, |m| {
        if m.topic == "/ribbon/status" {
            step = cdr::decode::<SimStatus>(&m.data).unwrap().step;
        }
        if m.topic == "/ribbon/markers" && step == 4 {
            dropped += 1;
            return None;
        }
        Some(m.data.clone())
    });
    assert_eq!(dropped, 1);
    let r = replay(&tampered, &ReplayOptions::default()).unwrap();
    assert!(!r.identical, "{r:?}");
    let markers = topic(&r, "/ribbon/markers");
    assert_eq!((markers.missing, markers.differing), (1, 0), "{markers:?}");
    assert!(
        markers.first_difference.starts_with("step 4:"),
        "{markers:?}"
    );
    replay_cli_says(&tampered, 1, "DIFFERENT");

    // the last state's markers missing from a complete bag count too
    let last = dir.join("last");
    let mut seen = 0;
    let total = 11; // steps 0..10
    rewrite(&bag, &last, |m| {
        if m.topic == "/ribbon/markers" {
            seen += 1;
            if seen == total {
                return None;
            }
        }
        Some(m.data.clone())
    });
    let r = replay(&last, &ReplayOptions::default()).unwrap();
    let markers = topic(&r, "/ribbon/markers");
    assert_eq!(markers.missing, 1, "{markers:?}");
    assert!(
        markers.first_difference.starts_with("step 10:"),
        "{markers:?}"
    );
}
