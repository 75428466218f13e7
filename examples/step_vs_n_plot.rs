//! The step time of ribbon_extreme_torsion against the number of elements n, per
//! solver, as a log-log PNG (the README's picture), from criterion's medians of one
//! `cargo bench --bench ribbon -- step_vs_n` run:
//!
//!     cargo bench --bench ribbon -- step_vs_n
//!     cargo run --release --example step_vs_n_plot [target/criterion] [docs/img/step_vs_n.png]
//!
//! `python3 tools/step_vs_n.py` prints the same medians as JSON.

use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let root = PathBuf::from(args.next().unwrap_or_else(|| "target/criterion".into()));
    let out = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "docs/img/step_vs_n.png".into()),
    );
    let group = root.join("step_vs_n");
    let mut series = Vec::new();
    for (kind, label) in [
        ("chain", "chain (default, O(n) per iteration)"),
        ("gauss_newton", "gauss_newton (dense)"),
        ("lbfgsb", "lbfgsb (the paper's)"),
    ] {
        let mut points = Vec::new();
        for n in [50u32, 100, 200, 400, 800, 1600] {
            let file = group
                .join(kind)
                .join(n.to_string())
                .join("new/estimates.json");
            let Ok(text) = std::fs::read_to_string(&file) else {
                continue;
            };
            let estimates: serde_json::Value = serde_json::from_str(&text)?;
            let median_ns = estimates["median"]["point_estimate"]
                .as_f64()
                .ok_or_else(|| format!("{}: no median", file.display()))?;
            points.push((f64::from(n), median_ns * 1e-6));
        }
        if !points.is_empty() {
            series.push((label.to_string(), points));
        }
    }
    let Some((_, chain)) = series.first().filter(|(l, _)| l.starts_with("chain")) else {
        return Err(format!(
            "no chain medians under {}: run the benchmark first",
            group.display()
        )
        .into());
    };
    // the slope a linear cost would have, through the chain's time at the smallest n
    let (n0, t0) = chain[0];
    let linear = chain.iter().map(|&(n, _)| (n, t0 * n / n0)).collect();
    series.push(("linear in n (from chain at n = 50)".to_string(), linear));
    developable_sim::report::write_lines(
        &out,
        "ribbon_extreme_torsion: one step against n",
        ("elements n", "median step time, ms"),
        &series,
    )?;
    println!("wrote {}", out.display());
    Ok(())
}
