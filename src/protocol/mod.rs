//! The wire protocol: message types, key expressions, encoding and decoding.
//!
//! Every payload is one byte of protocol version ([`VERSION`]) followed by the message in
//! postcard: integers as varints (LEB128, zig-zag for signed), `f32`/`f64` little-endian,
//! sequences and strings prefixed with their length as a varint, `Option` as a 0/1 byte, enum
//! variants as their index (varint) followed by their fields, structs as their fields in
//! order. `docs/protocol.md` lays out every message byte for byte.
//!
//! [`decode`] never panics: it returns a [`DecodeError`] saying what was wrong.

mod bounded;
pub mod build;
pub mod keys;
pub mod messages;
pub mod rate;
pub mod snapshot;
pub mod tilt;

pub use build::{
    BrokenJoint, Build, BuildBody, FilterSpec, JointEnd, JointInfo, JointKindSpec, JointRef,
    JointSpec, LimitSpec, Motion, MotorSpec, PartShape, PartSpec, RemoveJoints, SceneWithJoints,
    SpringSpec, MAX_PARTS,
};
pub use keys::{CommandKey, KeyError, Keys, DEFAULT_WORLD};
pub use messages::{
    BodyInfo, BodyRef, Colour, Event, EventKind, Orientation, Pose, Remove, Reset, SceneState,
    SetGravity, ShapeSpec, Snapshot, Spawn, SpawnBody, Stats, Tilt, Vector,
};
pub use messages::{
    Drag, HitInfo, QueryAnswer, QueryFilterSpec, RayHitInfo, SetVelocity, ShapeHit, ShapePair,
    WorldQuery,
};
pub use rate::RateLimit;
pub use snapshot::{
    decode_frame, encode_frame, Grid, GridPose, SnapshotDecoder, SnapshotEncoder, SnapshotFrame,
    SNAPSHOT_VERSION,
};
pub use tilt::gravity_from_accelerometer;

use serde::de::DeserializeOwned;
use serde::Serialize;
use thiserror::Error;

/// The protocol version: the first byte of every payload.
pub const VERSION: u8 = 1;

/// A message of this protocol, with its name for error messages.
pub trait Message: Serialize + DeserializeOwned {
    /// The message's name, e.g. `Snapshot`.
    const NAME: &'static str;
}

macro_rules! messages {
    ($($t:ident),*) => { $(impl Message for $t { const NAME: &'static str = stringify!($t); })* };
}
messages!(SetGravity, Tilt, Spawn, Remove, Reset, Event, SceneState, Stats);
messages!(SetVelocity, Drag, WorldQuery, QueryAnswer, QueryFilterSpec);
messages!(Build, RemoveJoints, SceneWithJoints);

/// Why a payload could not be decoded.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
pub enum DecodeError {
    /// The payload has no bytes at all.
    #[error("empty payload (expected a {message} with protocol version {VERSION})")]
    Empty {
        /// The message expected.
        message: &'static str,
    },
    /// The first byte is not a version this build speaks.
    #[error("unsupported protocol version {found} (this server speaks {VERSION})")]
    Version {
        /// The version byte found.
        found: u8,
    },
    /// The payload ended in the middle of a field.
    #[error("truncated {message}: the payload ended in the middle of a field")]
    Truncated {
        /// The message expected.
        message: &'static str,
    },
    /// An enum variant index this version does not know (or another invalid value).
    #[error("unknown variant in {message}: an enum variant index this version does not define")]
    UnknownVariant {
        /// The message expected.
        message: &'static str,
    },
    /// A polygon's vertex count above the limit, refused as soon as its length was read
    /// (the vertices themselves are not read, so a count larger than the payload is named
    /// as such, not as a truncated payload).
    #[error("{}shape.vertices must hold 3 to {} points, got {count}", .body.map(|i| format!("bodies[{i}]: ")).unwrap_or_default(), crate::physics::convex::MAX_VERTICES)]
    TooManyVertices {
        /// Index of the spawn body, when the polygon was in a spawn.
        body: Option<usize>,
        /// The vertex count the payload claims.
        count: usize,
    },
    /// A field had bytes that are not a valid value of its type.
    #[error("malformed {message}: {what}")]
    Malformed {
        /// The message expected.
        message: &'static str,
        /// What was wrong, e.g. `a string is not valid UTF-8`.
        what: &'static str,
    },
    /// A `…/poses` payload in another snapshot encoding than [`SNAPSHOT_VERSION`] (version 1
    /// carried `f32` poses; an older client meets version 2 as its own `Version` error).
    #[error("unsupported snapshot encoding version {found} on …/poses (this build decodes version {SNAPSHOT_VERSION}, quantized poses)")]
    SnapshotVersion {
        /// The version byte found.
        found: u8,
    },
    /// Bytes were left over after the message.
    #[error("{count} unexpected byte(s) after the end of a {message}")]
    TrailingBytes {
        /// The message expected.
        message: &'static str,
        /// How many bytes were left.
        count: usize,
    },
}

/// Why a message could not be encoded (only possible with types this protocol does not use).
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[error("cannot encode {message}: {source}")]
pub struct EncodeError {
    /// The message.
    pub message: &'static str,
    /// postcard's error.
    pub source: postcard::Error,
}

/// Encode `msg` as a payload: the version byte, then postcard.
pub fn encode<M: Message>(msg: &M) -> Result<Vec<u8>, EncodeError> {
    let mut out = Vec::with_capacity(64);
    encode_into(msg, &mut out)?;
    Ok(out)
}

/// Encode `msg` into `out` (cleared first), reusing its allocation.
pub fn encode_into<M: Message>(msg: &M, out: &mut Vec<u8>) -> Result<(), EncodeError> {
    out.clear();
    out.push(VERSION);
    let buf = std::mem::take(out);
    *out = postcard::to_extend(msg, buf).map_err(|source| EncodeError {
        message: M::NAME,
        source,
    })?;
    Ok(())
}

/// Decode a payload made by [`encode`]: checks the version, decodes, refuses trailing bytes.
pub fn decode<M: Message>(bytes: &[u8]) -> Result<M, DecodeError> {
    let message = M::NAME;
    let (&version, body) = bytes.split_first().ok_or(DecodeError::Empty { message })?;
    if version != VERSION {
        return Err(DecodeError::Version { found: version });
    }
    bounded::reset();
    let (msg, rest) = postcard::take_from_bytes::<M>(body).map_err(|e| {
        use postcard::Error as P;
        if let Some((body, count)) = bounded::take_refused() {
            return DecodeError::TooManyVertices { body, count };
        }
        if let Some(what) = bounded::take_refused_parts() {
            return DecodeError::Malformed { message, what };
        }
        let malformed = |what| DecodeError::Malformed { message, what };
        match e {
            P::DeserializeUnexpectedEnd => DecodeError::Truncated { message },
            // Our types have no custom validation: serde's only "custom" error for them is
            // an out-of-range enum variant index.
            P::SerdeDeCustom | P::DeserializeBadEnum => DecodeError::UnknownVariant { message },
            P::DeserializeBadVarint => malformed("a varint is longer than its type allows"),
            P::DeserializeBadBool => malformed("a bool byte is neither 0 nor 1"),
            P::DeserializeBadOption => malformed("an option tag is neither 0 nor 1"),
            P::DeserializeBadUtf8 | P::DeserializeBadChar => {
                malformed("a string is not valid UTF-8")
            }
            _ => malformed("not a valid encoding"),
        }
    })?;
    if !rest.is_empty() {
        return Err(DecodeError::TrailingBytes {
            message,
            count: rest.len(),
        });
    }
    Ok(msg)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body() -> SpawnBody {
        SpawnBody {
            name: Some("crate".into()),
            shape: ShapeSpec::Rect {
                width: 1.0,
                height: 0.5,
            },
            position: Vector::new(1.0, 2.0),
            angle: 0.25,
            velocity: Vector::new(-1.0, 0.0),
            angular_velocity: 3.0,
            density: 2.0,
            friction: 0.6,
            restitution: 0.1,
            colour: Colour {
                r: 0xd6,
                g: 0x45,
                b: 0x41,
            },
        }
    }

    fn info() -> BodyInfo {
        let id = BodyRef {
            index: 300,
            generation: 2,
        };
        let shape = ShapeSpec::Rect {
            width: 10.0,
            height: 1.0,
        };
        BodyInfo {
            name: "wall".into(),
            ..BodyInfo::wall(id, shape, Vector::new(0.0, -0.5))
        }
    }

    /// One of each shape kind, as a spawn or the daemon would carry it.
    fn shapes() -> [ShapeSpec; 4] {
        [
            ShapeSpec::Rect {
                width: 1.0,
                height: 0.5,
            },
            ShapeSpec::Circle { radius: 0.25 },
            ShapeSpec::Capsule {
                length: 2.0,
                radius: 0.5,
            },
            ShapeSpec::Polygon {
                vertices: vec![
                    Vector::new(0.0, 0.0),
                    Vector::new(1.5, 0.0),
                    Vector::new(0.0, 0.75),
                ],
            },
        ]
    }

    fn round_trip<M: Message + PartialEq + std::fmt::Debug>(m: M) {
        let bytes = encode(&m).unwrap();
        assert_eq!(bytes[0], VERSION);
        assert_eq!(decode::<M>(&bytes).unwrap(), m);
    }

    #[test]
    fn every_message_round_trips() {
        round_trip(SetGravity { x: 3.0, y: -1.0 });
        round_trip(Tilt::Orientation(Orientation::LandscapeRight));
        round_trip(Tilt::Accelerometer {
            x: 0.1,
            y: 9.7,
            z: 1.0,
        });
        round_trip(Spawn {
            bodies: vec![
                body(),
                SpawnBody {
                    name: None,
                    ..body()
                },
            ],
        });
        round_trip(Spawn {
            bodies: shapes()
                .into_iter()
                .map(|shape| SpawnBody { shape, ..body() })
                .collect(),
        });
        round_trip(Remove {
            ids: vec![BodyRef {
                index: 1,
                generation: 70000,
            }],
        });
        round_trip(Reset);
        for kind in [
            EventKind::Added {
                bodies: vec![info()],
            },
            EventKind::Removed {
                ids: vec![info().id],
            },
            EventKind::Reset {
                scene: "Falling Bricks".into(),
                gravity: Vector::new(0.0, -9.81),
                bodies: vec![info(), info()],
            },
            EventKind::Added {
                bodies: shapes()
                    .into_iter()
                    .map(|shape| BodyInfo { shape, ..info() })
                    .collect(),
            },
            EventKind::Rejected {
                key: "tiltbox/bricks/spawn".into(),
                reason: "density must be > 0".into(),
            },
        ] {
            round_trip(Event { frame: 9, kind });
        }
        round_trip(SceneState {
            world: "bricks".into(),
            scene: "Falling Bricks".into(),
            frame: 60,
            time: 1.0,
            gravity: Vector::new(0.0, -9.81),
            bodies: vec![info()],
        });
        round_trip(Stats {
            frame: 600,
            bodies: 42,
            awake: 38,
            contacts: 80,
            step_us_median: 120,
            step_us_max: 400,
            lateness_us_max: 90,
            commands_applied: 3,
            commands_rejected: 1,
            steps_dropped: 0,
            commands_received: 6,
            commands_dropped: 2,
        });
    }

    #[test]
    fn small_messages_have_the_documented_bytes() {
        // version 1, variant 1 (Accelerometer), three f32 LE
        let b = encode(&Tilt::Accelerometer {
            x: 0.0,
            y: -9.81,
            z: 0.0,
        })
        .unwrap();
        assert_eq!(b, [1, 1, 0, 0, 0, 0, 0xc3, 0xf5, 0x1c, 0xc1, 0, 0, 0, 0]);
        assert_eq!(
            encode(&Tilt::Orientation(Orientation::PortraitUpsideDown)).unwrap(),
            [1, 0, 1]
        );
        assert_eq!(encode(&Reset).unwrap(), [1]);
        assert_eq!(
            encode(&SetGravity { x: 0.0, y: -9.81 }).unwrap(),
            [1, 0, 0, 0, 0, 0xc3, 0xf5, 0x1c, 0xc1]
        );
        // id 300v2: 300 = 0b10_0101100 -> 0xac 0x02
        assert_eq!(
            encode(&Remove {
                ids: vec![BodyRef {
                    index: 300,
                    generation: 2
                }]
            })
            .unwrap(),
            [1, 1, 0xac, 0x02, 0x02]
        );
    }

    #[test]
    fn every_shape_kind_has_the_documented_bytes() {
        // variant index as a varint, then the fields: f32 little-endian, a Vec's length as a
        // varint. 1.0 = 0x3f800000, 0.5 = 0x3f000000, 0.25 = 0x3e800000, 2.0 = 0x40000000,
        // 1.5 = 0x3fc00000, 0.75 = 0x3f400000.
        let expected: [&[u8]; 4] = [
            &[0, 0, 0, 0x80, 0x3f, 0, 0, 0, 0x3f],
            &[1, 0, 0, 0x80, 0x3e],
            &[2, 0, 0, 0, 0x40, 0, 0, 0, 0x3f],
            &[
                3, 3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xc0, 0x3f, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x40,
                0x3f,
            ],
        ];
        for (shape, want) in shapes().iter().zip(expected) {
            assert_eq!(postcard::to_allocvec(shape).unwrap(), want, "{shape:?}");
        }
        // BodyInfo sizes per kind, for a body with an index < 128 and an empty name:
        // id 2 + name 1 + shape + static 1 + colour 3 + position 8 + angle 4 + velocity 8
        // + spin 4 + mass, friction, restitution 12 = 43 + shape.
        for (shape, size) in shapes().into_iter().zip([52, 48, 52, 69]) {
            let b = BodyInfo {
                id: BodyRef {
                    index: 3,
                    generation: 0,
                },
                name: String::new(),
                shape,
                ..info()
            };
            assert_eq!(postcard::to_allocvec(&b).unwrap().len(), size, "{b:?}");
        }
        // a shape index this version does not define
        let mut spawn = encode(&Spawn {
            bodies: vec![SpawnBody {
                name: None,
                ..body()
            }],
        })
        .unwrap();
        assert_eq!(
            spawn[3], 0,
            "version, count, None, then the shape's variant"
        );
        spawn[3] = 6; // 4 is Segment since issue 17, 5 Compound since issue 33
        assert_eq!(
            decode::<Spawn>(&spawn),
            Err(DecodeError::UnknownVariant { message: "Spawn" })
        );
    }

    #[test]
    fn bad_payloads_give_typed_errors() {
        assert_eq!(
            decode::<Tilt>(&[]),
            Err(DecodeError::Empty { message: "Tilt" })
        );
        assert_eq!(
            decode::<Tilt>(&[2, 0, 0]),
            Err(DecodeError::Version { found: 2 })
        );
        assert_eq!(
            decode::<Tilt>(&[1, 9]),
            Err(DecodeError::UnknownVariant { message: "Tilt" })
        );
        assert_eq!(
            decode::<Tilt>(&[1, 0, 6]),
            Err(DecodeError::UnknownVariant { message: "Tilt" })
        );
        assert_eq!(
            decode::<SetGravity>(&[1, 0, 0, 0]),
            Err(DecodeError::Truncated {
                message: "SetGravity"
            })
        );
        assert_eq!(
            decode::<Reset>(&[1, 0]),
            Err(DecodeError::TrailingBytes {
                message: "Reset",
                count: 1
            })
        );
        let mut spawn = encode(&Spawn {
            bodies: vec![body()],
        })
        .unwrap();
        // byte 2 is the name's option tag (Some = 1): 7 is not a tag
        spawn[2] = 7;
        assert!(matches!(
            decode::<Spawn>(&spawn),
            Err(DecodeError::Malformed { .. })
        ));
        // a huge length prefix on a short payload is reported, not allocated
        assert!(decode::<Spawn>(&[1, 0xff, 0xff, 0xff, 0xff, 0x0f]).is_err());
        // a 10-byte varint for a u64 frame that overflows
        let mut bad = vec![1];
        bad.extend([0xff; 11]);
        assert!(matches!(
            decode::<Stats>(&bad),
            Err(DecodeError::Malformed { .. })
        ));
        // every prefix of a valid payload is an error, never a panic
        let full = encode(&Spawn {
            bodies: vec![body()],
        })
        .unwrap();
        for n in 0..full.len() {
            assert!(decode::<Spawn>(&full[..n]).is_err(), "prefix {n}");
        }
    }
}
