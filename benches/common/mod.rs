//! Helpers the criterion benchmarks share: a scene of `config/scenes` advanced to
//! mid-motion, and the routine that times one step of it.

use std::hint::black_box;
use std::path::Path;

use criterion::{BatchSize, Bencher};
use developable_sim::scene::{self, Scene};

/// `config/scenes/<name>.yaml` with the `--set` overrides `sets`.
pub fn load(name: &str, sets: &[String]) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config/scenes")
        .join(format!("{name}.yaml"));
    scene::load(&path, sets).expect("scene")
}

/// `s` advanced `steps` steps, so the step measured is mid-motion.
pub fn warm(mut s: Scene, steps: usize) -> Scene {
    for _ in 0..steps {
        s.world.step(&[]);
    }
    s
}

/// [`load`], then [`warm`].
pub fn warmed(name: &str, sets: &[String], steps: usize) -> Scene {
    warm(load(name, sets), steps)
}

/// Times one `World::step` from a copy of `base`, so every sample measures the same
/// step; making the copy is not timed.
pub fn step_from(base: &Scene) -> impl FnMut(&mut Bencher) + '_ {
    move |b| {
        b.iter_batched(
            || base.clone(),
            |mut s| black_box(s.world.step(&[])),
            BatchSize::LargeInput,
        )
    }
}
