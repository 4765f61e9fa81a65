//! Segments (and chain pieces) against any shape, with ghost-collision prevention.
//!
//! The segment is first collided as what it is, a two-vertex core grown by its radius (the
//! polygon clipper, or the circle routine). A chain piece then checks the normal it got
//! against the neighbouring vertices, so that a body crossing a joint sees only normals the
//! chain's surface really has:
//!
//! - a normal pointing to the segment's back, or to the closed side of a one-sided segment,
//!   is replaced by the face normal (a one-sided segment ignores bodies whose centre is
//!   behind it altogether);
//! - a normal leaning past one of the segment's ends (a vertex contact, or a face of the
//!   other body chosen by the separating-axis test) is only kept where the chain turns away
//!   from the body there (a convex corner) and the lean stays within the corner's range of
//!   normals, up to the next piece's face normal. Over a straight or concave joint it is
//!   replaced by the face normal: this is what stops a box sliding over a seam from hitting
//!   the side of the next piece, which at a joint of two abutting boxes is a real face.
//! - at a convex corner the vertex belongs to the piece it ends (its `b`), so the two pieces
//!   meeting there do not both report it.
//!
//! "Replaced by the face normal" means the contact is rebuilt as a face contact: the other
//! body's incident edge clipped to the segment's extent and measured along the face normal.

use super::polygon::{collide_polygons, incident_edge, Rounded};
use super::{collide_polygon_circle, core, FeatureId, Manifold, ManifoldPoint};
use crate::physics::convex::Polygon;
use crate::physics::math::{Real, Rot, Transform, Vec2};
use crate::physics::segment::{convexity, Segment};
use crate::physics::shape::Shape;

/// Sine of the lean (of the normal along the segment) below which a normal counts as the
/// face normal: 0.001 rad. A contact on the face leans by round-off only.
const LEAN_TOL: Real = 1.0e-3;

/// Convexity (sine of the turn) at or below which a joint counts as straight: 0.001 rad.
/// Straight and concave joints are treated alike (the face normals cover them).
const TURN_TOL: Real = 1.0e-3;

/// Contact between segment `s` at `xf_a` and `other` at `xf_b`, keeping points whose
/// separation is at most `margin` (m). The normal points from the segment to the other shape.
pub fn collide_segment(
    s: &Segment,
    xf_a: Transform,
    other: &Shape,
    xf_b: Transform,
    margin: Real,
) -> Manifold {
    let (xf_l, half) = own_frame(s, xf_a);
    let line = Polygon::segment(half);
    let (core_b, rb) = core(other);
    // Which side of the line the other body's centre is on.
    let centre = xf_l.apply_inv(xf_b.p);
    let side: Real = if centre.y >= 0.0 { 1.0 } else { -1.0 };
    if s.one_sided && side < 0.0 {
        return Manifold::EMPTY;
    }
    let m = match other {
        Shape::Circle { radius } => {
            collide_polygon_circle(&line, s.radius, xf_l, *radius, xf_b, margin)
        }
        _ => {
            let rounded_a = Rounded::new(&line, s.radius, xf_l);
            let rounded_b = Rounded::new(&core_b, rb, xf_b);
            collide_polygons(rounded_a, rounded_b, margin)
        }
    };
    if m.count == 0 || (s.prev.is_none() && s.next.is_none() && !s.one_sided) {
        // Nothing found, or a lone two-sided segment: a capsule core like any other.
        return m;
    }
    let n = xf_l.q.inv_rotate(m.normal);
    match verdict(s, n, side, xf_a, xf_l) {
        Verdict::Keep => m,
        Verdict::Empty => Manifold::EMPTY,
        Verdict::Face => {
            // The other core in the segment's frame.
            let rel = Transform {
                p: centre,
                q: Rot {
                    c: xf_l.q.c * xf_b.q.c + xf_l.q.s * xf_b.q.s,
                    s: xf_l.q.c * xf_b.q.s - xf_l.q.s * xf_b.q.c,
                },
            };
            let face = SegmentFace {
                xf: xf_l,
                half,
                radius: s.radius,
                side,
            };
            face_contact(&face, &core_b.transformed(rel), rb, margin)
        }
    }
}

/// The segment's own frame in the world (origin at its middle, x along a -> b, y its left
/// normal) for a segment body at `xf_a`, and half the segment's length (m): in that frame
/// the segment runs (-half, 0)..(half, 0).
fn own_frame(s: &Segment, xf_a: Transform) -> (Transform, Real) {
    let e = s.b - s.a;
    let half = 0.5 * e.length();
    let dir = e / (2.0 * half);
    let xf_l = Transform {
        p: xf_a.apply(0.5 * (s.a + s.b)),
        q: Rot {
            c: xf_a.q.c * dir.x - xf_a.q.s * dir.y,
            s: xf_a.q.s * dir.x + xf_a.q.c * dir.y,
        },
    };
    (xf_l, half)
}

/// What the neighbours make of a manifold.
enum Verdict {
    /// Keep it as found.
    Keep,
    /// Drop it: another piece reports this contact.
    Empty,
    /// Rebuild it along the face normal.
    Face,
}

/// What segment `s`'s neighbours make of a manifold normal `n` (in the segment's own frame
/// `xf_l`; `xf_a` is the segment body's transform) for a body on `side` (+1 left, -1 right),
/// by the module's rules: a normal to the back (or square to the face) is rebuilt on the
/// face; one leaning past an end with no neighbour there is kept; over a convex corner it is
/// dropped at `a` (the previous piece reports it) and kept at `b` within the corner's normals;
/// over a straight or concave joint it is rebuilt on the face.
fn verdict(s: &Segment, n: Vec2, side: Real, xf_a: Transform, xf_l: Transform) -> Verdict {
    let e = s.b - s.a;
    let face = Vec2::new(0.0, side);
    // Back in A's frame, for the neighbours.
    let edge_dir = |from: Vec2, to: Vec2| to - from;
    if n.y * side <= LEAN_TOL {
        Verdict::Face
    } else if n.x < -LEAN_TOL {
        match s.prev {
            None => Verdict::Keep,
            // Convex: the previous piece owns this vertex (it is that piece's `b`).
            Some(g) if convexity(edge_dir(g, s.a), e, side) > TURN_TOL => Verdict::Empty,
            Some(_) => Verdict::Face,
        }
    } else if n.x > LEAN_TOL {
        match s.next {
            None => Verdict::Keep,
            Some(g) => {
                let out = edge_dir(s.b, g);
                if convexity(e, out, side) > TURN_TOL {
                    // Within the corner's normals, up to the next piece's face normal
                    // (in this frame); past it, the next piece's face answers.
                    let next_face = xf_l.q.inv_rotate(xf_a.q.rotate(left(out) * side));
                    if n.dot(face) + 1.0e-4 >= next_face.dot(face) {
                        Verdict::Keep
                    } else {
                        Verdict::Empty
                    }
                } else {
                    Verdict::Face
                }
            }
        }
    } else {
        Verdict::Keep
    }
}

/// Unit normal to the left of direction `d`.
fn left(d: Vec2) -> Vec2 {
    let d = d.normalize();
    Vec2::new(-d.y, d.x)
}

/// The segment's face that a contact is rebuilt on: the line (-`half`, 0)..(`half`, 0) of the
/// segment's own frame `xf`, grown by `radius` (m), facing (0, `side`).
struct SegmentFace {
    xf: Transform,
    half: Real,
    radius: Real,
    side: Real,
}

/// A face contact along the normal of `face` against `inc` (the other core, in the segment's
/// frame) grown by `rb` (m): its edge most against the normal, clipped to the segment's
/// extent, keeping points whose separation is at most `margin` (m). Ids as the clipper gives
/// them when the segment's face is the reference.
fn face_contact(face: &SegmentFace, inc: &Polygon, rb: Real, margin: Real) -> Manifold {
    let (ra, side) = (face.radius, face.side);
    let n = Vec2::new(0.0, side);
    // The reference edge of `Polygon::segment`: edge 1 faces +y, edge 0 faces -y.
    let ref_edge: usize = if side > 0.0 { 1 } else { 0 };
    let (i1, i2) = if inc.count == 1 {
        (0, 0)
    } else {
        let best = incident_edge(inc, n);
        (best, (best + 1) % inc.count)
    };
    let Some(points) = clip_to_extent([inc.vertices[i1], inc.vertices[i2]], face.half) else {
        return Manifold::EMPTY;
    };
    let v_ref = [(ref_edge + 1) % 2, ref_edge];
    let v_inc = [i1, i2];
    let mut m = Manifold::EMPTY;
    m.normal = face.xf.q.rotate(n);
    let slots = if inc.count == 1 { 1 } else { 2 };
    for k in 0..slots {
        let v = points[k];
        let core = n.dot(v);
        let separation = core - ra - rb;
        if separation > margin {
            continue;
        }
        let mid = v + (0.5 * (ra - rb - core)) * n;
        let id: FeatureId = if inc.count == 1 {
            (ref_edge as FeatureId) << 8
        } else {
            (v_ref[k] as FeatureId) << 8 | v_inc[k] as FeatureId
        };
        m.points[m.count] = ManifoldPoint {
            point: face.xf.apply(mid),
            separation,
            id,
        };
        m.count += 1;
    }
    m
}

/// The edge `points` (segment frame, m) clipped to the segment's side planes x >= -`half` and
/// x <= `half`, each end staying in its slot; None when it lies wholly past one of them.
fn clip_to_extent(mut points: [Vec2; 2], half: Real) -> Option<[Vec2; 2]> {
    for (sign, limit) in [(-1.0, half), (1.0, half)] {
        let d0 = sign * points[0].x - limit;
        let d1 = sign * points[1].x - limit;
        match (d0 <= 0.0, d1 <= 0.0) {
            (true, true) => {}
            (false, false) => return None,
            (in0, _) => {
                let t = d0 / (d0 - d1);
                let cut = points[0] + t * (points[1] - points[0]);
                if in0 {
                    points[1] = cut;
                } else {
                    points[0] = cut;
                }
            }
        }
    }
    Some(points)
}
