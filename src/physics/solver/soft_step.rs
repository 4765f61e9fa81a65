//! The soft-step solver, after Erin Catto's Box2D v3 "Solver2D" write-ups, in Box2D's stages:
//!
//! ```text
//! prepare contacts                      once per step
//! for each of `substeps` substeps of length h:
//!     integrate velocities              v += h (g + F/m)
//!     warm start                        apply last substep's impulses
//!     solve                             soft contacts, with bias
//!     integrate positions               x += h v (kinematic bodies too)
//!     relax                             solve again, without bias
//! recover                               push out, in position, the overlap the springs
//!                                       do not reach (once per step)
//! restitution                           once per step
//! store impulses                        once per step
//! ```
//!
//! Contacts are springs tuned in hertz and damping ratio rather than a Baumgarte factor, so
//! their stiffness does not depend on the step or the iteration count ([`Softness`]); the
//! push-out speed is capped; speculative points (separation > 0) only let the bodies close
//! the gap in one substep, which stops fast bodies at the surface. Every stage but prepare and
//! store runs on the bundles (`bundles.rs`): the overflow, then the colours, in one kernel
//! (`contact_solver.rs`). Joints (`joint.rs`) go through the same stages and take colours in
//! the same constraint graph (`graph.rs`): in the warm start and each pass, each colour's
//! joints run just before its contacts.

use super::bundles::{list_of, ContactBundles, PackInput, SharedPackInput, Work, DEEP};
use super::constraint::{set_contact_masses, Arms, ContactConstraint, PointConstraint};
use super::contact_solver::PointImpulses;
use super::joint::{self, JointPass, JointSet, JointStep, JointWork};
use super::recover::{Recovery, LOAD_REACH, SPRING_REACH};
use super::softness::Softness;
use super::{
    integrate_positions, integrate_velocities, restart_motion, Kinematic, Limits, Moving, PassKind,
    Selected, SolverBody,
};
use crate::physics::contact::Contact;
use crate::physics::math::{Real, PI};
use crate::physics::settings::Settings;
use crate::physics::team::{block, Region, SharedSlice};

/// How much work one solve does: the World's settings scaled by the stiffness tier of the
/// islands it solves (`Settings::adaptive_stiffness`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Effort {
    /// Substeps.
    pub substeps: u32,
    /// Relax passes after each substep's position update (normal and friction, no bias).
    pub relax_passes: u32,
    /// Further relax passes that solve the normal constraints only: friction keeps what the
    /// full ones left it.
    pub normal_relax_passes: u32,
    /// Contact stiffness (Hz), before the cap of a quarter of the substep rate.
    pub contact_hertz: Real,
    /// How much of last step's compression the springs creep by (see [`creep`]; 0: none).
    pub creep: Real,
    /// The stiffest a joint may be, as a fraction of the substep rate.
    pub joint_cap: Real,
}

/// What the stages of one solve share.
pub(crate) struct StepContext<'a> {
    /// The solver bodies, with one extra fixed body last for the empty lanes of bundles.
    pub bodies: &'a mut [SolverBody],
    /// The dynamic bodies this solve moves (every body its contacts join is among them).
    pub moving: Moving<'a>,
    /// The kinematic bodies: moved by their own velocity, substep by substep.
    pub kinematic: &'a [Kinematic],
    /// Every contact; the solve works on the `selected` ones.
    pub contacts: &'a mut [Contact],
    pub selected: Selected<'a>,
    /// Where the selected contacts are packed for the lanes.
    pub bundles: &'a mut ContactBundles,
    /// The selected contacts' constraints, in order, when the workers prepare them...
    pub prepared: &'a mut Vec<ContactConstraint>,
    /// ...and the list each is packed into (`bundles::list_of`).
    pub lists: &'a mut Vec<u8>,
    /// The points overlapping deeper than the spring reaches (`recover.rs`).
    pub recovery: &'a mut Recovery,
    /// This step's joints; the solve works on the `joint_selected` ones.
    pub joints: &'a mut JointSet,
    pub joint_selected: Selected<'a>,
    pub settings: &'a Settings,
    /// The step (s).
    pub dt: Real,
    /// The World's workers, awake for this step, if it has more than one
    /// (`Settings::workers`).
    pub region: Option<&'a Region<'a>>,
}

/// What a solve works out once from its settings and effort.
struct Plan {
    substeps: u32,
    /// Substep (s) and its inverse (1/s).
    h: Real,
    inv_h: Real,
    relax_passes: u32,
    normal_relax_passes: u32,
    stiffness: Stiffness,
    limits: Limits,
    joints: JointStep,
}

impl Plan {
    fn new(settings: &Settings, effort: &Effort, dt: Real) -> Plan {
        let substeps = effort.substeps.max(1);
        let h = dt / substeps as Real;
        let inv_h = 1.0 / h;
        // A spring stiffer than a quarter of the substep rate is not resolved by the substep:
        // neither the base spring nor the doubled one against static bodies may pass it.
        let cap = 0.25 * inv_h;
        let hertz = effort.contact_hertz.min(cap);
        let static_hertz = (2.0 * hertz).min(cap);
        let zeta = settings.contact_damping_ratio;
        let stiffness = Stiffness {
            hertz,
            static_hertz,
            springs: [
                Softness::new(hertz, zeta, h),
                Softness::new(static_hertz, zeta, h),
            ],
            max_hertz: if settings.load_aware_stiffness {
                settings.max_contact_hertz_ratio * inv_h
            } else {
                0.0
            },
            zeta,
            slop: settings.linear_slop.max(Real::EPSILON),
            h,
            creep: effort.creep,
            min_reach: SPRING_REACH * settings.linear_slop,
            per_substep: 1.0 / substeps as Real,
            warm_starting: settings.warm_starting,
        };
        Plan {
            substeps,
            h,
            inv_h,
            relax_passes: effort.relax_passes,
            normal_relax_passes: effort.normal_relax_passes,
            stiffness,
            limits: Limits {
                max_linear_speed: settings.max_linear_speed,
                max_rotation: settings.max_rotation,
            },
            joints: JointStep {
                h,
                substeps,
                baumgarte: 0.0,
                warm_starting: settings.warm_starting,
                hertz_scale: effort.contact_hertz / settings.contact_hertz * effort.joint_cap
                    / joint::JOINT_CAP,
                cap: effort.joint_cap,
            },
        }
    }
}

/// One step of `ctx.dt` seconds on the selected contacts and the moving bodies, stage by
/// stage.
pub(crate) fn solve(ctx: &mut StepContext, effort: &Effort) {
    let plan = Plan::new(ctx.settings, effort, ctx.dt);
    restart_motion(ctx.bodies, ctx.kinematic);
    let selected = ctx.selected.count(ctx.contacts.len())
        + ctx.joint_selected.count(ctx.joints.constraints.len());
    let region = ctx.region.filter(|_| ctx.bundles.worth_sharing(selected));
    stages(ctx, &plan, region);
}

/// Every stage but the restart: on this thread alone, or with each stage's blocks spread
/// over `region`'s workers.
fn stages(ctx: &mut StepContext, plan: &Plan, region: Option<&Region>) {
    prepare_contacts(ctx, plan, region);
    prepare_joints(ctx, plan, region);
    substeps(ctx, plan, region);
    store_impulses(ctx, plan, region);
}

/// The substeps, recover and restitution.
fn substeps(ctx: &mut StepContext, plan: &Plan, region: Option<&Region>) {
    for _ in 0..plan.substeps {
        integrate_velocities(ctx.bodies, ctx.moving, (plan.h, plan.limits), region);
        warm_start(ctx, region);
        solve_pass(ctx, plan, PassKind::Biased, region);
        let movers = (ctx.moving, ctx.kinematic);
        integrate_positions(ctx.bodies, movers, (plan.h, plan.limits), region);
        relax(ctx, plan, region);
    }
    recover(ctx);
    apply_restitution(ctx, region);
}

/// Prepare: each selected contact's constraint for this step (effective masses, adjusted
/// separations, approach speeds, spring, block), packed into its bundle's lane.
/// The contacts overlapping deeper than their springs reach are noted for the recover stage.
fn prepare_contacts(ctx: &mut StepContext, plan: &Plan, region: Option<&Region>) {
    let stiffness = &plan.stiffness;
    if let Some(region) = region {
        return prepare_and_pack_shared(ctx, stiffness, region);
    }
    let recovery = &mut *ctx.recovery;
    recovery.begin_solve();
    let limits = (1.0 / ctx.dt, ctx.settings.max_push_out_speed);
    ctx.bundles.build(PackInput {
        bodies: ctx.bodies,
        contacts: ctx.contacts,
        selected: ctx.selected,
        // Inlined into the packing loop (an attribute goes on a closure only as an argument,
        // hence `identity`): called, its constraint went back through memory, 2.5 % of a
        // pyramid's step.
        prepare: std::convert::identity(
            #[inline(always)]
            |c: &mut Contact, a: &SolverBody, b: &SolverBody, k: &mut ContactConstraint| {
                prepare_contact(a, b, c, stiffness, k);
                if k.reach > 0.0 {
                    recovery.note(c, (a, b), k.reach, limits);
                }
            },
        ),
        fill_gaps: ctx.joints.is_empty(),
    });
}

/// [`prepare_contacts`] on `region`'s workers: each contact prepared (`prepare_shared`),
/// then each colour's lists packed by one worker; the deep contacts noted for the recover
/// stage by this thread, in key order.
fn prepare_and_pack_shared(ctx: &mut StepContext, stiffness: &Stiffness, region: &Region) {
    prepare_shared(ctx, stiffness, region);
    let input = SharedPackInput {
        bodies: ctx.bodies,
        contacts: ctx.contacts,
        selected: ctx.selected,
        prepared: ctx.prepared,
        lists: ctx.lists,
    };
    ctx.bundles.build_shared(region, &input);
    let recovery = &mut *ctx.recovery;
    recovery.begin_solve();
    let limits = (1.0 / ctx.dt, ctx.settings.max_push_out_speed);
    // (The deep ones are marked in their list byte: scanning the constraints themselves, 2 MB
    // for a pyramid of 5,050 boxes, took 2.4 % of its step.)
    for (m, &l) in ctx.lists.iter().enumerate() {
        if l & DEEP != 0 {
            let (c, k) = (&ctx.contacts[ctx.selected.at(m)], &ctx.prepared[m]);
            let (a, b) = (&ctx.bodies[c.a as usize], &ctx.bodies[c.b as usize]);
            recovery.note(c, (a, b), k.reach, limits);
        }
    }
}

/// How many contacts a worker prepares at a time.
const PREPARED_PER_BLOCK: usize = 64;

/// Prepare the selected contacts' constraints, in order, into `ctx.prepared`, and the list
/// each is packed into into `ctx.lists`, spread over `region`'s workers.
fn prepare_shared(ctx: &mut StepContext, stiffness: &Stiffness, region: &Region) {
    let (selected, n) = (ctx.selected, ctx.selected.count(ctx.contacts.len()));
    // (Every one is written below: only new room is filled first. Clearing first rewrote
    // 2 MB a step for a pyramid of 5,050 boxes.)
    ctx.prepared.resize(n, ContactConstraint::default());
    ctx.lists.resize(n, 0);
    // SAFETY: the selected contacts are distinct (ascending indices), and each block
    // reaches its own run of them, of the constraints and of the lists.
    let (out, contacts, lists) = unsafe {
        (
            SharedSlice::new(ctx.prepared),
            SharedSlice::new(ctx.contacts),
            SharedSlice::new(ctx.lists),
        )
    };
    let (bodies, singles) = (&*ctx.bodies, ctx.bundles.singles_apart(n));
    region.for_blocks(n.div_ceil(PREPARED_PER_BLOCK), &|k| {
        for m in block(k, PREPARED_PER_BLOCK, n) {
            // SAFETY: as above.
            let (c, k, l) = unsafe { (contacts.get(selected.at(m)), out.get(m), lists.get(m)) };
            let (c, k) = (c.expect("a selected contact"), k.expect("its constraint"));
            prepare_contact(
                &bodies[c.a as usize],
                &bodies[c.b as usize],
                c,
                stiffness,
                k,
            );
            let deep = if k.reach > 0.0 { DEEP } else { 0 };
            *l.expect("its list") = list_of(c, k, singles) | deep;
        }
    });
}

/// Prepare the joints (`joint.rs`): springs, caps, impulses per substep.
fn prepare_joints(ctx: &mut StepContext, plan: &Plan, region: Option<&Region>) {
    if !ctx.joints.is_empty() {
        let region = joint_region(ctx, region);
        joint::prepare(ctx.joints, ctx.joint_selected, plan.joints, region);
    }
}

/// `region`, if the selected joints are enough to spread their prepare and store over it.
fn joint_region<'r>(ctx: &StepContext, region: Option<&'r Region<'r>>) -> Option<&'r Region<'r>> {
    let n = ctx.joint_selected.count(ctx.joints.constraints.len());
    region.filter(|_| n >= ctx.bundles.shared_from(joint::SHARED_JOINTS_FROM))
}

/// Warm start: apply each joint's and contact's accumulated impulses (zero them with warm
/// starting off), colour by colour.
fn warm_start(ctx: &mut StepContext, region: Option<&Region>) {
    let warm_starting = ctx.settings.warm_starting;
    let region = region.filter(|_| warm_starting);
    if ctx.joints.is_empty() {
        match region {
            Some(r) => ctx.bundles.run_shared(r, ctx.bodies, Work::WarmStart, None),
            None => ctx.bundles.warm_start(ctx.bodies, warm_starting, None),
        }
        return;
    }
    let mut pass = JointPass::new(ctx.joints, ctx.joint_selected, JointWork::WarmStart);
    match region {
        Some(r) => {
            let mut run =
                |bodies: &mut [SolverBody], rank: u8| pass.run_until_shared(r, bodies, rank);
            ctx.bundles
                .run_shared(r, ctx.bodies, Work::WarmStart, Some(&mut run));
            pass.run_until_shared(r, ctx.bodies, u8::MAX);
        }
        None => {
            let mut run = |bodies: &mut [SolverBody], rank: u8| pass.run_until(bodies, rank);
            ctx.bundles
                .warm_start(ctx.bodies, warm_starting, Some(&mut run));
            pass.run_until(ctx.bodies, u8::MAX);
        }
    }
}

/// One solve pass of `kind` over the joints (but for a normal relax pass) and the contacts,
/// colour by colour: the overflow's joints, the overflow's contacts, then each colour's
/// joints and contacts (Box2D v3's order).
fn solve_pass(ctx: &mut StepContext, plan: &Plan, kind: PassKind, region: Option<&Region>) {
    let args = (kind, plan.inv_h, ctx.settings.max_push_out_speed);
    if kind == PassKind::NormalRelax || ctx.joints.is_empty() {
        match region {
            Some(r) => ctx
                .bundles
                .run_shared(r, ctx.bodies, Work::Solve(args), None),
            None => ctx.bundles.solve(ctx.bodies, args, None),
        }
        return;
    }
    let work = JointWork::Solve {
        biased: kind == PassKind::Biased,
        inv_h: plan.inv_h,
    };
    let mut pass = JointPass::new(ctx.joints, ctx.joint_selected, work);
    match region {
        Some(r) => {
            let mut run =
                |bodies: &mut [SolverBody], rank: u8| pass.run_until_shared(r, bodies, rank);
            let work = Work::Solve(args);
            ctx.bundles.run_shared(r, ctx.bodies, work, Some(&mut run));
            pass.run_until_shared(r, ctx.bodies, u8::MAX);
        }
        None => {
            let mut run = |bodies: &mut [SolverBody], rank: u8| pass.run_until(bodies, rank);
            ctx.bundles.solve(ctx.bodies, args, Some(&mut run));
            pass.run_until(ctx.bodies, u8::MAX);
        }
    }
}

/// Recover: the overlap beyond the springs' reach pushed out in position (`recover.rs`).
fn recover(ctx: &mut StepContext) {
    ctx.recovery.push_out(ctx.bodies, ctx.dt);
}

/// Relax: the relax passes, then the normal relax passes.
fn relax(ctx: &mut StepContext, plan: &Plan, region: Option<&Region>) {
    for _ in 0..plan.relax_passes {
        solve_pass(ctx, plan, PassKind::Relax, region);
    }
    for _ in 0..plan.normal_relax_passes {
        solve_pass(ctx, plan, PassKind::NormalRelax, region);
    }
}

/// Restitution: reverse e times the approach speed where a point bounced.
fn apply_restitution(ctx: &mut StepContext, region: Option<&Region>) {
    let threshold = ctx.settings.restitution_threshold;
    match region {
        Some(r) => {
            let work = Work::Restitution(threshold);
            ctx.bundles.run_shared(r, ctx.bodies, work, None)
        }
        None => ctx.bundles.apply_restitution(ctx.bodies, threshold),
    }
}

/// Store: each joint's and contact's impulses back into it, per step, and its load.
fn store_impulses(ctx: &mut StepContext, plan: &Plan, region: Option<&Region>) {
    if !ctx.joints.is_empty() {
        joint::store(
            ctx.joints,
            ctx.joint_selected,
            ctx.bodies,
            plan.joints,
            region,
        );
    }
    let (substeps, inv_dt) = (plan.substeps as Real, 1.0 / ctx.dt);
    let then = |c: &mut Contact, ends: &[PointImpulses; 2]| finish(c, ends, substeps, inv_dt);
    match region {
        Some(r) => ctx.bundles.store_shared(r, ctx.contacts, &then),
        None => ctx.bundles.store(ctx.contacts, then),
    }
}

/// Contact `c`'s constraint for this step between bodies `a` and `b`, into `k`. The impulses it carries
/// from the last step become per substep: between steps a contact keeps its impulses per step,
/// so that an island whose substep count changes (adaptive stiffness) warm starts with the
/// same force (exact for substep counts that are powers of two, 4 and 16, and within rounding
/// for the middle tiers' 6 and 7).
#[inline(always)]
fn prepare_contact(
    a: &SolverBody,
    b: &SolverBody,
    c: &mut Contact,
    stiffness: &Stiffness,
    k: &mut ContactConstraint,
) {
    *k = ContactConstraint::default();
    let n = c.normal;
    let mut deepest = Real::INFINITY;
    for (p, kp) in c.live_mut().iter_mut().zip(&mut k.points) {
        deepest = deepest.min(p.separation);
        p.normal_impulse *= stiffness.per_substep;
        p.tangent_impulse *= stiffness.per_substep;
        let arms = Arms::new(p.anchor_a, p.anchor_b, n);
        kp.arms = arms;
        kp.adjusted_separation = p.separation - (arms.b_dot_n - arms.a_dot_n);
        p.total_normal_impulse = 0.0;
        if !stiffness.warm_starting {
            p.normal_impulse = 0.0;
            p.tangent_impulse = 0.0;
        }
    }
    let block = set_contact_masses(&mut k.points, a, b, c);
    k.softness = stiffness.softness(c, &k.points);
    k.creep = if stiffness.creep > 0.0 {
        stiffness.creep * creep(c, k.softness, a.inv_mass + b.inv_mass)
    } else {
        0.0
    };
    k.block = block;
    if deepest < -stiffness.min_reach {
        hold_if_deep(c, k, deepest, stiffness.min_reach);
    }
}

/// A contact whose deepest point (`deepest`, m) overlaps deeper than its spring reaches
/// ([`spring_reach`], at least `min_reach`, m) is held rigidly, with no spring and no creep
/// (a spring's damping under a load lets it sink on), and `k.reach` records the reach for the
/// recover stage, which pushes it out in position (`recover.rs`); any other keeps its spring
/// and a reach of 0. Rare, and kept out of line: inlined into the packing loop, it cost a
/// pyramid 7 % of its step.
#[cold]
#[inline(never)]
fn hold_if_deep(c: &Contact, k: &mut ContactConstraint, deepest: Real, min_reach: Real) {
    let reach = spring_reach(c, k.softness, &k.points).max(min_reach);
    if deepest < -reach {
        k.softness = Softness::RIGID;
        k.creep = 0.0;
        k.reach = reach;
    }
}

/// The end of a step for contact `c`, from its points' impulses `ends`: back from per
/// substep to per step, and the contact's load (`substeps` as a number, `inv_dt` in 1/s).
/// The friction impulse is clamped to the Coulomb cone of the normal impulse it ends with: a
/// normal relax pass, after the last friction solve, can lower the normal impulse under it.
#[inline]
fn finish(c: &mut Contact, ends: &[PointImpulses; 2], substeps: Real, inv_dt: Real) {
    let mut force = 0.0;
    for (p, end) in c.points[..c.count as usize].iter_mut().zip(ends) {
        // (A body blown apart by a joint may bring NaN here: it does not stay.)
        let end = &end.finite_or_zero();
        let max_f = (c.friction * end.normal).max(0.0);
        p.normal_impulse = end.normal * substeps;
        p.tangent_impulse = end.tangent.clamp(-max_f, max_f) * substeps;
        p.total_normal_impulse = end.total_normal;
        p.approach_velocity = end.approach;
        force += end.total_normal;
    }
    // The force the contact carried, held so that a load that comes and goes does not
    // switch an island's work on and off every step (`Settings::adaptive_stiffness`), and
    // counted only when it lasted two steps running: the impact of a falling body is a
    // one-step spike, not a load to stiffen for.
    let force = force * inv_dt;
    c.load = force.min(c.force).max(HERTZ_DECAY * c.load);
    c.force = force;
}

/// How stiff contacts are made this step, and what preparing a contact needs besides.
struct Stiffness {
    /// Base stiffness (Hz).
    hertz: Real,
    /// Stiffness against a static body (Hz): twice the base (Box2D), within the same cap of
    /// a quarter of the substep rate. Uncapped, at the default 60 Hz and 4 substeps it was
    /// 120 Hz, half the substep rate, and a plank leaning from a box against a wall rocked at
    /// 4 Hz forever in 2 of 200 simulated tilt histories of the Falling Bricks box.
    static_hertz: Real,
    /// The springs of `hertz` and `static_hertz`, worked out once per solve.
    springs: [Softness; 2],
    /// Ceiling for load-aware stiffening (Hz); 0 disables it.
    max_hertz: Real,
    /// Damping ratio.
    zeta: Real,
    /// Penetration the load may cause at rest (m).
    slop: Real,
    /// Substep (s).
    h: Real,
    /// How much of last step's compression the springs creep by (see [`creep`]; 0: none).
    creep: Real,
    /// The least overlap a spring acts on (m): [`SPRING_REACH`] slops.
    min_reach: Real,
    /// 1 / substeps: per step to per substep.
    per_substep: Real,
    /// Whether contacts start from last step's impulses.
    warm_starting: bool,
}

impl Stiffness {
    /// The contact's spring. A spring of stiffness k = m_eff omega^2 carrying a steady force F
    /// sinks s = F / k. Box2D fixes omega, so a contact under a tall stack sinks in proportion
    /// to the weight above it, and a column of such springs buckles (a 20-box stack at 30 Hz
    /// falls over). Load-aware stiffening raises omega just enough that last step's force sinks
    /// the contact by no more than the slop: omega^2 >= F / (m_eff slop), within the ceiling.
    ///
    /// The load moves from step to step, and a spring whose stiffness follows it can pump
    /// energy into a contact. So the frequency rises at once when the load calls for it but
    /// falls by at most [`HERTZ_DECAY`] per step. That hold is not enough for a big pile,
    /// which is why stiffening is off by default (`Settings::load_aware_stiffness`). `points`
    /// are the contact's constraints this step.
    #[inline(always)]
    fn softness(&self, c: &mut Contact, points: &[PointConstraint; 2]) -> Softness {
        let base = if c.touches_static {
            self.static_hertz
        } else {
            self.hertz
        };
        if self.max_hertz <= base {
            // No load-aware stiffening: every contact has one of the two springs.
            c.hertz = base;
            return self.springs[usize::from(c.touches_static)];
        }
        let mut force: Real = 0.0;
        let mut mass = Real::INFINITY;
        for (p, k) in c.live().iter().zip(points) {
            force = force.max(p.normal_impulse / self.h);
            mass = mass.min(k.normal_mass);
        }
        let mut wanted = base;
        if force > 0.0 && mass > 0.0 && mass.is_finite() {
            let omega = (force / (mass * self.slop)).sqrt();
            wanted = omega / (2.0 * PI);
        }
        let hertz = wanted
            .max(HERTZ_DECAY * c.hertz)
            .clamp(base, self.max_hertz);
        c.hertz = hertz;
        Softness::new(hertz, self.zeta, self.h)
    }
}

/// Load-aware stiffening: the most a contact's spring frequency may fall in one step, as a
/// factor (0.98: to half in 34 steps, about 0.6 s at 60 Hz).
const HERTZ_DECAY: Real = 0.98;

/// Creep: the compression (m) at which the contact's spring would carry, in translation, the
/// load it carried last step; the biased pass adds a fraction beta of it to each point's
/// separation, so that the spring's force lags its compression by a step.
///
/// A soft contact at rest takes the impulse -m ms br s - is P in the biased pass (see
/// [`Softness`]); pushing the pair apart as a whole (its mass along the normal is the reduced
/// mass mu = 1 / (1/mA + 1/mB)) it carries the total impulse P at the compression
/// s = -is P / (mu ms br), that is F / (mu omega^2) with F = P / h. Adding beta times that to
/// s gives the spring the response F_n = -k s_n - beta F_(n-1): for a slow motion
/// e^(i theta n) the force is -k s / (1 + beta e^(-i theta)), whose part in phase with the
/// velocity opposes it. The contact dissipates energy in the slow modes of a pile or a
/// pyramid (a base-30 pyramid bounces at about 4 Hz while its top rows slide) that the
/// springs' own damping, set per substep, leaves ringing; at rest it is 1 + beta times softer.
/// One value for all the contact's points: per point, the creep also acted on the rocking of
/// a two-point contact and threw a jittered 20-box stack over. The load is the contact's held
/// load (`Contact::load`), so the one-step spike of an impact makes nothing creep, and a
/// contact younger than [`CREEP_FROM_AGE`] steps does not creep. `sf` is the contact's spring
/// this step; `inv_mass` is 1/mA + 1/mB (1/kg).
fn creep(c: &Contact, sf: Softness, inv_mass: Real) -> Real {
    if c.force <= 0.0 || inv_mass <= 0.0 || c.age < CREEP_FROM_AGE {
        return 0.0;
    }
    let steady = (c.load / c.force).min(1.0);
    let impulse: Real = c.live().iter().map(|p| p.normal_impulse).sum();
    let stiffness = sf.mass_scale * sf.bias_rate;
    if stiffness > 0.0 {
        steady * sf.impulse_scale * impulse * inv_mass / stiffness
    } else {
        0.0
    }
}

/// The overlap (m) contact `c`'s spring may need for the load it carried last step:
/// [`LOAD_REACH`] times the compression at which each point would carry its share,
/// is P / (m ms br) with P its impulse, `is` the spring's impulse scale (see [`creep`]) and m
/// its mass along the normal, turning included
/// (the corner of a tilted box deep in a pile rests 34 mm into the box under it). `sf` is the
/// contact's spring this step, `points` its constraints.
fn spring_reach(c: &Contact, sf: Softness, points: &[PointConstraint; 2]) -> Real {
    let stiffness = sf.mass_scale * sf.bias_rate;
    let mut reach: Real = 0.0;
    for (p, k) in c.live().iter().zip(points) {
        if stiffness > 0.0 && k.normal_mass > 0.0 {
            let compression = sf.impulse_scale * p.normal_impulse / (k.normal_mass * stiffness);
            reach = reach.max(LOAD_REACH * compression);
        }
    }
    reach
}

/// Creep acts on contacts that have lasted this many steps: contacts that creep while bodies
/// are still landing let them sink and reach further, and a falling pile then finds and
/// solves more contacts (docs/benchmarks.md has the figures).
const CREEP_FROM_AGE: u8 = 4;
