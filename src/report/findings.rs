//! What a reader wants from a scene's runs, in words: the Pareto front as "for an
//! error under 1 mm, chain at dt = 5 ms is the cheapest", and, where a method's error
//! rises while its dt falls, the measured reason. Pure: the runs' numbers in,
//! sentences out (index.html prints them).

use super::errors::pareto_front;
use crate::plot::axis::{engineering, Unit};

/// What the sentences need of one run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunFacts {
    /// The method's name (`chain`, `lbfgsb`, ...) and, for exact scenes, its clamp.
    pub label: String,
    /// Whether this is the default solver's run (`chain`; `paper_newton` on paper).
    pub default: bool,
    /// Time step, s.
    pub dt: f64,
    /// Resolution: ribbon elements n, or the paper's samples/m.
    pub n: f64,
    /// The resolution in words: "n = 50", "120 samples/m".
    pub resolution: String,
    pub tolerance: f64,
    pub steps: usize,
    /// Process CPU time of the run, s.
    pub cpu_s: f64,
    /// Simulated time, s.
    pub duration: f64,
    /// RMS error over time, m (None: not compared, e.g. not finite).
    pub error: Option<f64>,
    pub unconverged: usize,
    pub stuck: usize,
    pub iterations_median: f64,
    /// RMS distance over time to the default solver's run at the same dt and n, m
    /// (None where there is none, or for the default itself).
    pub to_default: Option<f64>,
    /// The error over the problem's displacement scale (exact solutions: the tip's
    /// deflection, the midpoint rise), where there is one.
    pub relative: Option<f64>,
    /// A static solve (no time error): named by n only, its cost a run's.
    pub static_solve: bool,
}

impl RunFacts {
    /// CPU time of one step, s.
    fn per_step(&self) -> f64 {
        self.cpu_s / self.steps.max(1) as f64
    }
}

/// `v` seconds or metres in engineering units, 3 significant digits.
fn s(v: f64) -> String {
    engineering(v, Unit::Second)
}
fn m(v: f64) -> String {
    engineering(v, Unit::Metre)
}

/// A run as the sentences name it: "chain at dt = 5 ms (n = 50)", or for a static
/// solve "chain (moment_matched) at n = 50".
fn run_name(r: &RunFacts) -> String {
    if r.static_solve {
        format!(
            "{} at {} (tolerance {:e})",
            r.label, r.resolution, r.tolerance
        )
    } else {
        format!(
            "{} at dt = {} ({}, tolerance {:e})",
            r.label,
            s(r.dt),
            r.resolution,
            r.tolerance
        )
    }
}

/// What a run costs: "0.39 ms a step, 15.4 ms of CPU time per simulated second", or
/// for a static solve its CPU time.
fn cost(r: &RunFacts) -> String {
    if r.static_solve {
        format!("{} of CPU time", s(r.cpu_s))
    } else {
        format!(
            "{} a step, {} of CPU time per simulated second",
            s(r.per_step()),
            s(r.cpu_s / r.duration)
        )
    }
}

/// `v` rounded up, strictly, to 2 significant digits (17.22 mm -> 18 mm, 25 mm -> 26
/// mm), or to more where that is not below `below`.
fn round_up(v: f64, below: f64) -> f64 {
    for digits in 2..=6 {
        let scale = 10f64.powi(digits - 1 - v.log10().floor() as i32);
        let up = (v * scale * (1.0 + 1e-12)).ceil() / scale;
        if up < below {
            return up;
        }
    }
    v * (1.0 + 1e-9)
}

/// The error thresholds (m) the front is read at, coarse to fine, each with whether it
/// is a round one: 1, 2 and 5 times each power of ten from the first above the largest
/// front error down to the smallest; and each front run's error rounded up (so every
/// run of the front is named even when no round threshold falls between it and the
/// next).
fn thresholds(front_errors: &[f64]) -> Vec<(f64, bool)> {
    let finite: Vec<f64> = front_errors
        .iter()
        .copied()
        .filter(|e| e.is_finite() && *e > 0.0)
        .collect();
    let (Some(lo), Some(hi)) = (
        finite.iter().copied().reduce(f64::min),
        finite.iter().copied().reduce(f64::max),
    ) else {
        return Vec::new();
    };
    let mut out: Vec<(f64, bool)> = Vec::new();
    for e in (lo.log10().floor() as i32)..=(hi.log10().floor() as i32 + 1) {
        for m in [1.0, 2.0, 5.0] {
            // decimal text, so that 2e-3 is exactly the double "2e-3"
            let t: f64 = format!("{m}e{e}").parse().unwrap_or(f64::NAN);
            if t > lo {
                out.push((t, true));
            }
        }
    }
    out.sort_by(|a, b| b.0.total_cmp(&a.0));
    let first_above = out.iter().rposition(|t| t.0 >= hi).unwrap_or(0);
    let mut out = out.split_off(first_above);
    // the front's errors fall with cost: each run's, rounded up below the one before
    for (k, e) in finite.iter().enumerate() {
        let below = if k == 0 { f64::INFINITY } else { finite[k - 1] };
        out.push((round_up(*e, below), false));
    }
    out.sort_by(|a, b| b.0.total_cmp(&a.0));
    out
}

/// What a reader should know about a run before picking it: unconverged steps, a
/// solver that barely iterates (not said of a static solve, whose later load steps
/// start at their equilibrium).
fn caveats(r: &RunFacts) -> String {
    let mut c = String::new();
    if r.unconverged > 0 {
        c.push_str(&format!(
            " Caution: {} of its {} steps stopped unconverged.",
            r.unconverged, r.steps
        ));
    }
    if r.iterations_median <= 1.0 && !r.static_solve {
        c.push_str(&format!(
            " Caution: its solver stops after a median of {} iteration a step.",
            r.iterations_median
        ));
    }
    c
}

/// The Pareto front in words: for each error threshold (coarse to fine) the cheapest
/// run under it, its cost a step and per simulated second; one sentence per run of the
/// front, at the finest round threshold it answers (else its own error rounded up).
/// `resolved`, when known, is the smallest error the comparison resolves (the
/// reference's own error): thresholds below it say so. Runs on the front are those no
/// other run beats in both cost and error ([`pareto_front`]).
pub fn front_in_words(runs: &[RunFacts], resolved: Option<f64>) -> Vec<String> {
    let pts: Vec<(f64, f64)> = runs
        .iter()
        .map(|r| (r.cpu_s, r.error.unwrap_or(f64::INFINITY)))
        .collect();
    let front = pareto_front(&pts);
    let errors: Vec<f64> = front.iter().map(|&i| pts[i].1).collect();
    // (front run, threshold, round)
    let mut picks: Vec<(usize, f64, bool)> = Vec::new();
    for (t, round) in thresholds(&errors) {
        // the front is sorted by cost: its first run under t is the cheapest overall
        let Some(&i) = front.iter().find(|&&i| pts[i].1 < t) else {
            continue;
        };
        match picks.last_mut() {
            // the same answer: a finer round threshold replaces the one kept
            Some(last) if last.0 == i => {
                if round || !last.2 {
                    *last = (i, t, round);
                }
            }
            _ => picks.push((i, t, round)),
        }
    }
    picks
        .into_iter()
        .map(|(i, t, _)| {
            let r = &runs[i];
            let mut line = format!(
                "For an error under {}, {} is the cheapest: {} (error {}).",
                m(t),
                run_name(r),
                cost(r),
                m(pts[i].1)
            );
            line.push_str(&caveats(r));
            if let Some(b) = resolved.filter(|b| t < *b) {
                line.push_str(&format!(
                    " Not resolved: the reference's own error ({}) is larger than this \
                     threshold.",
                    m(b)
                ));
            }
            line
        })
        .collect()
}

/// What a sweep refines: the time step (falling) or the number of elements (rising).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refines {
    Dt,
    N,
}

impl Refines {
    /// Where a run sits on the sweep: "dt = 5 ms" or "n = 20".
    fn at(self, r: &RunFacts) -> String {
        match self {
            Refines::Dt => format!("dt = {}", s(r.dt)),
            Refines::N => r.resolution.clone(),
        }
    }
}

/// What a rise is judged against besides the runs themselves.
pub struct RiseContext<'a> {
    pub refines: Refines,
    /// The default solver's error at a dt (compared scenes), m.
    pub default_error: &'a dyn Fn(f64) -> Option<f64>,
    /// The reference's own error (None for an exact solution), m.
    pub resolved: Option<f64>,
    /// Whether the reference's halvings converge.
    pub reference_converged: bool,
}

/// Where a method's error rises while its sweep refines (dt falls or n rises), and why
/// (measured): `sweep` is one method's sweep, in any order. One sentence per rise.
pub fn rises_in_words(sweep: &[RunFacts], cx: &RiseContext) -> Vec<String> {
    let mut runs: Vec<&RunFacts> = sweep.iter().filter(|r| r.error.is_some()).collect();
    match cx.refines {
        Refines::Dt => runs.sort_by(|a, b| b.dt.total_cmp(&a.dt)),
        Refines::N => runs.sort_by(|a, b| a.n.total_cmp(&b.n)),
    }
    let mut out = Vec::new();
    for w in runs.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (ea, eb) = (a.error.unwrap_or(0.0), b.error.unwrap_or(0.0));
        if eb <= ea {
            continue;
        }
        let reasons = rise_reasons(a, b, cx);
        out.push(format!(
            "{}: the error rises from {} at {} to {} at {}. Measured: {}.",
            b.label,
            m(ea),
            cx.refines.at(a),
            m(eb),
            cx.refines.at(b),
            reasons.join("; ")
        ));
    }
    out
}

/// The measured facts that explain a rise from run `a` to the finer run `b`.
fn rise_reasons(a: &RunFacts, b: &RunFacts, cx: &RiseContext) -> Vec<String> {
    let mut reasons = Vec::new();
    let (ea, eb) = (a.error.unwrap_or(0.0), b.error.unwrap_or(0.0));
    let at = |r: &RunFacts| cx.refines.at(r);
    if let Some(bound) = cx.resolved {
        if ea.max(eb) < 3.0 * bound {
            reasons.push(format!(
                "both errors are within 3x the reference's own error ({}{}), so the \
                 reference does not rank these runs",
                m(bound),
                if cx.reference_converged {
                    ""
                } else {
                    ", a lower bound: its halvings do not converge"
                }
            ));
        }
    }
    for r in [a, b].into_iter().filter(|r| r.unconverged > 0) {
        reasons.push(format!(
            "at {}, {} of its {} steps stopped unconverged{}",
            at(r),
            r.unconverged,
            r.steps,
            if r.stuck > 0 {
                format!(" ({} stuck at their start)", r.stuck)
            } else {
                String::new()
            }
        ));
    }
    if b.iterations_median <= 1.0 && a.iterations_median > 1.0 {
        reasons.push(format!(
            "at {} its solver stops after a median of {} iteration a step (at {}: {}), \
             so its steps barely move the state",
            at(b),
            b.iterations_median,
            at(a),
            a.iterations_median
        ));
    }
    if let Some(rel) = b.relative.filter(|rel| *rel > 0.5) {
        reasons.push(format!(
            "at {} its error is {:.2} times the displacement it should have (the tip's \
             deflection or the midpoint rise): it has hardly left its start",
            at(b),
            rel
        ));
    }
    if let (Some(d), Some(e)) = (b.to_default, (cx.default_error)(b.dt)) {
        if d > 2.0 * e {
            reasons.push(format!(
                "at {} its run is {} from the default solver's at the same dt, \
                 whose own error is {}: its steps end on another state than the \
                 default's (a difference between solutions of the step problem, which \
                 a smaller dt does not remove)",
                at(b),
                m(d),
                m(e)
            ));
        }
    }
    if reasons.is_empty() {
        reasons.push(
            "no cause found among the measured quantities (convergence, iterations, \
             distance to the default solver, the reference's own error)"
                .to_string(),
        );
    }
    reasons
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(label: &str, dt: f64, cpu_s: f64, error: f64) -> RunFacts {
        RunFacts {
            label: label.into(),
            default: label == "chain",
            dt,
            n: 50.0,
            resolution: "n = 50".into(),
            tolerance: 1e-6,
            steps: (0.4 / dt).round() as usize,
            cpu_s,
            duration: 0.4,
            error: Some(error),
            unconverged: 0,
            stuck: 0,
            iterations_median: 8.0,
            to_default: None,
            relative: None,
            static_solve: false,
        }
    }

    #[test]
    fn the_front_names_the_cheapest_run_under_each_decade() {
        let runs = vec![
            run("chain", 0.04, 0.02, 2.5e-2),
            run("chain", 0.02, 0.03, 1.2e-2),
            run("chain", 0.005, 0.05, 4e-3),
            // dominated: slower and less accurate than chain at 5 ms
            run("lbfgsb", 0.005, 1.5, 1.7e-2),
        ];
        let words = front_in_words(&runs, Some(3e-3));
        // 50 mm: chain at 40 ms (error 25 mm); 20 mm: 20 ms; 10 and 5 mm: 5 ms (one
        // answer for both: the finer threshold is kept)
        assert_eq!(words.len(), 3, "{words:?}");
        assert!(
            words[0].starts_with(
                "For an error under 50 mm, chain at dt = 40 ms (n = 50, tolerance 1e-6)"
            ),
            "{words:?}"
        );
        assert!(
            words[1].contains("under 20 mm, chain at dt = 20 ms"),
            "{words:?}"
        );
        assert!(
            words[2].contains("under 5 mm, chain at dt = 5 ms"),
            "{words:?}"
        );
        assert!(words[2].contains("0.625 ms a step"), "{words:?}");
        assert!(!words.iter().any(|w| w.contains("lbfgsb")));
        // a threshold under the reference's own error is flagged
        let fine = front_in_words(&runs, Some(1e-2));
        assert!(fine[2].contains("Not resolved"), "{fine:?}");
        assert!(!fine[1].contains("Not resolved"), "{fine:?}");
        // a front within one decade: every run of it named, at its error rounded up
        // where no round threshold separates it from the next; a run that barely
        // iterates is flagged
        let mut close = vec![
            run("lbfgsb", 0.005, 0.004, 17.22e-3),
            run("chain", 0.01, 0.008, 14.6e-3),
            run("fem", 0.02, 2.5, 10.05e-3),
            run("fem", 0.005, 4.0, 9.9e-3),
        ];
        close[0].iterations_median = 1.0;
        let words = front_in_words(&close, None);
        assert_eq!(words.len(), 4, "{words:?}");
        assert!(
            words[0].starts_with("For an error under 20 mm, lbfgsb"),
            "{words:?}"
        );
        assert!(words[0].contains("Caution: its solver stops after a median of 1"));
        assert!(
            words[1].starts_with("For an error under 15 mm, chain"),
            "{words:?}"
        );
        assert!(words[2].starts_with("For an error under 11 mm, fem at dt = 20 ms"));
        assert!(words[3].starts_with("For an error under 10 mm, fem at dt = 5 ms"));
    }

    #[test]
    fn a_rise_is_explained_by_what_was_measured() {
        let mut a = run("lbfgsb", 0.01, 1.5, 1.49e-2);
        a.iterations_median = 1623.0;
        a.unconverged = 1;
        let mut b = run("lbfgsb", 0.005, 0.003, 1.72e-2);
        b.iterations_median = 1.0;
        b.to_default = Some(1.6e-2);
        let default_error = |_: f64| Some(4.1e-3);
        let cx = RiseContext {
            refines: Refines::Dt,
            default_error: &default_error,
            resolved: Some(4.4e-3),
            reference_converged: true,
        };
        let words = rises_in_words(&[b.clone(), a.clone()], &cx);
        assert_eq!(words.len(), 1, "{words:?}");
        let w = &words[0];
        assert!(
            w.starts_with("lbfgsb: the error rises from 14.9 mm at dt = 10 ms"),
            "{w}"
        );
        assert!(w.contains("1 of its 40 steps stopped unconverged"), "{w}");
        assert!(w.contains("median of 1 iteration"), "{w}");
        assert!(w.contains("16 mm from the default solver's"), "{w}");
        assert!(!w.contains("within 3x"), "{w}");
        // falling errors: nothing to explain
        let mut c = b.clone();
        c.error = Some(1e-2);
        let none = |_: f64| None;
        let bare = RiseContext {
            refines: Refines::Dt,
            default_error: &none,
            resolved: None,
            reference_converged: true,
        };
        assert!(rises_in_words(&[a.clone(), c], &bare).is_empty());
        // a rise with none of the measured causes says so
        let plain_b = run("chain", 0.005, 0.05, 2e-2);
        let plain_a = run("chain", 0.01, 0.03, 1e-2);
        let w = rises_in_words(&[plain_a.clone(), plain_b.clone()], &bare);
        assert!(w[0].contains("no cause found"), "{w:?}");
        // errors within 3x the reference's own: not resolved
        let w = rises_in_words(
            &[plain_a.clone(), plain_b.clone()],
            &RiseContext {
                resolved: Some(1e-2),
                ..bare
            },
        );
        assert!(
            w[0].contains("within 3x the reference's own error (10 mm)"),
            "{w:?}"
        );
        // along n: a finer mesh with a larger error
        let (mut c10, mut c20) = (plain_a, plain_b);
        (c10.n, c20.n) = (10.0, 20.0);
        (c10.resolution, c20.resolution) = ("n = 10".into(), "n = 20".into());
        c20.dt = c10.dt;
        let w = rises_in_words(
            &[c20.clone(), c10.clone()],
            &RiseContext {
                refines: Refines::N,
                ..bare
            },
        );
        assert!(w[0].contains("at n = 10 to 20 mm at n = 20"), "{w:?}");
        assert!(w[0].contains("no cause found"), "{w:?}");
        // a run that stays near its start says so
        let (mut s10, mut s20) = (c10.clone(), c20.clone());
        s20.relative = Some(1.1);
        (s10.static_solve, s20.static_solve) = (true, true);
        let n_cx = RiseContext {
            refines: Refines::N,
            ..bare
        };
        let w = rises_in_words(&[s10.clone(), s20.clone()], &n_cx);
        assert!(w[0].contains("1.10 times the displacement"), "{w:?}");
        let words = front_in_words(&[s10], None);
        assert!(
            words[0]
                .contains("chain at n = 10 (tolerance 1e-6) is the cheapest: 30 ms of CPU time"),
            "{words:?}"
        );
    }
}
