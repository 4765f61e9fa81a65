//! Terrain and motion (issue 17): segments and chains without ghost collisions, kinematic
//! bodies that carry and push. Each test compares against a closed form and says where its
//! tolerance comes from.

use tiltbox::physics::{vec2, BodyDef, BodyId, Real, Segment, Settings, Shape, Vec2, World};

const DT: Real = 1.0 / 60.0;

fn world(g: Vec2) -> World {
    World::new(Settings::default(), g).unwrap()
}

fn add_chain(w: &mut World, points: &[Vec2], closed: bool, one_sided: bool, friction: Real) {
    for def in BodyDef::chain(points, closed, one_sided).unwrap() {
        w.add_body(&def.with_friction(friction)).unwrap();
    }
}

/// The kinematic body `id` was never slowed: it is at x = `x` (to 1 mm, f32 sums over a few
/// hundred steps) and still moves at `v`.
fn assert_unslowed(w: &World, id: BodyId, x: Real, v: Vec2) {
    let b = w.body(id).unwrap();
    assert!((b.position().x - x).abs() < 1e-3, "at {}", b.position().x);
    assert_eq!(b.linear_velocity(), v);
}

fn steps(w: &mut World, seconds: Real, mut each: impl FnMut(&World)) {
    for _ in 0..(seconds / DT).round() as usize {
        w.step(DT).unwrap();
        each(w);
    }
}

/// The tiled floor: 20 tiles 2 m wide, their tops at y = 0, as one chain of 21
/// points. A frictionless 0.5 m box slides along it at 3 m/s for 10 s (30 m, over 15 seams).
#[test]
fn frictionless_box_slides_over_a_tiled_chain_at_constant_speed_without_tilting() {
    let mut w = world(vec2(0.0, -9.81));
    let points: Vec<Vec2> = (0..=20).map(|i| vec2(2.0 * i as Real, 0.0)).collect();
    add_chain(&mut w, &points, false, true, 0.0);
    let id = w
        .add_body(
            &BodyDef::dynamic(Shape::rect(0.5, 0.5), vec2(2.0, 0.25))
                .with_friction(0.0)
                .with_velocity(vec2(3.0, 0.0)),
        )
        .unwrap();
    let (mut worst_speed, mut worst_tilt): (Real, Real) = (0.0, 0.0);
    steps(&mut w, 10.0, |w| {
        let b = w.body(id).unwrap();
        worst_speed = worst_speed.max((b.linear_velocity().x - 3.0).abs() / 3.0);
        worst_tilt = worst_tilt.max(b.angle().abs());
    });
    let b = w.body(id).unwrap();
    println!("tiled chain: speed change {worst_speed:e} relative, tilt {worst_tilt:e} rad");
    // The bound: speed within 1e-4 relative over 10 s (with no friction nothing may
    // slow it; f32 keeps 3 m/s to ~2e-7). "Never tilts": 1e-4 rad, far below the 0.23 rad the
    // box tiles gave, and above f32 round-off of a resting box's angle.
    assert!(worst_speed < 1e-4, "speed off by {worst_speed} relative");
    assert!(worst_tilt < 1e-4, "tilted {worst_tilt} rad");
    assert!(
        (b.position().x - 32.0).abs() < 0.01,
        "x = {}",
        b.position().x
    );
}

/// A disc rolling without slipping down a slope accelerates at a = g sin(theta) / (1 + I/(m r^2))
/// = 2/3 g sin(theta). Made of 100 short chain pieces or one long segment, the slope must
/// give the same acceleration within 1 % (the bound).
#[test]
fn disc_rolls_down_a_100_piece_chain_as_down_one_slope() {
    let theta: Real = 20.0_f32.to_radians() as Real;
    let down = vec2(theta.cos(), -theta.sin());
    let length = 50.0;
    let r = 0.25;
    let roll = |pieces: usize| -> Real {
        let mut w = world(vec2(0.0, -9.81));
        let points: Vec<Vec2> = (0..=pieces)
            .map(|i| down * (length * i as Real / pieces as Real))
            .collect();
        add_chain(&mut w, &points, false, false, 0.6);
        let normal = vec2(theta.sin(), theta.cos());
        let start = down * 1.0 + normal * r;
        let id = w
            .add_body(&BodyDef::dynamic(Shape::circle(r), start).with_friction(0.6))
            .unwrap();
        // 3 s: about 20 m down the slope, over some 40 joints.
        let t = 3.0;
        steps(&mut w, t, |_| {});
        let travelled = (w.body(id).unwrap().position() - start).dot(down);
        2.0 * travelled / (t * t)
    };
    let one = roll(1);
    let many = roll(100);
    let closed_form = 2.0 / 3.0 * 9.81 * theta.sin();
    println!("rolling: 100 pieces {many} m/s^2, one slope {one} m/s^2, closed form {closed_form}");
    assert!(
        (many - one).abs() < 0.01 * one,
        "100 pieces: {many} m/s^2, one slope: {one} m/s^2"
    );
    // Semi-implicit Euler over 180 steps reaches s = a t^2/2 (1 + dt/t) (0.6 % more here),
    // and the soft contact lets the disc sink a little: 2 % covers both.
    assert!(
        (one - closed_form).abs() < 0.02 * closed_form,
        "one slope: {one} m/s^2, closed form {closed_form} m/s^2"
    );
}

/// A box put at rest on a kinematic platform that moves at a constant 1 m/s is brought up to
/// speed by friction (0.6; slipping lasts v / (mu g) = 0.17 s) and from then on carried: it
/// moves with the platform, drifting less than 1 mm over 5 s (without friction it would stay
/// behind, 5 m in 5 s).
#[test]
fn box_rides_a_kinematic_platform_without_drifting() {
    let mut w = world(vec2(0.0, -9.81));
    let v = vec2(1.0, 0.0);
    let platform = w
        .add_body(&BodyDef::kinematic(
            Shape::rect(4.0, 0.2),
            vec2(0.0, 0.0),
            v,
        ))
        .unwrap();
    let rider = w
        .add_body(&BodyDef::dynamic(Shape::rect(0.5, 0.5), vec2(0.0, 0.35)))
        .unwrap();
    let offset =
        |w: &World| w.body(rider).unwrap().position() - w.body(platform).unwrap().position();
    steps(&mut w, 1.0, |_| {});
    let settled = offset(&w);
    let mut drift: Real = 0.0;
    steps(&mut w, 5.0, |w| {
        drift = drift.max((offset(w).x - settled.x).abs())
    });
    println!("platform: rider drift {drift:e} m over 5 s");
    // The platform is never slowed: x = v t exactly up to f32 sums (330 steps x ulp(5)).
    assert_unslowed(&w, platform, 6.0, v);
    assert!(drift < 1e-3, "rider drifted {drift} m");
    assert!(
        w.body(rider).unwrap().is_awake(),
        "a carried body must not sleep"
    );
}

/// A kinematic wall moving at 1 m/s into a stack of five boxes pushes the whole stack along
/// and is not slowed: its position stays x0 + v t, and the boxes end up in front of it,
/// moving with it.
#[test]
fn kinematic_wall_pushes_a_stack_unslowed() {
    let mut w = world(vec2(0.0, -9.81));
    w.add_body(&BodyDef::fixed(Shape::rect(40.0, 1.0), vec2(0.0, -0.5)))
        .unwrap();
    let stack: Vec<BodyId> = (0..5)
        .map(|i| {
            w.add_body(&BodyDef::dynamic(
                Shape::rect(0.5, 0.5),
                vec2(0.0, 0.25 + 0.5 * i as Real),
            ))
            .unwrap()
        })
        .collect();
    steps(&mut w, 1.0, |_| {});
    let wall = w
        .add_body(&BodyDef::kinematic(
            Shape::rect(0.2, 3.0),
            vec2(-1.0, 1.5),
            vec2(1.0, 0.0),
        ))
        .unwrap();
    let mut deepest: Real = 0.0;
    let mut overlap = |w: &World| {
        let front = w.body(wall).unwrap().position().x + 0.1;
        for &id in &stack {
            let back = w.body(id).unwrap().position().x - 0.25;
            deepest = deepest.max(front - back);
        }
    };
    steps(&mut w, 2.0, &mut overlap);
    let before: Vec<Real> = stack
        .iter()
        .map(|&id| w.body(id).unwrap().position().x)
        .collect();
    steps(&mut w, 1.0, &mut overlap);
    println!("push: deepest overlap {deepest:e} m");
    // Never slowed: x = x0 + v t up to f32 sums (180 steps x ulp(2)).
    assert_unslowed(&w, wall, 2.0, vec2(1.0, 0.0));
    for (&id, x0) in stack.iter().zip(before) {
        let b = w.body(id).unwrap();
        // Pushed along at the wall's speed over the last second: the boxes cover 1 m within
        // 2 cm (the contact's soft give as the ground's friction pulls back).
        let moved = b.position().x - x0;
        println!("push: box {} moved {moved} m in the last second", b.id());
        assert!(
            (moved - 1.0).abs() < 0.02,
            "box {} moved {moved} m in 1 s",
            b.id()
        );
        assert!(
            b.position().x > 2.0,
            "box {} at x = {}",
            b.id(),
            b.position().x
        );
    }
    // The soft contact lets the wall sink into the boxes a little, never through: 2 cm.
    assert!(deepest < 0.02, "wall overlapped a box by {deepest} m");
}

/// Bodies inside a closed one-sided chain (a counter-clockwise octagon, open side inwards)
/// stay inside while gravity turns through all four directions, 1.5 s each, twice.
#[test]
fn bodies_inside_a_closed_chain_stay_inside_under_gravity_flips() {
    let mut w = world(vec2(0.0, -9.81));
    let radius = 5.0;
    let octagon: Vec<Vec2> = (0..8)
        .map(|k| {
            let a = (k as Real + 0.5) * std::f32::consts::FRAC_PI_4 as Real;
            vec2(radius * a.cos(), radius * a.sin())
        })
        .collect();
    add_chain(&mut w, &octagon, true, true, 0.4);
    let mut inside = Vec::new();
    for i in 0..5 {
        for j in 0..4 {
            let p = vec2(-2.0 + i as Real, -1.5 + j as Real);
            let shape = if (i + j) % 2 == 0 {
                Shape::rect(0.5, 0.4)
            } else {
                Shape::circle(0.3)
            };
            inside.push(w.add_body(&BodyDef::dynamic(shape, p)).unwrap());
        }
    }
    // How far inside the wall each centre keeps: its distance to the nearest edge line.
    let clearance = |p: Vec2| {
        (0..8)
            .map(|k| {
                let (a, b) = (octagon[k], octagon[(k + 1) % 8]);
                let e = (b - a).normalize();
                vec2(-e.y, e.x).dot(p - a)
            })
            .fold(Real::INFINITY, Real::min)
    };
    let mut closest = Real::INFINITY;
    for g in [(0.0, 9.81), (9.81, 0.0), (0.0, -9.81), (-9.81, 0.0)]
        .into_iter()
        .cycle()
        .take(8)
    {
        w.set_gravity(vec2(g.0, g.1)).unwrap();
        steps(&mut w, 1.5, |w| {
            for &id in &inside {
                closest = closest.min(clearance(w.body(id).unwrap().position()));
            }
        });
    }
    println!("closed chain: closest centre {closest} m from the wall");
    // Every centre stays at least its smallest half size (0.2 m for the boxes, 0.3 m for the
    // discs) from the wall, less 5 cm for a soft contact's overlap at landing.
    assert!(
        closest > 0.15,
        "a centre came within {closest} m of the wall"
    );
}

/// A one-sided segment lets a body through from below (a platform jumped through) and holds
/// it from above; a two-sided one holds it from both sides.
#[test]
fn one_sided_segments_push_only_to_their_left() {
    for (one_sided, passes) in [(true, true), (false, false)] {
        let mut w = world(vec2(0.0, -9.81));
        let mut s = Segment::new(vec2(-2.0, 0.0), vec2(2.0, 0.0), 0.0);
        s.one_sided = one_sided;
        w.add_body(&BodyDef::fixed(Shape::Segment(Box::new(s)), vec2(0.0, 2.0)))
            .unwrap();
        // Thrown up from below at 8 m/s: it would rise 3.3 m, through the platform at 2 m.
        let id = w
            .add_body(
                &BodyDef::dynamic(Shape::circle(0.25), vec2(0.0, 0.0))
                    .with_velocity(vec2(0.0, 8.0)),
            )
            .unwrap();
        steps(&mut w, 3.0, |_| {});
        let y = w.body(id).unwrap().position().y;
        if passes {
            // Through, then landed on top: its centre rests one radius above the line.
            assert!((y - 2.25).abs() < 0.01, "one-sided: y = {y}");
        } else {
            assert!(y < 2.0, "two-sided: y = {y}");
        }
    }
}

/// A box asleep on a kinematic platform at rest wakes when the platform starts moving, and
/// rides along; the platform itself never sleeps.
#[test]
fn a_kinematic_body_wakes_what_it_carries_when_it_moves() {
    let mut w = world(vec2(0.0, -9.81));
    let platform = w
        .add_body(&BodyDef::kinematic(
            Shape::rect(4.0, 0.2),
            Vec2::ZERO,
            Vec2::ZERO,
        ))
        .unwrap();
    let rider = w
        .add_body(&BodyDef::dynamic(Shape::rect(0.5, 0.5), vec2(0.0, 0.35)))
        .unwrap();
    steps(&mut w, 3.0, |_| {});
    assert!(
        !w.body(rider).unwrap().is_awake(),
        "the rider should be asleep by now"
    );
    w.set_velocity(platform, vec2(0.0, 0.5), 0.0).unwrap();
    steps(&mut w, 2.0, |_| {});
    let b = w.body(rider).unwrap();
    assert!(b.is_awake());
    // Lifted 1 m with the platform: 0.35 + 1.0, within the soft contact's sag (5 mm).
    assert!(
        (b.position().y - 1.35).abs() < 5e-3,
        "rider at y = {}",
        b.position().y
    );
    assert!(w.body(platform).unwrap().is_awake());
}

/// Segments refuse being dynamic, and a kinematic body takes no mass.
#[test]
fn segments_are_static_or_kinematic_only() {
    let mut w = world(vec2(0.0, -9.81));
    let s = Shape::Segment(Box::new(Segment::new(vec2(0.0, 0.0), vec2(1.0, 0.0), 0.1)));
    let e = w
        .add_body(&BodyDef::dynamic(s.clone(), Vec2::ZERO))
        .unwrap_err();
    assert!(
        e.to_string().contains("mass must be static or kinematic"),
        "{e}"
    );
    assert!(w
        .add_body(&BodyDef::kinematic(s, Vec2::ZERO, vec2(1.0, 0.0)))
        .is_ok());
    let short = Shape::Segment(Box::new(Segment::new(vec2(0.0, 0.0), vec2(0.0, 1e-6), 0.0)));
    let e = w.add_body(&BodyDef::fixed(short, Vec2::ZERO)).unwrap_err();
    assert!(e.to_string().contains("shape.b"), "{e}");
}

/// The stiff suite's "slide across a tiled floor": as one chain it must pass; as 20 boxes it
/// documents the ghost collision (it stays finite and on the floor, and it does lose speed
/// and tilt: if it ever stopped snagging, the case's note would be wrong).
#[cfg(feature = "measure")]
#[test]
fn stiff_suite_slides_across_a_tiled_floor() {
    use tiltbox::measure::accuracy::extreme;
    let chain = extreme::tiled_floor_chain(&Settings::default());
    println!("{}", chain.summary());
    assert!(chain.passed, "{}", chain.summary());
    let boxes = extreme::tiled_floor_boxes(&Settings::default());
    println!("{}", boxes.summary());
    assert!(boxes.passed, "{}", boxes.summary());
    let lost = boxes.value("largest speed change (relative)").unwrap();
    assert!(
        lost > 0.01,
        "tiles as boxes no longer snag: {}",
        boxes.summary()
    );
}

/// A kinematic body at rest is ground to everything else: a stack with a 200:1 mass ratio
/// (which adaptive stiffness solves in its top tier) standing on a kinematic platform steps
/// bit for bit like the same stack on a static one. So the solver, the islands and the tiers'
/// mass and load ratios all treat it as they treat a static body.
#[test]
fn a_resting_kinematic_body_is_treated_like_a_static_one() {
    let run = |platform: BodyDef| -> Vec<(Vec2, Real)> {
        let settings = Settings {
            enable_sleep: false,
            ..Settings::default()
        };
        let mut w = World::new(settings, vec2(0.0, -9.81)).unwrap();
        w.add_body(&platform).unwrap();
        let ids = [(0.25, 1.0), (0.75, 200.0), (1.25, 1.0)].map(|(y, m)| {
            w.add_body(&BodyDef::dynamic(Shape::rect(0.5, 0.5), vec2(0.01, y + 0.1)).with_mass(m))
                .unwrap()
        });
        steps(&mut w, 2.0, |_| {});
        ids.iter()
            .map(|&id| {
                let b = w.body(id).unwrap();
                (b.position(), b.angle())
            })
            .collect()
    };
    let shape = Shape::rect(4.0, 0.2);
    let on_static = run(BodyDef::fixed(shape.clone(), vec2(0.0, -0.1)));
    let on_kinematic = run(BodyDef::kinematic(shape, vec2(0.0, -0.1), Vec2::ZERO));
    assert_eq!(on_static, on_kinematic);
}
