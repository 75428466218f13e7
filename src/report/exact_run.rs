//! Runs the exact-solution scenes (an edge: loads scene files, times runs) and measures
//! every run against the exact solution ([`super::exact`]).

use std::path::Path;

use super::exact::{
    self, checks, exact_plan, Check, ExactError, ExactProblem, ExactSpec, VIBRATION_SEGMENTS,
    VIBRATION_TIP,
};
use super::exec::{execute_with, RunOutput};
use super::plan::{Method, SceneKind};
use super::report_error::ReportError;
use crate::geometry::{Point2, SurfaceMesh};
use crate::metrics::{grid_samples, world_at_material};
use crate::ribbon::{ClampRule, RibbonSim};

/// One exact-solution run: what it was, what it cost, its error.
#[derive(Clone, Debug)]
pub struct ExactRow {
    pub spec: ExactSpec,
    pub run: RunOutput,
    pub error: Option<ExactError>,
}

/// An exact-solution scene's runs and checks.
#[derive(Clone, Debug)]
pub struct ExactSceneReport {
    pub name: String,
    pub problem: ExactProblem,
    pub sample_times: Vec<f64>,
    pub rows: Vec<ExactRow>,
    pub checks: Vec<Check>,
    /// The scene's own clamp rule (the one checked).
    pub clamp: &'static str,
    /// Implicit Euler's own error on the first mode at each swept dt of the fast
    /// method, m ([`exact::implicit_euler_mode_error`] times the amplitude and the RMS of
    /// the mode shape over the compared points); empty for static scenes.
    pub theory: Vec<(f64, f64)>,
}

/// The exact problem scene `file` is built for, from its `name` and parameters (B =
/// 2 alpha w, q = rho w |g|, mu = rho w, D the far clamp's target x); None for scenes
/// without one.
pub fn problem_of(file: &Path) -> Result<Option<ExactProblem>, ReportError> {
    let scene = crate::scene::load(file, &[])?;
    if !exact::EXACT_SCENES.contains(&scene.name.as_str()) {
        return Ok(None);
    }
    let r = scene.world.object_as::<RibbonSim>(0).ok_or_else(|| {
        ReportError::Invalid(format!(
            "{}: an exact-solution scene is one ribbon",
            file.display()
        ))
    })?;
    let p = &r.params;
    let bending = 2.0 * p.bending_stiffness * p.width;
    let mu = p.density * p.width;
    let g = p.gravity;
    Ok(Some(match scene.name.as_str() {
        "exact_heavy_cantilever" => ExactProblem::HeavyCantilever {
            length: p.length,
            bending,
            weight_per_length: mu * (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt(),
        },
        "exact_buckled_strip" => {
            let h = scene.world.handles().first().ok_or_else(|| {
                ReportError::Invalid(format!("{}: no far clamp handle", file.display()))
            })?;
            let end = h.trajectory.pose_at(scene.duration).translation.vector;
            ExactProblem::BuckledStrip {
                length: p.length,
                bending,
                end_distance: end.x,
            }
        }
        _ => {
            if p.segments != VIBRATION_SEGMENTS {
                return Err(ReportError::Invalid(format!(
                    "{}: the vibrating cantilever is swept at its {VIBRATION_SEGMENTS} segments",
                    file.display()
                )));
            }
            ExactProblem::VibratingCantilever {
                length: p.length,
                bending,
                mass_per_length: mu,
                tip: VIBRATION_TIP,
            }
        }
    }))
}

/// The scene-file name of a clamp rule.
fn clamp_name(rule: ClampRule) -> &'static str {
    match rule {
        ClampRule::MomentMatched => "moment_matched",
        ClampRule::DualLength => "dual_length",
        ClampRule::Paper => "paper",
    }
}

/// The material points compared: 41 x 5 on the strip, inset by a micrometre.
fn points(problem: &ExactProblem, width: f64) -> Vec<Point2> {
    let l = problem.length();
    grid_samples(
        Point2::new(0.0, -0.5 * width),
        Point2::new(l, 0.5 * width),
        41,
        5,
        1e-6,
    )
}

/// A run's error against the exact solution over its samples (None if a sample is
/// missing, a point is outside the pattern or a position is not finite).
fn error_of(
    problem: &ExactProblem,
    times: &[f64],
    samples: &[SurfaceMesh],
    pts: &[Point2],
) -> Option<ExactError> {
    if samples.len() != times.len() || samples.is_empty() {
        return None;
    }
    let mut sum = 0.0;
    for (t, mesh) in times.iter().zip(samples) {
        let pos: Option<Vec<_>> = pts.iter().map(|m| world_at_material(mesh, m)).collect();
        let d = exact::rms_to_exact(&problem.curve_at(*t), pts, &pos?);
        sum += d * d;
    }
    let rms = (sum / times.len() as f64).sqrt();
    rms.is_finite().then(|| ExactError {
        rms,
        relative: rms / problem.scale(),
    })
}

/// Run every planned run of the exact-solution scene `file` (`on_run` is told before
/// each, for the progress bar).
pub fn run_exact_scene(
    file: &Path,
    name: &str,
    problem: ExactProblem,
    quick: bool,
    on_run: &mut dyn FnMut(String),
) -> Result<ExactSceneReport, ReportError> {
    let scene = crate::scene::load(file, &[])?;
    let ribbon = scene
        .world
        .object_as::<RibbonSim>(0)
        .ok_or_else(|| ReportError::Invalid(format!("{}: one ribbon", file.display())))?;
    let (dt, tolerance, width) = (
        scene.world.dt(),
        ribbon.params.solver.tolerance,
        ribbon.params.width,
    );
    let (duration, sample_times) = match problem.angular_frequency() {
        // one period, 5 (quick) or 10 samples
        Some(omega) => {
            let period = 2.0 * std::f64::consts::PI / omega;
            let k = if quick { 5 } else { 10 };
            (
                period,
                (1..=k)
                    .map(|i| period * i as f64 / k as f64)
                    .collect::<Vec<_>>(),
            )
        }
        None => (scene.duration, vec![scene.duration]),
    };
    let interval = sample_times[0];
    let pts = points(&problem, width);
    let clamp = clamp_name(ribbon.params.clamp);
    let mut rows = Vec::new();
    for spec in exact_plan(&problem, quick, dt, tolerance, interval, clamp) {
        let r = &spec.run;
        on_run(format!(
            "{name}: {} {} dt={} n={} tol={}",
            r.method.name(),
            spec.clamp,
            r.dt,
            r.resolution,
            r.tolerance
        ));
        let mut extra = vec![format!("ribbon.clamp={}", spec.clamp)];
        if !problem.is_static() {
            let n = r.resolution.round() as usize;
            let angles = exact::vibration_bending_angles(problem.length(), n, VIBRATION_TIP);
            extra.push(format!("ribbon.initial_shape.bending_angles={angles:?}"));
        }
        let mut run = execute_with(file, SceneKind::Ribbon, duration, r, &sample_times, &extra)
            .map_err(|e| {
                let what = format!("{name}: {} n={} dt={}", r.method.name(), r.resolution, r.dt);
                ReportError::in_run(what, e)
            })?;
        let error = error_of(&problem, &sample_times, &run.samples, &pts).filter(|_| run.finite);
        run.samples = Vec::new();
        rows.push(ExactRow { spec, run, error });
    }
    let pairs: Vec<(ExactSpec, Option<ExactError>)> =
        rows.iter().map(|r| (r.spec.clone(), r.error)).collect();
    let theory = match (problem, problem.angular_frequency()) {
        (ExactProblem::VibratingCantilever { length, tip, .. }, Some(omega)) => {
            let mode = crate::metrics::elastica::CantileverMode::new(length);
            let shape_rms = (pts.iter().map(|m| mode.shape(m.x).powi(2)).sum::<f64>()
                / pts.len() as f64)
                .sqrt();
            rows.iter()
                .filter(|r| r.spec.run.method == Method::Chain)
                .filter(|r| r.spec.run.sweep == super::plan::Sweep::TimeStep)
                .map(|r| {
                    let dt = r.spec.run.dt;
                    let e = exact::implicit_euler_mode_error(omega, dt, &sample_times);
                    (dt, e * tip * shape_rms)
                })
                .collect()
        }
        _ => Vec::new(),
    };
    Ok(ExactSceneReport {
        name: name.to_string(),
        problem,
        checks: checks(name, &problem, clamp, &pairs, &theory),
        clamp,
        sample_times,
        rows,
        theory,
    })
}
