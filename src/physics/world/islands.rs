//! Islands: bodies joined by contacts. Adaptive stiffness gives each awake island a tier;
//! sleep puts an island to rest when all of it has rested, and wakes it whole.

use super::*;
use crate::physics::shape::Aabb;

impl World {
    /// Give every awake island a stiffness tier from its contacts ([`SUBSTEP_QUARTERS`] says
    /// what each tier does). An island is loaded where a contact's lasting force is
    /// `stiff_load_ratio` times the lighter body's weight or more, or a touching contact is
    /// too new for its load to be known. A loaded island that is braced sideways (a pyramid,
    /// a pile: less than [`SLENDER`] times as tall as it is wide, along gravity, and with at
    /// least `stiff_load_ratio` moving bodies; see `island_tier`) gets [`BRACED`]; any other
    /// (a stack) [`STACK`], or [`TALL_STACK`] where the load is
    /// [`LOADED_RANGE`] times more. [`TALL_STACK`] also takes islands where two bodies' masses
    /// differ by `stiff_load_ratio`, and [`EXTREME`] those where they differ by
    /// `extreme_mass_ratio` or more.
    /// Fills `contact_tier` and `body_tier`; returns the highest tier (0: nothing needs more).
    pub(super) fn assign_tiers(&mut self) -> u8 {
        let g = self.gravity.length();
        let g_ref = if g > 1e-3 { g } else { 9.81 };
        let (stiff, extreme) = (
            self.settings.stiff_load_ratio,
            self.settings.extreme_mass_ratio,
        );
        if self.tier_inputs.len() != self.contacts.len() {
            // Contacts joined since they were found (an island woke): read them all again.
            let slop = self.settings.linear_slop;
            self.tier_inputs.clear();
            self.tier_inputs
                .extend(self.contacts.iter().map(|c| TierInput::of(c, slop)));
        }
        self.contact_tier.clear();
        self.contact_bodies.clear();
        let mut top = 0u8;
        for input in &self.tier_inputs {
            let [a, b] = input.bodies;
            let (ma, mb) = (
                self.solver_bodies[a as usize].inv_mass,
                self.solver_bodies[b as usize].inv_mass,
            );
            // Inverse masses: the lighter body has the larger one; static bodies have zero.
            let light_inv = ma.max(mb);
            let heavy_inv = ma.min(mb);
            let load = if light_inv > 0.0 {
                input.load * light_inv / g_ref
            } else {
                0.0
            };
            let masses = if heavy_inv > 0.0 {
                light_inv / heavy_inv
            } else {
                0.0
            };
            // A soft contact's spring compresses by its load over m omega^2, and omega can rise
            // with the substep rate only: 1.5 times the substeps hold 1.5^2 = 2.25 times the
            // load at the same compression. What the contact needs, before its island is
            // known to be slender or braced:
            let need = if masses >= extreme {
                EXTREME
            } else if masses >= stiff {
                TALL_STACK
            } else if load >= LOADED_RANGE * stiff {
                HEAVILY_LOADED
            } else if load >= stiff || input.unmeasured {
                LOADED
            } else {
                0
            };
            top = top.max(need);
            self.contact_tier.push(need);
            self.contact_bodies.push(input.bodies);
        }
        if top == 0 {
            return 0;
        }
        // Islands: union-find over contacts between dynamic awake bodies; an island's tier
        // comes from the highest need of its contacts and its shape, and all its contacts and
        // bodies take it.
        let n = self.solver_bodies.len();
        let moving = |i: u32, bodies: &[SolverBody]| bodies[i as usize].inv_mass > 0.0;
        let bodies = &self.solver_bodies;
        unite_islands(&mut self.island_parent, n, &self.contact_bodies, |i| {
            moving(i, bodies)
        });
        // Each island's need and its extent along gravity and across it (its bodies' boxes
        // from the broad phase, found this step), kept at its root; then its tier.
        self.body_tier.clear();
        self.body_tier.resize(n, 0);
        for (&need, pair) in self.contact_tier.iter().zip(&self.contact_bodies) {
            let i = if moving(pair[0], bodies) {
                pair[0]
            } else {
                pair[1]
            };
            let root = find(&mut self.island_parent, i) as usize;
            self.body_tier[root] = self.body_tier[root].max(need);
        }
        let down = if g > 1e-3 {
            self.gravity / g
        } else {
            Vec2::new(0.0, -1.0)
        };
        let across = Vec2::new(-down.y, down.x);
        self.island_extent.clear();
        self.island_extent.resize(n, Extent::EMPTY);
        self.island_bodies.clear();
        self.island_bodies.resize(n, 0);
        for (i, proxy) in self.proxies.iter().enumerate() {
            if moving(i as u32, bodies) {
                let root = find(&mut self.island_parent, i as u32) as usize;
                self.island_extent[root].add(&proxy.aabb, down, across);
                self.island_bodies[root] += 1;
            }
        }
        top = 0;
        for i in 0..n {
            if self.island_parent[i] as usize == i {
                let braced =
                    self.island_bodies[i] as Real >= stiff && !self.island_extent[i].slender();
                let tier = island_tier(self.body_tier[i], braced);
                self.body_tier[i] = tier;
                top = top.max(tier);
            }
        }
        for i in 0..n as u32 {
            let root = find(&mut self.island_parent, i) as usize;
            self.body_tier[i as usize] = self.body_tier[root];
        }
        for (tier, &[a, b]) in self.contact_tier.iter_mut().zip(&self.contact_bodies) {
            let i = if moving(a, bodies) { a } else { b };
            *tier = self.body_tier[i as usize];
        }
        top
    }

    /// Islands and sleep: bodies joined by contacts form islands; an island whose every body
    /// has rested (|v| + |w| r below the threshold) for `time_to_sleep` falls asleep together.
    pub(super) fn update_sleep(&mut self, dt: Real) {
        let threshold = self.settings.sleep_threshold;
        let n = self.slots.len();
        for slot in self.slots.iter_mut() {
            if let Some(b) = slot.body.as_mut().filter(|b| b.is_active()) {
                let speed =
                    b.linear_velocity.length() + b.angular_velocity.abs() * b.bounding_radius;
                b.sleep_time = if speed > threshold {
                    0.0
                } else {
                    b.sleep_time + dt
                };
            }
        }
        // Islands of awake dynamic bodies (static bodies join nothing).
        let active =
            |slots: &[Slot], i: u32| slots[i as usize].body.as_ref().is_some_and(Body::is_active);
        let slots = &self.slots;
        self.contact_bodies.clear();
        self.contact_bodies
            .extend(self.contacts.iter().map(|c| [c.a, c.b]));
        unite_islands(&mut self.island_parent, n, &self.contact_bodies, |i| {
            active(slots, i)
        });
        // The island rests as long as its most restless body.
        self.island_rest.clear();
        self.island_rest.resize(n, Real::INFINITY);
        for i in 0..n as u32 {
            if let Some(b) = self.slots[i as usize]
                .body
                .as_ref()
                .filter(|b| b.is_active())
            {
                let root = find(&mut self.island_parent, i) as usize;
                self.island_rest[root] = self.island_rest[root].min(b.sleep_time);
            }
        }
        self.changed.clear();
        for i in 0..n as u32 {
            let root = find(&mut self.island_parent, i);
            if let Some(b) = self.slots[i as usize]
                .body
                .as_mut()
                .filter(|b| b.is_active())
            {
                if self.island_rest[root as usize] >= self.settings.time_to_sleep {
                    b.awake = false;
                    b.linear_velocity = Vec2::ZERO;
                    b.angular_velocity = 0.0;
                    b.sleep_island = root;
                    self.changed.push(i);
                }
            }
        }
        if self.changed.is_empty() {
            return;
        }
        self.broad_phase.set_passive(&self.changed, true);
        // Contacts with no awake body left are kept aside, unsolved, for when the island wakes.
        let slots = &self.slots;
        let mut kept = 0;
        for k in 0..self.contacts.len() {
            let c = self.contacts[k];
            if !active(slots, c.a) && !active(slots, c.b) {
                // Not kept with a kinematic body: it finds the sleeper again when it moves.
                let kinematic =
                    |i: u32| slots[i as usize].body.as_ref().is_some_and(|b| b.kinematic);
                if !kinematic(c.a) && !kinematic(c.b) {
                    self.sleeping_contacts.push(c);
                }
            } else {
                self.contacts[kept] = c;
                kept += 1;
            }
        }
        self.contacts.truncate(kept);
    }

    /// Wake the islands of the bodies in the wake queue: their bodies rejoin the active list
    /// and their contacts (with the impulses they slept with) rejoin the solver.
    pub(super) fn wake_queued(&mut self) {
        if self.wake_queue.is_empty() {
            return;
        }
        // The islands to wake, then one pass over the bodies (not one per island).
        let slots = &self.slots;
        let asleep_in = |i: &u32| {
            slots[*i as usize]
                .body
                .as_ref()
                .filter(|b| !b.awake)
                .map(|b| b.sleep_island)
        };
        let islands = &mut self.waking_islands;
        islands.clear();
        islands.extend(self.wake_queue.iter().filter_map(asleep_in));
        islands.sort_unstable();
        islands.dedup();
        self.changed.clear();
        if !islands.is_empty() {
            for (j, slot) in self.slots.iter_mut().enumerate() {
                if let Some(b) = slot
                    .body
                    .as_mut()
                    .filter(|b| !b.awake && islands.binary_search(&b.sleep_island).is_ok())
                {
                    b.awake = true;
                    b.sleep_time = 0.0;
                    self.changed.push(j as u32);
                }
            }
        }
        self.wake_queue.clear();
        if self.changed.is_empty() {
            return;
        }
        self.broad_phase.set_passive(&self.changed, false);
        let slots = &self.slots;
        let active = |i: u32| slots[i as usize].body.as_ref().is_some_and(Body::is_active);
        let before = self.contacts.len();
        let mut k = 0;
        while k < self.sleeping_contacts.len() {
            let c = self.sleeping_contacts[k];
            if active(c.a) || active(c.b) {
                self.contacts.push(c);
                self.sleeping_contacts.swap_remove(k);
            } else {
                k += 1;
            }
        }
        if self.contacts.len() != before {
            self.contacts.sort_unstable_by_key(|c| c.key);
        }
    }
}

/// What adaptive stiffness reads of a contact, taken as the contact is found: 16 bytes, so
/// that giving the contacts their tiers does not stream through the whole contacts (that
/// pass was 7 % of large_pyramid's step when they were 400 bytes; they are 208 now).
#[derive(Clone, Copy, Debug)]
pub(super) struct TierInput {
    /// Slots of bodies A and B.
    pub bodies: [u32; 2],
    /// The contact's held load (N; `Contact::load`).
    pub load: Real,
    /// A contact that has just closed carries a load nobody has measured yet: while a stack
    /// settles its loads ramp up over about five steps, and at the base settings it sinks
    /// 2.6 cm in them. Such a contact (younger than [`NEW_CONTACT_STEPS`], a point within
    /// `linear_slop`) is solved as a loaded one until it is old enough for its load to count.
    pub unmeasured: bool,
}

impl TierInput {
    /// The contact's inputs; `slop` is `Settings::linear_slop` (m).
    #[inline]
    pub fn of(c: &Contact, slop: Real) -> TierInput {
        TierInput {
            bodies: [c.a, c.b],
            load: c.load,
            unmeasured: c.age < NEW_CONTACT_STEPS
                && c.points[..c.count].iter().any(|p| p.separation <= slop),
        }
    }
}

/// Adaptive stiffness: the base tier and the four above it.
pub(super) const TIERS: usize = 5;

/// Tier of a loaded island braced sideways (a pyramid, a pile): the base substeps with two
/// relax passes and creep.
pub(super) const BRACED: u8 = 1;
/// Tier of a loaded island that is not braced (a stack): 1.5 times the substeps and
/// stiffness.
pub(super) const STACK: u8 = 2;
/// Tier of an island that is not braced under [`LOADED_RANGE`] times the load (a tall stack), or with
/// masses `stiff_load_ratio` apart: 1.75 times the substeps and stiffness.
pub(super) const TALL_STACK: u8 = 3;
/// Tier of an island with masses `extreme_mass_ratio` apart: four times the substeps and
/// stiffness, eight times the relax passes.
pub(super) const EXTREME: u8 = 4;

/// What a contact asks of its island before the island's shape is known: a load from
/// `stiff_load_ratio` ([`BRACED`] if the island is braced, else [`STACK`]), or
/// [`LOADED_RANGE`] times that ([`BRACED`] if braced, else [`TALL_STACK`]).
const LOADED: u8 = STACK;
const HEAVILY_LOADED: u8 = TALL_STACK;

/// Adaptive stiffness: an island is slender (a stack) when it is at least this many times
/// as tall, along gravity, as it is wide across it (its bodies' boxes): a 20-box stack of
/// 1 m boxes is 14 times, a pyramid about once, a pile less. The shape is known at once; a
/// measure of how the load spreads (the most loaded contact against the island's weight)
/// needs the loads, which take five steps to build under a new stack: solved braced in the
/// meantime, a 20-box stack sank 2.18 cm (bound 2).
pub(super) const SLENDER: Real = 2.0;

/// An island's extent (m) along gravity (up) and across it, from its bodies' boxes.
#[derive(Clone, Copy, Debug)]
pub(super) struct Extent {
    up: [Real; 2],
    side: [Real; 2],
}

impl Extent {
    /// No body yet.
    pub const EMPTY: Extent = Extent {
        up: [Real::INFINITY, Real::NEG_INFINITY],
        side: [Real::INFINITY, Real::NEG_INFINITY],
    };

    /// Take in box `aabb`, with `down` the unit vector along gravity and `across` normal to it.
    #[inline]
    fn add(&mut self, aabb: &Aabb, down: Vec2, across: Vec2) {
        let centre = 0.5 * (aabb.min + aabb.max);
        let half = 0.5 * (aabb.max - aabb.min);
        let reach = |d: Vec2| half.x * d.x.abs() + half.y * d.y.abs();
        let (up, side) = (-centre.dot(down), centre.dot(across));
        let (r_up, r_side) = (reach(down), reach(across));
        self.up = [self.up[0].min(up - r_up), self.up[1].max(up + r_up)];
        self.side = [
            self.side[0].min(side - r_side),
            self.side[1].max(side + r_side),
        ];
    }

    /// At least [`SLENDER`] times as tall as wide.
    fn slender(&self) -> bool {
        self.up[1] - self.up[0] >= SLENDER * (self.side[1] - self.side[0])
    }
}

/// The tier of an island from its contacts' highest `need` and whether it is `braced`: not
/// slender, and with at least `stiff_load_ratio` moving bodies. A smaller island cannot carry
/// that many of its bodies' weight: it is loaded only by contacts too new to be measured,
/// unequal masses or an impact, and it is small, so it keeps the stack tiers (a box sliding
/// over a chain of tiles, loaded by each new contact, tilted past 1e-4 rad when it was solved
/// braced, on the base substeps with two relax passes).
fn island_tier(need: u8, braced: bool) -> u8 {
    let loaded = need == LOADED || need == HEAVILY_LOADED;
    if loaded && braced {
        BRACED
    } else {
        need
    }
}

/// Adaptive stiffness: substeps per tier in quarters of `Settings::substeps` (1, 1, 1.5,
/// 1.75 and 4 times: 4, 4, 6, 7 and 16 at the default 4); the contact hertz scales with
/// them, since its ceiling is a quarter of the substep rate.
///
/// Stacks need stiff springs, so more substeps: [`TALL_STACK`] was twice the base until
/// creep (`soft_step::creep`); with it, 7 substeps hold a jittered 50-box stack to 1.2 cm of
/// drift (bound 5), 6 do not (11.5 cm), nor do 4 with two relax passes (it falls).
/// Braced islands need the slow bounce of their rows damped rather than stiffer springs: on
/// the base substeps with a relax pass, a normal relax pass ([`NORMAL_RELAX_SCALE`]) and
/// creep, a base-134 pyramid ends with its fastest body at 0.04 m/s (bound 0.5) and
/// pyramid_30's top moves 0.74 cm (bound 2), for 12 solver passes and 4 normal-only ones a
/// step instead of 21 on 7 substeps.
pub(super) const SUBSTEP_QUARTERS: [u32; TIERS] = [4, 4, 6, 7, 16];

/// Adaptive stiffness: relax passes per tier, as multiples of `Settings::relax_iterations`.
/// The stack tiers need no more than the base: the springs' creep damps the slow bounce
/// ([`CREEP`]). [`BRACED`] has the base's and then a normal
/// relax pass ([`NORMAL_RELAX_SCALE`]). [`EXTREME`] gets 8 (not 4) times: with 4, the 4 m
/// box of 1000 kg on two 1 kg boxes overlapped 9.8 mm (bound 10) and slid 2.3 cm; with 8,
/// 2.5 mm and 0.04 mm. Its islands are small.
pub(super) const RELAX_SCALE: [u32; TIERS] = [1, 1, 1, 1, 8];

/// Adaptive stiffness: normal relax passes per tier (after the relax passes, solving the
/// normal constraints only), as multiples of `Settings::relax_iterations`. What damps a
/// braced island's slow bounce is a second pass over its normals; friction, solved by the
/// full relax pass before it, need not be solved again (the step clamps the friction impulse
/// to the cone of the normal impulse it ends with, `soft_step::finish`). With a full second
/// pass instead (about 10 % more of a pile's step), pyramid_30's top moved 0.00 cm sideways;
/// with the normal pass 0.74 cm (bound 2), and the mixed pile's fastest body in its last
/// second 0.0001 m/s (bound 0.05). With no second pass at all, 1.87 cm: too near the bound.
/// Before friction anchors were removed the normal pass kept big piles vibrating (up to 135
/// of many_boxes' 2,000 through 22 s); without them all 36 nudged piles tried rest by the
/// 12th second (`box_pile` runs six).
pub(super) const NORMAL_RELAX_SCALE: [u32; TIERS] = [0, 1, 0, 0, 0];

/// Adaptive stiffness: how much of last step's compression the springs creep by, per tier
/// (`soft_step::creep`). With 0.5 in the stack tiers, [`TALL_STACK`] holds on 7 substeps and
/// one relax pass where it needed 8 and two (pyramid_30's top: 0.98 cm sideways, bound 2;
/// 7.8 cm with one pass and no creep). With 0.65 a 20-box stack's top sank 2.14 cm (bound
/// 2); with 0.35 pyramid_30's top moved 1.32 cm (these with friction anchors, since removed).
/// Creep leaves a spring at rest 1.5 times
/// softer, which the other tiers do not need: on the base settings a 10-box stack sank 1.04
/// cm (bound 1), and in [`EXTREME`] a 1000 kg box on 1 kg overlapped 8.8 mm instead of 5.5
/// (bound 10).
pub(super) const CREEP: [Real; TIERS] = [0.0, 0.5, 0.5, 0.5, 0.0];

/// Adaptive stiffness: the loads tier 1 holds, as a multiple of `stiff_load_ratio`: 1.5^2,
/// the square of its substep factor (the spring's compression is load / (m omega^2)).
pub(super) const LOADED_RANGE: Real = 2.25;

/// Adaptive stiffness: how many steps a new touching contact is solved as a loaded one
/// before its measured load decides (`World::assign_tiers`).
const NEW_CONTACT_STEPS: u8 = 8;

/// Islands by union-find: `parent` becomes `n` singletons, then the two bodies of every
/// contact (`pairs`) for which `joins` holds on both sides are united. The lower root wins, so the
/// islands (and everything solved per island) are the same on every run.
fn unite_islands(parent: &mut Vec<u32>, n: usize, pairs: &[[u32; 2]], joins: impl Fn(u32) -> bool) {
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

/// Union-find root of `i`, halving paths as it goes.
#[inline]
fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let p = parent[i as usize];
        parent[i as usize] = parent[p as usize];
        i = p;
    }
    i
}
