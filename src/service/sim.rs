//! The simulation as the tick thread holds it: the World, what each body looks like, the
//! delta tracker for snapshots, and how commands are applied. No Zenoh here, no threads:
//! [`super::tick`] drives it, and tests can drive it directly.

#![allow(clippy::unnecessary_cast)] // Real <-> f32 casts matter with the `f64` feature.

use super::config::{Limits, ServerConfig};
use super::intake::{Command, Incoming, SpawnDef};
use crate::physics::{Body, BodyId, PhysicsError, Real, Shape, Vec2, World};
use crate::protocol::{
    BodyInfo, BodyRef, Colour, CommandKey, Event, EventKind, Keys, Pose, SceneState, ShapeSpec,
    Snapshot, Vector,
};
use crate::scene::{Scene, SceneError};
use std::collections::{HashMap, VecDeque};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A body is sent in a delta snapshot when it moved more than this since it was last sent
/// (metres along either axis, or radians). Keyframes resend every dynamic body exactly.
pub const POSE_EPSILON: f32 = 1e-4;

/// Where the scene comes from; `…/reset` loads it again from here.
#[derive(Clone, Debug)]
pub enum SceneSource {
    /// The Falling Bricks scene compiled into the binary.
    Embedded,
    /// A scene file, re-read on every reset.
    File(PathBuf),
    /// A scene held in memory (tests, benchmarks).
    Given(Box<Scene>),
}

impl SceneSource {
    /// The scene source a config names.
    pub fn from_config(config: &ServerConfig) -> SceneSource {
        match &config.scene {
            Some(path) => SceneSource::File(path.clone()),
            None => SceneSource::Embedded,
        }
    }

    /// Load (or reload) the scene.
    pub fn load(&self) -> Result<Scene, SceneError> {
        match self {
            SceneSource::Embedded => Scene::embedded_default(),
            SceneSource::File(path) => Scene::load(path),
            SceneSource::Given(scene) => Ok((**scene).clone()),
        }
    }
}

/// What a body looks like and is made of: fixed for its lifetime.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyMeta {
    /// Name (may be empty).
    pub name: String,
    /// Colour.
    pub colour: Colour,
    /// Immovable.
    pub is_static: bool,
    /// Shape.
    pub shape: ShapeSpec,
    /// Mass (kg), 0 for static bodies.
    pub mass: f32,
    /// Friction.
    pub friction: f32,
    /// Restitution.
    pub restitution: f32,
}

impl BodyMeta {
    fn of(body: &Body, name: String, colour: Colour) -> BodyMeta {
        BodyMeta {
            name,
            colour,
            is_static: body.is_static(),
            shape: shape_spec(body.shape()),
            mass: if body.is_static() {
                0.0
            } else {
                body.mass() as f32
            },
            friction: body.friction() as f32,
            restitution: body.restitution() as f32,
        }
    }
}

/// The wire form of an engine shape.
pub fn shape_spec(shape: &Shape) -> ShapeSpec {
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
            vertices: p
                .vertices()
                .iter()
                .map(|v| Vector::new(v.x as f32, v.y as f32))
                .collect(),
        },
    }
}

fn body_is_finite(b: &Body) -> bool {
    [
        b.position().x,
        b.position().y,
        b.angle(),
        b.linear_velocity().x,
        b.linear_velocity().y,
        b.angular_velocity(),
    ]
    .iter()
    .all(|v| v.is_finite())
}

fn vector(v: Vec2) -> Vector {
    Vector::new(v.x as f32, v.y as f32)
}

/// One body in a [`SceneView`].
#[derive(Clone, Debug)]
pub struct ViewBody {
    /// Id.
    pub id: BodyRef,
    /// What it is.
    pub meta: Arc<BodyMeta>,
    /// Centre of mass (m).
    pub position: Vector,
    /// Orientation (rad).
    pub angle: f32,
    /// Linear velocity (m/s).
    pub velocity: Vector,
    /// Angular velocity (rad/s).
    pub angular_velocity: f32,
}

impl ViewBody {
    /// The wire description.
    pub fn info(&self) -> BodyInfo {
        let m = &*self.meta;
        BodyInfo {
            id: self.id,
            name: m.name.clone(),
            shape: m.shape.clone(),
            is_static: m.is_static,
            colour: m.colour,
            position: self.position,
            angle: self.angle,
            velocity: self.velocity,
            angular_velocity: self.angular_velocity,
            mass: m.mass,
            friction: m.friction,
            restitution: m.restitution,
        }
    }
}

/// The whole state after a step, shared with the `…/scene` queryable through an `Arc` that the
/// tick thread replaces every tick (the World itself is never shared).
#[derive(Clone, Debug)]
pub struct SceneView {
    /// World name.
    pub world: String,
    /// Scene name.
    pub scene: String,
    /// Frame.
    pub frame: u64,
    /// Simulated time (s).
    pub time: f64,
    /// Gravity (m/s^2).
    pub gravity: Vector,
    /// Every body in slot order.
    pub bodies: Vec<ViewBody>,
}

impl SceneView {
    /// The `…/scene` reply.
    pub fn to_state(&self) -> SceneState {
        SceneState {
            world: self.world.clone(),
            scene: self.scene.clone(),
            frame: self.frame,
            time: self.time,
            gravity: self.gravity,
            bodies: self.bodies.iter().map(ViewBody::info).collect(),
        }
    }
}

/// Why the daemon could not start its simulation.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// The scene could not be loaded or built.
    #[error("scene: {0}")]
    Scene(#[from] SceneError),
    /// The scene has more bodies than the limit.
    #[error("the scene has {bodies} bodies, more than limits.max_bodies = {max}")]
    TooManyBodies {
        /// Bodies in the scene.
        bodies: usize,
        /// The limit.
        max: u32,
    },
    /// A checkpoint (or a journal's starting state) cannot be used.
    #[error("checkpoint: {0}")]
    Checkpoint(String),
}

/// Everything a [`Simulation`] carries from one tick to the next: what a checkpoint stores.
/// Snapshot delta bookkeeping is not kept (a restored simulation starts with a keyframe).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SimState {
    /// World name it ran as.
    pub world_name: String,
    /// Scene name.
    pub scene_name: String,
    /// |gravity| of the scene, which tilts scale.
    pub scene_gravity: f32,
    /// dt (s) it ran with.
    pub dt: f64,
    /// Last frame stepped.
    pub frame: u64,
    /// Per slot: the generation and what the body looks like.
    pub meta: Vec<Option<(u32, BodyMeta)>>,
    /// Frames of the spawns applied in the last second (the rate limit's window).
    pub spawn_frames: Vec<u64>,
    /// Commands applied.
    pub applied: u64,
    /// Commands rejected.
    pub rejected: u64,
    /// The World.
    pub world: crate::physics::WorldState,
}

/// The World plus everything the daemon keeps about it.
pub struct Simulation {
    world: World,
    scene_name: String,
    scene_gravity: f32,
    source: SceneSource,
    world_name: String,
    keys: Keys,
    limits: Limits,
    dt: Real,
    dt_secs: f64,
    frame: u64,
    meta: Vec<Option<(u32, Arc<BodyMeta>)>>,
    last_sent: Vec<Option<(u32, [f32; 3])>>,
    force_keyframe: bool,
    keyframe_every: u64,
    spawn_frames: VecDeque<u64>,
    spawn_window: u64,
    snapshot: Snapshot,
    /// Commands applied since start.
    pub applied: u64,
    /// Commands rejected since start.
    pub rejected: u64,
}

impl Simulation {
    /// Load the scene and build the World. Frame 0, nothing stepped yet.
    pub fn new(config: &ServerConfig, source: SceneSource) -> Result<Simulation, StartError> {
        let mut sim = Simulation::new_empty(config, source);
        sim.load_scene()?;
        Ok(sim)
    }

    fn new_empty(config: &ServerConfig, source: SceneSource) -> Simulation {
        let keys = config
            .keys()
            .expect("config validated before the simulation starts");
        Simulation {
            world: World::default(),
            scene_name: String::new(),
            scene_gravity: 9.81,
            source,
            world_name: config.world.clone(),
            keys,
            limits: config.limits.clone(),
            dt: config.dt() as Real,
            dt_secs: config.dt(),
            frame: 0,
            meta: Vec::new(),
            last_sent: Vec::new(),
            force_keyframe: true,
            keyframe_every: config.keyframe_every as u64,
            spawn_frames: VecDeque::new(),
            spawn_window: config.tick_hz.round().max(1.0) as u64,
            snapshot: Snapshot {
                frame: 0,
                time: 0.0,
                gravity: Vector::default(),
                keyframe: true,
                poses: Vec::new(),
            },
            applied: 0,
            rejected: 0,
        }
    }

    /// A simulation continuing from `state` (a checkpoint). `source` is still what `…/reset`
    /// loads. The world name, dt and limits in force are the config's; a different dt than
    /// the checkpoint's is refused (the continuation would not be the same simulation).
    pub fn restore(
        config: &ServerConfig,
        source: SceneSource,
        state: SimState,
    ) -> Result<Simulation, StartError> {
        let bad = |m: String| StartError::Checkpoint(m);
        if state.dt.to_bits() != config.dt().to_bits() {
            return Err(bad(format!(
                "it was taken with dt = {} s, the config has tick_hz = {} (dt = {} s)",
                state.dt,
                config.tick_hz,
                config.dt()
            )));
        }
        if !(state.scene_gravity.is_finite() && state.scene_gravity > 0.0) {
            return Err(bad(format!("scene gravity = {}", state.scene_gravity)));
        }
        let world = World::import_state(&state.world).map_err(|e| bad(e.to_string()))?;
        if world.body_count() > config.limits.max_bodies as usize {
            return Err(StartError::TooManyBodies {
                bodies: world.body_count(),
                max: config.limits.max_bodies,
            });
        }
        if state.world.steps != state.frame {
            tracing::debug!(
                steps = state.world.steps,
                frame = state.frame,
                "checkpoint: world steps and frame differ (resets keep the step count)"
            );
        }
        let mut sim = Simulation::new_empty(config, source);
        sim.world = world;
        sim.scene_name = state.scene_name;
        sim.scene_gravity = state.scene_gravity;
        sim.frame = state.frame;
        sim.meta = state
            .meta
            .into_iter()
            .map(|m| m.map(|(g, meta)| (g, Arc::new(meta))))
            .collect();
        sim.spawn_frames = state.spawn_frames.into();
        sim.applied = state.applied;
        sim.rejected = state.rejected;
        if state.world_name != sim.world_name {
            tracing::warn!(
                was = %state.world_name,
                now = %sim.world_name,
                "checkpoint taken under another world name"
            );
        }
        Ok(sim)
    }

    /// The state to checkpoint (see [`Simulation::restore`]).
    pub fn export_state(&self) -> SimState {
        SimState {
            world_name: self.world_name.clone(),
            scene_name: self.scene_name.clone(),
            scene_gravity: self.scene_gravity,
            dt: self.dt_secs,
            frame: self.frame,
            meta: self
                .meta
                .iter()
                .map(|m| m.as_ref().map(|(g, meta)| (*g, (**meta).clone())))
                .collect(),
            spawn_frames: self.spawn_frames.iter().copied().collect(),
            applied: self.applied,
            rejected: self.rejected,
            world: self.world.export_state(),
        }
    }

    /// (Re)load the scene from its source and replace the World; nothing changes on error.
    fn load_scene(&mut self) -> Result<(), StartError> {
        let scene = self.source.load()?;
        if scene.bodies.len() > self.limits.max_bodies as usize {
            return Err(StartError::TooManyBodies {
                bodies: scene.bodies.len(),
                max: self.limits.max_bodies,
            });
        }
        let (world, ids) = scene.build_world()?;
        self.world = world;
        self.meta.clear();
        self.last_sent.clear();
        for (body, id) in scene.bodies.iter().zip(ids) {
            let colour = Colour {
                r: body.colour.r,
                g: body.colour.g,
                b: body.colour.b,
            };
            self.set_meta(id, body.name.clone(), colour);
        }
        self.scene_name = scene.name.clone();
        let g = scene.gravity.length() as f32;
        self.scene_gravity = if g > 0.0 { g } else { 9.81 };
        self.force_keyframe = true;
        Ok(())
    }

    fn set_meta(&mut self, id: BodyId, name: String, colour: Colour) {
        let body = self.world.body(id).expect("body just added");
        let meta = Arc::new(BodyMeta::of(body, name, colour));
        let i = id.index() as usize;
        if self.meta.len() <= i {
            self.meta.resize(i + 1, None);
        }
        self.meta[i] = Some((id.generation(), meta));
    }

    fn meta_of(&self, id: BodyId) -> Arc<BodyMeta> {
        match self.meta.get(id.index() as usize) {
            Some(Some((generation, m))) if *generation == id.generation() => m.clone(),
            _ => Arc::new(BodyMeta::of(
                self.world.body(id).expect("live body"),
                String::new(),
                Colour::default(),
            )),
        }
    }

    /// The World (read only).
    pub fn world(&self) -> &World {
        &self.world
    }
    /// The last frame stepped (0 before the first step).
    pub fn frame(&self) -> u64 {
        self.frame
    }
    /// The frame the next step will have: commands applied now are stamped with it.
    pub fn next_frame(&self) -> u64 {
        self.frame + 1
    }
    /// Simulated time (s) at the last frame.
    pub fn time(&self) -> f64 {
        self.frame as f64 * self.dt_secs
    }
    /// The keys of this world.
    pub fn keys(&self) -> &Keys {
        &self.keys
    }

    fn info(&self, body: &Body) -> BodyInfo {
        self.view_body(body).info()
    }

    fn view_body(&self, body: &Body) -> ViewBody {
        ViewBody {
            id: body.id().into(),
            meta: self.meta_of(body.id()),
            position: vector(body.position()),
            angle: body.angle() as f32,
            velocity: vector(body.linear_velocity()),
            angular_velocity: body.angular_velocity() as f32,
        }
    }

    fn reject(&mut self, key: CommandKey, reason: String) -> Event {
        self.rejected += 1;
        tracing::warn!(key = %self.keys.command(key), frame = self.next_frame(), "rejected: {reason}");
        Event {
            frame: self.next_frame(),
            kind: EventKind::Rejected {
                key: self.keys.command(key),
                reason,
            },
        }
    }

    /// The rejection for `count` commands on `key` dropped because the command channel was full.
    pub fn reject_dropped(&mut self, key: CommandKey, count: u64, capacity: u32) -> Event {
        self.rejected += count - 1; // reject() counts one
        self.reject(
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
        self.world
            .set_gravity(Vec2::new(g.x as Real, g.y as Real))
            .map_err(|e| e.to_string())
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
                    for id in ids {
                        let _ = self.world.remove_body(id);
                    }
                    return Err(format!("bodies[{i}]: {e}"));
                }
            }
        }
        self.spawn_frames.push_back(frame);
        let mut bodies = Vec::with_capacity(ids.len());
        for (d, id) in defs.into_iter().zip(ids) {
            self.set_meta(id, d.name, d.colour);
            bodies.push(self.info(self.world.body(id).expect("just added")));
        }
        Ok(EventKind::Added { bodies })
    }

    fn remove(&mut self, refs: Vec<BodyRef>) -> Result<EventKind, String> {
        // The live bodies by their wire id: a wire id names a body only if one has it now.
        let live: HashMap<BodyRef, BodyId> = self
            .world
            .bodies()
            .map(|b| (BodyRef::from(b.id()), b.id()))
            .collect();
        let mut ids = Vec::with_capacity(refs.len());
        for (i, r) in refs.iter().enumerate() {
            let Some(&id) = live.get(r) else {
                return Err(format!("ids[{i}]: no body with id {r}"));
            };
            if refs[..i].contains(r) {
                return Err(format!("ids[{i}]: body {r} is listed twice"));
            }
            ids.push(id);
        }
        for id in &ids {
            self.world.remove_body(*id).map_err(|e| e.to_string())?;
            if let Some(m) = self.meta.get_mut(id.index() as usize) {
                *m = None;
            }
            if let Some(s) = self.last_sent.get_mut(id.index() as usize) {
                *s = None;
            }
        }
        Ok(EventKind::Removed { ids: refs })
    }

    fn reset(&mut self) -> Result<EventKind, String> {
        self.load_scene()
            .map_err(|e| format!("cannot reload the scene: {e}"))?;
        tracing::info!(frame = self.next_frame(), scene = %self.scene_name, "reset");
        Ok(EventKind::Reset {
            scene: self.scene_name.clone(),
            gravity: vector(self.world.gravity()),
            bodies: self.world.bodies().map(|b| self.info(b)).collect(),
        })
    }

    /// Step like [`Simulation::step`], but survive an engine failure: if `World::step`
    /// panics or leaves a body with a non-finite number, the scene is reloaded (the world is
    /// lost, the daemon is not) and the `Reset` event to publish is returned. Deterministic,
    /// so a replay recovers at the same frame.
    pub fn step_guarded(&mut self) -> Result<(Duration, Option<Event>), PhysicsError> {
        let t0 = Instant::now();
        let before = self.frame;
        let stepped = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| self.step()));
        let failure = match stepped {
            Ok(Ok(took)) => match self.world.bodies().find(|b| !body_is_finite(b)) {
                None => return Ok((took, None)),
                Some(b) => format!("body {} holds a non-finite number", b.id()),
            },
            Ok(Err(e)) => return Err(e),
            Err(_) => "the engine panicked".to_owned(),
        };
        // The frame that failed still counts, so frame numbers stay consecutive.
        self.frame = before + 1;
        tracing::error!(
            frame = self.frame,
            "{failure}: reloading the scene to keep serving"
        );
        let event = match self.reset() {
            Ok(kind) => Some(Event {
                frame: self.next_frame(),
                kind,
            }),
            Err(e) => {
                tracing::error!("cannot reload the scene either: {e}");
                self.world.clear();
                None
            }
        };
        Ok((t0.elapsed(), event))
    }

    /// Step the World once (frame += 1); returns how long `World::step` took.
    pub fn step(&mut self) -> Result<Duration, PhysicsError> {
        let t0 = Instant::now();
        self.world.step(self.dt)?;
        let took = t0.elapsed();
        self.frame += 1;
        Ok(took)
    }

    /// The snapshot of the frame just stepped: a keyframe every `keyframe_every` frames and
    /// after a reset, otherwise the dynamic bodies that moved more than [`POSE_EPSILON`]
    /// since they were last sent. Call once per step.
    pub fn snapshot(&mut self) -> &Snapshot {
        let keyframe = self.force_keyframe || self.frame % self.keyframe_every == 0;
        self.force_keyframe = false;
        let s = &mut self.snapshot;
        s.frame = self.frame;
        s.time = self.frame as f64 * self.dt_secs;
        s.gravity = vector(self.world.gravity());
        s.keyframe = keyframe;
        s.poses.clear();
        for body in self.world.bodies() {
            if body.is_static() {
                continue;
            }
            let id = body.id();
            let now = [
                body.position().x as f32,
                body.position().y as f32,
                body.angle() as f32,
            ];
            let i = id.index() as usize;
            if self.last_sent.len() <= i {
                self.last_sent.resize(i + 1, None);
            }
            let moved = match self.last_sent[i] {
                Some((generation, was)) if generation == id.generation() => {
                    (0..3).any(|k| (now[k] - was[k]).abs() > POSE_EPSILON)
                }
                _ => true,
            };
            if keyframe || moved {
                self.last_sent[i] = Some((id.generation(), now));
                s.poses.push(Pose {
                    id: id.into(),
                    x: now[0],
                    y: now[1],
                    angle: now[2],
                });
            }
        }
        &self.snapshot
    }

    /// The full state, for the `…/scene` queryable.
    pub fn view(&self) -> SceneView {
        SceneView {
            world: self.world_name.clone(),
            scene: self.scene_name.clone(),
            frame: self.frame,
            time: self.time(),
            gravity: vector(self.world.gravity()),
            bodies: self.world.bodies().map(|b| self.view_body(b)).collect(),
        }
    }

    /// Dynamic bodies that are awake.
    pub fn awake_count(&self) -> usize {
        self.world.awake_count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{encode, Spawn, SpawnBody};

    fn spawn(sim: &mut Simulation, shapes: Vec<(ShapeSpec, Vector, f32)>) -> Vec<BodyInfo> {
        let bodies = shapes
            .into_iter()
            .map(|(shape, position, angle)| SpawnBody {
                name: None,
                shape,
                position,
                angle,
                velocity: Vector::default(),
                angular_velocity: 0.0,
                density: 1.0,
                friction: 0.5,
                restitution: 0.0,
                colour: Colour::default(),
            })
            .collect();
        let payload = encode(&Spawn { bodies }).unwrap();
        let command = super::super::intake::parse(CommandKey::Spawn, &payload, &sim.limits);
        match sim.apply(Incoming {
            key: CommandKey::Spawn,
            command,
        }) {
            Some(Event {
                kind: EventKind::Added { bodies },
                ..
            }) => bodies,
            other => panic!("{other:?}"),
        }
    }

    /// Every shape kind a spawn can make, including a small polygon drawn far from its
    /// spawn position, survives a checkpoint: encoded, decoded, restored, and stepping on
    /// gives bit-identical states.
    #[test]
    fn every_spawned_shape_survives_a_checkpoint_round_trip() {
        let config = ServerConfig::default();
        let mut sim = Simulation::new(&config, SceneSource::Embedded).unwrap();
        let pentagon: Vec<Vector> = (0..5)
            .map(|i| {
                let a = 0.3 + i as f32 * 1.2566;
                Vector::new(998.0 + 0.05 * a.cos(), -997.0 + 0.05 * a.sin())
            })
            .collect();
        let added = spawn(
            &mut sim,
            vec![
                (
                    ShapeSpec::Circle { radius: 0.3 },
                    Vector::new(-2.0, 3.0),
                    0.3,
                ),
                (
                    ShapeSpec::Capsule {
                        length: 1.0,
                        radius: 0.2,
                    },
                    Vector::new(0.0, 3.0),
                    0.3,
                ),
                (
                    ShapeSpec::Polygon { vertices: pentagon },
                    Vector::new(-996.0, 1000.0),
                    0.0,
                ),
            ],
        );
        assert!(matches!(added[0].shape, ShapeSpec::Circle { .. }));
        assert!(matches!(added[1].shape, ShapeSpec::Capsule { .. }));
        assert!(matches!(added[2].shape, ShapeSpec::Polygon { .. }));
        // the pentagon's centroid is about (998, -997): the body lands near (2, 3)
        let p = added[2].position;
        assert!(
            (p.x - 2.0).abs() < 0.01 && (p.y - 3.0).abs() < 0.01,
            "{p:?}"
        );
        for _ in 0..5 {
            sim.step().unwrap();
        }
        let bytes = super::super::checkpoint::encode(&sim.export_state()).unwrap();
        let state = super::super::checkpoint::decode(&bytes).unwrap();
        assert_eq!(state, sim.export_state());
        let mut back = Simulation::restore(&config, SceneSource::Embedded, state).unwrap();
        for _ in 0..30 {
            sim.step().unwrap();
            back.step().unwrap();
        }
        assert_eq!(back.export_state(), sim.export_state());
        assert_eq!(
            back.view().to_state(),
            sim.view().to_state(),
            "restored and original agree"
        );
    }
}
