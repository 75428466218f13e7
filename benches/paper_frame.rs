//! Criterion benchmark of one frame of the paper simulator (Schreck et al.): the three
//! steps (FEM on S_P, remeshing of S_G, developable and isometric tracking) of a frame
//! of `paper_cylinder_then_bend` (fig. 1), measured at two moments: during the cylinder
//! wrap (smooth, one curved region) and during the orthogonal bend (singular vertices,
//! many regions). Each iteration steps a clone of the warmed world, so every sample
//! measures the same frame.
//!
//! Run: `cargo bench --bench paper_frame`.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use developable_sim::scene;

fn frame(c: &mut Criterion) {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("config/scenes/paper_cylinder_then_bend.yaml");
    let mut group = c.benchmark_group("paper_frame");
    group.sample_size(30);
    // frame 30 (t = 1 s, cylinder wrap) and frame 70 (t = 2.33 s, after the singular
    // vertices of the second bend)
    for warm in [30usize, 70] {
        let mut s = scene::load(&path, &[]).expect("scene");
        for _ in 0..warm {
            s.world.step(&[]);
        }
        group.bench_function(BenchmarkId::new("cylinder_then_bend", warm), |b| {
            b.iter_batched(
                || s.world.clone(),
                |mut w| black_box(w.step(&[])),
                criterion::BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, frame);
criterion_main!(benches);
