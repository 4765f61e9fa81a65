//! Collision shapes, their bounding boxes and their mass properties.
//!
//! Shapes are described in the body's frame, centred on the centre of mass. Each kind is an
//! enum variant plus narrow-phase routines for its pairs (`collide`); the solver only ever
//! sees contact manifolds, so it does not know which shapes touched.

use super::convex::Polygon;
use super::error::{positive, PhysicsError};
use super::math::{Real, Transform, Vec2, PI};
use super::segment::Segment;
use serde::{Deserialize, Serialize};

/// A collision shape in body coordinates (metres), centred on the centre of mass.
///
/// The serde form is externally tagged (`{"circle": {"radius": 0.5}}`), which both
/// self-describing formats and postcard read back; a polygon travels as its vertex list and is
/// re-checked on the way in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Shape {
    /// A rectangle of the given half extents (half width, half height), in metres. A polygon
    /// in all but name; it keeps its own variant for the closed-form box-box test.
    Rect {
        /// Half width and half height, metres.
        half_extents: Vec2,
    },
    /// A disc of the given radius (m), centred on the centre of mass.
    Circle {
        /// Radius, metres.
        radius: Real,
    },
    /// A stadium: the segment from (-half_length, 0) to (half_length, 0) in body coordinates,
    /// grown by `radius` (m). Its length end to end is 2 (half_length + radius).
    Capsule {
        /// Half the length of the core segment, metres.
        half_length: Real,
        /// Radius of the rounded ends (and half the thickness), metres.
        radius: Real,
    },
    /// A convex polygon of 3 to 8 vertices, centred on its centroid (see [`Polygon::new`]).
    /// Boxed: a polygon is 136 bytes, and keeping it out of line keeps `Shape` (and every body)
    /// small in worlds of boxes and circles.
    Polygon(Box<Polygon>),
    /// A line segment (a lone one, or one piece of a chain with its neighbours), for static
    /// and kinematic bodies: terrain, platforms, paddles (see [`Segment`]). Boxed like the
    /// polygon. Appended last, so the other kinds keep their serialized indices.
    Segment(Box<Segment>),
}

impl Shape {
    /// A rectangle `width` x `height` metres.
    pub fn rect(width: Real, height: Real) -> Shape {
        Shape::Rect {
            half_extents: Vec2::new(0.5 * width, 0.5 * height),
        }
    }

    /// A disc of `radius` metres.
    pub fn circle(radius: Real) -> Shape {
        Shape::Circle { radius }
    }

    /// A capsule lying along the body's x axis: `length` metres end to end (rounded ends
    /// included), `radius` metres thick on each side of the axis. `length >= 2 radius`.
    pub fn capsule(length: Real, radius: Real) -> Shape {
        Shape::Capsule {
            half_length: 0.5 * length - radius,
            radius,
        }
    }

    /// A capsule as [`Shape::capsule`] makes it, checked against the values as given:
    /// `radius` and `length` finite and > 0, and `length` more than twice `radius` (a capsule
    /// needs a straight part). The refusal names the field and quotes the value; scene files
    /// and spawns both build their capsules here.
    pub fn try_capsule(length: Real, radius: Real) -> Result<Shape, PhysicsError> {
        positive("shape.radius", radius)?;
        positive("shape.length", length)?;
        if length <= 2.0 * radius {
            return Err(PhysicsError::InvalidShape {
                field: "shape.length".into(),
                reason: format!(
                    "= {length} must be more than twice shape.radius = {radius} (the length is \
                     end to end, rounded ends included; use a circle for a capsule with no \
                     straight part)"
                ),
            });
        }
        let shape = Shape::capsule(length, radius);
        shape.validate()?;
        Ok(shape)
    }

    /// Refuse shapes that cannot be simulated (non-finite or non-positive sizes, a capsule
    /// shorter than its own ends).
    pub fn validate(&self) -> Result<(), PhysicsError> {
        match *self {
            Shape::Rect { half_extents } => {
                positive("shape.width", 2.0 * half_extents.x)?;
                positive("shape.height", 2.0 * half_extents.y)?;
            }
            Shape::Circle { radius } => {
                positive("shape.radius", radius)?;
            }
            Shape::Capsule {
                half_length,
                radius,
            } => {
                positive("shape.radius", radius)?;
                let length = 2.0 * (half_length + radius);
                positive("shape.length", length)?;
                if half_length <= 0.0 {
                    return Err(PhysicsError::InvalidShape {
                        field: "shape.length".into(),
                        reason: format!(
                            "= {length} must be more than twice shape.radius = {radius} \
                             (use a circle for a capsule with no straight part)"
                        ),
                    });
                }
            }
            // A Polygon can only be built through its checks.
            Shape::Polygon(_) => {}
            Shape::Segment(ref s) => s.validate()?,
        }
        Ok(())
    }

    /// Area in square metres.
    pub fn area(&self) -> Real {
        match *self {
            Shape::Rect { half_extents: h } => 4.0 * h.x * h.y,
            Shape::Circle { radius: r } => PI * r * r,
            // A 2L x 2r rectangle plus two half discs.
            Shape::Capsule {
                half_length: l,
                radius: r,
            } => 4.0 * l * r + PI * r * r,
            Shape::Polygon(ref p) => p.area(),
            // A bare line has none; a thick one is a stadium.
            Shape::Segment(ref s) => 2.0 * s.length() * s.radius + PI * s.radius * s.radius,
        }
    }

    /// Moment of inertia about the centre of mass for a body of `mass` kg (kg m^2).
    ///
    /// Rectangle: I = m (w^2 + h^2) / 12 (appendix, step 1). Disc: I = m r^2 / 2. Capsule:
    /// the rectangle's share plus the two half discs moved out by the parallel-axis theorem.
    /// Polygon: m J / A with J the polar second moment of area of its triangle fan.
    pub fn inertia(&self, mass: Real) -> Real {
        match *self {
            Shape::Rect { half_extents: h } => {
                let (w, hh) = (2.0 * h.x, 2.0 * h.y);
                mass * (w * w + hh * hh) / 12.0
            }
            Shape::Circle { radius: r } => 0.5 * mass * r * r,
            Shape::Capsule {
                half_length: l,
                radius: r,
            } => {
                let rect_area = 4.0 * l * r;
                let disc_area = PI * r * r;
                let density = mass / (rect_area + disc_area);
                let (m_rect, m_disc) = (density * rect_area, density * disc_area);
                // Rectangle 2L x 2r about its centre.
                let i_rect = m_rect * (4.0 * l * l + 4.0 * r * r) / 12.0;
                // Each half disc: m r^2/2 about the flat edge's centre; its centroid sits
                // 4r/(3 pi) out. Moved to the capsule centre (L + 4r/(3 pi) away), the pair adds
                // m_disc (r^2/2 + L^2 + 8 L r / (3 pi)).
                let i_discs = m_disc * (0.5 * r * r + l * l + 8.0 * l * r / (3.0 * PI));
                i_rect + i_discs
            }
            Shape::Polygon(ref p) => mass * p.second_moment() / p.area(),
            // Static and kinematic only (their mass is infinite): a thin rod about its middle,
            // m L^2 / 12, should anyone ask.
            Shape::Segment(ref s) => mass * s.length() * s.length() / 12.0,
        }
    }

    /// How far the shape's surface is grown out from its core (m): the radius of a disc, a
    /// capsule or a thick segment, 0 for a sharp polygon. A contact point on such a surface
    /// stays where the core is nearest the other body, however the body turns.
    pub fn rounding(&self) -> Real {
        match *self {
            Shape::Rect { .. } | Shape::Polygon(_) => 0.0,
            Shape::Circle { radius } | Shape::Capsule { radius, .. } => radius,
            Shape::Segment(ref s) => s.radius,
        }
    }

    /// The shortest distance from the centre of mass to the surface (m): half a rectangle's
    /// smaller side, a disc's or a capsule's radius, a polygon's nearest face. A body that
    /// moves more than a fraction of it in a step is fast (`world/continuous.rs`).
    pub fn min_extent(&self) -> Real {
        match *self {
            Shape::Rect { half_extents } => half_extents.x.min(half_extents.y),
            Shape::Circle { radius } | Shape::Capsule { radius, .. } => radius,
            Shape::Polygon(ref p) => p
                .normals()
                .iter()
                .zip(p.vertices())
                .map(|(n, v)| n.dot(*v))
                .fold(Real::INFINITY, Real::min),
            Shape::Segment(ref s) => s.radius,
        }
    }

    /// The radius of the smallest circle about the centre of mass that holds the shape (m).
    pub fn bounding_radius(&self) -> Real {
        match *self {
            Shape::Rect { half_extents } => half_extents.length(),
            Shape::Circle { radius } => radius,
            Shape::Capsule {
                half_length,
                radius,
            } => half_length + radius,
            Shape::Polygon(ref p) => p.radius(),
            Shape::Segment(ref s) => s.a.length().max(s.b.length()) + s.radius,
        }
    }

    /// The world-space bounding box of the shape placed at `xf`.
    pub fn aabb(&self, xf: Transform) -> Aabb {
        let e = match *self {
            Shape::Rect { half_extents: h } => {
                // |R| h: the extent of a rotated box along each world axis.
                let ex = xf.q.c.abs() * h.x + xf.q.s.abs() * h.y;
                let ey = xf.q.s.abs() * h.x + xf.q.c.abs() * h.y;
                Vec2::new(ex, ey)
            }
            Shape::Circle { radius } => Vec2::splat(radius),
            Shape::Capsule {
                half_length,
                radius,
            } => (xf.q.x_axis() * half_length).abs() + Vec2::splat(radius),
            Shape::Polygon(ref p) => {
                let (mut lo, mut hi) = (Vec2::splat(Real::INFINITY), Vec2::splat(-Real::INFINITY));
                for &v in p.vertices() {
                    let w = xf.q.rotate(v);
                    lo = lo.min(w);
                    hi = hi.max(w);
                }
                return Aabb {
                    min: xf.p + lo,
                    max: xf.p + hi,
                };
            }
            Shape::Segment(ref s) => {
                let (a, b) = (xf.q.rotate(s.a), xf.q.rotate(s.b));
                let r = Vec2::splat(s.radius);
                return Aabb {
                    min: xf.p + a.min(b) - r,
                    max: xf.p + a.max(b) + r,
                };
            }
        };
        Aabb {
            min: xf.p - e,
            max: xf.p + e,
        }
    }

    /// The kind's name as scenes and messages spell it: `rect`, `circle`, `capsule`, `polygon`,
    /// `segment`.
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Rect { .. } => "rect",
            Shape::Circle { .. } => "circle",
            Shape::Capsule { .. } => "capsule",
            Shape::Polygon(_) => "polygon",
            Shape::Segment(_) => "segment",
        }
    }
}

impl From<Polygon> for Shape {
    /// The polygon as a shape (boxed, see [`Shape::Polygon`]).
    fn from(p: Polygon) -> Shape {
        Shape::Polygon(Box::new(p))
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

    /// The box covering this one and this one moved by `shift` (m).
    #[inline]
    pub(crate) fn swept(self, shift: Vec2) -> Aabb {
        Aabb {
            min: self.min.min(self.min + shift),
            max: self.max.max(self.max + shift),
        }
    }

    /// True when `other` lies wholly inside this box.
    #[inline]
    pub fn contains(&self, other: &Aabb) -> bool {
        self.min.x <= other.min.x
            && self.min.y <= other.min.y
            && other.max.x <= self.max.x
            && other.max.y <= self.max.y
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
    fn circle_and_capsule_mass_properties_match_closed_form() {
        let c = Shape::circle(0.5);
        assert!((c.area() - PI * 0.25).abs() < 1e-6);
        assert!((c.inertia(2.0) - 0.25).abs() < 1e-6);
        // A capsule with a vanishing straight part is a disc.
        let thin = Shape::Capsule {
            half_length: 1e-7,
            radius: 0.5,
        };
        assert!((thin.inertia(2.0) - 0.25).abs() < 1e-5);
        // Capsule 3 m long, r = 0.5: rectangle 2 x 1 plus a disc of r 0.5.
        let cap = Shape::capsule(3.0, 0.5);
        let area = 2.0 + PI * 0.25;
        assert!((cap.area() - area).abs() < 1e-5);
        // Integrate I / rho numerically over the stadium on a fine grid as the reference.
        let (n, mut j, mut a) = (1200, 0.0f64, 0.0f64);
        let (hx, hy) = (1.5f64, 0.5f64);
        for ix in 0..n {
            for iy in 0..n {
                let x = -hx + (ix as f64 + 0.5) * 2.0 * hx / n as f64;
                let y = -hy + (iy as f64 + 0.5) * 2.0 * hy / n as f64;
                let dx = (x.abs() - 1.0).max(0.0);
                if dx * dx + y * y <= 0.25 {
                    let da = (2.0 * hx / n as f64) * (2.0 * hy / n as f64);
                    a += da;
                    j += (x * x + y * y) * da;
                }
            }
        }
        let mass = 3.0;
        let expected = mass as f64 * j / a;
        let got = cap.inertia(mass) as f64;
        assert!(
            (got - expected).abs() < 2e-3 * expected,
            "{got} vs {expected}"
        );
        assert!((a - area as f64).abs() < 1e-3);
    }

    #[test]
    fn capsule_and_polygon_aabbs_are_tight() {
        let cap = Shape::capsule(3.0, 0.5);
        let xf = Transform {
            p: vec2(0.0, 0.0),
            q: Rot::from_angle(PI / 2.0),
        };
        let b = cap.aabb(xf);
        assert!(
            (b.max.y - 1.5).abs() < 1e-5 && (b.max.x - 0.5).abs() < 1e-5,
            "{b:?}"
        );
        let (p, _) = Polygon::new(&[vec2(0.0, 0.0), vec2(2.0, 0.0), vec2(0.0, 1.0)]).unwrap();
        let b = Shape::from(p).aabb(Transform {
            p: vec2(10.0, 0.0),
            q: Rot::IDENTITY,
        });
        // Centroid (2/3, 1/3) sits at x = 10.
        assert!((b.min.x - (10.0 - 2.0 / 3.0)).abs() < 1e-5 && (b.max.y - 2.0 / 3.0).abs() < 1e-5);
    }

    #[test]
    fn bad_sizes_are_refused_with_the_field_name() {
        let e = Shape::circle(-1.0).validate().unwrap_err();
        assert!(e.to_string().contains("shape.radius"), "{e}");
        let e = Shape::capsule(0.8, 0.5).validate().unwrap_err();
        assert!(
            e.to_string().contains("shape.length") && e.to_string().contains("0.8"),
            "{e}"
        );
        let e = Shape::rect(0.0, 1.0).validate().unwrap_err();
        assert!(e.to_string().contains("shape.width"), "{e}");
        let e = Shape::rect(1.0, Real::NAN).validate().unwrap_err();
        assert!(e.to_string().contains("shape.height"), "{e}");
    }
}
