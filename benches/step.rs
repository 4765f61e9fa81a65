//! Criterion benchmarks of one `World::step` (dt 1/60, default soft-step settings) on the
//! benchmark scenes of `tiltbox::measure::cases::benchmark_setups()`.
//!
//! ```text
//! cargo bench --no-default-features --features measure --bench step   # engine and set-ups only: quickest build
//! cargo bench --no-default-features --features measure --bench step -- pyramid_20
//! cargo bench --no-default-features --features measure --bench step -- mixed_shapes
//! cargo bench --no-default-features --features measure --bench step -- narrow_phase   # box fast path vs polygon
//! ```
//!
//! Each benchmark steps one World over and over (the scene keeps evolving, as in a game), after
//! the scene's own warm-up steps (`resting_pyramid`: 300 steps, so it is asleep). Sample sizes
//! and times are set so the whole file runs in under a minute; the side-by-side
//! comparison with Box2D v3 and rapier2d lives in `benchmarks/vs-peers`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::time::Duration;
use tiltbox::measure::cases::{benchmark_setups, Setup};
use tiltbox::physics::{Real, World};

const DT: Real = 1.0 / 60.0;

fn setup(name: &str) -> Setup {
    benchmark_setups()
        .into_iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no benchmark set-up named {name}"))
}

/// The scene built and run through its warm-up steps.
fn warmed_up(setup: &Setup) -> World {
    let mut world = setup.build().expect("benchmark set-up refused");
    for _ in 0..setup.warm_up {
        world.step(DT).expect("step failed");
    }
    world
}

fn bench_scene(c: &mut Criterion, name: &str, samples: usize, warm_up: f64, measure: f64) {
    let setup = setup(name);
    let mut world = warmed_up(&setup);
    let mut group = c.benchmark_group("step");
    group
        .sample_size(samples)
        .warm_up_time(Duration::from_secs_f64(warm_up))
        .measurement_time(Duration::from_secs_f64(measure));
    group.bench_function(name, |b| {
        b.iter(|| world.step(black_box(DT)).expect("step failed"))
    });
    group.finish();
}

fn small_scenes(c: &mut Criterion) {
    // About 5 s each: 1 s warm-up, 4 s of samples.
    bench_scene(c, "pyramid_20", 50, 1.0, 4.0);
    bench_scene(c, "falling_bricks", 50, 1.0, 4.0);
    bench_scene(c, "many_boxes", 30, 1.0, 4.0);
    bench_scene(c, "resting_pyramid", 50, 1.0, 4.0);
    bench_scene(c, "mixed_shapes", 30, 1.0, 4.0);
}

/// The rectangle's closed-form fast path against the same rectangles as general polygons, on
/// one fixed set of 1,000 random pairs (touching, overlapping and apart): the measurement behind
/// keeping `Shape::Rect` as its own variant.
fn narrow_phase(c: &mut Criterion) {
    use tiltbox::physics::collide::collide;
    use tiltbox::physics::{vec2, Polygon, Rot, Shape, Transform};
    let mut seed: u32 = 7;
    let mut next = || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as Real / (1u32 << 24) as Real
    };
    let mut pairs = Vec::new();
    for _ in 0..1000 {
        let (w, h) = (0.2 + next(), 0.2 + next());
        let xa = Transform {
            p: vec2(0.0, 0.0),
            q: Rot::from_angle(6.3 * next()),
        };
        let xb = Transform {
            p: vec2(2.0 * next() - 1.0, 2.0 * next() - 1.0),
            q: Rot::from_angle(6.3 * next()),
        };
        pairs.push((w, h, xa, xb));
    }
    let as_polygon = |w: Real, h: Real| {
        let (x, y) = (0.5 * w, 0.5 * h);
        let corners = [vec2(-x, -y), vec2(x, -y), vec2(x, y), vec2(-x, y)];
        Shape::from(Polygon::new(&corners).expect("a rectangle is convex").0)
    };
    let rects: Vec<_> = pairs
        .iter()
        .map(|&(w, h, xa, xb)| (Shape::rect(w, h), Shape::rect(h, w), xa, xb))
        .collect();
    let polygons: Vec<_> = pairs
        .iter()
        .map(|&(w, h, xa, xb)| (as_polygon(w, h), as_polygon(h, w), xa, xb))
        .collect();
    let mut group = c.benchmark_group("narrow_phase_1000_pairs");
    group
        .sample_size(50)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for (name, set) in [("rect_fast_path", &rects), ("rect_as_polygon", &polygons)] {
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut points = 0;
                for (a, bb, xa, xb) in set.iter() {
                    points += collide(a, *xa, bb, *xb, black_box(0.02)).count;
                }
                points
            })
        });
    }
    group.finish();
}

fn large_pyramid(c: &mut Criterion) {
    // 5,050 boxes at some 10-20 ms/step: 10 samples (criterion's minimum) of a few steps each.
    bench_scene(c, "large_pyramid", 10, 1.0, 8.0);
}

criterion_group!(benches, small_scenes, narrow_phase, large_pyramid);
criterion_main!(benches);
