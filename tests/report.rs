//! `developable_sim report --quick` on one tiny scene, in process: the CSV's rows and
//! columns, finite positive errors, the fast solver's error falling with dt, the FEM
//! baseline's row, CPU run times of one-thread runs, valid PNG plots and the summary.

use std::path::PathBuf;

use developable_sim::report::{output::CSV_HEADER, run_report, ReportOptions};

/// A short cantilever: a coarse ribbon held at one end swings down under gravity (the
/// quick plan: a reference at 1/32 of the sample interval and its runs at 2 and 4 dt,
/// three time steps of the fast solver, one run each of L-BFGS-B, the lumped model and
/// the conforming FEM).
/// A smooth motion, so implicit Euler's error must fall with dt. (A twisted flat strip
/// buckles, a bifurcation seeded by a 1e-6 rad imperfection, and the helix unrolling
/// whips within hundredths of a second: at the quick time steps neither error is
/// guaranteed monotone in dt.)
const TINY_CANTILEVER: &str = "\
name: tiny_cantilever
duration: 0.2
dt: 0.01
gravity: [0.0, 0.0, -9.81]
solver: {kind: gauss_newton, tolerance: 1.0e-6}
ribbon:
  length: 0.5
  width: 0.05
  segments: 12
  density: 0.1
  bending_stiffness: 0.01
  crease_regularizer: 0.1
  kinetic: full
  base: {mode: fixed}
  initial_shape: {kind: flat}
";

#[test]
fn quick_report_on_a_tiny_cantilever() {
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("report_test");
    let scenes = root.join("scenes");
    let out = root.join("out");
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&scenes).unwrap();
    std::fs::write(scenes.join("tiny_cantilever.yaml"), TINY_CANTILEVER).unwrap();
    let opts = ReportOptions {
        scene_dir: scenes,
        scenes: Some("tiny_cantilever".into()),
        quick: true,
        out: out.clone(),
        progress: false,
    };
    run_report(&opts, "test").expect("report");

    let csv = std::fs::read_to_string(out.join("report.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some(CSV_HEADER));
    let columns: Vec<&str> = CSV_HEADER.split(',').collect();
    let col = |name: &str| columns.iter().position(|c| *c == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    for r in &rows {
        assert_eq!(r.len(), columns.len(), "{r:?}");
    }
    // reference + its 2 dt and 4 dt checks + 3 gauss_newton + lbfgsb + lumped +
    // conforming_fem
    assert_eq!(rows.len(), 9, "{csv}");
    assert_eq!(rows[0][col("sweep")], "reference");
    assert_eq!(rows[1][col("sweep")], "reference_2dt");
    assert_eq!(rows[2][col("sweep")], "reference_4dt");
    // a smooth motion: no reference step is stuck at its start
    for r in &rows[..3] {
        assert_eq!(r[col("stuck_steps")], "0", "{r:?}");
    }
    for r in &rows {
        // run time is the process CPU time; every run is on one thread, so it cannot
        // exceed the wall time (5 % + 5 ms: the two clocks are read one after another)
        let wall: f64 = r[col("wall_s")].parse().unwrap();
        let cpu: f64 = r[col("cpu_s")].parse().unwrap();
        assert!(
            cpu > 0.0 && cpu <= 1.05 * wall + 5e-3,
            "cpu {cpu} s, wall {wall} s: {r:?}"
        );
        let per_sim: f64 = r[col("cpu_per_simulated_s")].parse().unwrap();
        assert!(
            (per_sim - cpu / 0.2).abs() <= 1e-5 * (1.0 + per_sim),
            "{r:?}"
        );
    }
    // the reference's own error (its run at 2 dt against it) is below the error of
    // every swept run: they are all coarser
    let ref_err: f64 = rows[1][col("error_rms_m")]
        .parse()
        .expect("reference_2dt error");
    let ref_err_4dt: f64 = rows[2][col("error_rms_m")]
        .parse()
        .expect("reference_4dt error");
    assert!(ref_err_4dt > ref_err, "{ref_err_4dt} <= {ref_err}");
    for r in &rows[3..] {
        let e: f64 = r[col("error_rms_m")].parse().expect("error_rms_m");
        let end: f64 = r[col("error_end_m")].parse().expect("error_end_m");
        assert!(e.is_finite() && e > 0.0, "{r:?}");
        assert!(end.is_finite() && end > 0.0, "{r:?}");
        let wall: f64 = r[col("wall_s")].parse().unwrap();
        assert!(wall > 0.0, "{r:?}");
        assert_eq!(r[col("finite")], "true", "{r:?}");
        if r[col("method")] != "conforming_fem" {
            assert!(e > ref_err, "reference error {ref_err} not below {r:?}");
        }
    }
    // implicit Euler converges: halving dt must lower the error against the reference
    let mut fast: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r[col("method")] == "gauss_newton" && r[col("sweep")] == "dt")
        .map(|r| {
            (
                r[col("dt_s")].parse().unwrap(),
                r[col("error_rms_m")].parse().unwrap(),
            )
        })
        .collect();
    assert_eq!(fast.len(), 3);
    fast.sort_by(|a, b| b.0.total_cmp(&a.0));
    for w in fast.windows(2) {
        assert!(
            w[1].1 < w[0].1,
            "error does not fall with dt: {:?} then {:?}",
            w[0],
            w[1]
        );
    }
    assert!(
        rows.iter().any(|r| r[col("method")] == "conforming_fem"),
        "no FEM baseline row"
    );

    let png_path = out.join("tiny_cantilever.png");
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&png_path).expect("plot written"),
    ));
    let reader = decoder.read_info().expect("a valid PNG");
    let info = reader.info();
    assert_eq!((info.width, info.height), (900, 600));

    let summary = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(summary.contains("## tiny_cantilever"), "{summary}");
    assert!(summary.contains("Order in time"), "{summary}");
    assert!(
        summary.contains("Run time = CPU time of the process during the run"),
        "{summary}"
    );
    assert!(summary.contains("every run used one thread"), "{summary}");
    assert!(summary.contains("The reference's own error"), "{summary}");
    assert!(
        summary.contains("local order of the reference's halvings"),
        "{summary}"
    );
    assert!(!summary.contains("stuck at their start"), "{summary}");
}
