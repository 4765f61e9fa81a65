//! Finding contacts, in four parts: update the proxies (each body's box for this step), find
//! the candidate pairs (the broad phase), merge them with last step's contacts, and update
//! one contact (its manifold recycled, or the pair collided afresh; last step's impulses
//! carried to the points that persist, for warm starting).
//!
//! Contacts are kept sorted by pair key, as the broad phase yields its pairs, and this step's
//! are written over last step's **in place** while they come in the same order: in a scene at
//! rest every pair keeps its contact and nothing is copied (copying every contact cost 4-5 %
//! of a settled pyramid's step). At the first contact that is new or gone, the ones written so
//! far are copied to a fresh array and the rest is read from last step's. A contact that
//! begins takes a colour from the constraint graph; one that ends gives it back, in key order.

use super::tiers::TierInput;
use super::*;
use crate::physics::collide::{Manifold, ManifoldPoint};
use crate::physics::math::Transform;
use crate::physics::part_tree::PartTree;
use crate::physics::shape::{Aabb, Shape};
use crate::physics::solver::graph::UNCOLOURED;
use crate::physics::solver::lanes::prefetch;
use crate::physics::team::{block, Region, SharedSlice};

/// How many bodies' boxes a worker updates at a time.
const PROXIES_PER_BLOCK: usize = 512;

/// How many pairs ahead the merge fetches the bodies it will read.
const FETCH_AHEAD: usize = 4;

/// How many pairs a worker collides at a time...
const PAIRS_PER_BLOCK: usize = 128;
/// ...and the fewest candidate pairs for which the workers collide them before the merge.
const SHARED_PAIRS_FROM: usize = 512;

/// What the workers found for a pair before the merge ([`PairInput::collide_first`]).
#[derive(Clone, Copy)]
#[repr(u8)]
enum Found {
    /// No contact to keep: filtered, or a body gone.
    Skip,
    /// Bodies of several shapes: the merge collides them.
    Parts,
    /// Last step's contact, updated in place: its manifold recycled, or the contact made
    /// afresh over it.
    InPlace,
    /// A fresh manifold, for the merge to make a contact of: a pair that begins to touch, or
    /// one whose sleeping body it wakes.
    Fresh,
    /// Collided, and nothing to keep.
    Nothing,
}

/// What one block of pairs writes on a worker ([`PairInput::collide_block`]): each pair's
/// [`Found`], fresh manifold and tier input, and what its pairs of bodies of several shapes
/// found (with their scratch).
struct BlockOut<'b> {
    found: &'b mut [u8],
    manifolds: &'b mut [Manifold],
    tier_found: &'b mut [TierInput],
    parts: &'b mut Vec<PartFound>,
    scratch: &'b mut Vec<u32>,
}

/// What the workers found for one pair of shapes of a pair of bodies of several shapes
/// ([`PairInput::collide_parts_first`]), for the merge to write in order
/// ([`PairInput::update_found`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct PartFound {
    /// The pair of bodies, and their shapes as `i << 16 | j`.
    key: u64,
    shapes: u32,
    /// Whether last step's contact of these shapes recycles `manifold`; else `manifold` is
    /// fresh (no points: none).
    recycled: bool,
    manifold: Manifold,
    /// The bodies it wakes ([`WAKE_A`], [`WAKE_B`]).
    wakes: u8,
}

/// Where the contacts of pair `key` and after begin among `old` (in pair order), reading
/// only their keys and shapes.
///
/// # Safety
/// No worker may write a contact's key or shapes meanwhile.
unsafe fn first_of(old: SharedSlice<Contact>, key: u64) -> usize {
    let order = |i: usize| {
        let c = old.item(i);
        (
            std::ptr::addr_of!((*c).key).read(),
            std::ptr::addr_of!((*c).shapes).read(),
        )
    };
    let (mut lo, mut hi) = (0, old.len());
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if order(mid) < (key, 0) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Wake bits beside a [`Found`]: body A, body B.
const WAKE_A: u8 = 1 << 4;
const WAKE_B: u8 = 1 << 5;

/// The box of the body in `slot` for the broad phase: grown by `margin` (m) and by how far
/// it can travel in `dt` under `g` (see [`travel`]), which is returned beside it.
#[inline(always)]
fn proxy_of(slot: &Slot, (g, dt): (Vec2, Real), margin: Real) -> (Proxy, Travel) {
    match &slot.body {
        Some(b) => {
            let travel = if b.is_active() || b.kinematic {
                travel(b, g, dt)
            } else {
                Travel::NONE
            };
            let proxy = Proxy {
                aabb: b.aabb().inflated(margin + travel.grow).swept(travel.shift),
            };
            (proxy, travel)
        }
        None => (NO_PROXY, Travel::NONE),
    }
}

/// How far a body's broad-phase box reaches beyond its margin this step: grown by `grow` (m)
/// on every side, for how far its shapes can turn and what its acceleration adds, and swept
/// along `shift` (m), the motion its velocity foretells. A pile stirred round Box2D's
/// `spinner` at 25 m/s moves 0.4 m a step; grown by that on every side, each of its bodies
/// met 33 others, where swept it meets those it can reach.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Travel {
    /// How far the box is grown on every side for the turn and the acceleration (m).
    pub grow: Real,
    /// How far the box is swept: the step times the velocity (m).
    pub shift: Vec2,
}

impl Travel {
    /// A body that does not move.
    const NONE: Travel = Travel {
        grow: 0.0,
        shift: Vec2::ZERO,
    };
}

/// The proxy of an empty slot.
const NO_PROXY: Proxy = Proxy {
    aabb: Aabb {
        min: Vec2::ZERO,
        max: Vec2::ZERO,
    },
};

impl World {
    /// Find this step's contacts, then wake what they must wake.
    ///
    /// Points are kept up to `Settings::speculative_distance` apart, plus however far the pair
    /// can close in `dt` (so fast bodies meet the surface instead of tunnelling). A sleeping
    /// body that an awake one is about to touch wakes with its island.
    pub(super) fn find_contacts(&mut self, dt: Real, region: Option<&Region>) {
        self.update_proxies(dt, region);
        let bp = &mut self.broad_phase;
        bp.sweep
            .find_pairs(&bp.proxies, &bp.pieces, &mut bp.pair_keys, region);
        // (Tests that lower the solve's threshold lower this one with it.)
        let from = self.solver.bundles.shared_from(SHARED_PAIRS_FROM);
        let collided = match region {
            Some(region) if bp.pair_keys.len() >= from => {
                self.collide_pairs(dt, region);
                true
            }
            _ => false,
        };
        self.merge_contacts(dt, region.filter(|_| collided));
        self.wake_queued();
    }

    /// The narrow phase of the pairs of single shapes, spread over `region`'s workers, before
    /// the merge: each pair's [`Found`] (with its wake bits) into `found`, a fresh manifold
    /// into `manifolds`, and a recycled manifold straight into last step's contact (the merge
    /// then keeps it as it is). Pairs of bodies of several shapes are left to the merge.
    fn collide_pairs(&mut self, dt: Real, region: &Region) {
        let World {
            settings,
            gravity,
            bodies,
            contacts,
            broad_phase,
            joints,
            ..
        } = self;
        let pairs = PairInput::new(bodies, settings, *gravity, dt);
        let n = broad_phase.pair_keys.len();
        broad_phase.found.resize(n, 0);
        broad_phase.manifolds.resize(n, Manifold::EMPTY);
        let sorting = joints.keeps_pairs_apart() || bodies.filtered > 0 || bodies.flagged > 0;
        let blocks = n.div_ceil(PAIRS_PER_BLOCK);
        broad_phase.found_from.resize(blocks + 1, 0);
        broad_phase.steady.resize(blocks, false);
        // (Kept from step to step: a block's lists grow only while it meets more shapes.)
        if broad_phase.parts_found.len() < blocks {
            broad_phase.parts_found.resize_with(blocks, Vec::new);
            broad_phase.parts_scratch.resize_with(blocks, Vec::new);
        }
        broad_phase.tier_found.resize(n, TierInput::NONE);
        let keys = &broad_phase.pair_keys;
        let (joints, bodies) = (&*joints, &*bodies);
        let kept_apart = |key| sorting && !(filters_allow(key, bodies) && joints.may_collide(key));
        // SAFETY: each block writes its own run of `found`, `manifolds`, `tier_found`,
        // `found_from` and `steady`, and only the contacts of its own pairs (contacts are
        // ordered by pair, and a pair is one block's); the first stage only reads the
        // contacts' keys.
        let (found, manifolds, old, from, steady, tier_found) = unsafe {
            (
                SharedSlice::new(&mut broad_phase.found),
                SharedSlice::new(&mut broad_phase.manifolds),
                SharedSlice::new(&mut contacts.awake),
                SharedSlice::new(&mut broad_phase.found_from),
                SharedSlice::new(&mut broad_phase.steady),
                SharedSlice::new(&mut broad_phase.tier_found),
            )
        };
        // SAFETY: as above, block k's lists are its own.
        let (parts_found, parts_scratch) = unsafe {
            (
                SharedSlice::new(&mut broad_phase.parts_found),
                SharedSlice::new(&mut broad_phase.parts_scratch),
            )
        };
        // Where each block's pairs' contacts begin (a search each, reading keys only: no
        // block holds any contact yet).
        region.for_blocks(blocks, &|k| {
            // SAFETY: as above.
            let start = unsafe { first_of(old, keys[k * PAIRS_PER_BLOCK]) };
            *unsafe { from.get(k) }.expect("a block's start") = start;
        });
        *unsafe { from.get(blocks) }.expect("the end") = old.len();
        region.for_blocks(blocks, &|k| {
            let run = block(k, PAIRS_PER_BLOCK, n);
            // SAFETY: as above; the run of contacts from this block's start to the next's is
            // this block's alone.
            let (found, manifolds, old, tier_found) = unsafe {
                let (lo, hi) = (*from.item(k), *from.item(k + 1));
                (
                    found.range(run.clone()),
                    manifolds.range(run.clone()),
                    old.range(lo..hi),
                    tier_found.range(run.clone()),
                )
            };
            // SAFETY: as above.
            let parts = unsafe { (parts_scratch.get(k), parts_found.get(k)) };
            let (scratch, parts) = (parts.0.expect("a block's"), parts.1.expect("a block's"));
            let out = BlockOut {
                found,
                manifolds,
                tier_found,
                parts,
                scratch,
            };
            let is_steady = pairs.collide_block(&keys[run], old, out, &kept_apart);
            // SAFETY: as above.
            *unsafe { steady.get(k) }.expect("a block's flag") = is_steady;
        });
    }

    /// Each body's box grown by half the speculative distance and swept by how far it can
    /// travel this step, and that travel (spread over `region`'s workers if given).
    fn update_proxies(&mut self, dt: Real, region: Option<&Region>) {
        let g = self.gravity;
        let margin = 0.5 * self.settings.speculative_distance;
        let proxy = |slot: &Slot| proxy_of(slot, (g, dt), margin);
        let slots = &self.bodies.slots;
        let (proxies, reach) = (&mut self.broad_phase.proxies, &mut self.broad_phase.reach);
        let n = slots.len();
        proxies.resize(n, NO_PROXY);
        reach.resize(n, Travel::NONE);
        let fill = |proxies: &mut [Proxy], reach: &mut [Travel], slots: &[Slot]| {
            for ((p, r), slot) in proxies.iter_mut().zip(reach).zip(slots) {
                (*p, *r) = proxy(slot);
            }
        };
        match region {
            Some(region) => {
                // SAFETY: each block writes its own run of the proxies and of the reaches.
                let (proxies, reach) =
                    unsafe { (SharedSlice::new(proxies), SharedSlice::new(reach)) };
                region.for_blocks(n.div_ceil(PROXIES_PER_BLOCK), &|k| {
                    let run = block(k, PROXIES_PER_BLOCK, n);
                    // SAFETY: as above.
                    let (p, r) = unsafe { (proxies.range(run.clone()), reach.range(run.clone())) };
                    fill(p, r, &slots[run]);
                });
            }
            None => fill(proxies, reach, slots),
        }
        self.update_pieces(margin);
    }

    /// The shapes' boxes of the static bodies swept shape by shape, grown by `margin` (m) as
    /// their proxies are.
    fn update_pieces(&mut self, margin: Real) {
        let bp = &mut self.broad_phase;
        bp.pieces.clear();
        for &slot in &bp.pieced_slots {
            let Some(body) = &self.bodies.slots[slot as usize].body else {
                continue;
            };
            let Some(parts) = body.compound() else {
                continue;
            };
            let frame = body.frame();
            bp.pieces.extend(parts.all.iter().map(|part| Piece {
                slot,
                aabb: part.aabb(frame).inflated(margin),
            }));
        }
    }

    /// Walk the candidate pairs in key order beside last step's contacts: each pair's contact
    /// updated or begun, the pairs no longer in contact ended.
    fn merge_contacts(&mut self, dt: Real, collided: Option<&Region>) {
        let World {
            settings,
            gravity,
            bodies,
            contacts,
            broad_phase,
            tiers,
            islands,
            joints,
            ..
        } = self;
        let pairs = PairInput::new(bodies, settings, *gravity, dt);
        tiers.inputs.clear();
        let mut merge = Merge::begin(contacts);
        // Pairs kept apart by a joint, by their filters or by a sensor keep no contact (any
        // they had ends here); a World with none pays one test per step for it.
        let sorting = joints.keeps_pairs_apart() || bodies.filtered > 0 || bodies.flagged > 0;
        let keys = &broad_phase.pair_keys;
        if let Some(region) = collided {
            merge.defer = true;
            for (k, run) in keys.chunks(PAIRS_PER_BLOCK).enumerate() {
                let start = k * PAIRS_PER_BLOCK;
                if broad_phase.steady[k] {
                    let found = (&*broad_phase, &mut tiers.inputs);
                    keep_steady(&mut merge, contacts, found, start..start + run.len());
                    continue;
                }
                let mut parts = broad_phase.parts_found[k].iter().peekable();
                for (p, &key) in (start..).zip(run) {
                    let bp = &*broad_phase;
                    let found = (bp.found[p], &bp.manifolds[p], bp.tier_found[p]);
                    let wake = &mut islands.wake_queue;
                    let out = (&mut merge, &mut *contacts, wake);
                    match pairs.merge_found(key, found, out) {
                        Some(Some(input)) => tiers.inputs.push(input),
                        Some(None) => {}
                        None => {
                            // Bodies of several shapes: what the workers found for each pair
                            // of their shapes, in order.
                            let (a, b) = pairs.bodies(key).expect("a pair with bodies");
                            while let Some(part) = parts.next_if(|f| f.key == key) {
                                let wake = &mut islands.wake_queue;
                                let out = (&mut merge, &mut *contacts, wake);
                                if let Some(input) = pairs.update_found(part, (a, b), out) {
                                    tiers.inputs.push(input);
                                }
                            }
                        }
                    }
                }
            }
            merge.end(contacts, Some(region));
            return;
        }
        let ahead = if sorting {
            2 * FETCH_AHEAD
        } else {
            FETCH_AHEAD
        };
        for (p, &key) in keys.iter().enumerate() {
            if let Some(&next) = keys.get(p + ahead) {
                pairs.fetch(next);
            }
            if let Some(&near) = keys.get(p + FETCH_AHEAD).filter(|_| sorting) {
                pairs.fetch_extras(near);
            }
            if sorting && !(filters_allow(key, bodies) && joints.may_collide(key)) {
                continue;
            }
            let Some((a, b)) = pairs.bodies(key) else {
                continue;
            };
            let wake = &mut islands.wake_queue;
            if a.compound().is_none() && b.compound().is_none() {
                let sides = (Side::whole(a), Side::whole(b));
                if let Some(input) = pairs.update((key, 0), sides, &mut merge, contacts, wake) {
                    tiers.inputs.push(input);
                }
            } else {
                let out = (wake, &mut tiers.inputs, &mut broad_phase.shape_pairs);
                pairs.update_parts(key, (a, b), &mut merge, contacts, out);
            }
        }
        merge.end(contacts, None);
    }
}

/// The contacts of a steady block of `pairs` ([`BroadPhase::steady`]: none begins, and
/// each of last step's in its run was made in place by a worker) kept as one run, and their
/// tier inputs as the workers found them.
fn keep_steady(
    merge: &mut Merge,
    contacts: &mut Contacts,
    (bp, inputs): (&BroadPhase, &mut Vec<TierInput>),
    pairs: std::ops::Range<usize>,
) {
    let found = &bp.found[pairs.clone()];
    let start = pairs.start;
    let mut kept = pairs.filter(|p| found[p - start] == Found::InPlace as u8);
    if let Some(first) = kept.next() {
        merge.seek(contacts, (bp.pair_keys[first], 0));
        let before = inputs.len();
        let found = std::iter::once(first).chain(kept);
        inputs.extend(found.map(|p| bp.tier_found[p]));
        merge.keep_run(contacts, inputs.len() - before);
    }
}

/// One side of a pair: a body, and the shape of it that touches (its own, or one of several)
/// with that shape's pose in the world and its material.
#[derive(Clone, Copy)]
struct Side<'a> {
    body: &'a Body,
    shape: &'a Shape,
    pose: Transform,
    friction: Real,
    restitution: Real,
}

impl<'a> Side<'a> {
    /// A body of one shape.
    #[inline(always)]
    fn whole(body: &'a Body) -> Side<'a> {
        Side {
            body,
            shape: &body.shape,
            pose: body.frame(),
            friction: body.friction,
            restitution: body.restitution,
        }
    }

    /// Shape `i` of `body` (0 its own, or the first of its parts), with its filter.
    fn of(body: &'a Body, i: u32) -> (Side<'a>, Filter) {
        match body.compound() {
            None => (Side::whole(body), body.filter()),
            Some(parts) => {
                let part = &parts.all[i as usize];
                let side = Side {
                    body,
                    shape: &part.shape,
                    pose: body.frame().then(part.pose),
                    friction: part.friction,
                    restitution: part.restitution,
                };
                (side, part.filter)
            }
        }
    }

    /// Each shape of `body`, with its index.
    fn each(body: &'a Body) -> impl Iterator<Item = (u32, Side<'a>)> + 'a {
        let count = body.compound().map_or(1, |p| p.all.len() as u32);
        (0..count).map(move |i| (i, Side::of(body, i).0))
    }

    /// The shape's box in the world.
    fn aabb(&self) -> Aabb {
        self.shape.aabb(self.pose)
    }
}

/// The pairs of shapes of bodies `a` and `b` whose boxes may meet (A's grown by `margin`), as
/// `i << 16 | j`, sorted: through a body's [`crate::physics::part_tree::PartTree`] when it has
/// one (the other body's shapes query it), else every pair.
fn shape_pairs(a: &Body, b: &Body, margin: Real, out: &mut Vec<u32>) {
    fn tree(x: &Body) -> Option<&PartTree> {
        x.compound().and_then(|p| p.tree.as_ref())
    }
    out.clear();
    if let Some(tb) = tree(b) {
        for (i, sa) in Side::each(a) {
            let start = out.len();
            tb.query(b.frame(), &sa.aabb().inflated(margin), out);
            out[start..].iter_mut().for_each(|j| *j |= i << 16);
        }
    } else if let Some(ta) = tree(a) {
        for (j, sb) in Side::each(b) {
            let start = out.len();
            ta.query(a.frame(), &sb.aabb().inflated(margin), out);
            out[start..].iter_mut().for_each(|i| *i = *i << 16 | j);
        }
    } else {
        for (i, sa) in Side::each(a) {
            let box_a = sa.aabb().inflated(margin);
            for (j, sb) in Side::each(b) {
                if box_a.overlaps(&sb.aabb()) {
                    out.push(i << 16 | j);
                }
            }
        }
        return;
    }
    out.sort_unstable();
}

/// Whether the filters of pair `key`'s bodies let them collide, and neither is a sensor.
pub(super) fn filters_allow(key: u64, bodies: &Bodies) -> bool {
    if bodies.filtered == 0 && bodies.flagged == 0 {
        return true;
    }
    let (a, b) = pair_of(key);
    // A body of several shapes has a filter and flags per shape, tested shape by shape.
    let own = |i: u32| {
        let body = bodies.slots[i as usize].body.as_ref()?;
        body.compound()
            .is_none()
            .then(|| (body.filter(), body.flags().sensor))
    };
    match (own(a), own(b)) {
        (Some((fa, sa)), Some((fb, sb))) => !sa && !sb && fa.should_collide(&fb),
        (Some((_, true)), _) | (_, Some((_, true))) => false,
        _ => true,
    }
}

/// Whether shape `i` of a body of several is a sensor.
fn is_sensor(body: &Body, i: u32) -> bool {
    body.compound()
        .map_or_else(|| body.flags().sensor, |p| p.all[i as usize].flags.sensor)
}

/// Where the merge stands: in place (this step's contacts are `awake[..written]`, last
/// step's the rest) or copying (this step's are pushed to a fresh `awake`, last step's are
/// `previous[read..]`). Copying after the workers' narrow phase (`defer`), this step's
/// contacts are noted as runs of last step's and of those written, and the workers copy
/// them into `awake` at the end: a contact that begins early in key order turns the rest of
/// the walk into copies (4.6 MB a step in Box2D's `spinner`), which would otherwise run on
/// this thread alone.
struct Merge {
    in_place: bool,
    written: usize,
    read: usize,
    defer: bool,
}

/// A run of this step's contacts while the merge defers its copies.
#[derive(Clone, Copy, Debug)]
pub(super) enum Run {
    /// Last step's `previous[from..from + len]`, as they are.
    Kept { from: u32, len: u32 },
    /// Contacts the merge wrote, `Contacts::written[from..from + len]`.
    Written { from: u32, len: u32 },
}

impl Run {
    fn len(self) -> usize {
        match self {
            Run::Kept { len, .. } | Run::Written { len, .. } => len as usize,
        }
    }
}

/// Contacts a worker copies at a time at the end of a deferred merge.
const COPIED_PER_BLOCK: usize = 512;

impl Merge {
    /// Start the walk, in place (tests may ask to copy from the start).
    fn begin(contacts: &mut Contacts) -> Merge {
        #[cfg_attr(not(test), allow(unused_mut))]
        let mut merge = Merge {
            in_place: true,
            written: 0,
            read: 0,
            defer: false,
        };
        #[cfg(test)]
        if contacts.copy_for_tests {
            merge.copy_from_here(contacts);
        }
        #[cfg(not(test))]
        let _ = contacts;
        merge
    }

    /// Stop writing in place: last step's contacts become `previous` (those before `written`
    /// already overwritten by this step's), and this step's so far are copied to `awake`
    /// (noted, when deferred).
    fn copy_from_here(&mut self, contacts: &mut Contacts) {
        std::mem::swap(&mut contacts.awake, &mut contacts.previous);
        contacts.awake.clear();
        contacts.runs.clear();
        contacts.written.clear();
        if self.defer {
            Merge::note_kept(contacts, 0, self.written);
        } else {
            contacts
                .awake
                .extend_from_slice(&contacts.previous[..self.written]);
        }
        (self.in_place, self.read) = (false, self.written);
    }

    /// Note `previous[from..from + n]` as this step's next contacts (a deferred copy).
    fn note_kept(contacts: &mut Contacts, from: usize, n: usize) {
        if n == 0 {
            return;
        }
        let (from, len) = (from as u32, n as u32);
        match contacts.runs.last_mut() {
            Some(Run::Kept { from: f, len: l }) if *f + *l == from => *l += len,
            _ => contacts.runs.push(Run::Kept { from, len }),
        }
    }

    /// Note `contact` as this step's next contact (a deferred copy); it can still be updated.
    fn note_written(contacts: &mut Contacts, contact: Contact) -> &mut Contact {
        let from = contacts.written.len() as u32;
        contacts.written.push(contact);
        match contacts.runs.last_mut() {
            Some(Run::Written { from: f, len: l }) if *f + *l == from => *l += 1,
            _ => contacts.runs.push(Run::Written { from, len: 1 }),
        }
        contacts.written.last_mut().expect("just pushed")
    }

    /// Move to `key` among last step's contacts, ending those passed over; whether last step
    /// had a contact for `key` ([`Merge::last`]).
    #[inline(always)]
    fn seek(&mut self, contacts: &mut Contacts, order: (u64, u32)) -> bool {
        if self.in_place
            && contacts
                .awake
                .get(self.written)
                .is_some_and(|c| c.order() < order)
        {
            self.copy_from_here(contacts);
        }
        if self.in_place {
            return contacts
                .awake
                .get(self.written)
                .is_some_and(|c| c.order() == order);
        }
        while let Some(gone) = contacts
            .previous
            .get(self.read)
            .filter(|c| c.order() < order)
        {
            contacts.graph.remove(gone.colour, [gone.a, gone.b]);
            self.read += 1;
        }
        contacts
            .previous
            .get(self.read)
            .is_some_and(|c| c.order() == order)
    }

    /// Last step's contact for the key just sought (only after [`Merge::seek`] said there is
    /// one).
    fn last<'c>(&self, contacts: &'c Contacts) -> &'c Contact {
        if self.in_place {
            &contacts.awake[self.written]
        } else {
            &contacts.previous[self.read]
        }
    }

    /// Keep last step's contact for this key as this step's, to be updated in place.
    fn keep<'c>(&mut self, contacts: &'c mut Contacts) -> &'c mut Contact {
        if self.in_place {
            self.written += 1;
            &mut contacts.awake[self.written - 1]
        } else if self.defer {
            self.read += 1;
            let contact = contacts.previous[self.read - 1];
            Merge::note_written(contacts, contact)
        } else {
            contacts.awake.push(contacts.previous[self.read]);
            self.read += 1;
            contacts.awake.last_mut().expect("just pushed")
        }
    }

    /// Keep last step's contact for this key as this step's, as it is.
    fn keep_as_is(&mut self, contacts: &mut Contacts) {
        self.keep_run(contacts, 1);
    }

    /// Keep the next `n` of last step's contacts as this step's, as they are (the key of the
    /// first just sought).
    fn keep_run(&mut self, contacts: &mut Contacts, n: usize) {
        if self.in_place {
            self.written += n;
        } else if self.defer {
            Merge::note_kept(contacts, self.read, n);
            self.read += n;
        } else {
            let run = self.read..self.read + n;
            contacts.awake.extend_from_slice(&contacts.previous[run]);
            self.read += n;
        }
    }

    /// Write `contact`, which begins this step, as this step's for its key: it takes a colour
    /// (`dynamic`: which of its two bodies are nodes of the graph). (A contact that goes on
    /// is [`Merge::keep`]'s, made over in place.)
    fn write(&mut self, contacts: &mut Contacts, mut contact: Contact, dynamic: [bool; 2]) {
        contact.colour = contacts.graph.add([contact.a, contact.b], dynamic);
        if self.in_place && self.written < contacts.awake.len() {
            // A new contact before last step's others: from here, copying.
            self.copy_from_here(contacts);
        }
        if self.in_place {
            // Appended after last step's contacts, all of them passed.
            contacts.awake.push(contact);
            self.written += 1;
        } else if self.defer {
            Merge::note_written(contacts, contact);
        } else {
            contacts.awake.push(contact);
        }
    }

    /// Finish the walk: last step's contacts not reached are gone; deferred copies are made
    /// on `region`'s workers.
    fn end(self, contacts: &mut Contacts, region: Option<&Region>) {
        let gone = if self.in_place {
            &contacts.awake[self.written..]
        } else {
            &contacts.previous[self.read..]
        };
        for c in gone {
            contacts.graph.remove(c.colour, [c.a, c.b]);
        }
        if self.in_place {
            contacts.awake.truncate(self.written);
        } else if self.defer {
            copy_runs(contacts, region);
        }
    }
}

/// A deferred merge's runs copied into `awake` (empty), in blocks of [`COPIED_PER_BLOCK`]
/// spread over `region`'s workers (on this thread without one).
fn copy_runs(contacts: &mut Contacts, region: Option<&Region>) {
    let Contacts {
        awake,
        previous,
        runs,
        written,
        run_starts,
        ..
    } = contacts;
    run_starts.clear();
    run_starts.push(0);
    let mut total = 0;
    for run in runs.iter() {
        total += run.len();
        run_starts.push(total as u32);
    }
    debug_assert!(awake.is_empty(), "a deferred merge writes a fresh array");
    awake.reserve(total);
    let (runs, run_starts) = (&*runs, &*run_starts);
    let (previous, written) = (&*previous, &*written);
    // Contacts `range` of this step's into `out` (as many).
    let copy = |range: std::ops::Range<usize>, out: &mut [std::mem::MaybeUninit<Contact>]| {
        let mut k = run_starts.partition_point(|&s| s as usize <= range.start) - 1;
        let mut at = range.start;
        while at < range.end {
            let (start, end) = (run_starts[k] as usize, run_starts[k + 1] as usize);
            let n = end.min(range.end) - at;
            let source = match runs[k] {
                Run::Kept { from, .. } => &previous[from as usize..],
                Run::Written { from, .. } => &written[from as usize..],
            };
            let source = &source[at - start..at - start + n];
            let to = &mut out[at - range.start..at - range.start + n];
            for (to, from) in to.iter_mut().zip(source) {
                to.write(*from);
            }
            (at, k) = (at + n, k + 1);
        }
    };
    let spare = &mut awake.spare_capacity_mut()[..total];
    match region {
        None => copy(0..total, spare),
        Some(region) => {
            // SAFETY: each block writes its own run of the new contacts.
            let out = unsafe { SharedSlice::new(spare) };
            region.for_blocks(total.div_ceil(COPIED_PER_BLOCK), &|b| {
                let range = block(b, COPIED_PER_BLOCK, total);
                // SAFETY: as above.
                copy(range.clone(), unsafe { out.range(range) });
            });
        }
    }
    // SAFETY: every one of the first `total` was written just above.
    unsafe { awake.set_len(total) };
}

/// What updating a pair's contact reads.
struct PairInput<'a> {
    slots: &'a [Slot],
    /// Whether any body has flags (a sensor among them, maybe).
    flagged: bool,
    settings: &'a Settings,
    gravity: Vec2,
    dt: Real,
}

impl<'a> PairInput<'a> {
    /// What a step of `dt` s under `gravity` (m/s^2) reads of `bodies` and `settings`.
    fn new(bodies: &'a Bodies, settings: &'a Settings, gravity: Vec2, dt: Real) -> Self {
        PairInput {
            slots: &bodies.slots,
            flagged: bodies.flagged > 0,
            settings,
            gravity,
            dt,
        }
    }

    /// Start loading the bodies of pair `key` into the cache (a hint; nothing is read): the
    /// pairs come in key order, body A's ascending and B's from all over the array.
    #[inline(always)]
    fn fetch(&self, key: u64) {
        let (ia, ib) = pair_of(key);
        for i in [ia, ib] {
            if let Some(slot) = self.slots.get(i as usize) {
                prefetch(slot);
            }
        }
    }

    /// Start loading the extras (filters, parts) of the bodies of pair `key`, out of line on
    /// the heap: a filtered world tests every pair's filters, and most pairs of a pile of
    /// ragdolls are refused at once, too soon for a load begun there to arrive. Reads the
    /// bodies, which [`PairInput::fetch`] fetched some pairs before.
    #[inline(always)]
    fn fetch_extras(&self, key: u64) {
        let (ia, ib) = pair_of(key);
        for i in [ia, ib] {
            let body = self.slots.get(i as usize).and_then(|s| s.body.as_ref());
            if let Some(extras) = body.and_then(|b| b.extras.as_deref()) {
                prefetch(extras);
            }
        }
    }

    /// The live bodies of pair `key`, unless neither can move (a kinematic body meets static
    /// and kinematic ones without a contact).
    #[inline(always)]
    fn bodies(&self, key: u64) -> Option<(&'a Body, &'a Body)> {
        let (ia, ib) = pair_of(key);
        let (Some(a), Some(b)) = (&self.slots[ia as usize].body, &self.slots[ib as usize].body)
        else {
            return None;
        };
        (a.inv_mass > 0.0 || b.inv_mass > 0.0).then_some((a, b))
    }

    /// The contacts of a pair of which one body or both have several shapes: each pair of
    /// shapes whose boxes meet (grown as the bodies' proxies are) and whose filters allow it,
    /// in shape order (`found`: scratch). Kept out of the loop over plain pairs: cold.
    #[cold]
    #[inline(never)]
    fn update_parts(
        &self,
        key: u64,
        (a, b): (&Body, &Body),
        merge: &mut Merge,
        contacts: &mut Contacts,
        (wake, inputs, found): (&mut Vec<u32>, &mut Vec<TierInput>, &mut Vec<u32>),
    ) {
        for (ij, sa, sb) in self.touching_parts((a, b), found) {
            if let Some(input) = self.update((key, ij), (sa, sb), merge, contacts, wake) {
                inputs.push(input);
            }
        }
    }

    /// The pairs of shapes of `a` and `b` whose boxes meet within the margin and that may
    /// collide (filters, sensors), each as `i << 16 | j` with its two sides, in order
    /// (`scratch`: the candidates).
    fn touching_parts<'b>(
        &'b self,
        (a, b): (&'b Body, &'b Body),
        scratch: &'b mut Vec<u32>,
    ) -> impl Iterator<Item = (u32, Side<'b>, Side<'b>)> + 'b {
        let margin =
            self.settings.speculative_distance + closing_reach(a, b, self.gravity, self.dt);
        shape_pairs(a, b, margin, scratch);
        scratch.iter().filter_map(move |&ij| {
            let ((sa, fa), (sb, fb)) = (Side::of(a, ij >> 16), Side::of(b, ij & 0xffff));
            let meet = fa.should_collide(&fb) && sa.aabb().inflated(margin).overlaps(&sb.aabb());
            let sensed = || self.flagged && (is_sensor(a, ij >> 16) || is_sensor(b, ij & 0xffff));
            (meet && !sensed()).then_some((ij, sa, sb))
        })
    }

    /// The first half of [`PairInput::update_parts`] for pair `key`, run by the workers
    /// before the merge: each pair of shapes that may touch, with last step's manifold
    /// recycled or a fresh one, pushed onto `out` (reading last step's contacts `old`, in
    /// order, and nothing else; `scratch`: the pairs of shapes).
    fn collide_parts_first(
        &self,
        key: u64,
        old: &[Contact],
        (scratch, out): (&mut Vec<u32>, &mut Vec<PartFound>),
    ) {
        let (a, b) = self.bodies(key).expect("a pair with bodies");
        for (ij, sa, sb) in self.touching_parts((a, b), scratch) {
            let order = (key, ij);
            let last = old.get(old.partition_point(|c| c.order() < order));
            let last = last.filter(|c| c.order() == order);
            let (recycled, manifold, wakes) = match last.and_then(|c| self.recycled(c, a, b)) {
                Some(manifold) => (true, manifold, 0),
                None => match self.collide_pair((sa, sb)) {
                    (Some(manifold), wakes) => (false, manifold, wakes),
                    (None, _) => (false, Manifold::EMPTY, 0),
                },
            };
            out.push(PartFound {
                key,
                shapes: ij,
                recycled,
                manifold,
                wakes,
            });
        }
    }

    /// The second half, in the merge: what the workers `found` for a pair of shapes of `a`
    /// and `b`, written as [`PairInput::update`] would.
    fn update_found(
        &self,
        found: &PartFound,
        (a, b): (&Body, &Body),
        (merge, contacts, wake_queue): (&mut Merge, &mut Contacts, &mut Vec<u32>),
    ) -> Option<TierInput> {
        let (order, ij) = ((found.key, found.shapes), found.shapes);
        let sides = (Side::of(a, ij >> 16).0, Side::of(b, ij & 0xffff).0);
        let continued = merge.seek(contacts, order);
        let slop = self.settings.linear_slop;
        if found.recycled {
            debug_assert!(continued, "a recycled contact was last step's");
            let contact = merge.keep(contacts);
            self.set_geometry(contact, &found.manifold, sides);
            return Some(TierInput::of(contact, slop));
        }
        let (ia, ib) = pair_of(found.key);
        for (bit, i) in [(WAKE_A, ia), (WAKE_B, ib)] {
            if found.wakes & bit != 0 {
                wake_queue.push(i);
            }
        }
        if found.manifold.count == 0 {
            return None;
        }
        if continued {
            let contact = merge.keep(contacts);
            self.refresh(contact, &found.manifold, sides);
            return Some(TierInput::of(contact, slop));
        }
        let contact = self.fresh_contact(order, &found.manifold, sides);
        let input = TierInput::of(&contact, slop);
        merge.write(contacts, contact, [a.inv_mass > 0.0, b.inv_mass > 0.0]);
        Some(input)
    }

    /// The contact of shapes `sides` (`order`: their pair key and shapes) this step: last
    /// step's with its manifold recycled, or the pair collided afresh (waking sleepers it is
    /// about to touch), or none. Returns what adaptive stiffness reads of the contact written.
    #[inline(always)]
    fn update(
        &self,
        order: (u64, u32),
        (sa, sb): (Side, Side),
        merge: &mut Merge,
        contacts: &mut Contacts,
        wake_queue: &mut Vec<u32>,
    ) -> Option<TierInput> {
        let (a, b) = (sa.body, sb.body);
        let continued = merge.seek(contacts, order);
        let slop = self.settings.linear_slop;
        if continued {
            if let Some(manifold) = self.recycled(merge.last(contacts), a, b) {
                let contact = merge.keep(contacts);
                self.set_geometry(contact, &manifold, (sa, sb));
                return Some(TierInput::of(contact, slop));
            }
        }
        let manifold = self.collide((sa, sb), pair_of(order.0), wake_queue)?;
        if continued {
            let contact = merge.keep(contacts);
            self.refresh(contact, &manifold, (sa, sb));
            return Some(TierInput::of(contact, slop));
        }
        let contact = self.fresh_contact(order, &manifold, (sa, sb));
        let input = TierInput::of(&contact, slop);
        merge.write(contacts, contact, [a.inv_mass > 0.0, b.inv_mass > 0.0]);
        Some(input)
    }

    /// Last step's manifold of `c`, moved with its bodies, if the pair may recycle it: only
    /// between awake dynamic bodies and bodies that do not move (static, or kinematic at
    /// rest), so there is nothing to wake and no motion the solver does not see.
    #[inline(always)]
    fn recycled(&self, c: &Contact, a: &Body, b: &Body) -> Option<Manifold> {
        let steady = |x: &Body| x.is_active() || (x.inv_mass == 0.0 && !x.is_moving_kinematic());
        if !(self.settings.contact_recycling && steady(a) && steady(b)) {
            return None;
        }
        let size = a.bounding_radius.min(b.bounding_radius);
        let max_drift = RECYCLE_DRIFT.min(RECYCLE_SIZE * size);
        recycle(c, a.frame(), b.frame(), max_drift)
    }

    /// A recycled contact's new geometry: the same points, moved (everything else in it is
    /// worked out again by the solver's prepare stage).
    #[inline(always)]
    fn set_geometry(&self, contact: &mut Contact, manifold: &Manifold, (sa, sb): (Side, Side)) {
        let mixing = (
            self.settings.friction_mixing,
            self.settings.restitution_mixing,
        );
        let (a, b) = (sa.body, sb.body);
        contact.normal = manifold.normal;
        contact.friction = mixing.0.mix(sa.friction, sb.friction);
        contact.restitution = mixing.1.mix(sa.restitution, sb.restitution);
        contact.age = contact.age.saturating_add(1);
        for (cp, mp) in contact.points.iter_mut().zip(manifold.points()) {
            cp.point = mp.point;
            cp.separation = mp.separation;
            cp.anchor_a = mp.point - a.position;
            cp.anchor_b = mp.point - b.position;
        }
    }

    /// The pair's manifold, collided afresh, or None when it has no point or nothing to solve.
    /// A sleeping body wakes only if the gap can close this step: a speculative point farther
    /// out treats the sleeper as fixed (waking on it made a body resting 2 cm from an awake
    /// neighbour sleep and wake every 0.5 s forever). A kinematic body at rest wakes nothing.
    /// Inlined, as it was when it had one caller: called, its manifold and sides went through
    /// memory.
    #[inline(always)]
    fn collide(
        &self,
        sides: (Side, Side),
        (ia, ib): (u32, u32),
        wake_queue: &mut Vec<u32>,
    ) -> Option<Manifold> {
        let (manifold, wakes) = self.collide_pair(sides);
        for (bit, i) in [(WAKE_A, ia), (WAKE_B, ib)] {
            if wakes & bit != 0 {
                wake_queue.push(i);
            }
        }
        manifold
    }

    /// [`PairInput::collide`], with the bodies to wake as bits ([`WAKE_A`], [`WAKE_B`]).
    #[inline(always)]
    fn collide_pair(&self, (sa, sb): (Side, Side)) -> (Option<Manifold>, u8) {
        let (a, b) = (sa.body, sb.body);
        let (g, dt) = (self.gravity, self.dt);
        let reach = closing_reach(a, b, g, dt);
        let margin = self.settings.speculative_distance + reach;
        // Bodies whose bounding circles are farther apart than the margin have no point within
        // it: their boxes met only because one is swept or turned past the other.
        let apart = a.bounding_radius + b.bounding_radius + margin;
        if (b.position - a.position).length_squared() > apart * apart {
            return (None, 0);
        }
        let manifold = collide(sa.shape, sa.pose, sb.shape, sb.pose, margin);
        if manifold.count == 0 {
            return (None, 0);
        }
        let nearest = manifold
            .points()
            .iter()
            .map(|p| p.separation)
            .fold(Real::INFINITY, Real::min);
        let resting_kinematic = |x: &Body| x.kinematic && !x.is_moving_kinematic();
        let mut wakes = 0;
        if nearest <= reach + self.settings.linear_slop
            && !resting_kinematic(a)
            && !resting_kinematic(b)
        {
            for (bit, body) in [(WAKE_A, a), (WAKE_B, b)] {
                if !body.awake {
                    wakes |= bit;
                }
            }
        }
        // A sleeper beside a kinematic body at rest: nothing to solve.
        let solve = a.is_active() || b.is_active() || wakes != 0;
        (solve.then_some(manifold), wakes)
    }

    /// One block of pairs `keys` on a worker, against its run `old` of last step's contacts,
    /// into `out` ([`PairInput::collide_first`] and [`PairInput::collide_parts_first`] for
    /// each pair not `kept_apart`). Returns whether the block is steady: nothing for the merge
    /// to make, and every one of last step's contacts in the run one of the pairs' made in
    /// place (each such pair has its own), so none ended (pairs with nothing to keep may come
    /// between).
    fn collide_block(
        &self,
        keys: &[u64],
        old: &mut [Contact],
        out: BlockOut,
        kept_apart: &impl Fn(u64) -> bool,
    ) -> bool {
        out.parts.clear();
        let slop = self.settings.linear_slop;
        let (mut at, mut in_place, mut fresh) = (0, 0, false);
        let pairs_found = out.found.iter_mut().zip(out.manifolds).zip(out.tier_found);
        for (&key, ((f, m), t)) in keys.iter().zip(pairs_found) {
            *f = if kept_apart(key) {
                Found::Skip as u8
            } else {
                self.collide_first(key, (old, &mut at), m)
            };
            if *f == Found::Parts as u8 {
                self.collide_parts_first(key, old, (out.scratch, out.parts));
            }
            let kind = *f & !(WAKE_A | WAKE_B);
            if kind == Found::InPlace as u8 {
                *t = TierInput::of(&old[at], slop);
                in_place += 1;
            }
            fresh |= kind == Found::Fresh as u8 || kind == Found::Parts as u8;
        }
        !fresh && in_place == old.len()
    }

    /// The first half of [`PairInput::update`] for pair `key`, run by the workers before the
    /// merge: last step's contact for it (found from `at` on among the `old` contacts, which
    /// are in pair order) recycled in place, or the pair collided afresh into `out`. Returns
    /// the [`Found`] with the wake bits above it.
    #[inline(always)]
    fn collide_first(
        &self,
        key: u64,
        (old, at): (&mut [Contact], &mut usize),
        out: &mut Manifold,
    ) -> u8 {
        let Some((a, b)) = self.bodies(key) else {
            return Found::Skip as u8;
        };
        if a.compound().is_some() || b.compound().is_some() {
            return Found::Parts as u8;
        }
        let order = (key, 0);
        while old.get(*at).is_some_and(|c| c.order() < order) {
            *at += 1;
        }
        let sides = (Side::whole(a), Side::whole(b));
        let mut last = old.get_mut(*at).filter(|c| c.order() == order);
        if let Some(last) = last.as_deref_mut() {
            if let Some(manifold) = self.recycled(last, a, b) {
                self.set_geometry(last, &manifold, sides);
                return Found::InPlace as u8;
            }
        }
        match self.collide_pair(sides) {
            // A contact that goes on, and wakes nothing: made here, as the merge would make it
            // (on one thread, the merge made these: 1.7 ms of a 14 ms step of many_pyramids
            // with two workers).
            (Some(manifold), 0) if last.is_some() => {
                let last = last.expect("a contact that goes on");
                self.refresh(last, &manifold, sides);
                Found::InPlace as u8
            }
            (Some(manifold), wakes) => {
                *out = manifold;
                Found::Fresh as u8 | wakes
            }
            (None, _) => Found::Nothing as u8,
        }
    }

    /// The second half of [`PairInput::update`], in the merge: what the workers found for pair
    /// `key` (`found`, and its fresh `manifold`) written as this step's contact. None for a
    /// pair of bodies of several shapes (the merge collides those itself); else what adaptive
    /// stiffness reads of the contact written, if any.
    #[inline(always)]
    fn merge_found(
        &self,
        key: u64,
        (found, manifold, in_place): (u8, &Manifold, TierInput),
        (merge, contacts, wake_queue): (&mut Merge, &mut Contacts, &mut Vec<u32>),
    ) -> Option<Option<TierInput>> {
        let order = (key, 0);
        let slop = self.settings.linear_slop;
        let kind = found & !(WAKE_A | WAKE_B);
        if kind == Found::Skip as u8 {
            return Some(None);
        }
        if kind == Found::Parts as u8 {
            return None;
        }
        let continued = merge.seek(contacts, order);
        if kind == Found::InPlace as u8 {
            debug_assert!(continued, "a contact updated in place was last step's");
            merge.keep_as_is(contacts);
            return Some(Some(in_place));
        }
        if kind == Found::Nothing as u8 {
            return Some(None);
        }
        let (ia, ib) = pair_of(key);
        for (bit, i) in [(WAKE_A, ia), (WAKE_B, ib)] {
            if found & bit != 0 {
                wake_queue.push(i);
            }
        }
        let (a, b) = self.bodies(key).expect("a pair with bodies");
        let sides = (Side::whole(a), Side::whole(b));
        if continued {
            let contact = merge.keep(contacts);
            self.refresh(contact, manifold, sides);
            return Some(Some(TierInput::of(contact, slop)));
        }
        let contact = self.fresh_contact(order, manifold, sides);
        let input = TierInput::of(&contact, slop);
        merge.write(contacts, contact, [a.inv_mass > 0.0, b.inv_mass > 0.0]);
        Some(Some(input))
    }

    /// A contact that begins from a fresh `manifold` between `a` and `b` (uncoloured, until
    /// the merge writes it).
    fn fresh_contact(
        &self,
        (key, shapes): (u64, u32),
        manifold: &Manifold,
        sides: (Side, Side),
    ) -> Contact {
        let (ia, ib) = pair_of(key);
        let mut contact = Contact {
            key,
            a: ia,
            b: ib,
            shapes,
            normal: Vec2::ZERO,
            friction: 0.0,
            restitution: 0.0,
            touches_static: false,
            rounding: [0.0; 2],
            points: [ContactPoint::default(); 2],
            count: 0,
            hertz: 0.0,
            load: 0.0,
            force: 0.0,
            age: 0,
            colour: UNCOLOURED,
            local_normal: Vec2::ZERO,
            base_rotation: Rot::IDENTITY,
        };
        self.remake(&mut contact, manifold, sides, None);
        contact.age = 0;
        contact
    }

    /// Contact `c`, which goes on, made over in place from a fresh `manifold`: it keeps its
    /// colour, load and age, and the impulses of the points with the same feature ids. (Made
    /// apart and copied over it, as a contact that begins is, it cost two or three copies of
    /// its 216 bytes.)
    #[inline(always)]
    fn refresh(&self, c: &mut Contact, manifold: &Manifold, sides: (Side, Side)) {
        let (old, count) = (c.points, c.count as usize);
        self.remake(c, manifold, sides, Some(&old[..count]));
    }

    /// What a fresh `manifold` between `a` and `b` makes of contact `c`: its geometry (which
    /// also ages it a step), what recycling will read, and the impulses of `previous` points
    /// with the same feature ids.
    #[inline(always)]
    fn remake(
        &self,
        c: &mut Contact,
        manifold: &Manifold,
        (sa, sb): (Side, Side),
        previous: Option<&[ContactPoint]>,
    ) {
        let (a, b) = (sa.body, sb.body);
        let (xf_a, xf_b) = (a.frame(), b.frame());
        c.touches_static = a.inv_mass == 0.0 || b.inv_mass == 0.0;
        c.rounding = [sa.shape.rounding(), sb.shape.rounding()];
        c.count = manifold.count as u8;
        c.local_normal = xf_a.q.inv_rotate(manifold.normal);
        c.base_rotation = relative_rotation(xf_a.q, xf_b.q);
        c.points = [ContactPoint::default(); 2];
        self.set_geometry(c, manifold, (sa, sb));
        for (cp, mp) in c.points.iter_mut().zip(manifold.points()) {
            cp.id = mp.id;
            cp.local_a = xf_a.apply_inv(mp.point);
            cp.local_b = xf_b.apply_inv(mp.point);
            cp.base_separation = mp.separation;
            if let Some(prev) = previous.and_then(|p| p.iter().find(|p| p.id == mp.id)) {
                cp.normal_impulse = prev.normal_impulse;
                cp.tangent_impulse = prev.tangent_impulse;
                cp.approach_velocity = prev.approach_velocity;
            }
        }
    }
}

/// Contact recycling: how far (m) a point may drift from where it was computed before the
/// pair is collided afresh (`Settings::contact_recycling`)...
const RECYCLE_DRIFT: Real = 1.0e-3;
/// ...and at most this fraction of the smaller body's bounding radius (small bodies).
const RECYCLE_SIZE: Real = 0.005;
/// Contact recycling: the largest relative turn of the pair (sine of the angle) before the
/// pair is collided afresh.
const RECYCLE_TURN: Real = 2.0e-3;

/// B's rotation relative to A's: q_A^T q_B.
#[inline]
fn relative_rotation(qa: Rot, qb: Rot) -> Rot {
    Rot {
        c: qa.c * qb.c + qa.s * qb.s,
        s: qa.c * qb.s - qa.s * qb.c,
    }
}

/// The manifold of `base` at the bodies' new transforms, if they have hardly moved against
/// each other since it was computed (no point drifted `max_drift` metres, the pair turned less
/// than [`RECYCLE_TURN`]); None when the pair must be collided afresh.
///
/// Each point is fixed in both bodies (`local_a`, `local_b`, one world point when computed):
/// it lies halfway between its two material points now, the normal turns with A, and the
/// separation grows by how far the points have moved apart along the normal. For a vertex
/// of one body on a face of the other that is exact; only the clipping, which would slide a
/// clipped point along the face, is not redone.
///
/// Inlined: called, it handed its manifold back through memory, and the caller's reads of it
/// waited on the stores (a tenth of `find_contacts`' own time on a settled pile).
#[inline(always)]
fn recycle(base: &Contact, xf_a: Transform, xf_b: Transform, max_drift: Real) -> Option<Manifold> {
    let turn = relative_rotation(xf_a.q, xf_b.q);
    let q0 = base.base_rotation;
    if (q0.c * turn.s - q0.s * turn.c).abs() > RECYCLE_TURN {
        return None;
    }
    let normal = xf_a.q.rotate(base.local_normal);
    let mut manifold = Manifold::EMPTY;
    manifold.normal = normal;
    manifold.count = base.count as usize;
    for (mp, p) in manifold.points.iter_mut().zip(base.live()) {
        let (pa, pb) = (xf_a.apply(p.local_a), xf_b.apply(p.local_b));
        let drift = pb - pa;
        if drift.length_squared() > max_drift * max_drift {
            return None;
        }
        *mp = ManifoldPoint {
            point: 0.5 * (pa + pb),
            separation: p.base_separation + drift.dot(normal),
            id: p.id,
        };
    }
    Some(manifold)
}

/// How far two bodies can close on each other in `dt` (m): their relative linear motion, each
/// one's rotational reach, and what their relative acceleration adds. Gravity moves both alike
/// and cancels, so boxes falling side by side get no speculative contacts with each other.
#[inline]
fn closing_reach(a: &Body, b: &Body, g: Vec2, dt: Real) -> Real {
    let motion = |x: &Body| {
        if x.kinematic {
            (
                x.linear_velocity,
                x.angular_velocity.abs() * x.bounding_radius,
                Vec2::ZERO,
            )
        } else if x.is_active() {
            (
                x.linear_velocity,
                x.angular_velocity.abs() * x.bounding_radius,
                g + x.inv_mass * x.force,
            )
        } else {
            (Vec2::ZERO, 0.0, Vec2::ZERO)
        }
    };
    let (va, wa, aa) = motion(a);
    let (vb, wb, ab) = motion(b);
    dt * ((vb - va).length() + wa + wb) + dt * dt * (ab - aa).length()
}

/// How far any point of body `b` can move in `dt`: its velocity's motion, plus its
/// rotational reach and what gravity and applied force add within the step on every side.
#[inline]
fn travel(b: &Body, g: Vec2, dt: Real) -> Travel {
    let accel = g + b.inv_mass * b.force;
    Travel {
        grow: dt * b.angular_velocity.abs() * b.bounding_radius + dt * dt * accel.length(),
        shift: dt * b.linear_velocity,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::vec2;
    use crate::physics::shape::Shape;

    /// A 1 m box resting on a fixed floor (top at y = 0), sleep off, after `steps` steps.
    fn box_on_floor(recycling: bool, steps: usize) -> World {
        let settings = Settings {
            enable_sleep: false,
            contact_recycling: recycling,
            ..Settings::default()
        };
        let mut w = World::new(settings, vec2(0.0, -10.0)).unwrap();
        w.add_body(&BodyDef::fixed(Shape::rect(20.0, 1.0), vec2(0.0, -0.5)))
            .unwrap();
        w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.3, 0.5)))
            .unwrap();
        for _ in 0..steps {
            w.step(1.0 / 60.0).unwrap();
        }
        w
    }

    /// The floor's and the box's transforms, and the box's shape.
    fn poses(w: &World) -> (Transform, Transform, Shape) {
        let body = |i: usize| w.bodies.slots[i].body.as_ref().unwrap();
        (
            body(0).transform(),
            body(1).transform(),
            body(1).shape.clone(),
        )
    }

    /// The box moved by `d` (m) and turned by `turn` (rad) about its centre.
    fn moved(xf: Transform, d: Vec2, turn: Real) -> Transform {
        Transform {
            p: xf.p + d,
            q: Rot::from_angle(xf.q.angle() + turn),
        }
    }

    /// A box that moves 0.4 mm sideways, 0.3 mm down and turns 1 mrad (its corners drift up
    /// to 1.2 mm, so the test allows 2) keeps the same two
    /// corner points on the floor's face: the recycled manifold has the fresh one's normal,
    /// ids and separations (to 1 um: f32 round-off on metre coordinates is 0.1 um, and the
    /// anchored points are the box's own corners, so nothing else differs), and its points
    /// lie within the 0.4 mm the corners slid.
    #[test]
    fn a_recycled_manifold_is_the_fresh_one_for_a_small_motion() {
        let w = box_on_floor(true, 30);
        let contact = w.contacts.awake[0];
        let (xf_floor, xf_box, shape) = poses(&w);
        let xf = moved(xf_box, vec2(4.0e-4, -3.0e-4), 1.0e-3);
        let recycled = recycle(&contact, xf_floor, xf, 2.0e-3).expect("a small motion recycles");
        let floor = w.bodies.slots[0].body.as_ref().unwrap().shape.clone();
        let fresh = collide(&floor, xf_floor, &shape, xf, 0.02);
        assert_eq!((recycled.count, fresh.count), (2, 2));
        assert!((recycled.normal - fresh.normal).length() < 1e-6);
        for p in fresh.points() {
            let q = recycled
                .points()
                .iter()
                .find(|q| q.id == p.id)
                .expect("the same features");
            assert!(
                (q.separation - p.separation).abs() < 1e-6,
                "separation {} against {}",
                q.separation,
                p.separation
            );
            assert!((q.point - p.point).length() < 5e-4);
        }
    }

    /// Past 1 mm of drift at a point, or 2 mrad of turn, the pair is collided afresh.
    #[test]
    fn recycling_stops_when_a_pair_drifts_or_turns() {
        let w = box_on_floor(true, 30);
        let contact = w.contacts.awake[0];
        let (xf_floor, xf_box, _) = poses(&w);
        let drifted = moved(xf_box, vec2(1.2e-3, 0.0), 0.0);
        assert!(recycle(&contact, xf_floor, drifted, 1.0e-3).is_none());
        let turned = moved(xf_box, Vec2::ZERO, 2.5e-3);
        assert!(recycle(&contact, xf_floor, turned, 1.0).is_none());
        let still = moved(xf_box, vec2(1.0e-4, 0.0), 1.0e-4);
        assert!(recycle(&contact, xf_floor, still, 1.0e-3).is_some());
    }

    /// Recycling changes nothing a user can see in a resting stack: ten boxes stepped 5 s
    /// with recycling and without end with every centre within 0.05 mm (the recycled
    /// separations are exact for corners on faces; what differs is round-off, which the
    /// springs damp), while the recycled world really reused its manifolds (a point's
    /// separation moved on from the one it was computed with).
    #[test]
    fn recycling_leaves_a_resting_stack_where_fresh_manifolds_put_it() {
        let stack = |recycling: bool| {
            let mut w = box_on_floor(recycling, 0);
            for i in 1..10 {
                let y = 0.5 + i as Real;
                w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.3, y)))
                    .unwrap();
            }
            for _ in 0..300 {
                w.step(1.0 / 60.0).unwrap();
            }
            w
        };
        let (on, off) = (stack(true), stack(false));
        for (a, b) in on.bodies().zip(off.bodies()) {
            let d = (a.position() - b.position()).length();
            assert!(d < 5e-5, "body {} differs by {d} m", a.id());
        }
        let reused = on
            .contacts
            .awake
            .iter()
            .flat_map(|c| c.live().iter())
            .filter(|p| p.separation != p.base_separation)
            .count();
        assert!(reused > 0, "no contact was recycled");
        let fresh = off
            .contacts
            .awake
            .iter()
            .flat_map(|c| c.live().iter())
            .all(|p| p.separation == p.base_separation);
        assert!(fresh, "without recycling every manifold is fresh");
    }

    /// A grid of boxes flying together at 30 m/s (0.5 m a step, no gravity), 1 m apart. Each
    /// box's path reaches only the box ahead of it, so the broad phase pairs each row's
    /// neighbours (9 pairs a row, 90 in all) and nothing else. Grown by its travel on every
    /// side, each box met its neighbours across and aslant as well (342 pairs), none of which
    /// it can reach within the step.
    #[test]
    fn boxes_flying_together_pair_only_along_their_motion() {
        let settings = Settings {
            enable_sleep: false,
            ..Settings::default()
        };
        let mut w = World::new(settings, Vec2::ZERO).unwrap();
        for i in 0..10 {
            for j in 0..10 {
                let at = vec2(i as Real, j as Real);
                let def =
                    BodyDef::dynamic(Shape::rect(0.5, 0.5), at).with_velocity(vec2(30.0, 0.0));
                w.add_body(&def).unwrap();
            }
        }
        w.step(1.0 / 60.0).unwrap();
        assert_eq!(w.broad_phase.pair_keys.len(), 90);
        let rows = w.broad_phase.pair_keys.iter().all(|&key| {
            let (a, b) = pair_of(key);
            b - a == 10
        });
        assert!(rows, "every pair is of neighbours in a row");
        assert_eq!(w.contact_count(), 0, "nothing touches or closes in");
    }
}
