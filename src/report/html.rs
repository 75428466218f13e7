//! `index.html`: the whole report on one self-contained page (the SVG plots inline,
//! the style inline, no script, no network): per compared scene the plot, which run
//! to pick for an accuracy (the Pareto front in words), where a curve is not monotone
//! and the measured reason, the reference and its own error, every run in a table; per
//! exact-solution scene its two plots, its orders with their pass criteria, the front
//! and the table. An edge (writes a file); the sentences come from
//! [`super::findings`].

use std::fmt::Write as _;
use std::path::Path;

use super::axis::{engineering, Unit};
use super::exact::CLAMPS;
use super::exact_output::orders;
use super::exact_run::{ExactRow, ExactSceneReport};
use super::figures::{reference_band, resolution_words, row_facts};
use super::findings::{front_in_words, rises_in_words, Refines, RiseContext, RunFacts};
use super::output::SceneReport;
use super::plan::{Method, Sweep};
use super::report_error::{io, ReportError};

/// Everything the page shows.
pub struct Page<'a> {
    /// The command that made the report (quoted on the page).
    pub command: &'a str,
    pub quick: bool,
    /// Wall and CPU time of the whole report, s.
    pub wall_s: f64,
    pub cpu_s: f64,
    pub scenes: &'a [SceneReport],
    /// The SVG of each scene's plot, in `scenes`' order.
    pub scene_svgs: &'a [String],
    pub exact: &'a [ExactSceneReport],
    /// The SVGs of each exact scene's plots: (error against run time, against n or dt).
    pub exact_svgs: &'a [(String, String)],
}

const STYLE: &str = include_str!("report.css");

/// `text` escaped for HTML text and attribute values.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// `text` escaped, with `code` spans (backticks, as in summary.md) as `<code>`.
fn prose(text: &str) -> String {
    escape(text)
        .split('`')
        .enumerate()
        .map(|(i, part)| {
            if i % 2 == 1 {
                format!("<code>{part}</code>")
            } else {
                part.to_string()
            }
        })
        .collect()
}

/// An SVG document as an inline element (from `<svg` on: no XML prolog).
fn inline_svg(svg: &str) -> &str {
    svg.find("<svg").map_or(svg, |i| &svg[i..])
}

fn s(v: f64) -> String {
    engineering(v, Unit::Second)
}
fn m(v: f64) -> String {
    engineering(v, Unit::Metre)
}

/// A table: `head` cells, then `rows` (cells already HTML); a row whose first cell is
/// flagged gets the `default` class (bold).
fn table(head: &[&str], rows: &[(bool, Vec<String>)]) -> String {
    let mut t = String::from("<table>\n<tr>");
    for h in head {
        let _ = write!(t, "<th>{}</th>", escape(h));
    }
    t.push_str("</tr>\n");
    for (bold, cells) in rows {
        t.push_str(if *bold {
            "<tr class=\"default\">"
        } else {
            "<tr>"
        });
        for c in cells {
            let _ = write!(t, "<td>{c}</td>");
        }
        t.push_str("</tr>\n");
    }
    t.push_str("</table>\n");
    t
}

/// A list of sentences (escaped), or `empty` in a paragraph.
fn list(items: &[String], empty: &str) -> String {
    if items.is_empty() {
        return format!("<p>{}</p>\n", prose(empty));
    }
    let mut out = String::from("<ul>\n");
    for i in items {
        let _ = writeln!(out, "<li>{}</li>", prose(i));
    }
    out.push_str("</ul>\n");
    out
}

/// Steps converged: "40 of 40" or "39 of 40 (1 stuck)".
fn converged(steps: usize, unconverged: usize, stuck: usize) -> String {
    let mut c = format!("{} of {}", steps.saturating_sub(unconverged), steps);
    if stuck > 0 {
        let _ = write!(c, " ({stuck} stuck)");
    }
    c
}

/// The whole page.
pub fn index(page: &Page) -> String {
    let mut h = String::new();
    h.push_str(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>Error against run time</title>\n<style>\n",
    );
    h.push_str(STYLE);
    h.push_str("</style>\n</head>\n<body>\n");
    h.push_str(&opening(page));
    for (sc, svg) in page.scenes.iter().zip(page.scene_svgs) {
        h.push_str(&scene_section(sc, svg));
    }
    if !page.exact.is_empty() {
        h.push_str(
            "<h2 id=\"exact\">Against exact solutions</h2>\n<p>These scenes have an \
             exact solution (core/src/metrics/elastica.rs); every run is measured against \
             it, not against a run of ours, so their errors are accuracy, not \
             consistency.</p>\n",
        );
    }
    for (e, svgs) in page.exact.iter().zip(page.exact_svgs) {
        h.push_str(&exact_section(e, svgs));
    }
    h.push_str("</body>\n</html>\n");
    h
}

/// The title, how the report was made, how to read it, the contents.
fn opening(page: &Page) -> String {
    let mut h = String::from("<h1>Error against run time</h1>\n");
    let _ = writeln!(
        h,
        "<p>Generated by <code>{}</code> ({} report, {:.0} s wall, {:.0} s CPU). The \
         same numbers as <code>summary.md</code>, <code>report.csv</code> and \
         <code>exact.csv</code> beside this page; the plots are also there as PNG and \
         SVG.</p>",
        escape(page.command),
        if page.quick { "quick" } else { "full" },
        page.wall_s,
        page.cpu_s
    );
    h.push_str(
        "<p><b>How to read the plots.</b> Each mark is one run; a line joins one \
         method's runs over its swept time step (or n). The default solver, \
         <code>chain</code>, is the bold blue line; <code>gauss_newton</code> is the \
         same method on the dense matrix (the same iterates, so the same error, at its \
         own cost). The wide grey staircase is the Pareto front: the runs no other run \
         beats in both run time and error. Where the error is measured against a \
         reference run of ours, the shaded band is that reference's own error: errors \
         inside it are not resolved. <b>Run time</b> is the process CPU time of a run on \
         one thread (it equals wall time on an idle machine and is not inflated by \
         other work on a shared one).</p>\n<nav><ul>\n",
    );
    for sc in page.scenes {
        let _ = writeln!(h, "<li><a href=\"#{0}\">{0}</a></li>", escape(&sc.name));
    }
    for e in page.exact {
        let _ = writeln!(h, "<li><a href=\"#{0}\">{0}</a></li>", escape(&e.name));
    }
    h.push_str("</ul></nav>\n");
    h
}

/// One compared scene.
fn scene_section(sc: &SceneReport, svg: &str) -> String {
    let mut h = format!("<h2 id=\"{0}\">{0}</h2>\n", escape(&sc.name));
    let d = &sc.plan.defaults;
    let _ = writeln!(
        h,
        "<p>Simulated {} s{}</p>",
        d.duration,
        sc.duration_note
            .as_ref()
            .map_or(".".to_string(), |w| format!(
                ", shorter than the scene: {}.",
                prose(w)
            ))
    );
    let _ = writeln!(h, "<figure>{}</figure>", inline_svg(svg));
    let facts: Vec<RunFacts> = sc.rows.iter().map(|r| row_facts(sc, r)).collect();
    let band = reference_band(sc);
    h.push_str("<h3>Which run for a given accuracy</h3>\n");
    h.push_str(&list(
        &front_in_words(&facts, band.as_ref().map(|b| b.0)),
        "No run has a finite error.",
    ));
    h.push_str("<h3>Where a curve is not monotone</h3>\n");
    h.push_str(&list(
        &scene_rises(sc, &facts, band.as_ref().map(|b| (b.0, b.2))),
        "Every method's error falls as its time step falls.",
    ));
    if let Some(note) = &sc.rise_note {
        let _ = writeln!(h, "<p class=\"note\">{}.</p>", prose(note));
    }
    h.push_str("<h3>The reference and the order in time</h3>\n");
    h.push_str(&reference_paragraph(sc));
    h.push_str("<h3>Every run</h3>\n");
    h.push_str(&runs_table(sc));
    h
}

/// The rises of every method's dt sweep (compared scene).
fn scene_rises(sc: &SceneReport, facts: &[RunFacts], band: Option<(f64, bool)>) -> Vec<String> {
    let fast = sc.fast_method();
    let default_error = |dt: f64| {
        facts
            .iter()
            .zip(&sc.rows)
            .find(|(_, r)| r.run.spec.method == fast && r.run.spec.dt == dt)
            .and_then(|(f, _)| f.error)
    };
    let cx = RiseContext {
        refines: Refines::Dt,
        default_error: &default_error,
        resolved: band.map(|b| b.0),
        reference_converged: band.is_none_or(|b| b.1),
    };
    let mut out = Vec::new();
    for method in sc.methods() {
        let sweep: Vec<RunFacts> = facts
            .iter()
            .zip(&sc.rows)
            .filter(|(_, r)| r.run.spec.method == method && r.run.spec.sweep == Sweep::TimeStep)
            .map(|(f, _)| f.clone())
            .collect();
        out.extend(rises_in_words(&sweep, &cx));
    }
    out
}

/// The reference, its own error, why it does not converge (where measured), and the
/// default solver's order in time.
fn reference_paragraph(sc: &SceneReport) -> String {
    let r = &sc.reference.run;
    let mut h = format!(
        "<p>Reference: <code>{}</code> at dt = {} (the sample interval / {}), {}, \
         tolerance {:e}; {} of its steps converged, {} of CPU time. ",
        r.spec.method.name(),
        s(r.spec.dt),
        (sc.plan.sample_times[0] / r.spec.dt).round(),
        resolution_words(sc.plan.defaults.kind, r.spec.resolution),
        r.spec.tolerance,
        converged(r.steps, r.unconverged_steps, r.stuck_steps),
        s(r.cpu_s)
    );
    match (sc.reference_error_estimate(), sc.reference_halving) {
        (Some(e), Some(far)) => {
            let _ = write!(
                h,
                "The same run at 2 dt is {} from it, the run at 4 dt {} from the 2 dt \
                 run (local order of its halvings {}). ",
                m(e),
                m(far.rms_over_time),
                sc.reference_order()
                    .map_or("n/a".into(), |p| format!("{p:.2}"))
            );
        }
        (Some(e), None) => {
            let _ = write!(h, "The same run at 2 dt is {} from it. ", m(e));
        }
        _ => {}
    }
    match reference_band(sc) {
        Some((y, _, true)) => {
            let _ = write!(h, "Its own error: ~{}.", m(y));
        }
        Some((y, _, false)) => {
            let _ = write!(
                h,
                "Halving its dt does not bring the runs closer: its own error is at \
                 least {} and not bounded by this report.",
                m(y)
            );
        }
        None => {}
    }
    h.push_str("</p>\n");
    if let Some(note) = sc
        .reference_note
        .as_ref()
        .filter(|_| sc.reference_order().is_none_or(|p| p < 0.8))
    {
        let _ = writeln!(
            h,
            "<p class=\"note\">Why the reference does not converge in dt (measured): {}.</p>",
            prose(note)
        );
    }
    let fast = sc.fast_method();
    let _ = writeln!(
        h,
        "<p>Order in time of <code>{}</code>: {} against the reference, {} from \
         successive halvings of its own dt sweep (each run against the next finer one, \
         free of the reference's error); implicit Euler is first order.</p>",
        fast.name(),
        sc.order_against_reference()
            .map_or("n/a".into(), |p| format!("{p:.2}")),
        sc.self_convergence_order
            .map_or("n/a".into(), |p| format!("{p:.2}"))
    );
    h
}

/// Every run of a compared scene (the reference's three first).
fn runs_table(sc: &SceneReport) -> String {
    let fast = sc.fast_method();
    let head = [
        "method",
        "sweep",
        "dt",
        "resolution",
        "tolerance",
        "error (RMS over time)",
        "distance to the default solver at the same dt",
        "run time (CPU)",
        "per step",
        "steps converged",
        "iterations (median)",
    ];
    let rows: Vec<(bool, Vec<String>)> = sc
        .reference_rows()
        .into_iter()
        .chain(&sc.rows)
        .map(|row| {
            let r = &row.run;
            (
                r.spec.method == fast && r.spec.sweep == Sweep::TimeStep,
                vec![
                    format!("<code>{}</code>", r.spec.method.name()),
                    r.spec.sweep.name().to_string(),
                    s(r.spec.dt),
                    resolution_words(sc.plan.defaults.kind, r.spec.resolution),
                    format!("{:e}", r.spec.tolerance),
                    row.error.map_or("-".into(), |e| m(e.rms_over_time)),
                    row.to_default.map_or("-".into(), |e| m(e.rms_over_time)),
                    s(r.cpu_s),
                    s(r.cpu_s / r.steps.max(1) as f64),
                    converged(r.steps, r.unconverged_steps, r.stuck_steps),
                    format!("{}", r.iterations_median),
                ],
            )
        })
        .collect();
    table(&head, &rows)
}

/// An exact-solution row as the findings see it: label "chain (moment_matched)".
fn exact_facts(e: &ExactSceneReport, r: &ExactRow) -> RunFacts {
    let x = &r.run;
    let spec = &r.spec.run;
    RunFacts {
        label: exact_series_name(spec.method, r.spec.clamp),
        default: spec.method == Method::Chain && r.spec.clamp == e.clamp,
        dt: spec.dt,
        n: spec.resolution,
        resolution: format!("n = {}", spec.resolution),
        tolerance: spec.tolerance,
        steps: x.steps,
        cpu_s: x.cpu_s,
        duration: e.sample_times.last().copied().unwrap_or(0.0).max(spec.dt),
        error: r.error.map(|err| err.rms),
        unconverged: x.unconverged_steps,
        stuck: x.stuck_steps,
        iterations_median: x.iterations_median,
        to_default: None,
        relative: r.error.map(|err| err.relative),
        static_solve: e.problem.is_static(),
    }
}

fn exact_series_name(method: Method, clamp: &str) -> String {
    if method == Method::ConformingFem {
        method.name().to_string()
    } else {
        format!("{} ({clamp})", method.name())
    }
}

/// One exact-solution scene.
fn exact_section(e: &ExactSceneReport, (cost, conv): &(String, String)) -> String {
    let mut h = format!("<h2 id=\"{0}\">{0}</h2>\n", escape(&e.name));
    let _ = writeln!(
        h,
        "<p>{}; the scene's clamp rule: <code>{}</code>. Sample times: {}.</p>",
        escape(&e.problem.describe()),
        e.clamp,
        e.sample_times
            .iter()
            .map(|t| s(*t))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(h, "<figure>{}</figure>", inline_svg(cost));
    let _ = writeln!(h, "<figure>{}</figure>", inline_svg(conv));
    h.push_str("<h3>Orders and pass criteria</h3>\n");
    h.push_str(&exact_orders(e));
    let facts: Vec<RunFacts> = e.rows.iter().map(|r| exact_facts(e, r)).collect();
    h.push_str("<h3>Which run for a given accuracy</h3>\n");
    h.push_str(&list(
        &front_in_words(&facts, None),
        "No run has a finite error.",
    ));
    h.push_str("<h3>Where a curve is not monotone</h3>\n");
    h.push_str(&list(
        &exact_rises(e, &facts),
        if e.problem.is_static() {
            "Every series' error falls as n rises."
        } else {
            "Every method's error falls as its time step falls."
        },
    ));
    h.push_str("<h3>Every run</h3>\n");
    h.push_str(&exact_table(e));
    h
}

/// The measured orders of every series and the checks `report` exits on.
fn exact_orders(e: &ExactSceneReport) -> String {
    let what = if e.problem.is_static() { "n" } else { "dt" };
    let rows: Vec<(bool, Vec<String>)> = orders(e)
        .into_iter()
        .map(|(label, o)| {
            (
                label.starts_with(&format!("chain ({})", e.clamp)),
                vec![
                    escape(&label),
                    o.map_or("n/a".into(), |p| format!("{p:.2}")),
                ],
            )
        })
        .collect();
    let mut h = table(&["series", &format!("measured order in {what}")], &rows);
    h.push_str("<p>Checks (<code>report</code> exits non-zero when one fails):</p>\n<ul>\n");
    for c in &e.checks {
        let _ = writeln!(
            h,
            "<li><span class=\"{}\">{}</span> {}: measured {}</li>",
            if c.pass { "pass" } else { "fail" },
            if c.pass { "PASS" } else { "FAIL" },
            escape(&c.what),
            c.measured.map_or("n/a".into(), |v| format!("{v:.4}"))
        );
    }
    h.push_str("</ul>\n");
    if !e.theory.is_empty() {
        let _ = writeln!(
            h,
            "<p>Implicit Euler's exact error on the first mode at the same dt (its \
             damping and phase lag): {}.</p>",
            e.theory
                .iter()
                .map(|(dt, err)| format!("{} at dt = {}", m(*err), s(*dt)))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    h
}

/// The rises of every series of an exact-solution scene (along n or dt).
fn exact_rises(e: &ExactSceneReport, facts: &[RunFacts]) -> Vec<String> {
    let none = |_: f64| None;
    let cx = RiseContext {
        refines: if e.problem.is_static() {
            Refines::N
        } else {
            Refines::Dt
        },
        default_error: &none,
        resolved: None,
        reference_converged: true,
    };
    let sweep = if e.problem.is_static() {
        Sweep::Resolution
    } else {
        Sweep::TimeStep
    };
    let mut out = Vec::new();
    for method in [
        Method::Chain,
        Method::GaussNewton,
        Method::Lbfgsb,
        Method::Lumped,
        Method::ConformingFem,
    ] {
        for clamp in CLAMPS {
            let series: Vec<RunFacts> = facts
                .iter()
                .zip(&e.rows)
                .filter(|(_, r)| {
                    r.spec.run.method == method
                        && r.spec.clamp == clamp
                        && r.spec.run.sweep == sweep
                })
                .map(|(f, _)| f.clone())
                .collect();
            out.extend(rises_in_words(&series, &cx));
        }
    }
    out
}

/// Every run of an exact-solution scene.
fn exact_table(e: &ExactSceneReport) -> String {
    let rows: Vec<(bool, Vec<String>)> = e
        .rows
        .iter()
        .map(|r| {
            let spec = &r.spec.run;
            (
                spec.method == Method::Chain && r.spec.clamp == e.clamp,
                vec![
                    format!(
                        "<code>{}</code>",
                        escape(&exact_series_name(spec.method, r.spec.clamp))
                    ),
                    spec.sweep.name().to_string(),
                    format!("{}", spec.resolution),
                    s(spec.dt),
                    format!("{:e}", spec.tolerance),
                    r.error.map_or("not finite".into(), |x| m(x.rms)),
                    r.error
                        .map_or("-".into(), |x| format!("{:.3} %", 100.0 * x.relative)),
                    s(r.run.cpu_s),
                    converged(r.run.steps, r.run.unconverged_steps, r.run.stuck_steps),
                    format!("{}", r.run.iterations_median),
                ],
            )
        })
        .collect();
    table(
        &[
            "method (clamp)",
            "sweep",
            "n",
            "dt",
            "tolerance",
            "error",
            "relative",
            "run time (CPU)",
            "steps converged",
            "iterations (median)",
        ],
        &rows,
    )
}

/// Write the page to `path`.
pub fn write_index(path: &Path, page: &Page) -> Result<(), ReportError> {
    std::fs::write(path, index(page)).map_err(io("cannot write", path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_code_spans_kept() {
        assert_eq!(escape("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
        assert_eq!(prose("use `x<y` here"), "use <code>x&lt;y</code> here");
        assert_eq!(inline_svg("<?xml?>\n<svg a>"), "<svg a>");
    }

    #[test]
    fn an_empty_page_is_a_complete_document() {
        let page = Page {
            command: "developable_sim report <x>",
            quick: true,
            wall_s: 1.0,
            cpu_s: 1.0,
            scenes: &[],
            scene_svgs: &[],
            exact: &[],
            exact_svgs: &[],
        };
        let h = index(&page);
        assert!(h.starts_with("<!DOCTYPE html>") && h.ends_with("</html>\n"));
        assert!(h.contains("report &lt;x&gt;"));
    }
}
