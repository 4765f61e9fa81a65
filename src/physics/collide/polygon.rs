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

/// A convex core grown by a radius and placed in the world: one side of a polygon pair.
#[derive(Clone, Copy)]
pub(crate) struct Rounded<'a> {
    /// The core, in its body's frame.
    pub core: &'a Polygon,
    /// Radius the core is grown by (m); 0 for a sharp polygon.
    pub radius: Real,
    /// The body's transform.
    pub xf: Transform,
}

impl<'a> Rounded<'a> {
    /// `core` grown by `radius` (m), placed at `xf`.
    pub fn new(core: &'a Polygon, radius: Real, xf: Transform) -> Rounded<'a> {
        Rounded { core, radius, xf }
    }
}

/// A polygon's best candidate for the separating axis: the edge along which the other
/// polygon is farthest out, and that separation of the cores (m).
#[derive(Clone, Copy)]
struct Face {
    edge: usize,
    separation: Real,
}

/// The face of `p1` along which `p2` is farthest out.
///
/// For each edge normal n_i of p1 the separation is min_j n_i . (v2_j - v1_i): the appendix's
/// f_A components, generalised. The largest is the best separating-axis candidate.
fn max_separation(p1: &Polygon, p2: &Polygon) -> Face {
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
    Face {
        edge: best_edge,
        separation: best,
    }
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

/// Contact manifold between convex polygons `a` and `b`, each grown by its radius (0 for a
/// sharp polygon), keeping points whose separation is at most `margin` metres. The normal
/// points from A to B.
pub fn collide_polygons(a: Rounded, b: Rounded, margin: Real) -> Manifold {
    let rel = relative(a.xf, b.xf);
    let pb = b.core.transformed(rel);
    let reach = margin + a.radius + b.radius;

    let face_a = max_separation(a.core, &pb);
    if face_a.separation > reach {
        return Manifold::EMPTY;
    }
    let face_b = max_separation(&pb, a.core);
    if face_b.separation > reach {
        return Manifold::EMPTY;
    }
    clip_to_reference(
        Side {
            polygon: a.core,
            face: face_a,
            radius: a.radius,
        },
        Side {
            polygon: &pb,
            face: face_b,
            radius: b.radius,
        },
        a.xf,
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
    // Both sharp: rectangles are their own cores.
    clip_to_reference(
        Side {
            polygon: &pa,
            face: Face {
                edge: edge_a,
                separation: sep_a,
            },
            radius: 0.0,
        },
        Side {
            polygon: &pb,
            face: Face {
                edge: edge_b,
                separation: sep_b,
            },
            radius: 0.0,
        },
        xf_a,
        margin,
    )
}

/// One polygon of a pair as the clipper takes it, in A's frame: the polygon, its best face,
/// and the radius its core is grown by (m).
#[derive(Clone, Copy)]
struct Side<'a> {
    polygon: &'a Polygon,
    face: Face,
    radius: Real,
}

/// Pick the reference face from the best face of each polygon (both in A's frame), clip the
/// other polygon's incident edge to it, and build the manifold in world coordinates.
fn clip_to_reference(a: Side, b: Side, xf_a: Transform, margin: Real) -> Manifold {
    let clip = Clip::new(a, b);
    // Cores that do not touch meet where their two edges are closest, along the line between
    // those points: one point, named by the vertex of each edge nearest it.
    let cores_apart = a.face.separation.max(b.face.separation) > CORE_GAP;
    // If the edges are closest at a vertex of each, the shapes meet corner to corner and no
    // face normal is right (it would understate the gap, or clip away every point of a
    // speculative contact).
    if cores_apart {
        if let Some(closest) = clip.corner_to_corner() {
            return clip.closest_points(closest, xf_a, margin);
        }
    }
    // An incident edge that lies wholly past one of the side planes (by less than the corner
    // test's slack: a corner almost square to the reference face) still touches at its
    // closest points.
    match clip.side_planes() {
        Some(seg) => clip.project(seg, xf_a, margin),
        None if cores_apart => clip.closest_points(clip.closest(), xf_a, margin),
        None => Manifold::EMPTY,
    }
}

/// The reference face and the incident edge against it, in A's frame: what the clipper
/// measures, and the vertex numbers it names points by.
struct Clip {
    /// B holds the reference face: the normal is reversed and the ids' halves swapped so the
    /// manifold still reads from A to B.
    flip: bool,
    /// The reference face's outward unit normal.
    n: Vec2,
    /// The reference edge's start and end (m).
    r1: Vec2,
    r2: Vec2,
    /// Their vertex numbers on the reference polygon.
    ref_vertices: [usize; 2],
    /// The incident edge's start and end (m).
    seg: [Vec2; 2],
    /// Their vertex numbers on the incident polygon.
    inc_vertices: [usize; 2],
    /// The radii the reference and incident cores are grown by (m).
    r_ref: Real,
    r_inc: Real,
}

/// Where the reference and incident edges come closest: the fractions `s` and `t` along each,
/// the reference edge's point `c_ref` and the way `d` from it to the incident edge's (m).
struct Closest {
    s: Real,
    t: Real,
    c_ref: Vec2,
    d: Vec2,
}

impl Clip {
    /// Choose the reference face between the two polygons' best faces and find the other
    /// polygon's incident edge: the edge whose normal is most anti-parallel to the reference
    /// normal.
    fn new(a: Side, b: Side) -> Clip {
        // Prefer A's face unless B's is clearly better, so the reference face does not flicker
        // between near-equal candidates from one step to the next (the appendix's eq. 79 idea).
        const RELATIVE_TOL: Real = 0.98;
        const ABSOLUTE_TOL: Real = 0.0005;
        let (sep_a, sep_b) = (a.face.separation, b.face.separation);
        // (Written as sep_a + tol so that it favours A for gaps as well as overlaps: the
        // appendix's 0.98 sep_a + tol only does for overlaps, and for a speculative gap it would
        // prefer B's face even when A's separates more.)
        let flip = sep_b > sep_a + (1.0 - RELATIVE_TOL) * sep_a.abs() + ABSOLUTE_TOL;
        let (reference, incident) = if flip { (b, a) } else { (a, b) };
        let (ref_poly, inc_poly) = (reference.polygon, incident.polygon);
        let ref_edge = reference.face.edge;
        let ref_end = next(ref_edge, ref_poly.count);
        let n = ref_poly.normals[ref_edge];
        let i1 = incident_edge(inc_poly, n);
        let i2 = next(i1, inc_poly.count);
        Clip {
            flip,
            n,
            r1: ref_poly.vertices[ref_edge],
            r2: ref_poly.vertices[ref_end],
            ref_vertices: [ref_edge, ref_end],
            seg: [inc_poly.vertices[i1], inc_poly.vertices[i2]],
            inc_vertices: [i1, i2],
            r_ref: reference.radius,
            r_inc: incident.radius,
        }
    }

    /// Where the reference and incident edges come closest.
    fn closest(&self) -> Closest {
        let (r1, r2, seg) = (self.r1, self.r2, self.seg);
        let (s, t) = segment_closest(r1, r2, seg[0], seg[1]);
        let c_ref = r1 + s * (r2 - r1);
        let c_inc = seg[0] + t * (seg[1] - seg[0]);
        Closest {
            s,
            t,
            c_ref,
            d: c_inc - c_ref,
        }
    }

    /// Where the edges come closest, if that is at a vertex of each: the shapes then meet
    /// corner to corner.
    fn corner_to_corner(&self) -> Option<Closest> {
        // `x` is the end of its edge (0 or 1) and the other closest point lies beyond that end
        // (direction `away` from the vertex has a part along the edge pointing out). Parallel
        // faces side by side fail this: their gap is square to both edges.
        let past_end = |x: Real, edge: Vec2, away: Vec2| {
            let along = away.dot(edge);
            let slack = 1.0e-3 * away.length() * edge.length();
            (x == 0.0 && along < -slack) || (x == 1.0 && along > slack)
        };
        let c = self.closest();
        let corners =
            past_end(c.s, self.r2 - self.r1, c.d) && past_end(c.t, self.seg[1] - self.seg[0], -c.d);
        corners.then_some(c)
    }

    /// One point on the line between the edges' closest points `c`, named by the vertex of
    /// each edge nearest it; none if the surfaces are more than `margin` (m) apart or the
    /// cores touch there (no direction).
    fn closest_points(&self, c: Closest, xf_a: Transform, margin: Real) -> Manifold {
        let dist = c.d.length();
        let separation = dist - self.r_ref - self.r_inc;
        if separation > margin || dist <= 0.0 {
            return Manifold::EMPTY;
        }
        let n = c.d / dist;
        let [ref_start, ref_end] = self.ref_vertices;
        let v_ref = if c.s < 0.5 { ref_start } else { ref_end };
        let [inc_start, inc_end] = self.inc_vertices;
        let v_inc = if c.t < 0.5 { inc_start } else { inc_end };
        // Halfway between the reference surface (c_ref + r_ref n) and the incident one.
        let mid = c.c_ref + (self.r_ref + 0.5 * separation) * n;
        let mut manifold = Manifold::EMPTY;
        manifold.normal = xf_a.q.rotate(self.towards_b(n));
        manifold.points[0] = ManifoldPoint {
            point: xf_a.apply(mid),
            separation,
            id: self.id(v_ref, v_inc),
        };
        manifold.count = 1;
        manifold
    }

    /// The incident edge clipped to the reference edge's side planes (its tangent, bounded by
    /// its two end vertices), each end in its slot; None when it lies wholly past one.
    fn side_planes(&self) -> Option<[Vec2; 2]> {
        // The edge runs counter-clockwise with the normal on its right: its direction is the
        // normal turned a quarter left, already of unit length.
        let tangent = Vec2::new(-self.n.y, self.n.x);
        clip_segment(self.seg, -tangent, -tangent.dot(self.r1))
            .and_then(|seg| clip_segment(seg, tangent, tangent.dot(self.r2)))
    }

    /// The clipped incident edge `seg` projected onto the reference face (appendix eqs.
    /// 45-48), keeping the points whose separation is at most `margin` (m).
    fn project(&self, seg: [Vec2; 2], xf_a: Transform, margin: Real) -> Manifold {
        let n = self.n;
        let mut manifold = Manifold::EMPTY;
        manifold.normal = xf_a.q.rotate(self.towards_b(n));
        // The incident edge runs against the reference edge: its start (slot 0) lies towards
        // the reference edge's end vertex and its end (slot 1) towards the start vertex.
        let [ref_start, ref_end] = self.ref_vertices;
        let v_ref = [ref_end, ref_start];
        for (k, v) in seg.into_iter().enumerate() {
            let core = n.dot(v - self.r1);
            let separation = core - self.r_ref - self.r_inc;
            if separation > margin {
                continue;
            }
            // Halfway between the incident surface (v - r_inc n) and the reference surface
            // (v's projection on the reference edge, then r_ref out along n).
            let mid = v + (0.5 * (self.r_ref - self.r_inc - core)) * n;
            manifold.points[manifold.count] = ManifoldPoint {
                point: xf_a.apply(mid),
                separation,
                id: self.id(v_ref[k], self.inc_vertices[k]),
            };
            manifold.count += 1;
        }
        manifold
    }

    /// The id of a point named by reference vertex `v_ref` and incident vertex `v_inc`,
    /// written (A's vertex, B's vertex) whichever polygon is the reference, so the id survives
    /// the reference face switching sides between steps.
    fn id(&self, v_ref: usize, v_inc: usize) -> FeatureId {
        let (va, vb) = if self.flip {
            (v_inc, v_ref)
        } else {
            (v_ref, v_inc)
        };
        (va as FeatureId) << 8 | vb as FeatureId
    }

    /// A normal `n` out of the reference face, turned to point from A towards B as the
    /// manifold's normal does.
    fn towards_b(&self, n: Vec2) -> Vec2 {
        if self.flip {
            -n
        } else {
            n
        }
    }
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
            let (pa, pb) = (poly(ha), poly(hb));
            let general = collide_polygons(
                Rounded::new(&pa, 0.0, xa),
                Rounded::new(&pb, 0.0, xb),
                margin,
            );
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
