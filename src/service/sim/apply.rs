//! Applying commands at a tick boundary: gravity, tilt, spawn, remove, reset and a kinematic
//! body's velocity, each all or nothing, each answered by the event to publish (or a
//! rejection naming why).

use super::Simulation;
use crate::physics::PhysicsError;
use crate::protocol::{BodyRef, CommandKey, Event, EventKind, Vector};
use crate::service::command::{Command, Incoming, SpawnDef};
use crate::service::wire::{body_info, vec2, vector};
use std::collections::HashSet;

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
        let after = self.world.body_count() + defs.len();
        if after > self.limits.max_bodies as usize {
            return Err(format!(
                "{} bodies would make {after}, more than limits.max_bodies = {}",
                defs.len(),
                self.limits.max_bodies
            ));
        }
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
        self.spawn_frames.push_back(frame);
        let mut bodies = Vec::with_capacity(ids.len());
        for (d, id) in defs.into_iter().zip(ids) {
            self.describe(id, d.name, d.colour);
            let body = self.world.body(id).expect("just added");
            bodies.push(body_info(body, &self.bodies.meta_of(body)));
        }
        Ok(EventKind::Added { bodies })
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
        Ok(EventKind::Reset {
            scene: self.scene_name.clone(),
            gravity: vector(self.world.gravity()),
            bodies: self.body_infos(),
        })
    }
}
