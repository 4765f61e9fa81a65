//! One step, stage by stage: find contacts, load the solver bodies, solve (the sequential
//! solver, or the soft step tier by tier), finalize the bodies, then sleep.

use super::continuous::{moved_more_than, FAST_FRACTION};
use super::tiers::Tier;
use super::*;
use crate::physics::solver::joint::{self, JointConstraint, JointStep};
use crate::physics::solver::soft_step::{self, StepContext};
use crate::physics::solver::BODIES_PER_BLOCK;
use crate::physics::team::{block, Region, SharedSlice};
use std::sync::atomic::{AtomicBool, Ordering};

/// Awake bodies (the broad phase's active list, kinematic bodies among them) from which a World
/// with workers wakes them for a step: below, the step takes some tens of microseconds, about
/// what waking them costs.
const SHARED_STEP_FROM: usize = 256;

/// The sequential solver's joint bias factor (box2d-lite's `k_biasFactor`): the fraction of a
/// joint's position error its velocity removes per step.
const JOINT_BAUMGARTE: Real = 0.2;

use crate::physics::solver::{
    integrate_positions, integrate_velocities, sequential, Limits, Moving, Selected,
};

impl World {
    /// Advance the world by `dt` seconds.
    ///
    /// The pipeline of the appendix: (1) integrate forces and gravity into velocities,
    /// (2) find contacts, (3) solve contact impulses, (4) integrate positions. Contacts depend
    /// on positions only, so they are found first (which also wakes whatever an awake body is
    /// about to touch); the soft step runs (1), (3) and (4) inside each substep. Then resting
    /// islands fall asleep. Forces and torques are cleared after the step.
    pub fn step(&mut self, dt: Real) -> Result<(), PhysicsError> {
        positive("dt", dt)?;
        // The World's workers, if it has any and enough is awake to share: taken out while
        // they are in use (the step borrows the rest of the World).
        let mut workers = std::mem::take(&mut self.workers);
        // (Tests that lower the solve's threshold lower this one with it.)
        let from = self.solver.bundles.shared_from(SHARED_STEP_FROM);
        // (Sensors query the tree even while everything else sleeps.)
        let share = self.broad_phase.sweep.active_count() >= from
            || self.bodies.asking.sensors >= self.shared_sensors_from();
        match &mut workers {
            Workers::Own(team) if share => team.region(|region| self.step_with(dt, Some(region))),
            Workers::Pool(pool) if share => match pool.take() {
                Some(mut team) => team.region(|region| self.step_with(dt, Some(region))),
                // Another World's step holds the pool: this one runs alone, to the same result.
                None => self.step_with(dt, None),
            },
            _ => self.step_with(dt, None),
        }
        self.workers = workers;
        Ok(())
    }

    /// [`World::step`], with its stages' blocks spread over `region`'s workers if given.
    fn step_with(&mut self, dt: Real, region: Option<&Region>) {
        self.events.begin_step();
        if self.islands.unsettled {
            self.settle_created_asleep();
        }
        (self.islands.refind, self.islands.united) = (false, false);
        if !self.broad_phase.sweep.active_is_empty() {
            // (Otherwise everything is static or asleep, and anything pushed would have been
            // woken: nothing moves, nothing to find or solve.)
            self.find_contacts(dt, region);
            // Bodies created asleep that just woke have no contacts among them yet.
            while std::mem::take(&mut self.islands.refind) {
                self.find_contacts(dt, region);
            }
            if self.bodies.flagged > 0 {
                self.find_hit_candidates(region);
            }
            self.load_solver_bodies(region);
            // (The build replaces last step's constraints; on workers it fills only new room.)
            if self.joints.count > 0 {
                self.build_joint_constraints(region);
            } else {
                self.joints.constraints.clear();
            }
            self.solver.recovery.clear();
            match self.settings.solver {
                SolverKind::Sequential => self.solve_sequential(dt),
                SolverKind::SoftStep => self.solve_soft_step(dt, region),
            }
            self.finalize_bodies(region);
            if !self.events.hit_candidates.is_empty() {
                self.confirm_hits();
            }
            self.joints.broken.clear();
            self.joints.broken_loads.clear();
            if !self.joints.constraints.is_empty() {
                self.finish_joints(region);
            }
            self.solve_continuous(region);
            if self.settings.enable_sleep {
                self.update_sleep(dt);
            }
        }
        self.time += dt as f64;
        self.steps += 1;
        if self.bodies.asking.touches > 0 || !self.events.touching.is_empty() {
            self.find_contact_events(region);
        }
        if self.bodies.asking.sensors > 0 || !self.events.overlapping.is_empty() {
            self.find_sensor_events(region);
        }
    }

    /// The appendix's pipeline once per step: velocities, sequential impulses, positions,
    /// then the position correction (split impulse).
    fn solve_sequential(&mut self, dt: Real) {
        let limits = self.limits();
        let (solver, contacts) = (&mut self.solver, &mut self.contacts.awake);
        // One constraint per contact, each written by prepare before it is read.
        solver
            .constraints
            .resize(contacts.len(), ContactConstraint::default());
        integrate_velocities(&mut solver.bodies, Moving::All, (dt, limits), None);
        let (bodies, constraints) = (&mut solver.bodies, &mut solver.constraints);
        let joints = &mut self.joints.constraints;
        let step = JointStep {
            h: dt,
            substeps: 1,
            baumgarte: JOINT_BAUMGARTE,
            warm_starting: self.settings.warm_starting,
            hertz_scale: 1.0,
            cap: joint::JOINT_CAP,
        };
        joint::prepare(joints, Selected::All, step, None);
        joint::warm_start(joints, Selected::All, bodies);
        let inv_dt = 1.0 / dt;
        let solve_joints = |bodies: &mut [SolverBody]| {
            joint::solve(joints, Selected::All, bodies, true, inv_dt);
        };
        sequential::solve(
            bodies,
            contacts,
            constraints,
            &self.settings,
            dt,
            solve_joints,
        );
        joint::store(joints, Selected::All, bodies, step, None);
        let movers = (Moving::All, solver.kinematic.as_slice());
        integrate_positions(&mut solver.bodies, movers, (dt, limits), None);
        let (bodies, constraints) = (&mut solver.bodies, &solver.constraints);
        let split = &mut solver.split_impulse;
        split.correct(bodies, contacts, constraints, &self.settings, dt);
    }

    /// The soft step. With adaptive stiffness, islands whose load calls for it are solved
    /// apart with their tier's work (`tiers.rs`); the rest, usually everything, in one solve.
    fn solve_soft_step(&mut self, dt: Real, region: Option<&Region>) {
        let top = if self.settings.adaptive_stiffness {
            self.assign_tiers(region)
        } else {
            Tier::Base
        };
        if top == Tier::Base {
            let all = Selected::All;
            self.solve_tier(Tier::Base, (Moving::All, all, all), (dt, region));
            return;
        }
        let ranges = self.group_by_tier();
        let dynamic = self
            .solver
            .bodies
            .iter()
            .filter(|b| b.inv_mass > 0.0)
            .count();
        // The tier lists are taken out while a tier is solved (they are its parts) and put
        // back, so their storage is kept from step to step.
        let (mut bodies, contacts, mut joints) = (
            std::mem::take(&mut self.tiers.tier_bodies),
            std::mem::take(&mut self.tiers.tier_contacts),
            std::mem::take(&mut self.tiers.tier_joints),
        );
        for tier in Tier::ALL.into_iter().filter(|&t| t <= top) {
            let body_tier = &self.tiers.body_tier;
            let solver_bodies = &self.solver.bodies;
            bodies.clear();
            bodies.extend((0..body_tier.len() as u32).filter(|&i| {
                body_tier[i as usize] == tier && solver_bodies[i as usize].inv_mass > 0.0
            }));
            if bodies.is_empty() {
                continue;
            }
            // Every moving body in this tier (a pyramid, a pile): the plain loop.
            let moving = if bodies.len() == dynamic {
                Moving::All
            } else {
                Moving::Only(&bodies)
            };
            let selected = match &ranges {
                Some(ranges) => Selected::Only(&contacts[ranges[tier as usize].clone()]),
                None if self.tiers.contact_tier.first() == Some(&tier) => Selected::All,
                // Bodies touching nothing: only integrated.
                None => Selected::Only(&[]),
            };
            self.tier_joints(tier, &mut joints);
            let parts = (moving, selected, Selected::Only(&joints));
            self.solve_tier(tier, parts, (dt, region));
        }
        (self.tiers.tier_bodies, self.tiers.tier_contacts) = (bodies, contacts);
        self.tiers.tier_joints = joints;
    }

    /// The joints of `tier`'s islands, by index into this step's joint constraints.
    fn tier_joints(&self, tier: Tier, list: &mut Vec<u32>) {
        list.clear();
        let (body_tier, solver_bodies) = (&self.tiers.body_tier, &self.solver.bodies);
        let of = |k: &JointConstraint| {
            let dynamic = if solver_bodies[k.b as usize].inv_mass > 0.0 {
                k.b
            } else {
                k.a
            };
            body_tier
                .get(dynamic as usize)
                .copied()
                .unwrap_or(Tier::Base)
        };
        let constraints = &self.joints.constraints.constraints;
        list.extend(
            (0..constraints.len() as u32).filter(|&k| of(&constraints[k as usize]) == tier),
        );
    }

    /// One soft-step solve of `tier`'s work on the `moving` bodies, `selected` contacts and
    /// `joints`.
    fn solve_tier(
        &mut self,
        tier: Tier,
        (moving, selected, joints): (Moving, Selected, Selected),
        (dt, region): (Real, Option<&Region>),
    ) {
        let mut ctx = StepContext {
            bodies: &mut self.solver.bodies,
            moving,
            kinematic: &self.solver.kinematic,
            contacts: &mut self.contacts.awake,
            selected,
            bundles: &mut self.solver.bundles,
            prepared: &mut self.solver.constraints,
            lists: &mut self.solver.lists,
            recovery: &mut self.solver.recovery,
            joints: &mut self.joints.constraints,
            joint_selected: joints,
            settings: &self.settings,
            dt,
            region,
        };
        soft_step::solve(&mut ctx, &tier.effort(&self.settings));
    }

    /// Where the tiers' contacts are: None when every contact is in one tier (a stack, a
    /// pyramid, a pile: each solve takes them all); otherwise each tier's range of
    /// `tier_contacts`, which lists the contacts' indices by tier in key order (one counting
    /// sort: a pile with one box off on its own paid a pass over every contact per tier).
    fn group_by_tier(&mut self) -> Option<[std::ops::Range<usize>; Tier::ALL.len()]> {
        let tiers = &mut self.tiers;
        let mut counts = [0usize; Tier::ALL.len()];
        for &t in &tiers.contact_tier {
            counts[t as usize] += 1;
        }
        if counts.iter().filter(|&&n| n > 0).count() <= 1 {
            return None;
        }
        let mut ranges: [std::ops::Range<usize>; Tier::ALL.len()] = Default::default();
        let mut start = 0;
        for (range, &n) in ranges.iter_mut().zip(&counts) {
            *range = start..start + n;
            start += n;
        }
        let mut next = ranges.clone().map(|r| r.start);
        // Every slot is written below.
        tiers.tier_contacts.resize(tiers.contact_tier.len(), 0);
        for (k, &t) in tiers.contact_tier.iter().enumerate() {
            let slot = &mut next[t as usize];
            tiers.tier_contacts[*slot] = k as u32;
            *slot += 1;
        }
        Some(ranges)
    }

    /// The speed limits applied while integrating.
    fn limits(&self) -> Limits {
        Limits {
            max_linear_speed: self.settings.max_linear_speed,
            max_rotation: self.settings.max_rotation,
        }
    }

    /// Copy what the solver needs into the compact solver array: awake dynamic bodies, and
    /// kinematic ones (infinite mass that moves: contacts see its velocity, nothing changes
    /// it); everything else is fixed. Lists the kinematic bodies that move. Spread over
    /// `region`'s workers if given, in the blocks the integration takes.
    fn load_solver_bodies(&mut self, region: Option<&Region>) {
        let g = self.gravity;
        let solver = &mut self.solver;
        solver.kinematic.clear();
        let slots = &self.bodies.slots;
        let Some(region) = region else {
            solver.bodies.clear();
            for (i, slot) in slots.iter().enumerate() {
                let (body, moving) = solver_body(slot, g);
                if moving {
                    solver.kinematic.push(Kinematic::of(i, &body));
                }
                solver.bodies.push(body);
            }
            // One more fixed body, last, for the empty lanes of bundles.
            solver.bodies.push(SolverBody::FIXED);
            return;
        };
        let n = slots.len();
        // (Only new room is filled: every row is written below.)
        solver.bodies.resize(n + 1, SolverBody::FIXED);
        solver.bodies[n] = SolverBody::FIXED;
        solver.marks.resize(n, false);
        let any = AtomicBool::new(false);
        // SAFETY: each block writes its own run of rows and marks.
        let (rows, marks) = unsafe {
            (
                SharedSlice::new(&mut solver.bodies),
                SharedSlice::new(&mut solver.marks),
            )
        };
        region.for_blocks((n + 1).div_ceil(BODIES_PER_BLOCK), &|k| {
            let run = block(k, BODIES_PER_BLOCK, n);
            // SAFETY: as above.
            let (rows, marks) = unsafe { (rows.range(run.clone()), marks.range(run.clone())) };
            for ((row, mark), slot) in rows.iter_mut().zip(marks).zip(&slots[run]) {
                let moving;
                (*row, moving) = solver_body(slot, g);
                *mark = moving;
                if moving {
                    any.store(true, Ordering::Relaxed);
                }
            }
        });
        if any.into_inner() {
            let (bodies, marks) = (&solver.bodies, &solver.marks);
            let moving = marks.iter().enumerate().filter(|(_, &m)| m);
            solver
                .kinematic
                .extend(moving.map(|(i, _)| Kinematic::of(i, &bodies[i])));
        }
    }

    /// Finalize: write velocities and the step's motion back to the bodies the solver moved
    /// (awake dynamic ones, and kinematic ones by their own velocity); clear forces.
    /// The dynamic bodies that moved far for their size are listed for continuous collision.
    /// Spread over `region`'s workers if given, in the blocks the integration takes.
    fn finalize_bodies(&mut self, region: Option<&Region>) {
        let max_speed = self.settings.max_linear_speed;
        let (solver, slots) = (&mut self.solver, &mut self.bodies.slots);
        let Some(region) = region else {
            for (i, (slot, sb)) in slots.iter_mut().zip(&solver.bodies).enumerate() {
                if finalize_body(slot, sb, max_speed) {
                    solver.fast.push(i as u32);
                }
            }
            return;
        };
        let n = slots.len();
        solver.marks.resize(n, false);
        let any = AtomicBool::new(false);
        let rows = &solver.bodies;
        // SAFETY: each block writes its own run of slots and marks.
        let (shared_slots, marks) =
            unsafe { (SharedSlice::new(slots), SharedSlice::new(&mut solver.marks)) };
        region.for_blocks((n + 1).div_ceil(BODIES_PER_BLOCK), &|k| {
            let run = block(k, BODIES_PER_BLOCK, n);
            // SAFETY: as above.
            let (slots, marks) =
                unsafe { (shared_slots.range(run.clone()), marks.range(run.clone())) };
            for ((slot, mark), sb) in slots.iter_mut().zip(marks).zip(&rows[run]) {
                *mark = finalize_body(slot, sb, max_speed);
                if *mark {
                    any.store(true, Ordering::Relaxed);
                }
            }
        });
        if any.into_inner() {
            let fast = solver.marks.iter().enumerate().filter(|(_, &m)| m);
            solver.fast.extend(fast.map(|(i, _)| i as u32));
        }
    }
}

/// Slot `slot`'s solver body under gravity `g`, and whether it is a kinematic body that moves.
#[inline]
fn solver_body(slot: &Slot, g: Vec2) -> (SolverBody, bool) {
    match &slot.body {
        Some(b) if b.is_active() => {
            let body = SolverBody {
                v: b.linear_velocity,
                w: b.angular_velocity,
                inv_mass: b.inv_mass,
                inv_inertia: b.inv_inertia,
                accel: g + b.inv_mass * b.force,
                alpha: b.inv_inertia * b.torque,
                dp: Vec2::ZERO,
                dtheta: 0.0,
                dq: Rot::IDENTITY,
            };
            (body, false)
        }
        Some(b) if b.kinematic => {
            let body = SolverBody {
                v: b.linear_velocity,
                w: b.angular_velocity,
                ..SolverBody::FIXED
            };
            (body, b.is_moving_kinematic())
        }
        _ => (SolverBody::FIXED, false),
    }
}

/// Finalize slot `slot`'s body from its solver body `sb`; whether it moved far for its size
/// this step (a dynamic body, for continuous collision).
#[inline]
fn finalize_body(slot: &mut Slot, sb: &SolverBody, max_speed: Real) -> bool {
    let Some(b) = slot.body.as_mut() else {
        return false;
    };
    b.force = Vec2::ZERO;
    b.torque = 0.0;
    let mut fast = false;
    if b.is_active() {
        // The relax passes after the last position update may leave a body faster than the
        // cap, and a blown-apart joint (see `joint::store`) not finite.
        b.linear_velocity = clamp_speed(sb.v, max_speed);
        b.angular_velocity = if sb.w.is_finite() { sb.w } else { 0.0 };
        let limit = FAST_FRACTION * b.min_extent;
        // Turning moves the shape's core at most its reach (a disc's not at all).
        let rounding = if b.compound().is_none() {
            b.shape.rounding()
        } else {
            0.0
        };
        let core_reach = b.bounding_radius - rounding;
        fast = moved_more_than(sb.dp, sb.dtheta, core_reach, limit);
    } else if !b.is_moving_kinematic() {
        return false;
    }
    b.position += sb.dp;
    b.angle += sb.dtheta;
    b.rot = Rot::from_angle(b.angle);
    fast
}
