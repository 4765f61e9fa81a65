//! Adaptive stiffness (`Settings::adaptive_stiffness`): each awake island gets a tier from its
//! contacts' loads, its bodies' masses and its shape, and each tier is solved apart with the
//! work its islands need ([`TIERS`]). Islands of different tiers share no dynamic body, so
//! each tier solves its own contacts, taking their colours from the one constraint graph.

use super::contacts::Travel;
use super::islands::{flatten, unite_islands};
use super::*;
use crate::physics::shape::Aabb;
use crate::physics::solver::joint::JOINT_CAP;
use crate::physics::solver::soft_step::Effort;
use crate::physics::team::{block, Region, SharedSlice};

/// A stiffness tier, in order of the work it does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
#[repr(u8)]
pub(super) enum Tier {
    /// Nothing loaded: the World's settings.
    #[default]
    Base,
    /// A loaded island braced sideways (a pyramid, a pile).
    Braced,
    /// A loaded island that is not braced (a stack).
    Stack,
    /// A stack under [`LOADED_RANGE`] times the load (a tall stack), or an island joining
    /// masses `stiff_load_ratio` apart.
    TallStack,
    /// A loaded braced island at least [`HEAVY_DEPTH`] bodies deep (a pyramid of base 200),
    /// or one whose joints carry its load (a pile of ragdolls).
    HeavyBraced,
    /// An island joining masses `extreme_mass_ratio` apart.
    Extreme,
}

/// What a tier does, relative to the World's settings.
#[derive(Clone, Copy, Debug)]
pub(super) struct TierSpec {
    /// Substeps, in quarters of `Settings::substeps`; the contact hertz scales with them,
    /// since its ceiling is a quarter of the substep rate.
    pub substep_quarters: u32,
    /// Relax passes, as a multiple of `Settings::relax_iterations`.
    pub relax_scale: u32,
    /// Normal relax passes (after the relax passes, solving the normal constraints only), as
    /// a multiple of `Settings::relax_iterations`.
    pub normal_relax_scale: u32,
    /// How much of last step's compression the springs creep by (`soft_step::creep`).
    pub creep: Real,
    /// The stiffest a joint may be, as a fraction of the substep rate; the tier's joints are
    /// stiffened by as much again as its contacts, up to it.
    pub joint_cap: Real,
}

/// The tiers' work, indexed by [`Tier`]. Why each row is what it is:
///
/// - **Braced** islands need the slow bounce of their rows damped rather than stiffer
///   springs: the base substeps, a relax pass, a normal relax pass (what damps the bounce is
///   a second pass over the normals; friction, solved by the full relax pass before it, need
///   not be solved again, and the step clamps the friction impulse to the cone of the normal
///   impulse it ends with) and creep.
/// - **Stack** and **TallStack** need stiff springs, so more substeps: 1.5 and 1.75 times the
///   base (7 substeps hold a jittered 50-box stack, 6 do not) with creep, which damps their
///   slow bounce without more relax passes.
/// - **HeavyBraced** islands carry so much that the base springs give way under them: twice
///   the substeps and stiffness, so a spring holds four times the load at the same
///   compression, with the braced tier's passes and creep.
/// - **Extreme** (100:1 masses) needs five times the substeps and stiffness and eight times
///   the relax passes; its islands are small. Creep would leave its springs softer at rest,
///   which it cannot afford. Its joints go to half the substep rate, ten times their base
///   stiffness: a joint's give under a load W on a light link of mass m is
///   2 W / (m omega^2), and a 900 kg block on 0.5 kg links (the heavy rope case) opened each
///   joint 15.5 mm at a quarter of a 16-substep rate, 3.9 mm at half, 2.5 mm at half of 20
///   substeps; swinging, where the bottom of the swing carries 2.7 times the weight, the
///   widest gap was 14.2 mm on 16 substeps and 8.8 mm on 20. Joints may go where contacts
///   may not: a contact at half the rate switches on and off as it rocks (a leaning plank
///   rocked at 4 Hz), an equality row never switches.
///
/// docs/benchmarks.md and docs/design.md have the measurements behind each number.
pub(super) const TIERS: [TierSpec; 6] = [
    // Base
    TierSpec {
        substep_quarters: 4,
        relax_scale: 1,
        normal_relax_scale: 0,
        creep: 0.0,
        joint_cap: JOINT_CAP,
    },
    // Braced
    TierSpec {
        substep_quarters: 4,
        relax_scale: 1,
        normal_relax_scale: 1,
        creep: 0.5,
        joint_cap: JOINT_CAP,
    },
    // Stack
    TierSpec {
        substep_quarters: 6,
        relax_scale: 1,
        normal_relax_scale: 0,
        creep: 0.5,
        joint_cap: JOINT_CAP,
    },
    // TallStack
    TierSpec {
        substep_quarters: 7,
        relax_scale: 1,
        normal_relax_scale: 0,
        creep: 0.5,
        joint_cap: JOINT_CAP,
    },
    // HeavyBraced
    TierSpec {
        substep_quarters: 8,
        relax_scale: 1,
        normal_relax_scale: 1,
        creep: 0.5,
        joint_cap: JOINT_CAP,
    },
    // Extreme
    TierSpec {
        substep_quarters: 20,
        relax_scale: 8,
        normal_relax_scale: 0,
        creep: 0.0,
        joint_cap: 0.5,
    },
];

impl Tier {
    /// Every tier, in order.
    pub const ALL: [Tier; 6] = [
        Tier::Base,
        Tier::Braced,
        Tier::Stack,
        Tier::TallStack,
        Tier::HeavyBraced,
        Tier::Extreme,
    ];

    /// What the tier does.
    pub fn spec(self) -> &'static TierSpec {
        &TIERS[self as usize]
    }

    /// The work a solve of this tier does under `settings`. The base tier is the settings
    /// themselves.
    pub fn effort(self, settings: &Settings) -> Effort {
        let spec = self.spec();
        let relax = settings.relax_iterations;
        let (substeps, contact_hertz) = if self == Tier::Base {
            (settings.substeps, settings.contact_hertz)
        } else {
            let quarters = spec.substep_quarters;
            (
                settings.substeps * quarters / 4,
                settings.contact_hertz * quarters as Real / 4.0,
            )
        };
        Effort {
            substeps,
            relax_passes: relax * spec.relax_scale,
            normal_relax_passes: relax * spec.normal_relax_scale,
            contact_hertz,
            creep: spec.creep,
            joint_cap: spec.joint_cap,
        }
    }
}

/// Adaptive stiffness's buffers, reused every step.
#[derive(Clone, Debug, Default)]
pub(super) struct TierScratch {
    /// What each contact asks, in contact order, filled as the contacts are found (read again
    /// by `assign_tiers` when the counts differ).
    pub inputs: Vec<TierInput>,
    /// Each contact's tier.
    pub contact_tier: Vec<Tier>,
    /// Each slot's tier.
    pub body_tier: Vec<Tier>,
    /// Each island's extent, at its root.
    pub island_extent: Vec<Extent>,
    /// Each island's number of moving bodies, at its root.
    pub island_bodies: Vec<u32>,
    /// Each contact's: whether a moving kinematic body drives its load.
    pub driven: Vec<bool>,
    /// Each island's, at its root: whether any of its contacts is driven.
    pub island_driven: Vec<bool>,
    /// The contacts' indices grouped by tier, while tiers are solved apart.
    pub tier_contacts: Vec<u32>,
    /// The bodies of the tier being solved.
    pub tier_bodies: Vec<u32>,
    /// A body of each joint that asks for [`Tier::Extreme`].
    pub joint_needs: Vec<u32>,
    /// A body of each joint that carries `stiff_load_ratio` times its lighter body's weight.
    pub joint_loaded: Vec<u32>,
    /// Each island's, at its root: whether a joint of it is loaded (sized only when one is).
    pub island_joint_loaded: Vec<bool>,
    /// Each slot's: whether a joint holds its body to a body that does not move with it
    /// (static or kinematic), which then carries its weight (sized only when one does).
    pub anchored: Vec<bool>,
    /// The joints (indices of this step's joint constraints) of the tier being solved.
    pub tier_joints: Vec<u32>,
}

impl World {
    /// Give every awake island a stiffness tier (see [`Tier`] and [`TIERS`]). An island is
    /// loaded where a contact's lasting force is `stiff_load_ratio` times the lighter body's
    /// weight or more, or a touching contact is too new for its load to be known. A loaded
    /// island braced sideways (less than [`SLENDER`] times as tall as it is wide, along
    /// gravity, with at least `stiff_load_ratio` moving bodies, and, if a moving kinematic
    /// body drives it, [`DRIVEN_DEPTH`] bodies deep) is [`Tier::Braced`], or
    /// [`Tier::HeavyBraced`] from [`HEAVY_DEPTH`] bodies deep or where a joint carries
    /// `stiff_load_ratio` times its lighter body's weight; any other a stack tier. Masses
    /// `stiff_load_ratio` apart ask for [`Tier::TallStack`] (braced if the island is),
    /// `extreme_mass_ratio` apart for [`Tier::Extreme`], where the light body carries the heavy
    /// one's weight and no joint holds the heavy one to a fixed body. Fills `contact_tier` and
    /// `body_tier`; returns the highest tier.
    pub(super) fn assign_tiers(&mut self, region: Option<&Region>) -> Tier {
        self.mark_anchored();
        let need = self.contact_needs(region).max(self.joint_needs());
        if need == Tier::Base {
            return Tier::Base;
        }
        self.island_tiers()
    }

    /// Flag the bodies a joint holds to a static or kinematic body (`anchored`): the anchor
    /// carries their weight, so a light body they touch does not (Box2D's `spinner`: a 48 kg
    /// paddle on a motor, hinged to the ground, stirring 0.17 kg bodies asked for the
    /// mass-ratio tier at every touch, and ran at twice the cost for it).
    fn mark_anchored(&mut self) {
        self.tiers.anchored.clear();
        let slots = &self.bodies.slots;
        // (The solver's one fixed body past the slots stands for the world.)
        let fixed = |i: u32| {
            slots
                .get(i as usize)
                .map_or(true, |s| s.body.as_ref().is_some_and(|b| b.inv_mass == 0.0))
        };
        for k in &self.joints.constraints.constraints {
            let held = match (fixed(k.a), fixed(k.b)) {
                (true, false) => k.b,
                (false, true) => k.a,
                _ => continue,
            };
            if self.tiers.anchored.is_empty() {
                self.tiers.anchored.resize(slots.len(), false);
            }
            self.tiers.anchored[held as usize] = true;
        }
    }

    /// What the joints ask: their pairs of dynamic bodies join islands (appended to
    /// `islands.contact_bodies`, so that no tier splits jointed bodies), and a joint joining
    /// masses `extreme_mass_ratio` apart asks for [`Tier::Extreme`], as a contact does
    /// (`joint_needs`). A joint whose last force was `stiff_load_ratio` times its lighter
    /// body's weight or more is noted (`joint_loaded`): it asks nothing by itself, but makes
    /// a braced island that its contacts load [`Tier::HeavyBraced`] (see `island_tiers`).
    fn joint_needs(&mut self) -> Tier {
        self.tiers.joint_needs.clear();
        self.tiers.joint_loaded.clear();
        if self.joints.constraints.is_empty() {
            return Tier::Base;
        }
        let (extreme, stiff) = (
            self.settings.extreme_mass_ratio,
            self.settings.stiff_load_ratio,
        );
        let g = self.gravity.length();
        let set = &self.joints.constraints;
        let mut top = Tier::Base;
        for (k, cold) in set.constraints.iter().zip(&set.cold) {
            let inv_mass = |i: u32| self.solver.bodies[i as usize].inv_mass;
            let (ma, mb) = (inv_mass(k.a), inv_mass(k.b));
            if ma == 0.0 || mb == 0.0 {
                continue;
            }
            self.islands.contact_bodies.push([k.a, k.b]);
            if ma.max(mb) / ma.min(mb) >= extreme {
                self.tiers.joint_needs.push(k.b);
                top = Tier::Extreme;
            }
            // (Last step's, carried by the constraint: reading it from the joint's slot was a
            // cache miss per joint.)
            let force = cold.force.length();
            // The lighter body's weight is g / its inverse mass.
            if g > 1e-3 && force * ma.max(mb) >= stiff * g {
                self.tiers.joint_loaded.push(k.b);
            }
        }
        top
    }

    /// What each contact asks of its island before the island's shape is known, into
    /// `contact_tier` (and each contact's bodies into `islands.contact_bodies`); the most any
    /// asks. Spread over `region`'s workers if given: each contact's need is its own.
    fn contact_needs(&mut self, region: Option<&Region>) -> Tier {
        if self.tiers.inputs.len() != self.contacts.awake.len() {
            // Contacts joined since they were found (an island woke): read them all again.
            let slop = self.settings.linear_slop;
            let awake = &self.contacts.awake;
            self.tiers.inputs.clear();
            self.tiers
                .inputs
                .extend(awake.iter().map(|c| TierInput::of(c, slop)));
        }
        // (Tests that lower the solve's threshold lower this one with it.)
        let from = self.solver.bundles.shared_from(SHARED_NEEDS_FROM);
        let (tiers, islands) = (&mut self.tiers, &mut self.islands);
        let (inputs, n) = (&tiers.inputs, tiers.inputs.len());
        let asks = Asks::new(&self.settings, self.gravity);
        let (bodies, contacts) = (&self.solver.bodies, &self.contacts.awake);
        let anchored = &tiers.anchored;
        // Contacts `run`'s needs, whether each is driven and their pairs, into the three.
        let fill = |run: std::ops::Range<usize>, (needs, driven, pairs): Needs| {
            let out = needs.iter_mut().zip(driven.iter_mut().zip(pairs));
            for (k, (need, (is_driven, pair))) in run.zip(out) {
                let input = &inputs[k];
                (*need, *is_driven, *pair) = asks.of(k, input, (bodies, contacts), anchored);
            }
        };
        // (Only new room is filled: every entry is written below.)
        tiers.contact_tier.resize(n, Tier::Base);
        tiers.driven.resize(n, false);
        islands.contact_bodies.resize(n, [0, 0]);
        let outputs = (
            &mut tiers.contact_tier[..],
            &mut tiers.driven[..],
            &mut islands.contact_bodies[..],
        );
        match region.filter(|_| n >= from) {
            None => fill(0..n, outputs),
            Some(region) => {
                // SAFETY: each block writes its own run of each.
                let (needs, driven, pairs) = unsafe {
                    (
                        SharedSlice::new(outputs.0),
                        SharedSlice::new(outputs.1),
                        SharedSlice::new(outputs.2),
                    )
                };
                region.for_blocks(n.div_ceil(NEEDS_PER_BLOCK), &|b| {
                    let run = block(b, NEEDS_PER_BLOCK, n);
                    // SAFETY: as above.
                    let out = unsafe {
                        (
                            needs.range(run.clone()),
                            driven.range(run.clone()),
                            pairs.range(run.clone()),
                        )
                    };
                    fill(run, out);
                });
            }
        }
        let needs = self.tiers.contact_tier.iter().copied();
        needs.max().unwrap_or(Tier::Base)
    }

    /// Islands by union-find over the contacts between awake dynamic bodies; each island's
    /// tier from its contacts' highest need and its shape, given to all its bodies and
    /// contacts. Returns the highest.
    fn island_tiers(&mut self) -> Tier {
        let n = self.solver.bodies.len();
        let islands = &mut self.islands;
        unite_islands(&mut islands.parent, n, &islands.contact_bodies, |_| true);
        flatten(&mut islands.parent);
        // (The same islands as sleep's: a pair of moving bodies is a pair of awake dynamic
        // ones, and a step's joint constraints are the joints with an awake body.)
        islands.united = true;
        self.measure_islands();
        let (parent, pairs) = (&self.islands.parent, &self.islands.contact_bodies);
        let tiers = &mut self.tiers;
        tiers.body_tier.clear();
        tiers.body_tier.resize(n, Tier::Base);
        tiers.island_driven.clear();
        tiers.island_driven.resize(n, false);
        let needs = tiers.contact_tier.iter().zip(&tiers.driven);
        for ((&need, &driven), &[a, _]) in needs.zip(pairs) {
            let root = parent[a as usize] as usize;
            tiers.body_tier[root] = tiers.body_tier[root].max(need);
            tiers.island_driven[root] |= driven;
        }
        for &b in &tiers.joint_needs {
            tiers.body_tier[parent[b as usize] as usize] = Tier::Extreme;
        }
        let joint_loaded = !tiers.joint_loaded.is_empty();
        if joint_loaded {
            tiers.island_joint_loaded.clear();
            tiers.island_joint_loaded.resize(n, false);
            for &b in &tiers.joint_loaded {
                tiers.island_joint_loaded[parent[b as usize] as usize] = true;
            }
        }
        let stiff = self.settings.stiff_load_ratio;
        // Depth stands for weight only where there is gravity.
        let weighed = self.gravity.length() > 1e-3;
        let mut top = Tier::Base;
        // A root comes before the rest of its island (the lower root wins), so one pass
        // settles each root's tier and hands it on.
        for (i, &root) in parent.iter().enumerate() {
            if root as usize != i {
                tiers.body_tier[i] = tiers.body_tier[root as usize];
                continue;
            }
            // A loaded island driven by a kinematic body carries the driver's load along its
            // lines of contacts: braced only if it is [`DRIVEN_DEPTH`] bodies deep.
            let extent = &tiers.island_extent[i];
            let braced = tiers.island_bodies[i] as Real >= stiff
                && !extent.slender()
                && (!tiers.island_driven[i] || extent.depth() >= DRIVEN_DEPTH);
            // A braced island whose load its joints carry (a pile of ragdolls) needs the
            // heavy tier's stiffer springs: on the braced tier's, a limb under the pile rests
            // 0.16 rad past its hinge's limit; on the heavy tier's, 0.04.
            let heavy = weighed
                && (extent.depth() >= HEAVY_DEPTH || joint_loaded && tiers.island_joint_loaded[i]);
            tiers.body_tier[i] = island_tier(tiers.body_tier[i], braced, heavy);
            top = top.max(tiers.body_tier[i]);
        }
        for (tier, &[a, _]) in tiers.contact_tier.iter_mut().zip(pairs) {
            *tier = tiers.body_tier[a as usize];
        }
        top
    }

    /// Each island's extent along gravity and across it (its bodies' boxes from the broad
    /// phase, found this step) and its number of moving bodies, at its root.
    fn measure_islands(&mut self) {
        let n = self.solver.bodies.len();
        let g = self.gravity.length();
        let down = if g > 1e-3 {
            self.gravity / g
        } else {
            Vec2::new(0.0, -1.0)
        };
        let across = Vec2::new(-down.y, down.x);
        let tiers = &mut self.tiers;
        tiers.island_extent.clear();
        tiers.island_extent.resize(n, Extent::EMPTY);
        tiers.island_bodies.clear();
        tiers.island_bodies.resize(n, 0);
        let boxes = self.broad_phase.proxies.iter().zip(&self.broad_phase.reach);
        for (i, (proxy, reach)) in boxes.enumerate() {
            if self.solver.bodies[i].inv_mass > 0.0 {
                let root = self.islands.parent[i] as usize;
                tiers.island_extent[root].add(&proxy.aabb, reach, down, across);
                tiers.island_bodies[root] += 1;
            }
        }
    }
}

/// A contact's bodies `[a, b]` (inverse masses `(ma, mb)`, 1/kg) as the islands see them: a
/// body that does not move joins nothing, so a contact with one stands for the other alone
/// (`[b, b]` when neither moves). The first is the body whose island the contact is in.
#[inline]
fn island_pair([a, b]: [u32; 2], (ma, mb): (Real, Real)) -> [u32; 2] {
    match (ma > 0.0, mb > 0.0) {
        (true, true) => [a, b],
        (true, false) => [a, a],
        (false, _) => [b, b],
    }
}

/// The tier a contact asks for, from its load in its lighter body's weights, its bodies' mass
/// ratio where the lighter carries the heavier (0 otherwise), and whether its load is yet
/// unmeasured ([`TierInput`]), under gravity `g` (m/s^2), with `Settings::stiff_load_ratio`
/// and `Settings::extreme_mass_ratio`. A soft contact's spring compresses by its load over
/// m omega^2, and omega can rise with the substep rate only: 1.5 times the substeps hold
/// 1.5^2 = 2.25 times the load at the same compression.
#[inline]
fn need_of(
    (load, masses, unmeasured): (Real, Real, bool),
    g: Real,
    (stiff, extreme): (Real, Real),
) -> Tier {
    if g <= 1e-3 {
        // Without gravity no contact carries a weight: loads come from impacts and pushes,
        // which the base settings solve (Box2D's `smash`).
        Tier::Base
    } else if masses >= extreme {
        Tier::Extreme
    } else if masses >= stiff || load >= LOADED_RANGE * stiff {
        Tier::TallStack
    } else if load >= stiff || unmeasured {
        Tier::Stack
    } else {
        Tier::Base
    }
}

/// Whether the lighter body of a contact between bodies of inverse masses `(ma, mb)` (1/kg)
/// carries the heavier one's weight, so that their masses' ratio matters to the solve (Gauss-
/// Seidel passes a heavy body's weight through a light one poorly): the contact's held load is
/// at least [`CARRIED_SHARE`] of the heavy body's weight under gravity `g` (m/s^2), or, while
/// its load is not yet measured, the heavy body lies above the light one (`up`, unit, against
/// gravity). Without gravity nothing carries anything's weight. A heavy body that strikes or
/// pushes light ones (Box2D's `smash`: no gravity, an 8 m square driven at 40 m/s into 9,600
/// boxes of 0.16 kg), or carries them (a drum full of boxes), asks for nothing by its mass.
fn carries_heavy(
    input: &TierInput,
    (ma, mb): (Real, Real),
    (up, normal): (Vec2, impl Fn() -> Vec2),
    g: Real,
) -> bool {
    if g <= 1e-3 {
        return false;
    }
    let heavy_inv = ma.min(mb);
    if input.load * heavy_inv >= CARRIED_SHARE * g {
        return true;
    }
    // The normal points from A to B: B is above A where it points up.
    let b_above = normal().dot(up);
    let heavy_above = if mb <= ma { b_above } else { -b_above };
    input.unmeasured && heavy_above > HEAVY_ABOVE
}

/// The share of a heavy body's weight a light body must carry for their masses' ratio to
/// ask for a tier: a heavy body resting on four light ones puts a quarter on each.
const CARRIED_SHARE: Real = 0.25;

/// How far above a light body a heavy one must lie, as the cosine of the contact normal's angle
/// from up (0.5: within 60 degrees of up), for a new contact between them to be solved as
/// carrying it before its load is measured.
const HEAVY_ABOVE: Real = 0.5;

/// What adaptive stiffness reads of a contact, taken as the contact is found: 16 bytes, so
/// that giving the contacts their tiers does not stream through the whole contacts.
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
    /// A placeholder, overwritten before it is read.
    pub const NONE: TierInput = TierInput {
        bodies: [0, 0],
        load: 0.0,
        unmeasured: false,
    };

    /// The contact's inputs; `slop` is `Settings::linear_slop` (m).
    #[inline]
    pub fn of(c: &Contact, slop: Real) -> TierInput {
        TierInput {
            bodies: [c.a, c.b],
            load: c.load,
            unmeasured: c.age < NEW_CONTACT_STEPS && c.live().iter().any(|p| p.separation <= slop),
        }
    }
}

/// The fewest contacts whose needs are found on the workers...
const SHARED_NEEDS_FROM: usize = 1024;
/// ...and how many a worker takes at a time.
const NEEDS_PER_BLOCK: usize = 512;

/// A run of contacts' needs, whether each is driven, and their pairs of bodies.
type Needs<'a> = (&'a mut [Tier], &'a mut [bool], &'a mut [[u32; 2]]);

/// What a contact's need reads besides the contact: the settings and gravity, worked out once
/// a step.
struct Asks {
    /// g (m/s^2) and its inverse (none below 1e-3).
    g: Real,
    per_g: Real,
    stiff: Real,
    extreme: Real,
    /// Up, against gravity (none without gravity: nothing rests on anything then).
    up: Vec2,
}

impl Asks {
    fn new(settings: &Settings, gravity: Vec2) -> Asks {
        let g = gravity.length();
        Asks {
            g,
            // (Multiplied by, not divided by, per contact: the two divisions a contact took
            // were a sixth of this stage.)
            per_g: 1.0 / g.max(1e-3),
            stiff: settings.stiff_load_ratio,
            extreme: settings.extreme_mass_ratio,
            up: if g > 1e-3 { -gravity / g } else { Vec2::ZERO },
        }
    }

    /// Contact `k`'s need (its `input`), whether a moving kinematic body drives it, and its
    /// pair of bodies for the islands; `anchored` as `TierScratch::anchored`.
    #[inline(always)]
    fn of(
        &self,
        k: usize,
        input: &TierInput,
        (bodies, contacts): (&[SolverBody], &[Contact]),
        anchored: &[bool],
    ) -> (Tier, bool, [u32; 2]) {
        let [a, b] = input.bodies;
        let inv_mass = |i: u32| bodies[i as usize].inv_mass;
        // Inverse masses: the lighter body has the larger one; static bodies have zero.
        let (ma, mb) = (inv_mass(a), inv_mass(b));
        let (light_inv, heavy_inv) = (ma.max(mb), ma.min(mb));
        let load = if light_inv > 0.0 {
            input.load * light_inv * self.per_g
        } else {
            0.0
        };
        // The masses' ratio light_inv / heavy_inv reaches `stiff` (rarely): divided then.
        let ratio_stiff = heavy_inv > 0.0 && light_inv >= self.stiff * heavy_inv;
        // (The contact's normal is read only for such a pair: rare, and kept out of the
        // 16 bytes read for every contact. None if the inputs no longer line up with the
        // contacts.)
        let normal = || match contacts.get(k) {
            Some(c) if [c.a, c.b] == input.bodies => c.normal,
            _ => Vec2::ZERO,
        };
        // (Read only for such a pair, as the normal is.)
        let anchored = || {
            let heavy = if mb <= ma { b } else { a };
            anchored.get(heavy as usize) == Some(&true)
        };
        let g = self.g;
        let masses =
            if ratio_stiff && !anchored() && carries_heavy(input, (ma, mb), (self.up, normal), g) {
                light_inv / heavy_inv
            } else {
                0.0
            };
        let need = need_of(
            (load, masses, input.unmeasured),
            g,
            (self.stiff, self.extreme),
        );
        // A moving kinematic body (inverse mass 0, but a velocity) pushes or carries.
        let moving = |i: u32| {
            let s = &bodies[i as usize];
            s.inv_mass == 0.0 && (s.v != Vec2::ZERO || s.w != 0.0)
        };
        let driven = need >= Tier::Stack && (moving(a) || moving(b));
        (need, driven, island_pair(input.bodies, (ma, mb)))
    }
}

/// An island is slender (a stack) when it is at least this many times as tall, along
/// gravity, as it is wide across it (its bodies' boxes): a 20-box stack of 1 m boxes is 14
/// times, a pyramid about once, a pile less. The shape is known at once; a measure of how the
/// load spreads (the most loaded contact against the island's weight) needs the loads, which
/// take five steps to build under a new stack.
pub(super) const SLENDER: Real = 2.0;

/// An island's extent (m) along gravity (up) and across it, from its bodies' boxes.
#[derive(Clone, Copy, Debug)]
pub(super) struct Extent {
    up: [Real; 2],
    side: [Real; 2],
    /// The sum of the bodies' widths across gravity (m).
    widths: Real,
}

impl Extent {
    /// No body yet.
    pub const EMPTY: Extent = Extent {
        up: [Real::INFINITY, Real::NEG_INFINITY],
        side: [Real::INFINITY, Real::NEG_INFINITY],
        widths: 0.0,
    };

    /// Take in box `aabb`, grown and swept by `travel` for the body's travel this step, with
    /// `down` the unit vector along gravity and `across` normal to it. The travel counts in
    /// the island's extent but not in the body's width: bodies flung about (Box2D's `spinner`,
    /// whose paddle's tips move at 100 m/s) have boxes grown by metres, and their pile read
    /// twice or three times as deep as it is.
    #[inline]
    fn add(&mut self, aabb: &Aabb, travel: &Travel, down: Vec2, across: Vec2) {
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
        let swept = travel.shift.x.abs() * across.x.abs() + travel.shift.y.abs() * across.y.abs();
        self.widths += (2.0 * (r_side - travel.grow) - swept).max(0.0);
    }

    /// How many bodies deep the island is on average: its bodies' widths across gravity over
    /// its own. Laid side by side on the ground they would stand this many high, and that is
    /// about how many of their weights its lowest contacts carry: (n + 1) / 2 for a pyramid
    /// of base n, whose ground contacts carry up to 1.4 times that. The widths are the
    /// broad phase's boxes less the step's travel (still grown by the contact margin, and a
    /// turned body's box is wider than the body), so a pile of small or jumbled bodies reads
    /// somewhat deeper than it is.
    fn depth(&self) -> Real {
        self.widths / (self.side[1] - self.side[0])
    }

    /// At least [`SLENDER`] times as tall as wide.
    fn slender(&self) -> bool {
        self.up[1] - self.up[0] >= SLENDER * (self.side[1] - self.side[0])
    }
}

/// The tier of an island from its contacts' highest `need` and whether it is `braced`: not
/// slender, and with at least `stiff_load_ratio` moving bodies. A loaded braced island (a
/// stack tier's need: load, or masses `stiff_load_ratio` apart) is [`Tier::Braced`]. A
/// smaller island cannot carry that many of its bodies' weight: it is loaded only by contacts
/// too new to be measured, unequal masses or an impact, and it is small, so it keeps the
/// stack tiers (a box sliding over a chain of tiles, loaded by each new contact, tilted past
/// 1e-4 rad when it was solved braced).
fn island_tier(need: Tier, braced: bool, heavy: bool) -> Tier {
    match need {
        Tier::Stack | Tier::TallStack if braced && heavy => Tier::HeavyBraced,
        Tier::Stack | Tier::TallStack if braced => Tier::Braced,
        _ => need,
    }
}

/// The loads [`Tier::Stack`] holds, as a multiple of `stiff_load_ratio`: 1.5^2, the square of
/// its substep factor (a spring's compression is load / (m omega^2)).
pub(super) const LOADED_RANGE: Real = 2.25;

/// A braced island at least this many bodies deep ([`Extent::depth`]) is [`Tier::HeavyBraced`]:
/// its lowest contacts carry some 80 to 110 of their bodies' weights, under which a ground
/// spring at the base 60 Hz compresses 80 g / (2 pi 60)^2 = 5.5 mm or more, past the linear
/// slop. A pyramid of base 134 (68 deep) stands braced; one of base 200 (100 deep), braced,
/// caved in (its top 5 m down within 5 s). Known from the island's shape at once, as
/// [`SLENDER`] is: a pyramid's loads take some 30 steps to build, and switching tiers as
/// they pass a bound let it sag sideways.
pub(super) const HEAVY_DEPTH: Real = 80.0;

/// A loaded island that a moving kinematic body drives is braced from this many bodies deep
/// ([`Extent::depth`]): the driver's push spreads over about that many lines of contacts. A
/// row of 64 boxes (1 deep) pushed at 3 m/s, braced, let the pusher 7.8 mm into it against
/// the slop of 5 mm (2.6 mm on the stack tier's 1.5 times the substeps); an 8 x 8 block (8
/// deep), braced, 2.6 mm. Box2D's `junkyard` pushes a heap of some 4,900 bodies, which ran
/// the tall stack's 1.75 times the substeps.
pub(super) const DRIVEN_DEPTH: Real = 3.0;

/// How many steps a new touching contact is solved as a loaded one before its measured load
/// decides.
const NEW_CONTACT_STEPS: u8 = 8;
