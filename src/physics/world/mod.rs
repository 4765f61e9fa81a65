//! The World: bodies, gravity, settings, and `step(dt)`.
//!
//! - `mod.rs`: the World and its API (bodies, forces, queries, energy);
//! - `step.rs`: the step's stages in order, and the soft step by stiffness tier;
//! - `contacts.rs`: finding contacts (broad phase, narrow phase, merging with last step's);
//! - `tiers.rs`: adaptive stiffness, a tier for each island;
//! - `islands.rs`: islands, sleep and waking;
//! - `snapshot.rs`: the full state as plain data (checkpoints).

use super::body::{Body, BodyDef, BodyId};
use super::broad_phase::{pair_of, Piece, Proxy, SweepAndPrune};
use super::collide::collide;
use super::contact::{Contact, ContactInfo, ContactPoint, ContactPointInfo};
use super::error::{finite, finite_vec, positive, PhysicsError};
use super::events::EventState;
use super::filter::Filter;
use super::math::{cross, Real, Rot, Vec2};
use super::settings::{Settings, SolverKind};
use super::solver::bundles::ContactBundles;
use super::solver::constraint::ContactConstraint;
use super::solver::graph::ConstraintGraph;
use super::solver::recover::Recovery;
use super::solver::sequential::SplitImpulse;
use super::solver::{clamp_speed, Kinematic, SolverBody};
use super::team::{Team, WorkerPool};

/// Export and import of the full state (checkpoints); a child module so it reads private fields.
pub mod snapshot;

pub use queries::Query;

mod contacts;
mod continuous;
mod events;
mod islands;
mod joints;
mod queries;
#[cfg(test)]
mod query_tests;
mod step;
#[cfg(test)]
mod tests;
mod tiers;

/// One entry of the body array: a body, or a free slot remembering its generation.
#[derive(Clone, Debug)]
struct Slot {
    generation: u32,
    body: Option<Body>,
}

/// A 2D rigid-body world.
///
/// Units throughout: metres, seconds, radians, kilograms. Every method that takes input
/// validates it and refuses what cannot be simulated, so a World never holds NaN. Buffers are
/// kept from step to step, so a steady step does not allocate.
#[derive(Clone, Debug)]
pub struct World {
    settings: Settings,
    gravity: Vec2,
    /// Simulated time (s) and steps taken.
    time: f64,
    steps: u64,
    bodies: Bodies,
    contacts: Contacts,
    broad_phase: BroadPhase,
    solver: SolverScratch,
    tiers: tiers::TierScratch,
    islands: islands::IslandScratch,
    joints: joints::Joints,
    /// The query tree, built at the first query (`queries.rs`).
    queries: queries::QueryIndex,
    /// The last step's events and what finding the next ones reads (`events.rs`).
    events: EventState,
    /// The threads that share the step (`Settings::workers`).
    workers: Workers,
}

/// The threads that share a World's step: none for `Settings::workers = 1`, a team of its
/// own, or a pool it shares with other Worlds.
#[derive(Debug, Default)]
enum Workers {
    #[default]
    Alone,
    Own(Team),
    Pool(WorkerPool),
}

impl Workers {
    /// Workers for `settings`: this thread alone for one, a [`Team`] for more.
    fn start(workers: u32) -> Result<Workers, PhysicsError> {
        if workers <= 1 {
            return Ok(Workers::Alone);
        }
        Team::new(workers)
            .map(Workers::Own)
            .map_err(|e| PhysicsError::NoWorkers {
                workers,
                reason: e.to_string(),
            })
    }

    /// How many, the stepping thread included.
    fn count(&self) -> u32 {
        match self {
            Workers::Alone => 1,
            Workers::Own(team) => team.workers(),
            Workers::Pool(pool) => pool.workers(),
        }
    }
}

impl Clone for Workers {
    /// A team of the same size (or this thread alone, if the system starts no thread: the
    /// results are the same either way); a pool is shared with the clone.
    fn clone(&self) -> Self {
        match self {
            Workers::Alone => Workers::Alone,
            Workers::Own(team) => Team::new(team.workers()).map_or(Workers::Alone, Workers::Own),
            Workers::Pool(pool) => Workers::Pool(pool.clone()),
        }
    }
}

/// The bodies: a slot array with a free list.
#[derive(Clone, Debug, Default)]
struct Bodies {
    slots: Vec<Slot>,
    /// Free slots, reused last first.
    free: Vec<u32>,
    /// Live bodies.
    count: usize,
    /// Live bodies whose filter is not the default (none: no pair is filtered).
    filtered: usize,
    /// Live bodies with a shape that reports events or is a sensor (none: no step looks).
    flagged: usize,
    /// Live static bodies with a chain's piece or a one-sided segment (none: no step looks
    /// for centres that crossed one; `continuous::guards_shape`).
    guarded: usize,
    /// Of those, the bodies with a shape that reports touches, and those with a sensor: each
    /// event stage runs only while some body asks for it (8,100 boxes that report hits kept the
    /// sensor stage's query tree in step with them, 6 % of Box2D's washer, with no sensor).
    asking: Asking,
    /// Scratch for `remove_bodies`: a flag per slot, all false between calls.
    removing: Vec<bool>,
}

/// How many live bodies ask for each kind of event.
#[derive(Clone, Copy, Debug, Default)]
struct Asking {
    touches: usize,
    sensors: usize,
}

impl Bodies {
    /// Count `body`'s filter and flags in (`add`) or out.
    fn note(&mut self, body: &Body, add: bool) {
        let [filtered, flagged, touches, sensors, guarded] = [
            body.filter() != Filter::DEFAULT,
            body.any_flags(),
            body.asks(|f| f.contact_events),
            body.asks(|f| f.sensor),
            body.is_static() && body.shapes().any(|(s, _)| continuous::guards_shape(s)),
        ]
        .map(usize::from);
        if add {
            self.guarded += guarded;
            self.filtered += filtered;
            self.flagged += flagged;
            self.asking.touches += touches;
            self.asking.sensors += sensors;
        } else {
            self.guarded -= guarded;
            self.filtered -= filtered;
            self.flagged -= flagged;
            self.asking.touches -= touches;
            self.asking.sensors -= sensors;
        }
    }
}

/// The contacts, sorted by pair key, and the constraint graph that colours them.
#[derive(Clone, Debug, Default)]
struct Contacts {
    /// Contacts with an awake body: solved.
    awake: Vec<Contact>,
    /// Last step's, while this step's are found into `awake` (swapped, so neither allocates).
    previous: Vec<Contact>,
    /// Contacts between sleeping bodies (or sleeping and static): kept with their impulses to
    /// warm start their island when it wakes, never solved, not in the graph.
    sleeping: Vec<Contact>,
    /// Every awake contact's colour.
    graph: ConstraintGraph,
    /// While a merge after the workers' narrow phase copies (`contacts::Merge`): this step's
    /// contacts as runs of last step's and of those it wrote, copied into `awake` by the
    /// workers at its end...
    runs: Vec<contacts::Run>,
    /// ...the contacts it wrote, in order...
    written: Vec<Contact>,
    /// ...and where each run starts in `awake`.
    run_starts: Vec<u32>,
    /// Tests: find contacts into a fresh array every step, never in place.
    #[cfg(test)]
    copy_for_tests: bool,
}

/// The broad phase and what it reads each step.
#[derive(Clone, Debug, Default)]
struct BroadPhase {
    sweep: SweepAndPrune,
    /// Each slot's box for this step.
    proxies: Vec<Proxy>,
    /// Each slot's travel this step: how far its box is grown and swept beyond the margin.
    reach: Vec<contacts::Travel>,
    /// This step's candidate pairs, by key.
    pair_keys: Vec<u64>,
    /// Scratch for a pair of bodies of several shapes: its pairs of shapes whose boxes meet.
    shape_pairs: Vec<u32>,
    /// When the workers collide the pairs first: what each pair came to ([`contacts::Found`]
    /// and the wake bits), and the fresh manifolds, indexed like `pair_keys`.
    found: Vec<u8>,
    manifolds: Vec<crate::physics::collide::Manifold>,
    /// Where each block of `pair_keys`' contacts begin among last step's (and the end).
    found_from: Vec<usize>,
    /// Per block: what its pairs of bodies of several shapes found, pair of shapes by pair of
    /// shapes in order, and scratch for those pairs of shapes.
    parts_found: Vec<Vec<contacts::PartFound>>,
    parts_scratch: Vec<Vec<u32>>,
    /// Whether each block is steady: its pairs' contacts are last step's, each updated in
    /// place, none of last step's in its run ended, and no pair begins one (the merge keeps
    /// them at once).
    steady: Vec<bool>,
    /// What adaptive stiffness reads of each contact updated in place, indexed like
    /// `pair_keys`.
    tier_found: Vec<tiers::TierInput>,
    /// The static bodies of several shapes, swept shape by shape (see [`Piece`]), by slot.
    pieced_slots: Vec<u32>,
    /// Their shapes' boxes for this step.
    pieces: Vec<Piece>,
}

impl BroadPhase {
    /// A body came alive in slot `index`: into the sweep, passive if static or asleep.
    fn insert(&mut self, index: u32, body: &Body) {
        self.sweep.insert(index, body.is_static() || !body.awake);
        if body.is_static() && body.compound().is_some() {
            self.pieced_slots.push(index);
        }
    }

    /// Bodies in `slots` (sorted) went.
    fn remove(&mut self, slots: &[u32]) {
        self.sweep.remove(slots);
        if !self.pieced_slots.is_empty() {
            self.pieced_slots
                .retain(|i| slots.binary_search(i).is_err());
        }
    }

    /// Every body went.
    fn clear(&mut self) {
        self.sweep.clear();
        self.pieced_slots.clear();
    }
}

/// The solvers' buffers for one step.
#[derive(Clone, Debug, Default)]
struct SolverScratch {
    /// A solver body per slot (fixed for all but awake dynamic ones), and one fixed body more.
    bodies: Vec<SolverBody>,
    /// The kinematic bodies that move.
    kinematic: Vec<Kinematic>,
    /// Sequential solver: the constraint per contact, indexed like `Contacts::awake`.
    constraints: Vec<ContactConstraint>,
    /// Sequential solver: the position correction.
    split_impulse: SplitImpulse,
    /// Soft step: the contacts packed for the lanes.
    bundles: ContactBundles,
    /// Soft step, on workers: the list each selected contact is packed into.
    lists: Vec<u8>,
    /// Soft step: the overlap beyond the springs' reach.
    recovery: Recovery,
    /// The bodies that moved far for their size this step, in slot order, and the fraction
    /// of the step each keeps (continuous collision).
    fast: Vec<u32>,
    /// On workers: each slot's mark (a fast body at finalize, a moving kinematic one at load),
    /// gathered in slot order once any is marked.
    marks: Vec<bool>,
    fast_hits: Vec<Real>,
    /// Each slot's place in `fast`, or [`continuous::NOT_FAST`] (kept so between steps).
    fast_place: Vec<u32>,
    /// The static bodies' broad-phase boxes in a tree, built when a fast body left its own
    /// box, with the build's scratch.
    statics: continuous::StaticTree,
    /// On workers: each candidate pair's fraction of the step to its impact (1 for none).
    pair_hits: Vec<Real>,
    /// The bodies whose centres crossed a chain piece or a one-sided segment this step, and the fraction of the
    /// step's motion each keeps.
    crossed: Vec<(u32, Real)>,
}

impl Default for World {
    fn default() -> Self {
        World::with_settings(Settings::default(), Vec2::new(0.0, -9.81))
    }
}

impl World {
    /// An empty world with validated `settings` and `gravity` (m/s^2).
    pub fn new(settings: Settings, gravity: Vec2) -> Result<World, PhysicsError> {
        settings.validate()?;
        finite_vec(["gravity.x", "gravity.y"], gravity)?;
        let workers = Workers::start(settings.workers)?;
        let mut world = World::with_settings(settings, gravity);
        world.workers = workers;
        Ok(world)
    }

    fn with_settings(settings: Settings, gravity: Vec2) -> World {
        World {
            settings,
            gravity,
            time: 0.0,
            steps: 0,
            bodies: Bodies::default(),
            contacts: Contacts::default(),
            broad_phase: BroadPhase::default(),
            solver: SolverScratch::default(),
            tiers: Default::default(),
            islands: Default::default(),
            joints: Default::default(),
            queries: Default::default(),
            events: Default::default(),
            workers: Workers::default(),
        }
    }

    /// The current settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Replace the settings (validated first; on error nothing changes).
    pub fn set_settings(&mut self, settings: Settings) -> Result<(), PhysicsError> {
        settings.validate()?;
        if settings.workers != self.workers.count() {
            self.workers = Workers::start(settings.workers)?;
        }
        self.settings = settings;
        self.wake_all();
        Ok(())
    }

    /// Share the step among `workers` threads (`Settings::workers`): the results are the
    /// same to the bit, so nothing else changes and nothing wakes.
    pub fn set_workers(&mut self, workers: u32) -> Result<(), PhysicsError> {
        Settings {
            workers,
            ..self.settings.clone()
        }
        .validate()?;
        if workers != self.workers.count() {
            self.workers = Workers::start(workers)?;
        }
        self.settings.workers = workers;
        Ok(())
    }

    /// Share the step with `pool`'s workers, which other Worlds may share too: a step takes
    /// them when no other World's step holds them and otherwise runs on this thread alone.
    /// The results are the same to the bit either way, so nothing else changes and nothing
    /// wakes. `Settings::workers` becomes the pool's size.
    pub fn share_workers(&mut self, pool: &WorkerPool) {
        self.workers = Workers::Pool(pool.clone());
        self.settings.workers = pool.workers();
    }

    /// Gravity (m/s^2).
    pub fn gravity(&self) -> Vec2 {
        self.gravity
    }

    /// Set gravity (m/s^2), effective from the next step.
    pub fn set_gravity(&mut self, gravity: Vec2) -> Result<(), PhysicsError> {
        finite_vec(["gravity.x", "gravity.y"], gravity)?;
        if gravity != self.gravity {
            // A tilt changes what "at rest" means for everything.
            self.wake_all();
        }
        self.gravity = gravity;
        Ok(())
    }

    /// Simulated time so far (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken so far.
    pub fn step_count(&self) -> u64 {
        self.steps
    }

    /// Add a body; the definition is validated first and nothing changes on error.
    pub fn add_body(&mut self, def: &BodyDef) -> Result<BodyId, PhysicsError> {
        def.validate()?;
        self.queries.touch();
        self.check_speed(
            def.linear_velocity,
            def.angular_velocity,
            def.parts
                .iter()
                .map(|p| p.offset.length() + p.shape.bounding_radius())
                .fold(def.shape.bounding_radius(), Real::max),
        )?;
        let index = match self.bodies.free.pop() {
            Some(i) => i,
            None => {
                let i = u32::try_from(self.bodies.slots.len())
                    .map_err(|_| PhysicsError::Full(self.bodies.count))?;
                self.bodies.slots.push(Slot {
                    generation: 0,
                    body: None,
                });
                i
            }
        };
        let slot = &mut self.bodies.slots[index as usize];
        let id = BodyId {
            index,
            generation: slot.generation,
        };
        let body = Body::from_def(id, def);
        self.islands.unsettled |= body.is_created_asleep();
        self.broad_phase.insert(index, &body);
        self.bodies.note(&body, true);
        let slot = &mut self.bodies.slots[index as usize];
        slot.body = Some(body);
        self.bodies.count += 1;
        Ok(id)
    }

    /// Remove a body and every contact and joint it had; returns the removed body.
    pub fn remove_body(&mut self, id: BodyId) -> Result<Body, PhysicsError> {
        let mut removed = self.remove_bodies(&[id])?;
        Ok(removed.pop().expect("one id, one body"))
    }

    /// Remove several bodies and every contact and joint they had, all or none: each id must name a
    /// live body, once. One pass over the contacts and the broad phase however many go
    /// (removing them one at a time costs a pass each). Returns the bodies in the order given.
    pub fn remove_bodies(&mut self, ids: &[BodyId]) -> Result<Vec<Body>, PhysicsError> {
        self.queries.touch();
        // Flags set for the ids only (and cleared again), so a short list costs little.
        let mut gone = std::mem::take(&mut self.bodies.removing);
        gone.resize(self.bodies.slots.len(), false);
        let clear = |gone: &mut Vec<bool>| {
            for id in ids {
                if let Some(flag) = gone.get_mut(id.index as usize) {
                    *flag = false;
                }
            }
        };
        for &id in ids {
            let refused = if self.body(id).is_none() {
                Some(PhysicsError::UnknownBody(id))
            } else if std::mem::replace(&mut gone[id.index as usize], true) {
                Some(PhysicsError::ListedTwice(id))
            } else {
                None
            };
            if let Some(e) = refused {
                clear(&mut gone);
                self.bodies.removing = gone;
                return Err(e);
            }
        }
        let is_gone = |i: u32| gone[i as usize];
        // Whatever rested on these bodies must notice they are gone: woken, once their
        // contacts have left (and given their colours back, for the woken contacts to take).
        for c in self.contacts.awake.iter().chain(&self.contacts.sleeping) {
            if is_gone(c.a) && !is_gone(c.b) {
                self.islands.wake_queue.push(c.b);
            } else if is_gone(c.b) && !is_gone(c.a) {
                self.islands.wake_queue.push(c.a);
            }
        }
        let touches_gone = |c: &Contact| is_gone(c.a) || is_gone(c.b);
        self.contacts.sleeping.retain(|c| !touches_gone(c));
        let graph = &mut self.contacts.graph;
        self.contacts.awake.retain(|c| {
            let gone = touches_gone(c);
            if gone {
                graph.remove(c.colour, [c.a, c.b]);
            }
            !gone
        });
        self.wake_queued();
        self.remove_joints_of(&gone);
        clear(&mut gone);
        self.bodies.removing = gone;
        let mut removed = Vec::with_capacity(ids.len());
        let mut slots: Vec<u32> = ids.iter().map(|id| id.index).collect();
        slots.sort_unstable();
        self.broad_phase.remove(&slots);
        for &id in ids {
            let slot = &mut self.bodies.slots[id.index as usize];
            let body = slot.body.take().expect("checked above");
            // Bodies created asleep that it touched may no longer touch one another.
            self.islands.unsettled |= body.is_created_asleep();
            self.bodies.note(&body, false);
            let slot = &mut self.bodies.slots[id.index as usize];
            removed.push(body);
            slot.generation = slot.generation.wrapping_add(1);
            self.bodies.free.push(id.index);
        }
        self.bodies.count -= ids.len();
        Ok(removed)
    }

    /// The id of the live body in slot `index` with reuse count `generation`, if there is one
    /// (how a body named on the wire by its two numbers is found without a search).
    pub fn live_id(&self, index: u32, generation: u32) -> Option<BodyId> {
        let id = BodyId { index, generation };
        self.body(id).map(|_| id)
    }

    /// Refuse speeds beyond the World's speed cap: linear speed, and the rim speed |w| r of a
    /// body of bounding radius r. (The solver clamps speeds anyway; a velocity given at the
    /// API beyond the cap is a mistake worth naming.)
    fn check_speed(&self, v: Vec2, w: Real, radius: Real) -> Result<(), PhysicsError> {
        let limit = self.settings.max_linear_speed;
        let above = |field, value: Real| {
            (value > limit).then_some(PhysicsError::AboveLimit {
                field,
                value,
                setting: "Settings::max_linear_speed (m/s)",
                limit,
            })
        };
        match above("velocity (speed)", v.length())
            .or_else(|| above("angular_velocity (rim speed)", w.abs() * radius))
        {
            Some(error) => Err(error),
            None => Ok(()),
        }
    }

    /// Remove every body, joint and contact; settings, gravity and time are kept.
    pub fn clear(&mut self) {
        self.joints = Default::default();
        self.queries = Default::default();
        self.bodies.slots.clear();
        self.bodies.free.clear();
        self.bodies.count = 0;
        self.bodies.filtered = 0;
        self.bodies.flagged = 0;
        self.bodies.guarded = 0;
        self.bodies.asking = Asking::default();
        self.events = Default::default();
        self.broad_phase.clear();
        self.contacts.awake.clear();
        self.contacts.previous.clear();
        self.contacts.sleeping.clear();
        self.contacts.graph.clear();
    }

    /// The body with this id, if it is still in the world.
    pub fn body(&self, id: BodyId) -> Option<&Body> {
        self.bodies
            .slots
            .get(id.index as usize)
            .filter(|s| s.generation == id.generation)
            .and_then(|s| s.body.as_ref())
    }

    /// A body by id, woken (with its island) first: anything that pushes a body wakes it.
    fn body_mut(&mut self, id: BodyId) -> Result<&mut Body, PhysicsError> {
        if self.body(id).is_some_and(|b| !b.awake) {
            self.islands.wake_queue.push(id.index);
            self.wake_queued();
        }
        self.bodies
            .slots
            .get_mut(id.index as usize)
            .filter(|s| s.generation == id.generation)
            .and_then(|s| s.body.as_mut())
            .ok_or(PhysicsError::UnknownBody(id))
    }

    /// Every body, in slot order.
    pub fn bodies(&self) -> impl Iterator<Item = &Body> + '_ {
        self.bodies.slots.iter().filter_map(|s| s.body.as_ref())
    }

    /// Number of bodies.
    pub fn body_count(&self) -> usize {
        self.bodies.count
    }

    /// Number of dynamic bodies that are awake (the ones a step moves).
    pub fn awake_count(&self) -> usize {
        self.bodies().filter(|b| b.is_active()).count()
    }

    /// Wake every sleeping body.
    pub fn wake_all(&mut self) {
        let sleeping = self
            .bodies
            .slots
            .iter()
            .enumerate()
            .filter(|(_, s)| s.body.as_ref().is_some_and(|b| !b.awake));
        self.islands
            .wake_queue
            .extend(sleeping.map(|(i, _)| i as u32));
        self.wake_queued();
    }

    /// Add a force (N) through the centre of mass for the next step.
    pub fn apply_force(&mut self, id: BodyId, force: Vec2) -> Result<(), PhysicsError> {
        let centre = self.position_of(id)?;
        self.apply_force_at(id, force, centre)
    }

    /// Add a force (N) at a world point (m) for the next step: force plus torque r x F.
    pub fn apply_force_at(
        &mut self,
        id: BodyId,
        force: Vec2,
        point: Vec2,
    ) -> Result<(), PhysicsError> {
        finite_vec(["force.x", "force.y"], force)?;
        finite_vec(["point.x", "point.y"], point)?;
        let b = self.body_mut(id)?;
        b.force += force;
        b.torque += cross(point - b.position, force);
        Ok(())
    }

    /// Add a torque (N m) for the next step.
    pub fn apply_torque(&mut self, id: BodyId, torque: Real) -> Result<(), PhysicsError> {
        finite("torque", torque)?;
        let b = self.body_mut(id)?;
        b.torque += torque;
        Ok(())
    }

    /// Apply an impulse (N s) at the centre of mass now: v += P / m.
    pub fn apply_impulse(&mut self, id: BodyId, impulse: Vec2) -> Result<(), PhysicsError> {
        let centre = self.position_of(id)?;
        self.apply_impulse_at(id, impulse, centre)
    }

    /// A body's centre of mass (m), or `UnknownBody`.
    fn position_of(&self, id: BodyId) -> Result<Vec2, PhysicsError> {
        self.body(id)
            .map(|b| b.position)
            .ok_or(PhysicsError::UnknownBody(id))
    }

    /// Apply an impulse (N s) at a world point (m) now: v += P / m, w += (r x P) / I.
    pub fn apply_impulse_at(
        &mut self,
        id: BodyId,
        impulse: Vec2,
        point: Vec2,
    ) -> Result<(), PhysicsError> {
        finite_vec(["impulse.x", "impulse.y"], impulse)?;
        finite_vec(["point.x", "point.y"], point)?;
        let max_v = self.settings.max_linear_speed;
        let max_w = self.settings.max_rotation * 1e3;
        let b = self.body_mut(id)?;
        b.linear_velocity = clamp_speed(b.linear_velocity + b.inv_mass * impulse, max_v);
        let w = b.angular_velocity + b.inv_inertia * cross(point - b.position, impulse);
        b.angular_velocity = if w.is_finite() {
            w.clamp(-max_w, max_w)
        } else {
            0.0
        };
        Ok(())
    }

    /// Set a body's velocities (m/s, rad/s). Ignored for static bodies.
    pub fn set_velocity(
        &mut self,
        id: BodyId,
        linear: Vec2,
        angular: Real,
    ) -> Result<(), PhysicsError> {
        finite_vec(["velocity.x", "velocity.y"], linear)?;
        finite("angular_velocity", angular)?;
        let radius = self
            .body(id)
            .ok_or(PhysicsError::UnknownBody(id))?
            .bounding_radius;
        self.check_speed(linear, angular, radius)?;
        let b = self.body_mut(id)?;
        if !b.is_static() {
            b.linear_velocity = linear;
            b.angular_velocity = angular;
        }
        Ok(())
    }

    /// Aim a kinematic body at a pose to reach in `dt` seconds (Box2D's
    /// `b2Body_SetTargetTransform`): its velocities become those that carry its origin to
    /// `position` (m) and its angle to `angle` (rad, turning the shorter way) over a step of
    /// `dt`, and it keeps them until told otherwise. Refused, with nothing changed, for a body
    /// that is not kinematic, values that are not finite, `dt` not above zero, or speeds beyond
    /// `Settings::max_linear_speed`.
    pub fn set_target_transform(
        &mut self,
        id: BodyId,
        position: Vec2,
        angle: Real,
        dt: Real,
    ) -> Result<(), PhysicsError> {
        finite_vec(["position.x", "position.y"], position)?;
        finite("angle", angle)?;
        positive("dt", dt)?;
        let b = self.body(id).ok_or(PhysicsError::UnknownBody(id))?;
        if !b.kinematic {
            return Err(PhysicsError::NotKinematic(id));
        }
        // The centre (its origin unless it has parts) goes where the target puts it; the turn
        // is the target's rotation relative to the current one, within (-pi, pi].
        let target = Rot::from_angle(angle);
        let centre = position + target.rotate(b.local_center());
        let q = b.rot;
        let turn = (target.s * q.c - target.c * q.s).atan2(target.c * q.c + target.s * q.s);
        self.set_velocity(id, (centre - b.center_of_mass()) / dt, turn / dt)
    }

    /// Set a body's collision filter (its own shape's, for a body of several). Its island wakes; from the next step, its contacts with
    /// bodies the filter now refuses end and new ones begin where it now allows them.
    pub fn set_filter(&mut self, id: BodyId, filter: Filter) -> Result<(), PhysicsError> {
        let b = self.body_mut(id)?;
        let was = b.filter();
        b.set_filter(filter);
        self.bodies.filtered += usize::from(filter != Filter::DEFAULT);
        self.bodies.filtered -= usize::from(was != Filter::DEFAULT);
        Ok(())
    }

    /// Number of contacts (touching or speculative pairs), sleeping ones included.
    pub fn contact_count(&self) -> usize {
        self.contacts.awake.len() + self.contacts.sleeping.len()
    }

    /// The contacts found in the last step, with the impulses the solver applied.
    pub fn contacts(&self) -> impl Iterator<Item = ContactInfo> + '_ {
        self.contacts
            .awake
            .iter()
            .chain(&self.contacts.sleeping)
            .map(move |c| {
                let id = |i: u32| BodyId {
                    index: i,
                    generation: self.bodies.slots[i as usize].generation,
                };
                let mut points = [ContactPointInfo {
                    point: Vec2::ZERO,
                    separation: 0.0,
                    normal_impulse: 0.0,
                    tangent_impulse: 0.0,
                }; 2];
                for (out, p) in points.iter_mut().zip(c.live()) {
                    *out = ContactPointInfo {
                        point: p.point,
                        separation: p.separation,
                        normal_impulse: p.total_normal_impulse,
                        tangent_impulse: p.tangent_impulse,
                    };
                }
                ContactInfo {
                    body_a: id(c.a),
                    body_b: id(c.b),
                    shape_a: (c.shapes >> 16) as usize,
                    shape_b: (c.shapes & 0xffff) as usize,
                    normal: c.normal,
                    points,
                    count: c.count as usize,
                }
            })
    }

    /// Total kinetic energy (J).
    pub fn kinetic_energy(&self) -> Real {
        self.bodies().map(Body::kinetic_energy).sum()
    }

    /// Total potential energy in the current gravity field, relative to the origin (J).
    pub fn potential_energy(&self) -> Real {
        self.bodies()
            .filter(|b| b.inv_mass > 0.0)
            .map(|b| -b.mass * self.gravity.dot(b.position))
            .sum()
    }
}
