//! Segments and chains: line pieces of terrain that know their neighbours.
//!
//! A [`Segment`] is the line from `a` to `b` (body frame, metres), optionally grown by a
//! radius. A *chain* is a polyline cut into segments, each one a static body of its own that
//! remembers the vertex before `a` and the vertex after `b` ("ghost" vertices). The narrow
//! phase (`collide::segment`) uses them so that a body sliding along the chain only ever
//! meets normals the surface really has: over a flat or concave joint no normal may lean
//! past the segment's own face, which is what catches a box on the seam between two tiles
//! (the ghost-collision problem; Box2D v3 answers it with chain segments, rapier with
//! polylines). A one-sided segment pushes only towards its left, walking from `a` to `b`:
//! points listed left to right make a floor, a loop listed counter-clockwise holds bodies in.

use super::error::{finite, non_negative, PhysicsError};
use super::math::{cross, Real, Vec2};
use serde::{Deserialize, Serialize};

/// Shortest segment accepted (m): 0.1 mm, the polygons' smallest span.
pub const MIN_LENGTH: Real = super::convex::MIN_SPAN;

/// Most points a chain may have (a scene's body limit bounds it anyway).
pub const MAX_CHAIN_POINTS: usize = 65_536;

/// A line segment in body coordinates, with the chain neighbours it was cut from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// First end (m, body frame).
    pub a: Vec2,
    /// Second end (m, body frame).
    pub b: Vec2,
    /// Thickness on each side of the line (m); 0 for a bare line.
    pub radius: Real,
    /// The chain vertex before `a` (m, body frame), if the segment is part of a chain.
    pub prev: Option<Vec2>,
    /// The chain vertex after `b` (m, body frame), if the segment is part of a chain.
    pub next: Option<Vec2>,
    /// Push only towards the left of a -> b (the chain's open side).
    pub one_sided: bool,
}

impl Segment {
    /// A lone two-sided segment from `a` to `b` (m) grown by `radius` (m, may be 0).
    pub fn new(a: Vec2, b: Vec2, radius: Real) -> Segment {
        Segment {
            a,
            b,
            radius,
            prev: None,
            next: None,
            one_sided: false,
        }
    }

    /// Refuse a segment that cannot be simulated: non-finite points, ends closer than
    /// [`MIN_LENGTH`], a negative radius.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        for (field, v) in [
            ("shape.a", Some(self.a)),
            ("shape.b", Some(self.b)),
            ("shape.prev", self.prev),
            ("shape.next", self.next),
        ] {
            if let Some(v) = v {
                finite(field, v.x)?;
                finite(field, v.y)?;
            }
        }
        non_negative("shape.radius", self.radius)?;
        let length = (self.b - self.a).length();
        if length.is_nan() || length < MIN_LENGTH {
            return Err(PhysicsError::InvalidShape {
                field: "shape.b".into(),
                reason: format!(
                    "= [{}, {}] is {length} m from shape.a = [{}, {}]; a segment must be at \
                     least {MIN_LENGTH} m long",
                    self.b.x, self.b.y, self.a.x, self.a.y
                ),
            });
        }
        Ok(())
    }

    /// Length from `a` to `b` (m).
    pub fn length(&self) -> Real {
        (self.b - self.a).length()
    }

    /// Unit normal on the left of a -> b: the open side of a one-sided segment.
    pub fn left_normal(&self) -> Vec2 {
        let e = (self.b - self.a).normalize();
        Vec2::new(-e.y, e.x)
    }
}

/// Check a chain's points and cut it into segments, each placed at its midpoint: returns
/// (midpoint in world coordinates, segment relative to it) per piece. `points` are world
/// coordinates (m); `closed` joins the last point back to the first (do not repeat it);
/// `one_sided` makes every piece push only to its left. Refuses fewer than 2 points (3 for a
/// loop), non-finite coordinates, and consecutive points closer than [`MIN_LENGTH`], naming
/// `shape.points[i]`.
pub fn chain(
    points: &[Vec2],
    closed: bool,
    one_sided: bool,
) -> Result<Vec<(Vec2, Segment)>, PhysicsError> {
    let least = if closed { 3 } else { 2 };
    if points.len() < least || points.len() > MAX_CHAIN_POINTS {
        return Err(PhysicsError::InvalidShape {
            field: "shape.points".into(),
            reason: format!(
                "has {} points; a {} needs {least} to {MAX_CHAIN_POINTS}",
                points.len(),
                if closed { "loop" } else { "chain" }
            ),
        });
    }
    let n = points.len();
    for (i, p) in points.iter().enumerate() {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return Err(PhysicsError::InvalidShape {
                field: format!("shape.points[{i}]"),
                reason: format!("= [{}, {}] must be finite numbers", p.x, p.y),
            });
        }
    }
    let pieces = if closed { n } else { n - 1 };
    for i in 0..pieces {
        let (p, q) = (points[i], points[(i + 1) % n]);
        if (q - p).length() < MIN_LENGTH {
            let j = (i + 1) % n;
            return Err(PhysicsError::InvalidShape {
                field: format!("shape.points[{j}]"),
                reason: format!(
                    "= [{}, {}] is within {MIN_LENGTH} m of shape.points[{i}]; consecutive \
                     points must be apart{}",
                    q.x,
                    q.y,
                    if closed && j == 0 {
                        " (a loop closes itself: do not repeat the first point)"
                    } else {
                        ""
                    }
                ),
            });
        }
    }
    let at = |i: isize| -> Option<Vec2> {
        if closed {
            Some(points[i.rem_euclid(n as isize) as usize])
        } else if (0..n as isize).contains(&i) {
            Some(points[i as usize])
        } else {
            None
        }
    };
    Ok((0..pieces as isize)
        .map(|i| {
            let (a, b) = (at(i).unwrap_or_default(), at(i + 1).unwrap_or_default());
            let mid = 0.5 * (a + b);
            let local = |v: Option<Vec2>| v.map(|v| v - mid);
            let segment = Segment {
                a: a - mid,
                b: b - mid,
                radius: 0.0,
                prev: local(at(i - 1)),
                next: local(at(i + 2)),
                one_sided,
            };
            (mid, segment)
        })
        .collect())
}

/// Which way a chain turns at a joint, seen from the side a body is on (`side` = +1 for the
/// left of the walk, -1 for the right): positive for a convex corner (a hilltop, where the
/// surface falls away), negative for a concave one (a valley), zero when straight.
/// `e0` is the edge into the joint, `e1` the edge out of it.
#[inline]
pub(crate) fn convexity(e0: Vec2, e1: Vec2, side: Real) -> Real {
    // Walking with the open side on the left, a right turn (cross < 0) is a hilltop.
    -side * cross(e0.normalize(), e1.normalize())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::vec2;

    #[test]
    fn chain_pieces_know_their_neighbours() {
        let pts = [vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(2.0, 1.0)];
        let open = chain(&pts, false, false).unwrap();
        assert_eq!(open.len(), 2);
        let (mid, s) = &open[0];
        assert_eq!(*mid, vec2(0.5, 0.0));
        assert_eq!(s.prev, None);
        assert_eq!(s.next, Some(vec2(1.5, 1.0)));
        let closed = chain(&pts, true, true).unwrap();
        assert_eq!(closed.len(), 3);
        // The closing piece runs from the last point back to the first.
        let (mid, s) = &closed[2];
        assert_eq!(*mid + s.a, vec2(2.0, 1.0));
        assert_eq!(*mid + s.b, vec2(0.0, 0.0));
        assert_eq!(s.next.map(|v| v + *mid), Some(vec2(1.0, 0.0)));
        assert!(s.one_sided);
    }

    #[test]
    fn bad_chains_are_refused_naming_the_point() {
        let e = chain(&[vec2(0.0, 0.0)], false, false).unwrap_err();
        assert!(e.to_string().contains("shape.points has 1 points"), "{e}");
        let e = chain(&[vec2(0.0, 0.0), vec2(1.0, 0.0)], true, false).unwrap_err();
        assert!(e.to_string().contains("needs 3"), "{e}");
        let pts = [vec2(0.0, 0.0), vec2(1.0, Real::NAN)];
        let e = chain(&pts, false, false).unwrap_err();
        assert!(e.to_string().contains("shape.points[1]"), "{e}");
        let pts = [vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 0.0)];
        let e = chain(&pts, false, false).unwrap_err();
        assert!(e.to_string().contains("shape.points[2]"), "{e}");
        let pts = [
            vec2(0.0, 0.0),
            vec2(1.0, 0.0),
            vec2(1.0, 1.0),
            vec2(0.0, 0.0),
        ];
        let e = chain(&pts, true, false).unwrap_err();
        assert!(e.to_string().contains("do not repeat"), "{e}");
    }

    #[test]
    fn convexity_sign_follows_the_side() {
        // Up a slope then flat: seen from above (left of the walk), the joint is a hilltop.
        let (e0, e1) = (vec2(1.0, 1.0), vec2(1.0, 0.0));
        assert!(convexity(e0, e1, 1.0) > 0.0);
        assert!(convexity(e0, e1, -1.0) < 0.0);
        assert_eq!(convexity(vec2(1.0, 0.0), vec2(2.0, 0.0), 1.0), 0.0);
    }
}
