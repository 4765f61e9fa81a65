//! Glass-box tests of the box-box narrow phase: exact contact points, normals and separations
//! for separated, touching, overlapping, rotated and corner-on-edge pairs. Coordinates are
//! chosen so every expected value is exact in binary floating point (or stated otherwise).

use tiltbox::physics::collide::{collide, Manifold};
use tiltbox::physics::{vec2, Real, Rot, Shape, Transform, Vec2};

fn at(x: Real, y: Real, angle: Real) -> Transform {
    Transform {
        p: vec2(x, y),
        q: Rot::from_angle(angle),
    }
}

/// Two unit boxes at `a` and `b`, no speculative margin.
fn boxes(a: Transform, b: Transform) -> Manifold {
    collide(&unit(), a, &unit(), b, 0.0)
}

fn unit() -> Shape {
    Shape::rect(1.0, 1.0)
}

fn sorted_points(m: &Manifold) -> Vec<(Vec2, Real)> {
    let mut v: Vec<_> = m.points().iter().map(|p| (p.point, p.separation)).collect();
    v.sort_by(|a, b| a.0.y.total_cmp(&b.0.y).then(a.0.x.total_cmp(&b.0.x)));
    v
}

fn close(a: Vec2, b: Vec2) -> bool {
    (a - b).length() < 1e-5
}

#[test]
fn separated_boxes_have_no_contact_unless_within_the_margin() {
    // Gap of 0.5 m between the right face of A (x = 0.5) and the left face of B (x = 1.0).
    let (a, b) = (at(0.0, 0.0, 0.0), at(1.5, 0.0, 0.0));
    assert_eq!(boxes(a, b).count, 0);
    assert_eq!(collide(&unit(), a, &unit(), b, 0.49).count, 0);
    // Within a 0.6 m speculative margin: two points, each 0.5 m apart, halfway between faces.
    let m = collide(&unit(), a, &unit(), b, 0.6);
    assert_eq!(m.count, 2);
    assert!(close(m.normal, vec2(1.0, 0.0)), "{:?}", m.normal);
    let pts = sorted_points(&m);
    assert!(
        close(pts[0].0, vec2(0.75, -0.5)) && close(pts[1].0, vec2(0.75, 0.5)),
        "{pts:?}"
    );
    assert!(pts.iter().all(|p| (p.1 - 0.5).abs() < 1e-6));
}

#[test]
fn touching_boxes_have_zero_separation() {
    let m = boxes(at(0.0, 0.0, 0.0), at(0.0, 1.0, 0.0));
    assert_eq!(m.count, 2);
    assert!(close(m.normal, vec2(0.0, 1.0)));
    let pts = sorted_points(&m);
    assert!(
        close(pts[0].0, vec2(-0.5, 0.5)) && close(pts[1].0, vec2(0.5, 0.5)),
        "{pts:?}"
    );
    assert!(pts.iter().all(|p| p.1.abs() < 1e-6));
}

#[test]
fn overlapping_boxes_clip_the_incident_edge_to_the_reference_face() {
    // B overlaps A by 0.125 in x and is raised by 0.25: B's left edge spans y in [-0.25, 0.75],
    // clipped to A's right face y in [-0.5, 0.5].
    let m = boxes(at(0.0, 0.0, 0.0), at(0.875, 0.25, 0.0));
    assert_eq!(m.count, 2);
    assert!(close(m.normal, vec2(1.0, 0.0)), "{:?}", m.normal);
    let pts = sorted_points(&m);
    // Halfway between B's face (x = 0.375) and A's face (x = 0.5).
    assert!(close(pts[0].0, vec2(0.4375, -0.25)), "{pts:?}");
    assert!(close(pts[1].0, vec2(0.4375, 0.5)), "{pts:?}");
    assert!(pts.iter().all(|p| (p.1 + 0.125).abs() < 1e-6));
}

#[test]
fn rotated_box_corner_into_a_face_gives_one_point_at_the_corner() {
    // B turned 45 degrees above A: its lowest corner sits half a diagonal below its centre.
    let half_diagonal = (0.5 as Real).sqrt();
    let depth = 0.05;
    let b = at(
        0.25,
        0.5 + half_diagonal - depth,
        std::f64::consts::FRAC_PI_4 as Real,
    );
    let m = boxes(at(0.0, 0.0, 0.0), b);
    assert_eq!(m.count, 1, "{m:?}");
    assert!(close(m.normal, vec2(0.0, 1.0)), "{:?}", m.normal);
    let p = m.points[0];
    assert!((p.separation + depth).abs() < 1e-5, "{p:?}");
    assert!(close(p.point, vec2(0.25, 0.5 - 0.5 * depth)), "{p:?}");
}

#[test]
fn swapping_the_pair_flips_the_normal_and_keeps_the_points() {
    let (a, b) = (at(0.0, 0.0, 0.1), at(0.3, 0.95, -0.05));
    let ab = boxes(a, b);
    let ba = boxes(b, a);
    assert_eq!(ab.count, 2);
    assert_eq!(ba.count, ab.count);
    assert!(
        close(ab.normal, -ba.normal),
        "{:?} vs {:?}",
        ab.normal,
        ba.normal
    );
    let (p, q) = (sorted_points(&ab), sorted_points(&ba));
    for (x, y) in p.iter().zip(&q) {
        assert!(
            (x.0 - y.0).length() < 1e-4 && (x.1 - y.1).abs() < 1e-4,
            "{p:?} vs {q:?}"
        );
    }
}

#[test]
fn edge_on_corner_of_a_small_box_on_a_large_one() {
    // A wide plank resting edge-on on the corner region of a small box: the small box's top face
    // is the reference only where it is the better axis; either way the normal is vertical and
    // the points lie within both boxes' extents.
    let plank = Shape::rect(4.0, 0.5);
    let small = Shape::rect(1.0, 1.0);
    let m = collide(&small, at(0.0, 0.0, 0.0), &plank, at(1.5, 0.74, 0.0), 0.0);
    assert_eq!(m.count, 2, "{m:?}");
    assert!(close(m.normal, vec2(0.0, 1.0)), "{:?}", m.normal);
    let pts = sorted_points(&m);
    // The overlap in x is [-0.5, 0.5] (the small box's top face): both ends are clip points.
    let xs: Vec<Real> = pts.iter().map(|p| p.0.x).collect();
    assert!(
        xs.iter().any(|x| (x + 0.5).abs() < 1e-5) && xs.iter().any(|x| (x - 0.5).abs() < 1e-5),
        "{pts:?}"
    );
    assert!(pts.iter().all(|p| (p.1 + 0.01).abs() < 1e-5), "{pts:?}");
}

#[test]
fn feature_ids_survive_the_reference_face_switching_sides() {
    // Two stacked boxes, the upper one tilted slightly one way and then the other: the
    // reference face moves from A to B, but the ids of the two corners stay the same.
    let a = at(0.0, 0.0, 0.0);
    let m1 = boxes(a, at(0.0, 0.995, 0.002));
    let m2 = boxes(at(0.0, 0.0, 0.002), at(0.0, 0.995, 0.0));
    assert_eq!(m1.count, 2);
    assert_eq!(m2.count, 2);
    let ids = |m: &Manifold| {
        let mut v: Vec<_> = m.points().iter().map(|p| (p.point.x < 0.0, p.id)).collect();
        v.sort();
        v
    };
    assert_eq!(ids(&m1), ids(&m2));
}
