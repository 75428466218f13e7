//! The suite's pages: `stress.md` (the pass/fail table and how to read it) and
//! `index.html` (the same table and, per case, its energy over time against its bound,
//! one SVG plot inline per case, no external resource). An edge: strings out; the
//! caller writes them.

use std::fmt::Write as _;

use plotters::style::RGBColor;

use super::{cases, CaseResult, StressReport, DEFAULT_ALLOWANCE};
use crate::plot::axis::{engineering, Scale, Unit};
use crate::plot::page::{escape, inline_svg, STYLE};
use crate::plot::{svg, Axis, Figure, PlotError, Series, Style};

/// The pass/fail table and how to read it.
pub fn markdown(report: &StressReport) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "# Stress suite{}\n\n{} of {} runs passed, {:.1} s wall time. Each case's energy \
         over time against its bound: `index.html` beside this file.\n\n",
        if report.quick { " (--quick)" } else { "" },
        report.passed,
        report.results.len(),
        report.wall_s
    ));
    s.push_str(
        "Pass: every state finite; at every step E(t) - E(0) <= W(t) + tol(t), with E the total \
         energy (kinetic + elastic + gravity + external; gravity's work is in E as its \
         potential), W(t) the summed work bound of handles and point forces (|F| |dx| per step: \
         the force at the end of the step times the displacement of the point it acts on) and \
         tol(t) = ",
    );
    s.push_str(&format!(
        "r (S(0) + W(t)) + {:e} J with S(0) the kinetic + elastic energy at t = 0 (all \
         relative to the initial state: moving the scene changes nothing) and r = {} for ribbons \
         and {} for paper (its remeshing and isometry projection move S_P between FEM steps with \
         no energy balance); at most {} % of the steps unconverged (iteration limit) and none \
         rejected (non-finite result, previous state kept), unless the case's allowance says \
         otherwise (listed below with its reason); over_stretch: the reported violation reaches \
         (1.5 m - l)/2 = 0.25 m.\n\n",
        report.energy_absolute_tolerance_j,
        report.energy_relative_tolerance,
        report.paper_energy_relative_tolerance,
        report.unconverged_fraction * 100.0
    ));
    s.push_str("| case | dt (s) | steps | finite | E rise max (J) | W bound (J) | rise / allowance | violation max (m) | paper: largest edge strain, any frame; edges over 1 % at the end | unconverged | rejected | result |\n");
    s.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for r in &report.results {
        let strain = match (r.strain_max_pct, r.strained_edges_pct) {
            (Some(most), Some(share)) => format!("{most:.2} %; {share:.1} %"),
            _ => "-".to_string(),
        };
        s.push_str(&format!(
            "| {} | {} | {} | {} | {:.3e} | {:.3e} | {:.3} | {:.3e} | {} | {} | {} | {} |\n",
            r.case,
            r.dt,
            r.steps,
            if r.finite { "yes" } else { "**no**" },
            r.energy_rise_max,
            r.work_bound,
            r.energy_ratio_max,
            r.constraint_violation_max,
            strain,
            r.unconverged_steps,
            r.rejected_steps,
            if r.pass {
                "pass".to_string()
            } else {
                format!("**FAIL**: {}", r.reason)
            }
        ));
    }
    s.push_str("\nCases:\n\n");
    for c in cases() {
        let a = c.allowance;
        let allowance = if a == DEFAULT_ALLOWANCE {
            String::new()
        } else {
            format!(
                "; allowed {} % unconverged, {} rejected: {}",
                a.unconverged_fraction * 100.0,
                a.rejected_steps,
                a.reason
            )
        };
        s.push_str(&format!(
            "- `{}`: {} (`config/{}`){allowance}\n",
            c.name, c.description, c.scene
        ));
    }
    s
}

/// A run's colour in its case's plot, by its place among the case's time steps.
const PALETTE: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
];

/// One case's plot: per time step the energy's rise E(t) - E(0) (solid) and its bound
/// W(t) + tol(t) (dashed, same colour), against simulated time.
fn case_figure(name: &str, runs: &[&CaseResult]) -> Figure {
    let mut series = Vec::new();
    for (i, r) in runs.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let dt = engineering(r.dt, Unit::Second);
        series.push(Series {
            label: format!("dt = {dt}: E(t) - E(0)"),
            color,
            points: r.energy_series.iter().map(|e| (e.t_s, e.rise_j)).collect(),
            style: Style::Plain,
        });
        series.push(Series {
            label: format!("dt = {dt}: its bound W(t) + tol(t)"),
            color,
            points: r
                .energy_series
                .iter()
                .map(|e| (e.t_s, e.allowance_j))
                .collect(),
            style: Style::Dashed,
        });
    }
    Figure {
        title: format!("{name}: energy against its bound"),
        x: Axis {
            desc: "simulated time".into(),
            unit: Unit::Second,
            scale: Scale::Linear,
        },
        y: Axis {
            desc: "energy relative to t = 0".into(),
            unit: Unit::Joule,
            scale: Scale::Linear,
        },
        series,
        levels: Vec::new(),
        caption: "Swept: the time step dt. Solid: the rise of the total energy (kinetic + \
                  elastic + gravity + external) since t = 0; dashed: its bound, the work \
                  handles and forces did on the objects plus the tolerance. A run passes \
                  while solid stays under dashed (and it stays finite and converged)."
            .into(),
    }
}

/// A run's row: dt, steps, the energy margin, violation, steps converged, verdict.
fn row(r: &CaseResult) -> String {
    format!(
        "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td>\
         <td>{}</td><td>{} of {}</td><td>{}</td><td class=\"{}\">{}</td></tr>\n",
        escape(&r.case),
        engineering(r.dt, Unit::Second),
        r.steps,
        engineering(r.energy_rise_max, Unit::Joule),
        engineering(r.work_bound, Unit::Joule),
        r.energy_ratio_max,
        engineering(r.constraint_violation_max, Unit::Metre),
        r.object_steps.saturating_sub(r.unconverged_steps),
        r.object_steps,
        r.rejected_steps,
        if r.pass { "pass" } else { "fail" },
        if r.pass {
            "pass".to_string()
        } else {
            format!("FAIL: {}", escape(&r.reason))
        }
    )
}

const TABLE_HEAD: &str = "<table>\n<tr><th>case</th><th>dt</th><th>steps</th><th>largest \
    E(t) - E(0)</th><th>W at the end</th><th>largest rise / allowance</th><th>largest \
    constraint violation</th><th>object steps converged</th><th>rejected</th>\
    <th>result</th></tr>\n";

/// `index.html`: the verdicts, how a run is judged, and per case its plot and rows.
pub(super) fn index(report: &StressReport) -> Result<String, PlotError> {
    let mut h = String::from(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>Stress suite</title>\n<style>\n",
    );
    h.push_str(STYLE);
    h.push_str("</style>\n</head>\n<body>\n");
    let _ = writeln!(
        h,
        "<h1>Stress suite{}</h1>\n<p>{} of {} runs passed, {:.1} s wall time. A run \
         passes when every state is finite, the total energy never rises above the work \
         done on the objects plus a tolerance (E(t) - E(0) &lt;= W(t) + r (S(0) + W(t)) \
         + {:e} J, r = {} for ribbons and {} for paper; S(0) the kinetic and elastic \
         energy at t = 0), at most {} % of the steps stop unconverged and none is \
         rejected, unless the case states an allowance and why (below). \
         <code>stress.md</code> and <code>stress.json</code> beside this page hold the \
         same numbers.</p>",
        if report.quick { " (--quick)" } else { "" },
        report.passed,
        report.results.len(),
        report.wall_s,
        report.energy_absolute_tolerance_j,
        report.energy_relative_tolerance,
        report.paper_energy_relative_tolerance,
        report.unconverged_fraction * 100.0
    );
    h.push_str(TABLE_HEAD);
    for r in &report.results {
        h.push_str(&row(r));
    }
    h.push_str("</table>\n");
    for c in cases() {
        let runs: Vec<&CaseResult> = report.results.iter().filter(|r| r.case == c.name).collect();
        if runs.is_empty() {
            continue;
        }
        let _ = writeln!(
            h,
            "<h2 id=\"{0}\">{0}</h2>\n<p>{1} (<code>config/{2}</code>).{3}</p>",
            escape(c.name),
            escape(c.description),
            escape(c.scene),
            if c.allowance == DEFAULT_ALLOWANCE {
                String::new()
            } else {
                format!(
                    " Allowed: {} % unconverged, {} rejected: {}.",
                    c.allowance.unconverged_fraction * 100.0,
                    c.allowance.rejected_steps,
                    escape(c.allowance.reason)
                )
            }
        );
        let plot = svg(&case_figure(c.name, &runs))?;
        let _ = writeln!(h, "<figure>{}</figure>", inline_svg(&plot));
        h.push_str(TABLE_HEAD);
        for r in runs {
            h.push_str(&row(r));
        }
        h.push_str("</table>\n");
    }
    h.push_str("</body>\n</html>\n");
    Ok(h)
}
