//! docs/reliability.md's tables for decoding a journal record are the build's: the key
//! numbers are `CommandKey::ALL`'s order, each `Command` variant has the index the table
//! gives, and the worked example is the encoder's bytes.
#![cfg(feature = "net")]

mod common;

use tiltbox::protocol::*;
use tiltbox::service::journal::Record;
use tiltbox::service::Command;

fn doc() -> String {
    common::read_repo_file("docs/reliability.md")
}

/// The postcard bytes of a Command record carrying `command` at frame 5, key 0.
fn record(command: Command) -> Vec<u8> {
    postcard::to_stdvec(&Record::Command {
        frame: 5,
        key: 0,
        command: Ok(command),
    })
    .unwrap()
}

#[test]
fn the_key_numbers_are_the_command_keys_in_order() {
    let doc = doc();
    let row = doc
        .lines()
        .find(|l| l.starts_with("| `…/` |"))
        .expect("the key table's names row");
    let names: Vec<&str> = row
        .split('|')
        .map(str::trim)
        .filter(|c| c.starts_with('`') && *c != "`…/`")
        .map(|c| c.trim_matches('`'))
        .collect();
    let keys: Vec<&str> = CommandKey::ALL.iter().map(|k| k.suffix()).collect();
    assert_eq!(names, keys);
}

#[test]
fn each_command_variant_has_the_documented_index() {
    let doc = doc();
    let ref3 = BodyRef {
        index: 3,
        generation: 0,
    };
    let commands = [
        ("SetGravity", Command::SetGravity(Vector::new(0.0, -9.81))),
        (
            "Tilt",
            Command::Tilt(Tilt::Orientation(Orientation::Portrait)),
        ),
        ("Spawn", Command::Spawn(Vec::new())),
        ("Remove", Command::Remove(vec![ref3])),
        ("Reset", Command::Reset),
        (
            "SetVelocity",
            Command::SetVelocity {
                id: ref3,
                velocity: Vector::new(1.0, 0.0),
                angular_velocity: 0.0,
            },
        ),
        ("Drag", Command::Drag(Drag::Release { hand: 7 })),
        (
            "Build",
            Command::Build(Build {
                bodies: Vec::new(),
                joints: Vec::new(),
            }),
        ),
        ("RemoveJoints", Command::RemoveJoints(Vec::new())),
        ("HandGone", Command::HandGone(7)),
    ];
    for (name, command) in commands {
        let bytes = record(command);
        // 00 Command, 05 frame, 00 key, 00 Ok, then the variant index
        assert_eq!(&bytes[..4], &[0, 5, 0, 0]);
        let row = format!("| {} | `{name}` |", bytes[4]);
        assert!(doc.contains(&row), "docs/reliability.md has no row {row:?}");
    }
}

#[test]
fn the_worked_example_is_the_encoders_bytes() {
    let bytes = postcard::to_stdvec(&Record::Command {
        frame: 5,
        key: CommandKey::Drag.index() as u8,
        command: Ok(Command::Drag(Drag::Release { hand: 7 })),
    })
    .unwrap();
    let hex: Vec<String> = bytes.iter().map(|b| format!("{b:02x}")).collect();
    let want = format!("record payload `{}`", hex.join(" "));
    assert!(doc().contains(&want), "{want}");
    // and a Build record carries the message as it arrived: the wire bytes after the version
    let b = Build {
        bodies: Vec::new(),
        joints: vec![JointSpec {
            a: JointEnd::World,
            b: JointEnd::Live(BodyRef {
                index: 4,
                generation: 0,
            }),
            anchor_a: Vector::new(0.0, 5.0),
            anchor_b: Vector::new(0.0, 0.0),
            kind: JointKindSpec::Distance {
                length: None,
                spring: None,
                limit: None,
            },
            collide_connected: false,
            break_force: None,
            break_torque: None,
        }],
    };
    let rec = record(Command::Build(b.clone()));
    assert_eq!(&rec[5..], &encode(&b).unwrap()[1..]);
}
