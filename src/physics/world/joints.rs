//! The World's joints: adding, removing and reading them, and what a step does with them
//! (their constraints for the solvers, breaking). A World without joints skips all of it.

use super::snapshot::{JointSlotState, StateError};
use super::*;
use crate::physics::broad_phase::pair_key;
use crate::physics::joint::{Joint, JointDef, JointId, JointImpulses, JointKind};
use crate::physics::solver::graph::UNCOLOURED;
use crate::physics::solver::joint::{solve_rank, Frame, JointSet, JointSource, SHARED_JOINTS_FROM};
use crate::physics::solver::lanes::prefetch;
use crate::physics::team::{block, Region, SharedSlice};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::atomic::{AtomicBool, Ordering};

/// One entry of the joint array: a joint, or a free slot remembering its generation.
#[derive(Clone, Debug, Default)]
pub(super) struct JointSlot {
    pub generation: u32,
    pub joint: Option<Joint>,
}

/// The joints: a slot array with a free list, and the body pairs they keep from colliding.
#[derive(Clone, Debug, Default)]
pub(super) struct Joints {
    pub slots: Vec<JointSlot>,
    /// Free slots, reused last first.
    pub free: Vec<u32>,
    /// Live joints.
    pub count: usize,
    /// Per pair key of bodies joined by joints that keep them from colliding: how many.
    no_collide: HashMap<u64, u32, BuildHasherDefault<PairKeyHasher>>,
    /// This step's constraints, for the joints with an awake body.
    pub constraints: JointSet,
    /// Scratch: this step's awake joints as (solve rank, slot), sorted.
    order: Vec<(u8, u32)>,
    /// The awake joints' slots in solve order, worked out again only when `sorted_kept` is
    /// false: a joint was added or removed, or an island woke or fell asleep.
    sorted: Vec<u32>,
    pub sorted_kept: bool,
    /// The joints that broke in the last step, in id order.
    pub broken: Vec<JointId>,
    /// Their force (N) and torque (N m) in that step, in the same order.
    pub broken_loads: Vec<(Vec2, Real)>,
}

impl Joints {
    /// Whether any joint keeps its bodies from colliding.
    pub fn keeps_pairs_apart(&self) -> bool {
        !self.no_collide.is_empty()
    }

    /// Whether the bodies of pair `key` may collide: no joint between them says otherwise.
    #[inline]
    pub fn may_collide(&self, key: u64) -> bool {
        !self.no_collide.contains_key(&key)
    }
}

/// Hashes a pair key in one multiply: the map of pairs kept apart is read for candidate pairs
/// every step, and std's SipHash spent 6 % of rain's step there. The key's two slots are
/// folded, multiplied by 2^64 / phi and the high half folded back into the low bits, which
/// pick the map's bucket.
#[derive(Clone, Copy, Debug, Default)]
struct PairKeyHasher(u64);

impl Hasher for PairKeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(self.0 << 8 | u64::from(b));
        }
    }

    fn write_u64(&mut self, key: u64) {
        let h = (key ^ key >> 32).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        self.0 = h ^ h >> 29;
    }
}

/// The slots of `order` (solve rank, slot), in slot order, sorted by rank into `sorted`: a
/// counting sort, stable, so each rank keeps slot order (a comparison sort of joint_grid's
/// 19,794 joints took 5 % of its step).
fn by_rank(order: &[(u8, u32)], sorted: &mut Vec<u32>) {
    let mut start = [0usize; 256];
    for &(rank, _) in order {
        start[rank as usize] += 1;
    }
    let mut next = 0;
    for s in start.iter_mut() {
        (*s, next) = (next, next + *s);
    }
    sorted.clear();
    sorted.resize(order.len(), 0);
    for &(rank, slot) in order {
        sorted[start[rank as usize]] = slot;
        start[rank as usize] += 1;
    }
}

/// Whether either of a joint's bodies is awake and dynamic.
pub(super) fn joint_is_awake(def: &JointDef, slots: &[Slot]) -> bool {
    let active = |i: u32| slots[i as usize].body.as_ref().is_some_and(Body::is_active);
    active(def.body_b.index) || def.body_a.is_some_and(|a| active(a.index))
}

/// A joint's two ends as nodes of the constraint graph: the bodies' slots, and which are
/// dynamic (awake or asleep). The world's end (`body_a: None`) is B's slot again, not a node.
pub(super) fn graph_ends(def: &JointDef, slots: &[Slot]) -> ([u32; 2], [bool; 2]) {
    let dynamic = |i: u32| {
        slots[i as usize]
            .body
            .as_ref()
            .is_some_and(|b| b.inv_mass > 0.0)
    };
    let b = def.body_b.index;
    match def.body_a {
        Some(a) => ([a.index, b], [dynamic(a.index), dynamic(b)]),
        None => ([b, b], [false, dynamic(b)]),
    }
}

/// The world's end of a joint (`body_a: None`): the solver's fixed body, last.
fn solver_index(body: Option<BodyId>, fixed: u32) -> u32 {
    body.map_or(fixed, |id| id.index)
}

impl World {
    /// Add a joint. Refused, naming the field and the value, with nothing changed: an invalid
    /// definition ([`JointDef::validate`]), a body that is not in this World, the same body
    /// at both ends, or no dynamic body. A reference angle or distance left `None` is taken
    /// from the bodies as they are now. Both bodies wake.
    pub fn add_joint(&mut self, def: &JointDef) -> Result<JointId, PhysicsError> {
        let def = self.checked_joint(def)?;
        self.wake_joint_bodies(&def);
        Ok(self.insert_joint(def))
    }

    /// `def` validated against this World's bodies, its reference angle and length worked
    /// out.
    fn checked_joint(&self, def: &JointDef) -> Result<JointDef, PhysicsError> {
        def.validate()?;
        let b = self
            .body(def.body_b)
            .ok_or(PhysicsError::UnknownBody(def.body_b))?;
        let a = match def.body_a {
            Some(id) => Some(self.body(id).ok_or(PhysicsError::UnknownBody(id))?),
            None => None,
        };
        if b.inv_mass == 0.0 && a.map_or(true, |a| a.inv_mass == 0.0) {
            return Err(PhysicsError::NoDynamicBody(format!(
                "body_a ({}) and body_b ({}) are static or kinematic",
                def.body_a.map_or("the world".into(), |id| id.to_string()),
                def.body_b
            )));
        }
        Ok(resolved(def, a, b))
    }

    /// Put a checked joint in a free slot (or a new one).
    fn insert_joint(&mut self, def: JointDef) -> JointId {
        let index = self.joints.free.pop().unwrap_or_else(|| {
            self.joints.slots.push(JointSlot::default());
            self.joints.slots.len() as u32 - 1
        });
        let id = JointId {
            index,
            generation: self.joints.slots[index as usize].generation,
        };
        if !def.collide_connected {
            if let Some(a) = def.body_a {
                let key = pair_key(a.index, def.body_b.index);
                *self.joints.no_collide.entry(key).or_insert(0) += 1;
            }
        }
        self.joints.slots[index as usize].joint = Some(Joint {
            id,
            def,
            impulses: JointImpulses::default(),
            force: Vec2::ZERO,
            torque: 0.0,
            colour: UNCOLOURED,
        });
        self.joints.count += 1;
        self.joints.sorted_kept = false;
        id
    }

    /// Remove a joint; its bodies wake. Returns it.
    pub fn remove_joint(&mut self, id: JointId) -> Result<Joint, PhysicsError> {
        let slot = self
            .joints
            .slots
            .get_mut(id.index() as usize)
            .filter(|s| s.generation == id.generation() && s.joint.is_some())
            .ok_or(PhysicsError::UnknownJoint(id))?;
        let joint = slot.joint.take().expect("checked above");
        slot.generation = slot.generation.wrapping_add(1);
        let (ends, _) = graph_ends(&joint.def, &self.bodies.slots);
        self.contacts.graph.remove(joint.colour, ends);
        self.joints.free.push(id.index());
        self.joints.count -= 1;
        self.joints.sorted_kept = false;
        if !joint.def.collide_connected {
            if let Some(a) = joint.def.body_a {
                let key = pair_key(a.index, joint.def.body_b.index);
                let n = self
                    .joints
                    .no_collide
                    .get_mut(&key)
                    .expect("counted when added");
                *n -= 1;
                if *n == 0 {
                    self.joints.no_collide.remove(&key);
                }
            }
        }
        self.wake_joint_bodies(&joint.def);
        Ok(joint)
    }

    /// The joint with this id, if it is still in the World.
    pub fn joint(&self, id: JointId) -> Option<&Joint> {
        self.joints
            .slots
            .get(id.index() as usize)
            .filter(|s| s.generation == id.generation())
            .and_then(|s| s.joint.as_ref())
    }

    /// The id of the live joint in slot `index` with reuse count `generation`, if there is
    /// one (how a joint named on the wire by its two numbers is found without a search).
    pub fn live_joint_id(&self, index: u32, generation: u32) -> Option<JointId> {
        let id = JointId { index, generation };
        self.joint(id).map(|_| id)
    }

    /// Every joint, in slot order.
    pub fn joints(&self) -> impl Iterator<Item = &Joint> + '_ {
        self.joints.slots.iter().filter_map(|s| s.joint.as_ref())
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.joints.count
    }

    /// The joints that broke in the last step (their force or torque passed the break force
    /// or torque), in id order. They are gone from the World.
    pub fn broken_joints(&self) -> &[JointId] {
        &self.joints.broken
    }

    /// The force (N) and torque (N m) that broke each of [`World::broken_joints`], in the
    /// same order: the step's mean reaction, as [`Joint::reaction_force`] reads it.
    pub fn broken_joint_loads(&self) -> &[(Vec2, Real)] {
        &self.joints.broken_loads
    }

    /// Move a target joint's target (world point, m; held in A's frame when A is a body); its
    /// bodies wake.
    pub fn set_joint_target(&mut self, id: JointId, target: Vec2) -> Result<(), PhysicsError> {
        finite_vec(["target.x", "target.y"], target)?;
        let frame_a = match self.joint(id).and_then(|j| j.def.body_a) {
            Some(a) => self.body(a).map(Body::transform),
            None => None,
        };
        let def = self.joint_def_mut(id, "target", |k| matches!(k, JointKind::Target(_)))?;
        def.anchor_a = frame_a.map_or(target, |xf| xf.apply_inv(target));
        Ok(())
    }

    /// Set the speed of a joint's motor (rad/s, or m/s for a prismatic joint's); its bodies
    /// wake.
    pub fn set_motor_speed(&mut self, id: JointId, speed: Real) -> Result<(), PhysicsError> {
        finite("motor.speed", speed)?;
        let has_motor = |k: &JointKind| match k {
            JointKind::Revolute(r) => r.motor.is_some(),
            JointKind::Prismatic(p) => p.motor.is_some(),
            JointKind::Wheel(w) => w.motor.is_some(),
            _ => false,
        };
        let def = self.joint_def_mut(id, "motor", has_motor)?;
        let motor = match &mut def.kind {
            JointKind::Revolute(r) => r.motor.as_mut(),
            JointKind::Prismatic(p) => p.motor.as_mut(),
            JointKind::Wheel(w) => w.motor.as_mut(),
            _ => None,
        };
        motor.expect("checked above").speed = speed;
        Ok(())
    }

    /// A joint's definition to change, its bodies woken, if `fits` its kind (else an error
    /// saying it has no `what`).
    fn joint_def_mut(
        &mut self,
        id: JointId,
        what: &'static str,
        fits: impl Fn(&JointKind) -> bool,
    ) -> Result<&mut JointDef, PhysicsError> {
        let def = self
            .joint(id)
            .ok_or(PhysicsError::UnknownJoint(id))?
            .def
            .clone();
        if !fits(&def.kind) {
            return Err(PhysicsError::WrongJointKind {
                joint: id,
                kind: def.kind.name(),
                what,
            });
        }
        self.wake_joint_bodies(&def);
        let slot = &mut self.joints.slots[id.index() as usize];
        Ok(&mut slot.joint.as_mut().expect("checked above").def)
    }

    /// Wake both bodies of a joint (with their islands).
    fn wake_joint_bodies(&mut self, def: &JointDef) {
        let ids = def.body_a.into_iter().chain([def.body_b]);
        for id in ids {
            if self.body(id).is_some_and(|b| !b.awake) {
                self.islands.wake_queue.push(id.index);
            }
        }
        self.wake_queued();
    }

    /// Remove the joints of the bodies flagged in `gone` (their other bodies wake).
    pub(super) fn remove_joints_of(&mut self, gone: &[bool]) {
        if self.joints.count == 0 {
            return;
        }
        let doomed: Vec<JointId> = self
            .joints()
            .filter(|j| {
                let ends = j.def.body_a.into_iter().chain([j.def.body_b]);
                ends.into_iter().any(|id| gone[id.index as usize])
            })
            .map(|j| j.id)
            .collect();
        for id in doomed {
            self.remove_joint(id).expect("listed live");
        }
    }

    /// This step's constraints: one for each joint with an awake body, posed as the bodies
    /// are at the start of the step, carrying last step's impulses, in the solve order of
    /// their colours. A joint whose island woke (or new) takes its colour here, in slot order.
    #[inline(never)]
    pub(super) fn build_joint_constraints(&mut self, region: Option<&Region>) {
        if !self.joints.sorted_kept {
            self.sort_awake_joints();
        }
        let fixed = self.solver.bodies.len() as u32 - 1;
        let mut constraints = std::mem::take(&mut self.joints.constraints);
        let sorted = &self.joints.sorted;
        let source = |k: usize| {
            self.fetch_joint(k + JOINTS_AHEAD);
            let slot = sorted[k];
            let j = self.joints.slots[slot as usize].joint.as_ref();
            let j = j.expect("listed live");
            let d = &j.def;
            let a = d.body_a.and_then(|id| self.body(id));
            let b = self
                .body(d.body_b)
                .expect("joints of removed bodies are removed");
            JointSource {
                slot,
                ends: [solver_index(d.body_a, fixed), d.body_b.index],
                colour: j.colour,
                kind: &d.kind,
                length: rest_length(&d.kind),
                frame: frame(d, a, b),
                impulses: &j.impulses,
                force: j.force,
                hertz: d.constraint_hertz,
                zeta: d.constraint_damping_ratio,
            }
        };
        let from = self.solver.bundles.shared_from(SHARED_JOINTS_FROM);
        match region.filter(|_| sorted.len() >= from) {
            Some(region) => constraints.build_shared(sorted.len(), region, &source),
            None => {
                constraints.clear();
                (0..sorted.len()).for_each(|k| constraints.push(source(k)));
            }
        }
        self.joints.constraints = constraints;
    }

    /// Fetch what [`World::build_joint_constraints`] reads of the joint `k`th in solve order,
    /// in two moves: its slot now, and the bodies it joins once the slot has come (half the
    /// distance later). Joints in solve order lie all over their slots, and their bodies all
    /// over theirs: read without, the build waited on memory for two thirds of its time.
    #[inline(always)]
    fn fetch_joint(&self, k: usize) {
        let sorted = &self.joints.sorted;
        if let Some(&slot) = sorted.get(k) {
            prefetch(&self.joints.slots[slot as usize]);
        }
        let Some(&slot) = sorted.get(k - JOINTS_AHEAD / 2) else {
            return;
        };
        if let Some(j) = &self.joints.slots[slot as usize].joint {
            for id in j.def.body_a.iter().chain([&j.def.body_b]) {
                if let Some(slot) = self.bodies.slots.get(id.index as usize) {
                    prefetch(slot);
                }
            }
        }
    }

    /// The joints with an awake body, each given a colour if it has none (in slot order),
    /// listed in solve order: by their colour's rank, then slot.
    fn sort_awake_joints(&mut self) {
        let mut order = std::mem::take(&mut self.joints.order);
        order.clear();
        let (slots, graph) = (&self.bodies.slots, &mut self.contacts.graph);
        for (slot, s) in self.joints.slots.iter_mut().enumerate() {
            let Some(j) = &mut s.joint else { continue };
            if !joint_is_awake(&j.def, slots) {
                continue;
            }
            if j.colour == UNCOLOURED {
                let (ends, dynamic) = graph_ends(&j.def, slots);
                j.colour = graph.add(ends, dynamic);
            }
            order.push((solve_rank(j.colour), slot as u32));
        }
        by_rank(&order, &mut self.joints.sorted);
        self.joints.order = order;
        self.joints.sorted_kept = true;
    }

    /// The joints whose bodies have all fallen asleep give their colours back (the sleeping
    /// contacts do the same); they take new ones when their island wakes.
    pub(super) fn set_sleeping_joints_aside(&mut self) {
        if self.joints.count == 0 {
            return;
        }
        let (slots, graph) = (&self.bodies.slots, &mut self.contacts.graph);
        for s in &mut self.joints.slots {
            let Some(j) = s.joint.as_mut().filter(|j| j.colour != UNCOLOURED) else {
                continue;
            };
            if !joint_is_awake(&j.def, slots) {
                graph.remove(j.colour, graph_ends(&j.def, slots).0);
                j.colour = UNCOLOURED;
                self.joints.sorted_kept = false;
            }
        }
    }

    /// After the solve: each solved joint's impulses and reaction back into it; then the
    /// joints whose force or torque passed their break force or torque are removed, in id
    /// order, and listed in [`World::broken_joints`].
    #[inline(never)]
    pub(super) fn finish_joints(&mut self, region: Option<&Region>) {
        self.joints.broken.clear();
        self.joints.broken_loads.clear();
        let set = &self.joints.constraints;
        // Whether any joint is past its breaking force or torque.
        let overloaded = AtomicBool::new(false);
        let finish = |index: usize, j: &mut Joint| {
            let k = &set.cold[index];
            j.impulses = set.impulses(index);
            (j.force, j.torque) = (k.force, k.torque);
            if j.overloaded() {
                overloaded.store(true, Ordering::Relaxed);
            }
        };
        let n = set.cold.len();
        let from = self.solver.bundles.shared_from(SHARED_JOINTS_FROM);
        match region.filter(|_| n >= from) {
            Some(region) => {
                // SAFETY: each constraint is of its own joint slot, and each block reaches
                // only its constraints' slots.
                let slots = unsafe { SharedSlice::new(&mut self.joints.slots) };
                region.for_blocks(n.div_ceil(FINISHED_PER_BLOCK), &|b| {
                    for index in block(b, FINISHED_PER_BLOCK, n) {
                        // SAFETY: as above.
                        let slot = unsafe { slots.get(set.cold[index].slot as usize) };
                        finish(index, live(slot));
                    }
                });
            }
            None => {
                for index in 0..n {
                    // (The slots lie all over the array, as in the build.)
                    if let Some(cold) = set.cold.get(index + JOINTS_AHEAD) {
                        prefetch(&self.joints.slots[cold.slot as usize]);
                    }
                    finish(
                        index,
                        live(self.joints.slots.get_mut(set.cold[index].slot as usize)),
                    );
                }
            }
        }
        if !overloaded.into_inner() {
            return;
        }
        for k in &self.joints.constraints.cold {
            let j = self.joints.slots[k.slot as usize].joint.as_ref();
            let j = j.expect("constraints are of live joints");
            if j.overloaded() {
                self.joints.broken.push(j.id);
            }
        }
        self.joints.broken.sort_unstable();
        for i in 0..self.joints.broken.len() {
            let id = self.joints.broken[i];
            let j = self.remove_joint(id).expect("live");
            self.joints.broken_loads.push((j.force, j.torque));
        }
    }
}

/// The live joint of a slot a constraint names.
fn live(slot: Option<&mut JointSlot>) -> &mut Joint {
    let j = slot.and_then(|s| s.joint.as_mut());
    j.expect("constraints are of live joints")
}

/// How many joints a worker finishes at a time.
const FINISHED_PER_BLOCK: usize = 64;

/// The definition with a missing reference angle or length taken from the bodies as they are
/// (`a` None: the world).
fn resolved(def: &JointDef, a: Option<&Body>, b: &Body) -> JointDef {
    let mut def = def.clone();
    let angle = b.angle - a.map_or(0.0, |a| a.angle);
    let world_a = a.map_or(def.anchor_a, |a| a.transform().apply(def.anchor_a));
    let world_b = b.transform().apply(def.anchor_b);
    match &mut def.kind {
        JointKind::Revolute(r) => r.reference_angle = r.reference_angle.or(Some(angle)),
        JointKind::Prismatic(p) => p.reference_angle = p.reference_angle.or(Some(angle)),
        JointKind::Weld(w) => w.reference_angle = w.reference_angle.or(Some(angle)),
        JointKind::Distance(d) => {
            d.length = d
                .length
                .or(Some((world_b - world_a).length().max(MIN_LENGTH)));
        }
        JointKind::Wheel(_) | JointKind::Motor(_) | JointKind::Target(_) => {}
    }
    def
}

/// The shortest rest length a distance joint takes from its bodies (m): anchors that meet
/// have no direction to hold a distance along.
const MIN_LENGTH: Real = 0.005;

/// A distance joint's rest length (m; 0 for other kinds).
fn rest_length(kind: &JointKind) -> Real {
    match kind {
        JointKind::Distance(d) => d.length.unwrap_or(MIN_LENGTH),
        _ => 0.0,
    }
}

/// The joint's reference angle (rad): what its angle counts from.
fn reference_angle(kind: &JointKind) -> Real {
    match kind {
        JointKind::Revolute(r) => r.reference_angle.unwrap_or(0.0),
        JointKind::Prismatic(p) => p.reference_angle.unwrap_or(0.0),
        JointKind::Weld(w) => w.reference_angle.unwrap_or(0.0),
        _ => 0.0,
    }
}

/// The joint's axis in A's frame (unit; the x axis for kinds without one).
fn local_axis(kind: &JointKind) -> Vec2 {
    match kind {
        JointKind::Prismatic(p) => p.axis.normalize(),
        JointKind::Wheel(w) => w.axis.normalize(),
        _ => Vec2::X,
    }
}

/// Where joint `d`'s anchors and axis are with its bodies posed as now (`a` None: the world).
fn frame(d: &JointDef, a: Option<&Body>, b: &Body) -> Frame {
    // Anchors are given from the bodies' origins; the arms reach from their centres of mass.
    let (ca, qa, angle_a, center_a) = a.map_or((Vec2::ZERO, Rot::IDENTITY, 0.0, Vec2::ZERO), |a| {
        (a.position, a.rot, a.angle, a.local_center())
    });
    Frame {
        ra: qa.rotate(d.anchor_a - center_a),
        rb: b.rot.rotate(d.anchor_b - b.local_center()),
        centres: b.position - ca,
        angle: b.angle - angle_a - reference_angle(&d.kind),
        axis: qa.rotate(local_axis(&d.kind)),
    }
}

/// How many joints ahead in solve order the build fetches a joint's slot ([`World::fetch_joint`]).
const JOINTS_AHEAD: usize = 8;

/// The slots of the bodies of every joint between two dynamic bodies (islands go through
/// them; joints to static or kinematic bodies or the world join none).
pub(super) fn joint_pairs<'a>(
    joints: &'a Joints,
    slots: &'a [Slot],
) -> impl Iterator<Item = [u32; 2]> + 'a {
    let dynamic = |i: u32| {
        slots[i as usize]
            .body
            .as_ref()
            .is_some_and(|b| b.inv_mass > 0.0)
    };
    let live = joints.slots.iter().filter_map(|s| s.joint.as_ref());
    live.filter_map(move |j| match j.def.body_a {
        Some(a) if dynamic(a.index) && dynamic(j.def.body_b.index) => {
            Some([a.index, j.def.body_b.index])
        }
        _ => None,
    })
}

impl World {
    /// The joint slots as plain data (checkpoints).
    pub(super) fn export_joints(&self) -> Vec<JointSlotState> {
        let slots = self.joints.slots.iter();
        slots
            .map(|s| JointSlotState {
                generation: s.generation,
                joint: s.joint.as_ref().map(|j| (j.def.clone(), j.impulses)),
            })
            .collect()
    }

    /// The joints of a checkpoint, each checked as [`World::add_joint`] checks it and its
    /// impulses finite, with the free list checked against the slots; after the bodies.
    pub(super) fn import_joints(
        &mut self,
        slots: &[JointSlotState],
        free: &[u32],
    ) -> Result<(), StateError> {
        let mut is_free = vec![false; slots.len()];
        for &i in free {
            match slots.get(i as usize) {
                Some(s)
                    if s.joint.is_none() && !std::mem::replace(&mut is_free[i as usize], true) => {}
                _ => {
                    return Err(StateError(format!(
                        "joint free list names slot {i}, which is not a free joint slot"
                    )))
                }
            }
        }
        for (index, s) in slots.iter().enumerate() {
            self.joints.slots.push(JointSlot {
                generation: s.generation,
                joint: None,
            });
            let Some((def, impulses)) = &s.joint else {
                if !is_free[index] {
                    return Err(StateError(format!(
                        "joint slot {index} is empty but not in the free list"
                    )));
                }
                continue;
            };
            let finite = impulses
                .point
                .iter()
                .chain(&impulses.rows)
                .all(|x| x.is_finite());
            if !finite {
                return Err(StateError(format!("joint {index}: impulses not finite")));
            }
            let def = self
                .checked_joint(def)
                .map_err(|e| StateError(format!("joint {index}: {e}")))?;
            // Into this very slot, without waking anything.
            self.joints.free.push(index as u32);
            self.insert_joint(def);
            let joint = self.joints.slots[index].joint.as_mut().expect("just added");
            joint.impulses = *impulses;
        }
        self.joints.free = free.to_vec();
        Ok(())
    }
}
