//! Islands and sleep: resting islands sleep; touching, pushing, removing and tilting wake them.
#![cfg(feature = "measure")]

use tiltbox::measure::cases::{ground, stack};
use tiltbox::physics::{vec2, BodyDef, BodyId, Real, Settings, Shape, World};

const DT: Real = 1.0 / 60.0;

fn resting_stack(n: usize) -> (World, BodyId, Vec<BodyId>) {
    let mut w = World::new(Settings::default(), vec2(0.0, -9.81)).unwrap();
    let g = ground(&mut w, 0.0, 40.0, 1.0).unwrap();
    let ids = stack(&mut w, n, 1.0, 0.0, 0.0).unwrap();
    // Box2D's rule: below 0.05 m/s for 0.5 s; the stack settles within a second.
    for _ in 0..120 {
        w.step(DT).unwrap();
    }
    (w, g, ids)
}

#[test]
fn a_resting_stack_falls_asleep_and_stays_put() {
    let (mut w, _, ids) = resting_stack(5);
    assert_eq!(w.awake_count(), 0, "all five boxes asleep after 2 s");
    let before: Vec<_> = ids
        .iter()
        .map(|&id| w.body(id).unwrap().position())
        .collect();
    for _ in 0..60 {
        w.step(DT).unwrap();
    }
    for (id, p) in ids.iter().zip(before) {
        assert_eq!(
            w.body(*id).unwrap().position(),
            p,
            "a sleeping body does not move at all"
        );
        assert!(!w.body(*id).unwrap().is_awake());
    }
    assert!(
        w.contact_count() >= 5,
        "sleeping contacts are kept for warm starting"
    );
}

#[test]
fn tilting_gravity_wakes_everything_and_the_stack_slides() {
    let (mut w, _, ids) = resting_stack(3);
    assert_eq!(w.awake_count(), 0);
    w.set_gravity(vec2(-9.81, -1.0)).unwrap(); // nearly sideways: friction 0.6 cannot hold
    assert_eq!(w.awake_count(), 3);
    let x0 = w.body(ids[0]).unwrap().position().x;
    for _ in 0..30 {
        w.step(DT).unwrap();
    }
    assert!(
        w.body(ids[0]).unwrap().position().x < x0 - 0.05,
        "the stack slid left"
    );
    // Setting the same gravity again is not a change and wakes nothing.
    let (mut w2, _, _) = resting_stack(2);
    w2.set_gravity(vec2(0.0, -9.81)).unwrap();
    assert_eq!(w2.awake_count(), 0);
}

#[test]
fn a_body_landing_on_a_sleeping_stack_wakes_its_island() {
    let (mut w, _, ids) = resting_stack(4);
    let dropped = w
        .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 6.0)))
        .unwrap();
    assert_eq!(w.awake_count(), 1, "only the new body is awake");
    let mut woke = false;
    for _ in 0..60 {
        w.step(DT).unwrap();
        woke |= ids.iter().all(|&id| w.body(id).unwrap().is_awake());
    }
    assert!(woke, "the whole stack woke when the box arrived");
    let top = w.body(dropped).unwrap().position().y;
    assert!(
        (top - 4.5).abs() < 0.05,
        "the new box rests on top of the stack: y = {top}"
    );
}

#[test]
fn an_impulse_wakes_the_island_of_the_body_it_hits() {
    let (mut w, _, ids) = resting_stack(3);
    w.apply_impulse(ids[2], vec2(3.0, 0.0)).unwrap();
    assert!(
        ids.iter().all(|&id| w.body(id).unwrap().is_awake()),
        "the whole island wakes"
    );
    assert!(
        w.body(ids[2]).unwrap().linear_velocity().x > 2.9,
        "and the impulse is applied"
    );
}

#[test]
fn removing_the_bottom_box_lets_the_rest_fall() {
    let (mut w, _, ids) = resting_stack(3);
    let y1 = w.body(ids[1]).unwrap().position().y;
    w.remove_body(ids[0]).unwrap();
    for _ in 0..60 {
        w.step(DT).unwrap();
    }
    let y1_after = w.body(ids[1]).unwrap().position().y;
    assert!(
        y1_after < y1 - 0.9,
        "box 1 fell one box height: {y1} -> {y1_after}"
    );
}

#[test]
fn with_sleep_off_nothing_sleeps() {
    let mut w = World::new(
        Settings {
            enable_sleep: false,
            ..Settings::default()
        },
        vec2(0.0, -9.81),
    )
    .unwrap();
    ground(&mut w, 0.0, 40.0, 1.0).unwrap();
    stack(&mut w, 3, 1.0, 0.0, 0.0).unwrap();
    for _ in 0..180 {
        w.step(DT).unwrap();
    }
    assert_eq!(w.awake_count(), 3);
}

#[test]
fn a_neighbour_resting_inside_the_speculative_margin_does_not_wake_a_sleeper() {
    // One sleeping box; a new box set down beside it with a 1.5 cm gap: inside the soft
    // step's 2 cm speculative margin, but nothing closes that gap. It used to wake the sleeper
    // every time the newcomer's island was stepped, so the pair never slept.
    let (mut w, _, ids) = resting_stack(1);
    let sleeper = ids[0];
    assert!(!w.body(sleeper).unwrap().is_awake());
    let resting_y = w.body(sleeper).unwrap().position().y;
    let gap = 0.015;
    assert!(gap < w.settings().speculative_distance);
    let newcomer = w
        .add_body(&BodyDef::dynamic(
            Shape::rect(1.0, 1.0),
            vec2(1.0 + gap, resting_y),
        ))
        .unwrap();
    let mut woke = 0;
    for _ in 0..120 {
        w.step(DT).unwrap();
        woke += usize::from(w.body(sleeper).unwrap().is_awake());
    }
    assert_eq!(woke, 0, "the sleeper never woke");
    assert!(
        !w.body(newcomer).unwrap().is_awake(),
        "the newcomer fell asleep too"
    );
    // The speculative contact still holds: a push towards the sleeper wakes it.
    w.set_velocity(newcomer, vec2(-3.0, 0.0), 0.0).unwrap();
    w.step(DT).unwrap();
    assert!(
        w.body(sleeper).unwrap().is_awake(),
        "a closing neighbour wakes it"
    );
}
