//! Per-step solver work of one scene run: Newton iterations, augmented-Lagrangian rounds,
//! convergence and singular points of every step, then the median and largest
//! iteration counts and the steps that did not converge (the `--stats` JSON gives the
//! median only). Used for docs/ribbon_chain_solver.md (issue 47):
//!
//!     cargo run --release --example solver_steps -- config/scenes/ribbon_extreme_torsion.yaml \
//!         0.3 ribbon.segments=400 seed=1 solver.kind=trust_region
//!
//! Arguments: the scene file, the duration in s, then `--set` overrides (key=value).
//! With `QUIET=1` only the summary line is printed.

use developable_sim::scene;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: solver_steps SCENE DURATION [key=value ...]")?;
    let duration: f64 = args.next().ok_or("missing the duration (s)")?.parse()?;
    let sets: Vec<String> = args.collect();
    let mut s = scene::load(std::path::Path::new(&path), &sets)?;
    let steps = (duration / s.world.dt()).round() as usize;
    let quiet = std::env::var_os("QUIET").is_some();
    let mut iterations = Vec::with_capacity(steps);
    let (mut unconverged, mut singular_max) = (0, 0);
    for step in 0..steps {
        let report = s.world.step(&[]);
        let its: u32 = report.objects.iter().map(|o| o.iterations).sum();
        let rounds: u32 = report.objects.iter().map(|o| o.outer_iterations).sum();
        let converged = report.objects.iter().all(|o| o.converged);
        let singular: usize = report.objects.iter().map(|o| o.singular_points).sum();
        singular_max = singular_max.max(singular);
        unconverged += usize::from(!converged);
        iterations.push(its);
        if !quiet {
            println!(
                "step {step:3} t {:.3} iterations {its:4} rounds {rounds:2} converged {converged} singular {singular}",
                report.time
            );
        }
    }
    let mut sorted = iterations.clone();
    sorted.sort_unstable();
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0);
    let max = sorted.last().copied().unwrap_or(0);
    let total: u32 = iterations.iter().sum();
    println!(
        "{path} {sets:?}: {steps} steps, iterations median {median} max {max} total {total}, \
         unconverged {unconverged}, singular points max {singular_max}"
    );
    Ok(())
}
