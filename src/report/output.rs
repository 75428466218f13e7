//! The report's tables: `report.csv` and `summary.md` (the plots are
//! [`super::figures`], the page index.html [`super::html`]). An edge (writes files);
//! the numbers come from [`super::errors`].

use std::fmt::Write as _;
use std::path::Path;

use plotters::style::RGBColor;

use super::errors::{
    best_within, error_from_halvings, halving_order, log_log_slope, pareto_front, RunError,
};
use super::exec::RunOutput;
use super::plan::{Method, SceneKind, ScenePlan, Sweep};
use super::report_error::{io, ReportError};

/// One row of the CSV: a run and its error against the reference (None for the
/// reference itself, or when it could not be compared).
#[derive(Clone, Debug)]
pub struct Row {
    pub run: RunOutput,
    pub error: Option<RunError>,
    /// Distance to the default solver's run at the same dt, resolution and tolerance
    /// (None for the default's own runs and where it has none): a method that differs
    /// from it by more than the default's own error ends its steps on another state.
    pub to_default: Option<RunError>,
}

/// Everything measured on one scene.
#[derive(Clone, Debug)]
pub struct SceneReport {
    pub name: String,
    pub plan: ScenePlan,
    pub reference: Row,
    /// The reference at twice its time step, compared with the reference: its error
    /// estimates the reference's own time error.
    pub reference_check: Row,
    /// The reference at four times its time step, compared with the reference.
    pub reference_check_coarse: Row,
    /// The 4 dt check's distance to the 2 dt check (the reference's next halving).
    pub reference_halving: Option<RunError>,
    /// Why the report compares over a shorter duration than the scene's, if it does.
    pub duration_note: Option<String>,
    /// Why the reference's halvings do not converge in dt, where that was measured.
    pub reference_note: Option<String>,
    /// What was measured about a curve that is not monotone in dt (index.html), where
    /// that was investigated beyond the report's own numbers.
    pub rise_note: Option<String>,
    pub rows: Vec<Row>,
    /// Material points compared at each sample time.
    pub points_total: usize,
    /// The order in time of the fast method from successive halvings of dt (distance
    /// of each run to the next finer one), free of the reference's spatial error.
    pub self_convergence_order: Option<f64>,
    /// (dt, RMS distance over time to the run at the next finer dt) along the fast
    /// method's dt sweep, coarse to fine.
    pub successive_differences: Vec<(f64, f64)>,
}

impl SceneReport {
    /// The method whose dt sweep gives the order in time (the default solver).
    pub(crate) fn fast_method(&self) -> Method {
        Method::fast(self.plan.defaults.kind)
    }

    /// (dt, RMS error over time) of `method`'s dt sweep, coarse to fine.
    pub(crate) fn dt_sweep(&self, method: Method) -> Vec<(f64, f64)> {
        let mut v: Vec<(f64, f64)> = self
            .rows
            .iter()
            .filter(|r| r.run.spec.method == method && r.run.spec.sweep == Sweep::TimeStep)
            .filter_map(|r| r.error.map(|e| (r.run.spec.dt, e.rms_over_time)))
            .collect();
        v.sort_by(|a, b| b.0.total_cmp(&a.0));
        v
    }

    /// Slope of ln(error against the reference) over ln(dt), the fast method.
    pub(crate) fn order_against_reference(&self) -> Option<f64> {
        log_log_slope(&self.dt_sweep(self.fast_method()))
    }

    /// The reference's estimated time error: RMS over time of its distance to the same
    /// run at twice its dt (for a first-order method e(2h) - e(h) ~ e(h)), m.
    pub(crate) fn reference_error_estimate(&self) -> Option<f64> {
        self.reference_check.error.map(|e| e.rms_over_time)
    }

    /// Local order of the reference's own halvings ([`halving_order`]): its 2 dt run's
    /// distance to it against the 4 dt run's distance to the 2 dt run.
    pub(crate) fn reference_order(&self) -> Option<f64> {
        halving_order(
            self.reference_error_estimate()?,
            self.reference_halving?.rms_over_time,
        )
    }

    /// The reference's time error implied by its halvings, m ([`error_from_halvings`]):
    /// None when they do not converge (the reference's error is then not bounded by
    /// this report).
    pub(crate) fn reference_error_bound(&self) -> Option<f64> {
        error_from_halvings(self.reference_error_estimate()?, self.reference_order())
    }

    /// The reference and its 2 dt and 4 dt checks.
    pub(crate) fn reference_rows(&self) -> [&Row; 3] {
        [
            &self.reference,
            &self.reference_check,
            &self.reference_check_coarse,
        ]
    }

    pub(crate) fn methods(&self) -> Vec<Method> {
        let mut m: Vec<Method> = self.rows.iter().map(|r| r.run.spec.method).collect();
        m.sort();
        m.dedup();
        m
    }
}

pub const CSV_HEADER: &str = "scene,method,sweep,dt_s,resolution,tolerance,steps,error_rms_m,error_end_m,to_default_rms_m,points_compared,isometry_error_max,constraint_violation_max_m,wall_s,wall_per_simulated_s,cpu_s,cpu_per_simulated_s,step_ms_median,step_cpu_ms_median,iterations_median,unconverged_steps,stuck_steps,finite";

pub fn write_csv(path: &Path, scenes: &[SceneReport]) -> Result<(), ReportError> {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    for s in scenes {
        for row in s.reference_rows().into_iter().chain(&s.rows) {
            let r = &row.run;
            let (e_rms, e_end, used) = match row.error {
                Some(e) => (
                    format!("{:.6e}", e.rms_over_time),
                    format!("{:.6e}", e.at_end),
                    e.points_used_min.to_string(),
                ),
                None => (String::new(), String::new(), String::new()),
            };
            let to_default = row
                .to_default
                .map_or(String::new(), |e| format!("{:.6e}", e.rms_over_time));
            writeln!(
                out,
                "{},{},{},{},{},{:e},{},{},{},{to_default},{},{:.6e},{:.6e},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{},{},{},{}",
                s.name,
                r.spec.method.name(),
                r.spec.sweep.name(),
                r.spec.dt,
                r.spec.resolution,
                r.spec.tolerance,
                r.steps,
                e_rms,
                e_end,
                used,
                r.isometry_error_max,
                r.constraint_violation_max,
                r.wall_s,
                r.wall_s / s.plan.defaults.duration,
                r.cpu_s,
                r.cpu_s / s.plan.defaults.duration,
                r.step_ms_median,
                r.step_cpu_ms_median,
                r.iterations_median,
                r.unconverged_steps,
                r.stuck_steps,
                r.finite
            )?;
        }
    }
    std::fs::write(path, out).map_err(io("cannot write", path))
}

/// A method's colour in every plot.
pub(crate) fn color(method: Method) -> RGBColor {
    match method {
        Method::Chain => RGBColor(31, 119, 180),
        Method::GaussNewton => RGBColor(140, 86, 75),
        Method::Lbfgsb => RGBColor(255, 127, 14),
        Method::Lumped => RGBColor(44, 160, 44),
        Method::ConformingFem => RGBColor(214, 39, 40),
        Method::Paper => RGBColor(148, 103, 189),
    }
}

fn sci(v: f64) -> String {
    format!("{v:.2e}")
}

/// Runs whose process CPU time exceeds their wall time by more than 5 % (+ 5 ms of
/// clock granularity): they used more than one thread.
fn multithreaded_runs(s: &SceneReport) -> Vec<&Row> {
    s.reference_rows()
        .into_iter()
        .chain(&s.rows)
        .filter(|r| r.run.cpu_s > 1.05 * r.run.wall_s + 5e-3)
        .collect()
}

/// Local orders along a (dt, error) sequence, coarse to fine: ln(e_i / e_i+1) /
/// ln(dt_i / dt_i+1) for each pair.
fn local_orders(sweep: &[(f64, f64)]) -> Vec<f64> {
    sweep
        .windows(2)
        .filter(|w| w[0].1 > 0.0 && w[1].1 > 0.0 && w[0].0 != w[1].0)
        .map(|w| (w[0].1 / w[1].1).ln() / (w[0].0 / w[1].0).ln())
        .collect()
}

fn list(v: &[f64]) -> String {
    if v.is_empty() {
        return "n/a".into();
    }
    v.iter()
        .map(|p| format!("{p:.2}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `summary.md`: per scene the reference, a table of the runs, the order in time, the
/// Pareto front and the error each method reaches within the fast method's run time.
pub fn write_summary(
    path: &Path,
    scenes: &[SceneReport],
    quick: bool,
    command: &str,
    wall_s: f64,
    cpu_s: f64,
) -> Result<(), ReportError> {
    let mut md = String::new();
    let kind = if quick { "quick" } else { "full" };
    if scenes.is_empty() {
        // only exact-solution scenes were asked for (`--scenes 'exact_*'`): no reference
        // runs of our own, so none of their explanation applies
        writeln!(md, "# Error against exact solutions\n")?;
        writeln!(
            md,
            "Generated by `{command}` ({kind} report, {wall_s:.0} s wall, {cpu_s:.0} s \
             CPU). Every run is measured against the exact solution of its scene, not \
             against a run of ours; every run is in `exact.csv`, the plots are \
             `exact_<scene>.png` (error against CPU time) and `exact_<scene>_order.png` \
             (error against n and dt). Run time is the process CPU time of the run, on \
             one thread.\n"
        )?;
        // the exact-solution section is appended by the caller (`run_report`)
        return std::fs::write(path, md).map_err(io("cannot write", path));
    }
    summary_header(&mut md, scenes, kind, command, (wall_s, cpu_s))?;
    for s in scenes {
        scene_reference(&mut md, s)?;
        scene_runs(&mut md, s)?;
        scene_order_and_front(&mut md, s)?;
        scene_equal_time(&mut md, s)?;
    }
    std::fs::write(path, md).map_err(io("cannot write", path))
}

/// The report's opening: how errors and run times are measured, the methods.
fn summary_header(
    md: &mut String,
    scenes: &[SceneReport],
    kind: &str,
    command: &str,
    (wall_s, cpu_s): (f64, f64),
) -> Result<(), ReportError> {
    writeln!(md, "# Error against run time\n")?;
    writeln!(
        md,
        "Generated by `{command}` ({kind} report, {wall_s:.0} s wall, {cpu_s:.0} s CPU). \
         Errors are RMS distances (m) between a run's surface and the reference's at \
         matched material points (the ribbon remeshes in material space, so surfaces \
         are resampled, never compared by vertex index), at fixed sample times; `error_rms` is sqrt(mean over \
         sample times of the squared distance), `error_end` the distance at the last \
         sample time. Every run and its columns are in `report.csv`; the plots are \
         `<scene>.png` and `<scene>.svg` (lines: each method's dt sweep; hollow markers: \
         the default solver's resolution and tolerance sweeps; shaded: below the \
         reference's own estimated error); `index.html` shows them on one page.\n"
    )?;
    let threaded: usize = scenes.iter().map(|s| multithreaded_runs(s).len()).sum();
    writeln!(
        md,
        "**Run time = CPU time of the process during the run**; it equals wall time on \
         an idle machine with one thread. The runs execute one after another, each on \
         one thread (a one-thread rayon pool, faer's parallelism set to sequential), \
         and the process CPU time counts every thread, so parallel work could not hide \
         in it: {}. The machine is shared (2 cores, other builds and benchmarks), so \
         wall times are inflated by an unknown factor and are listed only for \
         reference; the plots, the Pareto front and the equal-run-time comparison use \
         CPU time.\n",
        if threaded == 0 {
            "no run's CPU time exceeded its wall time (by more than 5 %), i.e. every run \
             used one thread"
                .to_string()
        } else {
            format!(
                "{threaded} run(s) used more CPU than wall time (more than one thread), \
                 marked `(>1 thread)` below"
            )
        }
    )?;
    writeln!(
        md,
        "Methods: `chain` (ribbon, the default solver: our projected Newton method, its \
         Newton system solved along the chain in O(n), full kinetic model), \
         `gauss_newton` (the same method on the dense matrix: chain's iterates to \
         round-off at its cost; column `to_default_rms_m` of report.csv measures the \
         distance), `lbfgsb` (ribbon, the paper's solver), `chain_lumped` (ribbon, the \
         default solver with the mass lumped on the centerline), \
         `conforming_fem` (the conventional baseline of Pan et al. table 1: a triangle \
         mesh n x 10, Green-strain stretching with stiffness 1e8 N, discrete-shell \
         bending with the ribbon's alpha, handles eliminated as hard constraints; see \
         core/src/baseline/conforming_fem.rs), `paper_newton` (Schreck et al.'s simulator). \
         Resolution: ribbon elements along (FEM: quads along, 10 across; a helix start \
         keeps its shape: psi per crease scaled by n0/n); paper: boundary sample \
         density, samples/m.\n"
    )?;
    Ok(())
}

/// A scene's heading and its reference: the run, its own error, warnings.
fn scene_reference(md: &mut String, s: &SceneReport) -> Result<(), ReportError> {
    reference_run(md, s)?;
    reference_error(md, s)?;
    reference_warnings(md, s)
}

/// The scene's heading, why it is compared over a shorter duration (if it is), and
/// the reference run: dt (s), resolution, tolerance, CPU time (s), unconverged steps.
fn reference_run(md: &mut String, s: &SceneReport) -> Result<(), ReportError> {
    let d = &s.plan.defaults;
    let r = &s.reference.run.spec;
    writeln!(md, "## {}\n", s.name)?;
    if let Some(why) = &s.duration_note {
        writeln!(
            md,
            "Compared over {} s, shorter than the scene: {why}.\n",
            d.duration
        )?;
    }
    writeln!(
        md,
        "Simulated {} s, compared at {} times ({}) on {} material points. Reference: \
         `{}`, dt = {} s (the sample interval / {}), resolution {} (default \
         {}), tolerance {:e}; its run took {:.2} s CPU, {} of its {} steps stopped \
         unconverged ({} of them stuck: no step found from the start).\n",
        d.duration,
        s.plan.sample_times.len(),
        s.plan
            .sample_times
            .iter()
            .map(|t| format!("{t:.3}"))
            .collect::<Vec<_>>()
            .join(", "),
        s.points_total,
        r.method.name(),
        r.dt,
        (s.plan.sample_times[0] / r.dt).round(),
        r.resolution,
        d.resolution,
        r.tolerance,
        s.reference.run.cpu_s,
        s.reference.run.unconverged_steps,
        s.reference.run.steps,
        s.reference.run.stuck_steps,
    )?;
    Ok(())
}

/// The reference's own error, estimated from its 2 dt and 4 dt runs (m), what it
/// resolves, and the measured note on why it does not converge in dt where this run's
/// halvings agree.
fn reference_error(md: &mut String, s: &SceneReport) -> Result<(), ReportError> {
    if let Some(e) = s.reference_error_estimate() {
        write!(
            md,
            "**The reference's own error**: the same run at twice its dt \
             (`reference_2dt`) is {} m from it (RMS over time; {} at the end), and \
             the run at four times its dt (`reference_4dt`) is {} m from the 2 dt \
             run: local order of the reference's halvings {}. ",
            sci(e),
            s.reference_check
                .error
                .map_or("-".into(), |e| sci(e.at_end)),
            s.reference_halving
                .map_or("-".into(), |e| sci(e.rms_over_time)),
            s.reference_order()
                .map_or("n/a".into(), |p| format!("**{p:.2}**")),
        )?;
        match (s.reference_order(), s.reference_error_bound()) {
            (Some(p), Some(b)) if p < 0.8 => writeln!(
                md,
                "Below first order, so the 2 dt distance understates the \
                 reference's error: if the halvings kept shrinking at this order, \
                 e(h) ~ d / (2^p - 1) = {} m; errors below that are not resolved \
                 by this reference.\n",
                sci(b)
            )?,
            (_, Some(_)) => writeln!(
                md,
                "For implicit Euler (first order) e(2h) - e(h) ~ e(h), so errors \
                 below ~{} m are not resolved by this reference.\n",
                sci(e)
            )?,
            (_, None) => writeln!(
                md,
                "**Halving dt does not bring these runs closer** (order <= 0.2: \
                 the 4 dt run is hardly farther from the 2 dt run than that is from \
                 the reference, where first order would make it twice as far), so \
                 the reference is not converged in dt and its error is not bounded \
                 by this report: {} m is only a lower bound, and errors within a few \
                 times it are not resolved.\n",
                sci(e)
            )?,
        }
    }
    // measured separately (see docs/accuracy.md); shown where this run's halvings agree
    if let Some(note) = s
        .reference_note
        .as_ref()
        .filter(|_| s.reference_order().is_none_or(|p| p < 0.8))
    {
        writeln!(
            md,
            "**Why the reference does not converge in dt**: {note}.\n"
        )?;
    }
    Ok(())
}

/// Warnings: steps stuck at their start in the reference runs, and for paper the
/// material points a remeshed pattern left out.
fn reference_warnings(md: &mut String, s: &SceneReport) -> Result<(), ReportError> {
    let d = &s.plan.defaults;
    let stuck: Vec<usize> = s
        .reference_rows()
        .iter()
        .map(|r| r.run.stuck_steps)
        .collect();
    if stuck.iter().any(|&n| n > 0) {
        writeln!(
            md,
            "**Warning**: steps stuck at their start (the solver found no step and \
             kept it; for a ribbon that is the previous state, so the velocity drops \
             to zero): reference {}, 2 dt run {}, 4 dt run {}. A run with such a step \
             is not a converged solution; errors against it mean little.\n",
            stuck[0], stuck[1], stuck[2]
        )?;
    }
    if d.kind == SceneKind::Paper {
        let used_min = s
            .rows
            .iter()
            .filter_map(|r| r.error.map(|e| e.points_used_min))
            .min()
            .unwrap_or(0);
        writeln!(
            md,
            "The paper pattern is remeshed while it runs, so the comparison uses a \
             grid of {} points inside the sheet (inset 1 % of its size) and skips the \
             points that fall outside either run's pattern at a sample time; the \
             fewest compared at any sample time in any run: {used_min}.\n",
            s.points_total
        )?;
    }
    Ok(())
}

/// A scene's table of runs, the reference's first.
fn scene_runs(md: &mut String, s: &SceneReport) -> Result<(), ReportError> {
    let d = &s.plan.defaults;
    writeln!(
        md,
        "| method | sweep | dt s | resolution | tolerance | error_rms m | error_end m | isometry max | constraint max m | CPU s | CPU s per sim. s | wall s | step CPU ms (median) | iterations (median) | unconverged |"
    )?;
    writeln!(
        md,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    )?;
    let threaded = multithreaded_runs(s);
    for row in s.reference_rows().into_iter().chain(&s.rows) {
        let r = &row.run;
        let (e, e_end) = row
            .error
            .map(|e| (sci(e.rms_over_time), sci(e.at_end)))
            .unwrap_or(("-".into(), "-".into()));
        let mark = if threaded.iter().any(|t| std::ptr::eq(*t, row)) {
            " (>1 thread)"
        } else {
            ""
        };
        let unconverged = if r.stuck_steps > 0 {
            format!("{} ({} stuck)", r.unconverged_steps, r.stuck_steps)
        } else {
            r.unconverged_steps.to_string()
        };
        writeln!(
            md,
            "| {} | {} | {:.6} | {} | {:e} | {e} | {e_end} | {} | {} | {:.3}{mark} | {:.3} | {:.3} | {:.3} | {} | {unconverged} |",
            r.spec.method.name(),
            r.spec.sweep.name(),
            r.spec.dt,
            r.spec.resolution,
            r.spec.tolerance,
            sci(r.isometry_error_max),
            sci(r.constraint_violation_max),
            r.cpu_s,
            r.cpu_s / d.duration,
            r.wall_s,
            r.step_cpu_ms_median,
            r.iterations_median,
        )?;
    }
    Ok(())
}

/// A scene's order in time and its Pareto front.
fn scene_order_and_front(md: &mut String, s: &SceneReport) -> Result<(), ReportError> {
    let fast = s.fast_method();
    writeln!(md)?;
    let sweep = s.dt_sweep(fast);
    writeln!(
        md,
        "**Order in time** (implicit Euler, `{}`): slope of ln(error) against ln(dt) \
         over its dt sweep {}; from successive halvings (each run against the next \
         finer one, which cancels the reference's own error) {}. Local orders, coarse \
         to fine: against the reference {}; successive halvings {} (the distances \
         between successive runs, m: {}).\n",
        fast.name(),
        s.order_against_reference()
            .map_or("n/a".into(), |p| format!("**{p:.2}**")),
        s.self_convergence_order
            .map_or("n/a".into(), |p| format!("**{p:.2}**")),
        list(&local_orders(&sweep)),
        list(&local_orders(&s.successive_differences)),
        if s.successive_differences.is_empty() {
            "n/a".to_string()
        } else {
            s.successive_differences
                .iter()
                .map(|(_, e)| sci(*e))
                .collect::<Vec<_>>()
                .join(", ")
        },
    )?;
    let points: Vec<(f64, f64)> = s
        .rows
        .iter()
        .map(|r| {
            (
                r.run.cpu_s,
                r.error.map_or(f64::INFINITY, |e| e.rms_over_time),
            )
        })
        .collect();
    writeln!(
        md,
        "**Pareto front** (no other run is both faster, in CPU time, and more \
         accurate):\n"
    )?;
    for i in pareto_front(&points) {
        let r = &s.rows[i].run;
        writeln!(
            md,
            "- `{}` {} sweep, dt = {} s, resolution {}, tolerance {:e}: {} m in {:.3} s CPU",
            r.spec.method.name(),
            r.spec.sweep.name(),
            r.spec.dt,
            r.spec.resolution,
            r.spec.tolerance,
            sci(points[i].1),
            points[i].0
        )?;
    }
    writeln!(md)?;
    Ok(())
}

/// A scene's comparison of the methods at equal run time, if it has a budget.
fn scene_equal_time(md: &mut String, s: &SceneReport) -> Result<(), ReportError> {
    let fast = s.fast_method();
    if let Some(budget) = equal_time_budget(s) {
        writeln!(
            md,
            "**At equal run time** (budget {budget:.3} s CPU: the CPU time of the \
             middle run of the `{}` dt sweep): the best error each method reaches \
             within it, and what its cheapest run costs.\n",
            fast.name()
        )?;
        writeln!(md, "| method | best error within budget, m | ratio to `{}` | cheapest run: CPU s, error m |", fast.name())?;
        writeln!(md, "|---|---|---|---|")?;
        let fast_err = best_error(s, fast, budget);
        for m in s.methods() {
            let best = best_error(s, m, budget);
            let cheapest = s
                .rows
                .iter()
                .filter(|r| r.run.spec.method == m && r.error.is_some())
                .min_by(|a, b| a.run.cpu_s.total_cmp(&b.run.cpu_s));
            writeln!(
                md,
                "| `{}` | {} | {} | {} |",
                m.name(),
                best.map_or("none within budget".into(), sci),
                match (best, fast_err) {
                    (Some(b), Some(f)) if f > 0.0 => format!("{:.2}", b / f),
                    _ => "-".into(),
                },
                cheapest.map_or("-".into(), |r| format!(
                    "{:.3} s, {}",
                    r.run.cpu_s,
                    sci(r.error.map_or(f64::NAN, |e| e.rms_over_time))
                ))
            )?;
        }
        writeln!(md)?;
        match (fast_err, s.reference_error_bound()) {
            (Some(f), Some(b)) if f < 3.0 * b => writeln!(
                md,
                "The `{}` error within budget ({} m) is less than 3x the \
                 reference's own error ({} m, above): the ratios at this budget are \
                 not resolved.\n",
                fast.name(),
                sci(f),
                sci(b)
            )?,
            (Some(_), None) if s.reference_error_estimate().is_some() => writeln!(
                md,
                "The reference is not converged in dt (above): the errors and ratios \
                 at this budget hold only where they are well above its {} m lower \
                 bound.\n",
                sci(s.reference_error_estimate().unwrap_or(f64::NAN))
            )?,
            _ => {}
        }
    }
    Ok(())
}

/// The run-time budget of the equal-time comparison: the CPU time of the middle run of
/// the fast method's dt sweep, s.
fn equal_time_budget(s: &SceneReport) -> Option<f64> {
    let mut runs: Vec<&Row> = s
        .rows
        .iter()
        .filter(|r| r.run.spec.method == s.fast_method() && r.run.spec.sweep == Sweep::TimeStep)
        .collect();
    runs.sort_by(|a, b| b.run.spec.dt.total_cmp(&a.run.spec.dt));
    runs.get(runs.len() / 2).map(|r| r.run.cpu_s)
}

/// The smallest error `method` reaches with a run of at most `budget` s of CPU time.
fn best_error(s: &SceneReport, method: Method, budget: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = s
        .rows
        .iter()
        .filter(|r| r.run.spec.method == method)
        .filter_map(|r| r.error.map(|e| (r.run.cpu_s, e.rms_over_time)))
        .collect();
    best_within(&pts, budget).map(|i| pts[i].1)
}

#[cfg(test)]
mod tests {
    use super::{local_orders, write_summary};

    #[test]
    fn an_exact_only_summary_does_not_speak_of_reference_runs() {
        let dir = std::env::temp_dir().join(format!("exact_summary_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("summary.md");
        write_summary(&path, &[], true, "developable_sim report", 1.0, 1.0).unwrap();
        let md = std::fs::read_to_string(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(md.starts_with("# Error against exact solutions"), "{md}");
        assert!(!md.contains("reference"), "{md}");
    }

    #[test]
    fn local_orders_of_a_first_order_sequence_are_one() {
        let seq: Vec<(f64, f64)> = [0.1, 0.05, 0.025].iter().map(|&h| (h, 2.0 * h)).collect();
        let p = local_orders(&seq);
        assert_eq!(p.len(), 2);
        assert!(p.iter().all(|p| (p - 1.0).abs() < 1e-12), "{p:?}");
    }
}
