//! A timeline: commands scheduled at given simulated times (`tiltbox simulate --timeline
//! FILE`, docs/scenes.md). Each entry is turned into the wire message a client would put,
//! encoded, and validated by the daemon's own [`parse_command`], so a scripted run takes
//! exactly the commands the daemon would take; [`Simulation::apply`](super::Simulation::apply)
//! then applies them, as the tick loop does.
//!
//! Rounding: an entry at time `t` is applied at the first frame boundary whose time reaches
//! it, frame `k = ceil(t / dt)` (a ratio within 1e-9 of a whole number counts as that number),
//! that is before frame `k + 1` is stepped: the state printed for frame `k` is the one before
//! the command, the state of frame `k + 1` the first after it.

use super::command::Incoming;
use super::config::Limits;
use super::wire::parse_command;
use crate::protocol::{
    encode, BodyRef, CommandKey, Remove, SetGravity, SetVelocity, ShapeSpec, Spawn, SpawnBody,
    Tilt, Vector,
};
use crate::scene::Colour;
use serde::Deserialize;
use std::path::Path;

/// Why a timeline cannot be used: the file, the entry, the field, the value and the limit.
#[derive(Debug, thiserror::Error)]
#[error("timeline {path}: {reason}")]
pub struct TimelineError {
    /// The file.
    pub path: String,
    /// What is wrong, naming the entry (`at[2]`) and the field.
    pub reason: String,
}

/// The commands of a timeline, each with the frame it is applied before, in time order
/// (entries at the same frame in file order).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Timeline {
    /// (frame the command is applied before, `at[i]` index in the file, the command).
    pub entries: Vec<(u64, usize, Incoming)>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    at: Vec<Entry>,
}

/// One `[[at]]` table: a time and exactly one command.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    /// Simulated time (s).
    time: f64,
    /// Gravity (m/s^2), `[x, y]`.
    gravity: Option<[f32; 2]>,
    /// A tilt, as the wire's `Tilt`.
    tilt: Option<Tilt>,
    /// Bodies to add.
    spawn: Option<Vec<Body>>,
    /// Ids to remove, as `simulate` prints them (`"12v0"`).
    remove: Option<Vec<String>>,
    /// A kinematic body's new velocity, as the wire's `SetVelocity`.
    velocity: Option<Velocity>,
}

/// `velocity = { id, velocity, angular_velocity }`: the fields of the wire's `SetVelocity`,
/// the id written as `simulate` prints it. Both velocities are required: the command sets
/// both, so leaving one out would silently zero it.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Velocity {
    id: String,
    velocity: [f32; 2],
    angular_velocity: f32,
}

/// A body to spawn; omitted fields take [`SpawnBody::at`]'s values.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Body {
    name: Option<String>,
    shape: ShapeSpec,
    position: [f32; 2],
    #[serde(default)]
    angle: f32,
    #[serde(default)]
    velocity: [f32; 2],
    #[serde(default)]
    angular_velocity: f32,
    density: Option<f32>,
    friction: Option<f32>,
    restitution: Option<f32>,
    colour: Option<String>,
}

fn body_ref(s: &str) -> Option<BodyRef> {
    let (index, generation) = s.split_once('v')?;
    Some(BodyRef {
        index: index.parse().ok()?,
        generation: generation.parse().ok()?,
    })
}

impl Timeline {
    /// Read and check `path` for a run of `steps` steps of `dt` seconds under `limits`.
    pub fn load(
        path: &Path,
        dt: f64,
        steps: u64,
        limits: &Limits,
    ) -> Result<Timeline, TimelineError> {
        let err = |reason: String| TimelineError {
            path: path.display().to_string(),
            reason,
        };
        let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
        Timeline::parse(&text, dt, steps, limits).map_err(err)
    }

    /// [`Timeline::load`] from text; the error is the reason alone.
    pub fn parse(text: &str, dt: f64, steps: u64, limits: &Limits) -> Result<Timeline, String> {
        let file: File = toml::from_str(text).map_err(|e| e.to_string())?;
        let end = steps as f64 * dt;
        let mut entries = Vec::with_capacity(file.at.len());
        for (i, e) in file.at.into_iter().enumerate() {
            let here = format!("at[{i}]");
            if !(e.time.is_finite() && e.time >= 0.0) {
                return Err(format!(
                    "{here}.time = {}: must be a finite number of seconds >= 0",
                    e.time
                ));
            }
            let ratio = e.time / dt;
            let boundary = if (ratio - ratio.round()).abs() <= 1e-9 * ratio.max(1.0) {
                ratio.round()
            } else {
                ratio.ceil()
            };
            if boundary >= steps as f64 {
                return Err(format!(
                    "{here}.time = {} s: must be before the run's end, {end} s (--seconds), \
                     so that a step follows it",
                    e.time
                ));
            }
            let (key, field, payload) = match (e.gravity, e.tilt, e.spawn, e.remove, e.velocity) {
                (Some([x, y]), None, None, None, None) => {
                    (CommandKey::Gravity, "gravity", encode(&SetGravity { x, y }))
                }
                (None, Some(t), None, None, None) => (CommandKey::Tilt, "tilt", encode(&t)),
                (None, None, Some(bodies), None, None) => {
                    let wire = spawn_bodies(&here, bodies)?;
                    (CommandKey::Spawn, "spawn", encode(&Spawn { bodies: wire }))
                }
                (None, None, None, Some(ids), None) => {
                    let mut refs = Vec::with_capacity(ids.len());
                    for (j, s) in ids.iter().enumerate() {
                        refs.push(body_ref(s).ok_or_else(|| {
                            format!(
                                "{here}.remove[{j}] = {s:?}: not a body id (write it as \
                                 simulate prints it, e.g. \"12v0\")"
                            )
                        })?);
                    }
                    (CommandKey::Remove, "remove", encode(&Remove { ids: refs }))
                }
                (None, None, None, None, Some(v)) => {
                    // Whether the body is there and kinematic, and the World's speed cap, are
                    // the simulation's to check when applied (the dry run, before printing).
                    let id = body_ref(&v.id).ok_or_else(|| {
                        format!(
                            "{here}.velocity.id = {:?}: not a body id (write it as simulate \
                             prints it, e.g. \"1v0\")",
                            v.id
                        )
                    })?;
                    let message = SetVelocity {
                        id,
                        velocity: Vector::new(v.velocity[0], v.velocity[1]),
                        angular_velocity: v.angular_velocity,
                    };
                    (CommandKey::Velocity, "velocity", encode(&message))
                }
                _ => {
                    return Err(format!(
                        "{here}: give exactly one of gravity, tilt, spawn, remove, velocity"
                    ))
                }
            };
            let payload = payload.map_err(|e| format!("{here}.{field}: {e}"))?;
            // The daemon's own validation, on the bytes a client would have put.
            let command = parse_command(key, &payload, limits)
                .map_err(|reason| format!("{here}.{field} (time = {} s): {reason}", e.time))?;
            entries.push((
                boundary as u64 + 1,
                i,
                Incoming {
                    key,
                    command: Ok(command),
                },
            ));
        }
        entries.sort_by_key(|&(frame, i, _)| (frame, i));
        Ok(Timeline { entries })
    }
}

/// The wire's bodies for an entry's `spawn` list; omitted fields take [`SpawnBody::at`]'s
/// values. `here` names the entry (`at[2]`).
fn spawn_bodies(here: &str, bodies: Vec<Body>) -> Result<Vec<SpawnBody>, String> {
    let mut wire = Vec::with_capacity(bodies.len());
    for (j, b) in bodies.into_iter().enumerate() {
        let colour = match &b.colour {
            None => Colour::default(),
            Some(c) => c
                .parse()
                .map_err(|e| format!("{here}.spawn[{j}].colour = {c:?}: {e}"))?,
        };
        let at = SpawnBody::at(b.shape, Vector::new(b.position[0], b.position[1]));
        wire.push(SpawnBody {
            name: b.name,
            angle: b.angle,
            velocity: Vector::new(b.velocity[0], b.velocity[1]),
            angular_velocity: b.angular_velocity,
            density: b.density.unwrap_or(at.density),
            friction: b.friction.unwrap_or(at.friction),
            restitution: b.restitution.unwrap_or(at.restitution),
            colour,
            ..at
        });
    }
    Ok(wire)
}
