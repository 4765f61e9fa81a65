//! The soft step's contacts packed for the lanes: each colour of the constraint graph
//! (`graph.rs`) in bundles of four or eight contacts, and the overflow in bundles of one.
//!
//! Packing runs once per solve, in the prepare stage, in contact-key order: each contact is
//! prepared, then written straight into the open bundle of its (colour, kind), so each
//! colour's bundles hold its contacts in key order and the constraint never passes through
//! memory. Eight lanes run where the processor has AVX2 (detected at run time) and the solve
//! has at least [`EIGHT_LANES_FROM`] contacts; four (SSE2 on x86-64) otherwise. Every stage
//! then runs the overflow first (a Gauss-Seidel solve favours what it solves last, and the
//! overflow is what the graph could not place: Box2D gives it the lowest priority too), then
//! the colours in ascending order.

use super::constraint::ContactConstraint;
use super::contact_solver::{
    BounceLanes, Bundle, BundleKind, Ledger, Pass, PointImpulses, RoundLanes, Rows, Sides,
    NO_BOUNCE, NO_ROUNDING,
};
use super::gaps::{fill_gaps, Entry, GAPS_FILLED_UP_TO, NOT_A_NODE};
use super::graph::{COLOURS, OVERFLOW};
use super::lanes::{eight_lanes_available, prefetch, Lanes1, Lanes4, Lanes8, Wide};
use super::{BodyRows, PassKind, Selected, SharedRows, SolverBody};
use crate::physics::contact::Contact;
use crate::physics::math::Real;
use crate::physics::team::{block, Region, SharedSlice};

/// Contacts from which a solve packs eight to a bundle (where the processor can): below, the
/// bundles of each colour are mostly empty lanes (falling_bricks, 8 contacts, stepped 50 %
/// slower on eight lanes than on four; pyramid_20, 590 contacts, 15 % faster).
const EIGHT_LANES_FROM: usize = 64;

/// How many contacts a coloured bundle holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Width {
    /// One ([`Lanes1`]): the kernel as plain scalar code, packed as the lanes are (tests
    /// compare it with the lanes, bit for bit; the overflow always runs at this width).
    #[cfg_attr(not(test), allow(dead_code))]
    One,
    /// Four ([`Lanes4`]: SSE2 on x86-64).
    Four,
    /// Eight ([`Lanes8`]), compiled for AVX2 and run where the processor has it.
    Eight,
}

impl Width {
    /// The widest this machine runs: eight lanes with AVX2, four otherwise.
    pub fn detect() -> Width {
        if eight_lanes_available() {
            Width::Eight
        } else {
            Width::Four
        }
    }
}

/// A solve pass's kind, 1 / substep (1/s) and push-out cap (m/s).
pub(crate) type PassArgs = (PassKind, Real, Real);

/// The joints of a pass, if it has any: called with a colour's solve rank (the overflow 0,
/// colour c c + 1) before that colour's contacts, it runs the joints up to that rank that have
/// not run (`joint::JointPass`), so each colour's joints go just before its contacts.
pub(crate) type Joints<'a> = Option<&'a mut dyn FnMut(&mut [SolverBody], u8)>;

/// The overflow's solve rank.
const OVERFLOW_RANK: u8 = 0;

/// Run `joints` up to the solve rank of the colour of list `slot` (colour * KINDS + kind).
#[inline(always)]
fn before_colour(joints: &mut Joints, bodies: &mut [SolverBody], slot: u16) {
    if let Some(run) = joints.as_mut() {
        run(bodies, (slot as usize / KINDS) as u8 + 1);
    }
}

/// How many bundles a worker takes at a time in the parallel step: 32 contacts at eight
/// lanes, a few microseconds of a solve pass, against some 0.1 microsecond to take them.
const BUNDLES_PER_BLOCK: usize = 4;

/// Contacts and joints from which a solve spreads its colours over the workers: below, a pass
/// over them takes a few microseconds, which handing out blocks would eat.
const SHARED_FROM: usize = 1024;

/// A stage's work on each bundle, as the parallel step hands bundles out: in plain numbers,
/// which each block turns into lanes.
#[derive(Clone, Copy)]
pub(crate) enum Work {
    /// Apply the accumulated impulses.
    WarmStart,
    /// A solve pass.
    Solve(PassArgs),
    /// Restitution above a threshold (m/s).
    Restitution(Real),
}

/// What a block reads beside its bundles and the bodies: the rounding lanes, and the
/// restitution lanes, each bundle's its own; `plain` when no bundle of its list has either.
struct SideLanes<'a, L> {
    rounds: &'a [RoundLanes<L>],
    bounces: SharedSlice<'a, BounceLanes<L>>,
    plain: bool,
}

impl<L> Clone for SideLanes<'_, L> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<L> Copy for SideLanes<'_, L> {}

/// One list's share of a colour's stage in the parallel step: its bundles and ledgers,
/// whether the list is plain ([`SideLanes::plain`]), and the stage's first block that is its.
struct ColourPart<'a, L: Wide> {
    bundles: SharedSlice<'a, Bundle<L>>,
    ledgers: SharedSlice<'a, Ledger<L>>,
    plain: bool,
    first: usize,
}

/// The lists of one colour (at most one a kind), run as one stage: its blocks numbered
/// list after list.
struct ColourParts<'a, L: Wide> {
    parts: [Option<ColourPart<'a, L>>; KINDS],
    /// The stage's blocks, over all its lists.
    blocks: usize,
}

impl<L: Wide> Default for ColourParts<'_, L> {
    fn default() -> Self {
        ColourParts {
            parts: [None, None, None],
            blocks: 0,
        }
    }
}

impl<'a, L: Wide> ColourParts<'a, L> {
    /// Add `list` (the next kind of the colour), `plain` or not.
    fn push(&mut self, list: &'a mut List<L>, plain: bool) {
        let Some(free) = self.parts.iter_mut().find(|p| p.is_none()) else {
            unreachable!("a colour has one list a kind");
        };
        let first = self.blocks;
        self.blocks += list.bundles.len().div_ceil(BUNDLES_PER_BLOCK);
        // SAFETY: each block of the stage reaches its own run of one list's bundles and
        // ledgers ([`ColourParts::find`]).
        let (bundles, ledgers) = unsafe {
            (
                SharedSlice::new(&mut list.bundles),
                SharedSlice::new(&mut list.ledgers),
            )
        };
        *free = Some(ColourPart {
            bundles,
            ledgers,
            plain,
            first,
        });
    }

    /// The list block `k` of the stage is in, and its number within that list.
    #[inline]
    fn find(&self, k: usize) -> (&ColourPart<'a, L>, usize) {
        let part = self
            .parts
            .iter()
            .flatten()
            .take_while(|p| p.first <= k)
            .last();
        let part = part.expect("a block of the stage is in one of its lists");
        (part, k - part.first)
    }
}

/// What the store stage does with a contact and its points' impulses, from any worker.
pub(crate) type StoreFn<'a> = dyn Fn(&mut Contact, &[PointImpulses; 2]) + Sync + 'a;

/// Stores one block: [`store_block`] at a width, compiled for it.
type StoreBlock<L> =
    fn(&[Ledger<L>], &[Bundle<L>], &[BounceLanes<L>], SharedSlice<Contact>, &StoreFn);

/// Hand each contact of `bundles` (one block of a colour, with their `ledgers`) its points'
/// impulses. A contact is in one lane of one bundle, so the worker that took the block is the
/// only one to reach it.
#[inline(always)]
fn store_block<L: Wide>(
    ledgers: &[Ledger<L>],
    bundles: &[Bundle<L>],
    bounces: &[BounceLanes<L>],
    contacts: SharedSlice<Contact>,
    then: &StoreFn,
) {
    for (bundle, ledger) in bundles.iter().zip(ledgers) {
        let ends = bundle.impulses(ledger, bounces.get(bundle.bounce_index as usize));
        for (end, &ci) in ends.iter().zip(ledger.contact.as_ref()) {
            // SAFETY: as above: this lane's contact is this block's alone.
            if let Some(c) = unsafe { contacts.get(ci as usize) } {
                then(c, end);
            }
        }
    }
}

/// A solve pass over `bundles` of one list without rounded or bouncing bundles: one kernel
/// copy for all. (Most lists: looking up each bundle's sides and choosing its kernel were 5 %
/// of a pyramid's solve instructions.)
#[inline(always)]
fn solve_plain<L: Wide, R: Rows + ?Sized>(
    bundles: &mut [Bundle<L>],
    rows: &mut R,
    pass: &Pass<L>,
    friction: bool,
) {
    // A list holds one kind.
    if bundles
        .first()
        .is_some_and(|b| b.kind == BundleKind::Single)
    {
        for bundle in bundles {
            bundle.solve_plain::<1, R>(rows, pass, friction);
        }
    } else {
        for bundle in bundles {
            bundle.solve_plain::<2, R>(rows, pass, friction);
        }
    }
}

/// The warm start of `bundles` of one list, with their `ledgers`: a list holds one kind, so
/// one kernel copy runs them all (the first bundle's kind chooses it).
#[inline(always)]
fn warm_start_list<L: Wide, R: Rows + ?Sized>(
    bundles: &mut [Bundle<L>],
    ledgers: &mut [Ledger<L>],
    rows: &mut R,
) {
    let single = bundles
        .first()
        .is_some_and(|b| b.kind == BundleKind::Single);
    let bundles = bundles.iter_mut().zip(ledgers);
    // (Loops, not `for_each`: a closure does not take the AVX2 compilation of the kernel it is
    // called from, and once the warm start grew past the inliner's budget every lane operation
    // in it became a call.)
    if single {
        for (bundle, ledger) in bundles {
            bundle.warm_start::<1, R>(rows, ledger);
        }
    } else {
        for (bundle, ledger) in bundles {
            bundle.warm_start::<2, R>(rows, ledger);
        }
    }
}

/// Runs one block: [`run_block`] at a width, compiled for it.
type BlockRun<L> = fn(Block<L>, BodyRows, Work, SideLanes<L>);

/// One block of a colour's bundles, with their ledgers.
type Block<'a, L> = (&'a mut [Bundle<L>], &'a mut [Ledger<L>]);

/// `work` on each of `bundles` (one block of a colour).
#[inline(always)]
fn run_block<L: Wide>(
    (bundles, ledgers): Block<L>,
    rows: BodyRows,
    work: Work,
    side: SideLanes<L>,
) {
    let mut rows = rows;
    let rows = &mut rows;
    match work {
        Work::WarmStart => warm_start_list(bundles, ledgers, rows),
        Work::Solve((kind, inv_h, push_out)) => {
            let (inv_h, push_out) = (L::splat(inv_h), L::splat(-push_out));
            let pass = Pass::new(inv_h, kind == PassKind::Biased, push_out);
            let friction = kind != PassKind::NormalRelax;
            if side.plain {
                return solve_plain(bundles, rows, &pass, friction);
            }
            for bundle in bundles {
                // SAFETY: a bundle's restitution lanes are its own, and it is in one block.
                let sides = Sides {
                    round: side.rounds.get(bundle.round_index as usize),
                    bounce: unsafe { side.bounces.get(bundle.bounce_index as usize) },
                };
                bundle.solve(rows, &pass, sides, friction);
            }
        }
        Work::Restitution(threshold) => {
            let threshold = L::splat(threshold);
            for bundle in bundles {
                // SAFETY: as above.
                if let Some(bounce) = unsafe { side.bounces.get(bundle.bounce_index as usize) } {
                    bundle.apply_restitution(bounce, rows, threshold);
                }
            }
        }
    }
}

/// One (colour, kind)'s bundles and, index for index, their ledgers.
#[derive(Clone, Debug)]
struct List<L: Wide> {
    bundles: Vec<Bundle<L>>,
    ledgers: Vec<Ledger<L>>,
}

impl<L: Wide> Default for List<L> {
    fn default() -> Self {
        List {
            bundles: Vec::new(),
            ledgers: Vec::new(),
        }
    }
}

impl<L: Wide> List<L> {
    fn clear(&mut self) {
        self.bundles.clear();
        self.ledgers.clear();
    }
}

/// Bundles of one width, in lists per (colour, kind) flattened as colour * KINDS + kind, solved in
/// that order, with the restitution lanes of the bundles that bounce.
#[derive(Clone, Debug)]
struct Packed<L: Wide> {
    /// While packing: a list per (colour, kind).
    lists: Vec<List<L>>,
    /// Once packed: the lists that hold a bundle, moved out of `lists` in solve order (a scene
    /// uses a few of the 64, the ground's contacts in the top colours), so the stages walk
    /// them as one sequence; and the slot each came from, to give it back.
    packed: Vec<List<L>>,
    slots: Vec<u16>,
    /// Once packed: for each list in `packed`, whether a bundle of it bounces or has a rounded
    /// side; the solve passes run the others through the kernel without those sides.
    sided: Vec<bool>,
    bounces: Vec<BounceLanes<L>>,
    /// The rounding lanes of the bundles with a rounded side.
    rounds: Vec<RoundLanes<L>>,
    /// When the workers pack: each list's own restitution and rounding lanes, joined to
    /// `bounces` and `rounds` afterwards.
    list_sides: Vec<SideScratch<L>>,
    /// While packing: bit `slot` set for each list written to, so that closing visits those
    /// alone (a small solve fills a few of the 96).
    used: u128,
}

const _: () = assert!(LISTS <= u128::BITS as usize, "a bit for each list");

/// One list's restitution and rounding lanes while the workers pack.
type SideScratch<L> = (Vec<BounceLanes<L>>, Vec<RoundLanes<L>>);

impl<L: Wide> Default for Packed<L> {
    fn default() -> Self {
        Packed {
            lists: Vec::new(),
            packed: Vec::new(),
            slots: Vec::new(),
            sided: Vec::new(),
            bounces: Vec::new(),
            rounds: Vec::new(),
            list_sides: Vec::new(),
            used: 0,
        }
    }
}

/// How many kinds of bundle ([`BundleKind`]) a colour has lists for.
const KINDS: usize = 3;

/// The kinds, in their lists' order within a colour.
const ALL_KINDS: [BundleKind; KINDS] = [BundleKind::Block, BundleKind::Points, BundleKind::Single];

/// How many coloured lists there are: one per (colour, kind).
const LISTS: usize = COLOURS * KINDS;

/// Which list of its colour a bundle of `kind` goes in.
#[inline(always)]
fn kind_slot(kind: BundleKind) -> usize {
    match kind {
        BundleKind::Block => 0,
        BundleKind::Points => 1,
        BundleKind::Single => 2,
    }
}

/// Contacts from which a solve packs its one-point contacts apart ([`BundleKind::Single`]):
/// below, the extra lists' half-empty bundles cost more than the second point's lanes saved.
const SINGLES_FROM: usize = 1024;

/// The kind of bundle contact `c`, prepared as `k`, goes in: two points without a usable
/// block one after the other; one point alone if `singles`
/// ([`ContactBundles::singles_apart`]); else as a block.
#[inline(always)]
fn kind_of(c: &Contact, k: &ContactConstraint, singles: bool) -> BundleKind {
    match (c.count, &k.block) {
        (1, _) if singles => BundleKind::Single,
        (2, None) => BundleKind::Points,
        _ => BundleKind::Block,
    }
}

impl<L: Wide> Packed<L> {
    /// Empty, with `lists` lists.
    fn reset(&mut self, lists: usize) {
        self.lists.resize_with(lists, List::default);
        for (mut list, slot) in self.packed.drain(..).zip(self.slots.drain(..)) {
            list.clear();
            self.lists[slot as usize] = list;
        }
        self.sided.clear();
        self.bounces.clear();
        self.rounds.clear();
        self.used = 0;
    }

    /// Write contact `c` (index `i`) with its constraint `k` into the next lane of list
    /// `slot`, of which `filled` lanes are taken, opening a bundle (`inert()`) when the last
    /// is full.
    #[inline(always)]
    fn put(
        &mut self,
        (slot, filled): (usize, &mut usize),
        inert: impl FnOnce() -> Bundle<L>,
        (i, c): (usize, &Contact),
        k: &ContactConstraint,
        bodies: &[SolverBody],
    ) {
        if *filled == 0 {
            // (A 128-bit shift takes some ten instructions: once per list, not per contact.)
            self.used |= 1 << slot;
        }
        let sides = (&mut self.bounces, &mut self.rounds);
        put(
            &mut self.lists[slot],
            sides,
            (filled, inert),
            (i, c),
            k,
            bodies,
        );
    }

    /// After the workers packed: each list's side lanes appended to `bounces` and `rounds`, in
    /// list order, and its bundles' indices moved to match.
    fn join_sides(&mut self) {
        for (list, (bounces, rounds)) in self.lists.iter_mut().zip(&self.list_sides) {
            if bounces.is_empty() && rounds.is_empty() {
                continue;
            }
            let (b0, r0) = (self.bounces.len() as u32, self.rounds.len() as u32);
            for bundle in list.bundles.iter_mut() {
                if bundle.bounce_index != NO_BOUNCE {
                    bundle.bounce_index += b0;
                }
                if bundle.round_index != NO_ROUNDING {
                    bundle.round_index += r0;
                }
            }
            self.bounces.extend_from_slice(bounces);
            self.rounds.extend_from_slice(rounds);
        }
    }

    /// Once packed: each slot's list's index in `packed` (slots not in use: none).
    fn by_slot(&self) -> [usize; LISTS] {
        let mut at = [usize::MAX; LISTS];
        for (k, &slot) in self.slots.iter().enumerate() {
            at[slot as usize] = k;
        }
        at
    }

    /// Once packed: the impulses of lane `place` of list `k` of `packed`.
    #[inline(always)]
    fn lane_impulses(&self, k: usize, place: usize) -> [PointImpulses; 2] {
        let list = &self.packed[k];
        let (b, lane) = (place / L::WIDTH, place % L::WIDTH);
        let bundle = &list.bundles[b];
        let bounce = self.bounces.get(bundle.bounce_index as usize);
        bundle.lane_impulses(lane, &list.ledgers[b], bounce)
    }

    /// Move the lists in use out, in solve order, once packed.
    fn close(&mut self) {
        let mut used = std::mem::take(&mut self.used);
        while used != 0 {
            let slot = used.trailing_zeros() as usize;
            used &= used - 1;
            let list = std::mem::take(&mut self.lists[slot]);
            let plain = |b: &Bundle<L>| b.bounce_index == NO_BOUNCE && b.round_index == NO_ROUNDING;
            self.sided.push(!list.bundles.iter().all(plain));
            self.packed.push(list);
            self.slots.push(slot as u16);
        }
    }

    /// Packed bundles of `kind`.
    #[cfg(test)]
    fn count_of(&self, kind: BundleKind) -> usize {
        let bundles = self.packed.iter().flat_map(|list| &list.bundles);
        bundles.filter(|b| b.kind == kind).count()
    }

    /// Mark the lists the workers filled as used ([`Packed::close`]).
    fn mark_filled(&mut self) {
        for (slot, list) in self.lists.iter().enumerate() {
            if !list.bundles.is_empty() {
                self.used |= 1 << slot;
            }
        }
    }

    /// The warm start of a substep (or, with warm starting off, zeroed impulses), with
    /// `joints` run before each colour.
    #[inline(always)]
    fn warm_start(&mut self, bodies: &mut [SolverBody], warm_starting: bool, joints: Joints) {
        if warm_starting {
            let mut joints = joints;
            for (list, &slot) in self.packed.iter_mut().zip(&self.slots) {
                before_colour(&mut joints, bodies, slot);
                warm_start_list(&mut list.bundles, &mut list.ledgers, bodies);
            }
        } else {
            for list in &mut self.packed {
                for (bundle, ledger) in list.bundles.iter_mut().zip(&mut list.ledgers) {
                    bundle.clear_impulses(ledger);
                }
            }
        }
    }

    /// One solve pass of `kind` over every bundle, with `joints` run before each colour: one
    /// copy of the loop per kind of pass, each compiled without the arithmetic its kind leaves
    /// out (the relax passes without the bias, the normal relax also without friction).
    #[inline(always)]
    fn solve(&mut self, bodies: &mut [SolverBody], args: PassArgs, joints: Joints) {
        let (kind, inv_h, push_out) = args;
        let (inv_h, push_out) = (L::splat(inv_h), L::splat(-push_out));
        match kind {
            PassKind::Biased => self.pass(bodies, &Pass::new(inv_h, true, push_out), true, joints),
            PassKind::Relax => self.pass(bodies, &Pass::new(inv_h, false, push_out), true, joints),
            PassKind::NormalRelax => {
                self.pass(bodies, &Pass::new(inv_h, false, push_out), false, joints)
            }
        }
    }

    /// One pass over every bundle, with `friction` or without, with `joints` run before each
    /// colour. The biased pass updates the bouncing bundles' approach speeds.
    #[inline(always)]
    fn pass(&mut self, bodies: &mut [SolverBody], pass: &Pass<L>, friction: bool, joints: Joints) {
        let (rounds, bounces) = (&self.rounds, &mut self.bounces);
        let mut joints = joints;
        let lists = self.packed.iter_mut().zip(&self.slots).zip(&self.sided);
        for ((list, &slot), &sided) in lists {
            before_colour(&mut joints, bodies, slot);
            if !sided {
                solve_plain(&mut list.bundles, bodies, pass, friction);
                continue;
            }
            for bundle in &mut list.bundles {
                // (None for a bundle without them: its index is out of range.)
                let sides = Sides {
                    round: rounds.get(bundle.round_index as usize),
                    bounce: bounces.get_mut(bundle.bounce_index as usize),
                };
                bundle.solve(bodies, pass, sides, friction);
            }
        }
    }

    /// Restitution on the bundles that bounce.
    #[inline(always)]
    fn apply_restitution(&mut self, bodies: &mut [SolverBody], threshold: Real) {
        let threshold = L::splat(threshold);
        for bundle in self.packed.iter_mut().flat_map(|list| &mut list.bundles) {
            if bundle.bounce_index != NO_BOUNCE {
                let bounce = &self.bounces[bundle.bounce_index as usize];
                bundle.apply_restitution(bounce, bodies, threshold);
            }
        }
    }

    /// `work` colour by colour, each colour's bundles (of every kind) in blocks spread over
    /// `region`'s workers by `run`, one stage a colour, with `joints` run before each colour
    /// by this thread alone.
    fn run_shared(
        &mut self,
        region: &Region,
        rows: SharedRows,
        work: Work,
        (mut joints, run): (Joints, BlockRun<L>),
    ) {
        // SAFETY: a bundle's restitution lanes are its own (`bounce_index`), and each bundle
        // is in one block.
        let bounces = unsafe { SharedSlice::new(&mut self.bounces) };
        let side = SideLanes {
            rounds: &self.rounds,
            bounces,
            plain: false,
        };
        let mut lists = (self.packed.iter_mut().zip(&self.slots).zip(&self.sided)).peekable();
        while let Some(((list, &slot), &sided)) = lists.next() {
            let colour = slot as usize / KINDS;
            if let Some(run_joints) = joints.as_mut() {
                // SAFETY: between colours no block runs: the other workers wait.
                run_joints(unsafe { rows.exclusive() }, colour as u8 + 1);
            }
            // The colour's lists (one per kind in it) share no dynamic body either: one stage.
            let mut parts = ColourParts::default();
            parts.push(list, !sided);
            while let Some(((list, _), &sided)) =
                lists.next_if(|((_, &s), _)| s as usize / KINDS == colour)
            {
                parts.push(list, !sided);
            }
            region.for_blocks(parts.blocks, &|k| {
                let (part, k) = parts.find(k);
                let range = block(k, BUNDLES_PER_BLOCK, part.bundles.len());
                // SAFETY: block k's bundles and ledgers are reached by the worker that took k
                // alone.
                let block =
                    unsafe { (part.bundles.range(range.clone()), part.ledgers.range(range)) };
                let side = SideLanes {
                    plain: part.plain,
                    ..side
                };
                run(block, rows.rows(), work, side);
            });
        }
    }

    /// [`Packed::store`] in one stage: every list's bundles in blocks spread over `region`'s
    /// workers (each contact is in one lane of one bundle, so no two blocks write one).
    fn store_shared(
        &self,
        region: &Region,
        (contacts, then): (SharedSlice<Contact>, &StoreFn),
        store: StoreBlock<L>,
    ) {
        let blocks_of = |list: &List<L>| list.bundles.len().div_ceil(BUNDLES_PER_BLOCK);
        let mut starts = [0; LISTS + 1];
        for (k, list) in self.packed.iter().enumerate() {
            starts[k + 1] = starts[k] + blocks_of(list);
        }
        let starts = &starts[..=self.packed.len()];
        region.for_blocks(starts[starts.len() - 1], &|k| {
            let l = starts.partition_point(|&s| s <= k) - 1;
            let list = &self.packed[l];
            let range = block(k - starts[l], BUNDLES_PER_BLOCK, list.bundles.len());
            let (bundles, ledgers) = (&list.bundles[range.clone()], &list.ledgers[range]);
            store(ledgers, bundles, &self.bounces, contacts, then);
        });
    }

    /// Hand each contact its points' impulses. Bundles hold contacts from all over the array:
    /// while one bundle's are stored, the next bundle's are fetched (storing waited on those
    /// loads for three quarters of its time).
    fn store(
        &self,
        contacts: &mut [Contact],
        then: &mut impl FnMut(&mut Contact, &[PointImpulses; 2]),
    ) {
        let bundles = self
            .packed
            .iter()
            .flat_map(|l| l.bundles.iter().zip(&l.ledgers));
        let mut bundles = bundles.peekable();
        while let Some((bundle, ledger)) = bundles.next() {
            if let Some((_, next)) = bundles.peek() {
                for &ci in next.contact.as_ref() {
                    if let Some(c) = contacts.get(ci as usize) {
                        prefetch(c);
                    }
                }
            }
            let ends = bundle.impulses(ledger, self.bounces.get(bundle.bounce_index as usize));
            for (end, &ci) in ends.iter().zip(ledger.contact.as_ref()) {
                if let Some(c) = contacts.get_mut(ci as usize) {
                    then(c, end);
                }
            }
        }
    }
}

/// The packed contacts of one solve, kept by the World so a steady step does not allocate.
#[derive(Clone, Debug, Default)]
pub(crate) struct ContactBundles {
    single: Packed<Lanes1>,
    four: Packed<Lanes4>,
    eight: Packed<Lanes8>,
    /// The overflow, one contact a bundle, in two lists (block, points).
    overflow: Packed<Lanes1>,
    /// Whether any contact packed bounces (restitution runs only then).
    bouncy: bool,
    /// Bundle width; `None` picks four below [`EIGHT_LANES_FROM`] contacts and
    /// [`Width::detect`] from there, at each build (tests set it to compare).
    pub width: Option<Width>,
    /// Scratch for packing on the workers: the selected contacts by list.
    order: Vec<u32>,
    /// Contacts from which a solve is spread over the workers; `None`: [`SHARED_FROM`]
    /// (tests lower it so that small worlds take the parallel path).
    pub share_from: Option<usize>,
    /// Contacts from which a solve packs one-point contacts apart; `None`: [`SINGLES_FROM`]
    /// (tests lower it so that small worlds pack them so).
    pub singles_from: Option<usize>,
    /// The width of the bundles built last.
    built: Option<Width>,
    /// Scratch for packing a small solve ([`pack_small`]).
    small: SmallSolve,
    /// Contacts up to which a solve fills its half-empty bundles; `None`: [`GAPS_FILLED_UP_TO`]
    /// (tests set 0 to compare).
    pub gaps_up_to: Option<usize>,
    /// Where a build on this thread put each contact, in key order ([`Place`]); empty after
    /// a build on the workers, or where a list outgrew a place.
    places: Vec<Place>,
}

/// What packing reads: the bodies, the contacts, which of them to pack, and how to prepare
/// one (its constraint, written into the last argument, from the contact and its bodies A and
/// B; it may update the contact).
pub(crate) struct PackInput<'a, 'b, P> {
    pub bodies: &'a [SolverBody],
    pub contacts: &'a mut [Contact],
    pub selected: Selected<'b>,
    pub prepare: P,
    /// Whether contacts may change colour to fill half-empty bundles ([`fill_gaps`]): not in a
    /// solve with joints, whose colours the move does not see.
    pub fill_gaps: bool,
}

impl ContactBundles {
    /// The prepare stage's packing: each selected contact, in key order, prepared and written
    /// into its colour's open bundle (or the overflow). `bodies` must end with one extra fixed
    /// body, for empty lanes.
    pub fn build<P>(&mut self, input: PackInput<'_, '_, P>)
    where
        P: FnMut(&mut Contact, &SolverBody, &SolverBody, &mut ContactConstraint),
    {
        debug_assert!(
            input.bodies.last().is_some_and(|d| d.inv_mass == 0.0),
            "the last solver body is the fixed dummy"
        );
        let width = match self.width {
            Some(Width::Eight) if !eight_lanes_available() => Width::Four,
            Some(width) => width,
            None if input.selected.count(input.contacts.len()) < EIGHT_LANES_FROM => Width::Four,
            None => Width::detect(),
        };
        self.built = Some(width);
        self.overflow.reset(KINDS);
        let count = input.selected.count(input.contacts.len());
        let singles = self.singles_apart(count);
        let up_to = self.gaps_up_to.unwrap_or(GAPS_FILLED_UP_TO);
        let small = (input.fill_gaps && (2..=up_to).contains(&count)).then_some(&mut self.small);
        let (overflow, places) = (&mut self.overflow, &mut self.places);
        self.bouncy = match width {
            Width::One => pack(
                (&mut self.single, overflow, places),
                input,
                (singles, small),
            ),
            Width::Four => pack((&mut self.four, overflow, places), input, (singles, small)),
            Width::Eight => pack((&mut self.eight, overflow, places), input, (singles, small)),
        };
    }

    /// [`ContactBundles::build`] of contacts the workers prepared, each colour's lists filled
    /// by one of `region`'s workers (see [`pack_shared`]).
    pub fn build_shared(&mut self, region: &Region, input: &SharedPackInput) {
        let width = match self.width {
            Some(Width::Eight) if !eight_lanes_available() => Width::Four,
            Some(width) => width,
            None if input.lists.len() < EIGHT_LANES_FROM => Width::Four,
            None => Width::detect(),
        };
        self.built = Some(width);
        self.overflow.reset(KINDS);
        self.places.clear();
        let (order, overflow) = (&mut self.order, &mut self.overflow);
        self.bouncy = match width {
            Width::One => pack_shared((&mut self.single, overflow), input, region, order),
            Width::Four => pack_shared((&mut self.four, overflow), input, region, order),
            Width::Eight => pack_shared((&mut self.eight, overflow), input, region, order),
        };
    }

    /// The warm start of a substep, or with `warm_starting` off zeroed impulses; `joints`, if
    /// any, are run before the overflow and before each colour (see [`Joints`]).
    #[inline]
    pub fn warm_start(&mut self, bodies: &mut [SolverBody], warm_starting: bool, joints: Joints) {
        let mut joints = joints;
        if let Some(run) = joints.as_mut() {
            run(bodies, OVERFLOW_RANK);
        }
        self.overflow.warm_start(bodies, warm_starting, None);
        match self.built {
            Some(Width::Eight) => eight::warm_start(&mut self.eight, bodies, warm_starting, joints),
            Some(Width::One) => self.single.warm_start(bodies, warm_starting, joints),
            _ => self.four.warm_start(bodies, warm_starting, joints),
        }
    }

    /// One solve pass of `kind`, with `inv_h` 1 / substep (1/s) and `push_out` the push-out
    /// cap (m/s); `joints`, if any, are run before the overflow and before each colour.
    #[inline]
    pub fn solve(&mut self, bodies: &mut [SolverBody], args: PassArgs, joints: Joints) {
        let mut joints = joints;
        if let Some(run) = joints.as_mut() {
            run(bodies, OVERFLOW_RANK);
        }
        self.overflow.solve(bodies, args, None);
        match self.built {
            Some(Width::Eight) => eight::solve(&mut self.eight, bodies, args, joints),
            Some(Width::One) => self.single.solve(bodies, args, joints),
            _ => self.four.solve(bodies, args, joints),
        }
    }

    /// Restitution above `threshold` (m/s), where any contact bounces.
    #[inline]
    pub fn apply_restitution(&mut self, bodies: &mut [SolverBody], threshold: Real) {
        if !self.bouncy {
            return;
        }
        self.overflow.apply_restitution(bodies, threshold);
        match self.built {
            Some(Width::Eight) => eight::apply_restitution(&mut self.eight, bodies, threshold),
            Some(Width::One) => self.single.apply_restitution(bodies, threshold),
            _ => self.four.apply_restitution(bodies, threshold),
        }
    }

    /// Whether a solve of `contacts` contacts packs its one-point contacts apart
    /// ([`BundleKind::Single`]).
    #[inline]
    pub fn singles_apart(&self, contacts: usize) -> bool {
        contacts >= self.singles_from.unwrap_or(SINGLES_FROM)
    }

    /// The fewest items from which a stage is spread over the workers: `default`, or less
    /// where a test lowered [`ContactBundles::share_from`].
    pub fn shared_from(&self, default: usize) -> usize {
        self.share_from.map_or(default, |n| n.min(default))
    }

    /// Whether a solve of `constraints` contacts and joints is worth spreading over workers
    /// ([`SHARED_FROM`]).
    pub fn worth_sharing(&self, constraints: usize) -> bool {
        constraints >= self.share_from.unwrap_or(SHARED_FROM)
    }

    /// A stage's `work` with the colours spread over `region`'s workers: the overflow first,
    /// by this thread, then each colour's joints by this thread and its bundles by all.
    /// (With warm starting off, the warm start only zeroes impulses: this thread does it.)
    pub fn run_shared(
        &mut self,
        region: &Region,
        bodies: &mut [SolverBody],
        work: Work,
        joints: Joints,
    ) {
        let mut joints = joints;
        match work {
            Work::Restitution(_) if !self.bouncy => return,
            Work::Restitution(threshold) => self.overflow.apply_restitution(bodies, threshold),
            _ => {
                if let Some(run) = joints.as_mut() {
                    run(bodies, OVERFLOW_RANK);
                }
                match work {
                    Work::Solve(args) => self.overflow.solve(bodies, args, None),
                    _ => self.overflow.warm_start(bodies, true, None),
                }
            }
        }
        // SAFETY: a colour's bundles share no dynamic body, kernels never write a fixed
        // body's row, and only this thread touches the rows between colours.
        let rows = unsafe { SharedRows::new(bodies) };
        match self.built {
            Some(Width::Eight) => {
                let run: BlockRun<Lanes8> = eight::run_block;
                self.eight.run_shared(region, rows, work, (joints, run))
            }
            Some(Width::One) => {
                let run: BlockRun<Lanes1> = run_block::<Lanes1>;
                self.single.run_shared(region, rows, work, (joints, run))
            }
            _ => {
                let run: BlockRun<Lanes4> = run_block::<Lanes4>;
                self.four.run_shared(region, rows, work, (joints, run))
            }
        }
    }

    /// Hand each packed contact its points' impulses, for the store stage to write back: in
    /// key order where this thread packed them (each contact's lane read where its
    /// [`Place`] says), else bundle by bundle.
    pub fn store(
        &self,
        contacts: &mut [Contact],
        mut then: impl FnMut(&mut Contact, &[PointImpulses; 2]),
    ) {
        if !self.places.is_empty() {
            let (places, overflow) = (&self.places[..], &self.overflow);
            match self.built {
                Some(Width::Eight) => store_in_order(&self.eight, overflow, places, contacts, then),
                Some(Width::One) => store_in_order(&self.single, overflow, places, contacts, then),
                _ => store_in_order(&self.four, overflow, places, contacts, then),
            }
            return;
        }
        self.overflow.store(contacts, &mut then);
        match self.built {
            Some(Width::Eight) => eight::store(&self.eight, contacts, &mut then),
            Some(Width::One) => self.single.store(contacts, &mut then),
            _ => self.four.store(contacts, &mut then),
        }
    }

    /// [`ContactBundles::store`] with the colours' bundles spread over `region`'s workers.
    pub fn store_shared(&self, region: &Region, contacts: &mut [Contact], then: &StoreFn) {
        self.overflow.store(contacts, &mut |c, ends| then(c, ends));
        // SAFETY: each contact is in one bundle's lane (`Packed::store_shared`).
        let contacts = unsafe { SharedSlice::new(contacts) };
        let to = (contacts, then);
        match self.built {
            Some(Width::Eight) => self.eight.store_shared(region, to, eight::store_block),
            Some(Width::One) => self.single.store_shared(region, to, store_block::<Lanes1>),
            _ => self.four.store_shared(region, to, store_block::<Lanes4>),
        }
    }

    /// Contacts in the overflow at the last build.
    #[cfg(test)]
    pub fn overflow_count(&self) -> usize {
        self.overflow.packed.iter().map(|l| l.bundles.len()).sum()
    }

    /// Coloured bundles at the last build.
    #[cfg(test)]
    pub fn coloured_bundles(&self) -> usize {
        match self.built {
            Some(Width::Eight) => self.eight.packed.iter().map(|l| l.bundles.len()).sum(),
            Some(Width::One) => self.single.packed.iter().map(|l| l.bundles.len()).sum(),
            _ => self.four.packed.iter().map(|l| l.bundles.len()).sum(),
        }
    }

    /// Coloured bundles of one-point contacts ([`BundleKind::Single`]) at the last build.
    #[cfg(test)]
    pub fn single_bundles(&self) -> usize {
        match self.built {
            Some(Width::Eight) => self.eight.count_of(BundleKind::Single),
            Some(Width::One) => self.single.count_of(BundleKind::Single),
            _ => self.four.count_of(BundleKind::Single),
        }
    }
}

/// Write contact `c` (index `i`) with its constraint `k` into the next lane of `list`, of
/// which `filled` lanes are taken, opening a bundle (`inert()`) and its ledger when the last
/// is full; its restitution and rounding lanes, if it has them, into `bounces` and `rounds`.
#[inline(always)]
fn put<L: Wide>(
    list: &mut List<L>,
    (bounces, rounds): (&mut Vec<BounceLanes<L>>, &mut Vec<RoundLanes<L>>),
    (filled, inert): (&mut usize, impl FnOnce() -> Bundle<L>),
    (i, c): (usize, &Contact),
    k: &ContactConstraint,
    bodies: &[SolverBody],
) {
    let lane = *filled % L::WIDTH;
    *filled += 1;
    if lane == 0 {
        list.bundles.push(inert());
        list.ledgers.push(Ledger::empty());
    }
    let (Some(bundle), Some(ledger)) = (list.bundles.last_mut(), list.ledgers.last_mut()) else {
        unreachable!("a bundle is open, with its ledger");
    };
    bundle.set_contact((lane, ledger), (i as u32, c), k, bodies);
    if c.restitution != 0.0 {
        if bundle.bounce_index == NO_BOUNCE {
            bundle.bounce_index = bounces.len() as u32;
            bounces.push(BounceLanes::NONE);
        }
        bounces[bundle.bounce_index as usize].set(lane, c);
    }
    if c.rounding != [0.0; 2] {
        if bundle.round_index == NO_ROUNDING {
            bundle.round_index = rounds.len() as u32;
            rounds.push(RoundLanes::NONE);
        }
        rounds[bundle.round_index as usize].set(lane, c);
    }
}

/// Where the packer put a contact: its index (the high half), its list's slot (the overflow's
/// from [`IN_OVERFLOW`]) and its lane's place in the list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Place(u64);

impl Place {
    /// Bits of a lane's place in its list (32 million lanes a list).
    const LANE_BITS: u32 = 25;
    /// A contact whose place does not fit ([`Packer::finish`] then keeps none).
    const NONE: Place = Place(u64::MAX);

    /// Contact `i` in lane `lane` of list `slot`.
    #[inline(always)]
    fn of(i: usize, slot: usize, lane: usize) -> Place {
        if lane >> Self::LANE_BITS != 0 {
            return Self::NONE;
        }
        Place(((i as u64) << 32) | ((slot as u64) << Self::LANE_BITS) | lane as u64)
    }

    /// The contact, slot and lane.
    #[inline(always)]
    fn parts(self) -> (usize, usize, usize) {
        let low = self.0 as u32;
        let mask = (1 << Self::LANE_BITS) - 1;
        let (i, slot) = ((self.0 >> 32) as usize, (low >> Self::LANE_BITS) as usize);
        (i, slot, (low & mask) as usize)
    }
}

/// The store in key order: each contact at `places` handed its lane's impulses from the
/// `coloured` lists or the `overflow`. The contacts stream through once, in order, and each
/// colour's bundles are read in order too; bundle by bundle, the writes went all over the
/// contacts (a third of the store's time waited on their lines in large scenes).
fn store_in_order<L: Wide>(
    coloured: &Packed<L>,
    overflow: &Packed<Lanes1>,
    places: &[Place],
    contacts: &mut [Contact],
    mut then: impl FnMut(&mut Contact, &[PointImpulses; 2]),
) {
    let (lists, overflow_lists) = (coloured.by_slot(), overflow.by_slot());
    for &place in places {
        let (i, slot, lane) = place.parts();
        let ends = match slot.checked_sub(IN_OVERFLOW as usize) {
            Some(kind) => overflow.lane_impulses(overflow_lists[kind], lane),
            None => coloured.lane_impulses(lists[slot], lane),
        };
        if let Some(c) = contacts.get_mut(i) {
            then(c, &ends);
        }
    }
}

/// The list a prepared contact `c` (constraint `k`) is packed into: colour * KINDS + kind,
/// or for the overflow [`IN_OVERFLOW`] + kind (`singles`: [`ContactBundles::singles_apart`]).
#[inline(always)]
pub(crate) fn list_of(c: &Contact, k: &ContactConstraint, singles: bool) -> u8 {
    let s = kind_slot(kind_of(c, k, singles)) as u8;
    if c.colour >= OVERFLOW {
        IN_OVERFLOW + s
    } else {
        c.colour * KINDS as u8 + s
    }
}

/// [`list_of`]'s lists from here on are the overflow's.
pub(crate) const IN_OVERFLOW: u8 = LISTS as u8;

/// A bit beside a [`list_of`] list, free in every one: the contact overlaps deeper than its
/// spring reaches (the recover stage's).
pub(crate) const DEEP: u8 = 128;

const _: () = assert!(
    IN_OVERFLOW as usize + KINDS <= DEEP as usize,
    "DEEP is free in a list"
);

/// What packing on the workers reads: the bodies, the contacts, which of them to pack, and
/// each selected contact's prepared constraint and list ([`list_of`], maybe with [`DEEP`]),
/// in selection order.
pub(crate) struct SharedPackInput<'a, 'b> {
    pub bodies: &'a [SolverBody],
    pub contacts: &'a [Contact],
    pub selected: Selected<'b>,
    pub prepared: &'a [ContactConstraint],
    pub lists: &'a [u8],
}

/// [`pack`] with the contacts already prepared and the colours' lists filled by `region`'s
/// workers, a list each; the overflow by this thread. `order` is scratch. The bundles hold
/// the contacts in the same order as [`pack`]'s; their side lanes are numbered otherwise.
fn pack_shared<L: Wide>(
    (coloured, overflow): (&mut Packed<L>, &mut Packed<Lanes1>),
    input: &SharedPackInput,
    region: &Region,
    order: &mut Vec<u32>,
) -> bool {
    let SharedPackInput {
        bodies,
        contacts,
        selected,
        prepared,
        lists,
    } = *input;
    let dummy = (bodies.len() - 1) as u32;
    coloured.reset(LISTS);
    // The selected contacts by list, each list in selection (key) order: a counting sort.
    let mut starts = [0u32; LISTS + 1];
    for &l in lists {
        let l = l & !DEEP;
        if l < IN_OVERFLOW {
            starts[l as usize + 1] += 1;
        }
    }
    for l in 1..starts.len() {
        starts[l] += starts[l - 1];
    }
    order.clear();
    order.resize(starts[LISTS] as usize, 0);
    let mut next = starts;
    for (m, &l) in lists.iter().enumerate() {
        let l = l & !DEEP;
        if l < IN_OVERFLOW {
            order[next[l as usize] as usize] = m as u32;
            next[l as usize] += 1;
        }
    }
    coloured.list_sides.resize_with(LISTS, Default::default);
    let inert = ALL_KINDS.map(|kind| Bundle::<L>::inert(kind, dummy));
    let order = &*order;
    // SAFETY: each block fills its own list and its own side lanes.
    let (out, sides) = unsafe {
        (
            SharedSlice::new(&mut coloured.lists),
            SharedSlice::new(&mut coloured.list_sides),
        )
    };
    region.for_blocks(LISTS, &|l| {
        // SAFETY: as above.
        let (list, sides) = unsafe { (out.get(l), sides.get(l)) };
        let (list, (bounces, rounds)) = (list.expect("a list"), sides.expect("its side lanes"));
        bounces.clear();
        rounds.clear();
        let mut filled = 0;
        for &m in &order[starts[l] as usize..starts[l + 1] as usize] {
            let i = selected.at(m as usize);
            let (c, k) = (&contacts[i], &prepared[m as usize]);
            let inert = &inert[l % KINDS];
            put(
                list,
                (bounces, rounds),
                (&mut filled, || *inert),
                (i, c),
                k,
                bodies,
            );
        }
    });
    coloured.join_sides();
    coloured.mark_filled();
    let inert_one = ALL_KINDS.map(|kind| Bundle::inert(kind, dummy));
    let mut overflowed = [0usize; KINDS];
    let mut bouncy = false;
    for (m, &l) in lists.iter().enumerate() {
        let (i, l) = (selected.at(m), l & !DEEP);
        if l >= IN_OVERFLOW {
            let s = (l - IN_OVERFLOW) as usize;
            let (c, k) = (&contacts[i], &prepared[m]);
            overflow.put((s, &mut overflowed[s]), || inert_one[s], (i, c), k, bodies);
        }
    }
    for l in 0..LISTS {
        bouncy |= !coloured.list_sides[l].0.is_empty();
    }
    bouncy |= !overflow.bounces.is_empty();
    coloured.close();
    overflow.close();
    bouncy
}

/// Where packing writes: the coloured lists and the overflow, the fixed dummy body that a new
/// bundle's empty lanes point at, how full each list is, and whether any contact bounces.
struct Packer<'p, L: Wide> {
    coloured: &'p mut Packed<L>,
    overflow: &'p mut Packed<Lanes1>,
    /// Each contact's [`Place`], in packing order.
    places: &'p mut Vec<Place>,
    dummy: u32,
    filled: [usize; LISTS],
    overflowed: [usize; KINDS],
    bouncy: bool,
}

impl<'p, L: Wide> Packer<'p, L> {
    /// Empty lists, for `bodies` (the last the fixed dummy that empty lanes point at).
    fn new(
        (coloured, overflow, places): (
            &'p mut Packed<L>,
            &'p mut Packed<Lanes1>,
            &'p mut Vec<Place>,
        ),
        bodies: &[SolverBody],
    ) -> Self {
        let dummy = (bodies.len() - 1) as u32;
        coloured.reset(LISTS);
        places.clear();
        Packer {
            coloured,
            overflow,
            places,
            dummy,
            filled: [0; LISTS],
            overflowed: [0; KINDS],
            bouncy: false,
        }
    }

    /// Contact `c` (index `i`) prepared as `k` into the next lane of list `kind` of `colour`
    /// (or of the overflow).
    #[inline(always)]
    fn place(
        &mut self,
        (i, c): (usize, &Contact),
        k: &ContactConstraint,
        (colour, kind): (u8, usize),
        bodies: &[SolverBody],
    ) {
        self.bouncy |= c.restitution != 0.0;
        let dummy = self.dummy;
        let place = if colour >= OVERFLOW {
            let filled = &mut self.overflowed[kind];
            let place = Place::of(i, IN_OVERFLOW as usize + kind, *filled);
            let inert = || Bundle::inert(ALL_KINDS[kind], dummy);
            self.overflow.put((kind, filled), inert, (i, c), k, bodies);
            place
        } else {
            let slot = colour as usize * KINDS + kind;
            let filled = &mut self.filled[slot];
            let place = Place::of(i, slot, *filled);
            let inert = || Bundle::inert(ALL_KINDS[kind], dummy);
            self.coloured.put((slot, filled), inert, (i, c), k, bodies);
            place
        };
        self.places.push(place);
    }

    /// Close the lists; whether any contact bounces.
    fn finish(self) -> bool {
        self.coloured.close();
        self.overflow.close();
        if self.places.contains(&Place::NONE) {
            self.places.clear();
        }
        self.bouncy
    }
}

/// Pack the selected contacts into `coloured` bundles and the `overflow`, one-point contacts
/// apart if `singles`; whether any bounces. A small solve without joints (`small`) fills its
/// half-empty bundles from other colours ([`pack_small`]).
fn pack<L: Wide, P>(
    lists: (&mut Packed<L>, &mut Packed<Lanes1>, &mut Vec<Place>),
    input: PackInput<'_, '_, P>,
    (singles, small): (bool, Option<&mut SmallSolve>),
) -> bool
where
    P: FnMut(&mut Contact, &SolverBody, &SolverBody, &mut ContactConstraint),
{
    let mut packer = Packer::new(lists, input.bodies);
    if let Some(small) = small {
        return pack_small(packer, input, (singles, small));
    }
    let PackInput {
        bodies,
        contacts,
        selected,
        mut prepare,
        ..
    } = input;
    // (Written in place, field by field, and read the same way: returned, the constraint was
    // copied in 16-byte pieces over its 4- and 8-byte stores, which stalls store forwarding.)
    let mut k = ContactConstraint::default();
    selected.for_each_index(contacts.len(), |i| {
        let c = &mut contacts[i];
        let (a, b) = (&bodies[c.a as usize], &bodies[c.b as usize]);
        prepare(c, a, b, &mut k);
        let kind = kind_slot(kind_of(c, &k, singles));
        packer.place((i, c), &k, (c.colour, kind), bodies);
    });
    packer.finish()
}

/// A small solve's contacts while [`pack_small`] packs them: prepared, then placed.
#[derive(Clone, Debug, Default)]
pub(crate) struct SmallSolve {
    entries: Vec<Entry>,
    prepared: Vec<(usize, ContactConstraint)>,
}

/// [`pack`] in two passes: every contact prepared, then moved between colours where that
/// saves a bundle and changes no result ([`fill_gaps`]), then placed.
fn pack_small<L: Wide, P>(
    mut packer: Packer<'_, L>,
    input: PackInput<'_, '_, P>,
    (singles, small): (bool, &mut SmallSolve),
) -> bool
where
    P: FnMut(&mut Contact, &SolverBody, &SolverBody, &mut ContactConstraint),
{
    let PackInput {
        bodies,
        contacts,
        selected,
        mut prepare,
        ..
    } = input;
    let SmallSolve { entries, prepared } = small;
    entries.clear();
    prepared.clear();
    // Static, kinematic and the dummy: nothing is written to them, so they order nothing.
    let node = |slot: u32, body: &SolverBody| {
        let moves = body.inv_mass != 0.0 || body.inv_inertia != 0.0;
        if moves {
            slot
        } else {
            NOT_A_NODE
        }
    };
    selected.for_each_index(contacts.len(), |i| {
        let c = &mut contacts[i];
        let (a, b) = (&bodies[c.a as usize], &bodies[c.b as usize]);
        let mut k = ContactConstraint::default();
        prepare(c, a, b, &mut k);
        entries.push(Entry {
            colour: c.colour,
            kind: kind_slot(kind_of(c, &k, singles)) as u8,
            nodes: [node(c.a, a), node(c.b, b)],
        });
        prepared.push((i, k));
    });
    fill_gaps(entries, L::WIDTH, KINDS);
    for ((i, k), e) in prepared.iter().zip(entries.iter()) {
        packer.place((*i, &contacts[*i]), k, (e.colour, e.kind as usize), bodies);
    }
    packer.finish()
}

/// The eight-lane stages: compiled for AVX2 on x86-64, where [`ContactBundles::build`] packs
/// eight-lane bundles only if the processor has it; elsewhere never chosen.
mod eight {
    use super::{
        Block, BodyRows, BounceLanes, Bundle, Contact, Joints, Lanes8, Ledger, Packed, PassArgs,
        PointImpulses, Real, SharedSlice, SideLanes, SolverBody, StoreFn, Work,
    };

    /// Runs `$body` compiled for AVX2 where `Lanes8` is an AVX register, plainly elsewhere.
    macro_rules! avx2 {
        ($name:ident($($arg:ident: $ty:ty),*) $body:block) => {
            pub(super) fn $name($($arg: $ty),*) {
                #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
                {
                    /// # Safety
                    /// The processor must have AVX2.
                    #[target_feature(enable = "avx2")]
                    unsafe fn run($($arg: $ty),*) $body
                    // SAFETY: eight-lane bundles exist only where the processor has AVX2.
                    unsafe { run($($arg),*) }
                }
                #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
                $body
            }
        };
    }

    avx2!(warm_start(packed: &mut Packed<Lanes8>, bodies: &mut [SolverBody], warm_starting: bool, joints: Joints) {
        packed.warm_start(bodies, warm_starting, joints)
    });
    avx2!(solve(packed: &mut Packed<Lanes8>, bodies: &mut [SolverBody], args: PassArgs, joints: Joints) {
        packed.solve(bodies, args, joints)
    });
    avx2!(apply_restitution(packed: &mut Packed<Lanes8>, bodies: &mut [SolverBody], threshold: Real) {
        packed.apply_restitution(bodies, threshold)
    });
    avx2!(run_block(block: Block<Lanes8>, rows: BodyRows, work: Work, side: SideLanes<Lanes8>) {
        super::run_block(block, rows, work, side)
    });
    avx2!(store_block(ledgers: &[Ledger<Lanes8>], bundles: &[Bundle<Lanes8>], bounces: &[BounceLanes<Lanes8>], contacts: SharedSlice<Contact>, then: &StoreFn) {
        super::store_block(ledgers, bundles, bounces, contacts, then)
    });

    /// [`Packed::store`] compiled for AVX2 where `Lanes8` is an AVX register, plainly
    /// elsewhere (generic over `then`, which the macro's functions cannot be).
    pub(super) fn store<F>(packed: &Packed<Lanes8>, contacts: &mut [Contact], then: &mut F)
    where
        F: FnMut(&mut Contact, &[PointImpulses; 2]),
    {
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        {
            /// # Safety
            /// The processor must have AVX2.
            #[target_feature(enable = "avx2")]
            unsafe fn run<F>(packed: &Packed<Lanes8>, contacts: &mut [Contact], then: &mut F)
            where
                F: FnMut(&mut Contact, &[PointImpulses; 2]),
            {
                packed.store(contacts, then)
            }
            // SAFETY: eight-lane bundles exist only where the processor has AVX2.
            unsafe { run(packed, contacts, then) }
        }
        #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
        packed.store(contacts, then)
    }
}
