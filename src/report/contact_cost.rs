//! The contact scenes' cost against the number of elements, both contact methods side by
//! side (issue 46): `contact_cost.csv` and a table in summary.md. A data entry of the
//! report, apart from its error sweeps: each run is the scene at `--set
//! ribbon.segments=n --set contact.method=m`, its median and 95th-percentile step, the
//! solver's median iterations and the published frames' largest isometry error.
//!
//! Times are process CPU time (one thread, like the rest of the report), so another
//! process on a shared machine does not inflate them.

use std::path::Path;

use super::exec::process_cpu_s;
use super::report_error::{self, ReportError};
use crate::runner;
use crate::scene;

/// What is run: the scene (`config/scenes/<scene>.yaml`), the resolutions, the methods
/// and the simulated time, s (full report; `--quick` runs the first two resolutions for
/// `QUICK_DURATION`).
pub const SCENE: &str = "ribbon_falling";
pub const RESOLUTIONS: [usize; 4] = [150, 300, 600, 1200];
pub const METHODS: [&str; 2] = ["barrier", "projection"];
pub const DURATION: f64 = 1.5;
pub const QUICK_DURATION: f64 = 0.4;
/// The projection above this n takes minutes a step (docs/contact.md): not run.
pub const PROJECTION_MAX_N: usize = 600;

/// One run's cost.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactCost {
    pub n: usize,
    pub method: &'static str,
    pub steps: usize,
    /// Process CPU time per step: median and 95th percentile, ms.
    pub step_ms_median: f64,
    pub step_ms_p95: f64,
    pub cpu_s: f64,
    pub iterations_median: f64,
    /// Largest relative edge-length error of a published frame.
    pub isometry_error_max: f64,
}

/// Run the plan with the scenes in `scene_dir`.
pub fn run(scene_dir: &Path, quick: bool) -> Result<Vec<ContactCost>, ReportError> {
    let file = scene_dir.join(format!("{SCENE}.yaml"));
    let (resolutions, duration) = if quick {
        (&RESOLUTIONS[..2], QUICK_DURATION)
    } else {
        (&RESOLUTIONS[..], DURATION)
    };
    let mut rows = Vec::new();
    for &n in resolutions {
        for method in METHODS {
            if method == "projection" && n > PROJECTION_MAX_N {
                continue;
            }
            let sets = vec![
                format!("ribbon.segments={n}"),
                format!("contact.method={method}"),
                format!("duration={duration}"),
            ];
            let mut s = scene::load(&file, &sets)?;
            let cpu = process_cpu_s();
            let Ok(stats) = runner::run(&mut s, &mut (), &|| false);
            rows.push(ContactCost {
                n,
                method,
                steps: stats.steps,
                step_ms_median: stats.step_ms.median,
                step_ms_p95: stats.step_ms.p95,
                cpu_s: process_cpu_s() - cpu,
                iterations_median: stats.solver.iterations_median,
                isometry_error_max: stats.isometry_error_max,
            });
        }
    }
    Ok(rows)
}

/// `contact_cost.csv`.
pub fn write_csv(path: &Path, rows: &[ContactCost]) -> Result<(), ReportError> {
    let mut text = String::from(
        "scene,n,method,steps,step_ms_median,step_ms_p95,cpu_s,iterations_median,isometry_error_max\n",
    );
    for r in rows {
        text.push_str(&format!(
            "{SCENE},{},{},{},{},{},{},{},{:e}\n",
            r.n,
            r.method,
            r.steps,
            r.step_ms_median,
            r.step_ms_p95,
            r.cpu_s,
            r.iterations_median,
            r.isometry_error_max
        ));
    }
    std::fs::write(path, text).map_err(report_error::io("cannot write", path))
}

/// The summary's table.
pub fn summary(rows: &[ContactCost]) -> String {
    let mut s = format!(
        "## Contact against n ({SCENE}, both methods)\n\n`--set ribbon.segments=n --set contact.method=m`; step times are wall time of the runner (one thread), the isometry error is the published frames' largest relative edge error (docs/contact_barrier.md).\n\n| n | method | median step (ms) | p95 (ms) | CPU (s) | median iterations | isometry error max |\n|---|---|---|---|---|---|---|\n"
    );
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {:.2} | {:.2} | {:.2} | {} | {:.1e} |\n",
            r.n,
            r.method,
            r.step_ms_median,
            r.step_ms_p95,
            r.cpu_s,
            r.iterations_median,
            r.isometry_error_max
        ));
    }
    s
}
