//! Circles against circles and against (rounded) polygons: always one contact point.
//!
//! A circle touches anything convex at one point, so these routines skip clipping: they find
//! the closest point of the other shape's core to the circle's centre and put the normal
//! along the line between them.

use super::{FeatureId, Manifold, ManifoldPoint};
use crate::physics::convex::Polygon;
use crate::physics::math::{Real, Rot, Transform, Vec2};

/// Contact between a circle of radius `ra` centred at `pa` and one of radius `rb` at `pb`
/// (world frame, m); the normal points from A's centre to B's. Concentric circles push apart
/// along +y. A circle has no orientation, so only the centres matter.
pub fn collide_circles(ra: Real, pa: Vec2, rb: Real, pb: Vec2, margin: Real) -> Manifold {
    let d = pb - pa;
    let dist = d.length();
    let separation = dist - ra - rb;
    if separation > margin {
        return Manifold::EMPTY;
    }
    let n = if dist > Real::EPSILON * (ra + rb) {
        d / dist
    } else {
        Vec2::Y
    };
    let centre_a = Transform {
        p: pa,
        q: Rot::IDENTITY,
    };
    one_point(centre_a, n, n * (ra + 0.5 * separation), separation, 0)
}

/// Contact between polygon `a` grown by `ra` (a rectangle, polygon or capsule core) at `xf_a`
/// and a circle of radius `rb` at `xf_b`. The normal points from A to the circle.
///
/// The circle's centre is compared with every edge of the core; the edge it lies farthest out
/// of is the one its closest point is on, unless the centre is past one of that edge's ends,
/// where the closest point is the end vertex.
pub fn collide_polygon_circle(
    a: &Polygon,
    ra: Real,
    xf_a: Transform,
    rb: Real,
    xf_b: Transform,
    margin: Real,
) -> Manifold {
    let c = xf_a.apply_inv(xf_b.p);
    let reach = ra + rb + margin;
    let mut edge = 0;
    let mut best = Real::NEG_INFINITY;
    for i in 0..a.count {
        let s = a.normals[i].dot(c - a.vertices[i]);
        if s > reach {
            return Manifold::EMPTY;
        }
        if s > best {
            best = s;
            edge = i;
        }
    }
    let v1 = a.vertices[edge];
    let v2 = a.vertices[(edge + 1) % a.count];
    // Inside the core (best <= 0; a segment has no inside): the face of least penetration;
    // outside: the closest of the face interior and its two ends (Voronoi regions of the edge).
    let (closest, n, id) = if best <= 0.0 && a.count >= 3 {
        (c - best * a.normals[edge], a.normals[edge], edge)
    } else if (c - v1).dot(v2 - v1) <= 0.0 {
        (v1, dir_or(c - v1, a.normals[edge]), 8 + edge)
    } else if (c - v2).dot(v1 - v2) <= 0.0 {
        let j = (edge + 1) % a.count;
        (v2, dir_or(c - v2, a.normals[edge]), 8 + j)
    } else {
        (c - best * a.normals[edge], a.normals[edge], edge)
    };
    let dist = n.dot(c - closest);
    let separation = dist - ra - rb;
    if separation > margin {
        return Manifold::EMPTY;
    }
    let mid = closest + (ra + 0.5 * separation) * n;
    one_point(xf_a, n, mid, separation, (id as FeatureId) << 8)
}

/// `v` normalised, or `fallback` when `v` is too short to have a direction.
fn dir_or(v: Vec2, fallback: Vec2) -> Vec2 {
    let len = v.length();
    if len > Real::EPSILON {
        v / len
    } else {
        fallback
    }
}

/// A one-point manifold from A-frame quantities.
fn one_point(xf_a: Transform, n: Vec2, point: Vec2, separation: Real, id: FeatureId) -> Manifold {
    let mut m = Manifold::EMPTY;
    m.normal = xf_a.q.rotate(n);
    m.points[0] = ManifoldPoint {
        point: xf_a.apply(point),
        separation,
        id,
    };
    m.count = 1;
    m
}
