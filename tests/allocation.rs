//! A steady step allocates nothing: the World reuses its buffers (issue 6). Counted with a
//! global allocator that tallies allocations made by the current thread only, so the test
//! harness's own threads do not disturb the count.
#![cfg(feature = "measure")]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use tiltbox::measure::cases::{self, benchmark_setups};
use tiltbox::physics::{vec2, BodyDef, QueryFilter, Real, Settings, Shape, ShapeFlags, World};

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
    // A settled pile of every shape kind (polygons included) steps without allocating too.
    let mut world = World::new(Settings::soft_step(), vec2(0.0, -9.81)).expect("valid");
    cases::closed_box(&mut world, 10.0, 10.0, 0.5).expect("valid box");
    for i in 0..60 {
        let at = vec2(-4.5 + (i % 10) as Real, 0.6 + 1.1 * (i / 10) as Real);
        world
            .add_body(&BodyDef::dynamic(cases::mixed_shape(i), at))
            .expect("valid body");
    }
    for _ in 0..600 {
        world.step(1.0 / 60.0).expect("valid dt");
    }
    let before = allocations();
    for _ in 0..60 {
        world.step(1.0 / 60.0).expect("valid dt");
    }
    assert_eq!(
        allocations() - before,
        0,
        "mixed pile allocated in 60 steady steps"
    );
    // The counter does count: building a world allocates.
    let before = allocations();
    let _ = benchmark_setups()[1].build();
    assert!(allocations() > before);
}

#[test]
fn a_steady_step_with_joints_does_not_allocate() {
    // Box2D's joint grid, 20 a side, hanging: its joints' constraints and rows are rebuilt
    // into the same buffers every step.
    let setup = cases::joint_grid(20);
    let mut world = setup.build().expect("valid scene");
    for _ in 0..300 {
        world.step(1.0 / 60.0).expect("valid dt");
    }
    let before = allocations();
    for _ in 0..60 {
        world.step(1.0 / 60.0).expect("valid dt");
    }
    let during = allocations() - before;
    assert_eq!(
        during, 0,
        "joint_grid(20): {during} allocations in 60 steady steps"
    );
}

#[test]
fn a_steady_step_with_events_and_queries_does_not_allocate() {
    // A pile whose every shape reports contacts and hits, under a sensor, asked a ray each step:
    // the event lists and the query tree reuse their buffers.
    let settings = Settings {
        enable_sleep: false,
        ..Settings::soft_step()
    };
    let mut world = World::new(settings, vec2(0.0, -9.81)).expect("valid");
    cases::closed_box(&mut world, 10.0, 10.0, 0.5).expect("valid box");
    let all = ShapeFlags {
        contact_events: true,
        hit_events: true,
        sensor: false,
    };
    for i in 0..60 {
        let at = vec2(-4.5 + (i % 10) as Real, 0.6 + 1.1 * (i / 10) as Real);
        let def = BodyDef::dynamic(cases::mixed_shape(i), at).with_flags(all);
        world.add_body(&def).expect("valid body");
    }
    let zone = ShapeFlags {
        sensor: true,
        ..ShapeFlags::default()
    };
    let sensor = BodyDef::fixed(Shape::rect(5.0, 3.0), vec2(-2.5, 1.5)).with_flags(zone);
    world.add_body(&sensor).expect("valid sensor");
    let mut ray = || {
        world.step(1.0 / 60.0).expect("valid dt");
        let q = world.query();
        let hit = q.ray_closest(vec2(0.0, 9.0), vec2(0.0, -9.0), QueryFilter::DEFAULT);
        assert!(hit.expect("finite").is_some());
        world.events().contact_begin.len()
    };
    for _ in 0..600 {
        ray();
    }
    let before = allocations();
    for _ in 0..60 {
        ray();
    }
    let during = allocations() - before;
    assert_eq!(
        during, 0,
        "{during} allocations in 60 steady steps with events"
    );
}
