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

/// Contact between capsule A (core half length `ha`, radius `ra`) at `xf_a` and capsule B
/// (`hb`, `rb`) at `xf_b`; each core runs along its body's x axis. Normal from A to B.
pub fn collide_capsules(
    ha: Real,
    ra: Real,
    xf_a: Transform,
    hb: Real,
    rb: Real,
    xf_b: Transform,
    margin: Real,
) -> Manifold {
    // Everything in A's frame: A's core is (-ha, 0)..(ha, 0).
    let centre_b = xf_a.apply_inv(xf_b.p);
    let axis_b = xf_a.q.inv_rotate(xf_b.q.x_axis());
    let (p1, q1) = (Vec2::new(-ha, 0.0), Vec2::new(ha, 0.0));
    let (p2, q2) = (centre_b - hb * axis_b, centre_b + hb * axis_b);
    let (s, t) = super::polygon::segment_closest(p1, q1, p2, q2);
    let (ca, cb) = (p1 + s * (q1 - p1), p2 + t * (q2 - p2));
    let d = cb - ca;
    let dist = d.length();
    if dist - ra - rb > margin {
        return Manifold::EMPTY;
    }

    let mut m = Manifold::EMPTY;
    // Side by side: clip B's core to A's extent along A's axis and measure both ends.
    if cross(Vec2::X, axis_b).abs() < PARALLEL_SIN {
        let up = if centre_b.y >= 0.0 { 1.0 } else { -1.0 };
        let n = Vec2::new(0.0, up);
        let (lo, hi) = if axis_b.x >= 0.0 { (p2, q2) } else { (q2, p2) };
        // The point of B's core above A's axis coordinate x.
        let on_b = |x: Real| lo + ((x - lo.x) / (hi.x - lo.x)).clamp(0.0, 1.0) * (hi - lo);
        let x0 = lo.x.max(-ha);
        let x1 = hi.x.min(ha);
        if x1 - x0 > 0.01 * (ha + hb) {
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
                return m;
            }
        }
    }

    // One point on the line between the closest points of the cores (crossing cores: A's
    // side normal towards B).
    let n = if dist > 1.0e-6 * (ha + hb + ra + rb) {
        d / dist
    } else if centre_b.y >= 0.0 {
        Vec2::Y
    } else {
        -Vec2::Y
    };
    let core = n.dot(d);
    let separation = core - ra - rb;
    let mid = ca + (ra + 0.5 * separation) * n;
    let end = |x: Real| {
        if x == 0.0 {
            0
        } else if x == 1.0 {
            1
        } else {
            2
        }
    };
    m.normal = xf_a.q.rotate(n);
    m.points[0] = ManifoldPoint {
        point: xf_a.apply(mid),
        separation,
        id: 0x80 | (end(s) as FeatureId) << 8 | end(t) as FeatureId,
    };
    m.count = 1;
    m
}
