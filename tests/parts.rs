//! Bodies of several shapes: mass properties against integration over the area, the origin and
//! the centre of mass in free flight, resting on two parts, balancing on the centre of mass and
//! not on the origin, filters and materials per shape, joints anchored from the origin (a
//! compound pendulum's period), fast parts against a thin wall, checkpoints, and refusals.

use tiltbox::physics::joint::Revolute;
use tiltbox::physics::{
    vec2, BodyDef, BodyId, Filter, JointDef, JointKind, PartDef, Real, Rot, Shape, Vec2, World,
};

const DT: Real = 1.0 / 60.0;

fn ground(w: &mut World) -> BodyId {
    // Top at y = 0.
    w.add_body(&BodyDef::fixed(Shape::rect(40.0, 1.0), vec2(0.0, -0.5)))
        .unwrap()
}

fn run(w: &mut World, seconds: Real) {
    for _ in 0..(seconds / DT).round() as usize {
        w.step(DT).unwrap();
    }
}

/// An L with a turned tab: a 2 x 0.5 bar (density 2) at the origin, a 0.5 x 1.5 post (density
/// 3) standing on its right end, and a 0.4 x 0.2 tab (density 1) turned 0.5 rad above its left
/// end. No two overlap.
fn l_shape(at: Vec2, angle: Real) -> BodyDef {
    BodyDef::dynamic(Shape::rect(2.0, 0.5), at)
        .with_density(2.0)
        .with_angle(angle)
        .with_part(PartDef::new(Shape::rect(0.5, 1.5), vec2(0.75, 1.0)).with_density(3.0))
        .with_part(
            PartDef::new(Shape::rect(0.4, 0.2), vec2(-0.8, 0.6))
                .with_angle(0.5)
                .with_density(1.0),
        )
}

/// Mass, centre and inertia of the L by summing density over a 2,000 x 2,000 grid of its box
/// (independent of the engine's formulas).
fn integrated_l() -> (f64, [f64; 2], f64) {
    let inside = |x: f64, y: f64| -> f64 {
        let mut d = 0.0;
        if x.abs() <= 1.0 && y.abs() <= 0.25 {
            d += 2.0;
        }
        if (x - 0.75).abs() <= 0.25 && (y - 1.0).abs() <= 0.75 {
            d += 3.0;
        }
        let (c, s) = (0.5f64.cos(), 0.5f64.sin());
        let (dx, dy) = (x + 0.8, y - 0.6);
        let (lx, ly) = (c * dx + s * dy, -s * dx + c * dy);
        if lx.abs() <= 0.2 && ly.abs() <= 0.1 {
            d += 1.0;
        }
        d
    };
    let n = 2000;
    let (x0, x1, y0, y1) = (-1.1, 1.1, -0.3, 1.8);
    let (hx, hy) = ((x1 - x0) / n as f64, (y1 - y0) / n as f64);
    let (mut m, mut mx, mut my, mut j) = (0.0, 0.0, 0.0, 0.0);
    for i in 0..n {
        for k in 0..n {
            let (x, y) = (x0 + (i as f64 + 0.5) * hx, y0 + (k as f64 + 0.5) * hy);
            let dm = inside(x, y) * hx * hy;
            m += dm;
            mx += dm * x;
            my += dm * y;
            j += dm * (x * x + y * y);
        }
    }
    let c = [mx / m, my / m];
    (m, c, j - m * (c[0] * c[0] + c[1] * c[1]))
}

#[test]
fn mass_centre_and_inertia_come_from_the_parts() {
    // Closed form: m = 2 x 1 + 3 x 0.75 + 1 x 0.08 = 4.33 kg. The grid's cells are about 1 mm
    // across, so its sums are within about 0.2 % of the exact ones (edges cut cells).
    let mut w = World::default();
    let b = w.add_body(&l_shape(Vec2::ZERO, 0.0)).unwrap();
    let body = w.body(b).unwrap().clone();
    let (m, c, i) = integrated_l();
    assert!((body.mass() as f64 - 4.33).abs() < 1e-4, "{}", body.mass());
    assert!(
        (body.mass() as f64 - m).abs() / m < 2e-3,
        "{} vs {m}",
        body.mass()
    );
    let lc = body.local_center();
    assert!(
        (lc.x as f64 - c[0]).abs() < 2e-3 && (lc.y as f64 - c[1]).abs() < 2e-3,
        "{lc:?} vs {c:?}"
    );
    assert!(
        (body.inertia() as f64 - i).abs() / i < 3e-3,
        "{} vs {i}",
        body.inertia()
    );
    // Given by total mass instead, the same shares: mass 8.66 kg doubles everything.
    let mut def = l_shape(Vec2::ZERO, 0.0).with_mass(8.66);
    def.parts[0].density = 3.0 / 2.0;
    def.parts[1].density = 1.0 / 2.0;
    let b2 = w.add_body(&def).unwrap();
    let twice = w.body(b2).unwrap();
    assert!((twice.inertia() - 2.0 * body.inertia()).abs() < 1e-4 * body.inertia());
    assert!((twice.local_center() - lc).length() < 1e-6);
}

#[test]
fn the_origin_is_reported_and_the_centre_of_mass_flies_straight() {
    // No gravity, no contact: the centre moves at v exactly, the body turns at w exactly, and
    // the origin is the centre less R(angle) times the local centre (f32 round-off: 1e-4 m).
    let mut w = World::new(Default::default(), Vec2::ZERO).unwrap();
    let origin = vec2(5.0, 5.0);
    let def = l_shape(origin, 0.2)
        .with_velocity(vec2(1.0, 2.0))
        .with_angular_velocity(3.0);
    let b = w.add_body(&def).unwrap();
    let body = w.body(b).unwrap();
    assert_eq!(body.position(), origin);
    let lc = body.local_center();
    let com0 = origin + Rot::from_angle(0.2).rotate(lc);
    assert!((body.center_of_mass() - com0).length() < 1e-5);
    run(&mut w, 1.0);
    let body = w.body(b).unwrap();
    let com = com0 + vec2(1.0, 2.0);
    assert!(
        (body.center_of_mass() - com).length() < 1e-4,
        "{:?}",
        body.center_of_mass()
    );
    assert!((body.angle() - 3.2).abs() < 1e-4, "{}", body.angle());
    let expected = com - Rot::from_angle(3.2).rotate(lc);
    assert!((body.position() - expected).length() < 1e-4);
    assert_eq!(body.transform().p, body.position());
    // A body of one shape: origin and centre are one point.
    let one = w
        .add_body(&BodyDef::dynamic(Shape::circle(0.5), vec2(1.0, 1.0)))
        .unwrap();
    let one = w.body(one).unwrap();
    assert_eq!(one.position(), one.center_of_mass());
    assert_eq!(one.local_center(), Vec2::ZERO);
}

/// A dumbbell: a 2 x 0.1 bar with a disc of radius 0.3 on each end.
fn dumbbell(at: Vec2) -> BodyDef {
    BodyDef::dynamic(Shape::rect(2.0, 0.1), at)
        .with_part(PartDef::new(Shape::circle(0.3), vec2(-1.0, 0.0)))
        .with_part(PartDef::new(Shape::circle(0.3), vec2(1.0, 0.0)))
}

#[test]
fn a_dumbbell_rests_on_both_discs_with_a_contact_each() {
    // Resting: the discs' centres at their radius, 0.3 m, within the contacts' give (a few
    // mm under 9.81 m/s^2; bound 1 cm); one contact per disc, together carrying m g (the
    // solver's force at rest; bound 2 %).
    let mut w = World::default();
    let g = ground(&mut w);
    let b = w.add_body(&dumbbell(vec2(0.0, 1.0))).unwrap();
    run(&mut w, 3.0);
    let body = w.body(b).unwrap();
    assert!(
        (body.position().y - 0.3).abs() < 0.01,
        "{:?}",
        body.position()
    );
    assert!(body.angle().abs() < 0.01);
    let mut shapes = Vec::new();
    let mut force = 0.0;
    for c in w.contacts() {
        assert!(c.body_a == g || c.body_b == g);
        let (mine, ground_shape) = if c.body_b == b {
            (c.shape_b, c.shape_a)
        } else {
            (c.shape_a, c.shape_b)
        };
        assert_eq!(ground_shape, 0);
        shapes.push(mine);
        force += c.points[..c.count]
            .iter()
            .map(|p| p.normal_impulse)
            .sum::<Real>()
            / DT;
    }
    shapes.sort_unstable();
    assert_eq!(
        shapes,
        [1, 2],
        "a contact for each disc (parts 1 and 2), none for the bar"
    );
    let weight = w.body(b).unwrap().mass() * 9.81;
    assert!(
        (force - weight).abs() < 0.02 * weight,
        "{force} vs {weight}"
    );
}

/// A 0.2 x 2 post with its origin at x = `x` standing on a 1 x 0.2 foot whose centre is
/// `foot_x` to the right of it; the foot's sole at y = 0.
fn post_on_foot(x: Real, foot_x: Real) -> BodyDef {
    BodyDef::dynamic(Shape::rect(0.2, 2.0), vec2(x, 1.2))
        .with_part(PartDef::new(Shape::rect(1.0, 0.2), vec2(foot_x, -1.1)))
}

#[test]
fn a_body_balances_on_its_centre_of_mass_not_its_origin() {
    // Foot at 0.55 m: it spans 0.05..1.05; the origin (x = 0) is off it but the centre of
    // mass, 0.2 x 0.55 / 0.6 = 0.183 m, is on it: it stands. Foot at 1.0: it spans 0.5..1.5
    // and the centre (0.333 m) is off it: it falls over.
    let mut w = World::default();
    ground(&mut w);
    let stands = w.add_body(&post_on_foot(0.0, 0.55)).unwrap();
    let falls = w.add_body(&post_on_foot(8.0, 1.0)).unwrap();
    let lc = w.body(stands).unwrap().local_center();
    assert!((lc.x - 0.2 * 0.55 / 0.6).abs() < 1e-5, "{lc:?}");
    run(&mut w, 3.0);
    assert!(w.body(stands).unwrap().angle().abs() < 0.02);
    assert!(w.body(falls).unwrap().angle().abs() > 0.5);
}

#[test]
fn a_part_keeps_its_own_filter_and_material() {
    // The part under the box collides with nothing, so the box rests on its own shape: its
    // centre at 0.25 m (bound 1 cm), not held up by the part at 0.6 m.
    let mut w = World::default();
    ground(&mut w);
    let none = Filter {
        category: 1,
        mask: 0,
        group: 0,
    };
    let b = w
        .add_body(
            &BodyDef::dynamic(Shape::rect(0.5, 0.5), vec2(0.0, 1.0))
                .with_part(PartDef::new(Shape::rect(1.0, 0.2), vec2(0.0, -0.5)).with_filter(none)),
        )
        .unwrap();
    run(&mut w, 2.0);
    let y = w.body(b).unwrap().position().y;
    assert!((y - 0.25).abs() < 0.01, "{y}");

    // Restitution per part: a disc part of restitution 1 on a bar of restitution 0, dropped
    // onto a restitution-1 floor, bounces (mixed sqrt(1 x 1) = 1: well over half its height
    // back); the same body with the disc at 0 does not (sqrt(0 x 1) = 0).
    let bounce = |e: Real| {
        let mut w = World::default();
        let floor = BodyDef::fixed(Shape::rect(40.0, 1.0), vec2(0.0, -0.5)).with_restitution(1.0);
        w.add_body(&floor).unwrap();
        let def = BodyDef::dynamic(Shape::rect(0.2, 0.2), vec2(0.0, 3.0))
            .with_part(PartDef::new(Shape::circle(0.3), vec2(0.0, -0.4)).with_restitution(e));
        let b = w.add_body(&def).unwrap();
        let mut top_after_bounce: Real = 0.0;
        let mut landed = false;
        for _ in 0..150 {
            w.step(DT).unwrap();
            let body = w.body(b).unwrap();
            landed |= body.linear_velocity().y > 0.5;
            if landed {
                top_after_bounce = top_after_bounce.max(body.position().y);
            }
        }
        top_after_bounce
    };
    assert!(bounce(1.0) > 2.0, "{}", bounce(1.0));
    assert!(bounce(0.0) < 1.0, "{}", bounce(0.0));
}

#[test]
fn a_compound_pendulum_swings_about_its_origin_with_the_closed_form_period() {
    // A 0.05 m disc at the origin hinged to the world there, and a 0.2 m disc 1 m below it.
    // T = 2 pi sqrt(I_pivot / (m g d)), I_pivot = I_centre + m d^2, times 1 + theta0^2 / 16
    // for the 0.1 rad swing. Bound 1 %: the soft step's 60 Hz hinge and its round-off shift
    // a 2 s period by well under that; a hinge at the centre of mass would not swing at all.
    let mut w = World::default();
    let def = BodyDef::dynamic(Shape::circle(0.05), Vec2::ZERO)
        .with_angle(0.1)
        .with_part(PartDef::new(Shape::circle(0.2), vec2(0.0, -1.0)));
    let b = w.add_body(&def).unwrap();
    w.add_joint(&JointDef::new(
        JointKind::Revolute(Revolute::free()),
        None,
        b,
    ))
    .unwrap();
    let body = w.body(b).unwrap();
    let (m, d) = (body.mass(), body.local_center().length());
    let i_pivot = body.inertia() + m * d * d;
    let period = 2.0 * std::f64::consts::PI * (i_pivot as f64 / (m * 9.81 * d) as f64).sqrt();
    let period = period * (1.0 + 0.01 / 16.0);
    let mut crossings = Vec::new();
    let mut last = w.body(b).unwrap().angle();
    for k in 1..=600 {
        w.step(DT).unwrap();
        let a = w.body(b).unwrap().angle();
        if last > 0.0 && a <= 0.0 {
            crossings.push((k as f64 - 1.0 + last as f64 / (last - a) as f64) * DT as f64);
        }
        last = a;
        // The hinge holds the origin where it was.
        assert!(w.body(b).unwrap().position().length() < 2e-3);
    }
    assert!(crossings.len() >= 3, "{crossings:?}");
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    assert!(
        (measured - period).abs() < 0.01 * period,
        "{measured} s vs {period} s"
    );
}

#[test]
fn a_fast_body_does_not_pass_a_thin_wall_with_its_leading_part() {
    // 200 m/s, 3.3 m a step, a 5 cm plate leading 0.6 m ahead of a small box, at a 10 cm
    // wall: every shape ends on the near side (the plate's far face within twice the linear
    // slop of the wall's near face, 9.95 m).
    let mut w = World::new(Default::default(), Vec2::ZERO).unwrap();
    w.add_body(&BodyDef::fixed(Shape::rect(0.1, 4.0), vec2(10.0, 0.0)))
        .unwrap();
    let def = BodyDef::dynamic(Shape::rect(0.2, 0.2), Vec2::ZERO)
        .with_velocity(vec2(200.0, 0.0))
        .with_part(PartDef::new(Shape::rect(0.05, 1.0), vec2(0.6, 0.0)));
    let b = w.add_body(&def).unwrap();
    let slop = w.settings().linear_slop;
    for _ in 0..20 {
        w.step(DT).unwrap();
        let body = w.body(b).unwrap();
        let front = body.transform().apply(vec2(0.625, 0.0)).x;
        assert!(front < 9.95 + 2.0 * slop, "{front}");
    }
}

#[test]
fn checkpoints_carry_parts_and_continue_bit_identically() {
    let mut w = World::default();
    ground(&mut w);
    for k in 0..4 {
        w.add_body(&dumbbell(vec2(-6.0 + 3.0 * k as Real, 1.0 + k as Real)))
            .unwrap();
        w.add_body(&l_shape(vec2(-6.0 + 3.0 * k as Real, 4.0 + k as Real), 0.3))
            .unwrap();
    }
    run(&mut w, 0.75);
    let mut copy = World::import_state(&w.export_state()).unwrap();
    assert_eq!(copy.state_hash(), w.state_hash());
    for _ in 0..90 {
        w.step(DT).unwrap();
        copy.step(DT).unwrap();
        assert_eq!(copy.state_hash(), w.state_hash());
    }
    let parts = |w: &World| w.bodies().map(|b| b.parts().len()).collect::<Vec<_>>();
    assert_eq!(parts(&copy), parts(&w));
}

#[test]
fn bad_parts_are_refused_naming_the_part_and_nothing_is_added() {
    let mut w = World::default();
    let bad = BodyDef::dynamic(Shape::circle(0.5), Vec2::ZERO)
        .with_part(PartDef::new(Shape::circle(0.2), vec2(1.0, 0.0)))
        .with_part(PartDef::new(Shape::circle(0.2), vec2(2.0, 0.0)).with_density(-1.0));
    let e = w.add_body(&bad).unwrap_err().to_string();
    assert!(e.contains("parts[1].density") && e.contains("-1"), "{e}");
    let e = w
        .add_body(
            &BodyDef::dynamic(Shape::circle(0.5), Vec2::ZERO)
                .with_part(PartDef::new(Shape::circle(-0.2), Vec2::ZERO)),
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("parts[0].shape.radius"), "{e}");
    let e = w
        .add_body(
            &BodyDef::dynamic(Shape::circle(0.5), Vec2::ZERO)
                .with_part(PartDef::new(Shape::circle(0.2), vec2(Real::NAN, 0.0))),
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("parts[0].offset.x"), "{e}");
    let segment = Shape::Segment(Box::new(tiltbox::physics::Segment::new(
        vec2(-1.0, 0.0),
        vec2(1.0, 0.0),
        0.0,
    )));
    let e = w
        .add_body(
            &BodyDef::dynamic(Shape::circle(0.5), Vec2::ZERO)
                .with_part(PartDef::new(segment, Vec2::ZERO)),
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("mass") && e.contains("segment"), "{e}");
    assert_eq!(w.body_count(), 0);
}
