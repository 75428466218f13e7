//! Bad scenes end with a message naming the file, the key and why, and a non-zero exit;
//! never a panic.

use std::path::PathBuf;
use std::process::Command;

use developable_sim::scene;

mod common;
use common::scratch;

const BASE: &str =
    "duration: 0.05\ndt: 0.01\nribbon:\n  length: 1.0\n  width: 0.05\n  segments: 10\n";

fn load_err(text: &str, sets: &[&str]) -> String {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    match scene::load_str(text, &PathBuf::from("bad.yaml"), &sets) {
        Ok(_) => panic!("scene accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn check(text: &str, sets: &[&str], expected: &[&str]) {
    let msg = load_err(text, sets);
    for e in expected {
        assert!(msg.contains(e), "message `{msg}` lacks `{e}`");
    }
}

#[test]
fn a_valid_base_scene_loads() {
    let s = scene::load_str(BASE, &PathBuf::from("ok.yaml"), &[]).expect("valid");
    assert_eq!(s.world.object_names(), ["ribbon"]);
}

#[test]
fn unknown_keys_are_named_with_their_place() {
    check(
        &format!("{BASE}  colour: red\n"),
        &[],
        &["bad.yaml", "unknown field `colour`", "line"],
    );
    check(BASE, &["ribbon.segmnts=20"], &["unknown field `segmnts`"]);
    check(BASE, &["solver.kindd=lbfgsb"], &["unknown field `kindd`"]);
}

#[test]
fn wrong_types_and_malformed_yaml_are_reported() {
    check(
        BASE,
        &["ribbon.segments=many"],
        &["bad.yaml", "segments", "invalid type"],
    );
    check("duration: [1\ndt: 0.1", &[], &["bad.yaml", "line"]);
    check("", &[], &["bad.yaml", "empty"]);
    check(BASE, &["ribbon.segments"], &["KEY=VALUE"]);
}

#[test]
fn out_of_range_values_name_the_key() {
    check(
        BASE,
        &["ribbon.width=1.5"],
        &["`ribbon.width`", "smaller than ribbon.length"],
    );
    check(
        BASE,
        &["ribbon.segments=1"],
        &["`ribbon.segments`", "at least 2"],
    );
    check(BASE, &["ribbon.density=0"], &["`ribbon.density`", "> 0"]);
    check(BASE, &["ribbon.density=-1"], &["`ribbon.density`"]);
    check(BASE, &["dt=0"], &["`dt`", "> 0"]);
    check(BASE, &["dt=-0.01"], &["`dt`"]);
    check(BASE, &["duration=.nan"], &["`duration`", "finite"]);
    check(BASE, &["gravity=[0, .inf, 0]"], &["`gravity.1`", "finite"]);
    check(
        BASE,
        &["ribbon.kinetic=heavy"],
        &["`ribbon.kinetic`", "full, lumped, quasi_static"],
    );
    check(
        BASE,
        &["solver.kind=bfgs"],
        &["`solver.kind`", "gauss_newton, lbfgsb"],
    );
    check(BASE, &["solver.tolerance=2"], &["`solver.tolerance`"]);
    check(
        BASE,
        &["ribbon.crease_bound_factor=1.5"],
        &["`ribbon.crease_bound_factor`"],
    );
}

#[test]
fn handle_mistakes_name_the_handle() {
    let with_handle = format!("{BASE}handles:\n  - name: grip\n    point: [2.0, 0.0]\n");
    check(
        &with_handle,
        &[],
        &["`handles.0.point`", "outside the ribbon"],
    );
    let dup = format!(
        "{BASE}handles:\n  - {{name: a, point: [1.0, 0.0]}}\n  - {{name: a, point: [0.5, 0.0]}}\n"
    );
    check(&dup, &[], &["`handles.1.name`", "duplicate"]);
    let axis = format!("{BASE}handles:\n  - {{name: a, point: [1.0, 0.0], position_axes: [w]}}\n");
    check(&axis, &[], &["`handles.0.position_axes`", "unknown axis"]);
    check(
        BASE,
        &["ribbon.base.mode=driven"],
        &["`ribbon.base.handle`"],
    );
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_developable_sim"))
}

#[test]
fn the_cli_exits_non_zero_with_a_clear_message_and_no_panic() {
    let dir = scratch("cli");
    let bad = dir.join("bad.yaml");
    std::fs::write(&bad, format!("{BASE}  width: 0.05\n")).unwrap();
    let out = bin().arg("run").arg(&bad).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.yaml") && err.contains("width"), "{err}");
    assert!(!err.contains("panicked"), "{err}");

    let out = bin()
        .args(["run", "/nonexistent/scene.yaml"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("/nonexistent/scene.yaml") && err.contains("cannot read"),
        "{err}"
    );

    let good = dir.join("good.yaml");
    std::fs::write(&good, BASE).unwrap();
    let out = bin()
        .arg("run")
        .arg(&good)
        .args(["--set", "ribbon.segments=zero"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("segments"));

    // and a good run writes the stats contract
    let stats = dir.join("stats.json");
    let out = bin()
        .arg("run")
        .arg(&good)
        .arg("--stats")
        .arg(&stats)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    for key in [
        "scene",
        "dt",
        "steps",
        "finite",
        "step_ms",
        "solver",
        "gradient_us",
        "isometry_error_max",
        "constraint_violation_max",
        "singular_points_max",
        "final",
    ] {
        assert!(json.get(key).is_some(), "stats lack `{key}`");
    }
    assert_eq!(json["steps"], 5);
    assert_eq!(json["finite"], true);
    for key in ["median", "p95", "max"] {
        assert!(json["step_ms"][key].as_f64().unwrap() > 0.0);
    }
    let obj = &json["final"]["objects"][0];
    assert_eq!(obj["name"], "ribbon");
    assert_eq!(obj["vertices"].as_array().unwrap().len(), 22);
    assert_eq!(obj["triangles"].as_array().unwrap().len(), 20);
    assert_eq!(obj["material_vertices"].as_array().unwrap().len(), 22);
    assert_eq!(obj["crease_direction"].as_array().unwrap().len(), 11);
    assert_eq!(obj["bending_angle"].as_array().unwrap().len(), 11);
    std::fs::remove_dir_all(&dir).ok();
}
