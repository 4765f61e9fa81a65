//! Scalars, vectors and rotations: the one place where the engine picks `f32` or `f64`.
//!
//! Everything in the engine is written against [`Real`] and [`Vec2`]; enabling the `f64`
//! feature switches both to double precision (see `docs/accuracy.md` for why you might).

#[cfg(not(feature = "f64"))]
mod precision {
    /// The engine's scalar type (metres, seconds, radians, kilograms).
    pub type Real = f32;
    /// A 2D vector of [`Real`]: positions in metres, velocities in m/s, forces in newtons.
    pub type Vec2 = glam::Vec2;
    /// pi in [`Real`].
    pub const PI: Real = std::f32::consts::PI;
}

#[cfg(feature = "f64")]
mod precision {
    /// The engine's scalar type (metres, seconds, radians, kilograms).
    pub type Real = f64;
    /// A 2D vector of [`Real`]: positions in metres, velocities in m/s, forces in newtons.
    pub type Vec2 = glam::DVec2;
    /// pi in [`Real`].
    pub const PI: Real = std::f64::consts::PI;
}

pub use precision::{Real, Vec2, PI};

/// Shorthand for building a [`Vec2`].
#[inline]
pub const fn vec2(x: Real, y: Real) -> Vec2 {
    Vec2::new(x, y)
}

/// 2D cross product a x b (the z component of the 3D cross product).
#[inline]
pub fn cross(a: Vec2, b: Vec2) -> Real {
    a.x * b.y - a.y * b.x
}

/// Cross product of a scalar (z-axis vector) with a vector: w x r = (-w r.y, w r.x).
///
/// This is the velocity of a point at offset `r` on a body spinning at `w` rad/s.
#[inline]
pub fn cross_sv(w: Real, r: Vec2) -> Vec2 {
    Vec2::new(-w * r.y, w * r.x)
}

/// A rotation stored as its cosine and sine: the columns of R(theta) = [[c, -s], [s, c]].
/// Laid out as written (`c`, then `s`): the solver loads it with its neighbours.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Rot {
    /// cos(theta)
    pub c: Real,
    /// sin(theta)
    pub s: Real,
}

impl Rot {
    /// The identity rotation.
    pub const IDENTITY: Rot = Rot { c: 1.0, s: 0.0 };

    /// The rotation by `angle` radians, counter-clockwise.
    #[inline]
    pub fn from_angle(angle: Real) -> Rot {
        let (s, c) = angle.sin_cos();
        Rot { c, s }
    }

    /// `[cos, sin]`, as a saved state stores it.
    #[inline]
    pub fn to_cos_sin(self) -> [Real; 2] {
        [self.c, self.s]
    }

    /// The rotation whose cosine and sine are `[c, s]` (not renormalised).
    #[inline]
    pub fn from_cos_sin([c, s]: [Real; 2]) -> Rot {
        Rot { c, s }
    }

    /// The angle in radians, in (-pi, pi].
    #[inline]
    pub fn angle(self) -> Real {
        self.s.atan2(self.c)
    }

    /// R v: a body-frame vector expressed in the world frame.
    #[inline]
    pub fn rotate(self, v: Vec2) -> Vec2 {
        Vec2::new(self.c * v.x - self.s * v.y, self.s * v.x + self.c * v.y)
    }

    /// R^T v: a world-frame vector expressed in the body frame.
    #[inline]
    pub fn inv_rotate(self, v: Vec2) -> Vec2 {
        Vec2::new(self.c * v.x + self.s * v.y, -self.s * v.x + self.c * v.y)
    }

    /// The body's local x axis in world coordinates (first column of R).
    #[inline]
    pub fn x_axis(self) -> Vec2 {
        Vec2::new(self.c, self.s)
    }

    /// The body's local y axis in world coordinates (second column of R).
    #[inline]
    pub fn y_axis(self) -> Vec2 {
        Vec2::new(-self.s, self.c)
    }
}

/// A rigid transform: a rotation followed by a translation (world = R local + p).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Translation in metres.
    pub p: Vec2,
    /// Rotation.
    pub q: Rot,
}

impl Transform {
    /// No move, no turn.
    pub const IDENTITY: Transform = Transform {
        p: Vec2::ZERO,
        q: Rot::IDENTITY,
    };

    /// A local point expressed in the world frame.
    #[inline]
    pub fn apply(self, local: Vec2) -> Vec2 {
        self.q.rotate(local) + self.p
    }

    /// A world point expressed in the local frame.
    #[inline]
    pub fn apply_inv(self, world: Vec2) -> Vec2 {
        self.q.inv_rotate(world - self.p)
    }

    /// `inner` placed in this frame: the transform from `inner`'s frame to this one's
    /// parent (a body's part placed by the body's pose).
    #[inline]
    pub fn then(self, inner: Transform) -> Transform {
        Transform {
            p: self.apply(inner.p),
            q: Rot {
                c: self.q.c * inner.q.c - self.q.s * inner.q.s,
                s: self.q.s * inner.q.c + self.q.c * inner.q.s,
            },
        }
    }
}

/// True when `x` is neither NaN nor infinite.
#[inline]
pub fn is_finite(x: Real) -> bool {
    x.is_finite()
}

/// True when both components of `v` are finite.
#[inline]
pub fn is_finite_vec(v: Vec2) -> bool {
    v.x.is_finite() && v.y.is_finite()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_round_trips_and_matches_matrix() {
        let q = Rot::from_angle(0.7);
        let v = vec2(1.5, -2.0);
        let w = q.rotate(v);
        // R v by hand: [[c,-s],[s,c]] v
        let (s, c) = (0.7 as Real).sin_cos();
        assert!((w.x - (c * 1.5 + s * 2.0)).abs() < 1e-6);
        assert!((w.y - (s * 1.5 - c * 2.0)).abs() < 1e-6);
        let back = q.inv_rotate(w);
        assert!((back - v).length() < 1e-6);
        assert!((q.angle() - 0.7).abs() < 1e-6);
    }

    #[test]
    fn cross_products_follow_right_hand_rule() {
        assert_eq!(cross(vec2(1.0, 0.0), vec2(0.0, 1.0)), 1.0);
        // spinning at +2 rad/s, a point at +x moves towards +y
        assert_eq!(cross_sv(2.0, vec2(1.0, 0.0)), vec2(0.0, 2.0));
    }
}
