//! The World's full state as plain data: what a checkpoint stores and what a restarted daemon
//! loads, so that stepping the restored World gives bit-identical results to stepping the one
//! it was taken from.
//!
//! Everything that carries over from one step to the next is here: every slot (generation and
//! body, forces and sleep state included), the free list, time and step count, settings and
//! gravity, in the open; and the solver's history, which nothing can recompute, as one record
//! with a version of its own ([`SolverHistory`]): the persistent contacts (awake and sleeping)
//! with their warm-start impulses, their colours in the constraint graph, the loads and spring
//! frequencies adaptive stiffness holds, and what contact recycling reuses. A change to what a
//! solver heuristic keeps changes that record and its version (and, postcard being
//! positional, the checkpoint file's version with it); the rest keeps its shape. The broad phase
//! and the graph's per-body masks are rebuilt (the broad phase's output is sorted, so its
//! internal order does not change what a step computes); per-step scratch and the contacts'
//! per-step constraints are not stored.
//!
//! A child module of `world`, so it reads the World's private fields without widening their
//! visibility: the state's shape, its export, and its checked import (every field validated
//! before anything is replaced).

use super::super::body::Extras;
use super::super::body::{Body, BodyId};
use super::super::contact::{Contact, ContactPoint};
use super::super::error::PhysicsError;
use super::super::events::ShapeFlags;
use super::super::filter::Filter;
use super::super::hash::Fnv1a;
use super::super::joint::{JointDef, JointImpulses};
use super::super::math::{Real, Rot, Transform, Vec2};
use super::super::part::{Part, PartDef, Parts};
use super::super::settings::Settings;
use super::super::shape::Shape;
use super::super::solver::graph::{ConstraintGraph, OVERFLOW, UNCOLOURED};
use super::joints::{graph_ends, joint_is_awake};
use super::{Slot, World};
use serde::{Deserialize, Serialize};

/// Why a [`WorldState`] cannot become a World.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid world state: {0}")]
pub struct StateError(pub String);

/// One body exactly as the World holds it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyState {
    /// Shape, in body coordinates (m). A polygon is re-checked when read back.
    pub shape: Shape,
    /// Centre of mass (m).
    pub position: [Real; 2],
    /// Accumulated angle (rad).
    pub angle: Real,
    /// The rotation as stored (cos, sin): kept, not recomputed, so it stays bit-identical.
    pub rot: [Real; 2],
    /// Linear velocity (m/s).
    pub linear_velocity: [Real; 2],
    /// Angular velocity (rad/s).
    pub angular_velocity: Real,
    /// Force accumulated for the next step (N).
    pub force: [Real; 2],
    /// Torque accumulated for the next step (N m).
    pub torque: Real,
    /// Mass, inverse mass, inertia, inverse inertia.
    pub mass: [Real; 4],
    /// Friction.
    pub friction: Real,
    /// Restitution.
    pub restitution: Real,
    /// Awake.
    pub awake: bool,
    /// Time spent below the sleep threshold (s).
    pub sleep_time: Real,
    /// Island it sleeps with.
    pub sleep_island: u32,
    /// Kinematic (moved by its velocity only). Appended: checkpoint format version 4 on.
    pub kinematic: bool,
    /// Collision filter. Appended: checkpoint format version 10 on.
    pub filter: Filter,
    /// Further shapes, as given (their densities the share of a body given by mass).
    /// Appended, with the next two: checkpoint format version 11 on.
    pub parts: Vec<PartDef>,
    /// The centre of mass in the body's frame from its origin (m); zero with no parts.
    pub local_center: [Real; 2],
    /// The density of the body's own shape (kg/m^2) when it has parts.
    pub own_density: Real,
    /// What its own shape reports, and whether it is a sensor. Appended: checkpoint format
    /// version 13 on.
    pub flags: ShapeFlags,
}

/// A slot: its generation and its body, if live.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SlotState {
    /// Generation.
    pub generation: u32,
    /// The body.
    pub body: Option<BodyState>,
}

/// The version of [`SolverHistory`] this build writes and reads. 1: contacts with their
/// impulses, colours, held loads, spring frequencies, ages and recycling frames. 2: contacts
/// say which shapes touch. 3: joints' colours.
pub const SOLVER_HISTORY_VERSION: u32 = 3;

/// The solver's history: what it carries from step to step and cannot work out again. Opaque
/// to callers: written by [`World::export_state`], read back by [`World::import_state`], which
/// refuses another version.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolverHistory {
    /// [`SOLVER_HISTORY_VERSION`] of the build that wrote it.
    pub version: u32,
    /// Awake contacts, sorted by key.
    contacts: Vec<ContactRecord>,
    /// Sleeping contacts, in the World's order.
    sleeping: Vec<ContactRecord>,
    /// Each joint slot's colour in the constraint graph (`UNCOLOURED` for an empty slot, a
    /// sleeping joint, or one not yet stepped). Version 3 on.
    joint_colours: Vec<u8>,
}

/// One contact point with its solver state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct PointRecord {
    /// Feature id.
    id: u16,
    /// point.x, point.y, separation, anchor_a.x, anchor_a.y, anchor_b.x, anchor_b.y.
    geometry: [Real; 7],
    /// normal, tangent and total normal impulse (N s).
    impulses: [Real; 3],
    /// Sequential solver: the approach velocity of a speculative point that closed its gap
    /// (m/s).
    approach_velocity: Real,
    /// Contact recycling: local_a.x, local_a.y, local_b.x, local_b.y, base separation.
    recycle: [Real; 5],
}

/// A persistent contact.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct ContactRecord {
    /// Pair key; slots of A and B.
    key: u64,
    a: u32,
    b: u32,
    normal: [Real; 2],
    /// Mixed friction and restitution.
    friction: Real,
    restitution: Real,
    touches_static: bool,
    /// The live points (1 or 2).
    points: Vec<PointRecord>,
    /// Spring frequency last step (Hz), held load (N), last step's force (N), age (steps).
    hertz: Real,
    load: Real,
    force: Real,
    age: u8,
    /// Colour in the constraint graph (`UNCOLOURED` while asleep).
    colour: u8,
    /// Contact recycling: the normal in A's frame and B's rotation relative to A's (cos, sin)
    /// when the manifold was computed.
    recycle: [Real; 4],
    /// Which shapes touch (A's index in the high 16 bits, B's in the low). Solver history
    /// version 2 on.
    shapes: u32,
}

/// Everything a World carries from one step to the next.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorldState {
    /// Settings.
    pub settings: Settings,
    /// Gravity (m/s^2).
    pub gravity: [Real; 2],
    /// Every slot in index order.
    pub slots: Vec<SlotState>,
    /// Free slots, in the order they will be reused (last first).
    pub free: Vec<u32>,
    /// Simulated time (s).
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    /// The solver's history.
    pub solver: SolverHistory,
    /// Every joint slot in index order. Appended: checkpoint format version 10 on.
    pub joints: Vec<JointSlotState>,
    /// Free joint slots, in the order they will be reused (last first).
    pub joint_free: Vec<u32>,
}

/// A joint slot: its generation and its joint, if live.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointSlotState {
    /// Generation.
    pub generation: u32,
    /// The joint's definition (reference angle and length worked out) and the impulses it
    /// carries to the next step.
    pub joint: Option<(JointDef, JointImpulses)>,
}

fn v2(v: Vec2) -> [Real; 2] {
    [v.x, v.y]
}
fn vec(a: [Real; 2]) -> Vec2 {
    Vec2::new(a[0], a[1])
}

impl ContactRecord {
    fn of(c: &Contact) -> ContactRecord {
        let points = c
            .live()
            .iter()
            .map(|p| PointRecord {
                id: p.id,
                geometry: [
                    p.point.x,
                    p.point.y,
                    p.separation,
                    p.anchor_a.x,
                    p.anchor_a.y,
                    p.anchor_b.x,
                    p.anchor_b.y,
                ],
                impulses: [p.normal_impulse, p.tangent_impulse, p.total_normal_impulse],
                approach_velocity: p.approach_velocity,
                recycle: [
                    p.local_a.x,
                    p.local_a.y,
                    p.local_b.x,
                    p.local_b.y,
                    p.base_separation,
                ],
            })
            .collect();
        ContactRecord {
            key: c.key,
            a: c.a,
            b: c.b,
            shapes: c.shapes,
            normal: v2(c.normal),
            friction: c.friction,
            restitution: c.restitution,
            touches_static: c.touches_static,
            points,
            hertz: c.hertz,
            load: c.load,
            force: c.force,
            age: c.age,
            colour: c.colour,
            recycle: [
                c.local_normal.x,
                c.local_normal.y,
                c.base_rotation.c,
                c.base_rotation.s,
            ],
        }
    }

    /// The contact, checked against the `slots` it joins: two live bodies in order, its key,
    /// one or two points, finite numbers.
    fn contact(&self, slots: &[Slot]) -> Result<Contact, StateError> {
        let s = self;
        let live = |i: u32| slots.get(i as usize).is_some_and(|s| s.body.is_some());
        if !(s.a < s.b && live(s.a) && live(s.b)) {
            return Err(StateError(format!(
                "contact {:#x} joins slots {} and {}, not two live bodies in order",
                s.key, s.a, s.b
            )));
        }
        if s.key != (u64::from(s.a) << 32 | u64::from(s.b)) {
            return Err(StateError(format!(
                "contact key {:#x} does not match its bodies",
                s.key
            )));
        }
        if s.points.is_empty() || s.points.len() > 2 {
            return Err(StateError(format!(
                "contact {:#x} has {} points",
                s.key,
                s.points.len()
            )));
        }
        let numbers = [
            s.normal[0],
            s.normal[1],
            s.friction,
            s.restitution,
            s.hertz,
            s.load,
            s.force,
        ];
        finite_all("contact", &numbers)?;
        finite_all("contact recycling", &s.recycle)?;
        materials(&format!("contact {:#x}", s.key), s.friction, s.restitution)?;
        let length = (s.normal[0] * s.normal[0] + s.normal[1] * s.normal[1]).sqrt();
        if (length - 1.0).abs() > 1e-3 {
            return Err(StateError(format!(
                "contact {:#x}: normal of length {length}, not a unit vector",
                s.key
            )));
        }
        let mut points = [ContactPoint::default(); 2];
        for (out, p) in points.iter_mut().zip(&s.points) {
            *out = p.point()?;
        }
        let shapes = [(s.a, s.shapes >> 16), (s.b, s.shapes & 0xffff)];
        if shapes.iter().any(|&(i, k)| shape_of(slots, i, k).is_none()) {
            return Err(StateError(format!(
                "contact {:#x} names shapes {:#x} its bodies do not have",
                s.key, s.shapes
            )));
        }
        Ok(Contact {
            key: s.key,
            a: s.a,
            b: s.b,
            shapes: s.shapes,
            normal: vec(s.normal),
            friction: s.friction,
            restitution: s.restitution,
            touches_static: s.touches_static,
            // The shapes' own: worked out again, not stored.
            rounding: [(s.a, s.shapes >> 16), (s.b, s.shapes & 0xffff)]
                .map(|(i, shape)| shape_of(slots, i, shape).map_or(0.0, Shape::rounding)),
            points,
            count: s.points.len() as u8,
            hertz: s.hertz,
            load: s.load,
            force: s.force,
            age: s.age,
            colour: s.colour,
            local_normal: Vec2::new(s.recycle[0], s.recycle[1]),
            base_rotation: Rot {
                c: s.recycle[2],
                s: s.recycle[3],
            },
        })
    }
}

impl PointRecord {
    /// The point, its numbers checked finite.
    // `..ContactPoint::default()` is deliberate: a field added to ContactPoint later starts
    // from its default here instead of breaking the build.
    #[allow(clippy::needless_update)]
    fn point(&self) -> Result<ContactPoint, StateError> {
        let p = self;
        finite_all("contact point", &p.geometry)?;
        finite_all("contact point", &p.impulses)?;
        finite_all("contact point", &[p.approach_velocity])?;
        finite_all("contact point", &p.recycle)?;
        let g = &p.geometry;
        Ok(ContactPoint {
            id: p.id,
            point: Vec2::new(g[0], g[1]),
            separation: g[2],
            anchor_a: Vec2::new(g[3], g[4]),
            anchor_b: Vec2::new(g[5], g[6]),
            normal_impulse: p.impulses[0],
            tangent_impulse: p.impulses[1],
            total_normal_impulse: p.impulses[2],
            approach_velocity: p.approach_velocity,
            local_a: Vec2::new(p.recycle[0], p.recycle[1]),
            local_b: Vec2::new(p.recycle[2], p.recycle[3]),
            base_separation: p.recycle[4],
            ..ContactPoint::default()
        })
    }
}

/// Mass, inverse mass, inertia and inverse inertia as a body can have them: both inverses
/// finite and not negative; a dynamic body (inverse mass > 0) has finite positive mass and
/// inertia and a positive inverse inertia; a static or kinematic one (inverse mass 0) has an
/// inverse inertia of 0 too.
fn masses_usable([m, inv_m, i, inv_i]: [Real; 4]) -> bool {
    let inverses = inv_m.is_finite() && inv_i.is_finite() && inv_m >= 0.0 && inv_i >= 0.0;
    let dynamic = m.is_finite() && m > 0.0 && i.is_finite() && i > 0.0 && inv_i > 0.0;
    inverses && if inv_m > 0.0 { dynamic } else { inv_i == 0.0 }
}

/// Friction within [0, `MAX_FRICTION`] and restitution within [0, 1], as a body definition
/// must have them (mixed contact values stay within them too).
fn materials(what: &str, friction: Real, restitution: Real) -> Result<(), StateError> {
    let max = crate::physics::body::MAX_FRICTION;
    if (0.0..=max).contains(&friction) && (0.0..=1.0).contains(&restitution) {
        Ok(())
    } else {
        Err(StateError(format!(
            "{what}: friction {friction} or restitution {restitution} out of range \
             (friction within [0, {max}], restitution within [0, 1])"
        )))
    }
}

/// Shape `k` of the body in slot `i` (0 its own, or the first of its parts), if it has one.
fn shape_of(slots: &[Slot], i: u32, k: u32) -> Option<&Shape> {
    let body = slots.get(i as usize)?.body.as_ref()?;
    match body.compound() {
        None => (k == 0).then_some(&body.shape),
        Some(p) => p.all.get(k as usize).map(|part| &part.shape),
    }
}

fn finite_all(what: &str, values: &[Real]) -> Result<(), StateError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(StateError(format!("{what}: a value is not finite")))
    }
}

impl BodyState {
    fn of(b: &Body) -> BodyState {
        BodyState {
            shape: b.shape.clone(),
            position: v2(b.position),
            angle: b.angle,
            rot: b.rot.to_cos_sin(),
            linear_velocity: v2(b.linear_velocity),
            angular_velocity: b.angular_velocity,
            force: v2(b.force),
            torque: b.torque,
            mass: [b.mass, b.inv_mass, b.inertia, b.inv_inertia],
            friction: b.friction,
            restitution: b.restitution,
            awake: b.awake,
            sleep_time: b.sleep_time,
            sleep_island: b.sleep_island,
            kinematic: b.kinematic,
            filter: b.filter(),
            parts: b.parts().to_vec(),
            local_center: v2(b.local_center()),
            own_density: b.compound().map_or(1.0, |p| p.own_density),
            flags: b.flags(),
        }
    }

    /// The body's parts, each checked, placed around its stored centre of mass.
    fn parts(&self, index: u32, shape: &Shape) -> Result<Option<Parts>, StateError> {
        if self.parts.is_empty() {
            return Ok(None);
        }
        let bad = |e: String| StateError(format!("body {index}: {e}"));
        for (i, p) in self.parts.iter().enumerate() {
            p.validate().map_err(|e| bad(format!("parts[{i}].{e}")))?;
        }
        finite_all(
            &format!("body {index}"),
            &[self.local_center[0], self.local_center[1], self.own_density],
        )?;
        let own = Part {
            shape: shape.clone(),
            pose: Transform {
                p: Vec2::ZERO,
                q: Rot::IDENTITY,
            },
            friction: self.friction,
            restitution: self.restitution,
            filter: self.filter,
            flags: self.flags,
        };
        let mut parts = Parts::new(own, &self.parts, vec(self.local_center));
        parts.own_density = self.own_density;
        Ok(Some(parts))
    }

    /// The body in slot `id`, checked: a valid shape, finite numbers, masses not negative, an
    /// island among the `slots` slots.
    fn body(&self, id: BodyId, slots: usize) -> Result<Body, StateError> {
        let b = self;
        let index = id.index;
        let shape = b.shape.clone();
        shape.validate().map_err(|e| StateError(e.to_string()))?;
        let mut all = vec![
            b.angle,
            b.angular_velocity,
            b.torque,
            b.friction,
            b.restitution,
            b.sleep_time,
        ];
        for pair in [b.position, b.rot, b.linear_velocity, b.force] {
            all.extend_from_slice(&pair);
        }
        finite_all(&format!("body {index}"), &all)?;
        materials(&format!("body {index}"), b.friction, b.restitution)?;
        if !masses_usable(b.mass) || b.sleep_island as usize >= slots {
            return Err(StateError(format!(
                "body {index}: mass or island out of range"
            )));
        }
        let parts = self.parts(index, &shape)?;
        Ok(Body {
            id,
            bounding_radius: parts
                .as_ref()
                .map_or_else(|| shape.bounding_radius(), |p| p.bounding_radius()),
            min_extent: parts
                .as_ref()
                .map_or_else(|| shape.min_extent(), |p| p.min_extent()),
            has_parts: parts.is_some(),
            extras: Extras::boxed(b.filter, b.flags, parts),
            shape,
            position: vec(b.position),
            angle: b.angle,
            rot: Rot::from_cos_sin(b.rot),
            linear_velocity: vec(b.linear_velocity),
            angular_velocity: b.angular_velocity,
            force: vec(b.force),
            torque: b.torque,
            mass: b.mass[0],
            inv_mass: b.mass[1],
            inertia: b.mass[2],
            inv_inertia: b.mass[3],
            friction: b.friction,
            restitution: b.restitution,
            awake: b.awake,
            sleep_time: b.sleep_time,
            sleep_island: b.sleep_island,
            kinematic: b.kinematic && b.mass[1] == 0.0,
        })
    }
}

impl World {
    /// The words that define the World's motion, as raw bits: gravity, then per body its id,
    /// position, angle, velocities and whether it is awake. Two Worlds with equal words step
    /// identically from here on only if their contacts match too; replay and checkpoint tests
    /// compare these (or a hash of them) frame by frame.
    pub fn state_bits(&self) -> impl Iterator<Item = u64> + '_ {
        let g = self.gravity;
        [g.x.to_bits() as u64, g.y.to_bits() as u64]
            .into_iter()
            .chain(self.bodies().flat_map(|b| {
                let id = b.id();
                let (p, v) = (b.position(), b.linear_velocity());
                [
                    u64::from(id.index) << 32 | u64::from(id.generation),
                    p.x.to_bits() as u64,
                    p.y.to_bits() as u64,
                    b.angle().to_bits() as u64,
                    v.x.to_bits() as u64,
                    v.y.to_bits() as u64,
                    b.angular_velocity().to_bits() as u64,
                    u64::from(b.is_awake()),
                ]
            }))
    }

    /// FNV-1a hash of [`World::state_bits`]: one number per frame for replay checks.
    pub fn state_hash(&self) -> u64 {
        let mut h = Fnv1a::new();
        for word in self.state_bits() {
            h.write(&word.to_le_bytes());
        }
        h.finish()
    }

    /// The full state: what [`World::import_state`] needs to continue bit-identically.
    pub fn export_state(&self) -> WorldState {
        let slots = self.bodies.slots.iter().map(|s| SlotState {
            generation: s.generation,
            body: s.body.as_ref().map(BodyState::of),
        });
        WorldState {
            settings: self.settings.clone(),
            gravity: v2(self.gravity),
            slots: slots.collect(),
            free: self.bodies.free.clone(),
            time: self.time,
            steps: self.steps,
            joints: self.export_joints(),
            joint_free: self.joints.free.clone(),
            solver: SolverHistory {
                version: SOLVER_HISTORY_VERSION,
                contacts: self.contacts.awake.iter().map(ContactRecord::of).collect(),
                sleeping: self
                    .contacts
                    .sleeping
                    .iter()
                    .map(ContactRecord::of)
                    .collect(),
                joint_colours: self
                    .joints
                    .slots
                    .iter()
                    .map(|s| s.joint.as_ref().map_or(UNCOLOURED, |j| j.colour))
                    .collect(),
            },
        }
    }

    /// A World from a state taken by [`World::export_state`] (possibly read from a file):
    /// everything is validated (finite numbers, consistent slots, free list and contacts, the
    /// solver history's version) and refused with the reason otherwise.
    pub fn import_state(state: &WorldState) -> Result<World, StateError> {
        let err = |e: PhysicsError| StateError(e.to_string());
        let mut world = World::new(state.settings.clone(), vec(state.gravity)).map_err(err)?;
        world.import_slots(state)?;
        // Their islands drawn again, as the exporting World drew them.
        let created_asleep = world.bodies().any(Body::is_created_asleep);
        world.islands.unsettled = created_asleep;
        if !state.time.is_finite() || state.time < 0.0 {
            return Err(StateError(format!("time = {}", state.time)));
        }
        world.time = state.time;
        world.steps = state.steps;
        world.import_contacts(&state.solver)?;
        world.import_joints(&state.joints, &state.joint_free)?;
        world.import_joint_colours(&state.solver.joint_colours)?;
        Ok(world)
    }

    /// The slots and the free list of `state`, checked against each other.
    fn import_slots(&mut self, state: &WorldState) -> Result<(), StateError> {
        if state.slots.len() > u32::MAX as usize {
            return Err(StateError("too many slots".into()));
        }
        let mut free_seen = vec![false; state.slots.len()];
        for &i in &state.free {
            match state.slots.get(i as usize) {
                Some(s) if s.body.is_none() && !free_seen[i as usize] => {
                    free_seen[i as usize] = true
                }
                _ => {
                    return Err(StateError(format!(
                        "free list names slot {i}, which is not a free slot"
                    )))
                }
            }
        }
        for (index, s) in state.slots.iter().enumerate() {
            let id = BodyId {
                index: index as u32,
                generation: s.generation,
            };
            let body = match &s.body {
                None if !free_seen[index] => {
                    return Err(StateError(format!(
                        "slot {index} is empty but not in the free list"
                    )))
                }
                None => None,
                Some(b) => Some(b.body(id, state.slots.len())?),
            };
            if let Some(b) = &body {
                self.broad_phase.insert(id.index, b);
                self.bodies.count += 1;
                self.bodies.note(b, true);
            }
            self.bodies.slots.push(Slot {
                generation: s.generation,
                body,
            });
        }
        self.bodies.free = state.free.clone();
        Ok(())
    }

    /// The contacts of `history`, checked, with the constraint graph rebuilt from the awake
    /// contacts' colours (each colour free on the dynamic bodies it joins).
    fn import_contacts(&mut self, history: &SolverHistory) -> Result<(), StateError> {
        if history.version != SOLVER_HISTORY_VERSION {
            return Err(StateError(format!(
                "solver history version {}, this build reads version {SOLVER_HISTORY_VERSION}",
                history.version
            )));
        }
        let slots = &self.bodies.slots;
        let dynamic = |i: u32| {
            slots[i as usize]
                .body
                .as_ref()
                .is_some_and(|b| b.inv_mass > 0.0)
        };
        let mut graph = ConstraintGraph::default();
        for record in &history.contacts {
            let c = record.contact(slots)?;
            let pair = [c.a, c.b];
            if c.colour > OVERFLOW || !graph.restore(c.colour, pair, pair.map(dynamic)) {
                return Err(StateError(format!(
                    "contact {:#x} has colour {}, which its bodies cannot take",
                    c.key, c.colour
                )));
            }
            self.contacts.awake.push(c);
        }
        if !self
            .contacts
            .awake
            .windows(2)
            .all(|w| w[0].order() < w[1].order())
        {
            return Err(StateError("contacts are not sorted by key".into()));
        }
        let awake_body = |i: u32| slots[i as usize].body.as_ref().is_some_and(Body::is_active);
        let mut keys: Vec<(u64, u32)> = self.contacts.awake.iter().map(|c| c.order()).collect();
        for record in &history.sleeping {
            let c = record.contact(slots)?;
            let refused = if c.colour != UNCOLOURED {
                Some("has a colour")
            } else if awake_body(c.a) || awake_body(c.b) {
                Some("joins an awake body")
            } else {
                None
            };
            if let Some(why) = refused {
                return Err(StateError(format!("sleeping contact {:#x} {why}", c.key)));
            }
            keys.push(c.order());
            self.contacts.sleeping.push(c);
        }
        keys.sort_unstable();
        if let Some(w) = keys.windows(2).find(|w| w[0] == w[1]) {
            return Err(StateError(format!(
                "contact {:#x} (shapes {:#x}) is listed twice",
                w[0].0, w[0].1
            )));
        }
        self.contacts.graph = graph;
        Ok(())
    }

    /// The joints' colours, one per joint slot, put back into the constraint graph: a joint
    /// with an awake body may have one (free on its dynamic bodies), any other none.
    fn import_joint_colours(&mut self, colours: &[u8]) -> Result<(), StateError> {
        if colours.len() != self.joints.slots.len() {
            return Err(StateError(format!(
                "{} joint colours for {} joint slots",
                colours.len(),
                self.joints.slots.len()
            )));
        }
        let (slots, graph) = (&self.bodies.slots, &mut self.contacts.graph);
        for (index, (s, &colour)) in self.joints.slots.iter_mut().zip(colours).enumerate() {
            if colour == UNCOLOURED {
                continue;
            }
            let refused = match &mut s.joint {
                None => true,
                Some(j) => {
                    let (ends, dynamic) = graph_ends(&j.def, slots);
                    j.colour = colour;
                    !joint_is_awake(&j.def, slots)
                        || colour > OVERFLOW
                        || !graph.restore(colour, ends, dynamic)
                }
            };
            if refused {
                return Err(StateError(format!(
                    "joint slot {index} has colour {colour}, which it cannot take"
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::body::BodyDef;
    use super::super::super::math::Vec2;
    use super::super::super::shape::Shape;
    use super::super::World;
    use super::WorldState;

    fn bits(w: &World) -> Vec<u64> {
        w.state_bits().collect()
    }

    #[test]
    fn an_imported_world_steps_bit_identically() {
        let mut w = World::default();
        w.add_body(&BodyDef::fixed(
            Shape::rect(20.0, 1.0),
            Vec2::new(0.0, -0.5),
        ))
        .unwrap();
        let mut ids = Vec::new();
        for i in 0..12 {
            let x = (i % 4) as f32 * 1.1 - 1.5;
            let y = 0.5 + (i / 4) as f32 * 1.05;
            ids.push(
                w.add_body(&BodyDef::dynamic(
                    Shape::rect(1.0, 1.0),
                    Vec2::new(x as _, y as _),
                ))
                .unwrap(),
            );
        }
        w.remove_body(ids[5]).unwrap();
        for _ in 0..90 {
            w.step(1.0 / 60.0).unwrap();
        }
        assert!(w.contact_count() > 0);
        let state = w.export_state();
        let mut copy = World::import_state(&state).unwrap();
        assert_eq!(copy.export_state(), state);
        for frame in 0..240 {
            if frame == 100 {
                w.set_gravity(Vec2::new(3.0, -9.81)).unwrap();
                copy.set_gravity(Vec2::new(3.0, -9.81)).unwrap();
            }
            w.step(1.0 / 60.0).unwrap();
            copy.step(1.0 / 60.0).unwrap();
            assert_eq!(bits(&w), bits(&copy), "frame {frame}");
        }
        // a reused slot keeps its generation
        let id = w
            .add_body(&BodyDef::dynamic(
                Shape::rect(1.0, 1.0),
                Vec2::new(0.0, 9.0),
            ))
            .unwrap();
        let id2 = copy
            .add_body(&BodyDef::dynamic(
                Shape::rect(1.0, 1.0),
                Vec2::new(0.0, 9.0),
            ))
            .unwrap();
        assert_eq!(id, id2);
        assert_eq!(id.generation, 1);
    }

    #[test]
    fn inconsistent_states_are_refused() {
        let mut w = World::default();
        let a = w
            .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), Vec2::ZERO))
            .unwrap();
        w.add_body(&BodyDef::dynamic(
            Shape::rect(1.0, 1.0),
            Vec2::new(3.0, 0.0),
        ))
        .unwrap();
        w.remove_body(a).unwrap();
        let good = w.export_state();
        let mut s = good.clone();
        s.free.clear();
        assert!(World::import_state(&s).is_err());
        let mut s = good.clone();
        s.slots[1].body.as_mut().unwrap().position[0] = f32::NAN as _;
        assert!(World::import_state(&s).is_err());
        let mut s = good.clone();
        s.free.push(1);
        assert!(World::import_state(&s).is_err());
        assert!(World::import_state(&good).is_ok());
    }

    /// A pile settling in a box, checkpointed while contacts begin and end: 120 boxes, discs
    /// and capsules dropped in two waves with sleep on, one taken out and one thrown in after
    /// the checkpoint, so the restored World meets contacts that begin, end, fall asleep and
    /// wake. The resumed World's state hash equals the original's at every one of 1,000 frames
    /// (the colours, loads, spring frequencies and recycling frames it carries all matter: the
    /// graph's colours set the solve order).
    #[test]
    fn a_settling_pile_resumes_bit_identically_for_1000_frames() {
        use crate::physics::math::{vec2, Real};
        let mut w = World::default();
        for (w_, h, x, y) in [
            (12.0, 1.0, 0.0, -0.5),
            (1.0, 12.0, -6.5, 5.0),
            (1.0, 12.0, 6.5, 5.0),
        ] {
            w.add_body(&BodyDef::fixed(Shape::rect(w_, h), vec2(x, y)))
                .unwrap();
        }
        let spawn = |w: &mut World, i: usize, lift: Real| {
            let shape = match i % 3 {
                0 => Shape::rect(0.6, 0.4),
                1 => Shape::circle(0.3),
                _ => Shape::capsule(0.6, 0.15),
            };
            let (col, row) = ((i % 12) as Real, (i / 12) as Real);
            let at = vec2(-5.0 + 0.9 * col + 0.1 * row, 1.0 + lift + 0.8 * row);
            w.add_body(&BodyDef::dynamic(shape, at).with_angle(0.3 * i as Real))
                .unwrap()
        };
        let first: Vec<_> = (0..60).map(|i| spawn(&mut w, i, 0.0)).collect();
        for frame in 0..150 {
            if frame == 60 {
                for i in 60..120 {
                    spawn(&mut w, i, 6.0);
                }
            }
            w.step(1.0 / 60.0).unwrap();
        }
        let state = w.export_state();
        let mut copy = World::import_state(&state).unwrap();
        assert_eq!(copy.export_state(), state);
        let colours: std::collections::BTreeSet<u8> =
            w.contacts.awake.iter().map(|c| c.colour).collect();
        assert!(
            colours.len() > 4,
            "the graph is in use: colours {colours:?}"
        );
        let (mut begun, mut ended) = (0, 0);
        for frame in 0..1000 {
            let keys = |w: &World| {
                w.contacts
                    .awake
                    .iter()
                    .map(|c| c.key)
                    .collect::<std::collections::BTreeSet<_>>()
            };
            let before = keys(&w);
            for x in [&mut w, &mut copy] {
                match frame {
                    100 => drop(x.remove_body(first[30]).unwrap()),
                    400 => drop(spawn(x, 7, 8.0)),
                    _ => {}
                }
                x.step(1.0 / 60.0).unwrap();
            }
            let after = keys(&w);
            begun += after.difference(&before).count();
            ended += before.difference(&after).count();
            assert_eq!(
                w.state_hash(),
                copy.state_hash(),
                "frame {frame} after resuming"
            );
        }
        assert!(
            begun > 20 && ended > 20,
            "{begun} contacts began, {ended} ended"
        );
    }

    /// A solver history of another version, or a colour its bodies cannot take, is refused.
    #[test]
    fn a_foreign_solver_history_is_refused() {
        use crate::physics::math::{vec2, Real};
        let mut w = World::default();
        w.add_body(&BodyDef::fixed(Shape::rect(10.0, 1.0), vec2(0.0, -0.5)))
            .unwrap();
        for i in 0..3 {
            w.add_body(&BodyDef::dynamic(
                Shape::rect(1.0, 1.0),
                vec2(0.0, 0.5 + i as Real),
            ))
            .unwrap();
        }
        w.step(1.0 / 60.0).unwrap();
        let good = w.export_state();
        assert!(good.solver.contacts.len() >= 3);
        let mut s = good.clone();
        s.solver.version += 1;
        let e = World::import_state(&s).err().unwrap();
        assert!(e.to_string().contains("solver history version"), "{e}");
        // two contacts on the middle box in one colour
        let mut s = good.clone();
        let shared = s
            .solver
            .contacts
            .iter()
            .position(|c| c.a == 2 || c.b == 2)
            .unwrap();
        let colour = s.solver.contacts[shared].colour;
        for c in s
            .solver
            .contacts
            .iter_mut()
            .filter(|c| c.a == 2 || c.b == 2)
        {
            c.colour = colour;
        }
        let e = World::import_state(&s).err().unwrap();
        assert!(e.to_string().contains("colour"), "{e}");
        assert!(World::import_state(&good).is_ok());
    }

    /// What a damaged or hand-made checkpoint could hold that would make the step panic or
    /// go NaN is refused, naming it: a negative friction (the friction cone's clamp panics when
    /// its bounds cross), a restitution above 1, an infinite inverse mass, a contact normal
    /// that is not a unit vector, a sleeping contact on an awake body, a contact listed twice.
    #[test]
    fn states_the_step_cannot_run_are_refused() {
        use super::super::super::math::Real;
        use super::UNCOLOURED;
        use crate::physics::math::vec2;
        let mut w = World::default();
        w.add_body(&BodyDef::fixed(Shape::rect(10.0, 1.0), vec2(0.0, -0.5)))
            .unwrap();
        w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 0.5)))
            .unwrap();
        w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(3.0, 0.5)))
            .unwrap();
        w.step(1.0 / 60.0).unwrap();
        let good = w.export_state();
        assert!(!good.solver.contacts.is_empty());
        let refused = |s: &WorldState, what: &str| {
            let e = World::import_state(s).expect_err("refused");
            assert!(e.to_string().contains(what), "{e}");
        };
        let mut s = good.clone();
        s.slots[1].body.as_mut().unwrap().friction = -0.5;
        refused(&s, "friction -0.5");
        let mut s = good.clone();
        s.slots[1].body.as_mut().unwrap().restitution = 1.5;
        refused(&s, "restitution 1.5");
        let mut s = good.clone();
        s.slots[1].body.as_mut().unwrap().mass[1] = Real::INFINITY;
        refused(&s, "mass");
        let mut s = good.clone();
        s.solver.contacts[0].friction = -1.0;
        refused(&s, "friction -1");
        let mut s = good.clone();
        s.solver.contacts[0].normal = [0.0, 2.0];
        refused(&s, "unit vector");
        let mut s = good.clone();
        let mut asleep = s.solver.contacts[0].clone();
        asleep.colour = UNCOLOURED;
        s.solver.sleeping.push(asleep.clone());
        refused(&s, "joins an awake body");
        let mut s = good.clone();
        for slot in &mut s.slots {
            if let Some(b) = slot.body.as_mut() {
                b.awake = false;
            }
        }
        s.solver.sleeping.push(asleep);
        refused(&s, "listed twice");
        assert!(World::import_state(&good).is_ok());
    }
}
