//! No network: the worked examples in docs/protocol.md are real snapshots produced here, and
//! config/server.toml is the embedded default. If the engine's numbers change, the failure
//! prints the new bytes to paste into the doc.
#![cfg(feature = "net")]

use tiltbox::protocol::*;
use tiltbox::scene::Scene;
use tiltbox::service::{Incoming, SceneSource, ServerConfig, Simulation};

const EXAMPLE_SCENE: &str = r#"
name = "doc example"
gravity = [0.0, 0.0]

[[body]]
name = "floor"
static = true
shape = { type = "rect", width = 4.0, height = 0.5 }
position = [0.0, -0.25]

[[body]]
name = "still"
shape = { type = "rect", width = 1.0, height = 0.5 }
position = [-1.0, 1.0]
density = 1.0

[[body]]
name = "moving"
shape = { type = "rect", width = 1.0, height = 0.5 }
position = [1.0, 1.0]
velocity = [2.0, 0.0]
density = 1.0
"#;

/// 16 bytes per line, lower-case hex separated by spaces: the doc's format.
fn hex(bytes: &[u8]) -> String {
    bytes
        .chunks(16)
        .map(|c| {
            c.iter()
                .map(|b| format!("{b:02x}"))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn doc() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/protocol.md")).unwrap()
}

fn example_sim() -> Simulation {
    let scene = Scene::from_toml_str(EXAMPLE_SCENE).unwrap();
    Simulation::new(
        &ServerConfig::default(),
        SceneSource::Given(Box::new(scene)),
    )
    .unwrap()
}

#[test]
fn the_documented_snapshots_are_real_and_exact() {
    let mut sim = example_sim();
    sim.step().unwrap();
    let key = sim.snapshot().clone();
    assert!(key.keyframe && key.frame == 1 && key.poses.len() == 2);
    let key_bytes = encode(&key).unwrap();
    sim.step().unwrap();
    let delta = sim.snapshot().clone();
    assert!(!delta.keyframe && delta.frame == 2);
    assert_eq!(delta.poses.len(), 1, "only the moving body: {delta:?}");
    let delta_bytes = encode(&delta).unwrap();

    let doc = doc();
    let (kh, dh) = (hex(&key_bytes), hex(&delta_bytes));
    assert!(
        doc.contains(&kh),
        "docs/protocol.md must contain the keyframe bytes:\n{kh}\n{key:#?}"
    );
    assert!(
        doc.contains(&dh),
        "docs/protocol.md must contain the delta bytes:\n{dh}\n{delta:#?}"
    );
    // and they decode back
    assert_eq!(decode::<Snapshot>(&key_bytes).unwrap(), key);
    assert_eq!(key_bytes.len(), 1 + 1 + 8 + 8 + 1 + 1 + 2 * 14);
}

#[test]
fn the_documented_command_and_event_examples_are_exact() {
    let doc = doc();
    let mut sim = example_sim();
    let spawn = Spawn {
        bodies: vec![SpawnBody {
            name: Some("crate".into()),
            shape: ShapeSpec::Rect {
                width: 0.5,
                height: 0.5,
            },
            position: Vector::new(0.0, 2.0),
            angle: 0.0,
            velocity: Vector::new(0.0, 0.0),
            angular_velocity: 0.0,
            density: 1.0,
            friction: 0.5,
            restitution: 0.0,
            colour: Colour {
                r: 0xd6,
                g: 0x45,
                b: 0x41,
            },
        }],
    };
    let bytes = encode(&spawn).unwrap();
    assert!(doc.contains(&hex(&bytes)), "spawn:\n{}", hex(&bytes));
    let command =
        tiltbox::service::intake::parse(CommandKey::Spawn, &bytes, &ServerConfig::default().limits);
    let event = sim
        .apply(Incoming {
            key: CommandKey::Spawn,
            command,
        })
        .unwrap();
    let bytes = encode(&event).unwrap();
    assert!(doc.contains(&hex(&bytes)), "added event:\n{}", hex(&bytes));
    let rejected = sim
        .apply(Incoming {
            key: CommandKey::Gravity,
            command: tiltbox::service::intake::parse(
                CommandKey::Gravity,
                &[1],
                &ServerConfig::default().limits,
            ),
        })
        .unwrap();
    let bytes = encode(&rejected).unwrap();
    assert!(
        doc.contains(&hex(&bytes)),
        "rejected event:\n{}",
        hex(&bytes)
    );
    for (name, bytes) in [
        ("gravity", encode(&SetGravity { x: 0.0, y: -9.81 }).unwrap()),
        (
            "tilt",
            encode(&Tilt::Orientation(Orientation::PortraitUpsideDown)).unwrap(),
        ),
        (
            "accelerometer",
            encode(&Tilt::Accelerometer {
                x: 0.0,
                y: 9.81,
                z: 0.0,
            })
            .unwrap(),
        ),
        (
            "remove",
            encode(&Remove {
                ids: vec![BodyRef {
                    index: 3,
                    generation: 0,
                }],
            })
            .unwrap(),
        ),
        ("reset", encode(&Reset).unwrap()),
    ] {
        assert!(doc.contains(&hex(&bytes)), "{name}:\n{}", hex(&bytes));
    }
}

#[test]
fn config_server_toml_is_the_embedded_default() {
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/config/server.toml"));
    assert_eq!(ServerConfig::load(path).unwrap(), ServerConfig::default());
}

#[test]
fn the_shipped_zenoh_configs_load() {
    for f in ["loopback.json5", "lan.json5", "client.json5"] {
        let path = format!("{}/config/zenoh/{f}", env!("CARGO_MANIFEST_DIR"));
        let mut c = ServerConfig::default();
        c.zenoh.config_file = Some(path.into());
        c.validate().unwrap();
        c.zenoh_config().unwrap_or_else(|e| panic!("{f}: {e}"));
    }
}
