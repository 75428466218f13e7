//! Recording and replay: a recorded run replays bit for bit; a changed scene is
//! reported with its largest difference; a bag cut short (crash) or a full disk leaves a
//! bag that streaming readers, `reindex` and `replay` handle.

use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use developable_sim::record::bag::{BagOptions, BagWriter};
use developable_sim::record::metadata::{MetadataFile, Qos};
use developable_sim::record::read::{reindex, scan};
use developable_sim::record::recorder::RunRecorder;
use developable_sim::record::replay::{replay, ReplayOptions};
use developable_sim::ros::msgs::{Clock, Time};
use developable_sim::{runner, scene};

const TORSION: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/config/scenes/ribbon_extreme_torsion.yaml"
);

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("record_replay_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Record `duration` s of the torsion scene headless into `dir/bag`.
fn record(dir: &Path, duration: f64, options: BagOptions) -> PathBuf {
    let bag = dir.join("bag");
    let mut s = scene::load(Path::new(TORSION), &[format!("duration={duration}")]).unwrap();
    let mut rec = RunRecorder::create(&s, &bag, options).unwrap();
    runner::run(&mut s, &mut rec, &|| false).unwrap();
    rec.close().unwrap();
    bag
}

fn metadata(bag: &Path) -> MetadataFile {
    serde_yaml::from_str(&std::fs::read_to_string(bag.join("metadata.yaml")).unwrap()).unwrap()
}

#[test]
fn a_recorded_run_replays_bit_for_bit() {
    let dir = scratch("identical");
    let bag = record(&dir, 0.3, BagOptions::default());
    let meta = metadata(&bag);
    let info = &meta.rosbag2_bagfile_information;
    // 31 states (step 0..30) x (status, clock, markers, singular points)
    assert_eq!(info.message_count, 31 * 4);
    let r = replay(&bag, &ReplayOptions::default()).unwrap();
    assert_eq!(r.steps, 30);
    assert_eq!(r.topics.len(), 4);
    assert!(r.topics.iter().all(|t| t.compared == 31), "{r:?}");
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
    let status = r
        .topics
        .iter()
        .find(|t| t.topic == "/ribbon/status")
        .unwrap();
    assert!(status.differing > 0);
    assert!(status.max_at.starts_with("step "), "{}", status.max_at);
    // the clock does not depend on the stiffness
    let clock = r.topics.iter().find(|t| t.topic == "/clock").unwrap();
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
