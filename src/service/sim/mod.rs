//! The simulation as the tick thread holds it: the World, what each body looks like, the
//! delta tracker for snapshots, and how commands are applied. No Zenoh here, no threads:
//! the tick loop drives it, and tests can drive it directly.
//!
//! - [`SceneSource`] (`source.rs`): where the scene comes from;
//! - `bodies.rs`: each live body's name, colour and wire shape;
//! - `apply.rs`: applying commands (gravity, tilt, spawn, remove, reset, velocity), all or
//!   nothing;
//! - `hands.rs`: bodies held over `…/drag` (grab, move, let go, time out);
//! - `physics_events.rs`: the World's contact, hit and sensor events as `…/events`;
//! - `query.rs`: answering `…/query` (rays, points, boxes);
//! - `poses.rs`: the `…/poses` message of each frame, keyframes and deltas;
//! - [`SimState`] and [`StartError`] (`state.rs`): what a checkpoint stores, and why a
//!   simulation cannot start.

#![allow(clippy::unnecessary_cast)] // Real <-> f32 casts matter with the `f64` feature.

mod apply;
mod bodies;
mod hands;
mod physics_events;
mod poses;
mod query;
mod source;
mod state;

pub use physics_events::MAX_PHYSICS_EVENTS;
pub use source::SceneSource;
pub use state::{SimState, StartError};

use super::config::{Limits, ServerConfig};
use super::wire::{body_info, vector};
use crate::physics::{PhysicsError, Real, WorkerPool, World};
use crate::protocol::{
    BodyInfo, Event, Grid, JointInfo, Keys, SceneState, SceneWithJoints, SnapshotFrame,
};
use bodies::BodyRegistry;
use poses::PoseDeltas;
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// The World plus everything the daemon keeps about it.
pub struct Simulation {
    world: World,
    scene_name: String,
    /// |gravity| of the scene (m/s^2): a tilt gives gravity of this magnitude.
    scene_gravity: f32,
    source: SceneSource,
    world_name: String,
    keys: Keys,
    limits: Limits,
    dt: Real,
    dt_secs: f64,
    frame: u64,
    bodies: BodyRegistry,
    poses: PoseDeltas,
    /// Frames of the spawns applied within the last second (the rate limit's window).
    spawn_frames: VecDeque<u64>,
    /// The rate limit's window, in frames (one second).
    spawn_window: u64,
    applied: u64,
    rejected: u64,
    /// Bodies held over `…/drag`.
    hands: hands::Hands,
    /// A reset loaded a scene with joints: the next step's events list them (`Built`).
    announce_joints: bool,
    /// The workers that share the steps (the daemon's pool, see [`Simulation::share_workers`]);
    /// none: the World steps alone, whatever its scene's `workers` says.
    pool: Option<WorkerPool>,
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
            bodies: BodyRegistry::default(),
            poses: PoseDeltas::new(
                config.keyframe_every as u64,
                Grid::new(config.snapshot_grid_bits.min(255) as u8).unwrap_or_default(),
            ),
            spawn_frames: VecDeque::new(),
            spawn_window: config.tick_hz.round().max(1.0) as u64,
            applied: 0,
            rejected: 0,
            hands: hands::Hands::default(),
            announce_joints: false,
            pool: None,
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
        sim.apply_workers();
        sim.scene_name = state.scene_name;
        sim.scene_gravity = state.scene_gravity;
        sim.frame = state.frame;
        sim.bodies = BodyRegistry::from_slots(state.meta);
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
            meta: self.bodies.slots().to_vec(),
            spawn_frames: self.spawn_frames.iter().copied().collect(),
            applied: self.applied,
            rejected: self.rejected,
            world: if self.hands.joints().next().is_none() {
                self.world.export_state()
            } else {
                self.world_without_hands().export_state()
            },
        }
    }

    /// (Re)load the scene from its source and replace the World; nothing changes on error.
    fn load_scene(&mut self) -> Result<(), StartError> {
        let mut scene = self.source.load()?;
        if scene.bodies.len() > self.limits.max_bodies as usize {
            return Err(StartError::TooManyBodies {
                bodies: scene.bodies.len(),
                max: self.limits.max_bodies,
            });
        }
        // The daemon's workers replace the scene's (no team is started only to be dropped).
        let workers = self.pool.as_ref().map_or(1, WorkerPool::workers);
        if scene.settings.workers > 1 && scene.settings.workers != workers {
            tracing::info!(
                scene = scene.settings.workers,
                daemon = workers,
                "the scene's workers are replaced by the daemon's"
            );
        }
        scene.settings.workers = 1;
        let (world, ids) = scene.build_world()?;
        self.world = world;
        self.apply_workers();
        self.hands.clear();
        self.bodies.clear();
        self.poses.restart();
        for (body, id) in scene.bodies.iter().zip(ids) {
            self.describe(id, body.name.clone(), body.colour);
        }
        self.scene_name = scene.name.clone();
        let g = scene.gravity.length() as f32;
        self.scene_gravity = if g > 0.0 { g } else { 9.81 };
        Ok(())
    }

    /// Share the steps with `pool`'s workers (the daemon's, shared by all its worlds), or
    /// step alone with `None`; this World and every one a reset loads. The results are the
    /// same to the bit either way.
    pub fn share_workers(&mut self, pool: Option<WorkerPool>) {
        self.pool = pool;
        self.apply_workers();
    }

    fn apply_workers(&mut self) {
        match &self.pool {
            Some(pool) => self.world.share_workers(pool),
            None => {
                // One worker starts no thread and the settings are the World's own, valid.
                if let Err(e) = self.world.set_workers(1) {
                    tracing::error!("cannot step alone: {e}");
                }
            }
        }
    }

    /// Record what the body `id`, just added, is called and looks like.
    fn describe(
        &mut self,
        id: crate::physics::BodyId,
        name: String,
        colour: crate::protocol::Colour,
    ) {
        let body = self.world.body(id).expect("body just added");
        let meta = super::wire::BodyMeta::of(body, name, colour);
        self.bodies.set(id, meta);
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
    /// Commands applied since the start (a restored simulation counts on from its checkpoint).
    pub fn applied(&self) -> u64 {
        self.applied
    }
    /// Commands rejected since the start, each with its `Rejected` event (commands a full
    /// queue dropped are counted by the tick loop, not here).
    pub fn rejected(&self) -> u64 {
        self.rejected
    }
    /// The name `body` was given by its scene or its spawn (empty if none).
    pub fn body_name(&self, body: &crate::physics::Body) -> String {
        self.bodies.meta_of(body).name
    }
    /// Dynamic bodies that are awake.
    pub fn awake_count(&self) -> usize {
        self.world.awake_count()
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
            Ok(Ok(took)) => match self.world.bodies().find(|b| !b.is_finite()) {
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
        self.expire_hands();
        let t0 = Instant::now();
        self.world.step(self.dt)?;
        let took = t0.elapsed();
        self.frame += 1;
        Ok(took)
    }

    /// The `…/poses` payload of the frame just stepped, written into `out` (cleared first): a
    /// keyframe every `keyframe_every` frames and after a reset, otherwise a delta against
    /// the latest keyframe (`docs/protocol.md`). Returns the frame as encoded. Call once per
    /// step.
    pub fn snapshot_into(&mut self, out: &mut Vec<u8>) -> &SnapshotFrame {
        let time = self.time();
        self.poses.message(&self.world, self.frame, time, out)
    }

    /// The full state after the last step, every body included: the `…/scene` reply. Built
    /// on demand (late joiners ask for it), never kept.
    pub fn scene_state(&self) -> SceneState {
        SceneState {
            world: self.world_name.clone(),
            scene: self.scene_name.clone(),
            frame: self.frame,
            time: self.time(),
            gravity: vector(self.world.gravity()),
            bodies: self.body_infos(),
        }
    }

    /// The `…/scene?joints` reply: [`Simulation::scene_state`] and every joint (drag hands'
    /// excepted), in slot order.
    pub fn scene_with_joints(&self) -> SceneWithJoints {
        SceneWithJoints {
            scene: self.scene_state(),
            joints: self.joint_infos(),
        }
    }

    /// Every joint as the wire describes it, in slot order (a drag hand's target joint is
    /// never listed).
    pub(super) fn joint_infos(&self) -> Vec<JointInfo> {
        self.world
            .joints()
            .filter_map(super::wire::build::joint_info)
            .collect()
    }

    /// Every body, static ones included, in slot order, as the wire describes it.
    fn body_infos(&self) -> Vec<BodyInfo> {
        self.world
            .bodies()
            .map(|b| body_info(b, &self.bodies.meta_of(b)))
            .collect()
    }
}
