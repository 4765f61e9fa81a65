//! Narrow phase: exact contact manifolds for pairs of shapes.
//!
//! One routine per pair of shape kinds; [`collide`] dispatches on the pair. Every routine
//! reports up to two points with a shared normal pointing from body A to body B, a signed
//! separation per point (negative = overlap) and a feature id so the solver can match a point
//! with the same point last step (warm starting).

mod polygon;

pub use polygon::{collide_polygons, collide_rects, Polygon};

use super::math::{Real, Transform, Vec2};
use super::shape::Shape;

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
pub fn collide(a: &Shape, xf_a: Transform, b: &Shape, xf_b: Transform, margin: Real) -> Manifold {
    match (a, b) {
        (Shape::Rect { half_extents: ha }, Shape::Rect { half_extents: hb }) => {
            collide_rects(*ha, xf_a, *hb, xf_b, margin)
        }
    }
}
