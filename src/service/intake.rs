//! From a payload on a command key to a validated [`Command`]: what the Zenoh callbacks run.
//! Pure and non-blocking: decode, check every field, `try_send` into the tick thread's channel.

#![allow(clippy::unnecessary_cast)] // Real <-> f32 casts matter with the `f64` feature.

use super::config::Limits;
use crate::physics::{BodyDef, BodyId, MassSpec, PhysicsError, Polygon, Real, Shape, Vec2};
use crate::protocol::{
    decode, Colour, CommandKey, Remove, Reset, SetGravity, ShapeSpec, Spawn, SpawnBody, Tilt,
    Vector,
};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{SyncSender, TrySendError};
use std::sync::Arc;

/// A body to add, validated.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SpawnDef {
    /// The engine's definition (passed `BodyDef::validate`).
    #[serde(with = "compact_def")]
    pub def: BodyDef,
    /// Name (may be empty).
    pub name: String,
    /// Colour.
    pub colour: Colour,
}

/// `BodyDef` for the journal's postcard, with vectors as plain arrays so the f32 and f64
/// builds write the same layout per precision.
mod compact_def {
    use crate::physics::{BodyDef, MassSpec, Real, Shape, Vec2};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    #[derive(Serialize, Deserialize)]
    struct Compact {
        shape: Shape,
        position: [Real; 2],
        angle: Real,
        linear_velocity: [Real; 2],
        angular_velocity: Real,
        mass: MassSpec,
        friction: Real,
        restitution: Real,
    }

    pub fn serialize<S: Serializer>(d: &BodyDef, s: S) -> Result<S::Ok, S::Error> {
        Compact {
            shape: d.shape,
            position: [d.position.x, d.position.y],
            angle: d.angle,
            linear_velocity: [d.linear_velocity.x, d.linear_velocity.y],
            angular_velocity: d.angular_velocity,
            mass: d.mass,
            friction: d.friction,
            restitution: d.restitution,
        }
        .serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<BodyDef, D::Error> {
        let c = Compact::deserialize(d)?;
        Ok(BodyDef {
            shape: c.shape,
            position: Vec2::new(c.position[0], c.position[1]),
            angle: c.angle,
            linear_velocity: Vec2::new(c.linear_velocity[0], c.linear_velocity[1]),
            angular_velocity: c.angular_velocity,
            mass: c.mass,
            friction: c.friction,
            restitution: c.restitution,
        })
    }
}

/// A validated command for the tick thread (serializable: the journal stores it).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Command {
    /// Set gravity (m/s^2).
    SetGravity(Vector),
    /// Set gravity from a device's tilt.
    Tilt(Tilt),
    /// Add bodies, all or nothing.
    Spawn(Vec<SpawnDef>),
    /// Remove bodies, all or nothing.
    Remove(Vec<BodyId>),
    /// Reload the scene.
    Reset,
}

/// What a callback hands the tick thread: a command, or the reason it was refused.
#[derive(Clone, Debug, PartialEq)]
pub struct Incoming {
    /// The key it arrived on.
    pub key: CommandKey,
    /// The command, or why it was refused.
    pub command: Result<Command, String>,
}

fn finite(field: &str, v: f32) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{field} must be a finite number, got {v}"))
    }
}

fn magnitude(field: &str, v: f32, max: f32) -> Result<(), String> {
    if v <= max {
        Ok(())
    } else {
        Err(format!(
            "{field} = {v} is out of range: must be <= {max} m/s^2"
        ))
    }
}

/// Decode and validate a payload that arrived on `key`.
pub fn parse(key: CommandKey, payload: &[u8], limits: &Limits) -> Result<Command, String> {
    if payload.len() > limits.max_payload_bytes as usize {
        return Err(format!(
            "payload of {} bytes is larger than limits.max_payload_bytes = {}",
            payload.len(),
            limits.max_payload_bytes
        ));
    }
    let bad = |e: crate::protocol::DecodeError| e.to_string();
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
                .map(|(i, b)| spawn_def(b, limits).map_err(|e| format!("bodies[{i}]: {e}")))
                .collect::<Result<Vec<_>, String>>()?;
            Ok(Command::Spawn(defs))
        }
        CommandKey::Remove => {
            let r: Remove = decode(payload).map_err(bad)?;
            if r.ids.is_empty() {
                return Err("ids is empty: nothing to remove".into());
            }
            Ok(Command::Remove(
                r.ids.into_iter().map(BodyId::from).collect(),
            ))
        }
        CommandKey::Reset => {
            let Reset = decode(payload).map_err(bad)?;
            Ok(Command::Reset)
        }
    }
}

/// Largest spawn angle (rad): larger finite angles are legal but only lose precision.
const MAX_ANGLE: f32 = 1.0e4;

/// The engine shape for a wire shape, and where its centre of mass sits relative to the
/// body origin the sender gave (non-zero only for a polygon whose vertices are not centred).
/// Refuses what the engine refuses, naming the field.
pub fn shape_from_spec(spec: &ShapeSpec) -> Result<(Shape, Vec2), PhysicsError> {
    let shape = match *spec {
        ShapeSpec::Rect { width, height } => Shape::rect(width as Real, height as Real),
        ShapeSpec::Circle { radius } => Shape::circle(radius as Real),
        ShapeSpec::Capsule { length, radius } => Shape::capsule(length as Real, radius as Real),
        ShapeSpec::Polygon { ref vertices } => {
            let points: Vec<Vec2> = vertices
                .iter()
                .map(|v| Vec2::new(v.x as Real, v.y as Real))
                .collect();
            let (p, centroid) = Polygon::new(&points)?;
            return Ok((Shape::Polygon(p), centroid));
        }
    };
    shape.validate()?;
    Ok((shape, Vec2::ZERO))
}

/// The sizes of a wire shape that the daemon's limits bound: (field, metres) pairs checked
/// against `limits.max_coordinate` and `limits.min_size`.
fn shape_sizes(spec: &ShapeSpec) -> Vec<(String, f32)> {
    match spec {
        ShapeSpec::Rect { width, height } => vec![
            ("shape.width".into(), *width),
            ("shape.height".into(), *height),
        ],
        ShapeSpec::Circle { radius } => vec![("shape.radius".into(), 2.0 * radius)],
        ShapeSpec::Capsule { length, radius } => vec![
            ("shape.length".into(), *length),
            ("shape.radius".into(), 2.0 * radius),
        ],
        ShapeSpec::Polygon { vertices } => {
            let (mut lo, mut hi) = (
                Vector::new(f32::MAX, f32::MAX),
                Vector::new(f32::MIN, f32::MIN),
            );
            for v in vertices {
                lo = Vector::new(lo.x.min(v.x), lo.y.min(v.y));
                hi = Vector::new(hi.x.max(v.x), hi.y.max(v.y));
            }
            vec![
                ("shape.vertices (width)".into(), hi.x - lo.x),
                ("shape.vertices (height)".into(), hi.y - lo.y),
            ]
        }
    }
}

fn spawn_def(b: SpawnBody, limits: &Limits) -> Result<SpawnDef, String> {
    let (shape, centroid) = shape_from_spec(&b.shape).map_err(|e| e.to_string())?;
    let origin = Vec2::new(b.position.x as Real, b.position.y as Real);
    let def = BodyDef {
        shape,
        // A polygon's centre of mass: its centroid, turned with the body.
        position: origin + crate::physics::Rot::from_angle(b.angle as Real).rotate(centroid),
        angle: b.angle as Real,
        linear_velocity: Vec2::new(b.velocity.x as Real, b.velocity.y as Real),
        angular_velocity: b.angular_velocity as Real,
        mass: MassSpec::Density(b.density as Real),
        friction: b.friction as Real,
        restitution: b.restitution as Real,
    };
    def.validate().map_err(|e| e.to_string())?;
    let max = limits.max_coordinate;
    for (field, v) in [("position.x", b.position.x), ("position.y", b.position.y)]
        .into_iter()
        .map(|(f, v)| (f.to_string(), v))
        .chain(shape_sizes(&b.shape))
    {
        if v.abs() > max {
            return Err(format!(
                "{field} = {v} is out of range: must be within +-{max} (limits.max_coordinate)"
            ));
        }
    }
    for (field, v) in shape_sizes(&b.shape) {
        if v < limits.min_size {
            return Err(format!(
                "{field} = {v} is too small: must be >= {} (limits.min_size)",
                limits.min_size
            ));
        }
    }
    if !(limits.min_density..=limits.max_density).contains(&b.density) {
        return Err(format!(
            "density = {} is out of range: must be within {}..={} (limits.min_density, limits.max_density)",
            b.density, limits.min_density, limits.max_density
        ));
    }
    let speed = b.velocity.x.hypot(b.velocity.y);
    if speed > limits.max_speed {
        return Err(format!(
            "|velocity| = {speed} is out of range: must be <= {} m/s (limits.max_speed)",
            limits.max_speed
        ));
    }
    if b.angular_velocity.abs() > limits.max_angular_speed {
        return Err(format!(
            "angular_velocity = {} is out of range: must be within +-{} rad/s (limits.max_angular_speed)",
            b.angular_velocity, limits.max_angular_speed
        ));
    }
    if b.friction > limits.max_friction {
        return Err(format!(
            "friction = {} is out of range: must be <= {} (limits.max_friction)",
            b.friction, limits.max_friction
        ));
    }
    if b.angle.abs() > MAX_ANGLE {
        return Err(format!(
            "angle = {} is out of range: must be within +-{MAX_ANGLE} rad",
            b.angle
        ));
    }
    let name = b.name.unwrap_or_default();
    if name.len() > limits.max_name_bytes as usize {
        return Err(format!(
            "name is {} bytes long, more than limits.max_name_bytes = {}",
            name.len(),
            limits.max_name_bytes
        ));
    }
    Ok(SpawnDef {
        def,
        name,
        colour: b.colour,
    })
}

/// The callbacks' side of the command channel. Cloned into each subscriber's callback.
#[derive(Clone)]
pub struct Intake {
    tx: SyncSender<Incoming>,
    limits: Arc<Limits>,
    dropped: Arc<[AtomicU64; 5]>,
}

impl Intake {
    /// An intake sending into `tx`; `dropped` counts, per command key, what a full channel refused.
    pub fn new(tx: SyncSender<Incoming>, limits: Limits, dropped: Arc<[AtomicU64; 5]>) -> Intake {
        Intake {
            tx,
            limits: Arc::new(limits),
            dropped,
        }
    }

    /// Decode, validate and queue. Never blocks: a full channel is counted and reported by the
    /// tick thread as a rejection.
    pub fn handle(&self, key: CommandKey, payload: &[u8]) {
        let command = parse(key, payload, &self.limits);
        match self.tx.try_send(Incoming { key, command }) {
            Ok(()) => {}
            Err(TrySendError::Full(_)) => {
                self.dropped[key.index()].fetch_add(1, Ordering::Relaxed);
            }
            Err(TrySendError::Disconnected(_)) => {} // shutting down
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{encode, Orientation};

    fn body() -> SpawnBody {
        SpawnBody {
            name: None,
            shape: ShapeSpec::Rect {
                width: 1.0,
                height: 0.5,
            },
            position: Vector::new(0.0, 3.0),
            angle: 0.0,
            velocity: Vector::default(),
            angular_velocity: 0.0,
            density: 1.0,
            friction: 0.5,
            restitution: 0.0,
            colour: Colour::default(),
        }
    }

    #[test]
    fn valid_commands_parse() {
        let l = Limits::default();
        let p = encode(&SetGravity { x: 3.0, y: 0.0 }).unwrap();
        assert_eq!(
            parse(CommandKey::Gravity, &p, &l),
            Ok(Command::SetGravity(Vector::new(3.0, 0.0)))
        );
        let p = encode(&Tilt::Orientation(Orientation::FaceUp)).unwrap();
        assert!(parse(CommandKey::Tilt, &p, &l).is_ok());
        let p = encode(&Spawn {
            bodies: vec![body(), body()],
        })
        .unwrap();
        assert!(matches!(parse(CommandKey::Spawn, &p, &l), Ok(Command::Spawn(v)) if v.len() == 2));
        assert_eq!(parse(CommandKey::Reset, &[1], &l), Ok(Command::Reset));
    }

    #[test]
    fn bad_fields_are_named_with_their_value() {
        let l = Limits::default();
        let p = encode(&SetGravity {
            x: f32::NAN,
            y: 0.0,
        })
        .unwrap();
        let e = parse(CommandKey::Gravity, &p, &l).unwrap_err();
        assert!(e.contains("gravity.x") && e.contains("NaN"), "{e}");
        let p = encode(&SetGravity { x: 1e6, y: 0.0 }).unwrap();
        assert!(parse(CommandKey::Gravity, &p, &l)
            .unwrap_err()
            .contains("|gravity| = 1000000"));
        let p = encode(&Tilt::Accelerometer {
            x: 0.0,
            y: f32::INFINITY,
            z: 0.0,
        })
        .unwrap();
        assert!(parse(CommandKey::Tilt, &p, &l)
            .unwrap_err()
            .contains("tilt.y"));
        let mut b = body();
        b.density = -2.0;
        let p = encode(&Spawn {
            bodies: vec![body(), b],
        })
        .unwrap();
        let e = parse(CommandKey::Spawn, &p, &l).unwrap_err();
        assert!(e.starts_with("bodies[1]: density = -2"), "{e}");
        let mut b = body();
        b.position.x = 5e4;
        let p = encode(&Spawn { bodies: vec![b] }).unwrap();
        let e = parse(CommandKey::Spawn, &p, &l).unwrap_err();
        assert!(e.contains("position.x = 50000"), "{e}");
        let p = encode(&Spawn {
            bodies: vec![body(); 65],
        })
        .unwrap();
        let e = parse(CommandKey::Spawn, &p, &l).unwrap_err();
        assert!(e.contains("max_bodies_per_spawn = 64"), "{e}");
        let e = parse(CommandKey::Spawn, &vec![1; 70000], &l).unwrap_err();
        assert!(e.contains("max_payload_bytes"), "{e}");
        let e = parse(CommandKey::Tilt, &[1, 7], &l).unwrap_err();
        assert!(e.contains("unknown variant"), "{e}");
    }
}
