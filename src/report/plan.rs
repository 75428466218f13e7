//! What the report runs: per scene, a converged reference and sweeps of time step,
//! resolution and solver tolerance for each method. Pure data: the runs are described
//! as `--set` overrides of the scene file, executed by [`super::exec`].

/// How a run is simulated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Method {
    /// Ribbon, our projected Gauss-Newton, full kinetic model (Pan et al. sec. 4).
    GaussNewton,
    /// Ribbon, the paper's L-BFGS-B inside the augmented Lagrangian (algorithm 2).
    Lbfgsb,
    /// Ribbon, Gauss-Newton with the mass lumped on the centerline (sec. 6).
    Lumped,
    /// The conforming-FEM ribbon (triangle mesh, 10 across, stiffness 1e8).
    ConformingFem,
    /// The paper simulator (Schreck et al.), its Newton FEM step.
    Paper,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::GaussNewton => "gauss_newton",
            Method::Lbfgsb => "lbfgsb",
            Method::Lumped => "gauss_newton_lumped",
            Method::ConformingFem => "conforming_fem",
            Method::Paper => "paper_newton",
        }
    }
}

/// Which parameter a run varies (the others at the scene's defaults).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sweep {
    Reference,
    TimeStep,
    Resolution,
    Tolerance,
}

impl Sweep {
    pub fn name(self) -> &'static str {
        match self {
            Sweep::Reference => "reference",
            Sweep::TimeStep => "dt",
            Sweep::Resolution => "resolution",
            Sweep::Tolerance => "tolerance",
        }
    }
}

/// The kind of scene, which decides the methods and the resolution key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneKind {
    /// One ribbon (Pan et al.): resolution is `ribbon.segments` (elements along).
    Ribbon,
    /// One sheet (Schreck et al.): resolution is `paper.boundary_density` (samples/m).
    Paper,
}

/// One run of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSpec {
    pub method: Method,
    pub sweep: Sweep,
    /// Time step h, s.
    pub dt: f64,
    /// Ribbon elements along (ribbon methods and the FEM's quads along), or the paper's
    /// boundary sample density (samples/m).
    pub resolution: f64,
    /// Ribbon: the inner stop (projected gradient reduction, dimensionless); FEM and
    /// paper: the Newton stop on the largest update, m.
    pub tolerance: f64,
}

/// The scene's defaults the sweeps start from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneDefaults {
    pub kind: SceneKind,
    /// Simulated duration used by the report, s (the scene's, or shorter for --quick).
    pub duration: f64,
    pub resolution: f64,
    pub tolerance: f64,
}

/// A scene's plan: the sample times, the reference and the runs.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenePlan {
    pub defaults: SceneDefaults,
    /// Times at which every run is compared with the reference, s.
    pub sample_times: Vec<f64>,
    pub reference: RunSpec,
    pub runs: Vec<RunSpec>,
}

/// The sample interval divided by `k`: time steps that land on every sample time.
fn dts(interval: f64, divisors: &[u32]) -> Vec<f64> {
    divisors.iter().map(|k| interval / *k as f64).collect()
}

/// The plan of one scene. `quick`: 3 time steps of the fast solver, one run of each
/// other method, a reference that differs only in time step and tolerance (so even a
/// short run sees the time error alone); full: wider sweeps and a reference at twice
/// the resolution.
pub fn plan(defaults: SceneDefaults, quick: bool) -> ScenePlan {
    let samples = if quick { 5 } else { 10 };
    let interval = defaults.duration / samples as f64;
    let sample_times = (1..=samples).map(|k| interval * k as f64).collect();
    let d = defaults;
    let spec = |method, sweep, dt, resolution, tolerance| RunSpec {
        method,
        sweep,
        dt,
        resolution,
        tolerance,
    };
    let mut runs = Vec::new();
    match d.kind {
        SceneKind::Ribbon => {
            let (main, others, reference_div, ref_resolution) = if quick {
                (vec![2, 4, 8], vec![4], 16, d.resolution)
            } else {
                (
                    vec![2, 4, 8, 16, 32],
                    vec![2, 4, 8, 16],
                    64,
                    2.0 * d.resolution,
                )
            };
            for dt in dts(interval, &main) {
                runs.push(spec(
                    Method::GaussNewton,
                    Sweep::TimeStep,
                    dt,
                    d.resolution,
                    d.tolerance,
                ));
            }
            for dt in dts(interval, &others) {
                runs.push(spec(
                    Method::Lbfgsb,
                    Sweep::TimeStep,
                    dt,
                    d.resolution,
                    d.tolerance,
                ));
            }
            for dt in dts(interval, if quick { &others } else { &main }) {
                runs.push(spec(
                    Method::Lumped,
                    Sweep::TimeStep,
                    dt,
                    d.resolution,
                    d.tolerance,
                ));
            }
            // the FEM costs ~100x a ribbon step: three time steps in the full report
            let fem_dts = if quick { vec![4] } else { vec![2, 4, 8] };
            for dt in dts(interval, &fem_dts) {
                runs.push(spec(
                    Method::ConformingFem,
                    Sweep::TimeStep,
                    dt,
                    d.resolution,
                    1e-6,
                ));
            }
            if !quick {
                let dt = interval / 8.0;
                for r in [0.5 * d.resolution, 2.0 * d.resolution] {
                    runs.push(spec(
                        Method::GaussNewton,
                        Sweep::Resolution,
                        dt,
                        r.round(),
                        d.tolerance,
                    ));
                    runs.push(spec(
                        Method::ConformingFem,
                        Sweep::Resolution,
                        dt,
                        r.round(),
                        1e-6,
                    ));
                }
                for tol in [1e-3, 1e-9] {
                    runs.push(spec(
                        Method::GaussNewton,
                        Sweep::Tolerance,
                        dt,
                        d.resolution,
                        tol,
                    ));
                }
            }
            ScenePlan {
                defaults,
                sample_times,
                reference: spec(
                    Method::GaussNewton,
                    Sweep::Reference,
                    interval / reference_div as f64,
                    ref_resolution,
                    1e-10,
                ),
                runs,
            }
        }
        SceneKind::Paper => {
            let (main, reference_div, ref_resolution) = if quick {
                (vec![2, 4, 8], 16, d.resolution)
            } else {
                (vec![3, 6, 9, 18], 36, 2.0 * d.resolution)
            };
            for dt in dts(interval, &main) {
                runs.push(spec(
                    Method::Paper,
                    Sweep::TimeStep,
                    dt,
                    d.resolution,
                    d.tolerance,
                ));
            }
            if !quick {
                let dt = interval / 9.0;
                for r in [0.5 * d.resolution, 2.0 * d.resolution] {
                    runs.push(spec(Method::Paper, Sweep::Resolution, dt, r, d.tolerance));
                }
            }
            ScenePlan {
                defaults,
                sample_times,
                reference: spec(
                    Method::Paper,
                    Sweep::Reference,
                    interval / reference_div as f64,
                    ref_resolution,
                    d.tolerance * 1e-2,
                ),
                runs,
            }
        }
    }
}

/// The `--set` overrides that turn a scene file into `run` (the FEM reads the ribbon
/// scene built with them: dt, duration, strip; its own resolution is applied by the
/// executor).
pub fn overrides(kind: SceneKind, duration: f64, run: &RunSpec) -> Vec<String> {
    let mut o = vec![format!("duration={duration}"), format!("dt={}", run.dt)];
    match kind {
        SceneKind::Ribbon => {
            if run.method != Method::ConformingFem {
                o.push(format!(
                    "ribbon.segments={}",
                    run.resolution.round() as usize
                ));
                o.push(format!("solver.tolerance={}", run.tolerance));
            }
            match run.method {
                Method::Lbfgsb => o.push("solver.kind=lbfgsb".into()),
                Method::Lumped => o.push("ribbon.kinetic=lumped".into()),
                Method::GaussNewton => o.push("solver.kind=gauss_newton".into()),
                _ => {}
            }
        }
        SceneKind::Paper => {
            o.push(format!("paper.boundary_density={}", run.resolution));
            o.push(format!("paper.newton_tolerance={}", run.tolerance));
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_steps_land_on_every_sample_time() {
        for quick in [true, false] {
            for kind in [SceneKind::Ribbon, SceneKind::Paper] {
                let p = plan(
                    SceneDefaults {
                        kind,
                        duration: 2.0,
                        resolution: 50.0,
                        tolerance: 1e-6,
                    },
                    quick,
                );
                for run in p.runs.iter().chain([&p.reference]) {
                    for t in &p.sample_times {
                        let steps = t / run.dt;
                        assert!((steps - steps.round()).abs() < 1e-9, "{run:?} at {t}");
                    }
                }
            }
        }
    }
}
