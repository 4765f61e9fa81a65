//! Every query against brute force (each shape of each body tested, no tree), in a world of
//! every shape kind, bodies of several shapes and filters, as it falls and bodies come and
//! go; and the geometry against what a point test says along the ray.

use crate::physics::body::{BodyDef, BodyId};
use crate::physics::convex::Polygon;
use crate::physics::filter::Filter;
use crate::physics::math::{vec2, Rot};
use crate::physics::math::{Real, Transform, Vec2};
use crate::physics::part::PartDef;
use crate::physics::query::geometry::{point_to_core, ray_rounded, Rounded};
use crate::physics::query::{overlaps_body, rounded, shapes_of, QueryFilter, RayHit, ShapeRef};
use crate::physics::segment::Segment;
use crate::physics::shape::Aabb;
use crate::physics::shape::Shape;
use crate::physics::world::World;

/// A small deterministic generator (numbers in [0, 1)).
struct Dice(u32);

impl Dice {
    fn next(&mut self) -> Real {
        self.0 = self.0.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (self.0 >> 8) as Real / (1u32 << 24) as Real
    }
    fn range(&mut self, lo: Real, hi: Real) -> Real {
        lo + (hi - lo) * self.next()
    }
}

fn shape(dice: &mut Dice) -> Shape {
    match (dice.next() * 4.0) as u32 {
        0 => Shape::circle(dice.range(0.2, 1.0)),
        1 => Shape::rect(dice.range(0.3, 2.0), dice.range(0.3, 2.0)),
        2 => Shape::capsule(dice.range(1.2, 3.0), dice.range(0.1, 0.5)),
        _ => {
            let s = dice.range(0.4, 1.2);
            Shape::Polygon(Box::new(
                Polygon::new(&[vec2(-s, -s), vec2(s, -s), vec2(0.0, s)])
                    .unwrap()
                    .0,
            ))
        }
    }
}

fn filter(dice: &mut Dice) -> Filter {
    match (dice.next() * 3.0) as u32 {
        0 => Filter::DEFAULT,
        1 => Filter {
            category: 2,
            ..Filter::DEFAULT
        },
        _ => Filter {
            mask: !1,
            ..Filter::DEFAULT
        },
    }
}

/// 150 bodies of every kind over a floor, a slope of segments and a few static posts.
fn world(dice: &mut Dice) -> (World, Vec<BodyId>) {
    let mut w = World::default();
    w.add_body(&BodyDef::fixed(Shape::rect(80.0, 1.0), vec2(0.0, -0.5)))
        .unwrap();
    let slope = Segment::new(vec2(-40.0, 10.0), vec2(-10.0, 2.0), 0.0);
    w.add_body(&BodyDef::fixed(Shape::Segment(Box::new(slope)), Vec2::ZERO))
        .unwrap();
    let mut ids = Vec::new();
    for i in 0..150 {
        let at = vec2(dice.range(-35.0, 35.0), dice.range(1.0, 30.0));
        let mut def = BodyDef::dynamic(shape(dice), at)
            .with_angle(dice.range(0.0, 6.0))
            .with_filter(filter(dice));
        if i % 5 == 0 {
            let part = PartDef::new(shape(dice), vec2(dice.range(-2.0, 2.0), 1.5))
                .with_filter(filter(dice));
            def = def.with_part(part);
        }
        if i % 17 == 0 {
            def = BodyDef::fixed(shape(dice), at);
        }
        ids.push(w.add_body(&def).unwrap());
    }
    (w, ids)
}

fn filters() -> [QueryFilter; 3] {
    [
        QueryFilter::DEFAULT,
        QueryFilter {
            category: 1,
            mask: 2,
        },
        QueryFilter {
            category: 2,
            mask: u64::MAX,
        },
    ]
}

/// Every (shape, hit) a ray meets, by testing every shape.
fn brute_ray(w: &World, origin: Vec2, d: Vec2, filter: &QueryFilter) -> Vec<RayHit> {
    let mut hits = Vec::new();
    for body in w.bodies() {
        for (i, s, xf, _) in shapes_of(body).filter(|x| filter.sees(&x.3)) {
            if let Some(hit) = ray_rounded(&rounded(s, xf), origin, d, 1.0) {
                let shape = ShapeRef {
                    body: body.id(),
                    shape: i,
                };
                let point = origin + hit.fraction * d;
                hits.push(RayHit {
                    shape,
                    point,
                    normal: hit.normal,
                    fraction: hit.fraction,
                });
            }
        }
    }
    hits.sort_by(|a, b| {
        a.fraction
            .total_cmp(&b.fraction)
            .then(a.shape.cmp(&b.shape))
    });
    hits
}

/// Every shape holding `p` or overlapping `probe`, by testing every shape.
fn brute_overlap(w: &World, probe: &Rounded, filter: &QueryFilter) -> Vec<ShapeRef> {
    let mut out: Vec<ShapeRef> = w
        .bodies()
        .flat_map(|b| {
            overlaps_body(b, probe, |f| filter.sees(f)).map(|shape| ShapeRef {
                body: b.id(),
                shape,
            })
        })
        .collect();
    out.sort_unstable();
    out
}

fn check_queries(w: &mut World, dice: &mut Dice) {
    for _ in 0..40 {
        let origin = vec2(dice.range(-45.0, 45.0), dice.range(-2.0, 35.0));
        let d = vec2(dice.range(-60.0, 60.0), dice.range(-60.0, 60.0));
        let p = vec2(dice.range(-40.0, 40.0), dice.range(0.0, 20.0));
        let probe_shape = shape(dice);
        let pose = Transform {
            p,
            q: Rot::from_angle(dice.range(0.0, 6.0)),
        };
        for f in filters() {
            let expected = brute_ray(w, origin, d, &f);
            let q = w.query();
            let closest = q.ray_closest(origin, d, f).unwrap();
            assert_eq!(closest, expected.first().copied());
            assert_eq!(q.ray_all(origin, d, f, usize::MAX).unwrap(), expected);
            assert_eq!(
                q.ray_all(origin, d, f, 3).unwrap(),
                expected[..expected.len().min(3)]
            );
            let point = Rounded::new([p], 0.0);
            assert_eq!(q.at_point(p, f).unwrap(), brute_overlap(w, &point, &f));
            let probe = rounded(&probe_shape, pose);
            let found = w.query().overlapping(&probe_shape, pose, f).unwrap();
            assert_eq!(found, brute_overlap(w, &probe, &f));
        }
    }
}

#[test]
fn every_query_finds_what_testing_every_shape_finds() {
    let mut dice = Dice(11);
    let (mut w, ids) = world(&mut dice);
    check_queries(&mut w, &mut dice);
    for round in 0..4 {
        for _ in 0..30 {
            w.step(1.0 / 60.0).unwrap();
        }
        // Bodies go and come between queries, in the same step and across steps.
        w.remove_body(ids[round * 7 + 1]).unwrap();
        w.add_body(&BodyDef::dynamic(shape(&mut dice), vec2(0.0, 25.0)))
            .unwrap();
        check_queries(&mut w, &mut dice);
    }
}

/// Along a ray, no point before the closest hit lies in any shape the query sees, and a point
/// just past it lies in the shape hit: the ray test agrees with the point test, which measures
/// distances rather than crossings.
#[test]
fn nothing_lies_on_a_ray_before_its_closest_hit() {
    let mut dice = Dice(5);
    let (mut w, _) = world(&mut dice);
    for _ in 0..60 {
        w.step(1.0 / 60.0).unwrap();
    }
    let mut hits = 0;
    for _ in 0..200 {
        let origin = vec2(dice.range(-45.0, 45.0), dice.range(25.0, 40.0));
        let d = vec2(dice.range(-30.0, 30.0), -50.0);
        let q = w.query();
        let Some(hit) = q.ray_closest(origin, d, QueryFilter::DEFAULT).unwrap() else {
            continue;
        };
        hits += 1;
        for k in 0..200 {
            let t = hit.fraction * k as Real / 200.0;
            let inside = q.at_point(origin + t * d, QueryFilter::DEFAULT).unwrap();
            assert!(
                inside.is_empty(),
                "{inside:?} at t = {t} before the hit at {}",
                hit.fraction
            );
        }
        // A millimetre past the hit lies inside the shape (a segment has no inside).
        let thin = matches!(
            q.world().body(hit.shape.body).unwrap().shape(),
            Shape::Segment(_)
        );
        let past = q
            .at_point(hit.point - 1e-3 * hit.normal, QueryFilter::DEFAULT)
            .unwrap();
        assert!(thin || past.contains(&hit.shape), "{hit:?}");
        assert!((hit.normal.length() - 1.0).abs() < 1e-4);
    }
    assert!(hits > 150, "only {hits} rays of 200 hit anything");
}

/// A shape cast stops where the shape first touches: just before it, the shape overlaps
/// nothing; at it, it touches what was hit.
#[test]
fn a_swept_shape_stops_where_it_first_touches() {
    let mut dice = Dice(3);
    let (mut w, _) = world(&mut dice);
    for _ in 0..60 {
        w.step(1.0 / 60.0).unwrap();
    }
    let mut hits = 0;
    for _ in 0..100 {
        let probe = shape(&mut dice);
        let start = vec2(dice.range(-35.0, 35.0), 45.0);
        let pose = Transform {
            p: start,
            q: Rot::from_angle(dice.range(0.0, 6.0)),
        };
        let d = vec2(dice.range(-10.0, 10.0), -60.0);
        let q = w.query();
        let Some(hit) = q.cast_shape(&probe, pose, d, QueryFilter::DEFAULT).unwrap() else {
            continue;
        };
        hits += 1;
        assert!(hit.fraction > 0.0 && hit.normal.dot(d) < 0.0, "{hit:?}");
        let at = |t: Real| Transform {
            p: start + t * d,
            ..pose
        };
        // A millimetre of travel either side (a shape may pass a corner within centimetres).
        let mm = 1e-3 / d.length();
        let before = q
            .overlapping(&probe, at(hit.fraction - mm), QueryFilter::DEFAULT)
            .unwrap();
        assert!(before.is_empty(), "{before:?} before the hit {hit:?}");
        let after = q
            .overlapping(&probe, at(hit.fraction + mm), QueryFilter::DEFAULT)
            .unwrap();
        if !after.contains(&hit.shape) {
            let body = w.body(hit.shape.body).unwrap();
            let (_, s, xf, _) = shapes_of(body).find(|x| x.0 == hit.shape.shape).unwrap();
            panic!("{hit:?} then {after:?}: probe {probe:?} at {pose:?} by {d}, target {s:?} at {xf:?} {:?} {:?}", rounded(&probe, pose), rounded(s, xf));
        }
        // The point is on the hit shape's surface: within a millimetre of it.
        let body = w.body(hit.shape.body).unwrap();
        let (_, s, xf, _) = shapes_of(body).find(|x| x.0 == hit.shape.shape).unwrap();
        let target = rounded(s, xf);
        let gap = point_to_core(target.vertices(), hit.point).0 - target.radius;
        assert!(
            gap.abs() < 1e-3,
            "point {} is {gap} m off the surface",
            hit.point
        );
    }
    assert!(hits > 80, "only {hits} casts of 100 hit anything");
}

#[test]
fn queries_refuse_what_they_cannot_use_and_name_it() {
    let mut w = World::default();
    let q = w.query();
    let nan = vec2(Real::NAN, 0.0);
    let err = q
        .ray_closest(nan, vec2(1.0, 0.0), QueryFilter::DEFAULT)
        .unwrap_err();
    assert!(err.to_string().contains("origin.x"), "{err}");
    let err = q
        .ray_all(
            Vec2::ZERO,
            vec2(0.0, Real::INFINITY),
            QueryFilter::DEFAULT,
            4,
        )
        .unwrap_err();
    assert!(err.to_string().contains("translation.y"), "{err}");
    let reversed = Aabb {
        min: vec2(0.0, 1.0),
        max: vec2(1.0, 0.0),
    };
    let err = q.in_box(reversed, QueryFilter::DEFAULT).unwrap_err();
    assert!(
        err.to_string().contains("min.y") && err.to_string().contains("max.y"),
        "{err}"
    );
    let err = q
        .overlapping(
            &Shape::circle(-1.0),
            Transform::IDENTITY,
            QueryFilter::DEFAULT,
        )
        .unwrap_err();
    assert!(err.to_string().contains("radius"), "{err}");
}

#[test]
fn a_box_query_finds_shapes_inside_and_across_it_but_not_beside_it() {
    let mut w = World::default();
    let inside = w
        .add_body(&BodyDef::fixed(Shape::circle(0.5), vec2(1.0, 1.0)))
        .unwrap();
    let across = w
        .add_body(&BodyDef::fixed(Shape::rect(1.0, 1.0), vec2(3.0, 1.0)))
        .unwrap();
    // A disc whose box overlaps the query's corner but which lies beyond it.
    w.add_body(&BodyDef::fixed(Shape::circle(1.0), vec2(3.8, 3.8)))
        .unwrap();
    let q = w.query();
    let b = Aabb {
        min: vec2(0.0, 0.0),
        max: vec2(3.0, 3.0),
    };
    let found: Vec<_> = q
        .in_box(b, QueryFilter::DEFAULT)
        .unwrap()
        .iter()
        .map(|s| s.body)
        .collect();
    assert_eq!(found, vec![inside, across]);
}
