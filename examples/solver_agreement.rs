//! Two solver kinds on one scene (issue 47: trust_region against the damped chain
//! solver): along the first solver's trajectory, one step of each from the same state
//! at every step, the RMS distance of their step minimizers (largest over the
//! ribbons, at matched material points) where both converge; then both run on their
//! own and their singular-point counts are compared step by step.
//!
//!     cargo run --release --example solver_agreement -- ribbon_extreme_torsion 50 0.3 chain trust_region
//!
//! Arguments: the scene's name in config/scenes, n (every ribbon's elements), the
//! duration in s, the two solver kinds, optionally every ribbon's `solver.tolerance`
//! (both solvers; default: the scene's). A kind `chain+exact`, `chain+saddle`,
//! `chain+cut` (or several, `chain+exact+cut`) is the chain solver with the issue 47
//! variants `solver.end_crease_exact`, `solver.saddle_free`, `solver.cut_keeps_shift`.

use developable_sim::metrics::{rms_distance, strip_samples};
use developable_sim::ribbon::{ChainVariant, RibbonSim, SolverKind};
use developable_sim::scene::{self, Scene};

fn kind(name: &str) -> Result<(SolverKind, ChainVariant), String> {
    let mut parts = name.split('+');
    let kind = match parts.next().unwrap_or("") {
        "chain" => SolverKind::Chain,
        "gauss_newton" => SolverKind::GaussNewton,
        "trust_region" => SolverKind::TrustRegion,
        "interior_point" => SolverKind::InteriorPoint,
        "lbfgsb" => SolverKind::Lbfgsb,
        other => return Err(format!("unknown solver kind {other}")),
    };
    let mut variant = ChainVariant::default();
    for part in parts {
        match part {
            "exact" => variant.end_crease_exact = true,
            "saddle" => variant.saddle_free = true,
            "cut" => variant.cut_keeps_shift = true,
            other => return Err(format!("unknown chain variant {other}")),
        }
    }
    Ok((kind, variant))
}

fn load(name: &str, n: usize) -> Result<Scene, Box<dyn std::error::Error>> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config/scenes")
        .join(format!("{name}.yaml"));
    let text = std::fs::read_to_string(&path)?;
    if text.contains("\nribbons:") {
        let text = text.replace("segments: 50", &format!("segments: {n}"));
        let copy = std::env::temp_dir().join(format!("solver_agreement_{name}_{n}.yaml"));
        std::fs::write(&copy, text)?;
        return Ok(scene::load(&copy, &[])?);
    }
    Ok(scene::load(&path, &[format!("ribbon.segments={n}")])?)
}

fn set_kind(s: &mut Scene, (kind, variant): (SolverKind, ChainVariant)) {
    for i in 0..s.world.objects().len() {
        if let Some(r) = s.world.object_as_mut::<RibbonSim>(i) {
            r.params.solver.kind = kind;
            r.params.solver.chain_variant = variant;
        }
    }
}

/// Largest RMS distance over the ribbons of two scenes, m.
fn distance(a: &Scene, b: &Scene) -> f64 {
    let mut rms: f64 = 0.0;
    for i in 0..a.world.objects().len() {
        let Some(r) = a.world.object_as::<RibbonSim>(i) else {
            continue;
        };
        let strip = *r.strip();
        let samples = strip_samples(strip.length, strip.width, 101, 3);
        let d = rms_distance(a.world.mesh(i), b.world.mesh(i), &samples).unwrap_or(f64::NAN);
        rms = rms.max(d);
    }
    rms
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (name, n, duration, first, second, tolerance) = match args.as_slice() {
        [a, b, c, d, e] => (a, b, c, d, e, None),
        [a, b, c, d, e, t] => (a, b, c, d, e, Some(t.parse::<f64>()?)),
        _ => return Err("usage: solver_agreement SCENE N DURATION KIND_A KIND_B [TOL]".into()),
    };
    let n: usize = n.parse()?;
    let duration: f64 = duration.parse()?;
    let (ka, kb) = (kind(first)?, kind(second)?);
    let mut a = load(name, n)?;
    set_kind(&mut a, ka);
    if let Some(t) = tolerance {
        for i in 0..a.world.objects().len() {
            if let Some(r) = a.world.object_as_mut::<RibbonSim>(i) {
                r.params.solver.tolerance = t;
            }
        }
    }
    let steps = (duration / a.world.dt()).round() as usize;
    let mut b_alone = a.clone();
    set_kind(&mut b_alone, kb);
    let (mut worst, mut both, mut either_failed, mut its_a, mut its_b) = (0.0_f64, 0, 0, 0, 0);
    let (mut worst_step, mut singular_same_state) = (0, 0);
    let mut distances = Vec::with_capacity(steps);
    let (mut differing_counts, mut singular_a, mut singular_b) = (0, 0, 0);
    let converged = |r: &developable_sim::sim::StepReport| r.objects.iter().all(|o| o.converged);
    let singular = |r: &developable_sim::sim::StepReport| -> usize {
        r.objects.iter().map(|o| o.singular_points).sum()
    };
    let iterations = |r: &developable_sim::sim::StepReport| -> u32 {
        r.objects.iter().map(|o| o.iterations).sum()
    };
    for step in 0..steps {
        // one step of each from the same state
        let mut b = a.clone();
        set_kind(&mut b, kb);
        let rb = b.world.step(&[]);
        let ra = a.world.step(&[]);
        its_a += iterations(&ra);
        its_b += iterations(&rb);
        if converged(&ra) && converged(&rb) {
            both += 1;
            let d = distance(&a, &b);
            distances.push(d);
            // (a NaN distance, a sample outside a mesh, counts as the largest)
            if d.is_nan() || d > worst {
                worst = d;
                worst_step = step;
            }
        } else {
            either_failed += 1;
        }
        singular_same_state += usize::from(singular(&ra) != singular(&rb));
        // the second solver on its own trajectory
        let rb_alone = b_alone.world.step(&[]);
        differing_counts += usize::from(singular(&ra) != singular(&rb_alone));
        singular_a = singular_a.max(singular(&ra));
        singular_b = singular_b.max(singular(&rb_alone));
        if std::env::var_os("VERBOSE").is_some() {
            println!(
                "step {step:3} {first} {} it {} sing {} | {second} {} it {} sing {} | alone sing {} | rms {:.2e}",
                converged(&ra),
                iterations(&ra),
                singular(&ra),
                converged(&rb),
                iterations(&rb),
                singular(&rb),
                singular(&rb_alone),
                distance(&a, &b)
            );
        }
    }
    let final_distance = distance(&a, &b_alone);
    distances.sort_by(f64::total_cmp);
    let median = distances
        .get(distances.len() / 2)
        .copied()
        .unwrap_or(f64::NAN);
    let within = distances.iter().filter(|&&d| d <= 1e-9).count();
    println!(
        "{name} n={n} {duration}s tol {tolerance:?} {first} vs {second}: {steps} steps, both converged {both}, \
         either not {either_failed}, one-step RMS <= 1e-9 m in {within}, median {median:.1e} m, \
         largest {worst:.3e} m (step {worst_step}), \
         iterations {its_a} vs {its_b}; singular counts differ (same start) in {singular_same_state} \
         steps; own trajectories: counts differ in {differing_counts} steps, max {singular_a} vs \
         {singular_b}, final RMS {final_distance:.3e} m"
    );
    Ok(())
}
