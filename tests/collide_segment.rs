//! Glass-box tests of the segment narrow phase (issue 17): every dynamic kind against a
//! segment, normals that never lean past a straight or concave joint, convex corners reported
//! once, one-sidedness. Exact values from the geometry of each set-up.

use tiltbox::physics::collide::collide;
use tiltbox::physics::math::Transform;
use tiltbox::physics::segment::chain;
use tiltbox::physics::{vec2, Polygon, Real, Rot, Segment, Shape, Vec2};

fn at(x: Real, y: Real, angle: Real) -> Transform {
    Transform {
        p: vec2(x, y),
        q: Rot::from_angle(angle),
    }
}

/// The pieces of an open chain through `points`, one-sided, as (shape, transform).
fn pieces(points: &[Vec2]) -> Vec<(Shape, Transform)> {
    chain(points, false, true)
        .unwrap()
        .into_iter()
        .map(|(mid, s)| (Shape::Segment(Box::new(s)), at(mid.x, mid.y, 0.0)))
        .collect()
}

fn close(a: Vec2, b: Vec2) -> bool {
    (a - b).length() < 1e-5
}

#[test]
fn every_dynamic_kind_rests_on_a_segment_with_the_face_normal() {
    let (poly, _) = Polygon::new(&[vec2(-0.5, -0.5), vec2(0.5, -0.5), vec2(0.0, 0.5)]).unwrap();
    let floor = Shape::Segment(Box::new(Segment::new(vec2(-5.0, 0.0), vec2(5.0, 0.0), 0.0)));
    // Each shape's lowest point 1 cm into the floor.
    let cases: [(Shape, Real, usize); 4] = [
        (Shape::rect(1.0, 1.0), 0.49, 2),
        (Shape::circle(0.5), 0.49, 1),
        (Shape::capsule(2.0, 0.25), 0.24, 2),
        // The triangle's centroid is a third of its height above its base.
        (Shape::from(poly), 1.0 / 3.0 - 0.01, 2),
    ];
    for (shape, y, count) in cases {
        let m = collide(&floor, at(0.0, 0.0, 0.0), &shape, at(1.0, y, 0.0), 0.02);
        assert_eq!(m.count, count, "{}", shape.kind());
        assert!(
            close(m.normal, vec2(0.0, 1.0)),
            "{}: {:?}",
            shape.kind(),
            m.normal
        );
        for p in m.points() {
            assert!(
                (p.separation + 0.01).abs() < 1e-4,
                "{}: {}",
                shape.kind(),
                p.separation
            );
        }
        // Swapped: the same contact from the body's side.
        let s = collide(&shape, at(1.0, y, 0.0), &floor, at(0.0, 0.0, 0.0), 0.02);
        assert!(close(s.normal, vec2(0.0, -1.0)));
        assert_eq!(s.count, count);
    }
}

/// The ghost collision: a box 1 cm deep in a flat floor of two pieces, straddling the seam
/// with 5 mm of its width past it. As two lone segments, the second one's separating axis is
/// the box's side face (a horizontal normal: the snag); as chain pieces both answer with the
/// floor's normal.
#[test]
fn a_box_over_a_flat_seam_sees_only_the_floor_normal() {
    let b = Shape::rect(1.0, 1.0);
    let xf = at(-0.495, 0.49, 0.0); // right face at x = 0.005, the seam at x = 0
    let lone = Shape::Segment(Box::new(Segment::new(vec2(0.0, 0.0), vec2(2.0, 0.0), 0.0)));
    let m = collide(&lone, at(0.0, 0.0, 0.0), &b, xf, 0.02);
    assert!(
        m.count > 0 && m.normal.x.abs() > 0.9,
        "lone: {:?}",
        m.normal
    );
    let chain = pieces(&[vec2(-2.0, 0.0), vec2(0.0, 0.0), vec2(2.0, 0.0)]);
    for (shape, piece) in &chain {
        let m = collide(shape, *piece, &b, xf, 0.02);
        if m.count > 0 {
            assert!(close(m.normal, vec2(0.0, 1.0)), "{:?}", m.normal);
        }
    }
    let left = collide(&chain[0].0, chain[0].1, &b, xf, 0.02);
    assert_eq!(left.count, 2, "the piece under the box holds it");
}

/// A disc on a hilltop (a convex joint, 30 degrees each way) touches the vertex: one piece
/// reports it, not both, with the normal from the vertex to the centre.
#[test]
fn a_convex_corner_is_reported_by_one_piece() {
    let s = 30.0_f32.to_radians() as Real;
    let top = vec2(0.0, 0.0);
    let chain = pieces(&[
        vec2(-2.0 * s.cos(), -2.0 * s.sin()),
        top,
        vec2(2.0 * s.cos(), -2.0 * s.sin()),
    ]);
    let disc = Shape::circle(0.25);
    let xf = at(0.0, 0.24, 0.0);
    let found: Vec<_> = chain
        .iter()
        .map(|(shape, piece)| collide(shape, *piece, &disc, xf, 0.02))
        .filter(|m| m.count > 0)
        .collect();
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(
        close(found[0].normal, vec2(0.0, 1.0)),
        "{:?}",
        found[0].normal
    );
    assert!((found[0].points[0].separation + 0.01).abs() < 1e-5);
}

/// In a valley (a concave joint), a box resting on one slope near the bottom touches the
/// other slope only along that slope's own normal.
#[test]
fn a_concave_corner_gives_each_piece_its_own_normal() {
    let s = 30.0_f32.to_radians() as Real;
    let chain = pieces(&[
        vec2(-2.0 * s.cos(), 2.0 * s.sin()),
        vec2(0.0, 0.0),
        vec2(2.0 * s.cos(), 2.0 * s.sin()),
    ]);
    let disc = Shape::circle(0.25);
    // In the valley, touching both slopes.
    let xf = at(0.0, 0.25 / s.cos() - 0.01, 0.0);
    let normals: Vec<Vec2> = chain
        .iter()
        .map(|(shape, piece)| collide(shape, *piece, &disc, xf, 0.02))
        .filter(|m| m.count > 0)
        .map(|m| m.normal)
        .collect();
    assert_eq!(normals.len(), 2);
    assert!(
        close(normals[0], vec2(s.sin(), s.cos())),
        "{:?}",
        normals[0]
    );
    assert!(
        close(normals[1], vec2(-s.sin(), s.cos())),
        "{:?}",
        normals[1]
    );
}

/// One-sided pieces ignore bodies whose centre is behind them; two-sided ones push them out
/// the back.
#[test]
fn one_sided_segments_ignore_what_is_behind_them() {
    let mut s = Segment::new(vec2(-1.0, 0.0), vec2(1.0, 0.0), 0.0);
    let disc = Shape::circle(0.25);
    let below = at(0.0, -0.2, 0.0);
    let two = collide(
        &Shape::Segment(Box::new(s.clone())),
        at(0.0, 0.0, 0.0),
        &disc,
        below,
        0.02,
    );
    assert!(two.count == 1 && close(two.normal, vec2(0.0, -1.0)));
    s.one_sided = true;
    let one = collide(
        &Shape::Segment(Box::new(s)),
        at(0.0, 0.0, 0.0),
        &disc,
        below,
        0.02,
    );
    assert_eq!(one.count, 0);
}
