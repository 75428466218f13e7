//! No allocation per camera frame once warm (issue 48): a counting global allocator
//! sees no allocation while a warm renderer captures a snapshot of the world and renders
//! color, depth, noise and cloud, on two rayon threads. (Its own binary: the count is
//! global, and no other test may allocate meanwhile.)

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

use developable_sim::camera::{world_colliders, Renderer, Snapshot};
use developable_sim::scene::CameraMount;

mod common;
use common::load;

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
fn a_warm_camera_frame_allocates_nothing() {
    // the push scene: a ribbon, a ground plane, a box carried by a handle, D435 noise
    let mut s = load("ribbon_gripper_push", &[]);
    let cam = s.cameras[0].clone();
    let CameraMount::Fixed(pose) = cam.mount else {
        panic!("a fixed camera")
    };
    let mut renderer = Renderer::new(cam.camera, world_colliders(&s.world));
    let mut snapshot = Snapshot::default();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let mut counts = Vec::new();
    for frame in 0..8u64 {
        s.world.step(&[]);
        let before = allocations();
        snapshot.capture(&s.world);
        let key = cam.noise_key(s.source.seed, frame);
        pool.install(|| {
            renderer.render(&snapshot, &pose, &key);
        });
        counts.push(allocations() - before);
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
    // the first frames fill the buffers; after that, nothing
    assert!(counts[0] > 0, "{counts:?}");
    assert!(
        counts[2..].iter().all(|&c| c == 0),
        "allocations per frame: {counts:?}"
    );
}
