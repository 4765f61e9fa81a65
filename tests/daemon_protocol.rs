//! No network: the worked examples in docs/protocol.md are real snapshots produced here, and
//! config/server.toml is the embedded default. If the engine's numbers change, the failure
//! prints the new bytes to paste into the doc.
#![cfg(feature = "net")]

mod common;

use common::{hex, read_repo_file};
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

fn doc() -> String {
    read_repo_file("docs/protocol.md")
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
#[allow(clippy::unnecessary_cast)] // Real -> f32 matters with the `f64` feature.
fn the_documented_snapshots_are_real_and_exact() {
    let mut sim = example_sim();
    let (mut key_bytes, mut delta_bytes) = (Vec::new(), Vec::new());
    // The moving body's true x (the engine's own f32), as the prose states it after each step.
    let moving_x = |sim: &Simulation| {
        sim.world()
            .bodies()
            .map(|b| b.position().x)
            .fold(f32::MIN as tiltbox::physics::Real, |a, x| a.max(x)) as f32
    };
    sim.step().unwrap();
    let key = sim.snapshot_into(&mut key_bytes).clone();
    let x1 = moving_x(&sim);
    assert!(key.is_keyframe() && key.frame == 1 && key.poses.len() == 2);
    sim.step().unwrap();
    let delta = sim.snapshot_into(&mut delta_bytes).clone();
    let x2 = moving_x(&sim);
    for prose in [
        format!("the true x {x1} within 1/2048"),
        format!("the true {x2} within 1/2048"),
    ] {
        assert!(
            doc().contains(&prose),
            "docs/protocol.md must say {prose:?}"
        );
    }
    assert!(!delta.is_keyframe() && delta.frame == 2 && delta.reference == 1);
    assert_eq!(delta.poses.len(), 1, "only the moving body: {delta:?}");

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
    // they decode back, and a client reconstructs the documented poses
    assert_eq!(decode_frame(&key_bytes).unwrap(), key);
    assert_eq!(decode_frame(&delta_bytes).unwrap(), delta);
    // version, frame, time, gravity, reference, grid, count (21), then 7 bytes for "still"
    // and 6 for "moving" (its y is the same as the body before it: one byte)
    assert_eq!(key_bytes.len(), 21 + 7 + 6);
    let mut client = SnapshotDecoder::new();
    let k = client.decode(&key_bytes).unwrap().unwrap();
    let d = client.decode(&delta_bytes).unwrap().unwrap();
    let xy = |p: &Pose| (p.x, p.y, p.angle);
    assert_eq!(xy(&k.poses[0]), (-1.0, 1.0, 0.0));
    assert_eq!(xy(&k.poses[1]), (1058.0 / 1024.0, 1.0, 0.0));
    assert_eq!(d.poses.len(), 1);
    assert_eq!(xy(&d.poses[0]), (1092.0 / 1024.0, 1.0, 0.0));
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
        tiltbox::service::parse_command(CommandKey::Spawn, &bytes, &ServerConfig::default().limits);
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
            command: tiltbox::service::parse_command(
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

/// The circle and polygon spawns of docs/protocol.md, built as messages.
fn ball_and_triangle() -> (Spawn, Spawn) {
    let body = |name: Option<&str>, shape, position, restitution, colour| SpawnBody {
        name: name.map(Into::into),
        friction: 0.5,
        restitution,
        colour,
        ..SpawnBody::at(shape, position)
    };
    let ball = body(
        Some("ball"),
        ShapeSpec::Circle { radius: 0.25 },
        Vector::new(0.0, 3.0),
        0.5,
        Colour {
            r: 0x3a,
            g: 0x7b,
            b: 0xd5,
        },
    );
    let triangle = body(
        None,
        ShapeSpec::Polygon {
            vertices: vec![
                Vector::new(0.0, 0.0),
                Vector::new(1.5, 0.0),
                Vector::new(0.0, 0.75),
            ],
        },
        Vector::new(-1.0, 2.0),
        0.0,
        Colour {
            r: 0x2e,
            g: 0xcc,
            b: 0x71,
        },
    );
    (
        Spawn { bodies: vec![ball] },
        Spawn {
            bodies: vec![triangle],
        },
    )
}

/// The bytes of the two shape examples, derived by hand from postcard's rules (not copied
/// from the encoder): enum variants and lengths are varints (all < 128 here, so one byte
/// each), `Option` is a 0/1 tag, an f32 is its IEEE 754 bits little-endian.
///
/// f32 bits: 0.0 = 0x00000000, 0.25 = 0x3e800000 (exponent 125 = 0x7d: 0 01111101 000..,
/// sign+exponent bits 0011 1110 1 -> 0x3e80), 0.5 = 0x3f000000 (exponent 126),
/// 0.75 = 0x3f400000 (exponent 126, mantissa .1), 1.0 = 0x3f800000 (exponent 127),
/// 1.5 = 0x3fc00000 (exponent 127, mantissa .1), 2.0 = 0x40000000 (exponent 128),
/// 3.0 = 0x40400000 (exponent 128, mantissa .1), -1.0 = 0xbf800000 (sign bit + 1.0).
/// Little-endian puts the low byte first: 0.25 -> 00 00 80 3e.
fn hand_derived_shape_examples() -> (Vec<u8>, Vec<u8>) {
    const ZERO: [u8; 4] = [0x00, 0x00, 0x00, 0x00];
    const QUARTER: [u8; 4] = [0x00, 0x00, 0x80, 0x3e];
    const HALF: [u8; 4] = [0x00, 0x00, 0x00, 0x3f];
    const THREE_QUARTERS: [u8; 4] = [0x00, 0x00, 0x40, 0x3f];
    const ONE: [u8; 4] = [0x00, 0x00, 0x80, 0x3f];
    const ONE_AND_HALF: [u8; 4] = [0x00, 0x00, 0xc0, 0x3f];
    const TWO: [u8; 4] = [0x00, 0x00, 0x00, 0x40];
    const THREE: [u8; 4] = [0x00, 0x00, 0x40, 0x40];
    const MINUS_ONE: [u8; 4] = [0x00, 0x00, 0x80, 0xbf];

    // angle, velocity.x, velocity.y, angular_velocity: both bodies are at rest, not turned
    const AT_REST: [[u8; 4]; 4] = [ZERO; 4];
    // A spawn of one body: its header, then its shape and position, the at-rest fields, its
    // material (density 1, friction 0.5 for both, then its restitution) and its colour (r, g,
    // b: u8 each).
    let spawn = |header: &[u8], shape_and_position: &[[u8; 4]], restitution, colour| {
        let mut bytes = header.to_vec();
        let material = [ONE, HALF, restitution];
        for field in shape_and_position.iter().chain(&AT_REST).chain(&material) {
            bytes.extend(field);
        }
        bytes.extend::<[u8; 3]>(colour);
        bytes
    };

    let header = [
        0x01, // protocol version
        0x01, // Spawn.bodies: varint length 1
        0x01, // name: Some
        0x04, // name: varint byte length 4
        b'b', b'a', b'l', b'l', // "ball" = 62 61 6c 6c
        0x01, // shape: ShapeSpec variant 1 = Circle
    ];
    let shape_and_position = [
        QUARTER, // radius 0.25
        ZERO,    // position.x 0
        THREE,   // position.y 3
    ];
    // restitution 0.5, colour 3a 7b d5
    let ball = spawn(&header, &shape_and_position, HALF, [0x3a, 0x7b, 0xd5]);
    assert_eq!(ball.len(), 1 + 1 + 1 + 1 + 4 + 1 + 10 * 4 + 3);
    assert_eq!(ball.len(), 52);

    let header = [
        0x01, // protocol version
        0x01, // Spawn.bodies: varint length 1
        0x00, // name: None
        0x03, // shape: ShapeSpec variant 3 = Polygon
        0x03, // vertices: varint length 3
    ];
    let shape_and_position = [
        ZERO,           // vertices[0].x 0
        ZERO,           // vertices[0].y 0
        ONE_AND_HALF,   // vertices[1].x 1.5
        ZERO,           // vertices[1].y 0
        ZERO,           // vertices[2].x 0
        THREE_QUARTERS, // vertices[2].y 0.75
        MINUS_ONE,      // position.x -1
        TWO,            // position.y 2
    ];
    // restitution 0, colour 2e cc 71
    let triangle = spawn(&header, &shape_and_position, ZERO, [0x2e, 0xcc, 0x71]);
    assert_eq!(triangle.len(), 5 + 15 * 4 + 3);
    assert_eq!(triangle.len(), 68);
    (ball, triangle)
}

#[test]
fn the_documented_circle_and_polygon_spawns_are_exact_and_land_where_the_doc_says() {
    let doc = doc();
    let (ball, triangle) = ball_and_triangle();
    let (ball_bytes, triangle_bytes) = hand_derived_shape_examples();
    // postcard agrees with the hand derivation, and the doc shows exactly those bytes
    assert_eq!(encode(&ball).unwrap(), ball_bytes);
    assert_eq!(encode(&triangle).unwrap(), triangle_bytes);
    assert!(
        doc.contains(&hex(&ball_bytes)),
        "docs/protocol.md must contain the circle spawn:\n{}",
        hex(&ball_bytes)
    );
    assert!(
        doc.contains(&hex(&triangle_bytes)),
        "docs/protocol.md must contain the polygon spawn:\n{}",
        hex(&triangle_bytes)
    );
    assert!(doc.contains("(52 bytes)") && doc.contains("(68 bytes)"));
    assert_eq!(decode::<Spawn>(&ball_bytes).unwrap(), ball);
    assert_eq!(decode::<Spawn>(&triangle_bytes).unwrap(), triangle);

    // What the daemon makes of them: the Added events the doc describes.
    let limits = ServerConfig::default().limits;
    let mut sim = example_sim();
    let mut added = |bytes: &[u8]| {
        let command = tiltbox::service::parse_command(CommandKey::Spawn, bytes, &limits);
        match sim.apply(Incoming {
            key: CommandKey::Spawn,
            command,
        }) {
            Some(Event {
                kind: EventKind::Added { mut bodies },
                ..
            }) if bodies.len() == 1 => bodies.remove(0),
            other => panic!("{other:?}"),
        }
    };
    let b = added(&ball_bytes);
    assert_eq!(b.shape, ShapeSpec::Circle { radius: 0.25 });
    assert_eq!(b.position, Vector::new(0.0, 3.0));
    assert!(
        (b.mass - std::f32::consts::PI / 16.0).abs() < 1e-6,
        "{}",
        b.mass
    );
    // 43 + 4 name bytes + 5 shape bytes
    assert_eq!(
        postcard::to_allocvec(&b).unwrap().len(),
        52,
        "circle BodyInfo"
    );

    let t = added(&triangle_bytes);
    // the centroid of a triangle is the mean of its vertices: (1.5 / 3, 0.75 / 3)
    let c = (0.5f32, 0.25f32);
    assert_eq!(t.position, Vector::new(-1.0 + c.0, 2.0 + c.1));
    assert_eq!(t.position, Vector::new(-0.5, 2.25), "the doc's figures");
    assert_eq!(
        t.shape,
        ShapeSpec::Polygon {
            vertices: vec![
                Vector::new(-0.5, -0.25),
                Vector::new(1.0, -0.25),
                Vector::new(-0.5, 0.5),
            ],
        }
    );
    // area 1.5 x 0.75 / 2 = 0.5625 m^2 at density 1
    assert!((t.mass - 0.5625).abs() < 1e-6, "{}", t.mass);
    // 43 + 0 name bytes + 2 + 3 x 8 shape bytes
    assert_eq!(
        postcard::to_allocvec(&t).unwrap().len(),
        69,
        "triangle BodyInfo"
    );
    // and an octagon: 43 + 2 + 8 x 8
    let octagon = BodyInfo {
        shape: ShapeSpec::Polygon {
            vertices: vec![Vector::new(0.0, 0.0); 8],
        },
        ..t
    };
    assert_eq!(postcard::to_allocvec(&octagon).unwrap().len(), 109);
    for figure in ["48 for a circle", "69 for a triangle", "109 for an octagon"] {
        assert!(doc.contains(figure), "{figure}");
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

/// docs/protocol.md: an accepted gravity or tilt yields no event (the new gravity is in the
/// next snapshot); a refused one yields a `Rejected` event; an empty `Remove` is refused.
#[test]
fn accepted_gravity_and_tilt_yield_no_event_and_an_empty_remove_is_refused() {
    let mut sim = example_sim();
    let limits = ServerConfig::default().limits;
    let apply = |sim: &mut Simulation, key: CommandKey, bytes: Vec<u8>| {
        sim.apply(Incoming {
            key,
            command: tiltbox::service::parse_command(key, &bytes, &limits),
        })
    };
    let g = encode(&SetGravity { x: 1.0, y: -5.0 }).unwrap();
    assert_eq!(apply(&mut sim, CommandKey::Gravity, g), None);
    let t = encode(&Tilt::Accelerometer {
        x: 0.0,
        y: -9.0,
        z: 0.0,
    })
    .unwrap();
    assert_eq!(apply(&mut sim, CommandKey::Tilt, t), None);
    assert_eq!(sim.applied(), 2);
    sim.step().unwrap();
    let mut bytes = Vec::new();
    let frame = sim.snapshot_into(&mut bytes).clone();
    // gravity = (-a.x, -a.y) (protocol.md, Tilt)
    assert_eq!(frame.gravity, Vector::new(0.0, 9.0), "{frame:?}");
    let g = encode(&SetGravity { x: 1000.0, y: 0.0 }).unwrap();
    let refused = apply(&mut sim, CommandKey::Gravity, g).expect("a Rejected event");
    assert!(matches!(refused.kind, EventKind::Rejected { .. }));
    let empty = encode(&Remove { ids: vec![] }).unwrap();
    match apply(&mut sim, CommandKey::Remove, empty).map(|e| e.kind) {
        Some(EventKind::Rejected { reason, .. }) => {
            assert_eq!(reason, "ids is empty: nothing to remove");
            assert!(
                doc().contains("ids is empty: nothing to"),
                "the doc quotes it"
            );
        }
        other => panic!("{other:?}"),
    }
}
