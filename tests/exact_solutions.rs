//! The exact-solution scenes against the planar elastica (issue 15), through the
//! report's exact-solution path (src/report/exact.rs): the heavy cantilever and the
//! buckled strip converge at second order in n with the moment-matched clamp, the
//! vibrating cantilever at first order in dt; the checks `report --quick` exits on
//! fail on the paper's first-order clamp, in process and through the binary's exit
//! code.

use std::path::{Path, PathBuf};
use std::process::Command;

use developable_sim::report::exact::{vibration_bending_angles, ExactProblem, VIBRATION_TIP};
use developable_sim::report::exact_run::{problem_of, run_exact_scene};

mod common;
use common::{scene_path, scratch};

/// A copy of a scene with `from` replaced by `to` in its text, in a fresh folder.
fn variant(name: &str, dir: &str, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(scene_path(name)).unwrap();
    assert!(text.contains(from), "{name} has no `{from}`");
    let folder = scratch(dir);
    let file = folder.join(format!("{name}.yaml"));
    std::fs::write(&file, text.replace(from, to)).unwrap();
    file
}

/// The vibrating cantilever's start in the scene file is the generated first mode.
#[test]
fn the_vibrating_scene_starts_in_the_first_mode() {
    let s = developable_sim::scene::load(&scene_path("exact_vibrating_cantilever"), &[]).unwrap();
    let listed = s
        .source
        .ribbon
        .as_ref()
        .unwrap()
        .initial_shape
        .bending_angles
        .clone()
        .unwrap();
    let generated = vibration_bending_angles(1.0, 50, VIBRATION_TIP);
    assert_eq!(listed.len(), generated.len());
    for (a, b) in listed.iter().zip(&generated) {
        assert!((a - b).abs() < 1e-17 + 1e-12 * b.abs(), "{a} vs {b}");
    }
}

fn run_quick(file: &Path) -> developable_sim::report::exact_run::ExactSceneReport {
    let problem = problem_of(file).unwrap().expect("an exact-solution scene");
    let name = file.file_stem().unwrap().to_str().unwrap().to_string();
    run_exact_scene(file, &name, problem, true, &mut |_| {}).unwrap()
}

/// Both static scenes pass their checks (order in n >= 1.8, 0.2 % at n = 50) with the
/// default clamp; the paper's clamp fails the order check (first order).
#[test]
fn static_scenes_converge_at_second_order_and_the_paper_clamp_does_not() {
    for name in ["exact_heavy_cantilever", "exact_buckled_strip"] {
        let r = run_quick(&scene_path(name));
        assert!(matches!(
            r.problem,
            ExactProblem::HeavyCantilever { .. } | ExactProblem::BuckledStrip { .. }
        ));
        for c in &r.checks {
            assert!(c.pass, "{name}: {c:?}");
        }
        // the paper's rule in the same report: about first order
        let paper = developable_sim::report::exact_output::orders(&r)
            .into_iter()
            .find(|(label, _)| label == "chain (paper)")
            .and_then(|(_, o)| o)
            .unwrap();
        assert!(paper < 1.3, "{name}: the paper clamp's order {paper}");
    }
}

/// The pass criterion bites: the same scene on Pan et al.'s clamp (first order in n)
/// fails its order check in process, and `report --quick` on it exits non-zero.
#[test]
fn the_paper_clamp_fails_the_report() {
    let paper = variant(
        "exact_heavy_cantilever",
        "exact_paper_clamp",
        "clamp: moment_matched",
        "clamp: paper",
    );
    let r = run_quick(&paper);
    assert_eq!(r.clamp, "paper");
    let order = &r.checks[0];
    assert!(!order.pass, "{order:?}");
    assert!(order.measured.unwrap() < 1.3, "{order:?}");
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("exact_paper_clamp_out");
    let status = Command::new(env!("CARGO_BIN_EXE_developable_sim"))
        .args([
            "report",
            "--quick",
            "--scenes",
            "exact_heavy_cantilever",
            "--scene-dir",
        ])
        .arg(paper.parent().unwrap())
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&status.stderr);
    assert!(!status.status.success(), "{stderr}");
    assert!(stderr.contains("regressed"), "{stderr}");
    // and it still wrote its files
    assert!(out.join("exact.csv").exists() && out.join("summary.md").exists());
    assert!(out.join("index.html").exists());
    // the scene as shipped passes through the binary
    let ok_out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("exact_ok_out");
    let ok = Command::new(env!("CARGO_BIN_EXE_developable_sim"))
        .args([
            "report",
            "--quick",
            "--scenes",
            "exact_heavy_cantilever",
            "--out",
        ])
        .arg(&ok_out)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let stdout = String::from_utf8_lossy(&ok.stdout);
    assert!(
        stdout.contains("| exact_heavy_cantilever | moment_matched |"),
        "{stdout}"
    );
}

/// The vibrating cantilever's error falls at first order in dt (implicit Euler).
#[test]
fn the_vibrating_cantilever_is_first_order_in_dt() {
    let r = run_quick(&scene_path("exact_vibrating_cantilever"));
    for c in &r.checks {
        assert!(c.pass, "{c:?}");
    }
    assert!(!r.theory.is_empty());
}
