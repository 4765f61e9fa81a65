//! Continuous collision against static bodies (Box2D's time of impact).
//!
//! Speculative contacts stop a fast body at a surface it heads for, but only along the
//! features the narrow phase found at the start of the step: a thin plank spinning at 50 rad/s
//! swings an end through a post or a floor that no contact point stood for. So each dynamic
//! body that moved more than [`FAST_FRACTION`] of its shortest extent in the step is swept,
//! shape by shape, against the static bodies its box met this step, or every static its
//! path's box meets if it left that box (struck within the step) (`collide/toi.rs`); where a
//! shape would have come within the linear slop of one, the body goes back to that moment of
//! its motion, keeping its velocity, and the next step's speculative contact stops it there.
//! A shape that starts the step that close already (a box sliding fast along the floor, a
//! plank lying on it while it spins) would stop at once, so only its core, a disc of
//! [`CORE_FRACTION`] of its shortest extent about the centre of mass, is swept: the centre
//! never passes the surface, and the contacts see to the rest. So does a shape that starts
//! along the line of one of the static's faces (a disc rolling onto the next piece of a chain
//! would otherwise stop at every joint). A one-sided piece is skipped by
//! a body whose centre starts behind it, as its contacts are.

use super::{Slot, World};
use crate::physics::body::Body;
use crate::physics::broad_phase::{pair_of, Proxy};
use crate::physics::collide::toi::{lies_along_a_face, time_of_impact, Sweep};
use crate::physics::contact::Contact;
use crate::physics::math::{Real, Rot, Transform, Vec2};
use crate::physics::query::tree::Tree;
use crate::physics::segment::Segment;
use crate::physics::shape::{Aabb, Shape};
use crate::physics::team::{block, Region, SharedSlice};

/// A body is fast when it moved more than this fraction of its shortest extent in a step
/// (Box2D's default safety factor).
pub(super) const FAST_FRACTION: Real = 0.5;

/// How many candidate pairs a worker sweeps for impacts at a time...
const IMPACT_PAIRS_PER_BLOCK: usize = 256;
/// ...and the fewest fast bodies for which the workers sweep them.
const SHARED_IMPACTS_FROM: usize = 64;

/// A slot's place in the fast list when it is not on it.
pub(super) const NOT_FAST: u32 = u32::MAX;

/// The core swept for a shape that starts within the slop of a static body, as a fraction of
/// its shortest extent (Box2D's core fraction).
const CORE_FRACTION: Real = 0.25;

impl World {
    /// Continuous collision: each fast body (`solver.fast`, listed by finalize in slot order)
    /// against the static bodies it was paired with this step, and moved back to its first
    /// moment of impact.
    pub(super) fn solve_continuous(&mut self, region: Option<&Region>) {
        if self.bodies.guarded > 0 {
            self.keep_centres_in_front();
        }
        if self.solver.fast.is_empty() {
            return;
        }
        let fast = std::mem::take(&mut self.solver.fast);
        let mut hits = std::mem::take(&mut self.solver.fast_hits);
        let mut place = std::mem::take(&mut self.solver.fast_place);
        let mut found = std::mem::take(&mut self.broad_phase.shape_pairs);
        hits.clear();
        hits.resize(fast.len(), 1.0);
        place.resize(self.bodies.slots.len(), NOT_FAST);
        for (i, &slot) in fast.iter().enumerate() {
            place[slot as usize] = i as u32;
        }
        // (Tests that lower the solve's threshold lower this one with it.)
        let from = self.solver.bundles.shared_from(SHARED_IMPACTS_FROM);
        match region {
            Some(region) if fast.len() >= from => {
                self.pair_impacts_shared(region, &place, &mut hits)
            }
            _ => {
                for &key in &self.broad_phase.pair_keys {
                    if let Some((i, moving, other)) = self.fast_against_static(key, &place) {
                        let t = self.impact(moving, other, &mut found);
                        hits[i] = hits[i].min(t);
                    }
                }
            }
        }
        self.sweep_escaped(&fast, &mut hits, &mut found);
        self.broad_phase.shape_pairs = found;
        for (&slot, &t) in fast.iter().zip(&hits) {
            place[slot as usize] = NOT_FAST;
            if t < 1.0 {
                self.move_back(slot, t);
            }
        }
        self.solver.fast = fast;
        self.solver.fast.clear();
        self.solver.fast_hits = hits;
        self.solver.fast_place = place;
    }

    /// A body's centre does not cross a chain's piece or a one-sided segment ([`guards`]) it
    /// touched at the start of the step: past the line, the piece would push it on out, or
    /// (one-sided) no longer at all (a capsule pressed 0.2 m into Box2D's `spinner` ring by
    /// the stirred pile, too slowly for continuous collision to look at it, left the ring).
    /// Such a body goes back along its step's motion to where its centre is still the linear
    /// slop in front (or where it started, if nearer), keeping its velocity, and the next
    /// step's contact pushes it out. A body that comes from behind a one-sided piece has no
    /// contact with it, so it still passes, as through a jump-through platform.
    fn keep_centres_in_front(&mut self) {
        let mut crossed = std::mem::take(&mut self.solver.crossed);
        crossed.clear();
        let touching = self.contacts.awake.iter().filter(|c| c.touches_static);
        crossed.extend(touching.filter_map(|c| self.crossing(c)));
        // Each body goes back to its earliest crossing.
        crossed.sort_unstable_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)));
        crossed.dedup_by_key(|x| x.0);
        for &(slot, keep) in &crossed {
            self.move_back(slot, keep);
            let sb = &mut self.solver.bodies[slot as usize];
            // Continuous collision, next, sweeps the motion the body kept.
            sb.dp *= keep;
            sb.dtheta *= keep;
        }
        self.solver.crossed = crossed;
    }

    /// If contact `c` holds a dynamic body against a chain's piece or a one-sided segment of a
    /// static body ([`guards`]) and the body's centre crossed the piece within the step, the
    /// body's slot and the fraction of its step's motion it keeps.
    fn crossing(&self, c: &Contact) -> Option<(u32, Real)> {
        let inv_mass = |i: u32| self.solver.bodies[i as usize].inv_mass;
        let (fixed, moving, shape) = if inv_mass(c.a) == 0.0 {
            (c.a, c.b, c.shapes >> 16)
        } else {
            (c.b, c.a, c.shapes & 0xFFFF)
        };
        let slots = &self.bodies.slots;
        let fixed = slots[fixed as usize].body.as_ref()?;
        let body = slots[moving as usize].body.as_ref()?;
        let (Shape::Segment(s), pose) = shape_at(fixed, shape as usize)? else {
            return None;
        };
        if !guards(s) || !fixed.is_static() || inv_mass(moving) == 0.0 {
            return None;
        }
        let xf = fixed.frame().then(pose);
        let (a, b, left) = (xf.apply(s.a), xf.apply(s.b), xf.q.rotate(s.left_normal()));
        let end = body.position;
        let start = end - self.solver.bodies[moving as usize].dp;
        // The front: the left of a one-sided piece, the side the centre started on of a
        // two-sided one.
        let started = (start - a).dot(left);
        let out = if s.one_sided || started >= 0.0 {
            left
        } else {
            -left
        };
        let (front, behind) = ((start - a).dot(out), (end - a).dot(out));
        if front < 0.0 || behind >= 0.0 {
            return None;
        }
        // Where the centre crossed the line: on this piece (a chain's neighbours take the
        // rest; past a lone piece's end there is nothing to cross).
        let at = start + (end - start) * (front / (front - behind));
        let along = (at - a).dot(b - a) / (b - a).length_squared().max(Real::MIN_POSITIVE);
        if !(0.0..=1.0).contains(&along) {
            return None;
        }
        let keep_in_front = front.min(self.settings.linear_slop);
        Some((moving, (front - keep_in_front) / (front - behind)))
    }

    /// The fast body of pair `key` (its place in the fast list, its slot) and the static body
    /// it meets, if the pair is such. Only a static body can be the other: it has no inverse
    /// mass (read from the solver's compact bodies before the body itself).
    #[inline]
    fn fast_against_static(&self, key: u64, place: &[u32]) -> Option<(usize, u32, u32)> {
        let (a, b) = pair_of(key);
        [(a, b), (b, a)].into_iter().find_map(|(moving, other)| {
            let i = place[moving as usize];
            (i != NOT_FAST && self.solver.bodies[other as usize].inv_mass == 0.0)
                .then_some((i as usize, moving, other))
        })
    }

    /// The pairs' impacts, spread over `region`'s workers: each pair's fraction (1 for none)
    /// into `solver.pair_hits`, then each fast body's first in pair order on this thread.
    /// The smallest of the same numbers is the same in any order: the results are the same
    /// to the bit for any number of workers.
    fn pair_impacts_shared(&mut self, region: &Region, place: &[u32], hits: &mut [Real]) {
        let mut pair_hits = std::mem::take(&mut self.solver.pair_hits);
        let n = self.broad_phase.pair_keys.len();
        pair_hits.clear();
        pair_hits.resize(n, 1.0);
        {
            let world = &*self;
            let keys = &world.broad_phase.pair_keys;
            // SAFETY: each block writes its own run of the pairs' fractions.
            let out = unsafe { SharedSlice::new(&mut pair_hits) };
            region.for_blocks(n.div_ceil(IMPACT_PAIRS_PER_BLOCK), &|k| {
                let run = block(k, IMPACT_PAIRS_PER_BLOCK, n);
                // SAFETY: as above.
                let out = unsafe { out.range(run.clone()) };
                // (Allocates only for a static body of several shapes in a tree.)
                let mut found = Vec::new();
                for (t, &key) in out.iter_mut().zip(&keys[run]) {
                    if let Some((_, moving, other)) = world.fast_against_static(key, place) {
                        *t = world.impact(moving, other, &mut found);
                    }
                }
            });
        }
        for (&key, &t) in self.broad_phase.pair_keys.iter().zip(&pair_hits) {
            if t < 1.0 {
                if let Some((i, _, _)) = self.fast_against_static(key, place) {
                    hits[i] = hits[i].min(t);
                }
            }
        }
        self.solver.pair_hits = pair_hits;
    }

    /// A fast body whose box at the end of the step is not inside the box the broad phase
    /// paired it by (swept along the motion its velocity at the start of the step foretold)
    /// changed its motion within the step, struck by another body: the statics it reached were never
    /// paired with it, so it is swept against every static whose box its path's box meets,
    /// found through a tree of the statics' boxes (Box2D queries its static tree alike). The
    /// tree is built only in a step where some body escaped: in Box2D's `spinner`, where the
    /// paddle strikes hundreds a step, trying each against each of the ring's 360 pieces was
    /// 13 % of the step's instructions.
    fn sweep_escaped(&mut self, fast: &[u32], hits: &mut [Real], found: &mut Vec<u32>) {
        let mut statics = std::mem::take(&mut self.solver.statics);
        let mut built = false;
        for (i, &slot) in fast.iter().enumerate() {
            let Some(body) = self.bodies.slots[slot as usize].body.as_ref() else {
                continue;
            };
            let paired_by = &self.broad_phase.proxies[slot as usize].aabb;
            if paired_by.contains(&body.aabb()) {
                continue;
            }
            if !built {
                statics.build(&self.bodies.slots, &self.broad_phase.proxies);
                built = true;
            }
            let path = self.path_box(slot, body);
            statics.tree.query(&path, |other| {
                hits[i] = hits[i].min(self.impact(slot, other, found));
                true
            });
        }
        self.solver.statics = statics;
    }

    /// The box of `body`'s path this step (in `slot`), grown by its bounding radius and the
    /// linear slop: its shapes stay inside it.
    fn path_box(&self, slot: u32, body: &Body) -> Aabb {
        let sb = &self.solver.bodies[slot as usize];
        let (start, end) = (body.position - sb.dp, body.position);
        let reach = Vec2::splat(body.bounding_radius + self.settings.linear_slop);
        Aabb {
            min: start.min(end) - reach,
            max: start.max(end) + reach,
        }
    }

    /// The fraction of its step's motion at which body `moving` first comes within the slop of
    /// body `other`, if that is static; 1 if never. A static body of many shapes is swept
    /// against only those near the path, found through its tree (`found`: scratch).
    fn impact(&self, moving: u32, other: u32, found: &mut Vec<u32>) -> Real {
        let slots = &self.bodies.slots;
        let (Some(body), Some(fixed)) = (
            slots[moving as usize].body.as_ref(),
            slots[other as usize].body.as_ref(),
        ) else {
            return 1.0;
        };
        if !fixed.is_static() {
            return 1.0;
        }
        let sb = &self.solver.bodies[moving as usize];
        let (start, end) = (
            (body.position - sb.dp, body.angle - sb.dtheta),
            (body.position, body.angle),
        );
        // Where the box of the path misses the static's (its proxy's: a box falling past a
        // wall), nothing is swept.
        let swept = self.path_box(moving, body);
        if !swept.overlaps(&self.broad_phase.proxies[other as usize].aabb) {
            return 1.0;
        }
        let near = fixed
            .compound()
            .and_then(|p| p.tree.as_ref().map(|t| (p, t)));
        if let Some((_, tree)) = near {
            found.clear();
            tree.query(fixed.frame(), &swept, found);
        }
        let mut first: Real = 1.0;
        let gated = self.bodies.filtered > 0 || self.bodies.flagged > 0;
        for (i, (shape, local)) in body.shapes().enumerate() {
            let sweep = Sweep { start, end, local };
            let mut sweep_against = |k: usize, (fixed_shape, pose): (&Shape, Transform)| {
                if gated && !may_touch((body, i), (fixed, k)) {
                    return;
                }
                let xf = fixed.frame().then(pose);
                first = first.min(self.shape_impact((fixed_shape, xf), shape, &sweep));
            };
            match near {
                Some((parts, _)) => found.iter().for_each(|&k| {
                    let p = &parts.all[k as usize];
                    sweep_against(k as usize, (&p.shape, p.pose))
                }),
                None => fixed
                    .shapes()
                    .enumerate()
                    .for_each(|(k, s)| sweep_against(k, s)),
            }
        }
        first
    }

    /// The fraction of `sweep` at which shape `moving` first comes within the slop of the
    /// static shape `fixed`; 1 if never.
    fn shape_impact(&self, fixed: (&Shape, Transform), moving: &Shape, sweep: &Sweep) -> Real {
        if let Shape::Segment(s) = fixed.0 {
            if passes_alongside(fixed, s, moving, sweep) {
                return 1.0;
            }
        }
        let target = self.settings.linear_slop;
        let whole = if lies_along_a_face(fixed, moving, sweep.at(0.0), target) {
            Some(0.0)
        } else {
            time_of_impact(fixed, moving, sweep, target)
        };
        match whole {
            Some(t) if t > 0.0 => t,
            None => 1.0,
            Some(_) => {
                let core = Shape::circle(CORE_FRACTION * moving.min_extent());
                match time_of_impact(fixed, &core, sweep, target) {
                    Some(t) if t > 0.0 => t,
                    _ => 1.0,
                }
            }
        }
    }

    /// Put body `slot` a fraction `t` of the way along its step's motion.
    fn move_back(&mut self, slot: u32, t: Real) {
        let sb = &self.solver.bodies[slot as usize];
        let (dp, dtheta) = (sb.dp, sb.dtheta);
        if let Some(b) = self.bodies.slots[slot as usize].body.as_mut() {
            let back = 1.0 - t;
            b.position -= back * dp;
            b.angle -= back * dtheta;
            b.rot = Rot::from_angle(b.angle);
        }
    }
}

/// Whether a body's centre is kept from crossing static segment `s` within a step: a
/// one-sided segment or a chain's piece (the walls of containers and the ground of terrain).
/// A lone two-sided segment is a capsule's core like any other.
fn guards(s: &Segment) -> bool {
    s.one_sided || s.prev.is_some() || s.next.is_some()
}

/// Whether `shape` is a static segment that [`guards`] a body's centre.
pub(super) fn guards_shape(shape: &Shape) -> bool {
    matches!(shape, Shape::Segment(s) if guards(s))
}

/// Shape `k` of `body` (in [`Body::shapes`]' order) and its pose in the body's frame.
fn shape_at(body: &Body, k: usize) -> Option<(&Shape, Transform)> {
    match body.compound() {
        Some(parts) => parts.all.get(k).map(|p| (&p.shape, p.pose)),
        None => (k == 0).then_some((body.shape(), Transform::IDENTITY)),
    }
}

/// Whether the sweep of shape `moving` may skip the static segment `s` (posed by `fixed.1`):
/// a one-sided segment whose centre starts behind it (as its contacts skip it), or a segment
/// the centre neither starts behind nor approaches by its core ([`CORE_FRACTION`] of its
/// shortest extent) while ending farther than the core in front: a body turning about a
/// centre that stays clear of the segment (a paddle whose tip grazes a ring of chain pieces)
/// is left to its contacts, as Box2D leaves a chain segment, instead of being stopped where
/// the tip first comes near. (Box2D's early out; the centre can never pass the segment.)
fn passes_alongside(
    fixed: (&Shape, Transform),
    s: &Segment,
    moving: &Shape,
    sweep: &Sweep,
) -> bool {
    let (a, b) = (fixed.1.apply(s.a), fixed.1.apply(s.b));
    let left = fixed.1.q.rotate(s.left_normal());
    let (c1, c2) = (sweep.start.0, sweep.end.0);
    let (mut sep1, mut sep2) = ((c1 - a).dot(left), (c2 - a).dot(left));
    if s.one_sided && sep1 < 0.0 {
        return true;
    }
    if (b - a).length() <= MIN_SEGMENT {
        return false;
    }
    if sep1 < 0.0 {
        (sep1, sep2) = (-sep1, -sep2);
    }
    (sep1, sep2) = (sep1 - s.radius, sep2 - s.radius);
    let core = CORE_FRACTION * moving.min_extent();
    sep1 - sep2 < core && sep2 > core
}

/// Segments shorter than this (m) are always swept (Box2D's linear slop).
const MIN_SEGMENT: Real = 0.005;

/// Whether a body moved more than `limit` (m) this step: its centre's travel `dp` plus its
/// turn `dtheta` times its `reach` (compared squared, without a root, for every body).
#[inline]
pub(super) fn moved_more_than(dp: Vec2, dtheta: Real, reach: Real, limit: Real) -> bool {
    let left = limit - dtheta.abs() * reach;
    left < 0.0 || dp.length_squared() > left * left
}

/// Whether shape `i` of body `a` and shape `k` of body `b` may touch: their filters allow it
/// and neither is a sensor.
fn may_touch((a, i): (&Body, usize), (b, k): (&Body, usize)) -> bool {
    let of = |x: &Body, j: usize| {
        x.compound().map_or_else(
            || (x.filter(), x.flags().sensor),
            |p| (p.all[j].filter, p.all[j].flags.sensor),
        )
    };
    let ((fa, sa), (fb, sb)) = (of(a, i), of(b, k));
    !sa && !sb && fa.should_collide(&fb)
}

/// The static bodies' broad-phase boxes in a tree (rebuilt, in place, in a step that needs
/// it), for the fast bodies that left the boxes they were paired by.
#[derive(Clone, Debug, Default)]
pub(super) struct StaticTree {
    tree: Tree,
    items: Vec<(u32, Aabb)>,
    order: Vec<u32>,
    leaves: Vec<u32>,
}

impl StaticTree {
    /// Build the tree over the static bodies in `slots` with their boxes in `proxies`.
    fn build(&mut self, slots: &[Slot], proxies: &[Proxy]) {
        self.items.clear();
        let is_static = |s: &Slot| s.body.as_ref().is_some_and(|b| b.is_static());
        let statics = slots.iter().zip(proxies).enumerate();
        self.items.extend(
            statics
                .filter(|(_, (s, _))| is_static(s))
                .map(|(j, (_, p))| (j as u32, p.aabb)),
        );
        self.tree
            .rebuild(&self.items, &mut self.order, &mut self.leaves);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::vec2;

    /// A sweep of a 4 m x 0.2 m plank (core: a quarter of its 0.1 m half-thickness, 0.025 m)
    /// from centre `c1` at angle 0 to `c2` at angle 0.5 rad, against a floor segment from
    /// (-10, 0) to (10, 0), two-sided or not.
    fn skips(c1: Vec2, c2: Vec2, one_sided: bool) -> bool {
        let floor = Segment {
            one_sided,
            ..Segment::new(vec2(-10.0, 0.0), vec2(10.0, 0.0), 0.0)
        };
        let plank = Shape::rect(4.0, 0.2);
        let sweep = Sweep {
            start: (c1, 0.0),
            end: (c2, 0.5),
            local: Transform::IDENTITY,
        };
        let fixed = (
            &Shape::Segment(Box::new(floor.clone())),
            Transform::IDENTITY,
        );
        passes_alongside(fixed, &floor, &plank, &sweep)
    }

    /// The early out keeps what it must: a plank turning about a centre that stays 1.9 m
    /// above a floor (its tips reach 2 m) is left to its contacts from above or below a
    /// two-sided floor; one whose centre drops by more than its core, or ends within
    /// the core of the floor, is swept; a one-sided floor skips a centre that starts behind it.
    #[test]
    fn only_a_centre_that_stays_clear_of_a_segment_skips_its_sweep() {
        let (high, low) = (vec2(0.0, 1.9), vec2(0.0, -1.9));
        assert!(skips(high, high, false));
        assert!(skips(low, low, false));
        assert!(
            skips(high, vec2(0.0, 1.88), false),
            "approach under the core"
        );
        assert!(
            !skips(high, vec2(0.0, 1.85), false),
            "approach by twice the core"
        );
        assert!(
            !skips(vec2(0.0, 0.03), vec2(0.0, 0.02), false),
            "ends within the core"
        );
        assert!(
            skips(low, vec2(0.0, 1.0), true),
            "starts behind a one-sided floor"
        );
        assert!(
            !skips(high, vec2(0.0, -1.0), true),
            "crosses a one-sided floor"
        );
    }
}
