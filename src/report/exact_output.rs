//! The exact-solution scenes' tables: `exact.csv`, the summary.md section and the
//! README's table (their plots are [`super::figures::exact_figures`]). An edge (writes
//! files); the numbers come from [`super::exact`].

use std::fmt::Write as _;
use std::path::Path;

use super::errors::pareto_front;
use super::exact::{order, CLAMPS, SEGMENTS};
use super::exact_run::{ExactRow, ExactSceneReport};
use super::plan::{Method, Sweep};
use super::report_error::{io, ReportError};

const EXACT_CSV_HEADER: &str = "scene,method,clamp,sweep,dt_s,segments,tolerance,steps,error_rms_m,error_relative,cpu_s,wall_s,iterations_median,unconverged_steps,stuck_steps,finite";

/// `exact.csv`: one row per run.
pub fn write_exact_csv(path: &Path, scenes: &[ExactSceneReport]) -> Result<(), ReportError> {
    let mut out = String::from(EXACT_CSV_HEADER);
    out.push('\n');
    for s in scenes {
        for r in &s.rows {
            let (e, rel) = r
                .error
                .map_or((f64::NAN, f64::NAN), |e| (e.rms, e.relative));
            let x = &r.run;
            writeln!(
                out,
                "{},{},{},{},{},{},{},{},{e:e},{rel:e},{},{},{},{},{},{}",
                s.name,
                r.spec.run.method.name(),
                r.spec.clamp,
                r.spec.run.sweep.name(),
                r.spec.run.dt,
                r.spec.run.resolution,
                r.spec.run.tolerance,
                x.steps,
                x.cpu_s,
                x.wall_s,
                x.iterations_median,
                x.unconverged_steps,
                x.stuck_steps,
                x.finite
            )?;
        }
    }
    std::fs::write(path, out).map_err(io("cannot write", path))
}

/// The clamp column: the FEM has no clamp rule (its clamp is its eliminated nodes).
fn clamp_of(r: &ExactRow) -> &'static str {
    if r.spec.run.method == Method::ConformingFem {
        "-"
    } else {
        r.spec.clamp
    }
}

/// A series of one scene: its method, clamp and sweep.
pub(crate) fn series<'a>(
    s: &'a ExactSceneReport,
    method: Method,
    clamp: &str,
    sweep: Sweep,
) -> Vec<&'a ExactRow> {
    s.rows
        .iter()
        .filter(|r| {
            r.spec.run.method == method && r.spec.clamp == clamp && r.spec.run.sweep == sweep
        })
        .collect()
}

/// (x, error) of a series, x = n (static) or dt.
pub(crate) fn xy(rows: &[&ExactRow], by_n: bool) -> Vec<(f64, f64)> {
    rows.iter()
        .filter_map(|r| {
            let x = if by_n {
                r.spec.run.resolution
            } else {
                r.spec.run.dt
            };
            r.error.map(|e| (x, e.rms))
        })
        .collect()
}

/// The series a scene's plots and order lines show: (label, method, clamp, sweep).
pub(crate) fn lines(s: &ExactSceneReport) -> Vec<(String, Method, &'static str, Sweep)> {
    let mut out = Vec::new();
    let sweep = if s.problem.is_static() {
        Sweep::Resolution
    } else {
        Sweep::TimeStep
    };
    for method in [
        Method::Chain,
        Method::GaussNewton,
        Method::Lbfgsb,
        Method::Lumped,
        Method::ConformingFem,
    ] {
        for clamp in CLAMPS {
            if !series(s, method, clamp, sweep).is_empty() {
                let label = if method == Method::ConformingFem {
                    method.name().to_string()
                } else {
                    format!("{} ({clamp})", method.name())
                };
                out.push((label, method, clamp, sweep));
            }
        }
    }
    out
}

/// The orders of every series: (label, order in n or dt).
pub fn orders(s: &ExactSceneReport) -> Vec<(String, Option<f64>)> {
    let by_n = s.problem.is_static();
    lines(s)
        .into_iter()
        .map(|(label, m, c, sw)| {
            let o = order(&xy(&series(s, m, c, sw), by_n));
            (label, if by_n { o.map(|p| -p) } else { o })
        })
        .collect()
}

/// The summary.md section of the exact-solution scenes.
pub fn exact_summary(scenes: &[ExactSceneReport]) -> Result<String, ReportError> {
    let mut md = String::new();
    writeln!(md, "## Exact solutions\n")?;
    writeln!(
        md,
        "Errors are RMS distances (m) to the exact solution at 41 x 5 material points, \
         over the sample times (src/report/exact.rs); relative = over the tip \
         displacement (cantilevers) or the midpoint rise (buckled strip). Run time is \
         the process CPU time.\n"
    )?;
    for s in scenes {
        writeln!(md, "### {}\n", s.name)?;
        writeln!(
            md,
            "{:?}, sample times {:?} s.\n",
            s.problem, s.sample_times
        )?;
        writeln!(md, "| method | clamp | sweep | n | dt (s) | tolerance | error (m) | relative | CPU (s) | iterations (median) | unconverged |")?;
        writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|")?;
        for r in &s.rows {
            let (e, rel) = r.error.map_or(("not finite".into(), "-".into()), |e| {
                (format!("{:.3e}", e.rms), format!("{:.2e}", e.relative))
            });
            writeln!(
                md,
                "| {} | {} | {} | {} | {:.4e} | {:e} | {e} | {rel} | {:.2e} | {} | {} |",
                r.spec.run.method.name(),
                clamp_of(r),
                r.spec.run.sweep.name(),
                r.spec.run.resolution,
                r.spec.run.dt,
                r.spec.run.tolerance,
                r.run.cpu_s,
                r.run.iterations_median,
                r.run.unconverged_steps
            )?;
        }
        let what = if s.problem.is_static() {
            "in n"
        } else {
            "in dt"
        };
        writeln!(
            md,
            "\nMeasured orders {what} (least-squares slope of ln error):\n"
        )?;
        for (label, o) in orders(s) {
            writeln!(
                md,
                "- {label}: {}",
                o.map_or("n/a".into(), |p| format!("{p:.2}"))
            )?;
        }
        if !s.theory.is_empty() {
            let theory = order(&s.theory);
            writeln!(
                md,
                "- implicit Euler's theory on the first mode over the same dt (its damping and phase \
                 lag, src/report/exact.rs `implicit_euler_mode_error`): errors {}, order {}",
                s.theory.iter().map(|(_, e)| format!("{e:.3e}")).collect::<Vec<_>>().join(", "),
                theory.map_or("n/a".into(), |p| format!("{p:.2}"))
            )?;
        }
        let pts: Vec<(f64, f64)> = s
            .rows
            .iter()
            .map(|r| (r.run.cpu_s, r.error.map_or(f64::NAN, |e| e.rms)))
            .collect();
        writeln!(
            md,
            "\nPareto front (error against CPU time, no run both cheaper and more accurate):\n"
        )?;
        for i in pareto_front(&pts) {
            let r = &s.rows[i];
            writeln!(
                md,
                "- {} ({}) n = {}, dt = {:.4e} s, tolerance {:e}: {:.3e} m in {:.2e} s",
                r.spec.run.method.name(),
                clamp_of(r),
                r.spec.run.resolution,
                r.spec.run.dt,
                r.spec.run.tolerance,
                pts[i].1,
                pts[i].0
            )?;
        }
        writeln!(md, "\nChecks (`report --quick` fails when one fails):\n")?;
        for c in &s.checks {
            writeln!(
                md,
                "- {}: {}: measured {}",
                if c.pass { "PASS" } else { "FAIL" },
                c.what,
                c.measured.map_or("n/a".into(), |m| format!("{m:.4}"))
            )?;
        }
        writeln!(md)?;
    }
    Ok(md)
}

/// The README's table: the static scenes' error (m and relative) at n = 10, 20, 50,
/// 100 for each clamp rule (the default solver, chain) and the measured order in n, and the
/// vibrating cantilever's order in dt. Markdown, printed by `report`.
pub fn readme_table(scenes: &[ExactSceneReport]) -> String {
    let mut md = String::from("| scene | clamp |");
    for n in SEGMENTS {
        md.push_str(&format!(" n = {n} |"));
    }
    md.push_str(" order in n |\n|---|---|");
    md.push_str(&"---|".repeat(SEGMENTS.len() + 1));
    md.push('\n');
    for s in scenes.iter().filter(|s| s.problem.is_static()) {
        for clamp in CLAMPS {
            let rows = series(s, Method::Chain, clamp, Sweep::Resolution);
            md.push_str(&format!("| {} | {clamp} |", s.name));
            for n in SEGMENTS {
                let cell = rows
                    .iter()
                    .find(|r| r.spec.run.resolution == n as f64)
                    .and_then(|r| r.error)
                    .map_or("-".into(), |e| {
                        format!("{:.2e} m ({:.3} %)", e.rms, 100.0 * e.relative)
                    });
                md.push_str(&format!(" {cell} |"));
            }
            let o = order(&xy(&rows, true)).map(|p| -p);
            md.push_str(&format!(
                " {} |\n",
                o.map_or("n/a".into(), |p| format!("{p:.2}"))
            ));
        }
    }
    for s in scenes.iter().filter(|s| !s.problem.is_static()) {
        let gn = series(s, Method::Chain, s.clamp, Sweep::TimeStep);
        let pts = xy(&gn, false);
        let o = order(&pts);
        md.push_str(&format!(
            "\n{} (n = {}): error {} at dt {} s; order in dt {} (implicit Euler's theory: {})\n",
            s.name,
            gn.first().map_or(0.0, |r| r.spec.run.resolution),
            pts.iter()
                .map(|p| format!("{:.2e} m", p.1))
                .collect::<Vec<_>>()
                .join(", "),
            pts.iter()
                .map(|p| format!("{:.2e}", p.0))
                .collect::<Vec<_>>()
                .join(", "),
            o.map_or("n/a".into(), |p| format!("{p:.2}")),
            order(&s.theory).map_or("n/a".into(), |p| format!("{p:.2}"))
        ));
    }
    md
}
