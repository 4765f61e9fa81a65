//! `…/drag`: a hand grabs a brick of Falling Bricks, pulls it, throws it, and is refused what
//! it may not do, driven through the daemon's own decoding and tick-boundary application.
#![cfg(feature = "net")]
#![allow(clippy::unnecessary_cast)] // Real <-> f32 casts matter with the `f64` feature.

mod common;

use tiltbox::physics::{Body, Real, Vec2};
use tiltbox::protocol::*;
use tiltbox::service::{
    checkpoint, parse_command, Incoming, SceneSource, ServerConfig, Simulation,
};

fn bricks() -> (ServerConfig, Simulation) {
    let config = ServerConfig::default();
    let sim = Simulation::new(&config, SceneSource::Embedded).unwrap();
    (config, sim)
}

fn named(sim: &Simulation, name: &str) -> BodyRef {
    let scene = sim.scene_state();
    scene.bodies.iter().find(|b| b.name == name).expect(name).id
}

fn body(sim: &Simulation, r: BodyRef) -> &Body {
    sim.world()
        .bodies()
        .find(|b| BodyRef::from(b.id()) == r)
        .unwrap()
}

/// Send `d` on `…/drag`; the rejection's reason, if any.
fn send(sim: &mut Simulation, config: &ServerConfig, d: Drag) -> Option<String> {
    let payload = encode(&d).unwrap();
    let command = parse_command(CommandKey::Drag, &payload, &config.limits);
    match sim.apply(Incoming {
        key: CommandKey::Drag,
        command,
    })? {
        Event {
            kind: EventKind::Rejected { reason, .. },
            ..
        } => Some(reason),
        other => panic!("unexpected event {other:?}"),
    }
}

/// Hand `hand` grabs body `id` at its centre of mass; the point grabbed (it must be accepted).
fn grab_centre(sim: &mut Simulation, config: &ServerConfig, hand: u64, id: BodyRef) -> Vector {
    let c = body(sim, id).center_of_mass();
    let point = v(c.x as f32, c.y as f32);
    assert_eq!(send(sim, config, Drag::Grab { hand, id, point }), None);
    point
}

/// Apply a command on `key` as the tick thread does.
fn apply(sim: &mut Simulation, config: &ServerConfig, key: CommandKey, payload: Vec<u8>) {
    let command = parse_command(key, &payload, &config.limits);
    sim.apply(Incoming { key, command });
}

fn steps(sim: &mut Simulation, n: usize) {
    for _ in 0..n {
        sim.step().unwrap();
    }
}

fn v(x: f32, y: f32) -> Vector {
    Vector::new(x, y)
}

fn settled() -> (ServerConfig, Simulation, BodyRef) {
    let (config, mut sim) = bricks();
    steps(&mut sim, 180);
    let red = named(&sim, "red brick");
    (config, sim, red)
}

#[test]
fn a_grabbed_brick_follows_the_finger_to_within_5_cm_200_ms_after_it_stops() {
    let (config, mut sim, red) = settled();
    let start = body(&sim, red).center_of_mass();
    grab_centre(&mut sim, &config, 7, red);
    // The finger lifts it 2 m and carries it 1 m right over half a second, then stops.
    let end = start + Vec2::new(1.0, 2.0);
    for k in 1..=30 {
        let t = k as Real / 30.0;
        let p = start + (end - start) * t;
        let target = v(p.x as f32, p.y as f32);
        assert_eq!(
            send(&mut sim, &config, Drag::Move { hand: 7, target }),
            None
        );
        steps(&mut sim, 1);
    }
    // 200 ms later (12 steps of 1/60 s) the grabbed point (the centre, where it was grabbed)
    // is within 5 cm of the target: the 5 Hz spring, damped at 0.7, settles to 2 % in
    // 4 / (0.7 x 2 pi 5) = 0.18 s, and holds the brick's weight 1 cm low (g / omega^2).
    steps(&mut sim, 12);
    let at = body(&sim, red).center_of_mass();
    assert!((at - end).length() < 0.05, "at {at}, target {end}");
    assert_eq!(send(&mut sim, &config, Drag::Release { hand: 7 }), None);
    steps(&mut sim, 120);
    assert!(
        body(&sim, red).center_of_mass().y < end.y - 1.0,
        "it falls once let go"
    );
}

#[test]
fn a_brick_let_go_while_moving_leaves_at_the_fingers_speed() {
    let (config, mut sim, red) = settled();
    let start = body(&sim, red).center_of_mass();
    grab_centre(&mut sim, &config, 1, red);
    // Up 1 m, then a flick to the right at 3 m/s for 0.5 s, let go while moving.
    let lift = start + Vec2::new(0.0, 1.0);
    for _ in 0..30 {
        let target = v(lift.x as f32, lift.y as f32);
        send(&mut sim, &config, Drag::Move { hand: 1, target });
        steps(&mut sim, 1);
    }
    let speed: Real = 3.0;
    for k in 1..=30 {
        let p = lift + Vec2::new(speed * k as Real / 60.0 - 1.5, 0.0);
        send(
            &mut sim,
            &config,
            Drag::Move {
                hand: 1,
                target: v(p.x as f32, p.y as f32),
            },
        );
        steps(&mut sim, 1);
    }
    assert_eq!(send(&mut sim, &config, Drag::Release { hand: 1 }), None);
    steps(&mut sim, 1);
    let vx = body(&sim, red).linear_velocity().x;
    assert!(
        (vx - speed).abs() < 0.1 * speed,
        "left at {vx} m/s, the finger at {speed}"
    );
}

#[test]
fn what_a_hand_may_not_do_is_refused_by_name_and_changes_nothing() {
    let (config, mut sim, red) = settled();
    let floor = named(&sim, "floor");
    let before = sim.world().joint_count();
    let cases: [(Drag, &[&str]); 6] = [
        (
            Drag::Grab {
                hand: 1,
                id: floor,
                point: v(0.0, 0.0),
            },
            &["id", "static"],
        ),
        (
            Drag::Grab {
                hand: 1,
                id: BodyRef {
                    index: 999,
                    generation: 0,
                },
                point: v(0.0, 0.0),
            },
            &["id", "999v0"],
        ),
        (
            Drag::Grab {
                hand: 1,
                id: red,
                point: v(f32::NAN, 0.0),
            },
            &["point.x", "NaN"],
        ),
        (
            Drag::Move {
                hand: 1,
                target: v(0.0, 5000.0),
            },
            &["target.y", "5000", "max_coordinate"],
        ),
        (
            Drag::Move {
                hand: 9,
                target: v(0.0, 1.0),
            },
            &["hand", "9"],
        ),
        (Drag::Release { hand: 9 }, &["hand", "9"]),
    ];
    for (d, words) in cases {
        let reason = send(&mut sim, &config, d).unwrap_or_else(|| panic!("{d:?} accepted"));
        for w in words {
            assert!(reason.contains(w), "{d:?}: {reason:?} lacks {w:?}");
        }
        assert_eq!(sim.world().joint_count(), before, "{d:?} left a joint");
    }
    // At most 16 hands at once.
    let bricks: Vec<BodyRef> = sim
        .scene_state()
        .bodies
        .iter()
        .filter(|b| !b.is_static)
        .map(|b| b.id)
        .collect();
    for hand in 0..16u64 {
        let id = bricks[hand as usize % bricks.len()];
        let p = body(&sim, id).center_of_mass();
        let grab = Drag::Grab {
            hand,
            id,
            point: v(p.x as f32, p.y as f32),
        };
        assert_eq!(send(&mut sim, &config, grab), None);
    }
    let p = body(&sim, red).center_of_mass();
    let reason = send(
        &mut sim,
        &config,
        Drag::Grab {
            hand: 99,
            id: red,
            point: v(p.x as f32, p.y as f32),
        },
    );
    assert!(reason.is_some_and(|r| r.contains("16")));
    assert_eq!(sim.world().joint_count(), before + 16);
}

#[test]
fn a_silent_hand_is_let_go_after_3_s_and_a_checkpoint_holds_none() {
    let (config, mut sim, red) = settled();
    let p = body(&sim, red).center_of_mass();
    let grab = Drag::Grab {
        hand: 5,
        id: red,
        point: v(p.x as f32, p.y as f32 + 1.0),
    };
    assert_eq!(send(&mut sim, &config, grab), None);
    assert_eq!(sim.world().joint_count(), 1);
    // A checkpoint now is taken as if the hand had let go; the live world still holds it.
    let state = checkpoint::decode(&checkpoint::encode(&sim.export_state()).unwrap()).unwrap();
    let restored = Simulation::restore(&config, SceneSource::Embedded, state).unwrap();
    assert_eq!(restored.world().joint_count(), 0);
    assert_eq!(sim.world().joint_count(), 1);
    // 3 s of silence (180 steps at 60 Hz): still held at 179, let go by 180.
    steps(&mut sim, 179);
    assert_eq!(sim.world().joint_count(), 1);
    steps(&mut sim, 1);
    assert_eq!(sim.world().joint_count(), 0);
    let reason = send(
        &mut sim,
        &config,
        Drag::Move {
            hand: 5,
            target: v(0.0, 1.0),
        },
    );
    assert!(reason.is_some_and(|r| r.contains("hand 5 holds no body")));
}

#[test]
fn a_reset_or_a_removed_body_empties_the_hand() {
    let (config, mut sim, red) = settled();
    let point = grab_centre(&mut sim, &config, 2, red);
    apply(
        &mut sim,
        &config,
        CommandKey::Remove,
        encode(&Remove { ids: vec![red] }).unwrap(),
    );
    let reason = send(
        &mut sim,
        &config,
        Drag::Move {
            hand: 2,
            target: point,
        },
    );
    assert!(reason.is_some_and(|r| r.contains("holds no body")));
    let other = named(&sim, "blue brick");
    grab_centre(&mut sim, &config, 2, other);
    apply(
        &mut sim,
        &config,
        CommandKey::Reset,
        encode(&Reset).unwrap(),
    );
    assert_eq!(sim.world().joint_count(), 0);
    let reason = send(&mut sim, &config, Drag::Release { hand: 2 });
    assert!(reason.is_some_and(|r| r.contains("holds no body")));
}
