//! What the report runs: per scene, a converged reference and sweeps of time step,
//! resolution and solver tolerance for each method. Pure data: the runs are described
//! as `--set` overrides of the scene file, executed by [`super::exec`].

/// How a run is simulated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Method {
    /// Ribbon, the default solver (`solver.kind: chain`): our projected Newton method
    /// with the Newton system solved along the chain in O(n), full kinetic model (Pan
    /// et al. sec. 4).
    Chain,
    /// Ribbon, the same projected Newton method on the dense matrix (O(n^3) a
    /// factorization): the same iterates as [`Method::Chain`] to round-off, at a
    /// higher cost; the report shows it so the cost of the dense baseline is visible.
    GaussNewton,
    /// Ribbon, the paper's L-BFGS-B inside the augmented Lagrangian (algorithm 2).
    Lbfgsb,
    /// Ribbon, the default solver with the mass lumped on the centerline (sec. 6).
    Lumped,
    /// The conforming-FEM ribbon (triangle mesh, 10 across, stiffness 1e8).
    ConformingFem,
    /// The paper simulator (Schreck et al.), its Newton FEM step.
    Paper,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Chain => "chain",
            Method::GaussNewton => "gauss_newton",
            Method::Lbfgsb => "lbfgsb",
            Method::Lumped => "chain_lumped",
            Method::ConformingFem => "conforming_fem",
            Method::Paper => "paper_newton",
        }
    }

    /// The method in a legend or a table's heading: its name and what it is.
    pub fn describe(self) -> &'static str {
        match self {
            Method::Chain => "chain (the default solver)",
            Method::GaussNewton => "gauss_newton (dense matrix: chain's iterates, its cost)",
            Method::Lbfgsb => "lbfgsb (the paper's L-BFGS-B)",
            Method::Lumped => "chain_lumped (mass lumped on the centerline)",
            Method::ConformingFem => "conforming_fem (triangle-mesh baseline)",
            Method::Paper => "paper_newton (the paper simulator)",
        }
    }

    /// The method whose dt sweep gives a scene's order in time (the default solver).
    pub fn fast(kind: SceneKind) -> Method {
        match kind {
            SceneKind::Ribbon => Method::Chain,
            SceneKind::Paper => Method::Paper,
        }
    }
}

/// Which parameter a run varies (the others at the scene's defaults).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sweep {
    Reference,
    /// The reference at twice its time step: its distance to the reference estimates
    /// the reference's own time error (first order: e(2h) - e(h) ~ e(h)).
    ReferenceCheck,
    /// The reference at four times its time step: its distance to the 2 dt run,
    /// against the 2 dt run's distance to the reference, gives the order of the
    /// reference's own halvings, i.e. whether the 2 dt estimate holds.
    ReferenceCheckCoarse,
    TimeStep,
    Resolution,
    Tolerance,
}

impl Sweep {
    pub fn name(self) -> &'static str {
        match self {
            Sweep::Reference => "reference",
            Sweep::ReferenceCheck => "reference_2dt",
            Sweep::ReferenceCheckCoarse => "reference_4dt",
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
    /// The reference at twice its time step (see [`Sweep::ReferenceCheck`]).
    pub reference_check: RunSpec,
    /// The reference at four times its time step (see [`Sweep::ReferenceCheckCoarse`]).
    pub reference_check_coarse: RunSpec,
    pub runs: Vec<RunSpec>,
}

impl ScenePlan {
    fn new(
        defaults: SceneDefaults,
        sample_times: Vec<f64>,
        reference: RunSpec,
        runs: Vec<RunSpec>,
    ) -> Self {
        let reference_check = RunSpec {
            sweep: Sweep::ReferenceCheck,
            dt: 2.0 * reference.dt,
            ..reference.clone()
        };
        let reference_check_coarse = RunSpec {
            sweep: Sweep::ReferenceCheckCoarse,
            dt: 4.0 * reference.dt,
            ..reference.clone()
        };
        ScenePlan {
            defaults,
            sample_times,
            reference,
            reference_check,
            reference_check_coarse,
            runs,
        }
    }
}

/// The sample interval divided by `k`: time steps that land on every sample time.
fn dts(interval: f64, divisors: &[u32]) -> Vec<f64> {
    divisors.iter().map(|k| interval / *k as f64).collect()
}

/// The plan of one scene. `quick`: 3 time steps of the fast solver, one run of each
/// other method, a reference that differs only in time step (1/32 of the sample
/// interval) and tolerance (so even a short run sees the time error alone); full: 5
/// (4 when the reference is coarse) time steps of the fast solver and of the lumped
/// model, up to 4 of L-BFGS-B, up to 3 of the conforming FEM (~100x a ribbon step),
/// all at least 4x the reference's dt, resolution and tolerance sweeps of the fast
/// solver at its middle dt, and a reference at 1/`reference_divisor` of the sample
/// interval (default 64 for ribbons, 72 for paper; a multiple of 4, so the reference's
/// 2 dt and 4 dt checks land on the sample times too) and `reference_refinement`
/// (default 2) times the resolution.
pub fn plan(
    defaults: SceneDefaults,
    quick: bool,
    reference_divisor: Option<u32>,
    reference_refinement: Option<f64>,
) -> ScenePlan {
    let refine = reference_refinement.unwrap_or(2.0);
    let samples = if quick { 5 } else { 10 };
    let interval = defaults.duration / samples as f64;
    let sample_times = (1..=samples).map(|k| interval * k as f64).collect();
    let sweep = SweepSettings {
        interval,
        quick,
        reference_divisor,
        refine,
    };
    let (runs, reference) = match defaults.kind {
        SceneKind::Ribbon => ribbon_runs(defaults, &sweep),
        SceneKind::Paper => paper_runs(defaults, &sweep),
    };
    ScenePlan::new(defaults, sample_times, reference, runs)
}

/// What a scene's sweeps are derived from besides its defaults.
struct SweepSettings {
    /// The sample interval, s.
    interval: f64,
    quick: bool,
    /// The reference's dt is `interval` divided by this (default per kind).
    reference_divisor: Option<u32>,
    /// The reference's resolution over the scene's.
    refine: f64,
}

/// A run of `method` in `sweep` at time step `dt` (s), `resolution` and `tolerance`.
fn spec(method: Method, sweep: Sweep, dt: f64, resolution: f64, tolerance: f64) -> RunSpec {
    RunSpec {
        method,
        sweep,
        dt,
        resolution,
        tolerance,
    }
}

/// The divisors of the sample interval a ribbon scene's dt sweeps use, per method,
/// and its reference's divisor and resolution (elements).
struct RibbonDivisors {
    main: Vec<u32>,
    lbfgsb: Vec<u32>,
    fem: Vec<u32>,
    reference: u32,
    reference_resolution: f64,
}

/// Quick: 2, 4, 8 for the fast solver, 4 for the others, a reference at interval / 32
/// and the scene's resolution. Full: every swept dt at least 4x the reference's (so
/// its 2 dt check run is still finer than every run).
fn ribbon_divisors(d: SceneDefaults, sweep: &SweepSettings) -> RibbonDivisors {
    if sweep.quick {
        return RibbonDivisors {
            main: vec![2, 4, 8],
            lbfgsb: vec![4],
            fem: vec![4],
            reference: 32,
            reference_resolution: d.resolution,
        };
    }
    // the 5 finest of interval / 1 .. 32
    let reference_div = sweep.reference_divisor.unwrap_or(64);
    let upto = |ks: &[u32], keep: usize| -> Vec<u32> {
        let v: Vec<u32> = ks
            .iter()
            .copied()
            .filter(|k| 4 * k <= reference_div)
            .collect();
        v[v.len().saturating_sub(keep)..].to_vec()
    };
    RibbonDivisors {
        main: upto(&[1, 2, 4, 8, 16, 32], 5),
        lbfgsb: upto(&[1, 2, 4, 8, 16], 4),
        fem: upto(&[2, 4, 8], 3),
        reference: reference_div,
        reference_resolution: (sweep.refine * d.resolution).round(),
    }
}

/// A ribbon scene's runs (dt sweeps of every method; full: resolution and tolerance
/// sweeps of the fast solver at its middle dt) and its reference.
fn ribbon_runs(d: SceneDefaults, sweep: &SweepSettings) -> (Vec<RunSpec>, RunSpec) {
    let (interval, quick) = (sweep.interval, sweep.quick);
    let k = ribbon_divisors(d, sweep);
    let mut runs = Vec::new();
    for dt in dts(interval, &k.main) {
        runs.push(spec(
            Method::Chain,
            Sweep::TimeStep,
            dt,
            d.resolution,
            d.tolerance,
        ));
    }
    // the dense baseline: chain's iterates at its cost (quick: the middle dt only)
    let middle = [k.main[k.main.len() / 2]];
    for dt in dts(interval, if quick { &middle } else { &k.main }) {
        runs.push(spec(
            Method::GaussNewton,
            Sweep::TimeStep,
            dt,
            d.resolution,
            d.tolerance,
        ));
    }
    for dt in dts(interval, &k.lbfgsb) {
        runs.push(spec(
            Method::Lbfgsb,
            Sweep::TimeStep,
            dt,
            d.resolution,
            d.tolerance,
        ));
    }
    for dt in dts(interval, if quick { &k.lbfgsb } else { &k.main }) {
        runs.push(spec(
            Method::Lumped,
            Sweep::TimeStep,
            dt,
            d.resolution,
            d.tolerance,
        ));
    }
    for dt in dts(interval, &k.fem) {
        runs.push(spec(
            Method::ConformingFem,
            Sweep::TimeStep,
            dt,
            d.resolution,
            1e-6,
        ));
    }
    if !quick {
        let dt = interval / k.main[k.main.len() / 2] as f64;
        for r in [0.5 * d.resolution, 2.0 * d.resolution] {
            runs.push(spec(
                Method::Chain,
                Sweep::Resolution,
                dt,
                r.round(),
                d.tolerance,
            ));
        }
        for tol in [1e-3, 1e-9] {
            runs.push(spec(Method::Chain, Sweep::Tolerance, dt, d.resolution, tol));
        }
    }
    let reference = spec(
        Method::Chain,
        Sweep::Reference,
        interval / k.reference as f64,
        k.reference_resolution,
        1e-10,
    );
    (runs, reference)
}

/// A paper scene's runs (a dt sweep; full: resolution and tolerance sweeps at
/// interval / 9) and its reference (default interval / 72, tolerance / 100).
fn paper_runs(d: SceneDefaults, sweep: &SweepSettings) -> (Vec<RunSpec>, RunSpec) {
    let (interval, quick) = (sweep.interval, sweep.quick);
    let (main, reference_div, ref_resolution) = if quick {
        (vec![2, 4, 8], 32, d.resolution)
    } else {
        (
            vec![3, 6, 9, 18],
            sweep.reference_divisor.unwrap_or(72),
            sweep.refine * d.resolution,
        )
    };
    let mut runs = Vec::new();
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
        for tol in [1e-4, 1e-8] {
            runs.push(spec(Method::Paper, Sweep::Tolerance, dt, d.resolution, tol));
        }
    }
    let reference = spec(
        Method::Paper,
        Sweep::Reference,
        interval / reference_div as f64,
        ref_resolution,
        d.tolerance * 1e-2,
    );
    (runs, reference)
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
                Method::Chain => o.push("solver.kind=chain".into()),
                Method::Lbfgsb => o.push("solver.kind=lbfgsb".into()),
                Method::Lumped => {
                    o.push("ribbon.kinetic=lumped".into());
                    o.push("solver.kind=chain".into());
                }
                Method::GaussNewton => o.push("solver.kind=gauss_newton".into()),
                Method::ConformingFem | Method::Paper => {}
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
                    None,
                    None,
                );
                for run in p.runs.iter().chain([
                    &p.reference,
                    &p.reference_check,
                    &p.reference_check_coarse,
                ]) {
                    for t in &p.sample_times {
                        let steps = t / run.dt;
                        assert!((steps - steps.round()).abs() < 1e-9, "{run:?} at {t}");
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod full_plan_tests {
    use super::*;

    /// The full report sweeps what issue 6 asks for on a ribbon: >= 4 time steps of our
    /// solver, L-BFGS-B, the lumped model, >= 2 time steps of the conforming FEM, a
    /// resolution and a tolerance sweep; the reference is finer than every run.
    #[test]
    fn full_ribbon_plan_sweeps_every_axis() {
        let d = SceneDefaults {
            kind: SceneKind::Ribbon,
            duration: 0.4,
            resolution: 50.0,
            tolerance: 1e-6,
        };
        let p = plan(d, false, Some(32), None);
        assert!(p.runs.iter().all(|r| r.dt >= 4.0 * p.reference.dt - 1e-15));
        let count = |m: Method, s: Sweep| {
            p.runs
                .iter()
                .filter(|r| r.method == m && r.sweep == s)
                .count()
        };
        assert!(count(Method::Chain, Sweep::TimeStep) >= 4);
        assert_eq!(
            count(Method::GaussNewton, Sweep::TimeStep),
            count(Method::Chain, Sweep::TimeStep)
        );
        assert!(count(Method::Lbfgsb, Sweep::TimeStep) >= 2);
        assert!(count(Method::Lumped, Sweep::TimeStep) >= 2);
        assert!(count(Method::ConformingFem, Sweep::TimeStep) >= 2);
        assert_eq!(count(Method::Chain, Sweep::Resolution), 2);
        assert_eq!(count(Method::Chain, Sweep::Tolerance), 2);
        let finest = p.runs.iter().map(|r| r.dt).fold(f64::MAX, f64::min);
        assert!(p.reference.dt < finest && p.reference_check.dt < finest);
        // with a fine reference: 5 time steps of our solver, 4 of L-BFGS-B
        let fine = plan(d, false, Some(128), Some(1.0));
        assert_eq!(fine.reference.resolution, d.resolution);
        assert_eq!(p.reference.resolution, 2.0 * d.resolution);
        let n = |m: Method| {
            fine.runs
                .iter()
                .filter(|r| r.method == m && r.sweep == Sweep::TimeStep)
                .count()
        };
        assert_eq!((n(Method::Chain), n(Method::Lbfgsb)), (5, 4));
        assert_eq!(p.reference_check.dt, 2.0 * p.reference.dt);
        assert_eq!(p.reference_check_coarse.dt, 4.0 * p.reference.dt);
        // the 4 dt check may coincide with the finest swept dt, never be finer
        assert!(p.reference_check_coarse.dt <= finest + 1e-15);
        assert!((p.reference.dt - 0.04 / 32.0).abs() < 1e-15);
    }
}
