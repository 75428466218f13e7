//! Bad parameters and arguments fail before the node joins DDS, with a message that
//! names the file (or the command line) and the key, and exit code 2; a handle target
//! the object cannot reach is named while the node goes on.

use std::process::Command;

mod common;
use common::{scratch, TORSION};

const BIN: &str = env!("CARGO_BIN_EXE_developable_sim");

/// Run the binary; returns (exit code, stderr).
fn run(args: &[&str], env: &[(&str, &str)]) -> (i32, String) {
    let out = Command::new(BIN)
        .args(args)
        .envs(env.iter().copied())
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn check(args: &[&str], env: &[(&str, &str)], expected: &[&str]) {
    let (code, err) = run(args, env);
    assert_eq!(code, 2, "{args:?}: {err}");
    for e in expected {
        assert!(err.contains(e), "{args:?}: `{e}` not in: {err}");
    }
}

#[test]
fn bad_params_files_name_the_file_and_the_key() {
    let dir = scratch("params");
    let cases = [
        (
            "unknown.yaml",
            "developable_sim:\n  ros__parameters:\n    real_time_factr: 2.0\n",
            vec![
                "developable_sim.ros__parameters.real_time_factr",
                "unknown parameter",
            ],
        ),
        (
            "type.yaml",
            "/**:\n  ros__parameters:\n    as_fast_as_possible: 1\n",
            vec![
                "/**.ros__parameters.as_fast_as_possible",
                "expected a bool, got the integer 1",
            ],
        ),
        (
            "range.yaml",
            "developable_sim:\n  ros__parameters:\n    real_time_factor: -1.0\n",
            vec![
                "developable_sim.ros__parameters.real_time_factor",
                "must be > 0",
            ],
        ),
        (
            "nested.yaml",
            "developable_sim:\n  ros__parameters:\n    marker:\n      line_width: wide\n",
            vec![
                "developable_sim.ros__parameters.marker.line_width",
                "expected a double",
            ],
        ),
        (
            "format.yaml",
            "developable_sim:\n  params:\n    duration: 1.0\n",
            vec!["ros__parameters"],
        ),
        (
            "lockstep.yaml",
            "developable_sim:\n  ros__parameters:\n    lockstep: nosuch\n",
            vec!["ros__parameters.lockstep", "twist_end"],
        ),
    ];
    for (name, text, expected) in cases {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let p = path.to_str().unwrap();
        let mut expected = expected.clone();
        expected.push(p);
        check(&["node", TORSION, "--params", p], &[], &expected);
        check(
            &["node", TORSION, "--ros-args", "--params-file", p],
            &[],
            &expected,
        );
    }
    check(
        &["node", TORSION, "--params", "/nonexistent/params.yaml"],
        &[],
        &["/nonexistent/params.yaml", "cannot read"],
    );
}

#[test]
fn bad_command_line_values_are_explained() {
    check(
        &["node", TORSION, "--lockstep", "nosuch"],
        &[],
        &["--lockstep", "twist_end"],
    );
    check(
        &["node", TORSION, "--ros-args", "-p", "lockstep:=nosuch"],
        &[],
        &["command line (-p)", "lockstep"],
    );
    check(
        &["node", TORSION, "--ros-args", "-p", "duration"],
        &[],
        &["NAME:=VALUE"],
    );
    check(
        &["node", TORSION, "--ros-args", "--bogus"],
        &[],
        &["unknown ROS argument"],
    );
    check(
        &["node", TORSION],
        &[("ROS_DOMAIN_ID", "abc")],
        &["ROS_DOMAIN_ID"],
    );
    check(
        &["node", TORSION, "--domain-id", "300"],
        &[],
        &["out of range"],
    );
    check(
        &["node", TORSION, "--namespace", "/a b"],
        &[],
        &["invalid ROS name"],
    );
    check(&["node"], &[], &["no scene"]);
    check(
        &["run", TORSION, "--ros-args", "-p", "a:=1"],
        &[],
        &["--ros-args"],
    );
    check(
        &["node", TORSION, "--set", "ribbon.segments=1"],
        &[],
        &["ribbon.segments"],
    );
}

#[test]
fn a_bag_folder_in_use_is_refused() {
    let dir = scratch("bag_in_use");
    std::fs::write(dir.join("something"), "x").unwrap();
    check(
        &[
            "run",
            TORSION,
            "--duration",
            "0.02",
            "--record",
            dir.to_str().unwrap(),
        ],
        &[],
        &["already exists"],
    );
}

#[test]
fn an_unreachable_handle_target_is_named_once_and_the_node_goes_on() {
    // Two grippers pull a 1 m inextensible ribbon to 1.5 m apart (the stress suite's
    // over-stretch): the node must say which handle cannot reach its target, once, and
    // keep stepping to the end of its duration. A random-ish domain id keeps parallel
    // runs apart (this one joins DDS).
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/config/stress/ribbon_over_stretch.yaml"
    );
    let domain = (100 + std::process::id() % 100).to_string();
    let (code, err) = run(
        &[
            "node",
            scene,
            "--as-fast-as-possible",
            "--duration",
            "1",
            "--domain-id",
            &domain,
        ],
        &[],
    );
    assert_eq!(code, 0, "{err}");
    let warnings: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("cannot reach its target"))
        .collect();
    assert_eq!(warnings.len(), 1, "{err}");
    assert!(
        warnings[0].starts_with("[developable_sim] warning: ribbon: handle '"),
        "{}",
        warnings[0]
    );
    assert!(
        err.contains("stopped at t = 1.000 s after 100 steps"),
        "{err}"
    );
}
