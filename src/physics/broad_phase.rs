//! Broad phase: which pairs of bodies might touch this step.
//!
//! Sort and sweep along x over two lists: *active* bodies (awake and dynamic), whose boxes move
//! every step, and *passive* ones (static or asleep), whose boxes do not. Both lists are kept
//! sorted by the left edge of their boxes. The active list barely changes order between steps,
//! so insertion sort restores it in close to linear time; the passive list is re-sorted only
//! when a body joins it. Active-active pairs come from a sweep; active-passive pairs from a
//! merge of the two sorted lists. Passive-passive pairs (static with static, or anything that
//! sleeps) are never examined, so a world at rest costs almost nothing here.
//!
//! A sweep along x alone tests every pair whose boxes overlap in x, and a column of bodies
//! overlaps all along itself: 2,000 boxes falling in a 40 x 50 grid took 41,000 tests a sweep
//! for no pair, 119,000 for 6,000 as they landed. So the active bodies are swept in horizontal
//! bands as tall as the tallest of their boxes ([`bands_of`]), each box in the bands it
//! reaches into, each pair reported in one band only; a pile's sweeps test about a tenth as
//! many pairs and find the same ones.
//!
//! The sweep runs on *fat* boxes, each body's box grown by [`FAT_MARGIN`], and its pairs are
//! kept. While every body's box stays inside its fat box (a pyramid or a pile at rest, awake),
//! those kept pairs are a superset of this step's, and filtering them by overlap gives this
//! step's exactly, without sweeping (Box2D's dynamic tree keeps fat boxes for the same reason).
//! When only a few boxes left their fat boxes (a settling pile: from 57 down to 1 of 2,000 a
//! step), only those get new fat boxes and only their pairs are searched again, against the
//! sorted lists (Box2D re-queries its moved proxies alike); the rest of the kept pairs stand.
//! The kept pairs are always exactly the pairs of overlapping fat boxes, and the output is the
//! same set whichever path ran, so results do not depend on it.
//!
//! A static body of several shapes (a ground of 20 segments, one a row of pyramids) is swept
//! shape by shape: its box spans all its shapes, and swept whole it paired with every body
//! above it (all 22,000 boxes of Box2D's `many_pyramids`), each pair then searched for
//! touching shapes every step. Its shapes' boxes ([`Piece`]s) stand in the passive list
//! instead, so only a body near one of its shapes pairs with it (Box2D's tree holds shapes,
//! not bodies). The kept pairs with such a body are those whose fat boxes meet a piece's; the
//! narrow phase tests its shapes one by one, so results are the same as swept whole.

use super::math::Real;
use super::shape::Aabb;
use super::team::{block, Region, SharedSlice};

/// What the broad phase needs to know about one body slot.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Proxy {
    /// Bounding box, already grown by the body's contact margin (m).
    pub aabb: Aabb,
}

/// One shape of a static body of several, swept in its body's place: the shape's box, grown
/// as a proxy is (m), and its body's slot.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Piece {
    pub slot: u32,
    pub aabb: Aabb,
}

/// A candidate pair as a sortable key: lower slot index in the high 32 bits.
#[inline]
pub(crate) fn pair_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (lo as u64) << 32 | hi as u64
}

/// How many items a worker marks at a time.
const MARKED_PER_BLOCK: usize = 1024;

/// `marks[i] = test(&items[i])` for every item, in blocks spread over `region`'s workers.
fn mark_shared<T: Sync>(
    region: &Region,
    items: &[T],
    marks: &mut Vec<bool>,
    test: &(dyn Fn(&T) -> bool + Sync),
) {
    let n = items.len();
    // (Only new room is filled: every mark is written below.)
    marks.resize(n, false);
    // SAFETY: each block writes its own run of marks.
    let shared = unsafe { SharedSlice::new(marks) };
    region.for_blocks(n.div_ceil(MARKED_PER_BLOCK), &|k| {
        let run = block(k, MARKED_PER_BLOCK, n);
        // SAFETY: as above.
        let marks = unsafe { shared.range(run.clone()) };
        for (mark, item) in marks.iter_mut().zip(&items[run]) {
            *mark = test(item);
        }
    });
}

/// The two slot indices of a pair key, lower first.
#[inline]
pub(crate) fn pair_of(key: u64) -> (u32, u32) {
    ((key >> 32) as u32, key as u32)
}

/// How far (m) a body's box may move or grow past its last swept position before the pairs
/// are swept again. Box2D v3 uses 0.1 m; half that keeps the extra pairs of a close-packed
/// pile few while a body at rest (moving well under a millimetre a step) stays inside for
/// many steps.
pub(crate) const FAT_MARGIN: Real = 0.05;

/// Sort-and-sweep broad phase with persistent orders.
#[derive(Debug, Default, Clone)]
pub(crate) struct SweepAndPrune {
    /// Awake dynamic bodies, sorted by `aabb.min.x` as of the last query.
    active: Vec<u32>,
    /// Static and sleeping bodies, sorted by `aabb.min.x` unless `passive_dirty`.
    passive: Vec<u32>,
    passive_dirty: bool,
    /// The boxes of `active` and `passive`, in their orders, side by side in memory: the
    /// sweeps read them in sequence instead of hopping through the proxies by slot.
    active_boxes: Vec<SortedBox>,
    passive_boxes: Vec<SortedBox>,
    /// Scratch for `set_passive`: the moved slots, sorted.
    moved: Vec<u32>,
    /// Each slot's box at the last sweep, grown by [`FAT_MARGIN`].
    fat: Vec<Aabb>,
    /// The pairs of overlapping fat boxes found by the last sweep, sorted.
    fat_pairs: Vec<u64>,
    /// False when the lists changed since the last sweep (a body came, went, slept or woke).
    fat_valid: bool,
    /// How many sweeps have run (the steps in between reused the fat pairs, or updated them).
    sweeps: u64,
    /// How many queries updated the fat pairs of the few bodies that left their fat boxes.
    updates: u64,
    /// Scratch for `find_pairs`: the slots outside their fat boxes, and a flag per slot.
    outside: Vec<u32>,
    outside_flag: Vec<bool>,
    /// Scratch for `find_pairs` on workers: a mark per body of the lists (outside its fat
    /// box) or per kept pair (its boxes overlap), gathered in order on one thread.
    marks: Vec<bool>,
    /// Scratch for `update`: the moved bodies' boxes and their new pairs.
    moved_boxes: Vec<SortedBox>,
    new_pairs: Vec<u64>,
    /// Scratch for [`bands_of`]: the active boxes band by band, and where each band ends.
    band_boxes: Vec<SortedBox>,
    band_start: Vec<u32>,
    /// Scratch for a sweep on workers: the pairs each block found.
    block_pairs: Vec<Vec<u64>>,
    /// Scratch for [`sort_keys`].
    sort_scratch: Vec<u64>,
    /// Scratch for [`sort_by_min_x`]: each body's left edge, place in the old order and slot;
    /// and whether the last sweep's order was sorted afresh.
    order_scratch: Vec<(Real, u32, u32)>,
    sorted_afresh: bool,
    /// Each slot's: whether its body is swept by its [`Piece`]s (sized only when some are).
    pieced: Vec<bool>,
    /// Scratch for `sweep`: the pieces' fat boxes, sorted by left edge.
    piece_boxes: Vec<SortedBox>,
    /// Slots freed since the lists were last compacted, flagged by slot in `dead` (removal
    /// marks them, the next query drops them in one pass: removing k bodies costs k, not k
    /// passes over the lists).
    dead: Vec<bool>,
    dead_count: usize,
}

/// A body's box in a sweep order, with its slot.
#[derive(Clone, Copy, Debug)]
struct SortedBox {
    min_x: Real,
    max_x: Real,
    min_y: Real,
    max_y: Real,
    slot: u32,
}

impl SortedBox {
    fn new(slot: u32, boxes: &[Aabb]) -> SortedBox {
        let b = &boxes[slot as usize];
        SortedBox {
            min_x: b.min.x,
            max_x: b.max.x,
            min_y: b.min.y,
            max_y: b.max.y,
            slot,
        }
    }

    /// Whether the two boxes overlap along y (the sweep has settled x).
    #[inline]
    fn overlaps_y(&self, other: &SortedBox) -> bool {
        (self.min_y <= other.max_y) & (other.min_y <= self.max_y)
    }
}

impl SweepAndPrune {
    /// A body slot came alive; `passive` for static or sleeping bodies.
    pub fn insert(&mut self, index: u32, passive: bool) {
        if self.dead.get(index as usize).copied().unwrap_or(false) {
            // The slot is reused before its old entry was dropped.
            self.compact();
        }
        if passive {
            self.passive.push(index);
            self.passive_dirty = true;
        } else {
            self.active.push(index);
        }
        self.fat_valid = false;
    }

    /// Body slots were freed. Their entries are dropped by the next query (or insert into a
    /// freed slot), in one pass however many went.
    pub fn remove(&mut self, slots: &[u32]) {
        for &i in slots {
            let i = i as usize;
            if i >= self.dead.len() {
                self.dead.resize(i + 1, false);
            }
            if !std::mem::replace(&mut self.dead[i], true) {
                self.dead_count += 1;
            }
        }
        self.fat_valid = false;
    }

    /// Drop the entries of freed slots from both lists.
    fn compact(&mut self) {
        if self.dead_count == 0 {
            return;
        }
        let dead = |i: &u32| self.dead.get(*i as usize).copied().unwrap_or(false);
        self.active.retain(|i| !dead(i));
        self.passive.retain(|i| !dead(i));
        self.dead.iter_mut().for_each(|d| *d = false);
        self.dead_count = 0;
    }

    /// Move bodies between the lists (they fell asleep, or woke up).
    pub fn set_passive(&mut self, indices: &[u32], passive: bool) {
        if indices.is_empty() {
            return;
        }
        let (from, to) = if passive {
            (&mut self.active, &mut self.passive)
        } else {
            (&mut self.passive, &mut self.active)
        };
        // Linear in the list, whatever the number moved (a pyramid falls asleep at once).
        self.moved.clear();
        self.moved.extend_from_slice(indices);
        self.moved.sort_unstable();
        let moved = &self.moved;
        from.retain(|i| moved.binary_search(i).is_err());
        to.extend_from_slice(indices);
        if passive {
            self.passive_dirty = true;
        }
        self.fat_valid = false;
    }

    /// True when no body is awake and dynamic.
    pub fn active_is_empty(&mut self) -> bool {
        self.compact();
        self.active.is_empty()
    }

    /// How many bodies are awake and dynamic (or kinematic).
    pub fn active_count(&mut self) -> usize {
        self.compact();
        self.active.len()
    }

    /// Forget every body.
    pub fn clear(&mut self) {
        self.active.clear();
        self.passive.clear();
        self.dead.clear();
        self.dead_count = 0;
        self.fat_valid = false;
    }

    /// Fill `out` with the keys of all active-active and active-passive pairs whose boxes
    /// overlap, sorted ascending. `proxies` is indexed by slot; `pieces` are the shapes of the
    /// static bodies swept shape by shape, by slot (a pair with one of them is kept where a
    /// piece's fat box meets the other body's and their whole boxes overlap).
    pub fn find_pairs(
        &mut self,
        proxies: &[Proxy],
        pieces: &[Piece],
        out: &mut Vec<u64>,
        region: Option<&Region>,
    ) {
        out.clear();
        if self.active_is_empty() {
            return;
        }
        self.flag_pieced(proxies.len(), pieces);
        self.outside.clear();
        let kept = self.fat_valid && self.fat.len() == proxies.len();
        // More than this many outside and the whole sweep runs: the count stops there.
        let most = self.active.len() / UPDATE_FRACTION;
        if kept {
            self.find_outside(proxies, most, region);
        }
        // A body swept by pieces that grew (the margins changed) is swept again whole.
        let pieced = &self.pieced;
        let piece_moved = !pieces.is_empty() && self.outside.iter().any(|&i| pieced[i as usize]);
        if !kept || self.outside.len() > most || piece_moved {
            self.fat.clear();
            self.fat
                .extend(proxies.iter().map(|p| p.aabb.inflated(FAT_MARGIN)));
            let fat = std::mem::take(&mut self.fat);
            let mut pairs = std::mem::take(&mut self.fat_pairs);
            self.sweep(&fat, pieces, &mut pairs, region);
            (self.fat, self.fat_pairs) = (fat, pairs);
            self.fat_valid = true;
        } else if !self.outside.is_empty() {
            self.update(proxies);
        }
        let overlap = |key: &u64| {
            let (a, b) = pair_of(*key);
            proxies[a as usize].aabb.overlaps(&proxies[b as usize].aabb)
        };
        let pairs = &self.fat_pairs;
        match region {
            None => out.extend(pairs.iter().copied().filter(overlap)),
            Some(region) => {
                mark_shared(region, pairs, &mut self.marks, &overlap);
                let kept = pairs.iter().zip(&self.marks).filter(|(_, &m)| m);
                out.extend(kept.map(|(&key, _)| key));
            }
        }
    }

    /// Into `outside`, the first `most + 1` bodies of the lists (active, then passive) whose
    /// boxes left their fat boxes.
    fn find_outside(&mut self, proxies: &[Proxy], most: usize, region: Option<&Region>) {
        let fat = &self.fat;
        let left = |i: &u32| {
            let (tight, fat) = (&proxies[*i as usize].aabb, &fat[*i as usize]);
            !(fat.min.x <= tight.min.x
                && fat.min.y <= tight.min.y
                && tight.max.x <= fat.max.x
                && tight.max.y <= fat.max.y)
        };
        let Some(region) = region else {
            let all = self.active.iter().chain(&self.passive);
            self.outside
                .extend(all.filter(|i| left(i)).take(most + 1).copied());
            return;
        };
        // The active list, then the passive one (whose boxes do not move: few leave).
        mark_shared(region, &self.active, &mut self.marks, &left);
        let marked = self.active.iter().zip(&self.marks).filter(|(_, &m)| m);
        self.outside.extend(marked.take(most + 1).map(|(&i, _)| i));
        if self.outside.len() <= most {
            let rest = most + 1 - self.outside.len();
            let passive = self.passive.iter().filter(|i| left(i));
            self.outside.extend(passive.take(rest).copied());
        }
    }

    /// Flag the slots swept by `pieces` (a world without any skips this).
    fn flag_pieced(&mut self, slots: usize, pieces: &[Piece]) {
        if pieces.is_empty() && self.pieced.is_empty() {
            return;
        }
        self.pieced.clear();
        if !pieces.is_empty() {
            self.pieced.resize(slots, false);
            for p in pieces {
                self.pieced[p.slot as usize] = true;
            }
        }
    }

    /// Give the bodies in `outside` new fat boxes from `proxies` and search their pairs
    /// again; every other kept pair stands (its fat boxes did not change). Afterwards the
    /// kept pairs are again exactly the active-active and active-passive pairs of overlapping
    /// fat boxes, sorted.
    fn update(&mut self, proxies: &[Proxy]) {
        self.updates += 1;
        if self.outside_flag.len() < self.fat.len() {
            self.outside_flag.resize(self.fat.len(), false);
        }
        for &i in &self.outside {
            self.fat[i as usize] = proxies[i as usize].aabb.inflated(FAT_MARGIN);
            self.outside_flag[i as usize] = true;
        }
        let flag = &self.outside_flag;
        let moved = |key: &u64| {
            let (a, b) = pair_of(*key);
            flag[a as usize] || flag[b as usize]
        };
        self.fat_pairs.retain(|key| !moved(key));

        // The sorted lists with the new boxes, sorted again (a few entries moved a little).
        let fat = &self.fat;
        for b in self.active_boxes.iter_mut().chain(&mut self.passive_boxes) {
            if flag[b.slot as usize] {
                *b = SortedBox::new(b.slot, fat);
            }
        }
        insertion_sort_boxes(&mut self.active_boxes);
        insertion_sort_boxes(&mut self.passive_boxes);
        self.active.clear();
        self.active.extend(self.active_boxes.iter().map(|b| b.slot));
        self.passive.clear();
        if self.pieced.is_empty() {
            self.passive
                .extend(self.passive_boxes.iter().map(|b| b.slot));
        } else {
            // Each piece stands in the sorted list; its body is listed once, at the end.
            let pieced = &self.pieced;
            self.passive.extend(
                self.passive_boxes
                    .iter()
                    .map(|b| b.slot)
                    .filter(|&i| !pieced[i as usize]),
            );
            let by_pieces = pieced.iter().enumerate().filter(|(_, &p)| p);
            self.passive.extend(by_pieces.map(|(i, _)| i as u32));
        }

        // The moved boxes, active and passive apart (each in sorted order), against the
        // lists they pair with: moved active boxes with the active and the passive ones,
        // moved passive ones with the active ones. A pair of two moved boxes is found from
        // both sides; duplicates go below.
        let (active, passive) = (&self.active_boxes, &self.passive_boxes);
        let is_moved = |b: &&SortedBox| flag[b.slot as usize];
        self.moved_boxes.clear();
        self.moved_boxes.extend(active.iter().filter(is_moved));
        let moved_active = self.moved_boxes.len();
        self.moved_boxes.extend(passive.iter().filter(is_moved));
        let (moved_active, moved_passive) = self.moved_boxes.split_at(moved_active);
        self.new_pairs.clear();
        cross_pairs(moved_active, active, &mut self.new_pairs);
        cross_pairs(moved_active, passive, &mut self.new_pairs);
        cross_pairs(moved_passive, active, &mut self.new_pairs);
        sort_keys(&mut self.new_pairs, &mut self.sort_scratch, proxies.len());
        self.new_pairs.dedup();
        merge_sorted(&mut self.fat_pairs, &self.new_pairs);
        for &i in &self.outside {
            self.outside_flag[i as usize] = false;
        }
    }

    /// Fill `out` with the active-active and active-passive pairs of overlapping `boxes`
    /// (indexed by slot), the bodies swept by `pieces` through their pieces (grown as `boxes`
    /// are), sorted ascending; the sweeps in blocks over `region`'s workers, if any and there
    /// are enough boxes (sorted, the pairs are the same whoever found them).
    fn sweep(
        &mut self,
        boxes: &[Aabb],
        pieces: &[Piece],
        out: &mut Vec<u64>,
        region: Option<&Region>,
    ) {
        out.clear();
        self.sweeps += 1;
        let min_x = |i: u32| boxes[i as usize].min.x;
        let scratch = (&mut self.order_scratch, &mut self.sorted_afresh);
        sort_by_min_x(&mut self.active, boxes, scratch);
        if self.passive_dirty {
            self.passive
                .sort_unstable_by(|&a, &b| min_x(a).total_cmp(&min_x(b)).then(a.cmp(&b)));
            self.passive_dirty = false;
        }
        self.active_boxes.clear();
        self.active_boxes
            .extend(self.active.iter().map(|&i| SortedBox::new(i, boxes)));
        self.passive_boxes.clear();
        if pieces.is_empty() {
            self.passive_boxes
                .extend(self.passive.iter().map(|&i| SortedBox::new(i, boxes)));
        } else {
            self.sort_pieces_in(boxes, pieces);
        }
        let (active, passive) = (&self.active_boxes, &self.passive_boxes);
        let bands = bands_of(active, &mut self.band_boxes, &mut self.band_start);
        let swept = Swept {
            active,
            passive,
            bands: bands.map(|n| (&self.band_boxes[..], &self.band_start[..n])),
        };
        match region.filter(|_| active.len() >= SHARED_SWEEP_FROM) {
            None => swept.pairs(out),
            Some(region) => swept.pairs_shared(region, &mut self.block_pairs, out),
        }
        sort_keys(out, &mut self.sort_scratch, boxes.len());
        if !pieces.is_empty() {
            // A body near two pieces of one body paired with each.
            out.dedup();
        }
    }

    /// The passive boxes in sorted order with each body swept by pieces replaced by its
    /// pieces' fat boxes (merged in: both lists are sorted by left edge).
    fn sort_pieces_in(&mut self, boxes: &[Aabb], pieces: &[Piece]) {
        self.piece_boxes.clear();
        self.piece_boxes.extend(pieces.iter().map(|p| {
            let b = p.aabb.inflated(FAT_MARGIN);
            SortedBox {
                min_x: b.min.x,
                max_x: b.max.x,
                min_y: b.min.y,
                max_y: b.max.y,
                slot: p.slot,
            }
        }));
        self.piece_boxes
            .sort_unstable_by(|a, b| a.min_x.total_cmp(&b.min_x).then(a.slot.cmp(&b.slot)));
        let pieced = &self.pieced;
        let mut whole = self
            .passive
            .iter()
            .filter(|&&i| !pieced[i as usize])
            .map(|&i| SortedBox::new(i, boxes))
            .peekable();
        let mut parts = self.piece_boxes.iter().copied().peekable();
        loop {
            let take_whole = match (whole.peek(), parts.peek()) {
                (Some(w), Some(p)) => w.min_x <= p.min_x,
                (Some(_), None) => true,
                (None, Some(_)) => false,
                (None, None) => break,
            };
            let next = if take_whole {
                whole.next()
            } else {
                parts.next()
            };
            self.passive_boxes.extend(next);
        }
    }
}

/// Sort `active` (sorted by left edge) into horizontal bands for the sweep along x, into
/// `boxes`, and return how many (band k ends at `starts[k]`), or None when one plain sweep
/// of `active` is the sweep. Band k holds the boxes that reach into [y0 + k h, y0 + (k + 1) h),
/// with h the tallest box's height but the outliers' (so a box is in one or two bands, three
/// only by rounding; an outlier in as many as it reaches), each band in the list's order. A
/// pair is pushed only in the band of the higher of its two lower edges: that edge lies in
/// both boxes' height, so both are in its band (the band of a height is non-decreasing in it,
/// rounding included), and it is one band. Within a band the tests are the plain sweep's, so
/// the pairs are exactly its pairs.
fn bands_of(
    active: &[SortedBox],
    boxes: &mut Vec<SortedBox>,
    starts: &mut Vec<u32>,
) -> Option<usize> {
    let (mut y0, mut y1, mut sum) = (Real::INFINITY, Real::NEG_INFINITY, 0.0 as Real);
    let mut slots = 0;
    for b in active {
        y0 = y0.min(b.min_y);
        y1 = y1.max(b.max_y);
        sum += b.max_y - b.min_y;
        slots |= b.slot;
    }
    // The tallest box but the outliers: one body many times the others' size (Box2D's
    // tumbler's drum, 28 m around 0.35 m boxes) would make one band of them all. An outlier
    // goes into every band it reaches, which costs it one insertion per band.
    let cap = OUTLIER * sum / active.len().max(1) as Real;
    let (mut height, mut tallest) = (0.0 as Real, 0.0 as Real);
    for b in active {
        let h = b.max_y - b.min_y;
        tallest = tallest.max(h);
        if h <= cap {
            height = height.max(h);
        }
    }
    // Unless the outliers together would be inserted more than three times per box (many
    // tall boxes): then the tallest sets the height, as without outliers.
    let insertions: Real = active
        .iter()
        .map(|b| ((b.max_y - b.min_y) - cap).max(0.0))
        .sum::<Real>()
        / height;
    let few = insertions <= 3.0 * active.len() as Real;
    if !few {
        height = tallest;
    }
    // At most one band per two boxes: a world of small boxes spread very far apart
    // vertically does not pay for empty bands.
    let most = (active.len() / 2).max(1) as Real;
    let height = height.max((y1 - y0) / most);
    let bands = ((y1 - y0) / height).floor() + 1.0;
    let flaggable = slots & LOWEST == 0;
    if active.len() < BANDS_FROM
        || !(height > 0.0 && bands.is_finite())
        || bands < 2.0
        || !flaggable
    {
        return None;
    }
    // Every y here is at or above y0, so truncating is flooring (and no call to floorf).
    // Multiplying by the reciprocal is as monotonic as dividing, and cheaper.
    let per_height = 1.0 / height;
    let band = |y: Real| (((y - y0) * per_height) as usize).min(bands as usize - 1);
    sort_into_bands(active, (band, bands as usize), boxes, starts);
    Some(bands as usize)
}

/// What a full sweep pairs: the active boxes with each other (in bands, if [`bands_of`] made
/// them: the boxes band by band and each band's end) and with the passive ones.
struct Swept<'a> {
    active: &'a [SortedBox],
    passive: &'a [SortedBox],
    bands: Option<(&'a [SortedBox], &'a [u32])>,
}

impl Swept<'_> {
    /// Push every pair, on this thread.
    fn pairs(&self, out: &mut Vec<u64>) {
        match self.bands {
            None => sweep_band(self.active, false, out),
            Some((boxes, ends)) => {
                // The band of the higher lower edge is the higher of the two lower edges'
                // bands (the band is non-decreasing in the height), and both boxes reach into
                // band k, so neither lower edge's band is above k: the pair is band k's when
                // either box is lowest in it.
                let mut start = 0;
                for &end in ends {
                    sweep_band(&boxes[start..end as usize], true, out);
                    start = end as usize;
                }
            }
        }
        // Active with passive: each active box against the passive list, from both sides.
        cross_from(self.active, self.passive, out);
        cross_to(self.active, self.passive, out);
    }

    /// Push every pair, in blocks spread over `region`'s workers: runs of bands of about
    /// [`SWEPT_PER_BLOCK`] boxes, then runs of the active boxes against the passive list, then
    /// runs of the passive boxes against the active list, each block's pairs into its own
    /// list of `per_block`, appended to `out` in block order.
    fn pairs_shared(&self, region: &Region, per_block: &mut Vec<Vec<u64>>, out: &mut Vec<u64>) {
        // The bands' blocks: where each run of bands ends (one plain sweep: one block).
        let mut band_runs = [0u32; MAX_BAND_BLOCKS];
        let runs = match self.bands {
            None => {
                band_runs[0] = 1;
                1
            }
            Some((boxes, ends)) => {
                let per = boxes.len().div_ceil(MAX_BAND_BLOCKS).max(SWEPT_PER_BLOCK);
                let mut runs = 0;
                let mut from = 0;
                for (k, &end) in ends.iter().enumerate() {
                    let full = end as usize - from >= per && runs + 1 < MAX_BAND_BLOCKS;
                    if full || k + 1 == ends.len() {
                        band_runs[runs] = k as u32 + 1;
                        runs += 1;
                        from = end as usize;
                    }
                }
                runs
            }
        };
        let (active, passive) = (self.active, self.passive);
        let from_blocks = active.len().div_ceil(SWEPT_PER_BLOCK);
        let to_blocks = passive.len().div_ceil(SWEPT_PER_BLOCK);
        let blocks = runs + from_blocks + to_blocks;
        if per_block.len() < blocks {
            per_block.resize_with(blocks, Vec::new);
        }
        // SAFETY: each block writes its own list.
        let lists = unsafe { SharedSlice::new(&mut per_block[..blocks]) };
        let band_runs = &band_runs[..runs];
        region.for_blocks(blocks, &|k| {
            // SAFETY: as above.
            let out = unsafe { lists.get(k) }.expect("a list a block");
            out.clear();
            if k < runs {
                self.band_run(band_runs, k, out);
            } else if k < runs + from_blocks {
                let run = block(k - runs, SWEPT_PER_BLOCK, active.len());
                cross_from(&active[run], passive, out);
            } else {
                let run = block(k - runs - from_blocks, SWEPT_PER_BLOCK, passive.len());
                cross_to(active, &passive[run], out);
            }
        });
        for list in &per_block[..blocks] {
            out.extend_from_slice(list);
        }
    }

    /// The pairs of run `k` of the bands (`runs`: where each ends, in bands).
    fn band_run(&self, runs: &[u32], k: usize, out: &mut Vec<u64>) {
        let Some((boxes, ends)) = self.bands else {
            return sweep_band(self.active, false, out);
        };
        let first = if k == 0 { 0 } else { runs[k - 1] as usize };
        let mut start = if first == 0 {
            0
        } else {
            ends[first - 1] as usize
        };
        for &end in &ends[first..runs[k] as usize] {
            sweep_band(&boxes[start..end as usize], true, out);
            start = end as usize;
        }
    }
}

/// Push every overlapping pair of `active` (sorted by left edge), in bands where
/// [`bands_of`] makes them; `boxes` and `starts` are scratch.
#[cfg(test)]
fn band_pairs(
    active: &[SortedBox],
    boxes: &mut Vec<SortedBox>,
    starts: &mut Vec<u32>,
    out: &mut Vec<u64>,
) {
    let bands = bands_of(active, boxes, starts);
    let swept = Swept {
        active,
        passive: &[],
        bands: bands.map(|n| (&boxes[..], &starts[..n])),
    };
    swept.pairs(out);
}

/// Active boxes from which a full sweep is spread over the workers.
const SHARED_SWEEP_FROM: usize = 2048;

/// Boxes a worker sweeps at a time (at least; a band is not split).
const SWEPT_PER_BLOCK: usize = 1024;

/// The most blocks the bands of a shared sweep are cut into.
const MAX_BAND_BLOCKS: usize = 64;

/// Counting sort of the `active` boxes into `bands` horizontal bands (`band`: the band of a
/// height), each box into every band from its lower edge's to its upper edge's, keeping the
/// sweep order in each: band k is `boxes[starts[k - 1]..starts[k]]` (from 0 for the first).
/// The copy in a box's lowest band carries the flag [`LOWEST`].
fn sort_into_bands(
    active: &[SortedBox],
    (band, bands): (impl Fn(Real) -> usize, usize),
    boxes: &mut Vec<SortedBox>,
    starts: &mut Vec<u32>,
) {
    starts.clear();
    starts.resize(bands + 1, 0);
    for b in active {
        for k in band(b.min_y)..=band(b.max_y) {
            starts[k + 1] += 1;
        }
    }
    for k in 1..starts.len() {
        starts[k] += starts[k - 1];
    }
    boxes.clear();
    boxes.resize(starts[starts.len() - 1] as usize, active[0]);
    // Filling moves each band's start to its end, which is the next band's start.
    for b in active {
        let lowest = band(b.min_y);
        for k in lowest..=band(b.max_y) {
            let flag = if k == lowest { LOWEST } else { 0 };
            boxes[starts[k] as usize] = SortedBox {
                slot: b.slot | flag,
                ..*b
            };
            starts[k] += 1;
        }
    }
}

/// The flag, in the high bit of a slot copied into a band, of the band its box's lower edge
/// lies in (a slot is below 2^31 there: `bands_of` checks).
const LOWEST: u32 = 1 << 31;

/// The plain sweep over `boxes` (sorted by left edge): every pair overlapping in x is tested
/// in y and pushed if it overlaps; if `banded`, only if either box carries [`LOWEST`].
#[inline]
fn sweep_band(boxes: &[SortedBox], banded: bool, out: &mut Vec<u64>) {
    let slot = if banded { !LOWEST } else { u32::MAX };
    // Each candidate is written and kept only if it passes, without a branch on the test: in
    // a moving pile half the candidates overlap in y, and the branch on it mispredicted.
    let mut staged = [0u64; STAGED];
    let mut n = 0;
    for (i, a) in boxes.iter().enumerate() {
        for b in &boxes[i + 1..] {
            if b.min_x > a.max_x {
                break;
            }
            let hit = a.overlaps_y(b) & (!banded | ((a.slot | b.slot) & LOWEST != 0));
            staged[n] = pair_key(a.slot & slot, b.slot & slot);
            n += usize::from(hit);
            if n == STAGED {
                out.extend_from_slice(&staged);
                n = 0;
            }
        }
    }
    out.extend_from_slice(&staged[..n]);
}

/// Pairs a sweep stages before appending them.
const STAGED: usize = 64;

/// A box taller than this many times the mean height does not set the bands' height.
const OUTLIER: Real = 4.0;

/// Sort pair keys ascending, as `sort_unstable` does, for keys of slots below `slots`. A full
/// sweep yields its pairs in no order, thousands of them when everything moves (2,025 boxes
/// tumbling in Box2D's `tumbler`): a least-significant-digit radix sort over each half's
/// significant bits is linear where the comparison sort is n log n. Each half takes as few
/// passes of at most [`RADIX_BITS`] bits as cover it: one for up to 8,192 slots (Box2D's
/// spinner, 6,437 bodies, took four passes of 11 bits), two for up to 2^26. Short lists, and
/// worlds of more slots, take the comparison sort.
fn sort_keys(keys: &mut Vec<u64>, scratch: &mut Vec<u64>, slots: usize) {
    let wide = usize::BITS - slots.max(1).leading_zeros();
    let passes_per_half = wide.div_ceil(RADIX_BITS).max(1);
    let bits = wide.div_ceil(passes_per_half).max(1);
    // A pass clears and sums 2^bits counts: worth it only for as many keys as half that.
    if keys.len() < RADIX_FROM.max(1 << bits >> 1) || passes_per_half > 2 {
        keys.sort_unstable();
        return;
    }
    scratch.clear();
    scratch.resize(keys.len(), 0);
    let mut counts = [0u32; 1 << RADIX_BITS];
    let counts = &mut counts[..1 << bits];
    // The higher slot (low half) first, then the lower (high half): least significant first.
    for shift in (0..passes_per_half)
        .map(|p| p * bits)
        .chain((0..passes_per_half).map(|p| 32 + p * bits))
    {
        let digit = |k: u64| ((k >> shift) as usize) & ((1 << bits) - 1);
        counts.fill(0);
        for &k in keys.iter() {
            counts[digit(k)] += 1;
        }
        let mut at = 0;
        for c in counts.iter_mut() {
            (at, *c) = (at + *c, at);
        }
        for &k in keys.iter() {
            let d = digit(k);
            scratch[counts[d] as usize] = k;
            counts[d] += 1;
        }
        std::mem::swap(keys, scratch);
    }
}

/// The most bits [`sort_keys`] sorts by in one pass: 2^13 counts, 32 KB, stay in the first
/// level cache.
const RADIX_BITS: u32 = 13;

/// Pair lists shorter than this are sorted by comparison ([`sort_keys`]).
const RADIX_FROM: usize = 512;

/// Fewer active bodies than this are swept in one band.
const BANDS_FROM: usize = 64;

/// Fat-pair updates are for a few moved bodies: when more than one active body in this many
/// left its fat box, the whole sweep runs instead (a falling pile: every body, every step).
const UPDATE_FRACTION: usize = 8;

/// Push every pair of a box of `moved` and a box of `list` (both sorted by left edge) that
/// overlap, a box never with itself, with the sweep's closed overlap test. A pair overlaps in
/// x exactly when the list box's left edge lies within the moved box (strictly right of its
/// left edge: [`cross_from`]) or the moved box's left edge lies within the list box (at or
/// right of its left edge: [`cross_to`]): each side is a binary search and a short scan, so
/// the cost is linear in the list whatever the boxes' widths (no search window as wide as the
/// widest). The sweep pairs the active boxes with the passive ones this way too.
fn cross_pairs(moved: &[SortedBox], list: &[SortedBox], out: &mut Vec<u64>) {
    if moved.is_empty() {
        return;
    }
    cross_from(moved, list, out);
    cross_to(moved, list, out);
}

/// [`cross_pairs`]' pairs whose `list` box's left edge lies strictly right of the `moved`
/// box's and within it.
fn cross_from(moved: &[SortedBox], list: &[SortedBox], out: &mut Vec<u64>) {
    for m in moved {
        let start = list.partition_point(|b| b.min_x <= m.min_x);
        for b in &list[start..] {
            if b.min_x > m.max_x {
                break;
            }
            if b.slot != m.slot && m.overlaps_y(b) {
                out.push(pair_key(m.slot, b.slot));
            }
        }
    }
}

/// [`cross_pairs`]' pairs whose `moved` box's left edge lies at or right of the `list` box's
/// and within it.
fn cross_to(moved: &[SortedBox], list: &[SortedBox], out: &mut Vec<u64>) {
    for b in list {
        let start = moved.partition_point(|m| m.min_x < b.min_x);
        for m in &moved[start..] {
            if m.min_x > b.max_x {
                break;
            }
            if b.slot != m.slot && m.overlaps_y(b) {
                out.push(pair_key(m.slot, b.slot));
            }
        }
    }
}

/// Insertion sort of sorted boxes by their left edges (nearly sorted input: close to O(n)).
fn insertion_sort_boxes(boxes: &mut [SortedBox]) {
    for i in 1..boxes.len() {
        let item = boxes[i];
        let mut j = i;
        while j > 0 && boxes[j - 1].min_x > item.min_x {
            boxes[j] = boxes[j - 1];
            j -= 1;
        }
        boxes[j] = item;
    }
}

/// Merge the sorted `extra` into the sorted `into` (no key is in both), in place from the back.
fn merge_sorted(into: &mut Vec<u64>, extra: &[u64]) {
    let mut i = into.len();
    let mut j = extra.len();
    into.resize(i + j, 0);
    let mut k = into.len();
    while j > 0 {
        k -= 1;
        if i > 0 && into[i - 1] > extra[j - 1] {
            i -= 1;
            into[k] = into[i];
        } else {
            j -= 1;
            into[k] = extra[j];
        }
    }
}

/// Sort `order` by its boxes' left edges, stably (bodies whose edges are equal keep their
/// order). An order that barely changed since the last sweep (a pile at rest, falling or
/// sliding together) is restored by insertion sort in close to linear time. One that changed
/// a lot is sorted afresh: Box2D's `spinner` stirs its pile round the ring at 25 m/s, and
/// insertion sort moved each body past 500 others a step. `afresh` says whether the last
/// order was sorted afresh, and is set to whether this one is: after one that was, an order
/// with many bodies out of place (one in [`DESCENTS_PER`] or more left of its neighbour) is
/// sorted afresh at once, without spending insertion sort's budget first (a step of spinner
/// did, 1 % of its time). Either way the order is the same.
fn sort_by_min_x(
    order: &mut [u32],
    boxes: &[Aabb],
    (scratch, afresh): (&mut Vec<(Real, u32, u32)>, &mut bool),
) {
    let x = |k: u32| boxes[k as usize].min.x;
    if *afresh {
        let most = order.len() / DESCENTS_PER;
        let descents = order
            .windows(2)
            .filter(|w| x(w[0]) > x(w[1]))
            .take(most + 1);
        if descents.count() > most {
            return sort_afresh(order, boxes, scratch);
        }
    }
    *afresh = false;
    let budget = INSERTION_MOVES * order.len();
    let mut moves = 0;
    for i in 1..order.len() {
        let item = order[i];
        let x = x(item);
        let mut j = i;
        while j > 0 && boxes[order[j - 1] as usize].min.x > x {
            order[j] = order[j - 1];
            j -= 1;
        }
        order[j] = item;
        moves += i - j;
        if moves > budget {
            // Equal edges are in their old order still (insertion moves a body past greater
            // edges only), so their places in this order break ties as a stable sort would.
            *afresh = true;
            return sort_afresh(order, boxes, scratch);
        }
    }
}

/// Sort `order` by its boxes' left edges, equal edges in their order here (a comparison
/// sort by edge and place). (+ 0.0 makes -0.0 equal to 0.0, as insertion sort holds them.)
fn sort_afresh(order: &mut [u32], boxes: &[Aabb], scratch: &mut Vec<(Real, u32, u32)>) {
    scratch.clear();
    scratch.extend((order.iter().zip(0..)).map(|(&k, at)| (boxes[k as usize].min.x + 0.0, at, k)));
    scratch.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    for (slot, &(_, _, k)) in order.iter_mut().zip(scratch.iter()) {
        *slot = k;
    }
}

/// After an order sorted afresh, one body in this many out of place sorts the next afresh.
const DESCENTS_PER: usize = 16;

/// How many places, per body on average, insertion sort may move the bodies before the order
/// is sorted afresh instead (a comparison sort costs about log2 n comparisons a body).
const INSERTION_MOVES: usize = 16;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::{vec2, Real};
    use crate::physics::team::Team;

    fn proxy(x0: Real, y0: Real, x1: Real, y1: Real) -> Proxy {
        Proxy {
            aabb: Aabb {
                min: vec2(x0, y0),
                max: vec2(x1, y1),
            },
        }
    }

    #[test]
    fn finds_exactly_the_overlapping_pairs_that_involve_an_active_body() {
        let proxies = [
            proxy(0.0, 0.0, 1.0, 1.0),     // 0 active, overlaps 1, 3, 4
            proxy(0.5, 0.5, 1.5, 1.5),     // 1 active, overlaps 0 and 5 (above the ground)
            proxy(0.2, 5.0, 0.8, 6.0),     // 2 active: same x range as 0, far in y
            proxy(-10.0, -1.0, 10.0, 0.1), // 3 passive ground under 0 and 1
            proxy(-10.0, -1.0, 10.0, 0.1), // 4 passive: never paired with 3
            proxy(1.2, 1.2, 2.0, 2.0),     // 5 passive, its left edge inside 1
            proxy(3.0, 0.0, 4.0, 1.0),     // 6 passive, touches nothing
        ];
        let mut sap = SweepAndPrune::default();
        for i in 0..3 {
            sap.insert(i, false);
        }
        for i in 3..7 {
            sap.insert(i, true);
        }
        let mut out = Vec::new();
        sap.find_pairs(&proxies, &[], &mut out, None);
        let pairs: Vec<_> = out.iter().map(|&k| pair_of(k)).collect();
        assert_eq!(pairs, vec![(0, 1), (0, 3), (0, 4), (1, 5)]);

        // Body 1 falls asleep: its pair with the passive 5 is no longer examined.
        sap.set_passive(&[1], true);
        sap.find_pairs(&proxies, &[], &mut out, None);
        let pairs: Vec<_> = out.iter().map(|&k| pair_of(k)).collect();
        assert_eq!(pairs, vec![(0, 1), (0, 3), (0, 4)]);

        // Everything asleep: nothing at all.
        sap.set_passive(&[0, 2], true);
        sap.find_pairs(&proxies, &[], &mut out, None);
        assert!(out.is_empty());
    }

    /// A repeatable stream of numbers in [0, 1] (xorshift32 from `seed`).
    fn xorshift(mut seed: u32) -> impl FnMut() -> Real {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed as Real / u32::MAX as Real
        }
    }

    /// The pairs a full search finds: every active-involving pair of overlapping boxes.
    fn brute_force(proxies: &[Proxy], active: &[bool], alive: &[bool]) -> Vec<(u32, u32)> {
        let mut pairs = Vec::new();
        for a in 0..proxies.len() {
            for b in a + 1..proxies.len() {
                if alive[a]
                    && alive[b]
                    && (active[a] || active[b])
                    && proxies[a].aabb.overlaps(&proxies[b].aabb)
                {
                    pairs.push((a as u32, b as u32));
                }
            }
        }
        pairs
    }

    /// A full sweep spread over two and three workers finds exactly the pairs one thread
    /// finds, and those are a full search's: 3,000 active boxes in bands (beyond
    /// [`SHARED_SWEEP_FROM`], several blocks of bands and of boxes against the passive list),
    /// 2,500 passive ones and a static body swept by its pieces; then the active boxes in one
    /// row (a single band, one block). Every round moves them all, so every query sweeps.
    #[test]
    fn a_sweep_on_workers_finds_the_pairs_of_one_thread() {
        let mut rand = xorshift(0x0bad_cafe);
        let (active_n, passive_n) = (3_000, 2_500);
        let n = active_n + passive_n + 1;
        let mut proxies: Vec<Proxy> = (0..n).map(|_| proxy(0.0, 0.0, 0.0, 0.0)).collect();
        let pieced = (n - 1) as u32;
        let pieces: Vec<Piece> = (0..6)
            .map(|k| Piece {
                slot: pieced,
                aabb: proxy(10.0 * k as Real, 7.0, 10.0 * k as Real + 4.0, 7.5).aabb,
            })
            .collect();
        let alive = vec![true; n];
        let mut active = vec![false; n];
        active[..active_n].fill(true);
        let mut saps: Vec<SweepAndPrune> = (0..3).map(|_| SweepAndPrune::default()).collect();
        for sap in &mut saps {
            for (i, &a) in active.iter().enumerate() {
                sap.insert(i as u32, !a);
            }
        }
        let mut teams = [Team::new(2), Team::new(3)].map(|t| t.expect("threads start"));
        for round in 0..4 {
            // Rounds 0-2: a 60 m x 40 m field; round 3: every box in one 0.5 m tall row.
            let tall = if round < 3 { 40.0 } else { 0.0 };
            // (The passive boxes are placed once: static bodies do not move.)
            let moving = if round == 0 { n - 1 } else { active_n };
            for p in proxies.iter_mut().take(moving) {
                let (x, y, w) = (60.0 * rand(), tall * rand(), 0.2 + 0.8 * rand());
                *p = proxy(x, y, x + w, y + 0.2 + 0.3 * rand());
            }
            proxies[n - 1] = proxy(0.0, 7.0, 54.0, 7.5);
            let mut one = Vec::new();
            saps[0].find_pairs(&proxies, &pieces, &mut one, None);
            for (k, team) in teams.iter_mut().enumerate() {
                let (sap, mut out) = (&mut saps[k + 1], Vec::new());
                team.region(|r| sap.find_pairs(&proxies, &pieces, &mut out, Some(r)));
                assert_eq!(out, one, "round {round}: {} workers", k + 2);
            }
            assert!(one.len() > 1_000, "round {round}: {} pairs", one.len());
            // Against a full search. The pieced body pairs where a body's box meets its box
            // and its fat box meets a piece's (the sweep's test on the pieces).
            let mut expected = brute_force(&proxies[..n - 1], &active[..n - 1], &alive[..n - 1]);
            let whole = proxies[n - 1].aabb;
            let near_piece = |i: usize| {
                let b = proxies[i].aabb;
                let fat = b.inflated(FAT_MARGIN);
                let piece_met = pieces
                    .iter()
                    .any(|p| p.aabb.inflated(FAT_MARGIN).overlaps(&fat));
                piece_met && b.overlaps(&whole)
            };
            expected.extend(
                (0..active_n)
                    .filter(|&i| near_piece(i))
                    .map(|i| (i as u32, pieced)),
            );
            expected.sort_unstable();
            let found: Vec<_> = one.iter().map(|&k| pair_of(k)).collect();
            assert!(
                found == expected,
                "round {round}: {} found, {} expected",
                found.len(),
                expected.len()
            );
        }
    }

    /// The banded sweep (from [`BANDS_FROM`] active bodies) finds exactly a full search's
    /// pairs: columns of unit boxes touching edge to edge (touching counts as overlapping),
    /// boxes of random heights from 0.05 to 3 m and one 7.3 m tall (so the bands are 7.3 m
    /// and many boxes reach into two), moved far enough every round that every query sweeps
    /// afresh. Reporting a pair in every band both boxes share fails it (duplicates).
    #[test]
    fn banded_sweep_finds_exactly_the_pairs_of_a_full_search() {
        let mut rand = xorshift(0x2545_f491);
        let mut proxies: Vec<Proxy> = (0..150)
            .map(|i| {
                let (x, y) = ((i % 10) as Real, (i / 10) as Real);
                proxy(x, y, x + 1.0, y + 1.0)
            })
            .collect();
        for _ in 0..60 {
            let (x, y, w, h) = (
                12.0 * rand(),
                16.0 * rand(),
                0.05 + rand(),
                0.05 + 3.0 * rand(),
            );
            proxies.push(proxy(x, y, x + w, y + h));
        }
        proxies.push(proxy(4.5, 2.0, 5.0, 9.3));
        let n = proxies.len();
        let mut active = vec![true; n];
        for i in [3, 77, 160] {
            active[i] = false;
        }
        let alive = vec![true; n];
        let mut sap = SweepAndPrune::default();
        for (i, &a) in active.iter().enumerate() {
            sap.insert(i as u32, !a);
        }
        let mut out = Vec::new();
        for round in 0..6 {
            sap.find_pairs(&proxies, &[], &mut out, None);
            let pairs: Vec<_> = out.iter().map(|&k| pair_of(k)).collect();
            let expected = brute_force(&proxies, &active, &alive);
            assert!(
                expected.len() > 300,
                "round {round}: only {} pairs",
                expected.len()
            );
            assert_eq!(pairs, expected, "round {round}");
            for (i, p) in proxies.iter_mut().enumerate() {
                let d = if i < 150 {
                    vec2(0.0, (round % 2) as Real)
                } else {
                    vec2(rand() - 0.5, rand() - 0.5)
                };
                if active[i] {
                    p.aabb.min += d;
                    p.aabb.max += d;
                }
            }
        }
        assert_eq!(sap.updates, 0, "every query swept");
    }

    /// `band_pairs` on `boxes` (all active), sorted, against every pair tested directly.
    fn bands_match_a_full_search(boxes: &[Aabb]) -> usize {
        let mut sorted: Vec<SortedBox> = (0..boxes.len() as u32)
            .map(|i| SortedBox::new(i, boxes))
            .collect();
        sorted.sort_by(|a, b| a.min_x.total_cmp(&b.min_x).then(a.slot.cmp(&b.slot)));
        let (mut scratch, mut starts, mut out) = (Vec::new(), Vec::new(), Vec::new());
        band_pairs(&sorted, &mut scratch, &mut starts, &mut out);
        out.sort_unstable();
        let proxies: Vec<Proxy> = boxes.iter().map(|&aabb| Proxy { aabb }).collect();
        let every = vec![true; boxes.len()];
        let expected: Vec<u64> = brute_force(&proxies, &every, &every)
            .into_iter()
            .map(|(a, b)| pair_key(a, b))
            .collect();
        assert_eq!(out, expected);
        expected.len()
    }

    /// `band_pairs` itself, where the bands' edges bite: a 10 x 12 grid of unit boxes touching
    /// edge to edge, so every lower edge lies exactly on a band boundary and every upper edge
    /// on the next (each touching pair once); boxes spread 1e4 m up, so the band count hits
    /// its cap of one band per two boxes; a box at 1e30 m beside them (bands far taller than
    /// any box); and one at the largest finite height, whose span overflows to infinity (the
    /// plain sweep).
    #[test]
    fn band_pairs_match_a_full_search_at_band_edges_caps_and_huge_spans() {
        let unit = |x: Real, y: Real, w: Real, h: Real| Aabb {
            min: vec2(x, y),
            max: vec2(x + w, y + h),
        };
        let grid: Vec<Aabb> = (0..120)
            .map(|i| unit((i % 10) as Real, (i / 10) as Real, 1.0, 1.0))
            .collect();
        assert_eq!(
            bands_match_a_full_search(&grid),
            9 * 12 + 10 * 11 + 2 * 9 * 11
        );
        let mut rand = xorshift(0x1234_5678);
        let spread: Vec<Aabb> = (0..200)
            .map(|_| unit(5.0 * rand(), 1.0e4 * rand(), 0.5, 0.5 + rand()))
            .chain(grid.iter().copied())
            .collect();
        bands_match_a_full_search(&spread);
        let mut far = spread.clone();
        far.push(unit(0.0, 1.0e30, 1.0, 1.0));
        bands_match_a_full_search(&far);
        // A drum around the grid, 30 times its boxes' height: in every band it reaches.
        let mut drum = grid.clone();
        drum.push(unit(-1.0, -1.0, 12.0, 30.0));
        assert_eq!(
            bands_match_a_full_search(&drum),
            9 * 12 + 10 * 11 + 2 * 9 * 11 + 120
        );
        let mut overflow = spread;
        overflow.push(unit(0.0, Real::MAX / 2.0, 1.0, Real::MAX / 2.0));
        overflow.push(unit(0.0, -Real::MAX / 2.0, 1.0, 1.0));
        bands_match_a_full_search(&overflow);
    }

    #[test]
    fn pair_keys_sort_as_the_comparison_sort_sorts_them() {
        // Lengths on both sides of the radix threshold, slot counts needing two and four
        // passes (of 13 bits and fewer) and the comparison sort's fallback, duplicates
        // included.
        let mut rand = xorshift(0x9e37_79b9);
        let mut scratch = Vec::new();
        for (n, slots) in [
            (100, 50),
            (600, 2_000),
            (5_000, 2_048),
            (5_000, 6_437),
            (5_000, 8_193),
            (20_000, 10_455),
            (5_000, 300_000),
            (3_000, 1 << 23),
            (3_000, 1 << 27),
        ] {
            let mut keys: Vec<u64> = (0..n)
                .map(|_| {
                    let a = (rand() * slots as Real) as u32 % slots as u32;
                    let b = (rand() * slots as Real) as u32 % slots as u32;
                    pair_key(a, b)
                })
                .collect();
            keys.extend_from_within(..n / 10);
            let mut expected = keys.clone();
            expected.sort_unstable();
            sort_keys(&mut keys, &mut scratch, slots);
            assert_eq!(keys, expected, "{n} keys of {slots} slots");
        }
    }

    #[test]
    fn kept_fat_pairs_give_exactly_the_pairs_of_a_full_search() {
        // 60 unit boxes on a jittered grid; each step every active box moves by up to 4 mm
        // (mostly inside its fat box, so the kept pairs are filtered) and every 25th step
        // two jump 0.3 m (past FAT_MARGIN, so their pairs are searched again); bodies fall
        // asleep, wake, and are removed. Every step must agree with a search over all pairs.
        let mut rand = xorshift(0x9e37_79b9);
        let mut proxies: Vec<Proxy> = (0..60)
            .map(|i| {
                let (x, y) = ((i % 10) as Real * 0.9, (i / 10) as Real * 0.9);
                proxy(x, y, x + 1.0, y + 1.0)
            })
            .collect();
        let mut active = vec![true; 60];
        active[0] = false; // a static body
        let mut alive = vec![true; 60];
        let mut sap = SweepAndPrune::default();
        for (i, &a) in active.iter().enumerate() {
            sap.insert(i as u32, !a);
        }
        let mut out = Vec::new();
        for step in 0..400 {
            for (i, p) in proxies.iter_mut().enumerate() {
                if active[i] {
                    // Two neighbours jump together: a pair of moved bodies is found from
                    // both sides.
                    let jumps = i == step % 60 || i == (step + 1) % 60;
                    let big = if step % 25 == 0 && jumps { 60.0 } else { 1.0 };
                    let d = vec2(rand() - 0.5, rand() - 0.5) * (0.008 * big);
                    p.aabb.min += d;
                    p.aabb.max += d;
                }
            }
            if step % 50 == 49 {
                let i = 1 + step % 59;
                active[i] = !active[i];
                sap.set_passive(&[i as u32], !active[i]);
            }
            // Bodies removed three at a time, and one slot reused (inserted again) before
            // the next query has dropped its old entry.
            if step % 40 == 20 {
                let gone = [step % 60, (step + 7) % 60, (step + 31) % 60];
                for &i in &gone {
                    alive[i] = false;
                }
                sap.remove(&gone.map(|i| i as u32));
                if step % 80 == 20 {
                    alive[gone[0]] = true;
                    sap.insert(gone[0] as u32, !active[gone[0]]);
                }
            }
            sap.find_pairs(&proxies, &[], &mut out, None);
            let pairs: Vec<_> = out.iter().map(|&k| pair_of(k)).collect();
            assert_eq!(pairs, brute_force(&proxies, &active, &alive), "step {step}");
        }
        // All three paths ran: the sleep changes and removals swept; the jumps (at most one
        // in 8 of the 59 dynamic bodies left its fat box) updated the kept pairs of the
        // bodies that moved; and most steps reused the kept pairs as they were (otherwise
        // this tested only the sweep). 19 sweeps and 10 updates when written.
        assert!((16..200).contains(&sap.sweeps), "{} sweeps", sap.sweeps);
        assert!(sap.updates >= 8, "{} updates", sap.updates);
    }
    /// A static body swept by pieces (four thin strips at different heights, its whole box
    /// spanning them all) pairs with every active box that meets a strip, and with none that
    /// lies clear of every strip by more than the fat margins allow (swept whole it would pair
    /// with all of them); every other pair is exactly a full search's. Active boxes jiggle
    /// every step and jump now and then, so the sweep, the update and the kept pairs all run.
    #[test]
    fn a_static_body_of_several_shapes_pairs_only_near_its_shapes() {
        let mut rand = xorshift(0x1234_5677);
        let strip = |y: Real| proxy(-1.0, y, 11.0, y + 0.1).aabb;
        let strips: Vec<Aabb> = [0.0, 2.5, 5.0, 7.5].map(strip).to_vec();
        let pieced = 40u32;
        let mut proxies: Vec<Proxy> = (0..40)
            .map(|i| {
                // Rows 2 and 4 meet a strip; rows 1, 3 and 5 lie 0.3 m clear.
                let (x, y) = ((i % 8) as Real * 1.3, (i / 8) as Real * 1.5 + 0.4);
                proxy(x, y, x + 0.8, y + 0.8)
            })
            .collect();
        proxies.push(proxy(-1.0, 0.0, 11.0, 7.6)); // the body swept by its strips
        proxies.push(proxy(5.0, 3.0, 5.5, 3.5)); // an ordinary static body
        let pieces: Vec<Piece> = strips
            .iter()
            .map(|&aabb| Piece { slot: pieced, aabb })
            .collect();
        let mut sap = SweepAndPrune::default();
        for i in 0..40 {
            sap.insert(i, false);
        }
        sap.insert(pieced, true);
        sap.insert(pieced + 1, true);
        let (active, alive) = ((0..42).map(|i| i < 40).collect::<Vec<_>>(), vec![true; 42]);
        let (mut out, mut with_pieced) = (Vec::new(), 0);
        for step in 0..300 {
            for (i, p) in proxies.iter_mut().take(40).enumerate() {
                // One body jumps now and then (an update); at step 150 ten do (a sweep).
                let jumps = step % 30 == 0 && i == step % 40 || step == 150 && i < 10;
                let big = if jumps { 80.0 } else { 1.0 };
                let d = vec2(rand() - 0.5, rand() - 0.5) * (0.01 * big);
                p.aabb.min += d;
                p.aabb.max += d;
            }
            sap.find_pairs(&proxies, &pieces, &mut out, None);
            let pairs: Vec<_> = out.iter().map(|&k| pair_of(k)).collect();
            let mut expected = brute_force(&proxies, &active, &alive);
            expected.retain(|&(a, b)| {
                b != pieced || {
                    let near = proxies[a as usize].aabb.inflated(3.0 * FAT_MARGIN);
                    strips.iter().any(|s| s.overlaps(&near))
                }
            });
            let (others, found): (Vec<_>, Vec<_>) = pairs.iter().partition(|p| p.1 != pieced);
            let (others_expected, candidates): (Vec<_>, Vec<_>) =
                expected.iter().partition(|p| p.1 != pieced);
            assert_eq!(others, others_expected, "step {step}");
            for &(a, _) in &found {
                assert!(
                    candidates.contains(&(a, pieced)),
                    "step {step}: {a} far from every strip"
                );
            }
            for a in 0..40u32 {
                let meets = strips.iter().any(|s| s.overlaps(&proxies[a as usize].aabb));
                assert!(
                    !meets || found.contains(&(a, pieced)),
                    "step {step}: {a} missed"
                );
            }
            with_pieced += found.len();
        }
        // Boxes met the strips (5,382 pairs in all when written: the two rows, and jumpers),
        // and every path ran (2 sweeps and 46 updates).
        assert!(with_pieced >= 300, "{with_pieced} pairs with the strips");
        assert!(
            sap.sweeps >= 2 && sap.updates >= 2,
            "{} / {}",
            sap.sweeps,
            sap.updates
        );
    }

    /// The order by left edge is the stable sort's whether insertion sort restores it or it is
    /// sorted afresh: equal edges (-0.0 and 0.0 among them) keep their old order.
    #[test]
    fn the_sweep_order_is_the_stable_sort_however_it_is_found() {
        let edge = |k: u32| match k % 5 {
            0 => -0.0,
            1 => 0.0,
            _ => (k % 7) as Real - 3.0,
        };
        let boxes: Vec<Aabb> = (0..200)
            .map(|k| Aabb {
                min: vec2(edge(k), 0.0),
                max: vec2(edge(k) + 1.0, 1.0),
            })
            .collect();
        // Nearly sorted (one body out of place: insertion sort) and reversed (afresh).
        let mut nearly: Vec<u32> = (0..200).collect();
        nearly.sort_by(|&a, &b| edge(a).partial_cmp(&edge(b)).unwrap());
        nearly.swap(10, 11);
        let reversed: Vec<u32> = (0..200).rev().collect();
        // Each both after an order restored by insertion and after one sorted afresh (which
        // sorts the reversed one afresh at once, and tries insertion on the nearly sorted).
        let cases = [
            (&nearly, false),
            (&reversed, false),
            (&nearly, true),
            (&reversed, true),
        ];
        for (start, last_afresh) in cases {
            let start = start.clone();
            let sorted_afresh = start == reversed;
            let mut expected = start.clone();
            expected.sort_by(|&a, &b| edge(a).partial_cmp(&edge(b)).unwrap());
            let mut order = start;
            let mut afresh = last_afresh;
            sort_by_min_x(&mut order, &boxes, (&mut Vec::new(), &mut afresh));
            assert_eq!(
                order, expected,
                "after an order sorted afresh: {last_afresh}"
            );
            assert_eq!(
                afresh, sorted_afresh,
                "only the reversed order is sorted afresh"
            );
        }
    }
}
