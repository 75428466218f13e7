//! `developable_sim report --quick` on two tiny scenes, in process: a coarse cantilever
//! compared with its own reference and the exact-solution heavy cantilever. The CSV's
//! rows and columns, finite positive errors, the default solver's error falling with
//! dt, the dense solver sharing its iterates, the FEM baseline's row, CPU run times of
//! one-thread runs, the summary; and every plot's SVG read back by its text
//! (`plot::svg_check`): one label per decade on both axes, no two text boxes
//! overlapping, every legend entry present, a caption; PNGs of the same size beside
//! them; index.html with every plot inline.

use std::path::{Path, PathBuf};

use developable_sim::plot::svg_check::{
    axis_labels, decade_problems, label_value, missing_entries, overlapping, text_boxes,
};
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

/// The report of the tiny cantilever and the exact-solution heavy cantilever (a copy of
/// the shipped scene: its quick plan is static solves of a few ms), made once.
fn tiny_report() -> &'static Path {
    static OUT: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    OUT.get_or_init(|| {
        let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("report_test");
        let scenes = root.join("scenes");
        let out = root.join("out");
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(&scenes).unwrap();
        std::fs::write(scenes.join("tiny_cantilever.yaml"), TINY_CANTILEVER).unwrap();
        let exact =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("config/scenes/exact_heavy_cantilever.yaml");
        std::fs::copy(exact, scenes.join("exact_heavy_cantilever.yaml")).unwrap();
        let opts = ReportOptions {
            scene_dir: scenes,
            scenes: Some("*".into()),
            quick: true,
            out: out.clone(),
            progress: false,
        };
        run_report(&opts, "test").expect("report");
        out
    })
}

#[test]
fn quick_report_on_a_tiny_cantilever() {
    let out = tiny_report();

    let csv = std::fs::read_to_string(out.join("report.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some(CSV_HEADER));
    let columns: Vec<&str> = CSV_HEADER.split(',').collect();
    let col = |name: &str| columns.iter().position(|c| *c == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    for r in &rows {
        assert_eq!(r.len(), columns.len(), "{r:?}");
    }
    // reference + its 2 dt and 4 dt checks + 3 chain + gauss_newton (dense) + lbfgsb +
    // chain_lumped + conforming_fem
    assert_eq!(rows.len(), 10, "{csv}");
    assert_eq!(rows[0][col("method")], "chain");
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
    // the dense solver takes chain's iterates: its run is within round-off of chain's
    // at the same dt (the solvers stop at a relative gradient of 1e-6, so not bit for
    // bit: measured 2026-12-07, < 1e-9 m)
    let dense = rows
        .iter()
        .find(|r| r[col("method")] == "gauss_newton")
        .expect("a dense run");
    let to_chain: f64 = dense[col("to_default_rms_m")].parse().expect("distance");
    assert!(to_chain < 1e-6, "gauss_newton is {to_chain} m from chain");
    // implicit Euler converges: halving dt must lower the error against the reference
    let mut fast: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r[col("method")] == "chain" && r[col("sweep")] == "dt")
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

/// The PNG's size, px.
fn png_size(path: &Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    ));
    let reader = decoder.read_info().expect("a valid PNG");
    (reader.info().width, reader.info().height)
}

/// The SVG's width and height attributes, px.
fn svg_size(svg: &str) -> (u32, u32) {
    let attr = |name: &str| -> u32 {
        let key = format!("{name}=\"");
        let start = svg.find(&key).unwrap() + key.len();
        svg[start..].split('"').next().unwrap().parse().unwrap()
    };
    (attr("width"), attr("height"))
}

/// Check one plot: its PNG and SVG of one size, one label per decade on each axis, no
/// two text boxes overlapping, every `legend` entry, a caption saying what was swept
/// and what the error is measured against.
fn check_plot(out: &Path, stem: &str, legend: &[&str], against: &str) -> String {
    let svg = std::fs::read_to_string(out.join(format!("{stem}.svg"))).unwrap();
    assert_eq!(png_size(&out.join(format!("{stem}.png"))), svg_size(&svg));
    let boxes = text_boxes(&svg).unwrap();
    let overlaps = overlapping(&boxes);
    assert!(
        overlaps.is_empty(),
        "{stem}: overlapping text: {overlaps:#?}"
    );
    let (x, y) = axis_labels(&boxes);
    for (axis, labels) in [("x", &x), ("y", &y)] {
        let problems = decade_problems(labels, label_value);
        let texts: Vec<&str> = labels.iter().map(|b| b.text.as_str()).collect();
        assert!(
            problems.is_empty(),
            "{stem} {axis}: {problems:?} in {texts:?}"
        );
    }
    let missing = missing_entries(&boxes, legend);
    assert!(missing.is_empty(), "{stem}: no legend entry {missing:?}");
    let caption = missing_entries(&boxes, &["Swept: ", against]);
    assert!(caption.is_empty(), "{stem}: the caption lacks {caption:?}");
    svg
}

/// The plots a reader trusts: decades in engineering units, nothing overlapping, every
/// mark in the legend (the default solver named as such, the Pareto front, the
/// reference's own error), a caption; and index.html with each of them inline.
#[test]
fn every_plot_labels_its_decades_and_names_every_mark() {
    let out = tiny_report();
    let method = |m: &str| format!("{m}: dt sweep");
    let mut legend: Vec<String> = [
        "chain (the default solver)",
        "gauss_newton (dense matrix: chain's iterates, its cost)",
        "lbfgsb (the paper's L-BFGS-B)",
        "chain_lumped (mass lumped on the centerline)",
        "conforming_fem (triangle-mesh baseline)",
    ]
    .iter()
    .map(|m| method(m))
    .collect();
    legend.push("Pareto front: no run is both cheaper and more accurate".into());
    legend.push("reference's own error".into());
    let legend: Vec<&str> = legend.iter().map(String::as_str).collect();
    let mut svgs = vec![check_plot(
        out,
        "tiny_cantilever",
        &legend,
        "Error: RMS distance at 205 material points over 5 sample times to a reference run of ours",
    )];
    let chain = "chain (the default solver, clamp moment_matched, the scene's)";
    let exact = "Error: RMS distance at 205 material points to the exact solution";
    svgs.push(check_plot(
        out,
        "exact_heavy_cantilever",
        &[
            chain,
            "chain (the default solver, clamp paper)",
            "gauss_newton (dense, clamp moment_matched, the scene's)",
            "lbfgsb (clamp moment_matched, the scene's)",
            "Pareto front",
        ],
        exact,
    ));
    let order = check_plot(out, "exact_heavy_cantilever_order", &[chain], exact);
    // its errors are chain's: left out of the error-against-n plot, and said so
    assert!(
        !order.contains("gauss_newton (dense, clamp"),
        "the dense line is drawn"
    );
    assert!(missing_entries(
        &text_boxes(&order).unwrap(),
        &["gauss_newton (dense) is not drawn"]
    )
    .is_empty());
    svgs.push(order);
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for svg in &svgs {
        let inline = &svg[svg.find("<svg").unwrap()..];
        assert!(html.contains(inline), "a plot is not inline in index.html");
    }
    for section in ["id=\"tiny_cantilever\"", "id=\"exact_heavy_cantilever\""] {
        assert!(html.contains(section), "no {section}");
    }
    assert!(
        html.contains("For an error under"),
        "no Pareto front in words"
    );
    assert!(html.contains("order in n of chain (moment_matched) &gt;= 1.8"));
}

/// The committed full report (docs/img/report, what docs/accuracy.md and the README
/// show) passes the same checks as the tiny one: every plot's SVG has one label per
/// decade on both axes, no two text boxes overlapping, a caption and a PNG of its size
/// beside it, and is inline in the committed index.html, which names the command that
/// made it. (Regenerating the report by hand cannot leave an illegible plot behind.)
#[test]
fn the_committed_full_report_passes_the_same_checks() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/img/report");
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert!(html.contains("<code>developable_sim report --out docs/img/report</code>"));
    let mut stems: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| {
            let name = e.unwrap().file_name().into_string().unwrap();
            name.strip_suffix(".svg").map(str::to_string)
        })
        .collect();
    stems.sort();
    // three scenes against a reference, three exact ones with an order plot each
    assert_eq!(stems.len(), 9, "{stems:?}");
    for stem in &stems {
        let against = if stem.starts_with("exact_") {
            "to the exact solution"
        } else {
            "to a reference run of ours"
        };
        let svg = check_plot(&dir, stem, &[], against);
        let inline = &svg[svg.find("<svg").unwrap()..];
        assert!(html.contains(inline), "{stem} is not inline in index.html");
    }
}
