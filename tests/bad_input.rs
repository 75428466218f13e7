//! Bad input at the command line (issue 6): malformed scenes point at the line and
//! column, a missing scene or an unwritable bag folder is named with the cause, and a
//! disk that fills while recording ends the run with a clear error and a bag whose
//! recorded messages are all still readable (and `bag reindex` repairs it).

use std::path::Path;
use std::process::{Command, Output};

use developable_sim::record::read::scan;
use developable_sim::scene;

mod common;
use common::{metadata, scratch, TORSION};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_developable_sim"))
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn load_err(text: &str) -> String {
    match scene::load_str(text, Path::new("bad.yaml"), &[]) {
        Ok(_) => panic!("scene accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn malformed_yaml_and_wrong_types_name_line_and_column() {
    // an unclosed flow sequence: the parser stops at line 2
    let e = load_err("duration: [1\ndt: 0.1\n");
    assert!(e.starts_with("bad.yaml: "), "{e}");
    assert!(e.contains("line 2 column"), "{e}");
    // a wrong type in the file (no overrides): the key path, the type, line and column
    let e = load_err(
        "duration: 0.05\ndt: 0.01\nribbon:\n  length: 1.0\n  width: 0.05\n  segments: many\n",
    );
    for part in [
        "bad.yaml",
        "ribbon.segments",
        "invalid type",
        "line 6 column 13",
    ] {
        assert!(e.contains(part), "`{e}` lacks `{part}`");
    }
    assert_eq!(e.matches("ribbon.segments").count(), 1, "the key once: {e}");
    // a tab where YAML wants spaces
    let e = load_err("duration: 0.05\ndt: 0.01\nribbon:\n\tlength: 1.0\n");
    assert!(e.contains("line 4 column"), "{e}");
}

#[test]
fn a_missing_scene_or_an_unwritable_bag_folder_is_named_with_the_cause() {
    let dir = scratch("cli");
    let missing = dir.join("no_such_scene.yaml");
    let out = bin().arg("run").arg(&missing).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let e = stderr(&out);
    assert!(
        e.contains(&missing.display().to_string()) && e.contains("cannot read"),
        "{e}"
    );
    assert!(e.contains("No such file"), "the OS cause is kept: {e}");

    // a bag folder whose parent is a file cannot be created
    std::fs::write(dir.join("occupied"), "x").unwrap();
    let bag = dir.join("occupied").join("bag");
    let out = bin()
        .args(["run", TORSION, "--duration", "0.05", "--record"])
        .arg(&bag)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let e = stderr(&out);
    assert!(e.contains(&bag.display().to_string()), "{e}");
    assert!(e.contains("cannot create it"), "{e}");
    assert!(!e.contains("panicked"), "{e}");
}

/// Run the binary with `args` (quoted for sh) while its files may not grow past
/// RLIMIT_FSIZE = 64 blocks of 512 bytes (`ulimit -f`), like a disk full at 32 KiB: a
/// few hundred messages of the torsion scene fit, a 2 s run does not. With SIGXFSZ
/// ignored (the disposition survives exec) the write past it fails with EFBIG. Asserts
/// that the run fails with exit code 2 and does not panic; returns its stderr, or None
/// (and says it skipped) without /bin/sh.
fn under_a_full_disk(args: &str) -> Option<String> {
    if !Path::new("/bin/sh").exists() {
        eprintln!("skipped: no /bin/sh");
        return None;
    }
    let script = format!(
        "trap '' XFSZ; ulimit -f 64 && exec '{}' {args}",
        env!("CARGO_BIN_EXE_developable_sim"),
    );
    let out = Command::new("/bin/sh")
        .args(["-c", &script])
        .output()
        .unwrap();
    let e = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{e}");
    assert!(!e.contains("panicked"), "{e}");
    Some(e)
}

#[test]
fn a_full_disk_while_recording_ends_the_run_clearly_and_keeps_the_bag_readable() {
    let dir = scratch("full_disk");
    let bag = dir.join("bag");
    let args = format!("run '{TORSION}' --record '{}'", bag.display());
    let Some(e) = under_a_full_disk(&args) else {
        return;
    };
    // the error names the bag file and the cause
    assert!(e.contains("bag_0.mcap"), "{e}");
    assert!(e.contains("File too large"), "{e}");
    let mcap = bag.join("bag_0.mcap");
    assert!(mcap.exists(), "{e}");
    // what was recorded before the failure is readable by a streaming reader
    let before = scan(&mcap).unwrap();
    assert!(before.message_count() > 0, "{e}");
    // `bag reindex` (no size limit now) rebuilds metadata.yaml and the index; nothing
    // the streaming reader saw is lost
    let out = bin().args(["bag", "reindex"]).arg(&bag).output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let after = scan(&mcap).unwrap();
    assert!(after.complete, "reindex writes a complete file");
    assert_eq!(after.message_count(), before.message_count());
    let meta = metadata(&bag);
    assert_eq!(
        meta.rosbag2_bagfile_information.message_count,
        after.message_count()
    );
    let out = bin().args(["bag", "info"]).arg(&bag).output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
}

/// The node under the same limit: it says once that recording stopped, keeps
/// simulating (and publishing) to the end of its run, then exits with code 2; the bag
/// holds what was written before the failure, and replays identical up to there.
#[test]
fn a_full_disk_while_the_node_records_is_logged_once_and_the_node_goes_on() {
    let dir = scratch("node_full_disk");
    let bag = dir.join("bag");
    let domain = (100 + std::process::id() % 100).to_string();
    // as fast as possible: 200 steps of the torsion scene, far more than 32 KiB
    let args = format!(
        "node '{TORSION}' --as-fast-as-possible --duration 2 --domain-id {domain} \
         --record '{}'",
        bag.display()
    );
    let Some(e) = under_a_full_disk(&args) else {
        return;
    };
    let stopped: Vec<&str> = e
        .lines()
        .filter(|l| l.contains("recording stopped"))
        .collect();
    assert_eq!(stopped.len(), 1, "logged once: {e}");
    assert!(
        stopped[0].contains("bag_0.mcap") && stopped[0].contains("File too large"),
        "{e}"
    );
    assert!(stopped[0].contains("the simulation goes on"), "{e}");
    // it kept simulating to the end of its duration
    assert!(e.contains("stopped at t = 2.000 s after 200 steps"), "{e}");
    // and said why it exits non-zero, last
    assert!(
        e.lines()
            .last()
            .unwrap_or("")
            .starts_with("error: recording failed"),
        "{e}"
    );
    // the bag: what was written is readable, metadata.yaml counts exactly that
    let mcap = bag.join("bag_0.mcap");
    let s = scan(&mcap).unwrap();
    let recorded = s.message_count();
    assert!(recorded > 0, "{e}");
    let status_count = s
        .topics()
        .into_iter()
        .find(|t| t.name == "/ribbon/status")
        .map(|t| t.count)
        .unwrap_or(0);
    assert!(
        status_count > 0 && status_count < 201,
        "the failure came before the end: {status_count} statuses"
    );
    let meta = metadata(&bag);
    assert_eq!(meta.rosbag2_bagfile_information.message_count, recorded);
    // replay compares everything up to the failure, and finds it identical
    let out = bin().arg("replay").arg(&bag).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", stderr(&out));
    assert!(stdout.contains("identical"), "{stdout}");
}
