//! Collision shapes, their bounding boxes and their mass properties.
//!
//! Shapes are described in the body's frame, centred on the centre of mass. New kinds
//! (circles, convex polygons) are new enum variants plus a narrow-phase routine per pair;
//! the solver only ever sees contact manifolds, so it does not change.

use super::error::{positive, PhysicsError};
use super::math::{Real, Transform, Vec2};
use serde::{Deserialize, Serialize};

/// A collision shape in body coordinates (metres), centred on the centre of mass.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Shape {
    /// A rectangle of the given half extents (half width, half height), in metres.
    Rect {
        /// Half width and half height, metres.
        half_extents: Vec2,
    },
}

impl Shape {
    /// A rectangle `width` x `height` metres.
    pub fn rect(width: Real, height: Real) -> Shape {
        Shape::Rect {
            half_extents: Vec2::new(0.5 * width, 0.5 * height),
        }
    }

    /// Refuse shapes that cannot be simulated (non-finite or non-positive sizes).
    pub fn validate(&self) -> Result<(), PhysicsError> {
        match *self {
            Shape::Rect { half_extents } => {
                positive("shape.width", 2.0 * half_extents.x)?;
                positive("shape.height", 2.0 * half_extents.y)?;
            }
        }
        Ok(())
    }

    /// Area in square metres.
    pub fn area(&self) -> Real {
        match *self {
            Shape::Rect { half_extents: h } => 4.0 * h.x * h.y,
        }
    }

    /// Moment of inertia about the centre of mass for a body of `mass` kg (kg m^2).
    ///
    /// Rectangle: I = m (w^2 + h^2) / 12 (appendix, step 1).
    pub fn inertia(&self, mass: Real) -> Real {
        match *self {
            Shape::Rect { half_extents: h } => {
                let (w, hh) = (2.0 * h.x, 2.0 * h.y);
                mass * (w * w + hh * hh) / 12.0
            }
        }
    }

    /// The radius of the smallest circle about the centre of mass that holds the shape (m).
    pub fn bounding_radius(&self) -> Real {
        match *self {
            Shape::Rect { half_extents } => half_extents.length(),
        }
    }

    /// The world-space bounding box of the shape placed at `xf`.
    pub fn aabb(&self, xf: Transform) -> Aabb {
        match *self {
            Shape::Rect { half_extents: h } => {
                // |R| h: the extent of a rotated box along each world axis.
                let ex = xf.q.c.abs() * h.x + xf.q.s.abs() * h.y;
                let ey = xf.q.s.abs() * h.x + xf.q.c.abs() * h.y;
                let e = Vec2::new(ex, ey);
                Aabb {
                    min: xf.p - e,
                    max: xf.p + e,
                }
            }
        }
    }
}

/// An axis-aligned bounding box in world coordinates (metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower-left corner.
    pub min: Vec2,
    /// Upper-right corner.
    pub max: Vec2,
}

impl Aabb {
    /// The box grown by `margin` metres on every side.
    #[inline]
    pub fn inflated(self, margin: Real) -> Aabb {
        let m = Vec2::splat(margin);
        Aabb {
            min: self.min - m,
            max: self.max + m,
        }
    }

    /// True when the two boxes overlap or touch.
    #[inline]
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.x <= other.max.x
            && other.min.x <= self.max.x
            && self.min.y <= other.max.y
            && other.min.y <= self.max.y
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::{vec2, Rot};

    #[test]
    fn rect_inertia_is_m_w2_plus_h2_over_12() {
        let s = Shape::rect(2.0, 1.0);
        assert_eq!(s.area(), 2.0);
        assert!((s.inertia(3.0) - 3.0 * 5.0 / 12.0).abs() < 1e-6);
    }

    #[test]
    fn rotated_rect_aabb_is_tight() {
        let s = Shape::rect(2.0, 2.0);
        let xf = Transform {
            p: vec2(1.0, 0.0),
            q: Rot::from_angle(std::f32::consts::FRAC_PI_4 as Real),
        };
        let b = s.aabb(xf);
        let r = (2.0 as Real).sqrt();
        assert!((b.max.x - (1.0 + r)).abs() < 1e-5 && (b.min.y + r).abs() < 1e-5);
    }

    #[test]
    fn bad_sizes_are_refused_with_the_field_name() {
        let e = Shape::rect(0.0, 1.0).validate().unwrap_err();
        assert!(e.to_string().contains("shape.width"), "{e}");
        let e = Shape::rect(1.0, Real::NAN).validate().unwrap_err();
        assert!(e.to_string().contains("shape.height"), "{e}");
    }
}
