//! Contact, hit and sensor events against free fall's closed forms, and what asks for them.

use tiltbox::physics::*;

const DT: Real = 1.0 / 60.0;
const G: Real = 9.81;

fn ground(w: &mut World) -> BodyId {
    w.add_body(&BodyDef::fixed(Shape::rect(40.0, 1.0), vec2(0.0, -0.5)))
        .unwrap()
}

/// How far a body falls from rest in `k` steps of the default soft step: semi-implicit Euler
/// over 4 substeps of dt / 4, g dt^2 k (k + 1/4) / 2.
fn fall(k: usize) -> Real {
    G * DT * DT * k as Real * (k as Real + 0.25) / 2.0
}

/// The step (counted from 0) in which a body falling from rest has fallen `h`.
fn landing_step(h: Real) -> usize {
    (0..).find(|&k| fall(k + 1) >= h).unwrap()
}

fn flags(contact_events: bool, hit_events: bool, sensor: bool) -> ShapeFlags {
    ShapeFlags {
        contact_events,
        hit_events,
        sensor,
    }
}

/// A ball dropped from rest with its lowest point `drop` above the ground: the step at which
/// it first reports touching, and every event of the run.
fn drop_ball(drop: Real, f: ShapeFlags, steps: usize) -> (World, BodyId, Vec<(usize, StepEvents)>) {
    let mut w = World::default();
    ground(&mut w);
    let ball = BodyDef::dynamic(Shape::circle(0.25), vec2(0.0, 0.25 + drop)).with_flags(f);
    let ball = w.add_body(&ball).unwrap();
    let mut log = Vec::new();
    for k in 0..steps {
        w.step(DT).unwrap();
        if !w.events().is_empty() {
            log.push((k, w.events().clone()));
        }
    }
    (w, ball, log)
}

#[test]
fn a_dropped_ball_begins_touching_when_free_fall_says_and_not_again_at_rest() {
    // Dropped 2 m, it reaches the ground at t = sqrt(2 h / g) = 0.639 s, in step 37 (counted
    // from 0, of 1/60 s). Touching is judged at the step's start, so the first step that
    // starts within the slop is the one after it lands, or the one after that.
    let (w, ball, log) = drop_ball(2.0, flags(true, false, false), 240);
    let begins: Vec<_> = log
        .iter()
        .filter(|(_, e)| !e.contact_begin.is_empty())
        .collect();
    assert_eq!(begins.len(), 1, "{log:?}");
    let (k, e) = begins[0];
    let landing = landing_step(2.0);
    assert!(
        (landing + 1..=landing + 2).contains(k),
        "began at step {k}, landed in {landing}"
    );
    assert_eq!(e.contact_begin[0].b.body, ball);
    // It rests (and sleeps) without an end.
    assert!(log.iter().all(|(_, e)| e.contact_end.is_empty()), "{log:?}");
    assert!(!w.body(ball).unwrap().is_awake());
}

#[test]
fn removing_a_touching_body_ends_its_contact() {
    let (mut w, ball, _) = drop_ball(0.5, flags(true, false, false), 120);
    w.remove_body(ball).unwrap();
    w.step(DT).unwrap();
    let ends = &w.events().contact_end;
    assert_eq!(ends.len(), 1);
    assert_eq!(ends[0].b.body, ball);
    w.step(DT).unwrap();
    assert!(w.events().is_empty());
}

#[test]
fn shapes_that_did_not_ask_report_nothing() {
    let (_, _, log) = drop_ball(2.0, ShapeFlags::default(), 120);
    assert!(log.is_empty(), "{log:?}");
}

#[test]
fn a_hit_reports_the_approach_speed_of_free_fall() {
    // Dropped 2 m: it meets the ground at sqrt(2 g h) = 6.26 m/s. The hit reports the speed at
    // the start of the step it lands in, at most one step's g dt = 0.16 m/s less, and that
    // step may come one early: semi-implicit Euler has fallen g dt t / 2 (5 cm) more than
    // free fall by t = 0.64 s. So within 2 g dt = 0.33 m/s (5 %) below. As
    // Box2D's, a hit is reported every step a pushing point still approaches faster than the
    // threshold: the soft contact takes a step or two to stop the ball, each slower, then
    // nothing at rest.
    let (_, ball, log) = drop_ball(2.0, flags(false, true, false), 240);
    let hits: Vec<_> = log
        .iter()
        .flat_map(|(k, e)| e.hits.iter().map(move |h| (*k, *h)))
        .collect();
    let (first, hit) = hits[0];
    assert!(
        hits.windows(2)
            .all(|p| p[1].0 == p[0].0 + 1 && p[1].1.approach_speed < p[0].1.approach_speed),
        "one impact, slowing: {hits:?}"
    );
    // It is reported in the step the ball comes within the speculative distance (2 cm) of the
    // ground, where the soft contact starts to push.
    assert!(hits.len() <= 3, "{hits:?}");
    assert!(
        fall(first) < 2.0 && fall(first + 1) >= 2.0 - 0.02,
        "{hits:?}"
    );
    // Exactly the speed semi-implicit Euler gives at that step's start, g dt k.
    assert!(
        (hit.approach_speed - G * DT * first as Real).abs() < 1e-3,
        "{hit:?}"
    );
    let expected = (2.0 * G * 2.0).sqrt();
    assert!(
        hit.approach_speed <= expected && hit.approach_speed >= expected - 2.0 * G * DT,
        "{} against {expected}",
        hit.approach_speed
    );
    assert_eq!(hit.b.body, ball);
    assert!((hit.normal - vec2(0.0, 1.0)).length() < 1e-4);
    // The point is the contact's (between the surfaces, as Box2D's), from a ball whose bottom
    // was less than the step's travel v dt + g dt^2 = 0.104 m above the ground.
    assert!(
        (0.0..0.104).contains(&hit.point.y) && hit.point.x.abs() < 1e-3,
        "{:?}",
        hit.point
    );
    // From 2 cm it lands at 0.63 m/s, under the 1 m/s threshold: no hit.
    let (_, _, log) = drop_ball(0.02, flags(false, true, false), 120);
    assert!(log.iter().all(|(_, e)| e.hits.is_empty()), "{log:?}");
}

#[test]
fn a_sensor_reports_a_ball_falling_through_it_and_does_not_touch_it() {
    let mut w = World::default();
    ground(&mut w);
    // A sensor 1 m tall whose top is 5 m up; a ball of radius 0.25 dropped from 10 m.
    let zone =
        BodyDef::fixed(Shape::rect(4.0, 1.0), vec2(0.0, 4.5)).with_flags(flags(false, false, true));
    let zone = w.add_body(&zone).unwrap();
    let ball = w
        .add_body(&BodyDef::dynamic(Shape::circle(0.25), vec2(0.0, 10.0)))
        .unwrap();
    let (mut entered, mut left) = (None, None);
    for k in 1..=150 {
        w.step(DT).unwrap();
        let e = w.events();
        if let Some(s) = e.sensor_begin.first() {
            assert_eq!((s.sensor.body, s.visitor.body), (zone, ball));
            entered = Some(k);
        }
        if let Some(s) = e.sensor_end.first() {
            assert_eq!((s.sensor.body, s.visitor.body), (zone, ball));
            left = Some(k);
        }
    }
    // Free fall (semi-implicit Euler: y_k = y0 - g dt^2 k (k + 1) / 2) untouched by the sensor:
    // the ball's bottom passes the sensor's top (5 m, 4.75 m of fall) and its top passes the
    // sensor's bottom (4 m, 6.25 m of fall), each reported at the end of the step it happens.
    let step_of = |fall: Real| {
        (1..)
            .find(|&k| G * DT * DT * (k * (k + 1)) as Real / 2.0 > fall)
            .unwrap()
    };
    assert_eq!(entered, Some(step_of(4.75)));
    assert_eq!(left, Some(step_of(6.25)));
}

#[test]
fn a_sensor_sees_sleeping_bodies_and_its_filter_chooses_what() {
    let mut w = World::default();
    ground(&mut w);
    let crate_ = w
        .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 0.5)))
        .unwrap();
    let ghost = Filter {
        category: 2,
        ..Filter::DEFAULT
    };
    let other = BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(3.0, 0.5)).with_filter(ghost);
    w.add_body(&other).unwrap();
    for _ in 0..120 {
        w.step(DT).unwrap();
    }
    assert!(!w.body(crate_).unwrap().is_awake());
    // A kinematic sensor sweeps over both; it sees only category 1.
    let sees_one = Filter {
        mask: 1,
        ..Filter::DEFAULT
    };
    // (Clear of the ground: from 0.1 m to 3.1 m up.)
    let sweep = BodyDef::kinematic(Shape::rect(0.5, 3.0), vec2(-3.0, 1.6), vec2(2.0, 0.0))
        .with_filter(sees_one)
        .with_flags(flags(false, false, true));
    let sweep = w.add_body(&sweep).unwrap();
    let mut seen = Vec::new();
    for _ in 0..240 {
        w.step(DT).unwrap();
        seen.extend(
            w.events()
                .sensor_begin
                .iter()
                .map(|s| (s.sensor.body, s.visitor.body)),
        );
    }
    assert_eq!(seen, vec![(sweep, crate_)]);
    assert!(
        !w.body(crate_).unwrap().is_awake(),
        "a sensor wakes nothing"
    );
}

#[test]
fn rays_and_overlaps_pass_through_sensors() {
    let mut w = World::default();
    let wall = ground(&mut w);
    let zone =
        BodyDef::fixed(Shape::rect(4.0, 4.0), vec2(0.0, 3.0)).with_flags(flags(false, false, true));
    w.add_body(&zone).unwrap();
    let q = w.query();
    let hit = q
        .ray_closest(vec2(0.0, 10.0), vec2(0.0, -20.0), QueryFilter::DEFAULT)
        .unwrap()
        .unwrap();
    assert_eq!(hit.shape.body, wall);
    assert!((hit.point.y - 0.0).abs() < 1e-5);
    assert!(q
        .at_point(vec2(0.0, 3.0), QueryFilter::DEFAULT)
        .unwrap()
        .is_empty());
}

#[test]
fn flags_survive_a_checkpoint() {
    let mut w = World::default();
    ground(&mut w);
    let f = flags(true, true, false);
    let part =
        PartDef::new(Shape::circle(0.2), vec2(1.0, 0.0)).with_flags(flags(false, false, true));
    let def = BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 3.0))
        .with_flags(f)
        .with_part(part);
    let id = w.add_body(&def).unwrap();
    let back = World::import_state(&w.export_state()).unwrap();
    let body = back.body(id).unwrap();
    assert_eq!(body.flags(), f);
    assert!(body.parts()[0].flags.sensor);
}
