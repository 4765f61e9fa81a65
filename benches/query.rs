//! Criterion benchmarks of queries: the closest hit of a 40 m ray, and the first query after a
//! step (bringing the query tree up to date), in worlds of 10,000 and 100,000 bodies.
//!
//! ```text
//! cargo bench --no-default-features --features measure --bench query
//! ```
//!
//! The bodies are boxes, discs and capsules of 0.5-1.5 m, one per 2 m cell of a square grid
//! (jittered, turned), static, as the resting bricks of a large scene are. Each ray starts at a
//! random point among them and runs 40 m in a random direction, so most stop at their first
//! body within a few metres (as a pointer's or a line of sight's do) and some cross open
//! ground. The bound set before tuning (issue 33): a closest hit in at most 20 us at 10,000
//! bodies and at most twice that at 100,000.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::time::Duration;
use tiltbox::physics::{vec2, BodyDef, QueryFilter, Real, Shape, Vec2, World};

/// A small deterministic generator (numbers in [0, 1)).
struct Dice(u32);

impl Dice {
    fn next(&mut self) -> Real {
        self.0 = self.0.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (self.0 >> 8) as Real / (1u32 << 24) as Real
    }
}

/// `n` static bodies on a grid of 2 m cells; the side of the grid (m).
fn world(n: usize, dice: &mut Dice) -> (World, Real) {
    let side = (n as Real).sqrt().ceil() as usize;
    let mut w = World::default();
    for i in 0..n {
        let cell = vec2((i % side) as Real, (i / side) as Real) * 2.0;
        let at = cell + vec2(dice.next(), dice.next()) * 0.5;
        let size = 0.5 + dice.next();
        let shape = match i % 3 {
            0 => Shape::rect(size, 0.5 * size),
            1 => Shape::circle(0.5 * size),
            _ => Shape::capsule(size, 0.2 * size),
        };
        let def = BodyDef::fixed(shape, at).with_angle(6.0 * dice.next());
        w.add_body(&def).expect("valid body");
    }
    (w, 2.0 * side as Real)
}

fn rays(count: usize, side: Real, dice: &mut Dice) -> Vec<(Vec2, Vec2)> {
    (0..count)
        .map(|_| {
            let origin = vec2(dice.next(), dice.next()) * side;
            let angle = std::f64::consts::TAU as Real * dice.next();
            (origin, vec2(angle.cos(), angle.sin()) * 40.0)
        })
        .collect()
}

fn bench_rays(c: &mut Criterion) {
    for n in [10_000usize, 100_000] {
        let mut dice = Dice(17);
        let (mut w, side) = world(n, &mut dice);
        let rays = rays(4096, side, &mut dice);
        let q = w.query();
        let mut k = 0;
        c.bench_function(&format!("ray_closest/{n}"), |b| {
            b.iter(|| {
                let (origin, d) = rays[k % rays.len()];
                k += 1;
                black_box(
                    q.ray_closest(origin, d, QueryFilter::DEFAULT)
                        .expect("finite"),
                )
            })
        });
    }
}

fn bench_refresh(c: &mut Criterion) {
    let mut dice = Dice(5);
    let (mut w, _) = world(10_000, &mut dice);
    w.query();
    c.bench_function("query_after_a_step/10000", |b| {
        b.iter(|| {
            w.step(1.0 / 60.0).expect("step");
            black_box(w.query().world().body_count())
        })
    });
}

criterion_group! {
    name = queries;
    config = Criterion::default()
        .sample_size(30)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    targets = bench_rays, bench_refresh
}
criterion_main!(queries);
