//! The report's figures ([`crate::plot::Figure`]): per compared scene, error against run
//! time; per exact-solution scene, error against run time and against n or dt. Each
//! names every mark in its legend (the default solver as such, the Pareto front, the
//! reference's own error) and says in its caption what was swept and what the error is
//! measured against. Pure: reports in, figures out ([`crate::plot`] draws them).

use plotters::style::RGBColor;

use super::errors::pareto_front;
use super::exact_output::{lines, series, xy};
use super::exact_run::ExactSceneReport;
use super::findings::RunFacts;
use super::output::{color, Row, SceneReport};
use super::plan::{Method, SceneKind, Sweep};
use crate::plot::axis::{engineering, Scale, Unit};
use crate::plot::{Axis, Figure, Level, Series, Style};

/// The Pareto front's colour (drawn translucent under the markers).
const FRONT: RGBColor = RGBColor(0, 0, 0);
const FRONT_LABEL: &str = "Pareto front: no run is both cheaper and more accurate";

fn run_time_axis() -> Axis {
    Axis {
        desc: "run time (process CPU time, one thread)".into(),
        unit: Unit::Second,
        scale: Scale::Log,
    }
}

/// The Pareto front of `(cost, error)` points as a series.
fn front(points: &[(f64, f64)]) -> Series {
    Series {
        label: FRONT_LABEL.into(),
        color: FRONT,
        points: pareto_front(points)
            .into_iter()
            .map(|i| points[i])
            .collect(),
        style: Style::Front,
    }
}

/// A run's resolution in words: "n = 50" (ribbon elements) or "120 samples/m" (the
/// paper's boundary density).
pub(crate) fn resolution_words(kind: SceneKind, resolution: f64) -> String {
    match kind {
        SceneKind::Ribbon => format!("n = {resolution}"),
        SceneKind::Paper => format!("{resolution} samples/m"),
    }
}

/// A scene's reference, in words: "chain, dt = 2.5 ms, n = 50, tolerance 1e-10".
fn reference_words(s: &SceneReport) -> String {
    let r = &s.reference.run.spec;
    format!(
        "{}, dt = {}, {}, tolerance {:e}",
        r.method.name(),
        engineering(r.dt, Unit::Second),
        resolution_words(s.plan.defaults.kind, r.resolution),
        r.tolerance
    )
}

/// The reference's own error as the plot's band: (y, legend label, converged).
pub(crate) fn reference_band(s: &SceneReport) -> Option<(f64, String, bool)> {
    let m = |v: f64| engineering(v, Unit::Metre);
    let (y, label, converged) = match s.reference_error_bound() {
        Some(b) if s.reference_order().is_some_and(|p| p < 0.8) => (
            b,
            format!(
                "reference's own error, ~{} (from its 2 dt and 4 dt runs); \
                 shaded: not resolved",
                m(b)
            ),
            true,
        ),
        Some(b) => (
            b,
            format!(
                "reference's own error, ~{} (its distance to its 2 dt run); shaded: \
                 not resolved",
                m(b)
            ),
            true,
        ),
        None => {
            let e = s.reference_error_estimate()?;
            (
                e,
                format!(
                    "reference's own error: at least {} (its halvings do not \
                     converge); shaded: not resolved",
                    m(e)
                ),
                false,
            )
        }
    };
    (y > 0.0 && y.is_finite()).then_some((y, label, converged))
}

/// (run time, error) of the rows of `method` in `sweep`.
fn cost_points(s: &SceneReport, method: Method, sweep: Sweep) -> Vec<(f64, f64)> {
    s.rows
        .iter()
        .filter(|r| r.run.spec.method == method && r.run.spec.sweep == sweep)
        .filter_map(|r| r.error.map(|e| (r.run.cpu_s, e.rms_over_time)))
        .collect()
}

/// A compared scene's figure: error against run time, a line per method's dt sweep
/// (the default solver bold), the default solver's resolution and tolerance sweeps
/// hollow, the Pareto front, the reference's own error as a shaded band.
pub(crate) fn scene_figure(s: &SceneReport) -> Figure {
    let fast = s.fast_method();
    let mut series = Vec::new();
    for method in s.methods() {
        series.push(Series {
            label: format!("{}: dt sweep", method.describe()),
            color: color(method),
            points: cost_points(s, method, Sweep::TimeStep),
            style: Style::Line {
                bold: method == fast,
            },
        });
    }
    let resolution = match s.plan.defaults.kind {
        SceneKind::Ribbon => "n sweep",
        SceneKind::Paper => "resolution (samples/m) sweep",
    };
    for (sweep, style, what) in [
        (Sweep::Resolution, Style::HollowCircle, resolution),
        (Sweep::Tolerance, Style::HollowSquare, "tolerance sweep"),
    ] {
        let points = cost_points(s, fast, sweep);
        if !points.is_empty() {
            series.push(Series {
                label: format!("{}: {what} at dt = {}", fast.name(), sweep_dt(s, sweep)),
                color: color(fast),
                points,
                style,
            });
        }
    }
    let all: Vec<(f64, f64)> = s
        .rows
        .iter()
        .filter_map(|r| r.error.map(|e| (r.run.cpu_s, e.rms_over_time)))
        .collect();
    series.push(front(&all));
    let band = reference_band(s);
    let caption = format!(
        "Swept: the time step dt of each method ({} to {}){}. Error: RMS distance at {} \
         material points over {} sample times to a reference run of ours ({}), not an \
         exact solution; {}.",
        engineering(min_dt(s, true), Unit::Second),
        engineering(min_dt(s, false), Unit::Second),
        if series.iter().any(|x| x.style == Style::HollowCircle) {
            format!(", and {}'s resolution and tolerance (hollow)", fast.name())
        } else {
            String::new()
        },
        s.points_total,
        s.plan.sample_times.len(),
        reference_words(s),
        match &band {
            Some((y, _, true)) => format!(
                "its own error is ~{} (shaded band)",
                engineering(*y, Unit::Metre)
            ),
            Some((y, _, false)) => format!(
                "its own error is at least {}: not converged in dt (shaded band)",
                engineering(*y, Unit::Metre)
            ),
            None => "its own error is not estimated".into(),
        }
    );
    Figure {
        title: format!("{}: error against run time", s.name),
        x: run_time_axis(),
        y: Axis {
            desc: "RMS error over time against the reference".into(),
            unit: Unit::Metre,
            scale: Scale::Log,
        },
        series,
        levels: band
            .map(|(y, label, _)| Level {
                y,
                label,
                band: true,
            })
            .into_iter()
            .collect(),
        caption,
    }
}

/// The dt of a sweep at fixed dt, in engineering units.
fn sweep_dt(s: &SceneReport, sweep: Sweep) -> String {
    s.rows
        .iter()
        .find(|r| r.run.spec.sweep == sweep)
        .map_or("-".into(), |r| engineering(r.run.spec.dt, Unit::Second))
}

/// The largest (`coarsest`) or smallest swept dt, s.
fn min_dt(s: &SceneReport, coarsest: bool) -> f64 {
    let dts = s
        .rows
        .iter()
        .filter(|r| r.run.spec.sweep == Sweep::TimeStep)
        .map(|r| r.run.spec.dt);
    if coarsest {
        dts.fold(f64::NAN, f64::max)
    } else {
        dts.fold(f64::NAN, f64::min)
    }
}

/// A compared scene's row as the findings see it.
pub(crate) fn row_facts(s: &SceneReport, r: &Row) -> RunFacts {
    let x = &r.run;
    RunFacts {
        label: x.spec.method.name().to_string(),
        default: x.spec.method == s.fast_method(),
        dt: x.spec.dt,
        n: x.spec.resolution,
        resolution: resolution_words(s.plan.defaults.kind, x.spec.resolution),
        tolerance: x.spec.tolerance,
        steps: x.steps,
        cpu_s: x.cpu_s,
        duration: s.plan.defaults.duration,
        error: r.error.map(|e| e.rms_over_time),
        unconverged: x.unconverged_steps,
        stuck: x.stuck_steps,
        iterations_median: x.iterations_median,
        to_default: r.to_default.map(|e| e.rms_over_time),
        relative: None,
        static_solve: false,
    }
}

/// A series' colour: the method's, darker for the dual-length clamp, lighter for the
/// paper's.
fn shade(method: Method, clamp: &str) -> RGBColor {
    let RGBColor(r, g, b) = color(method);
    let f = |v: u8, k: f64| (v as f64 * k).min(255.0) as u8;
    match clamp {
        "dual_length" => RGBColor(f(r, 0.55), f(g, 0.55), f(b, 0.55)),
        "paper" => RGBColor(f(r, 0.5) + 120, f(g, 0.5) + 120, f(b, 0.5) + 120),
        _ => RGBColor(r, g, b),
    }
}

/// A series of an exact-solution scene in a legend: method, what it is, its clamp.
fn exact_label(s: &ExactSceneReport, method: Method, clamp: &str) -> String {
    let what = match method {
        Method::ConformingFem => return method.describe().to_string(),
        Method::Chain => "the default solver, ",
        Method::GaussNewton => "dense, ",
        _ => "",
    };
    let own = if clamp == s.clamp {
        ", the scene's"
    } else {
        ""
    };
    format!("{} ({what}clamp {clamp}{own})", method.name())
}

/// An exact-solution scene's two figures: error against run time (every series, the
/// Pareto front) and against n (static) or dt (dynamic; with implicit Euler's theory).
/// The dense `gauss_newton` is left out of the second: its errors are chain's to
/// round-off, so its line would hide under chain's.
pub(crate) fn exact_figures(s: &ExactSceneReport) -> (Figure, Figure) {
    let by_n = s.problem.is_static();
    let mut cost = Vec::new();
    let mut conv = Vec::new();
    for (_, m, c, sw) in lines(s) {
        let rows = series(s, m, c, sw);
        let label = exact_label(s, m, c);
        let style = Style::Line {
            bold: m == Method::Chain && c == s.clamp,
        };
        cost.push(Series {
            label: label.clone(),
            color: shade(m, c),
            points: rows
                .iter()
                .filter_map(|r| r.error.map(|e| (r.run.cpu_s, e.rms)))
                .collect(),
            style,
        });
        if m != Method::GaussNewton {
            conv.push(Series {
                label,
                color: shade(m, c),
                points: xy(&rows, by_n),
                style,
            });
        }
    }
    let all: Vec<(f64, f64)> = s
        .rows
        .iter()
        .filter_map(|r| r.error.map(|e| (r.run.cpu_s, e.rms)))
        .collect();
    cost.push(front(&all));
    if !s.theory.is_empty() {
        conv.push(Series {
            label: "implicit Euler's exact error on the first mode (theory)".into(),
            color: RGBColor(60, 60, 60),
            points: s.theory.clone(),
            style: Style::Dashed,
        });
    }
    let against = "Error: RMS distance at 205 material points to the exact solution \
                   (core/src/metrics/elastica.rs, itself accurate to ~1e-13 m), not to a \
                   run of ours";
    let swept = if by_n {
        "Swept: the number of elements n per clamp rule and solver (a static solve: no \
         time error)"
    } else {
        "Swept: the time step dt per method at n = 50 (the spatial error is ~2 % of \
         the finest time error)"
    };
    let y = || Axis {
        desc: "RMS error against the exact solution".into(),
        unit: Unit::Metre,
        scale: Scale::Log,
    };
    let cost_fig = Figure {
        title: format!("{}: error against run time", s.name),
        x: run_time_axis(),
        y: y(),
        series: cost,
        levels: Vec::new(),
        caption: format!("{swept}. {against}."),
    };
    let conv_fig = Figure {
        title: format!(
            "{}: error against {}",
            s.name,
            if by_n { "n" } else { "dt" }
        ),
        x: if by_n {
            Axis {
                desc: "ribbon elements n".into(),
                unit: Unit::Count,
                scale: Scale::Log,
            }
        } else {
            Axis {
                desc: "time step dt".into(),
                unit: Unit::Second,
                scale: Scale::Log,
            }
        },
        y: y(),
        series: conv,
        levels: Vec::new(),
        caption: format!(
            "{swept}. {against}. gauss_newton (dense) is not drawn: its errors are \
             chain's to round-off (table)."
        ),
    };
    (cost_fig, conv_fig)
}
