//! Narrow phase: exact contact manifolds for pairs of shapes.
//!
//! One routine per pair of shape kinds; [`collide`] dispatches on the pair. Every routine
//! reports up to two points with a shared normal pointing from body A to body B, a signed
//! separation per point (negative = overlap) and a feature id so the solver can match a point
//! with the same point last step (warm starting).

mod capsule;
mod circle;
mod polygon;
mod segment;
pub(crate) mod toi;

pub(crate) use capsule::{collide_capsules, Capsule};
pub(crate) use circle::{collide_circles, collide_polygon_circle};
pub(crate) use polygon::{collide_polygons, collide_rects, Rounded};
pub(crate) use segment::collide_segment;

use super::convex::Polygon;
use super::math::{Real, Transform, Vec2};
use super::shape::Shape;
use std::borrow::Cow;

/// Identifies which features (edges and vertices) of the two shapes produced a contact point,
/// so the same physical contact keeps the same id from one step to the next.
pub type FeatureId = u16;

/// One contact point of a manifold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManifoldPoint {
    /// World position of the point, halfway between the two surfaces (m).
    pub point: Vec2,
    /// Signed distance between the surfaces along the normal (m); negative when overlapping.
    pub separation: Real,
    /// Which features produced the point.
    pub id: FeatureId,
}

/// The contact between two shapes: up to two points sharing one normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Manifold {
    /// Unit normal, world frame, pointing from shape A towards shape B.
    pub normal: Vec2,
    /// The points; only the first `count` are meaningful.
    pub points: [ManifoldPoint; 2],
    /// Number of points, 0 to 2.
    pub count: usize,
}

impl Manifold {
    /// A manifold with no points (the shapes are farther apart than the margin).
    pub const EMPTY: Manifold = Manifold {
        normal: Vec2::ZERO,
        points: [ManifoldPoint {
            point: Vec2::ZERO,
            separation: 0.0,
            id: 0,
        }; 2],
        count: 0,
    };

    /// The meaningful points.
    pub fn points(&self) -> &[ManifoldPoint] {
        &self.points[..self.count]
    }
}

/// Contact manifold between shape `a` at `xf_a` and shape `b` at `xf_b`.
///
/// Points whose separation exceeds `margin` metres are left out, so `margin > 0` also yields
/// speculative contacts (surfaces about to touch), which the soft-step solver uses to stop fast
/// bodies at the surface instead of letting them tunnel.
///
/// Every pair of kinds is covered: rectangle pairs by the closed-form box test; anything with a
/// circle by the one-point circle routines; capsule pairs by their segments' closest points;
/// every other pair (polygons, rectangles, a capsule against either) by the general clipper on
/// the shapes' cores and radii.
/// Segments (chain pieces) go through `collide_segment`, which knows their neighbours.
pub fn collide(a: &Shape, xf_a: Transform, b: &Shape, xf_b: Transform, margin: Real) -> Manifold {
    match (a, b) {
        (Shape::Segment(s), _) => collide_segment(s, xf_a, b, xf_b, margin),
        (_, Shape::Segment(s)) => collide_segment(s, xf_b, a, xf_a, margin).swapped(),
        (Shape::Rect { half_extents: ha }, Shape::Rect { half_extents: hb }) => {
            collide_rects(*ha, xf_a, *hb, xf_b, margin)
        }
        (Shape::Circle { radius: ra }, Shape::Circle { radius: rb }) => {
            collide_circles(*ra, xf_a.p, *rb, xf_b.p, margin)
        }
        (_, Shape::Circle { radius: rb }) => {
            let (core_a, ra) = core(a);
            collide_polygon_circle(&core_a, ra, xf_a, *rb, xf_b, margin)
        }
        (
            Shape::Capsule {
                half_length: ha,
                radius: ra,
            },
            Shape::Capsule {
                half_length: hb,
                radius: rb,
            },
        ) => {
            let capsule_a = Capsule {
                half_length: *ha,
                radius: *ra,
                xf: xf_a,
            };
            let capsule_b = Capsule {
                half_length: *hb,
                radius: *rb,
                xf: xf_b,
            };
            collide_capsules(capsule_a, capsule_b, margin)
        }
        (Shape::Circle { radius: ra }, _) => {
            let (core_b, rb) = core(b);
            collide_polygon_circle(&core_b, rb, xf_b, *ra, xf_a, margin).swapped()
        }
        _ => {
            let ((core_a, ra), (core_b, rb)) = (core(a), core(b));
            let rounded_a = Rounded::new(&core_a, ra, xf_a);
            let rounded_b = Rounded::new(&core_b, rb, xf_b);
            collide_polygons(rounded_a, rounded_b, margin)
        }
    }
}

/// A shape as a convex core and the radius it is grown by (m): a rectangle or polygon is its
/// own core with radius 0, a capsule is its segment, a circle is its centre.
pub(crate) fn core(shape: &Shape) -> (Cow<'_, Polygon>, Real) {
    match shape {
        Shape::Rect { half_extents } => (Cow::Owned(Polygon::rect(*half_extents)), 0.0),
        Shape::Polygon(p) => (Cow::Borrowed(p), 0.0),
        Shape::Capsule {
            half_length,
            radius,
        } => (Cow::Owned(Polygon::segment(*half_length)), *radius),
        Shape::Circle { radius } => (Cow::Owned(Polygon::point()), *radius),
        Shape::Segment(s) => (Cow::Owned(Polygon::between(s.a, s.b)), s.radius),
    }
}

impl Manifold {
    /// The same contact seen from the other body: normal reversed, and each feature id's two
    /// halves swapped so it still reads (A's feature, B's feature).
    pub fn swapped(mut self) -> Manifold {
        self.normal = -self.normal;
        for p in &mut self.points[..self.count] {
            p.id = p.id.rotate_left(8);
        }
        self
    }
}
