//! The commands the tick thread applies, as validated from the wire ([`super::wire`]), and the
//! channel that carries them there from the Zenoh callbacks ([`Intake`]). A command is
//! serializable: the journal stores each one with the frame it was applied before.

use super::config::Limits;
use super::wire::parse_command;
use crate::physics::BodyDef;
use crate::protocol::{BodyRef, Build, Colour, CommandKey, Drag, JointRef, Tilt, Vector};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{SyncSender, TrySendError};
use std::sync::Arc;

/// A validated command for the tick thread.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Command {
    /// Set gravity (m/s^2).
    SetGravity(Vector),
    /// Set gravity from a device's tilt.
    Tilt(Tilt),
    /// Add bodies, all or nothing.
    Spawn(Vec<SpawnDef>),
    /// Remove bodies, all or nothing: ids as sent, resolved to live bodies when applied.
    Remove(Vec<BodyRef>),
    /// Reload the scene.
    Reset,
    /// Set a kinematic body's velocity (m/s, rad/s): the id as sent, resolved when applied.
    /// Appended, so earlier journals read as before.
    SetVelocity {
        /// The body, as sent.
        id: BodyRef,
        /// Linear velocity (m/s).
        velocity: Vector,
        /// Angular velocity (rad/s).
        angular_velocity: f32,
    },
    /// Grab, move or release a body (finite numbers within the limits' coordinates). Appended.
    Drag(Drag),
    /// Add bodies and joints, all or nothing: the message as sent (checked by
    /// `wire::build::check_build`), turned into the engine's definitions when applied, so the
    /// journal keeps what arrived. Appended.
    Build(Build),
    /// Remove joints, all or nothing: ids as sent, resolved when applied. Appended.
    RemoveJoints(Vec<JointRef>),
    /// The client of hand `0` went away (its `…/hand/<hand>` liveliness token went): let the
    /// hand go if it holds a body, silently. Arrives on `…/drag`'s channel. Appended.
    HandGone(u64),
}

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
            shape: d.shape.clone(),
            position: d.position.to_array(),
            angle: d.angle,
            linear_velocity: d.linear_velocity.to_array(),
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
            position: Vec2::from_array(c.position),
            angle: c.angle,
            linear_velocity: Vec2::from_array(c.linear_velocity),
            angular_velocity: c.angular_velocity,
            mass: c.mass,
            friction: c.friction,
            restitution: c.restitution,
            filter: Default::default(),
            parts: Vec::new(),
            flags: Default::default(),
            awake: true,
        })
    }
}

/// What a callback hands the tick thread: a command, or the reason it was refused.
#[derive(Clone, Debug, PartialEq)]
pub struct Incoming {
    /// The key it arrived on.
    pub key: CommandKey,
    /// The command, or why it was refused.
    pub command: Result<Command, String>,
}

/// How many commands a full channel refused, per command key ([`CommandKey::index`]): the
/// tick thread reports them as rejections.
pub type DroppedCounts = Arc<[AtomicU64; CommandKey::ALL.len()]>;

/// The callbacks' side of the command channel. Cloned into each subscriber's callback.
#[derive(Clone)]
pub struct Intake {
    tx: SyncSender<Incoming>,
    limits: Arc<Limits>,
    dropped: DroppedCounts,
    received: Arc<AtomicU64>,
}

impl Intake {
    /// An intake sending into `tx`; `dropped` counts, per command key, what a full channel
    /// refused.
    pub fn new(tx: SyncSender<Incoming>, limits: Limits, dropped: DroppedCounts) -> Intake {
        Intake {
            tx,
            limits: Arc::new(limits),
            dropped,
            received: Arc::default(),
        }
    }

    /// How many samples [`Intake::handle`] has been given (every one is then queued or
    /// counted as dropped): the `commands_received` of `…/stats`.
    pub fn received(&self) -> Arc<AtomicU64> {
        self.received.clone()
    }

    /// Queue the release of hand `hand`, whose client went away (never blocks; on a full
    /// channel it is counted as a dropped `…/drag` command, and the hand's time-out lets it go).
    pub fn hand_gone(&self, hand: u64) {
        let key = CommandKey::Drag;
        let command = Ok(Command::HandGone(hand));
        if let Err(TrySendError::Full(_)) = self.tx.try_send(Incoming { key, command }) {
            self.dropped[key.index()].fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Decode, validate and queue. Never blocks: a full channel is counted and reported by the
    /// tick thread as a rejection.
    pub fn handle(&self, key: CommandKey, payload: &[u8]) {
        self.received.fetch_add(1, Ordering::Relaxed);
        let command = parse_command(key, payload, &self.limits);
        match self.tx.try_send(Incoming { key, command }) {
            Ok(()) => {}
            Err(TrySendError::Full(_)) => {
                self.dropped[key.index()].fetch_add(1, Ordering::Relaxed);
            }
            Err(TrySendError::Disconnected(_)) => {} // shutting down
        }
    }
}
