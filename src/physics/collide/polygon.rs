//! Convex polygon against convex polygon by the separating axis test, a reference face, and
//! an incident edge clipped to the reference face's side planes.
//!
//! This is the appendix's box-box routine (its f_A, f_B face separations, reference and
//! incident edges, two clips and projection) written for any convex polygon. Each polygon may
//! carry a radius: a capsule is its core segment (a two-vertex polygon) grown by its radius,
//! so capsule-capsule and capsule-polygon run through here too. Rounded cores that do not
//! touch may meet corner to corner, where no face normal is right; that case is detected from
//! the closest points of the two candidate edges and answered with one point on the line
//! between them.

use super::{FeatureId, Manifold, ManifoldPoint};
use crate::physics::convex::Polygon;
use crate::physics::math::{Real, Rot, Transform, Vec2};

/// Core separation (m) above which two rounded shapes are treated as apart at their cores,
/// so the corner-to-corner test runs. Below it the cores touch or overlap and the face
/// normal is the better answer.
const CORE_GAP: Real = 5.0e-4;

/// The edge of `p1` along which `p2` is farthest out, and that separation (m).
///
/// For each edge normal n_i of p1 the separation is min_j n_i . (v2_j - v1_i): the appendix's
/// f_A components, generalised. The largest is the best separating-axis candidate.
fn max_separation(p1: &Polygon, p2: &Polygon) -> (usize, Real) {
    let mut best_edge = 0;
    let mut best = Real::NEG_INFINITY;
    for i in 0..p1.count {
        let n = p1.normals[i];
        let v = p1.vertices[i];
        let mut si = Real::INFINITY;
        for j in 0..p2.count {
            si = si.min(n.dot(p2.vertices[j] - v));
        }
        if si > best {
            best = si;
            best_edge = i;
        }
    }
    (best_edge, best)
}

/// Keep the part of segment `seg` with `dot(n, v) <= offset`, each end staying in its slot.
/// Returns None when nothing of the segment is left (appendix eqs. 29-44).
fn clip_segment(seg: [Vec2; 2], n: Vec2, offset: Real) -> Option<[Vec2; 2]> {
    let d0 = n.dot(seg[0]) - offset;
    let d1 = n.dot(seg[1]) - offset;
    match (d0 <= 0.0, d1 <= 0.0) {
        (true, true) => Some(seg),
        (false, false) => None,
        (in0, _) => {
            let t = d0 / (d0 - d1);
            let cut = seg[0] + t * (seg[1] - seg[0]);
            Some(if in0 { [seg[0], cut] } else { [cut, seg[1]] })
        }
    }
}

/// Contact manifold between convex polygons `a` at `xf_a` and `b` at `xf_b`, each grown by a
/// radius (`ra`, `rb`, metres; 0 for a sharp polygon), keeping points whose separation is at
/// most `margin` metres. The normal points from A to B.
pub fn collide_polygons(
    a: &Polygon,
    ra: Real,
    xf_a: Transform,
    b: &Polygon,
    rb: Real,
    xf_b: Transform,
    margin: Real,
) -> Manifold {
    let rel = relative(xf_a, xf_b);
    let pb = b.transformed(rel);
    let reach = margin + ra + rb;

    let (edge_a, sep_a) = max_separation(a, &pb);
    if sep_a > reach {
        return Manifold::EMPTY;
    }
    let (edge_b, sep_b) = max_separation(&pb, a);
    if sep_b > reach {
        return Manifold::EMPTY;
    }
    let radii = Radii { a: ra, b: rb };
    clip_to_reference(
        a,
        &pb,
        (edge_a, sep_a),
        (edge_b, sep_b),
        radii,
        xf_a,
        margin,
    )
}

/// The vertex after `i` on a polygon of `count` vertices (a compare, not a division).
#[inline]
fn next(i: usize, count: usize) -> usize {
    if i + 1 == count {
        0
    } else {
        i + 1
    }
}

/// The radii the two cores are grown by (m).
#[derive(Clone, Copy)]
struct Radii {
    a: Real,
    b: Real,
}

/// The incident edge of `polygon` against reference normal `n`: the edge whose normal is most
/// anti-parallel to `n` (the first such, in vertex order).
pub(super) fn incident_edge(polygon: &Polygon, n: Vec2) -> usize {
    let mut edge = 0;
    let mut min_dot = Real::INFINITY;
    for (i, normal) in polygon.normals[..polygon.count].iter().enumerate() {
        let d = n.dot(*normal);
        if d < min_dot {
            min_dot = d;
            edge = i;
        }
    }
    edge
}

/// Closest points between segments p1-q1 and p2-q2: (s, t) along each, both clamped to [0, 1]
/// (the standard clamp-and-recompute solution of the 2x2 normal equations).
pub(super) fn segment_closest(p1: Vec2, q1: Vec2, p2: Vec2, q2: Vec2) -> (Real, Real) {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let c = d1.dot(r);
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    let mut s = if denom > 1.0e-12 * a * e {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// B's transform relative to A. Working in A's frame subtracts the two positions once, so
/// worlds far from the origin lose as little precision as f32 allows.
#[inline]
fn relative(xf_a: Transform, xf_b: Transform) -> Transform {
    Transform {
        p: xf_a.q.inv_rotate(xf_b.p - xf_a.p),
        q: Rot {
            c: xf_a.q.c * xf_b.q.c + xf_a.q.s * xf_b.q.s,
            s: xf_a.q.c * xf_b.q.s - xf_a.q.s * xf_b.q.c,
        },
    }
}

/// Rectangle against rectangle: the same manifold as `collide_polygons`, with the separating
/// axis test in closed form (the appendix's f_A = |d_A| - h_A - |C| h_B and
/// f_B = |d_B| - h_B - |C^T| h_A) instead of every vertex against every edge.
pub fn collide_rects(
    ha: Vec2,
    xf_a: Transform,
    hb: Vec2,
    xf_b: Transform,
    margin: Real,
) -> Manifold {
    let rel = relative(xf_a, xf_b);
    let d = rel.p;
    let (c, s) = (rel.q.c.abs(), rel.q.s.abs());
    // A's faces: x axis (edge 1 right / 3 left), y axis (edge 2 top / 0 bottom).
    let fax = d.x.abs() - ha.x - (c * hb.x + s * hb.y);
    let fay = d.y.abs() - ha.y - (s * hb.x + c * hb.y);
    let (edge_a, sep_a) = if fay > fax {
        (if d.y > 0.0 { 2 } else { 0 }, fay)
    } else {
        (if d.x > 0.0 { 1 } else { 3 }, fax)
    };
    if sep_a > margin {
        return Manifold::EMPTY;
    }
    // B's faces, in B's frame: A lies at -d_B from B.
    let db = rel.q.inv_rotate(d);
    let fbx = db.x.abs() - hb.x - (c * ha.x + s * ha.y);
    let fby = db.y.abs() - hb.y - (s * ha.x + c * ha.y);
    let (edge_b, sep_b) = if fby > fbx {
        (if db.y < 0.0 { 2 } else { 0 }, fby)
    } else {
        (if db.x < 0.0 { 1 } else { 3 }, fbx)
    };
    if sep_b > margin {
        return Manifold::EMPTY;
    }
    let pa = Polygon::rect(ha);
    let pb = Polygon::rect_at(hb, rel);
    let sharp = Radii { a: 0.0, b: 0.0 };
    clip_to_reference(
        &pa,
        &pb,
        (edge_a, sep_a),
        (edge_b, sep_b),
        sharp,
        xf_a,
        margin,
    )
}

/// Pick the reference face from the best face of each polygon (both in A's frame), clip the
/// other polygon's incident edge to it, and build the manifold in world coordinates.
fn clip_to_reference(
    pa: &Polygon,
    pb: &Polygon,
    (edge_a, sep_a): (usize, Real),
    (edge_b, sep_b): (usize, Real),
    radii: Radii,
    xf_a: Transform,
    margin: Real,
) -> Manifold {
    // Prefer A's face unless B's is clearly better, so the reference face does not flicker
    // between near-equal candidates from one step to the next (the appendix's eq. 79 idea).
    const RELATIVE_TOL: Real = 0.98;
    const ABSOLUTE_TOL: Real = 0.0005;
    // (Written as sep_a + tol so that it favours A for gaps as well as overlaps: the
    // appendix's 0.98 sep_a + tol only does for overlaps, and for a speculative gap it would
    // prefer B's face even when A's separates more.)
    let flip = sep_b > sep_a + (1.0 - RELATIVE_TOL) * sep_a.abs() + ABSOLUTE_TOL;
    let (reference, incident, ref_edge) = if flip {
        (pb, pa, edge_b)
    } else {
        (pa, pb, edge_a)
    };
    let (r_ref, r_inc) = if flip {
        (radii.b, radii.a)
    } else {
        (radii.a, radii.b)
    };

    // Incident edge: the edge of the other polygon whose normal is most anti-parallel to the
    // reference normal.
    let n = reference.normals[ref_edge];
    let i1 = incident_edge(incident, n);
    let i2 = next(i1, incident.count);
    let seg = [incident.vertices[i1], incident.vertices[i2]];
    let r1 = reference.vertices[ref_edge];
    let r2 = reference.vertices[next(ref_edge, reference.count)];

    // Cores that do not touch meet where their two edges are closest, along the line between
    // those points: one point, named by the vertex of each edge nearest it.
    let cores_apart = sep_a.max(sep_b) > CORE_GAP;
    // (s, t) along each edge, the reference edge's point, and the way to the incident one.
    let closest = || {
        let (s, t) = segment_closest(r1, r2, seg[0], seg[1]);
        let c_ref = r1 + s * (r2 - r1);
        let c_inc = seg[0] + t * (seg[1] - seg[0]);
        (s, t, c_ref, c_inc - c_ref)
    };
    let closest_points = |(s, t, c_ref, d): (Real, Real, Vec2, Vec2)| {
        let dist = d.length();
        let separation = dist - r_ref - r_inc;
        if separation > margin || dist <= 0.0 {
            return Manifold::EMPTY;
        }
        let n = d / dist;
        let v_ref = if s < 0.5 {
            ref_edge
        } else {
            next(ref_edge, reference.count)
        };
        let v_inc = if t < 0.5 { i1 } else { i2 };
        let (va, vb, normal_in_a) = if flip {
            (v_inc, v_ref, -n)
        } else {
            (v_ref, v_inc, n)
        };
        // Halfway between the reference surface (c_ref + r_ref n) and the incident one.
        let mid = c_ref + (r_ref + 0.5 * separation) * n;
        let mut manifold = Manifold::EMPTY;
        manifold.normal = xf_a.q.rotate(normal_in_a);
        manifold.points[0] = ManifoldPoint {
            point: xf_a.apply(mid),
            separation,
            id: (va as u16) << 8 | vb as u16,
        };
        manifold.count = 1;
        manifold
    };
    // If the edges are closest at a vertex of each, the shapes meet corner to corner and no
    // face normal is right (it would understate the gap, or clip away every point of a
    // speculative contact).
    if cores_apart {
        // `x` is the end of its edge (0 or 1) and the other closest point lies beyond that end
        // (direction `away` from the vertex has a part along the edge pointing out). Parallel
        // faces side by side fail this: their gap is square to both edges.
        let past_end = |x: Real, edge: Vec2, away: Vec2| {
            let along = away.dot(edge);
            let slack = 1.0e-3 * away.length() * edge.length();
            (x == 0.0 && along < -slack) || (x == 1.0 && along > slack)
        };
        let (s, t, c_ref, d) = closest();
        if past_end(s, r2 - r1, d) && past_end(t, seg[1] - seg[0], -d) {
            return closest_points((s, t, c_ref, d));
        }
    }

    // Side planes of the reference edge: its tangent t, bounded by its two end vertices. An
    // incident edge that lies wholly past one of them (by less than the corner test's slack:
    // a corner almost square to the reference face) still touches at its closest points.
    // The edge runs counter-clockwise with the normal on its right: its direction is the
    // normal turned a quarter left, already of unit length.
    let tangent = Vec2::new(-n.y, n.x);
    let side_clipped = clip_segment(seg, -tangent, -tangent.dot(r1))
        .and_then(|seg| clip_segment(seg, tangent, tangent.dot(r2)));
    let Some(seg) = side_clipped else {
        return if cores_apart {
            closest_points(closest())
        } else {
            Manifold::EMPTY
        };
    };

    // Project onto the reference face (appendix eqs. 45-48), keeping points within the margin.
    let mut manifold = Manifold::EMPTY;
    let normal_in_a = if flip { -n } else { n };
    manifold.normal = xf_a.q.rotate(normal_in_a);
    // The incident edge runs against the reference edge: its start (slot 0) lies towards the
    // reference edge's end vertex and its end (slot 1) towards the start vertex. A point is
    // named by that pair of vertices, written (A's vertex, B's vertex) whichever polygon is the
    // reference, so the id survives the reference face switching sides between steps.
    let v_ref = [next(ref_edge, reference.count), ref_edge];
    let v_inc = [i1, i2];
    for (k, v) in seg.into_iter().enumerate() {
        let core = n.dot(v - r1);
        let separation = core - r_ref - r_inc;
        if separation > margin {
            continue;
        }
        // Halfway between the incident surface (v - r_inc n) and the reference surface
        // (v's projection on the reference edge, then r_ref out along n).
        let mid = v + (0.5 * (r_ref - r_inc - core)) * n;
        let (va, vb) = if flip {
            (v_inc[k], v_ref[k])
        } else {
            (v_ref[k], v_inc[k])
        };
        let id: FeatureId = (va as u16) << 8 | vb as u16;
        manifold.points[manifold.count] = ManifoldPoint {
            point: xf_a.apply(mid),
            separation,
            id,
        };
        manifold.count += 1;
    }
    manifold
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::vec2;

    /// A transform at (`x`, `y`) m, turned by `angle` rad.
    fn at(x: Real, y: Real, angle: Real) -> Transform {
        Transform {
            p: vec2(x, y),
            q: Rot::from_angle(angle),
        }
    }

    #[test]
    fn the_rectangle_fast_path_agrees_with_the_general_polygon_routine() {
        let poly = |h: Vec2| {
            let corners = [
                vec2(-h.x, -h.y),
                vec2(h.x, -h.y),
                vec2(h.x, h.y),
                vec2(-h.x, h.y),
            ];
            Polygon::new(&corners).unwrap().0
        };
        // A deterministic sweep of sizes, offsets and angles, touching, overlapping and apart.
        let mut seed: u32 = 12345;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as Real / (1u32 << 24) as Real
        };
        let mut compared = 0;
        for _ in 0..2000 {
            let ha = vec2(0.1 + next(), 0.1 + next());
            let hb = vec2(0.1 + next(), 0.1 + next());
            let xa = at(4.0 * next() - 2.0, 4.0 * next() - 2.0, 6.3 * next());
            let xb = at(
                xa.p.x + 3.0 * next() - 1.5,
                xa.p.y + 3.0 * next() - 1.5,
                6.3 * next(),
            );
            let margin = 0.2 * next();
            let fast = collide_rects(ha, xa, hb, xb, margin);
            let general = collide_polygons(&poly(ha), 0.0, xa, &poly(hb), 0.0, xb, margin);
            assert_eq!(fast.count, general.count, "{ha:?} {xa:?} {hb:?} {xb:?}");
            if fast.count > 0 {
                compared += 1;
                assert!(
                    (fast.normal - general.normal).length() < 1e-4,
                    "{fast:?} vs {general:?}"
                );
                for (p, q) in fast.points().iter().zip(general.points()) {
                    assert!(
                        (p.point - q.point).length() < 1e-4
                            && (p.separation - q.separation).abs() < 1e-4,
                        "{fast:?} vs {general:?}"
                    );
                    assert_eq!(p.id, q.id);
                }
            }
        }
        assert!(compared > 300, "only {compared} touching pairs compared");
    }
}
