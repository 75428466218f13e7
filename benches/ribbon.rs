//! Criterion benchmarks of the ribbon simulator (Pan et al.):
//! - one implicit-Euler step of each paper scene (ours), and the paper's L-BFGS-B on
//!   extreme torsion as the baseline in the same run;
//! - one objective + gradient evaluation against n, adjoint (appendix C) vs chain rule
//!   (appendix A);
//! - one step of extreme torsion against n = 50 .. 1600: the chain solver
//!   (docs/ribbon_chain_solver.md), the dense projected Newton up to n = 400 and the
//!   paper's L-BFGS-B up to n = 100 (beyond, a step takes seconds: issue 14).
//!
//! Run: `cargo bench --bench ribbon` (add `-- gradient`, `-- step/` or `-- step_vs_n`
//! to filter); `python3 tools/step_vs_n.py` prints the step_vs_n medians as JSON.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use developable_sim::ribbon::objective::GradientMode;
use developable_sim::ribbon::{RibbonSim, SolverKind};

mod common;
use common::{step_from, warmed};

fn step_per_scene(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    group.sample_size(20);
    for (name, warm) in [
        ("ribbon_extreme_torsion", 50),
        ("ribbon_extreme_dragging", 20),
        ("ribbon_wide_torsion", 50),
        ("ribbon_helix_unrolling", 20),
        ("ribbon_spinning", 50),
        ("mobius_band", 5),
    ] {
        let base = warmed(name, &[], warm);
        group.bench_function(BenchmarkId::new("newton", name), step_from(&base));
    }
    let base = warmed(
        "ribbon_extreme_torsion",
        &["solver.kind=lbfgsb".to_string()],
        50,
    );
    group.sample_size(10);
    group.bench_function(
        BenchmarkId::new("lbfgsb", "ribbon_extreme_torsion"),
        step_from(&base),
    );
    group.finish();
}

fn gradient_vs_n(c: &mut Criterion) {
    let mut group = c.benchmark_group("gradient");
    group.sample_size(20);
    for n in [50usize, 100, 200, 400, 800] {
        let mut s = warmed(
            "ribbon_extreme_torsion",
            &[format!("ribbon.segments={n}"), "duration=0.05".into()],
            3,
        );
        let r = s
            .world
            .object_as_mut::<RibbonSim>(0)
            .expect("a ribbon scene");
        let mut g = Vec::new();
        group.bench_function(BenchmarkId::new("adjoint", n), |b| {
            b.iter(|| black_box(r.evaluate_gradient(GradientMode::Adjoint, &mut g)))
        });
        if n <= 400 {
            group.bench_function(BenchmarkId::new("chain_rule", n), |b| {
                b.iter(|| black_box(r.evaluate_gradient(GradientMode::ChainRule, &mut g)))
            });
        }
    }
    group.finish();
}

/// One step of ribbon_extreme_torsion at n elements, after 10 steps of the chain solver
/// (past the flat start's saddle), by each solver from that same state.
fn step_vs_n(c: &mut Criterion) {
    let mut group = c.benchmark_group("step_vs_n");
    group.sample_size(10);
    for n in [50usize, 100, 200, 400, 800, 1600] {
        let sets = [
            format!("ribbon.segments={n}"),
            "solver.kind=chain".to_string(),
        ];
        let base = warmed("ribbon_extreme_torsion", &sets, 10);
        for (kind, largest) in [
            (SolverKind::Chain, 1600),
            (SolverKind::GaussNewton, 400),
            (SolverKind::Lbfgsb, 100),
        ] {
            if n > largest {
                continue;
            }
            let mut start = base.clone();
            start
                .world
                .object_as_mut::<RibbonSim>(0)
                .expect("a ribbon scene")
                .params
                .solver
                .kind = kind;
            group.bench_function(BenchmarkId::new(kind_name(kind), n), step_from(&start));
        }
    }
    group.finish();
}

fn kind_name(kind: SolverKind) -> &'static str {
    match kind {
        SolverKind::Chain => "chain",
        SolverKind::GaussNewton => "gauss_newton",
        SolverKind::Lbfgsb => "lbfgsb",
        SolverKind::TrustRegion => "trust_region",
        SolverKind::InteriorPoint => "interior_point",
    }
}

criterion_group!(benches, step_per_scene, gradient_vs_n, step_vs_n);
criterion_main!(benches);
