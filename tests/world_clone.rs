//! A `World` cloned in the middle of a run steps on exactly as the original: every
//! piece of state a step carries to the next (the ribbon's history, its adaptive
//! penalty, the Newton solvers' damping, the trust region's radius, the paper's meshes)
//! is copied, buffers are not. The Python binding's `Simulation.copy()` relies on it (docs/python.md).

mod common;

use developable_sim::sim::World;

/// Every object's mesh vertices, as bits.
fn bits(world: &World) -> Vec<u64> {
    (0..world.objects().len())
        .flat_map(|o| world.mesh(o).vertices.clone())
        .flat_map(|p| [p.x, p.y, p.z])
        .map(f64::to_bits)
        .collect()
}

/// Step `k` steps, clone, step both `m` more: the two end bit-identical, with the same
/// step reports.
fn clone_continues(name: &str, sets: &[&str], k: usize, m: usize) {
    let mut world = common::load(name, sets).world;
    for _ in 0..k {
        world.step(&[]);
    }
    let mut twin = world.clone();
    for step in 0..m {
        let a = world.step(&[]);
        let b = twin.step(&[]);
        assert_eq!(
            a, b,
            "{name} {sets:?}: reports differ {step} steps after the clone"
        );
    }
    assert_eq!(bits(&world), bits(&twin), "{name} {sets:?}");
}

#[test]
fn a_cloned_world_continues_bit_for_bit() {
    // each ribbon solver (chain and dense Newton carry their damping between steps, the
    // trust region its radius and shift)
    for solver in ["chain", "gauss_newton", "lbfgsb", "trust_region"] {
        let kind = format!("solver.kind={solver}");
        clone_continues("ribbon_gripper", &["ribbon.segments=20", &kind], 8, 8);
    }
    // the contact stage, and the paper simulator across its first singular point
    clone_continues("ribbon_gripper_push", &["ribbon.segments=20"], 8, 8);
    clone_continues("paper_first_singularity", &[], 30, 8);
}

/// The check's negative test: a clone stepped with one other target differs.
#[test]
fn the_check_sees_a_clone_that_went_elsewhere() {
    let mut world = common::load("ribbon_gripper", &["ribbon.segments=20"]).world;
    for _ in 0..4 {
        world.step(&[]);
    }
    let mut twin = world.clone();
    let mut target = world.scripted_target(0, world.time() + world.dt());
    world.step(&[]);
    target.translation.vector.z += 1e-9;
    twin.step(&[Some(target)]);
    assert_ne!(bits(&world), bits(&twin));
}
