//! The `…/velocity` command (issue 17): a client drives a kinematic body. Validated at the
//! wire boundary and by the World, refused naming field and value with nothing changed, kept
//! by checkpoints, and the terrain scene's chain and paddle travel on the wire as segments.
#![cfg(feature = "net")]

mod common;

use tiltbox::physics::{vec2, Body, Real};
use tiltbox::protocol::*;
use tiltbox::service::{
    checkpoint, parse_command, Incoming, SceneSource, ServerConfig, Simulation,
};

fn terrain() -> (ServerConfig, Simulation) {
    let config = ServerConfig::default();
    let source = SceneSource::File(common::repo_path("config/scenes/terrain.toml"));
    let sim = Simulation::new(&config, source).unwrap();
    (config, sim)
}

fn named(sim: &Simulation, name: &str) -> BodyRef {
    sim.scene_state()
        .bodies
        .iter()
        .find(|b| b.name == name)
        .unwrap_or_else(|| panic!("no {name}"))
        .id
}

fn body(sim: &Simulation, r: BodyRef) -> &Body {
    sim.world()
        .bodies()
        .find(|b| BodyRef::from(b.id()) == r)
        .unwrap()
}

/// Send `message` on `…/velocity`; the rejection's reason, if any.
fn send(sim: &mut Simulation, config: &ServerConfig, message: &SetVelocity) -> Option<String> {
    let payload = encode(message).unwrap();
    let command = parse_command(CommandKey::Velocity, &payload, &config.limits);
    match sim.apply(Incoming {
        key: CommandKey::Velocity,
        command,
    }) {
        None => None,
        Some(Event {
            kind: EventKind::Rejected { reason, key },
            ..
        }) => {
            assert!(key.ends_with("/velocity"), "{key}");
            Some(reason)
        }
        Some(other) => panic!("unexpected event {other:?}"),
    }
}

#[test]
fn a_client_drives_the_paddle_and_bad_commands_change_nothing() {
    let (config, mut sim) = terrain();
    let paddle = named(&sim, "paddle");
    let set = |velocity: Vector, angular_velocity: f32| SetVelocity {
        id: paddle,
        velocity,
        angular_velocity,
    };
    assert_eq!(
        send(&mut sim, &config, &set(Vector::new(0.5, 0.0), 0.0)),
        None
    );
    let x0 = body(&sim, paddle).position().x;
    for _ in 0..60 {
        sim.step().unwrap();
    }
    let p = body(&sim, paddle);
    assert_eq!(p.linear_velocity(), vec2(0.5, 0.0));
    assert_eq!(p.angular_velocity(), 0.0);
    // 1 s at 0.5 m/s: exact up to f32 sums over 60 steps.
    assert!(
        (p.position().x - x0 - 0.5).abs() < 1e-4,
        "{}",
        p.position().x
    );

    let brick = named(&sim, "red brick");
    let refusals: [(SetVelocity, &[&str]); 5] = [
        (
            SetVelocity {
                id: brick,
                ..set(Vector::new(1.0, 0.0), 0.0)
            },
            &["id", "not kinematic"],
        ),
        (
            SetVelocity {
                id: BodyRef {
                    index: 999,
                    generation: 0,
                },
                ..set(Vector::new(1.0, 0.0), 0.0)
            },
            &["id", "999v0"],
        ),
        (set(Vector::new(f32::NAN, 0.0), 0.0), &["velocity.x", "NaN"]),
        (
            set(Vector::new(0.0, 0.0), f32::INFINITY),
            &["angular_velocity", "inf"],
        ),
        (
            set(Vector::new(1000.0, 0.0), 0.0),
            &["velocity (speed)", "1000", "400"],
        ),
    ];
    let rejected = sim.rejected();
    for (message, words) in refusals {
        let reason = send(&mut sim, &config, &message).expect("refused");
        for w in words {
            assert!(reason.contains(w), "{reason:?} should name {w:?}");
        }
        // Nothing changed: the paddle keeps the velocity it was given.
        let p = body(&sim, paddle);
        assert_eq!(p.linear_velocity(), vec2(0.5, 0.0));
        assert!(body(&sim, brick).is_finite());
    }
    assert_eq!(sim.rejected(), rejected + 5);
}

#[test]
fn a_checkpoint_keeps_kinematic_bodies_and_chains() {
    let (config, mut sim) = terrain();
    let paddle = named(&sim, "paddle");
    let cmd = SetVelocity {
        id: paddle,
        velocity: Vector::new(0.0, 0.25),
        angular_velocity: -0.3,
    };
    assert_eq!(send(&mut sim, &config, &cmd), None);
    for _ in 0..30 {
        sim.step().unwrap();
    }
    let bytes = checkpoint::encode(&sim.export_state()).unwrap();
    let source = SceneSource::File(common::repo_path("config/scenes/terrain.toml"));
    let mut restored =
        Simulation::restore(&config, source, checkpoint::decode(&bytes).unwrap()).unwrap();
    for _ in 0..30 {
        sim.step().unwrap();
        restored.step().unwrap();
    }
    // Bit-identical continuation, the paddle still kinematic and moving as it was told.
    assert_eq!(sim.world().state_hash(), restored.world().state_hash());
    let p = body(&restored, paddle);
    assert!(p.is_kinematic());
    assert_eq!(p.angular_velocity(), -0.3 as Real);
}

#[test]
fn the_terrain_scene_goes_on_the_wire_as_segments_and_a_moving_paddle() {
    let (_, mut sim) = terrain();
    let state = sim.scene_state();
    let pieces: Vec<&BodyInfo> = state
        .bodies
        .iter()
        .filter(|b| b.name.starts_with("hills["))
        .collect();
    assert_eq!(pieces.len(), 16);
    for (i, b) in pieces.iter().enumerate() {
        assert!(b.is_static);
        let ShapeSpec::Segment {
            prev,
            next,
            one_sided,
            ..
        } = b.shape
        else {
            panic!("{:?}", b.shape)
        };
        assert!(one_sided);
        // Open chain: the first piece has no vertex before it, the last none after it.
        assert_eq!(prev.is_none(), i == 0);
        assert_eq!(next.is_none(), i == 15);
    }
    // Decodes as it was encoded.
    let bytes = encode(&state).unwrap();
    assert_eq!(decode::<SceneState>(&bytes).unwrap(), state);
    // The paddle is not static, weighs nothing on the wire, and its pose is published.
    let paddle = state.bodies.iter().find(|b| b.name == "paddle").unwrap();
    assert!(!paddle.is_static);
    assert_eq!(paddle.mass, 0.0);
    sim.step().unwrap();
    let mut payload = Vec::new();
    assert!(sim
        .snapshot_into(&mut payload)
        .poses
        .iter()
        .any(|p| p.id == paddle.id));
}

/// docs/protocol.md's `Segment` and `SetVelocity` examples are what the encoder writes.
#[test]
fn the_documented_segment_and_velocity_bytes_are_exact() {
    let doc = common::read_repo_file("docs/protocol.md");
    let hex = common::hex;
    let piece = ShapeSpec::Segment {
        a: Vector::new(-1.0, 0.0),
        b: Vector::new(1.0, 0.0),
        radius: 0.0,
        prev: None,
        next: Some(Vector::new(3.0, 0.5)),
        one_sided: true,
    };
    let bytes = postcard::to_allocvec(&piece).unwrap();
    assert_eq!(bytes.len(), 32);
    assert!(doc.contains(&hex(&bytes)), "segment:\n{}", hex(&bytes));
    let v = SetVelocity {
        id: BodyRef {
            index: 5,
            generation: 0,
        },
        velocity: Vector::new(0.5, 0.0),
        angular_velocity: 0.0,
    };
    let bytes = encode(&v).unwrap();
    assert_eq!(bytes.len(), 15);
    assert!(doc.contains(&hex(&bytes)), "velocity:\n{}", hex(&bytes));
}
