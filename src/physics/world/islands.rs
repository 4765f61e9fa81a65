//! Islands: bodies joined by contacts and joints. Sleep puts an island to rest when all of it has
//! rested, and wakes it whole; adaptive stiffness (`tiers.rs`) gives each awake one a tier.

use super::*;
use crate::physics::body::CREATED_ASLEEP;
use crate::physics::broad_phase::pair_key;
use crate::physics::shape::Aabb;
use crate::physics::solver::graph::UNCOLOURED;

/// Islands' and sleep's buffers, reused every step.
#[derive(Clone, Debug, Default)]
pub(super) struct IslandScratch {
    /// Each contact's two bodies, in contact order: the island passes read 8 bytes a contact
    /// instead of the whole contact.
    pub contact_bodies: Vec<[u32; 2]>,
    /// Union-find parent per slot.
    pub parent: Vec<u32>,
    /// Per island root: how long its most restless body has rested (s).
    pub rest: Vec<Real>,
    /// Bodies to wake (with their islands) before the next solve.
    pub wake_queue: Vec<u32>,
    /// The bodies that just fell asleep, or just woke.
    pub changed: Vec<u32>,
    /// The sleeping islands to wake, sorted.
    pub waking: Vec<u32>,
    /// Bodies were created asleep (or one of them was removed) since the islands of the
    /// bodies created asleep were last drawn: they are drawn again before the next step.
    pub unsettled: bool,
    /// A body created asleep woke while contacts were being found: its island's contacts
    /// are found before the solve.
    pub refind: bool,
    /// `parent` holds this step's islands of awake dynamic bodies, found by adaptive
    /// stiffness before the solve (`tiers.rs`): sleep takes them as they are.
    pub united: bool,
}

impl World {
    /// Islands and sleep: bodies joined by contacts form islands; an island whose every body
    /// has rested (|v| + |w| r below the threshold) for `time_to_sleep` falls asleep together.
    pub(super) fn update_sleep(&mut self, dt: Real) {
        // The tiers' islands are sleep's, unless a joint broke since they were found.
        if !(std::mem::take(&mut self.islands.united) && self.joints.broken.is_empty()) {
            self.unite_awake_islands();
        }
        if self.update_rest_times(dt) {
            self.put_rested_islands_to_sleep();
        }
        if self.islands.changed.is_empty() {
            return;
        }
        self.broad_phase
            .sweep
            .set_passive(&self.islands.changed, true);
        self.set_sleeping_contacts_aside();
        self.set_sleeping_joints_aside();
    }

    /// Each awake body's time at rest (how long it has been slower than the threshold), and
    /// each island's (`rest`, at its root): an island rests as long as its most restless
    /// body. Returns whether any island has rested `time_to_sleep`.
    fn update_rest_times(&mut self, dt: Real) -> bool {
        let threshold = self.settings.sleep_threshold;
        let n = self.bodies.slots.len();
        let islands = &mut self.islands;
        islands.rest.clear();
        islands.rest.resize(n, Real::INFINITY);
        islands.changed.clear();
        for (i, slot) in self.bodies.slots.iter_mut().enumerate() {
            if let Some(b) = slot.body.as_mut().filter(|b| b.is_active()) {
                let speed =
                    b.linear_velocity.length() + b.angular_velocity.abs() * b.bounding_radius;
                b.sleep_time = if speed > threshold {
                    0.0
                } else {
                    b.sleep_time + dt
                };
                let root = find(&mut islands.parent, i as u32) as usize;
                islands.rest[root] = islands.rest[root].min(b.sleep_time);
            }
        }
        // Pushed out of a deep overlap this step: moving, however slow its velocity.
        for i in self.solver.recovery.pushed_bodies() {
            if let Some(b) = self.bodies.slots[i as usize].body.as_mut() {
                b.sleep_time = 0.0;
                if b.is_active() {
                    islands.rest[find(&mut islands.parent, i) as usize] = 0.0;
                }
            }
        }
        // (An entry no island's body reached stays infinite.)
        let time_to_sleep = self.settings.time_to_sleep;
        let rested = |&r: &Real| r.is_finite() && r >= time_to_sleep;
        islands.rest.iter().any(rested)
    }

    /// Islands of awake dynamic bodies joined by contacts and joints (static bodies join
    /// nothing), by union-find.
    fn unite_awake_islands(&mut self) {
        let slots = &self.bodies.slots;
        let pairs = &mut self.islands.contact_bodies;
        pairs.clear();
        pairs.extend(self.contacts.awake.iter().map(|c| [c.a, c.b]));
        if self.joints.count > 0 {
            pairs.extend(super::joints::joint_pairs(&self.joints, slots));
        }
        unite_islands(&mut self.islands.parent, slots.len(), pairs, |i| {
            is_active(slots, i)
        });
    }

    /// The islands that have rested `time_to_sleep` ([`World::update_rest_times`]) fall
    /// asleep, their bodies listed in `changed`.
    fn put_rested_islands_to_sleep(&mut self) {
        let islands = &mut self.islands;
        for (i, slot) in self.bodies.slots.iter_mut().enumerate() {
            let root = find(&mut islands.parent, i as u32);
            let Some(b) = slot.body.as_mut().filter(|b| b.is_active()) else {
                continue;
            };
            if islands.rest[root as usize] >= self.settings.time_to_sleep {
                b.awake = false;
                b.linear_velocity = Vec2::ZERO;
                b.angular_velocity = 0.0;
                b.sleep_island = root;
                islands.changed.push(i as u32);
            }
        }
    }

    /// Bodies created asleep sleep with the bodies created asleep that they touch, as if they
    /// had come to rest together: whatever reaches one wakes them all, and their contacts are
    /// found before that step's solve, so a blow passes through a block of them at once
    /// instead of a layer a step (which drove each layer deep into the next). Two touch when
    /// their boxes, grown by half the speculative distance as the broad phase grows them,
    /// overlap and their filters let them collide. Islands by union-find, the lowest slot the
    /// root (no other island's: its members are not asleep otherwise).
    pub(super) fn settle_created_asleep(&mut self) {
        self.islands.unsettled = false;
        let margin = 0.5 * self.settings.speculative_distance;
        let slots = &self.bodies.slots;
        let mut boxes: Vec<(Aabb, u32)> = slots
            .iter()
            .enumerate()
            .filter_map(|(i, s)| {
                let b = s.body.as_ref().filter(|b| b.is_created_asleep())?;
                Some((b.aabb().inflated(margin), i as u32))
            })
            .collect();
        boxes.sort_unstable_by(|x, y| x.0.min.x.total_cmp(&y.0.min.x).then(x.1.cmp(&y.1)));
        let pairs = &mut self.islands.contact_bodies;
        pairs.clear();
        for (k, &(a, i)) in boxes.iter().enumerate() {
            for &(b, j) in boxes[k + 1..]
                .iter()
                .take_while(|(b, _)| b.min.x <= a.max.x)
            {
                let overlap = b.min.y <= a.max.y && a.min.y <= b.max.y;
                if overlap && super::contacts::filters_allow(pair_key(i, j), &self.bodies) {
                    pairs.push([i, j]);
                }
            }
        }
        let parent = &mut self.islands.parent;
        unite_islands(parent, slots.len(), pairs, |_| true);
        for &(_, i) in &boxes {
            let root = find(parent, i);
            if let Some(b) = self.bodies.slots[i as usize].body.as_mut() {
                b.sleep_island = root;
            }
        }
    }

    /// Contacts with no awake body left leave the graph and are kept aside, unsolved, for
    /// when their island wakes.
    fn set_sleeping_contacts_aside(&mut self) {
        let slots = &self.bodies.slots;
        let contacts = &mut self.contacts;
        let mut kept = 0;
        for k in 0..contacts.awake.len() {
            let mut c = contacts.awake[k];
            if !is_active(slots, c.a) && !is_active(slots, c.b) {
                contacts.graph.remove(c.colour, [c.a, c.b]);
                c.colour = UNCOLOURED;
                // Not kept with a kinematic body: it finds the sleeper again when it moves.
                let kinematic =
                    |i: u32| slots[i as usize].body.as_ref().is_some_and(|b| b.kinematic);
                if !kinematic(c.a) && !kinematic(c.b) {
                    contacts.sleeping.push(c);
                }
            } else {
                contacts.awake[kept] = c;
                kept += 1;
            }
        }
        contacts.awake.truncate(kept);
    }

    /// Wake the islands of the bodies in the wake queue: their bodies rejoin the active list
    /// and their contacts (with the impulses they slept with) rejoin the solver.
    pub(super) fn wake_queued(&mut self) {
        if self.islands.wake_queue.is_empty() {
            return;
        }
        // The islands to wake, then one pass over the bodies (not one per island).
        let slots = &self.bodies.slots;
        let asleep_in = |i: &u32| {
            slots[*i as usize]
                .body
                .as_ref()
                .filter(|b| !b.awake)
                .map(|b| b.sleep_island)
        };
        let islands = &mut self.islands.waking;
        islands.clear();
        islands.extend(self.islands.wake_queue.iter().filter_map(asleep_in));
        islands.sort_unstable();
        islands.dedup();
        self.islands.changed.clear();
        if !islands.is_empty() {
            for (j, slot) in self.bodies.slots.iter_mut().enumerate() {
                if let Some(b) = slot
                    .body
                    .as_mut()
                    .filter(|b| !b.awake && islands.binary_search(&b.sleep_island).is_ok())
                {
                    b.awake = true;
                    self.islands.refind |= b.sleep_time == CREATED_ASLEEP;
                    b.sleep_time = 0.0;
                    self.islands.changed.push(j as u32);
                }
            }
        }
        self.islands.wake_queue.clear();
        if self.islands.changed.is_empty() {
            return;
        }
        // Their joints take colours at the next step.
        self.joints.sorted_kept = false;
        self.broad_phase
            .sweep
            .set_passive(&self.islands.changed, false);
        let slots = &self.bodies.slots;
        let active = |i: u32| slots[i as usize].body.as_ref().is_some_and(Body::is_active);
        let before = self.contacts.awake.len();
        let mut k = 0;
        while k < self.contacts.sleeping.len() {
            let c = self.contacts.sleeping[k];
            if active(c.a) || active(c.b) {
                self.contacts.awake.push(c);
                self.contacts.sleeping.swap_remove(k);
            } else {
                k += 1;
            }
        }
        if self.contacts.awake.len() != before {
            self.contacts.awake.sort_unstable_by_key(Contact::order);
            // The woken contacts rejoin the graph, in key order.
            let (slots, contacts) = (&self.bodies.slots, &mut self.contacts);
            let dynamic = |i: u32| {
                slots[i as usize]
                    .body
                    .as_ref()
                    .is_some_and(|b| b.inv_mass > 0.0)
            };
            for c in contacts.awake.iter_mut().filter(|c| c.colour == UNCOLOURED) {
                c.colour = contacts.graph.add([c.a, c.b], [dynamic(c.a), dynamic(c.b)]);
            }
        }
    }
}

/// Islands by union-find: `parent` becomes `n` singletons, then the two bodies of every
/// contact (`pairs`) for which `joins` holds on both sides are united. The lower root wins, so the
/// islands (and everything solved per island) are the same on every run.
pub(super) fn unite_islands(
    parent: &mut Vec<u32>,
    n: usize,
    pairs: &[[u32; 2]],
    joins: impl Fn(u32) -> bool,
) {
    parent.clear();
    parent.extend(0..n as u32);
    for &[a, b] in pairs {
        if joins(a) && joins(b) {
            let (ra, rb) = (find(parent, a), find(parent, b));
            if ra != rb {
                let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
                parent[hi as usize] = lo;
            }
        }
    }
}

/// Point every entry of `parent`, after [`unite_islands`], straight at its root, so that a
/// root is one load away. One pass in order does it: the lower root wins, so an entry's parent
/// comes before it and has already been pointed at its root.
pub(super) fn flatten(parent: &mut [u32]) {
    for i in 0..parent.len() {
        let p = parent[i] as usize;
        debug_assert!(p <= i, "a parent comes before its child");
        parent[i] = parent[p];
    }
}

/// Union-find root of `i`, halving paths as it goes.
#[inline]
pub(super) fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let p = parent[i as usize];
        parent[i as usize] = parent[p as usize];
        i = p;
    }
    i
}

/// Whether slot `i` holds an awake dynamic body.
fn is_active(slots: &[Slot], i: u32) -> bool {
    slots[i as usize].body.as_ref().is_some_and(Body::is_active)
}
