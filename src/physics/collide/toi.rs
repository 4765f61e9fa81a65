//! Time of impact: the first moment of a body's motion over a step at which one of its shapes
//! comes within a target distance of a fixed shape (continuous collision, `world/continuous.rs`).
//!
//! Conservative advancement (Mirtich): at the current moment, a lower bound d on the distance
//! between the shapes and an axis n along which it holds: every point of the fixed shape lies
//! on one side of a slab of width d across n, every point of the moving one on the other. The
//! moving shape cannot touch the fixed one before one of its points crosses the slab, and none
//! approaches along -n faster than the centre does plus the turn times the farthest point's
//! reach, so the motion may advance by (d - target) over that speed without passing the
//! target distance. A shape that does not approach along n (a box sliding along a floor) is
//! never stopped. The bound is the largest separation of the two cores over a few axes
//! (each core's face normals and the directions between their vertices), less their radii:
//! any axis gives a lower bound of the distance, and these include the axis it is measured on.

use super::core;
use crate::physics::convex::Polygon;
use crate::physics::math::{Real, Rot, Transform, Vec2};
use crate::physics::shape::Shape;

/// Advancement steps before the search gives up where it is (still short of the target: the
/// moment it returns is earlier than the true one, never later).
const MAX_ITERATIONS: usize = 32;

/// A shape's motion over a step with its body (which turns about its position, its centre of
/// mass): where the body starts and ends (m), its angle at each end (rad), and the shape's
/// pose in the body's centre-of-mass frame.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sweep {
    pub start: (Vec2, Real),
    pub end: (Vec2, Real),
    pub local: Transform,
}

impl Sweep {
    /// The shape's transform a fraction `t` (0 to 1) of the way along the motion.
    pub fn at(&self, t: Real) -> Transform {
        let ((p0, a0), (p1, a1)) = (self.start, self.end);
        let body = Transform {
            p: p0 + t * (p1 - p0),
            q: Rot::from_angle(a0 + t * (a1 - a0)),
        };
        body.then(self.local)
    }
}

/// The first fraction (0 to 1) of `sweep` at which shape `moving` comes within `target` (m) of
/// shape `fixed` placed at `xf_fixed`, give or take a quarter of the target; None if it stays
/// farther all along. 0 when it starts that close. After [`MAX_ITERATIONS`] steps of
/// advancement still short of the target, the moment reached (earlier than the true one).
pub(crate) fn time_of_impact(
    (fixed, xf_fixed): (&Shape, Transform),
    moving: &Shape,
    sweep: &Sweep,
    target: Real,
) -> Option<Real> {
    let (core_f, radius_f) = core(fixed);
    let (core_m, radius_m) = core(moving);
    let travel = sweep.end.0 - sweep.start.0;
    // Turning moves the core's points at most its reach from the centre (a disc's not at
    // all, unless it sits off the body's centre).
    let core_reach = moving.bounding_radius() - moving.rounding() + sweep.local.p.length();
    let turn = (sweep.end.1 - sweep.start.1).abs() * core_reach;
    let tolerance = 0.25 * target;
    let mut t = 0.0;
    for _ in 0..MAX_ITERATIONS {
        let xf = sweep.at(t);
        let (d, n) = separation((&core_f, xf_fixed), (&core_m, xf), radius_f + radius_m);
        if d <= target + tolerance {
            return Some(t);
        }
        let approach = -travel.dot(n) + turn;
        if approach <= 0.0 {
            return None;
        }
        t += (d - target) / approach;
        if t >= 1.0 {
            return None;
        }
    }
    Some(t)
}

/// Whether shape `moving` at `xf` lies along the line of one of `fixed`'s faces, outside it and
/// within `target` (m) of that line either way: it slides or rolls on a surface that `fixed`
/// continues, as a disc rolling over the joint between two pieces of a chain or a box sliding
/// onto the next floor tile. Swept whole, such a shape would stop at the seam (it comes within
/// the target of the next piece's end at once), so the caller sweeps its core instead.
pub(crate) fn lies_along_a_face(
    (fixed, xf_fixed): (&Shape, Transform),
    moving: &Shape,
    xf: Transform,
    target: Real,
) -> bool {
    let (core_f, radius_f) = core(fixed);
    let (core_m, radius_m) = core(moving);
    let (faces, points) = (core_f.transformed(xf_fixed), core_m.transformed(xf));
    faces
        .vertices()
        .iter()
        .zip(faces.normals())
        .any(|(&v, &n)| {
            let nearest = points
                .vertices()
                .iter()
                .map(|&p| n.dot(p - v))
                .fold(Real::INFINITY, Real::min);
            (nearest - radius_f - radius_m).abs() < target
        })
}

/// A lower bound on the distance (m) between cores `a` and `b` at their transforms grown by
/// `radii` (m) in all, and the unit axis, from A towards B, it holds along.
fn separation(
    (a, xf_a): (&Polygon, Transform),
    (b, xf_b): (&Polygon, Transform),
    radii: Real,
) -> (Real, Vec2) {
    let world = |p: &Polygon, xf: Transform| -> ([Vec2; 8], usize) {
        let mut out = [Vec2::ZERO; 8];
        for (o, &v) in out.iter_mut().zip(p.vertices()) {
            *o = xf.apply(v);
        }
        (out, p.vertices().len())
    };
    let ((va, na), (vb, nb)) = (world(a, xf_a), world(b, xf_b));
    let (va, vb) = (&va[..na], &vb[..nb]);
    // Along n: the gap between A's farthest point towards B and B's nearest.
    let gap = |n: Vec2| {
        let far_a = va
            .iter()
            .map(|&v| n.dot(v))
            .fold(Real::NEG_INFINITY, Real::max);
        let near_b = vb.iter().map(|&v| n.dot(v)).fold(Real::INFINITY, Real::min);
        near_b - far_a
    };
    let mut best = (Real::NEG_INFINITY, Vec2::new(0.0, 1.0));
    let mut consider = |n: Vec2| {
        let g = gap(n);
        if g > best.0 {
            best = (g, n);
        }
    };
    for &n in a.normals() {
        consider(xf_a.q.rotate(n));
    }
    for &n in b.normals() {
        consider(-xf_b.q.rotate(n));
    }
    for &p in va {
        for &q in vb {
            let d = q - p;
            let len = d.length();
            if len > Real::EPSILON {
                consider(d / len);
            }
        }
    }
    (best.0 - radii, best.1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::vec2;
    use crate::physics::segment::Segment;

    fn at(p: Vec2, angle: Real) -> Transform {
        Transform {
            p,
            q: Rot::from_angle(angle),
        }
    }

    /// A 1 m box falling 10 m onto a floor whose top is at y = 0 (a 20 m x 1 m box): it first
    /// comes within the target 1 cm when its bottom is 1 cm up, its centre at 0.51 m, at the
    /// fraction (10.5 - 0.51) / 10 of the fall, within the quarter-target tolerance.
    #[test]
    fn a_falling_box_meets_the_floor_where_its_bottom_reaches_it() {
        let floor = (&Shape::rect(20.0, 1.0), at(vec2(0.0, -0.5), 0.0));
        let sweep = Sweep {
            start: (vec2(0.0, 10.5), 0.0),
            end: (vec2(0.0, 0.5), 0.0),
            local: Transform::IDENTITY,
        };
        let t = time_of_impact(floor, &Shape::rect(1.0, 1.0), &sweep, 0.01).unwrap();
        let bottom = sweep.at(t).p.y - 0.5;
        assert!(
            (0.01..=0.0125).contains(&bottom),
            "bottom {bottom} m up at t = {t}"
        );
    }

    /// A 4 m x 0.1 m plank whose centre passes 1 m above a thin post's top while it turns a
    /// half turn: its ends sweep down to the post. With the turn ignored it would pass; the
    /// contact must be found before any point of the plank is within the target of the post.
    #[test]
    fn a_spinning_plank_is_stopped_by_its_turning_end() {
        let post = (&Shape::rect(0.1, 2.0), at(vec2(0.0, -1.0), 0.0));
        let plank = Shape::rect(4.0, 0.1);
        let sweep = Sweep {
            start: (vec2(-2.0, 1.0), 0.0),
            end: (vec2(2.0, 1.0), std::f32::consts::PI as Real),
            local: Transform::IDENTITY,
        };
        let t = time_of_impact(post, &plank, &sweep, 0.01).expect("the plank's end meets the post");
        // At the moment found, the plank is still clear of the post by the target, give or
        // take the tolerance, and sampled finely up to it, never closer.
        let (core_p, _) = core(post.0);
        let (core_k, _) = core(&plank);
        for i in 0..=100 {
            let s = t * i as Real / 100.0;
            let (d, _) = separation((&core_p, post.1), (&core_k, sweep.at(s)), 0.0);
            assert!(d >= 0.0, "plank inside the post at {s} < {t}: {d} m");
        }
        let (d, _) = separation((&core_p, post.1), (&core_k, sweep.at(t)), 0.0);
        assert!(d <= 0.0125 + 1e-4, "stopped {d} m short at t = {t}");
    }

    /// A box sliding along a floor it touches is never stopped: it does not approach.
    #[test]
    fn a_box_sliding_along_a_floor_is_not_stopped() {
        let floor = (&Shape::rect(20.0, 1.0), at(vec2(0.0, -0.5), 0.0));
        let sweep = Sweep {
            start: (vec2(0.0, 0.52), 0.0),
            end: (vec2(5.0, 0.52), 0.0),
            local: Transform::IDENTITY,
        };
        assert_eq!(
            time_of_impact(floor, &Shape::rect(1.0, 1.0), &sweep, 0.01),
            None
        );
    }

    /// A disc passing a box's corner diagonally: the vertex-to-vertex axis bounds the gap; the
    /// disc (radius 0.5) whose centre passes 0.6 m from the corner never comes within 1 cm.
    #[test]
    fn a_disc_passing_a_corner_at_a_distance_is_not_stopped() {
        let block = (&Shape::rect(2.0, 2.0), at(vec2(0.0, 0.0), 0.0));
        let corner = vec2(1.0, 1.0);
        let off = corner + vec2(1.0, 1.0).normalize() * 0.6;
        let along = vec2(1.0, -1.0).normalize() * 3.0;
        let sweep = Sweep {
            start: (off - along, 0.0),
            end: (off + along, 0.0),
            local: Transform::IDENTITY,
        };
        assert_eq!(
            time_of_impact(block, &Shape::circle(0.5), &sweep, 0.01),
            None
        );
    }

    /// A disc resting on the line of a segment beyond its end (the next piece of a straight
    /// chain) lies along its face; the same disc 5 cm up, or resting on a line at 90 degrees
    /// to the segment, does not.
    #[test]
    fn a_disc_on_the_line_of_the_next_piece_lies_along_its_face() {
        let piece = Shape::Segment(Box::new(Segment::new(vec2(0.0, 0.0), vec2(1.0, 0.0), 0.0)));
        let fixed = (&piece, at(Vec2::ZERO, 0.0));
        let disc = Shape::circle(0.25);
        let on_line = at(vec2(-0.3, 0.25), 0.0);
        assert!(lies_along_a_face(fixed, &disc, on_line, 0.005));
        let above = at(vec2(-0.3, 0.30), 0.0);
        assert!(!lies_along_a_face(fixed, &disc, above, 0.005));
        let beside_end = at(vec2(-0.4, 0.0), 0.0);
        assert!(!lies_along_a_face(fixed, &disc, beside_end, 0.005));
    }
}
