//! Queries: what a ray, a swept shape, a point, a box or a shape meets in the World.
//!
//! [`crate::physics::World::query`] brings the query tree (`tree.rs`) up to date and returns a
//! [`Query`](crate::physics::world::Query) view; this module holds what a query answers and the
//! exact test of one body's shapes (`geometry.rs`). Filters test both ways, as Box2D's
//! `b2QueryFilter`: a shape is seen when its category is in the query's mask and the query's
//! category is in the shape's mask.

pub(crate) mod geometry;
pub(crate) mod tree;

use self::geometry::{Crossing, Rounded};
use super::body::Body;
use super::collide::core;
use super::events::ShapeFlags;
use super::filter::Filter;
pub use super::id::ShapeRef;
use super::math::{Real, Transform, Vec2};
use super::shape::Shape;

/// Which shapes a query sees: those whose category is in `mask` and whose mask holds
/// `category`. The default (category 1, mask all) sees every shape with a default filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QueryFilter {
    /// The categories the query is in (tested against each shape's mask).
    pub category: u64,
    /// The categories it sees (tested against each shape's category).
    pub mask: u64,
}

impl QueryFilter {
    /// Sees every shape whose mask holds category 1 (every shape with a default filter).
    pub const DEFAULT: QueryFilter = QueryFilter {
        category: 1,
        mask: u64::MAX,
    };

    /// Whether the query sees a shape with filter `shape`.
    #[inline]
    pub fn sees(&self, shape: &Filter) -> bool {
        shape.category & self.mask != 0 && shape.mask & self.category != 0
    }
}

impl Default for QueryFilter {
    fn default() -> Self {
        QueryFilter::DEFAULT
    }
}

/// Where a ray or a swept shape first meets a shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// The shape met.
    pub shape: ShapeRef,
    /// The point met, on the shape's surface (m, world).
    pub point: Vec2,
    /// The shape's outward unit normal there (zero for a swept shape that starts overlapping).
    pub normal: Vec2,
    /// How far along the translation (0 at the start, 1 at its end).
    pub fraction: Real,
}

/// Each of `body`'s shapes with its index, its pose in the world, its filter and its flags.
pub(crate) fn every_shape(
    body: &Body,
) -> impl Iterator<Item = (u32, &Shape, Transform, Filter, ShapeFlags)> {
    let frame = body.frame();
    let own = body
        .compound()
        .is_none()
        .then(|| (0, body.shape(), frame, body.filter(), body.flags()));
    let parts = body.compound().into_iter().flat_map(move |p| {
        p.all.iter().enumerate().map(move |(i, part)| {
            let pose = frame.then(part.pose);
            (i as u32, &part.shape, pose, part.filter, part.flags)
        })
    });
    own.into_iter().chain(parts)
}

/// The shapes of `body` a query sees (sensors are never seen), as [`every_shape`] gives them.
pub(crate) fn shapes_of(body: &Body) -> impl Iterator<Item = (u32, &Shape, Transform, Filter)> {
    every_shape(body)
        .filter(|s| !s.4.sensor)
        .map(|(i, shape, xf, filter, _)| (i, shape, xf, filter))
}

/// A shape's core in the world at `xf`, with its radius.
pub(crate) fn rounded(shape: &Shape, xf: Transform) -> Rounded {
    let (core, radius) = core(shape);
    Rounded::new(core.vertices().iter().map(|&v| xf.apply(v)), radius)
}

/// The first of `body`'s shapes that `filter` sees met by `origin + t d`, t in [0, max].
pub(crate) fn ray_body(
    body: &Body,
    (origin, d, max): (Vec2, Vec2, Real),
    filter: &QueryFilter,
) -> Option<(u32, Crossing)> {
    shapes_of(body)
        .filter(|(_, _, _, f)| filter.sees(f))
        .filter_map(|(i, shape, xf, _)| {
            let hit = geometry::ray_rounded(&rounded(shape, xf), origin, d, max)?;
            Some((i, hit))
        })
        .min_by(|a, b| a.1.fraction.total_cmp(&b.1.fraction))
}

/// The shapes of `body` whose filter `sees` passes and that overlap `probe` (a rounded core in
/// the world): their cores closer than the two radii, or touching.
pub(crate) fn overlaps_body<'a>(
    body: &'a Body,
    probe: &'a Rounded,
    sees: impl Fn(&Filter) -> bool + 'a,
) -> impl Iterator<Item = u32> + 'a {
    shapes_of(body)
        .filter(move |(_, _, _, f)| sees(f))
        .filter(|(_, shape, xf, _)| {
            let s = rounded(shape, *xf);
            let gap = geometry::core_to_core(probe.vertices(), s.vertices()).0;
            gap == 0.0 || gap < probe.radius + s.radius
        })
        .map(|(i, ..)| i)
}

/// Where `probe` (a rounded core in the world) moved by `d` first meets one of `body`'s
/// shapes that `filter` sees within [0, max] of `d`.
pub(crate) fn cast_body(
    body: &Body,
    probe: &Rounded,
    d: Vec2,
    max: Real,
    filter: &QueryFilter,
) -> Option<RayHit> {
    shapes_of(body)
        .filter(|(_, _, _, f)| filter.sees(f))
        .filter_map(|(i, shape, xf, _)| {
            let (fraction, point, normal) = cast(probe, &rounded(shape, xf), d, max)?;
            let shape = ShapeRef {
                body: body.id(),
                shape: i,
            };
            Some(RayHit {
                shape,
                point,
                normal,
                fraction,
            })
        })
        .min_by(|a, b| a.fraction.total_cmp(&b.fraction))
}

/// Where `probe` moved by `d` first meets `target` within [0, max]: the fraction, the point on
/// `target`'s surface, and its normal there (toward the probe). A probe that starts
/// overlapping meets it at 0 with no normal.
fn cast(probe: &Rounded, target: &Rounded, d: Vec2, max: Real) -> Option<(Real, Vec2, Vec2)> {
    let (gap, pa, pb) = geometry::core_to_core(probe.vertices(), target.vertices());
    let reach = probe.radius + target.radius;
    if gap < reach {
        return Some((
            0.0,
            pb + (pa - pb).normalize_or_zero() * target.radius,
            Vec2::ZERO,
        ));
    }
    let mut offsets = geometry::difference(target.vertices(), probe.vertices());
    offsets.radius = reach;
    let hit = geometry::ray_rounded(&offsets, Vec2::ZERO, d, max)?;
    let moved = probe.moved(hit.fraction * d);
    let (_, _, pb) = geometry::core_to_core(moved.vertices(), target.vertices());
    Some((hit.fraction, pb + hit.normal * target.radius, hit.normal))
}
