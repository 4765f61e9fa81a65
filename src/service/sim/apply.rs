//! Applying commands at a tick boundary: gravity, tilt, spawn, remove, reset and a kinematic
//! body's velocity, each all or nothing, each answered by the event to publish (or a
//! rejection naming why).

use super::Simulation;
use crate::physics::PhysicsError;
use crate::physics::{BodyId, JointId};
use crate::protocol::{
    BodyInfo, BodyRef, Build, CommandKey, Event, EventKind, JointEnd, JointRef, Vector,
};
use crate::service::command::{Command, Incoming, SpawnDef};
use crate::service::wire::{body_info, build, vec2, vector};
use std::collections::HashSet;

/// A joint end of a build once its live body is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum End {
    /// The world's fixed frame.
    World,
    /// A live body.
    Live(BodyId),
    /// The build's body at this index.
    New(u32),
}

impl Simulation {
    fn reject(&mut self, key: CommandKey, reason: String) -> Event {
        self.rejected += 1;
        self.rejected_event(key, reason)
    }

    fn rejected_event(&self, key: CommandKey, reason: String) -> Event {
        tracing::warn!(key = %self.keys.command(key), frame = self.next_frame(), "rejected: {reason}");
        Event {
            frame: self.next_frame(),
            kind: EventKind::Rejected {
                key: self.keys.command(key),
                reason,
            },
        }
    }

    /// The `Rejected` event for `count` commands on `key` dropped because the command channel
    /// was full. They are not counted in [`Simulation::rejected`]: the tick loop counts them
    /// as dropped (`commands_dropped` in `…/stats`).
    pub fn reject_dropped(&mut self, key: CommandKey, count: u64, capacity: u32) -> Event {
        self.rejected_event(
            key,
            format!("command queue full (capacity {capacity}): {count} command(s) dropped"),
        )
    }

    /// Apply one command at the tick boundary before frame [`Simulation::next_frame`]; returns
    /// the event to publish, if any. Never half-applies: on error nothing changes.
    pub fn apply(&mut self, incoming: Incoming) -> Option<Event> {
        let key = incoming.key;
        let command = match incoming.command {
            Ok(c) => c,
            Err(reason) => return Some(self.reject(key, reason)),
        };
        let frame = self.next_frame();
        tracing::debug!(frame, key = %key, ?command, "applying");
        let result = match command {
            Command::SetGravity(g) => self.set_gravity(g).map(|()| None),
            Command::Tilt(t) => self
                .set_gravity(t.gravity(self.scene_gravity))
                .map(|()| None),
            Command::Spawn(defs) => self.spawn(defs).map(Some),
            Command::Remove(ids) => self.remove(ids).map(Some),
            Command::Reset => self.reset().map(Some),
            Command::SetVelocity {
                id,
                velocity,
                angular_velocity,
            } => self
                .set_velocity(id, velocity, angular_velocity)
                .map(|()| None),
            Command::Drag(d) => self.drag(d).map(|()| None),
            Command::Build(b) => self.build(b).map(Some),
            Command::RemoveJoints(ids) => self.remove_joints(ids).map(Some),
            Command::HandGone(hand) => {
                self.hand_gone(hand);
                Ok(None)
            }
        };
        match result {
            Ok(kind) => {
                self.applied += 1;
                kind.map(|kind| Event { frame, kind })
            }
            Err(reason) => Some(self.reject(key, reason)),
        }
    }

    fn set_gravity(&mut self, g: Vector) -> Result<(), String> {
        self.world.set_gravity(vec2(g)).map_err(|e| e.to_string())
    }

    fn spawn(&mut self, defs: Vec<SpawnDef>) -> Result<EventKind, String> {
        self.check_spawn_room(defs.len())?;
        let ids = self.add_bodies(&defs)?;
        self.spawn_frames.push_back(self.next_frame());
        let bodies = self.describe_added(defs, &ids);
        Ok(EventKind::Added { bodies })
    }

    /// Refuse a spawn or build over the rate limit, or one that would make more than
    /// `limits.max_bodies` bodies.
    fn check_spawn_room(&mut self, new_bodies: usize) -> Result<(), String> {
        let frame = self.next_frame();
        while self
            .spawn_frames
            .front()
            .is_some_and(|&f| f + self.spawn_window <= frame)
        {
            self.spawn_frames.pop_front();
        }
        let max = self.limits.max_spawns_per_second;
        if self.spawn_frames.len() >= max as usize {
            return Err(format!(
                "rate limit: limits.max_spawns_per_second = {max} spawns already applied in the last second"
            ));
        }
        let after = self.world.body_count() + new_bodies;
        if after > self.limits.max_bodies as usize {
            return Err(format!(
                "{new_bodies} bodies would make {after}, more than limits.max_bodies = {}",
                self.limits.max_bodies
            ));
        }
        Ok(())
    }

    /// Add checked bodies, all or nothing.
    fn add_bodies(&mut self, defs: &[SpawnDef]) -> Result<Vec<BodyId>, String> {
        let mut ids = Vec::with_capacity(defs.len());
        for (i, d) in defs.iter().enumerate() {
            match self.world.add_body(&d.def) {
                Ok(id) => ids.push(id),
                Err(e) => {
                    // Validated already, so this is a World limit: undo what was added.
                    let _ = self.world.remove_bodies(&ids);
                    return Err(format!("bodies[{i}]: {e}"));
                }
            }
        }
        Ok(ids)
    }

    /// Name and colour the bodies just added, and describe them for the event.
    fn describe_added(&mut self, defs: Vec<SpawnDef>, ids: &[BodyId]) -> Vec<BodyInfo> {
        let mut bodies = Vec::with_capacity(ids.len());
        for (d, &id) in defs.into_iter().zip(ids) {
            self.describe(id, d.name, d.colour);
            let body = self.world.body(id).expect("just added");
            bodies.push(body_info(body, &self.bodies.meta_of(body)));
        }
        bodies
    }

    /// Add a build's bodies and joints, all or nothing. Everything that can be refused is
    /// checked before anything is added; what is left (a World limit) is undone.
    fn build(&mut self, b: Build) -> Result<EventKind, String> {
        let defs = b
            .bodies
            .iter()
            .enumerate()
            .map(|(i, body)| {
                build::body_def(body, &self.limits).map_err(|e| format!("bodies[{i}]: {e}"))
            })
            .collect::<Result<Vec<_>, String>>()?;
        if !defs.is_empty() {
            self.check_spawn_room(defs.len())?;
        }
        let joints = self.world.joint_count() + b.joints.len();
        if joints > self.limits.max_bodies as usize {
            return Err(format!(
                "{} joints would make {joints}, more than limits.max_bodies = {} (which bounds \
                 joints too)",
                b.joints.len(),
                self.limits.max_bodies
            ));
        }
        let ends = self.live_ends(&b)?;
        let ids = self.add_bodies(&defs)?;
        let mut joint_ids = Vec::with_capacity(b.joints.len());
        let pick = |e: End| match e {
            End::World => None,
            End::Live(id) => Some(id),
            End::New(n) => Some(ids[n as usize]),
        };
        for (i, (j, &(a, bb))) in b.joints.iter().zip(&ends).enumerate() {
            let bb = pick(bb).expect("checked when parsed: b is a body");
            let def = build::joint_def(j, pick(a), bb);
            match self.world.add_joint(&def) {
                Ok(id) => joint_ids.push(id),
                Err(e) => {
                    for &id in &joint_ids {
                        let _ = self.world.remove_joint(id);
                    }
                    let _ = self.world.remove_bodies(&ids);
                    return Err(format!("joints[{i}]: {e}"));
                }
            }
        }
        if !defs.is_empty() {
            self.spawn_frames.push_back(self.next_frame());
        }
        let bodies = self.describe_added(defs, &ids);
        let joints = joint_ids
            .iter()
            .filter_map(|&id| self.world.joint(id).and_then(build::joint_info))
            .collect();
        Ok(EventKind::Built { bodies, joints })
    }

    /// Each joint's ends, live ids found. Refuses a live id that names no body, and a joint
    /// whose ends are all static or kinematic.
    fn live_ends(&self, b: &Build) -> Result<Vec<(End, End)>, String> {
        let end = |i: usize, field: &str, e: JointEnd| match e {
            JointEnd::World => Ok(End::World),
            JointEnd::New(n) => Ok(End::New(n)),
            JointEnd::Live(r) => self
                .world
                .live_id(r.index, r.generation)
                .map(End::Live)
                .ok_or_else(|| format!("joints[{i}]: {field}: no body with id {r}")),
        };
        let moves = |e: End| match e {
            End::World => false,
            End::New(n) => b.bodies[n as usize].motion.is_dynamic(),
            End::Live(id) => self.world.body(id).is_some_and(|b| b.inv_mass() > 0.0),
        };
        let mut out = Vec::with_capacity(b.joints.len());
        for (i, j) in b.joints.iter().enumerate() {
            let (a, bb) = (end(i, "a", j.a)?, end(i, "b", j.b)?);
            if a == bb {
                return Err(format!("joints[{i}]: a and b are the same body"));
            }
            if !moves(a) && !moves(bb) {
                return Err(format!(
                    "joints[{i}]: neither a nor b is a dynamic body: a joint must move something"
                ));
            }
            out.push((a, bb));
        }
        Ok(out)
    }

    /// Remove joints by wire id, all or nothing (a drag hand's joint is not the client's to
    /// remove).
    fn remove_joints(&mut self, refs: Vec<JointRef>) -> Result<EventKind, String> {
        let mut ids = Vec::with_capacity(refs.len());
        let mut seen = HashSet::with_capacity(refs.len());
        let hands: HashSet<JointId> = self.hands.joints().collect();
        for (i, r) in refs.iter().enumerate() {
            let found = self
                .world
                .live_joint_id(r.index, r.generation)
                .filter(|id| !hands.contains(id));
            let Some(id) = found else {
                return Err(format!("ids[{i}]: no {r}"));
            };
            if !seen.insert(id) {
                return Err(format!("ids[{i}]: {r} is listed twice"));
            }
            ids.push(id);
        }
        for id in ids {
            self.world.remove_joint(id).expect("checked above");
        }
        Ok(EventKind::JointsRemoved { ids: refs })
    }

    /// Remove the bodies the wire ids name, all or nothing. A wire id names a body only if a
    /// live body has exactly that id (slot and generation).
    fn remove(&mut self, refs: Vec<BodyRef>) -> Result<EventKind, String> {
        // Linear in the list: each id is looked up by its slot, duplicates through a set.
        let mut ids = Vec::with_capacity(refs.len());
        let mut seen = HashSet::with_capacity(refs.len());
        for (i, r) in refs.iter().enumerate() {
            let Some(id) = self.world.live_id(r.index, r.generation) else {
                // The engine's own words for an id it does not know.
                return Err(format!("ids[{i}]: no body with id {r}"));
            };
            if !seen.insert(id) {
                return Err(format!("ids[{i}]: body {r} is listed twice"));
            }
            ids.push(id);
        }
        self.world
            .remove_bodies(&ids)
            .map_err(|e: PhysicsError| e.to_string())?;
        for &id in &ids {
            self.bodies.remove(id);
            self.poses.forget(id);
        }
        Ok(EventKind::Removed { ids: refs })
    }

    /// Set a kinematic body's velocity. Only kinematic bodies take one: a dynamic body is
    /// moved by forces and contacts, a static one not at all.
    fn set_velocity(&mut self, r: BodyRef, v: Vector, w: f32) -> Result<(), String> {
        let found = self.world.live_id(r.index, r.generation);
        let Some(body) = found.and_then(|id| self.world.body(id)) else {
            return Err(format!("id: no body with id {r}"));
        };
        if !body.is_kinematic() {
            return Err(format!(
                "id: body {r} is not kinematic (only kinematic bodies take a velocity; make it \
                 kinematic = true in the scene)"
            ));
        }
        // The World refuses these too, but names its default cap; this names the cap the
        // World runs with (a scene's `settings.max_linear_speed`) and the rim speed's radius.
        let max = self.world.settings().max_linear_speed;
        let speed = vec2(v).length();
        if speed > max {
            return Err(format!(
                "velocity (speed) = {speed} m/s is out of range: must not exceed the World's \
                 settings.max_linear_speed = {max} m/s"
            ));
        }
        let radius = body.shape().bounding_radius();
        let rim = (w as crate::physics::Real).abs() * radius;
        if rim > max {
            return Err(format!(
                "angular_velocity = {w} rad/s is out of range: its rim speed |w| r = {rim} m/s \
                 (r = {radius} m, the body's bounding radius) must not exceed the World's \
                 settings.max_linear_speed = {max} m/s"
            ));
        }
        let id = body.id();
        self.world
            .set_velocity(id, vec2(v), w as crate::physics::Real)
            .map_err(|e| e.to_string())
    }

    /// Reload the scene; the event carries every body of the new World.
    pub(super) fn reset(&mut self) -> Result<EventKind, String> {
        self.load_scene()
            .map_err(|e| format!("cannot reload the scene: {e}"))?;
        tracing::info!(frame = self.next_frame(), scene = %self.scene_name, "reset");
        self.announce_joints = self.world.joint_count() > 0;
        Ok(EventKind::Reset {
            scene: self.scene_name.clone(),
            gravity: vector(self.world.gravity()),
            bodies: self.body_infos(),
        })
    }
}
