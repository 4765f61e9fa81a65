//! Hands: bodies held over `…/drag`. Each hand (named by an id its client picks, one per
//! finger or pointer) holds one dynamic body by a target joint from the world, whose target
//! the hand moves; letting go removes the joint, so a body released while moving flies on at
//! the speed it had. The spring is Box2D's sample's (5 Hz, damping ratio 0.7) with at most 100
//! times the body's weight at standard gravity (not the World's gravity: a phone lying flat has
//! none in the plane, and a held body must still follow).
//!
//! A hand that sends nothing for [`HAND_TIMEOUT_SECONDS`] is let go (its client may be gone);
//! a hand whose body was removed is forgotten. Hands live in the tick thread only: the
//! commands that make and move them are journaled like any other, and the timeouts follow
//! from the frames, so a replay holds and lets go at the same frames. A checkpoint holds no
//! hands: it is taken as if every hand had let go.

use super::Simulation;
use crate::physics::{BodyId, JointDef, JointId, JointKind, Real, Target, World};
use crate::protocol::{BodyRef, Drag, Vector};
use crate::service::wire::vec2;
use std::collections::BTreeMap;

/// The hand's spring (Hz) and damping ratio: Box2D's sample's.
pub const HAND_HERTZ: Real = 5.0;
/// See [`HAND_HERTZ`].
pub const HAND_DAMPING_RATIO: Real = 0.7;
/// The most a hand pulls, per kilogram of the body held (N/kg): 100 times standard gravity.
pub const HAND_FORCE_PER_KG: Real = 100.0 * 9.80665;
/// A hand that sends nothing (no move) for this long is let go (s).
pub const HAND_TIMEOUT_SECONDS: f64 = 3.0;
/// The most hands holding bodies at once.
pub const MAX_HANDS: usize = 16;

/// One hand: the joint that holds its body, and the frame after which it last sent (its
/// command applied at the boundary before the next one).
#[derive(Clone, Debug)]
pub(super) struct Hand {
    joint: JointId,
    last_frame: u64,
}

/// Every hand, by its client's id (ordered, so what is done to them is done in one order).
#[derive(Clone, Debug, Default)]
pub(super) struct Hands(BTreeMap<u64, Hand>);

impl Hands {
    /// Forget every hand (the World they held in is gone).
    pub fn clear(&mut self) {
        self.0.clear();
    }

    /// The joints the hands hold by.
    pub fn joints(&self) -> impl Iterator<Item = JointId> + '_ {
        self.0.values().map(|h| h.joint)
    }
}

impl Simulation {
    /// Apply a `Drag` command.
    pub(super) fn drag(&mut self, d: Drag) -> Result<(), String> {
        match d {
            Drag::Grab { hand, id, point } => self.grab(hand, id, point),
            Drag::Move { hand, target } => {
                let frame = self.frame;
                let h = self.held(hand)?;
                h.last_frame = frame;
                let joint = h.joint;
                self.world
                    .set_joint_target(joint, vec2(target))
                    .map_err(|e| e.to_string())
            }
            Drag::Release { hand } => {
                let joint = self.held(hand)?.joint;
                self.hands.0.remove(&hand);
                let _ = self.world.remove_joint(joint);
                Ok(())
            }
        }
    }

    /// Let hand `hand` go if it holds a body (its client went away); nothing otherwise.
    pub(super) fn hand_gone(&mut self, hand: u64) {
        if let Some(h) = self.hands.0.remove(&hand) {
            let _ = self.world.remove_joint(h.joint);
        }
    }

    /// The hand `hand`, if it holds a body.
    fn held(&mut self, hand: u64) -> Result<&mut Hand, String> {
        let live = self.hands.0.get(&hand).map(|h| h.joint);
        if live.is_some_and(|j| self.world.joint(j).is_none()) {
            self.hands.0.remove(&hand);
        }
        self.hands
            .0
            .get_mut(&hand)
            .ok_or_else(|| format!("hand: hand {hand} holds no body"))
    }

    fn grab(&mut self, hand: u64, r: BodyRef, point: Vector) -> Result<(), String> {
        let found = self.world.live_id(r.index, r.generation);
        let Some(body) = found.and_then(|id| self.world.body(id)) else {
            return Err(format!("id: no body with id {r}"));
        };
        if body.is_static() || body.is_kinematic() {
            let kind = if body.is_static() {
                "static"
            } else {
                "kinematic"
            };
            return Err(format!(
                "id: body {r} is {kind}: only dynamic bodies can be grabbed"
            ));
        }
        if !self.hands.0.contains_key(&hand) && self.hands.0.len() >= MAX_HANDS {
            return Err(format!(
                "hand: {MAX_HANDS} hands hold bodies already (at most {MAX_HANDS} at once)"
            ));
        }
        let (id, mass, local) = (
            body.id(),
            body.mass(),
            body.transform().apply_inv(vec2(point)),
        );
        let def = hand_joint(id, mass, local, vec2(point));
        let joint = self.world.add_joint(&def).map_err(|e| e.to_string())?;
        let last_frame = self.frame;
        if let Some(old) = self.hands.0.insert(hand, Hand { joint, last_frame }) {
            let _ = self.world.remove_joint(old.joint);
        }
        Ok(())
    }

    /// Before a step: let go of the hands that have sent nothing for the timeout, and forget
    /// those whose body is gone.
    pub(super) fn expire_hands(&mut self) {
        if self.hands.0.is_empty() {
            return;
        }
        let frame = self.next_frame();
        let timeout = (HAND_TIMEOUT_SECONDS / self.dt_secs).round() as u64;
        let world = &mut self.world;
        self.hands.0.retain(|_, h| {
            let idle = frame >= h.last_frame + timeout;
            if idle {
                let _ = world.remove_joint(h.joint);
            }
            !idle && world.joint(h.joint).is_some()
        });
    }

    /// The World as a checkpoint takes it: without the hands' joints.
    pub(super) fn world_without_hands(&self) -> World {
        let mut world = self.world.clone();
        for joint in self.hands.joints() {
            let _ = world.remove_joint(joint);
        }
        world
    }
}

/// The joint by which a hand holds body `id` (of `mass` kg) at `local` (its frame), pulled
/// toward `target` (m, world).
fn hand_joint(
    id: BodyId,
    mass: Real,
    local: crate::physics::Vec2,
    target: crate::physics::Vec2,
) -> JointDef {
    let kind = JointKind::Target(Target {
        hertz: HAND_HERTZ,
        damping_ratio: HAND_DAMPING_RATIO,
        max_force: HAND_FORCE_PER_KG * mass,
    });
    JointDef::new(kind, None, id).with_anchors(target, local)
}
