//! No allocation per Newton iteration once warm (issue 14): a counting global allocator
//! sees the same number of allocations in every step of the chain solver on
//! ribbon_extreme_torsion, whatever that step's iteration count. (Its own binary: the
//! count is global, and no other test may allocate meanwhile.)

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use developable_sim::ribbon::{RibbonSim, SolverKind};
use developable_sim::scene;

mod common;
use common::TORSION;

struct Counting;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> u64 {
    ALLOCATIONS.load(Ordering::Relaxed)
}

#[test]
fn a_chain_step_allocates_the_same_whatever_its_iteration_count() {
    let path = Path::new(TORSION);
    let sets = [
        "ribbon.segments=100".to_string(),
        "solver.kind=chain".to_string(),
        // one augmented-Lagrangian round a step: a round allocates its multiplier
        // update (per round, not per iteration)
        "solver.max_outer_iterations=1".to_string(),
    ];
    let mut s = scene::load(path, &sets).expect("scene");
    assert_eq!(
        s.world
            .object_as::<RibbonSim>(0)
            .expect("a ribbon")
            .params
            .solver
            .kind,
        SolverKind::Chain
    );
    for _ in 0..5 {
        s.world.step(&[]);
    }
    let mut per_step = Vec::new();
    for _ in 0..12 {
        let before = allocations();
        let report = s.world.step(&[]);
        let count = allocations() - before;
        per_step.push((report.objects[0].iterations, count));
        // the check's teeth: an allocation in the counted span is seen
        let before = allocations();
        let probe = std::hint::black_box(vec![1u8; 16]);
        assert_eq!(
            allocations() - before,
            1,
            "the counter missed an allocation"
        );
        drop(probe);
    }
    let iterations: Vec<u32> = per_step.iter().map(|p| p.0).collect();
    assert!(
        iterations.iter().max() > iterations.iter().min(),
        "steps with different iteration counts are needed: {per_step:?}"
    );
    let counts: Vec<u64> = per_step.iter().map(|p| p.1).collect();
    assert!(
        counts.iter().all(|&c| c == counts[0]),
        "allocations per step vary with the iterations: {per_step:?}"
    );
}
