//! Criterion benchmarks of the contact stage (Pan et al. sec. 5.2):
//! - `overhead`: one step of a free-falling 50-element ribbon without colliders (no
//!   contact stage is built), with a ground plane far below (the stage runs, finds
//!   nothing) and resting on the ground (contacts every step): a scene without
//!   colliders pays nothing;
//! - `scene`: one whole step (optimization + contact) of the falling ribbon, the double
//!   chain and the Moebius chain mid-motion;
//! - `closeness`: the double chain with the stiff (Pan et al.) and the plain (Harmon et
//!   al.) closeness measure;
//! - `resting_vs_n`: one step of the falling ribbon at rest on the ground, n = 150, 300
//!   and 600 elements (the contact stage against n).
//!
//! Run: `cargo bench --bench contact` (add `-- overhead` etc. to filter).

use std::path::Path;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use developable_sim::scene;

mod common;
use common::{step_from, warm, warmed};

const FREE: &str = "duration: 1.0\ndt: 0.01\nribbon:\n  segments: 50\n  base: {mode: floating, position: [0, 0, 0.5]}\n";

fn overhead(c: &mut Criterion) {
    let mut group = c.benchmark_group("overhead");
    group.sample_size(30);
    let free = scene::load_str(FREE, Path::new("free.yaml"), &[]).expect("scene");
    assert!(
        free.world.contact_stage().is_none(),
        "no colliders: no stage"
    );
    let far = format!("{FREE}colliders:\n  - {{kind: plane, position: [0, 0, -10]}}\n");
    let far = scene::load_str(&far, Path::new("far.yaml"), &[]).expect("scene");
    assert!(far.world.contact_stage().is_some());
    let resting = FREE.replace("[0, 0, 0.5]", "[0, 0, 0.0011]")
        + "colliders:\n  - {kind: plane}\ncontact: {thickness: 0.002}\n";
    let resting = scene::load_str(&resting, Path::new("resting.yaml"), &[]).expect("scene");
    for (name, base) in [
        ("no_colliders", warm(free, 5)),
        ("far_ground", warm(far, 5)),
        ("resting", warm(resting, 5)),
    ] {
        group.bench_function(name, step_from(&base));
    }
    group.finish();
}

fn scenes(c: &mut Criterion) {
    let mut group = c.benchmark_group("scene");
    group.sample_size(10);
    for (name, warm) in [
        ("ribbon_falling", 60),
        ("ribbon_double_chain", 15),
        ("ribbon_mobius_chain", 25),
        ("ribbon_gripper_push", 60),
    ] {
        let base = warmed(name, &[], warm);
        group.bench_function(name, step_from(&base));
    }
    group.finish();
}

fn closeness(c: &mut Criterion) {
    let mut group = c.benchmark_group("closeness");
    group.sample_size(10);
    for kind in ["stiff", "plain"] {
        let base = warmed(
            "ribbon_double_chain",
            &[format!("contact.closeness={kind}")],
            15,
        );
        group.bench_function(BenchmarkId::new("double_chain", kind), step_from(&base));
    }
    group.finish();
}

/// One step of ribbon_falling at rest on the ground (t = 1.2 s: every contact of the
/// patch active) against the number of elements: the contact stage's cost against n.
fn resting_vs_n(c: &mut Criterion) {
    let mut group = c.benchmark_group("resting_vs_n");
    group.sample_size(10);
    for n in [150usize, 300, 600] {
        let base = warmed("ribbon_falling", &[format!("ribbon.segments={n}")], 120);
        group.bench_function(BenchmarkId::from_parameter(n), step_from(&base));
    }
    group.finish();
}

criterion_group!(benches, overhead, scenes, closeness, resting_vs_n);
criterion_main!(benches);
