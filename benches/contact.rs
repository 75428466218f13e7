//! Criterion benchmarks of contact, both methods side by side (`barrier`: contact
//! inside the step, docs/contact_barrier.md, the default; `projection`: the stage of
//! Pan et al. sec. 5.2 after it):
//! - `overhead`: one step of a free-falling 50-element ribbon without colliders (no
//!   contact is built), with a ground plane far below (contact runs, finds nothing)
//!   and resting on the ground (contacts every step): a scene without colliders pays
//!   nothing;
//! - `scene`: one whole step of each contact scene mid-motion, per method (the box
//!   edge and capsule fingers scenes: barrier only);
//! - `closeness`: the double chain with the stiff (Pan et al.) and the plain (Harmon et
//!   al.) closeness measure (projection);
//! - `resting_vs_n`: one step of the falling ribbon at rest on the ground (t = 1.2 s)
//!   against n, per method: the cost of contact against n (barrier: O(n) per Newton
//!   iteration; projection: the dense dual, O(m^3) in the resting contacts m).
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
    let mut cases = vec![("no_colliders".to_string(), warm(free, 5))];
    for method in METHODS {
        let far = format!(
            "{FREE}colliders:\n  - {{kind: plane, position: [0, 0, -10]}}\ncontact: {{method: {method}}}\n"
        );
        let far = scene::load_str(&far, Path::new("far.yaml"), &[]).expect("scene");
        assert!(far.world.has_contact());
        let resting = FREE.replace("[0, 0, 0.5]", "[0, 0, 0.0011]")
            + &format!("colliders:\n  - {{kind: plane}}\ncontact: {{thickness: 0.002, method: {method}}}\n");
        let resting = scene::load_str(&resting, Path::new("resting.yaml"), &[]).expect("scene");
        cases.push((format!("far_ground/{method}"), warm(far, 5)));
        cases.push((format!("resting/{method}"), warm(resting, 5)));
    }
    for (name, base) in &cases {
        group.bench_function(name.as_str(), step_from(base));
    }
    group.finish();
}

/// The two contact methods.
const METHODS: [&str; 2] = ["barrier", "projection"];

fn scenes(c: &mut Criterion) {
    let mut group = c.benchmark_group("scene");
    group.sample_size(10);
    for (name, warm) in [
        ("ribbon_falling", 60),
        ("ribbon_double_chain", 15),
        ("ribbon_mobius_chain", 25),
        ("ribbon_gripper_push", 60),
        ("ribbon_box_edge", 30),
        ("ribbon_capsule_fingers", 50),
    ] {
        for method in METHODS {
            let barrier_only = name == "ribbon_box_edge" || name == "ribbon_capsule_fingers";
            if method == "projection" && barrier_only {
                continue;
            }
            let base = warmed(name, &[format!("contact.method={method}")], warm);
            group.bench_function(BenchmarkId::new(name, method), step_from(&base));
        }
    }
    group.finish();
}

fn closeness(c: &mut Criterion) {
    let mut group = c.benchmark_group("closeness");
    group.sample_size(10);
    for kind in ["stiff", "plain"] {
        let base = warmed(
            "ribbon_double_chain",
            &[
                format!("contact.closeness={kind}"),
                "contact.method=projection".to_string(),
            ],
            15,
        );
        group.bench_function(BenchmarkId::new("double_chain", kind), step_from(&base));
    }
    group.finish();
}

/// One step of ribbon_falling at rest on the ground (t = 1.2 s: every contact of the
/// patch active) against the number of elements, per method: the cost of contact
/// against n (the projection at n = 1200 is left out: minutes a step, docs/contact.md).
fn resting_vs_n(c: &mut Criterion) {
    let mut group = c.benchmark_group("resting_vs_n");
    group.sample_size(10);
    for n in [150usize, 300, 600, 1200] {
        for method in METHODS {
            if method == "projection" && n > 600 {
                continue;
            }
            let sets = [
                format!("ribbon.segments={n}"),
                format!("contact.method={method}"),
            ];
            let base = warmed("ribbon_falling", &sets, 120);
            group.bench_function(BenchmarkId::new(method, n), step_from(&base));
        }
    }
    group.finish();
}

criterion_group!(benches, overhead, scenes, closeness, resting_vs_n);
criterion_main!(benches);
