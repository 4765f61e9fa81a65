//! A steady step allocates nothing: the World reuses its buffers (issue 6). Counted with a
//! global allocator that tallies allocations made by the current thread only, so the test
//! harness's own threads do not disturb the count.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use tiltbox::cases::benchmark_setups;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> u64 {
    ALLOCATIONS.with(|c| c.get())
}

#[test]
fn a_steady_step_does_not_allocate() {
    for name in ["pyramid_20", "resting_pyramid", "falling_bricks"] {
        let setup = benchmark_setups()
            .into_iter()
            .find(|s| s.name == name)
            .expect("known scene");
        let mut world = setup.build().expect("valid scene");
        // Warm up: buffers grow to the scene's size, islands fall asleep where allowed.
        for _ in 0..(setup.warm_up.max(120)) {
            world.step(1.0 / 60.0).expect("valid dt");
        }
        let before = allocations();
        for _ in 0..60 {
            world.step(1.0 / 60.0).expect("valid dt");
        }
        let during = allocations() - before;
        assert_eq!(during, 0, "{name}: {during} allocations in 60 steady steps");
    }
    // The counter does count: building a world allocates.
    let before = allocations();
    let _ = benchmark_setups()[1].build();
    assert!(allocations() > before);
}
