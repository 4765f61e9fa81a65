//! Standard set-ups shared by the tests, the accuracy report and the benchmarks: grounds,
//! stacks, pyramids and closed boxes, built the way Box2D's samples and benchmark build them.

use crate::physics::{BodyDef, BodyId, PhysicsError, Real, Shape, Vec2, World};

/// A static ground box `width` x `thickness` metres whose top surface is at y = 0, centred on x = `x`.
pub fn ground(
    world: &mut World,
    x: Real,
    width: Real,
    thickness: Real,
) -> Result<BodyId, PhysicsError> {
    world.add_body(&BodyDef::fixed(
        Shape::rect(width, thickness),
        Vec2::new(x, -0.5 * thickness),
    ))
}

/// `n` boxes of side `size` stacked on y = 0, centred on x = `x`, each `gap` above the one below.
/// Returns the ids bottom to top.
pub fn stack(
    world: &mut World,
    n: usize,
    size: Real,
    x: Real,
    gap: Real,
) -> Result<Vec<BodyId>, PhysicsError> {
    (0..n)
        .map(|i| {
            let y = 0.5 * size + i as Real * (size + gap);
            world.add_body(&BodyDef::dynamic(Shape::rect(size, size), Vec2::new(x, y)))
        })
        .collect()
}

/// A pyramid with `base` boxes of side `size` in its bottom row, resting on y = 0 and centred on
/// x = `x`: row i has base - i boxes (Box2D's benchmark layout). `base` = 100 gives 5,050 boxes.
pub fn pyramid(
    world: &mut World,
    base: usize,
    size: Real,
    x: Real,
    friction: Real,
) -> Result<Vec<BodyId>, PhysicsError> {
    let mut ids = Vec::with_capacity(base * (base + 1) / 2);
    for row in 0..base {
        let count = base - row;
        let y = (0.5 + row as Real) * size;
        let x0 = x - 0.5 * (count as Real - 1.0) * size;
        for j in 0..count {
            let def =
                BodyDef::dynamic(Shape::rect(size, size), Vec2::new(x0 + j as Real * size, y))
                    .with_friction(friction);
            ids.push(world.add_body(&def)?);
        }
    }
    Ok(ids)
}

/// A closed box of four static walls: inner size `width` x `height` metres, walls `thickness`
/// thick, inner floor at y = 0, centred on x = 0. Returns the walls: floor, ceiling, left, right.
pub fn closed_box(
    world: &mut World,
    width: Real,
    height: Real,
    thickness: Real,
) -> Result<[BodyId; 4], PhysicsError> {
    let t = thickness;
    let outer = width + 2.0 * t;
    Ok([
        world.add_body(&BodyDef::fixed(
            Shape::rect(outer, t),
            Vec2::new(0.0, -0.5 * t),
        ))?,
        world.add_body(&BodyDef::fixed(
            Shape::rect(outer, t),
            Vec2::new(0.0, height + 0.5 * t),
        ))?,
        world.add_body(&BodyDef::fixed(
            Shape::rect(t, height),
            Vec2::new(-0.5 * (width + t), 0.5 * height),
        ))?,
        world.add_body(&BodyDef::fixed(
            Shape::rect(t, height),
            Vec2::new(0.5 * (width + t), 0.5 * height),
        ))?,
    ])
}
