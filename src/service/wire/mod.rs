//! The daemon's one boundary between the wire and the engine. Inward: a payload on a command
//! key is decoded and every field checked against the engine's rules and the daemon's
//! [`Limits`] ([`parse_command`]; spawned bodies in [`spawn`]), so nothing unchecked reaches
//! the tick thread. Outward: engine shapes, vectors and bodies become the protocol's
//! [`ShapeSpec`], [`Vector`] and [`BodyInfo`]. Pure and non-blocking: the Zenoh callbacks run
//! it.
//!
//! Placement rules shared with scene files (a capsule's length against its radius, a polygon
//! given around a position) are the engine's own constructors, `Shape::try_capsule` and
//! `BodyDef::placed`; numbers on the wire are `f32` whatever the engine's [`Real`] is.

#![allow(clippy::unnecessary_cast)] // Real <-> f32 casts matter with the `f64` feature.

pub(crate) mod build;
pub(crate) mod spawn;

use super::command::Command;
use super::config::Limits;
use crate::physics::{Body, Real, Shape, Vec2};
use crate::protocol::{
    decode, BodyInfo, Build, CommandKey, DecodeError, Drag, Remove, RemoveJoints, Reset,
    SetGravity, SetVelocity, ShapeSpec, Spawn, Tilt, Vector, WorldQuery,
};

/// Decode and validate a payload that arrived on `key`: the command to apply, or the reason
/// it is refused, naming the field and the value as sent.
pub fn parse_command(key: CommandKey, payload: &[u8], limits: &Limits) -> Result<Command, String> {
    if payload.len() > limits.max_payload_bytes as usize {
        return Err(format!(
            "payload of {} bytes is larger than limits.max_payload_bytes = {}",
            payload.len(),
            limits.max_payload_bytes
        ));
    }
    let bad = |e: DecodeError| e.to_string();
    match key {
        CommandKey::Gravity => {
            let g: SetGravity = decode(payload).map_err(bad)?;
            finite("gravity.x", g.x)?;
            finite("gravity.y", g.y)?;
            magnitude("|gravity|", g.x.hypot(g.y), limits.max_gravity)?;
            Ok(Command::SetGravity(Vector::new(g.x, g.y)))
        }
        CommandKey::Tilt => {
            let t: Tilt = decode(payload).map_err(bad)?;
            if let Tilt::Accelerometer { x, y, z } = t {
                finite("tilt.x", x)?;
                finite("tilt.y", y)?;
                finite("tilt.z", z)?;
                let m = (x * x + y * y + z * z).sqrt();
                magnitude("|tilt|", m, limits.max_gravity)?;
            }
            Ok(Command::Tilt(t))
        }
        CommandKey::Spawn => {
            let s: Spawn = decode(payload).map_err(bad)?;
            if s.bodies.is_empty() {
                return Err("bodies is empty: nothing to spawn".into());
            }
            let max = limits.max_bodies_per_spawn;
            if s.bodies.len() > max as usize {
                return Err(format!(
                    "{} bodies in one spawn, more than limits.max_bodies_per_spawn = {max}",
                    s.bodies.len()
                ));
            }
            let defs = s
                .bodies
                .into_iter()
                .enumerate()
                .map(|(i, b)| spawn::spawn_def(b, limits).map_err(|e| format!("bodies[{i}]: {e}")))
                .collect::<Result<Vec<_>, String>>()?;
            Ok(Command::Spawn(defs))
        }
        CommandKey::Remove => {
            let r: Remove = decode(payload).map_err(bad)?;
            if r.ids.is_empty() {
                return Err("ids is empty: nothing to remove".into());
            }
            Ok(Command::Remove(r.ids))
        }
        CommandKey::Reset => {
            let Reset = decode(payload).map_err(bad)?;
            Ok(Command::Reset)
        }
        CommandKey::Velocity => {
            // The speed cap and the body's kind are the World's to check when applied.
            let v: SetVelocity = decode(payload).map_err(bad)?;
            finite("velocity.x", v.velocity.x)?;
            finite("velocity.y", v.velocity.y)?;
            finite("angular_velocity", v.angular_velocity)?;
            Ok(Command::SetVelocity {
                id: v.id,
                velocity: v.velocity,
                angular_velocity: v.angular_velocity,
            })
        }
        CommandKey::Drag => {
            let d: Drag = decode(payload).map_err(bad)?;
            let at = match d {
                Drag::Grab { point, .. } => Some(("point", point)),
                Drag::Move { target, .. } => Some(("target", target)),
                Drag::Release { .. } => None,
            };
            if let Some((field, p)) = at {
                for (axis, v) in [("x", p.x), ("y", p.y)] {
                    let name = format!("{field}.{axis}");
                    finite(&name, v)?;
                    if v.abs() > limits.max_coordinate {
                        return Err(format!(
                            "{name} = {v} is out of range: must be within +-{} m \
                             (limits.max_coordinate)",
                            limits.max_coordinate
                        ));
                    }
                }
            }
            Ok(Command::Drag(d))
        }
        CommandKey::Build => {
            let b: Build = decode(payload).map_err(bad)?;
            build::check_build(&b, limits)?;
            Ok(Command::Build(b))
        }
        CommandKey::RemoveJoints => {
            let r: RemoveJoints = decode(payload).map_err(bad)?;
            if r.ids.is_empty() {
                return Err("ids is empty: no joint to remove".into());
            }
            Ok(Command::RemoveJoints(r.ids))
        }
    }
}

/// Check a `…/query` request: every coordinate finite and within `limits.max_coordinate`
/// (the box's corners, the ray's origin and translation, the point), a box's corners in order
/// (the World checks that, naming them, when it answers).
pub fn check_query(q: &WorldQuery, limits: &Limits) -> Result<(), String> {
    let fields: &[(&str, Vector)] = match q {
        WorldQuery::RayClosest {
            origin,
            translation,
            ..
        }
        | WorldQuery::RayAll {
            origin,
            translation,
            ..
        } => &[("origin", *origin), ("translation", *translation)],
        WorldQuery::Point { point, .. } => &[("point", *point)],
        WorldQuery::Box { min, max, .. } => &[("min", *min), ("max", *max)],
    };
    for &(field, v) in fields {
        for (axis, value) in [("x", v.x), ("y", v.y)] {
            let name = format!("{field}.{axis}");
            finite(&name, value)?;
            if value.abs() > limits.max_coordinate {
                return Err(format!(
                    "{name} = {value} is out of range: must be within +-{} m (limits.max_coordinate)",
                    limits.max_coordinate
                ));
            }
        }
    }
    Ok(())
}

/// A number as sent must be finite; the refusal names the field and quotes the value.
pub(crate) fn finite(field: &str, v: f32) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{field} must be a finite number, got {v}"))
    }
}

/// An acceleration as sent must be at most `max` m/s^2 (`limits.max_gravity`).
fn magnitude(field: &str, v: f32, max: f32) -> Result<(), String> {
    if v <= max {
        Ok(())
    } else {
        Err(format!(
            "{field} = {v} is out of range: must be <= {max} m/s^2 (limits.max_gravity)"
        ))
    }
}

/// The engine vector for a wire vector.
pub(crate) fn vec2(v: Vector) -> Vec2 {
    Vec2::new(v.x as Real, v.y as Real)
}

/// The wire vector for an engine vector.
pub(crate) fn vector(v: Vec2) -> Vector {
    Vector::new(v.x as f32, v.y as f32)
}

/// The wire form of an engine shape (its sizes in metres).
pub(crate) fn shape_spec(shape: &Shape) -> ShapeSpec {
    match *shape {
        Shape::Rect { half_extents } => ShapeSpec::Rect {
            width: 2.0 * half_extents.x as f32,
            height: 2.0 * half_extents.y as f32,
        },
        Shape::Circle { radius } => ShapeSpec::Circle {
            radius: radius as f32,
        },
        Shape::Capsule {
            half_length,
            radius,
        } => ShapeSpec::Capsule {
            length: 2.0 * (half_length + radius) as f32,
            radius: radius as f32,
        },
        Shape::Polygon(ref p) => ShapeSpec::Polygon {
            vertices: p.vertices().iter().map(|&v| vector(v)).collect(),
        },
        Shape::Segment(ref s) => ShapeSpec::Segment {
            a: vector(s.a),
            b: vector(s.b),
            radius: s.radius as f32,
            prev: s.prev.map(vector),
            next: s.next.map(vector),
            one_sided: s.one_sided,
        },
    }
}

/// What the daemon keeps about a body besides the engine's state: fixed for its lifetime, and
/// stored in checkpoints.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyMeta {
    /// Name (may be empty).
    pub name: String,
    /// Colour.
    pub colour: crate::protocol::Colour,
    /// Immovable.
    pub is_static: bool,
    /// Shape, in its wire form.
    pub shape: ShapeSpec,
    /// Mass (kg), 0 for static and kinematic bodies.
    pub mass: f32,
    /// Friction coefficient.
    pub friction: f32,
    /// Restitution.
    pub restitution: f32,
}

impl BodyMeta {
    /// The description of `body`, named `name` and drawn in `colour`.
    pub(crate) fn of(body: &Body, name: String, colour: crate::protocol::Colour) -> BodyMeta {
        BodyMeta {
            name,
            colour,
            is_static: body.is_static(),
            shape: build::body_shape_spec(body),
            // Kinematic bodies too: their mass is infinite.
            mass: if body.inv_mass() == 0.0 {
                0.0
            } else {
                body.mass() as f32
            },
            friction: body.friction() as f32,
            restitution: body.restitution() as f32,
        }
    }
}

/// Everything about `body` as the `…/scene` reply and the `Added` and `Reset` events carry it.
pub(crate) fn body_info(body: &Body, meta: &BodyMeta) -> BodyInfo {
    BodyInfo {
        id: body.id().into(),
        name: meta.name.clone(),
        shape: meta.shape.clone(),
        is_static: meta.is_static,
        colour: meta.colour,
        position: vector(body.position()),
        angle: body.angle() as f32,
        velocity: vector(body.linear_velocity()),
        angular_velocity: body.angular_velocity() as f32,
        mass: meta.mass,
        friction: meta.friction,
        restitution: meta.restitution,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{encode, Orientation, SpawnBody};

    #[test]
    fn valid_commands_parse() {
        let l = Limits::default();
        let p = encode(&SetGravity { x: 3.0, y: 0.0 }).unwrap();
        assert_eq!(
            parse_command(CommandKey::Gravity, &p, &l),
            Ok(Command::SetGravity(Vector::new(3.0, 0.0)))
        );
        let p = encode(&Tilt::Orientation(Orientation::FaceUp)).unwrap();
        assert!(parse_command(CommandKey::Tilt, &p, &l).is_ok());
        let body = SpawnBody::at(
            ShapeSpec::Rect {
                width: 1.0,
                height: 0.5,
            },
            Vector::new(0.0, 3.0),
        );
        let p = encode(&Spawn {
            bodies: vec![body.clone(), body],
        })
        .unwrap();
        assert!(
            matches!(parse_command(CommandKey::Spawn, &p, &l), Ok(Command::Spawn(v)) if v.len() == 2)
        );
        assert_eq!(
            parse_command(CommandKey::Reset, &[1], &l),
            Ok(Command::Reset)
        );
    }

    #[test]
    fn bad_fields_are_named_with_their_value() {
        let l = Limits::default();
        let p = encode(&SetGravity {
            x: f32::NAN,
            y: 0.0,
        })
        .unwrap();
        let e = parse_command(CommandKey::Gravity, &p, &l).unwrap_err();
        assert!(e.contains("gravity.x") && e.contains("NaN"), "{e}");
        let p = encode(&SetGravity { x: 1e6, y: 0.0 }).unwrap();
        assert!(parse_command(CommandKey::Gravity, &p, &l)
            .unwrap_err()
            .contains("|gravity| = 1000000"));
        let p = encode(&Tilt::Accelerometer {
            x: 0.0,
            y: f32::INFINITY,
            z: 0.0,
        })
        .unwrap();
        assert!(parse_command(CommandKey::Tilt, &p, &l)
            .unwrap_err()
            .contains("tilt.y"));
        let body = SpawnBody::at(ShapeSpec::Circle { radius: 0.5 }, Vector::new(0.0, 3.0));
        let p = encode(&Spawn {
            bodies: vec![body.clone(); 65],
        })
        .unwrap();
        let e = parse_command(CommandKey::Spawn, &p, &l).unwrap_err();
        assert!(e.contains("max_bodies_per_spawn = 64"), "{e}");
        let e = parse_command(CommandKey::Spawn, &vec![1; 70000], &l).unwrap_err();
        assert!(e.contains("max_payload_bytes"), "{e}");
        let e = parse_command(CommandKey::Tilt, &[1, 7], &l).unwrap_err();
        assert!(e.contains("unknown variant"), "{e}");
        let p = encode(&Remove { ids: vec![] }).unwrap();
        let e = parse_command(CommandKey::Remove, &p, &l).unwrap_err();
        assert_eq!(e, "ids is empty: nothing to remove");
    }

    #[test]
    fn engine_shapes_go_out_as_the_shapes_they_came_in_as() {
        for shape in [
            Shape::rect(1.0, 0.5),
            Shape::circle(0.25),
            Shape::capsule(2.0, 0.5),
        ] {
            let (back, offset) = spawn::shape_from_spec(&shape_spec(&shape)).unwrap();
            assert_eq!((back, offset), (shape, Vec2::ZERO));
        }
    }
}
