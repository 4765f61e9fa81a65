//! Capsule against capsule: the closest points of the two core segments.
//!
//! Two segments have no face normals that separate them end to end, so the polygon clipper's
//! axis test cannot see that gap; this routine measures the segment distance directly and
//! adds a second point only when the capsules lie side by side.

use super::{FeatureId, Manifold, ManifoldPoint};
use crate::physics::math::{cross, Real, Transform, Vec2};

/// |sin| of the angle between the axes below which two capsules count as side by side and
/// get a two-point manifold (about 3 degrees, as a resting capsule on another tilts).
const PARALLEL_SIN: Real = 0.05;

/// A capsule placed in the world: a core segment along its body's x axis, from
/// -`half_length` to `half_length` (m), grown by `radius` (m).
#[derive(Clone, Copy)]
pub(crate) struct Capsule {
    pub half_length: Real,
    pub radius: Real,
    /// The body's transform.
    pub xf: Transform,
}

/// Capsule B's core in A's frame (where A's core is (-ha, 0)..(ha, 0)): its centre, its unit
/// axis, and its ends `p2` = centre - hb axis and `q2` = centre + hb axis (m).
struct CoreB {
    centre: Vec2,
    axis: Vec2,
    p2: Vec2,
    q2: Vec2,
}

/// Where the two cores come closest, in A's frame: the fractions `s` along A's core and `t`
/// along B's, A's point `ca`, the way `d` from it to B's point and its length `dist` (m).
struct Closest {
    s: Real,
    t: Real,
    ca: Vec2,
    d: Vec2,
    dist: Real,
}

/// Contact between capsules `a` and `b`, keeping points whose separation is at most `margin`
/// (m). Normal from A to B.
pub fn collide_capsules(a: Capsule, b: Capsule, margin: Real) -> Manifold {
    let (ha, ra, xf_a) = (a.half_length, a.radius, a.xf);
    let (hb, rb) = (b.half_length, b.radius);
    // Everything in A's frame: A's core is (-ha, 0)..(ha, 0).
    let centre_b = xf_a.apply_inv(b.xf.p);
    let axis_b = xf_a.q.inv_rotate(b.xf.q.x_axis());
    let (p1, q1) = (Vec2::new(-ha, 0.0), Vec2::new(ha, 0.0));
    let (p2, q2) = (centre_b - hb * axis_b, centre_b + hb * axis_b);
    let (s, t) = super::polygon::segment_closest(p1, q1, p2, q2);
    let (ca, cb) = (p1 + s * (q1 - p1), p2 + t * (q2 - p2));
    let d = cb - ca;
    let dist = d.length();
    if dist - ra - rb > margin {
        return Manifold::EMPTY;
    }

    let core_b = CoreB {
        centre: centre_b,
        axis: axis_b,
        p2,
        q2,
    };
    // Side by side: clip B's core to A's extent along A's axis and measure both ends.
    if cross(Vec2::X, axis_b).abs() < PARALLEL_SIN {
        if let Some(m) = side_by_side(&a, &b, &core_b, margin) {
            return m;
        }
    }
    let closest = Closest { s, t, ca, d, dist };
    closest_points(&a, &b, &core_b, closest)
}

/// Capsules side by side (axes within `PARALLEL_SIN` of parallel): B's core clipped to A's
/// extent along A's axis and both ends measured along A's side normal, keeping points whose
/// separation is at most `margin` (m). None when the cores barely overlap along the axis or
/// no end is within the margin: the closest points answer then.
fn side_by_side(a: &Capsule, b: &Capsule, core_b: &CoreB, margin: Real) -> Option<Manifold> {
    let (ha, ra, xf_a) = (a.half_length, a.radius, a.xf);
    let (hb, rb) = (b.half_length, b.radius);
    let (p2, q2) = (core_b.p2, core_b.q2);
    let up = if core_b.centre.y >= 0.0 { 1.0 } else { -1.0 };
    let n = Vec2::new(0.0, up);
    let (lo, hi) = if core_b.axis.x >= 0.0 {
        (p2, q2)
    } else {
        (q2, p2)
    };
    // The point of B's core above A's axis coordinate x.
    let on_b = |x: Real| lo + ((x - lo.x) / (hi.x - lo.x)).clamp(0.0, 1.0) * (hi - lo);
    let x0 = lo.x.max(-ha);
    let x1 = hi.x.min(ha);
    // Two points only where the cores overlap along the axis by more than a sliver.
    if x1 - x0 > 0.01 * (ha + hb) {
        let mut m = Manifold::EMPTY;
        for (k, x) in [x0, x1].into_iter().enumerate() {
            let v = on_b(x);
            let core = n.dot(v);
            let separation = core - ra - rb;
            if separation > margin {
                continue;
            }
            let mid = v + (0.5 * (ra - rb - core)) * n;
            m.points[m.count] = ManifoldPoint {
                point: xf_a.apply(mid),
                separation,
                id: (k as FeatureId) << 8 | k as FeatureId,
            };
            m.count += 1;
        }
        if m.count > 0 {
            m.normal = xf_a.q.rotate(n);
            return Some(m);
        }
    }
    None
}

/// One point on the line between the cores' closest points `c`, named by the end of each
/// core it lies at (2 for neither). Crossing cores (no line between the points) take A's
/// side normal towards B's centre.
fn closest_points(a: &Capsule, b: &Capsule, core_b: &CoreB, c: Closest) -> Manifold {
    let (ha, ra, xf_a) = (a.half_length, a.radius, a.xf);
    let (hb, rb) = (b.half_length, b.radius);
    let n = if c.dist > 1.0e-6 * (ha + hb + ra + rb) {
        c.d / c.dist
    } else if core_b.centre.y >= 0.0 {
        Vec2::Y
    } else {
        -Vec2::Y
    };
    let core = n.dot(c.d);
    let separation = core - ra - rb;
    let mid = c.ca + (ra + 0.5 * separation) * n;
    let end = |x: Real| {
        if x == 0.0 {
            0
        } else if x == 1.0 {
            1
        } else {
            2
        }
    };
    let mut m = Manifold::EMPTY;
    m.normal = xf_a.q.rotate(n);
    m.points[0] = ManifoldPoint {
        point: xf_a.apply(mid),
        separation,
        id: 0x80 | (end(c.s) as FeatureId) << 8 | end(c.t) as FeatureId,
    };
    m.count = 1;
    m
}
