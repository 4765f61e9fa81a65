//! docs/protocol.md's byte examples for the command messages and the events are the
//! encoder's: each hex block is compared with the encoding of the message its prose
//! describes (built here from the prose, not from the block), the stated sizes are the
//! blocks' sizes, and the worked `Rejected` example's reason is what the daemon really says
//! for that payload. A client written in another language from these examples gets the real
//! bytes.
#![cfg(feature = "net")]

mod common;

use common::read_repo_file;
use tiltbox::protocol::*;
use tiltbox::service::{parse_command, Limits};

/// The bytes of one line of a hex block: its leading two-digit hex tokens (a comment may
/// follow them).
fn line_bytes(line: &str) -> Vec<u8> {
    line.split_whitespace()
        .map_while(|t| {
            (t.len() == 2)
                .then(|| u8::from_str_radix(t, 16).ok())
                .flatten()
        })
        .collect()
}

/// The first ```text block after `marker` in docs/protocol.md, line by line, and the prose
/// between the marker and the block.
fn block_after(marker: &str) -> (Vec<Vec<u8>>, String) {
    let doc = read_repo_file("docs/protocol.md");
    let at = doc
        .find(marker)
        .unwrap_or_else(|| panic!("docs/protocol.md has no {marker:?}"));
    let rest = &doc[at..];
    let open = rest
        .find("```text\n")
        .expect("a text block after the marker");
    let body = &rest[open + 8..];
    let body = &body[..body.find("```").expect("the block's end")];
    let lines = body.lines().map(line_bytes).collect();
    (lines, rest[..open].to_owned())
}

/// All the lines of the block after `marker` as one payload.
fn payload_after(marker: &str) -> (Vec<u8>, String) {
    let (lines, prose) = block_after(marker);
    (lines.concat(), prose)
}

/// The "(N bytes)" the prose states.
fn stated_size(prose: &str) -> usize {
    let end = prose.rfind(" bytes)").expect("a stated size");
    let start = prose[..end].rfind('(').expect("a stated size") + 1;
    prose[start..end].parse().expect("a number of bytes")
}

fn colour(hex: &str) -> Colour {
    hex.parse().expect("a colour")
}

#[test]
fn set_gravity_tilt_remove_and_reset_examples_are_the_encoded_bytes() {
    let (bytes, _) = payload_after("### SetGravity");
    assert_eq!(bytes, encode(&SetGravity { x: 0.0, y: -9.81 }).unwrap());

    let (lines, _) = block_after("send `(-9.81·x, -9.81·y, -9.81·z)`");
    assert_eq!(
        lines[0],
        encode(&Tilt::Orientation(Orientation::PortraitUpsideDown)).unwrap()
    );
    assert_eq!(
        lines[1],
        encode(&Tilt::Accelerometer {
            x: 0.0,
            y: 9.81,
            z: 0.0
        })
        .unwrap()
    );

    let (bytes, _) = payload_after("### Remove");
    let ids = vec![BodyRef {
        index: 3,
        generation: 0,
    }];
    assert_eq!(bytes, encode(&Remove { ids }).unwrap());

    let (bytes, _) = payload_after("### Reset");
    assert_eq!(bytes, encode(&Reset).unwrap());
}

#[test]
fn drag_examples_are_the_encoded_bytes_and_their_sizes_are_stated() {
    let (lines, prose) = block_after("### Drag");
    let id = BodyRef {
        index: 3,
        generation: 0,
    };
    let messages = [
        Drag::Grab {
            hand: 7,
            id,
            point: Vector::new(1.0, 2.0),
        },
        Drag::Move {
            hand: 7,
            target: Vector::new(1.5, 2.0),
        },
        Drag::Release { hand: 7 },
    ];
    for (line, m) in lines.iter().zip(messages) {
        assert_eq!(line, &encode(&m).unwrap(), "{m:?}");
    }
    for (n, line) in [13, 11, 3].iter().zip(&lines) {
        assert!(
            prose.contains(&format!("({n} bytes)")) && line.len() == *n,
            "{line:02x?}"
        );
    }
}

#[test]
fn world_query_examples_are_the_encoded_bytes_and_their_sizes_are_stated() {
    let (lines, prose) = block_after("A ray from (0, 5) straight down 10 m");
    let ray = WorldQuery::RayClosest {
        origin: Vector::new(0.0, 5.0),
        translation: Vector::new(0.0, -10.0),
        filter: QueryFilterSpec::default(),
    };
    let bytes = lines.concat();
    assert_eq!(bytes, encode(&ray).unwrap());
    assert_eq!(stated_size(&prose), bytes.len());
    let (lines, prose) = block_after("Its answer after frame 5");
    let answer = QueryAnswer::Hits {
        frame: 5,
        hits: vec![RayHitInfo {
            hit: ShapeHit {
                id: BodyRef {
                    index: 4,
                    generation: 0,
                },
                shape: 0,
            },
            point: Vector::new(0.0, 0.4),
            normal: Vector::new(0.0, 1.0),
            fraction: 0.46,
        }],
    };
    let bytes = lines.concat();
    assert_eq!(bytes, encode(&answer).unwrap());
    assert_eq!(stated_size(&prose), bytes.len());
    // The default filter's bytes, as the prose spells them out.
    let filter = encode(&QueryFilterSpec::default()).unwrap();
    assert_eq!(
        &filter[1..],
        &[0x01, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01]
    );
}

#[test]
fn the_hits_example_is_the_encoded_event_its_prose_describes() {
    let (bytes, prose) = payload_after("**Worked example (Hits).**");
    let shape = |index| ShapeHit {
        id: BodyRef {
            index,
            generation: 0,
        },
        shape: 0,
    };
    let event = Event {
        frame: 72,
        kind: EventKind::Hits {
            hits: vec![HitInfo {
                pair: ShapePair {
                    a: shape(0),
                    b: shape(10),
                },
                point: Vector::new(0.0, 0.05),
                normal: Vector::new(0.0, 1.0),
                approach_speed: 6.05,
            }],
            dropped: 0,
        },
    };
    assert_eq!(bytes, encode(&event).unwrap());
    assert_eq!(stated_size(&prose), bytes.len());
}

#[test]
fn a_segment_shape_spec_takes_24_to_40_bytes_as_the_tables_say() {
    let segment = |ends: Option<Vector>| ShapeSpec::Segment {
        a: Vector::new(0.0, 0.0),
        b: Vector::new(1.0, 0.0),
        radius: 0.0,
        prev: ends,
        next: ends,
        one_sided: false,
    };
    // A ShapeSpec alone is no message; inside a one-body Spawn it follows a fixed prefix.
    let size = |s: ShapeSpec| {
        let bodies = vec![SpawnBody::at(s, Vector::new(0.0, 0.0))];
        let circle = vec![SpawnBody::at(
            ShapeSpec::Circle { radius: 1.0 },
            Vector::default(),
        )];
        encode(&Spawn { bodies }).unwrap().len() - encode(&Spawn { bodies: circle }).unwrap().len()
            + 5
    };
    assert_eq!(size(segment(None)), 24);
    assert_eq!(size(segment(Some(Vector::new(2.0, 0.0)))), 40);
    let doc = read_repo_file("docs/protocol.md");
    assert_eq!(
        doc.matches("24 to 40").count(),
        2,
        "both tables state 24 to 40"
    );
    assert!(!doc.contains("23 to 39"));
}

#[test]
fn the_checkpoint_version_reliability_md_states_is_the_builds() {
    let doc = read_repo_file("docs/reliability.md");
    let stated = format!(
        "writes and reads format version {} only",
        tiltbox::service::checkpoint::FORMAT_VERSION
    );
    assert!(
        doc.contains(&stated),
        "docs/reliability.md lacks {stated:?}"
    );
}

#[test]
fn spawn_examples_are_the_encoded_bytes_of_the_bodies_described() {
    let (bytes, prose) = payload_after("A 0.5 m crate named \"crate\"");
    let crate_body = SpawnBody {
        name: Some("crate".into()),
        friction: 0.5,
        colour: colour("#d64541"),
        ..SpawnBody::at(
            ShapeSpec::Rect {
                width: 0.5,
                height: 0.5,
            },
            Vector::new(0.0, 2.0),
        )
    };
    let spawn = Spawn {
        bodies: vec![crate_body],
    };
    assert_eq!(bytes, encode(&spawn).unwrap());
    assert_eq!(bytes.len(), stated_size(&prose));

    let (bytes, prose) = payload_after("A ball named \"ball\"");
    let ball = SpawnBody {
        name: Some("ball".into()),
        friction: 0.5,
        restitution: 0.5,
        colour: colour("#3a7bd5"),
        ..SpawnBody::at(ShapeSpec::Circle { radius: 0.25 }, Vector::new(0.0, 3.0))
    };
    assert_eq!(bytes, encode(&Spawn { bodies: vec![ball] }).unwrap());
    assert_eq!(bytes.len(), stated_size(&prose));

    let (bytes, prose) = payload_after("An unnamed right triangle");
    let vertices = vec![
        Vector::new(0.0, 0.0),
        Vector::new(1.5, 0.0),
        Vector::new(0.0, 0.75),
    ];
    let triangle = SpawnBody {
        friction: 0.5,
        colour: colour("#2ecc71"),
        ..SpawnBody::at(ShapeSpec::Polygon { vertices }, Vector::new(-1.0, 2.0))
    };
    let spawn = Spawn {
        bodies: vec![triangle],
    };
    assert_eq!(bytes, encode(&spawn).unwrap());
    assert_eq!(bytes.len(), stated_size(&prose));
}

#[test]
fn the_event_examples_decode_to_what_their_prose_says() {
    // Rejected: the reason is the daemon's own for a gravity payload of one version byte.
    let (bytes, _) = payload_after("**Worked example (Rejected).**");
    let reason = parse_command(CommandKey::Gravity, &[VERSION], &Limits::default())
        .expect_err("a bare version byte is refused");
    let event = Event {
        frame: 1,
        kind: EventKind::Rejected {
            key: "tiltbox/bricks/gravity".into(),
            reason,
        },
    };
    assert_eq!(bytes, encode(&event).unwrap());

    // Added: the crate spawned above, as the daemon reports it (mass 0.5 x 0.5 x 1).
    let (bytes, prose) = payload_after("**Worked example (Added).**");
    let event: Event = decode(&bytes).expect("the Added example decodes");
    assert_eq!(encode(&event).unwrap(), bytes, "and is canonical");
    assert_eq!(bytes.len(), stated_size(&prose));
    let EventKind::Added { bodies } = event.kind else {
        panic!("not an Added event: {event:?}")
    };
    let b = &bodies[0];
    assert_eq!(
        (b.id, b.name.as_str(), b.mass, b.friction, b.colour),
        (
            BodyRef {
                index: 3,
                generation: 0
            },
            "crate",
            0.25,
            0.5,
            colour("#d64541")
        )
    );
    assert_eq!(b.position, Vector::new(0.0, 2.0));
}

#[test]
fn build_remove_joints_and_joints_broken_examples_are_the_encoded_bytes() {
    let (bytes, prose) = payload_after("### Build");
    let v = Vector::new;
    let body = |motion, position, colour: &str, shape| BuildBody {
        colour: colour.parse().unwrap(),
        ..BuildBody::new(motion, position, vec![PartSpec::at(shape, v(0.0, 0.0))])
    };
    let pendulum = Build {
        bodies: vec![
            body(
                Motion::Static,
                v(0.0, 5.0),
                "#5b5b66",
                ShapeSpec::Rect {
                    width: 0.25,
                    height: 0.25,
                },
            ),
            body(
                Motion::Dynamic,
                v(1.5, 5.0),
                "#d64541",
                ShapeSpec::Circle { radius: 0.25 },
            ),
        ],
        joints: vec![JointSpec::hinge(
            JointEnd::New(0),
            JointEnd::New(1),
            v(0.0, 0.0),
            v(-1.5, 0.0),
        )],
    };
    assert_eq!(bytes, encode(&pendulum).unwrap());
    assert_eq!(stated_size(&prose), bytes.len());
    // "With the defaults a part takes its shape's bytes + 39": a rect part is 9 + 39.
    let part = PartSpec::at(
        ShapeSpec::Rect {
            width: 1.0,
            height: 1.0,
        },
        v(0.0, 0.0),
    );
    assert!(prose.contains("its shape's bytes + 39"));
    assert_eq!(postcard::to_allocvec(&part).unwrap().len(), 9 + 39);
    // and the daemon accepts it
    assert!(parse_command(CommandKey::Build, &bytes, &Limits::default()).is_ok());

    let (bytes, prose) = payload_after("### RemoveJoints");
    let ids = vec![JointRef {
        index: 2,
        generation: 0,
    }];
    assert_eq!(bytes, encode(&RemoveJoints { ids }).unwrap());
    assert_eq!(stated_size(&prose), bytes.len());

    let (bytes, prose) = payload_after("**Worked example (JointsBroken).**");
    let broken = Event {
        frame: 300,
        kind: EventKind::JointsBroken {
            joints: vec![BrokenJoint {
                id: JointRef {
                    index: 2,
                    generation: 0,
                },
                force: 9.75,
                torque: 0.0,
            }],
        },
    };
    assert_eq!(bytes, encode(&broken).unwrap());
    assert_eq!(stated_size(&prose), bytes.len());
}

#[test]
fn a_compound_takes_two_bytes_and_its_parts_as_the_shape_table_says() {
    // "2 + per part its shape + 12": a rect (9) and a circle (5) part.
    let c = ShapeSpec::Compound {
        parts: vec![
            PartShape {
                shape: ShapeSpec::Rect {
                    width: 1.0,
                    height: 0.25,
                },
                offset: Vector::new(0.0, 0.0),
                angle: 0.0,
            },
            PartShape {
                shape: ShapeSpec::Circle { radius: 0.25 },
                offset: Vector::new(0.5, 0.0),
                angle: 0.0,
            },
        ],
    };
    let doc = read_repo_file("docs/protocol.md");
    assert!(doc.contains("| 2 + per part its shape + 12 |"));
    assert_eq!(
        postcard::to_allocvec(&c).unwrap().len(),
        2 + (9 + 12) + (5 + 12)
    );
}
