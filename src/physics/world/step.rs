//! One step: the stages in order (contacts, solve, store, sleep) and the soft step's tiers.

use super::islands::{CREEP, NORMAL_RELAX_SCALE, RELAX_SCALE, SUBSTEP_QUARTERS, TIERS};
use super::*;
use crate::physics::solver::constraint::ContactConstraint;
use crate::physics::solver::soft_step::Work;

impl World {
    /// Advance the world by `dt` seconds.
    ///
    /// The pipeline of the appendix: (1) integrate forces and gravity into velocities,
    /// (2) find contacts, (3) solve contact impulses, (4) integrate positions. Contacts depend
    /// on positions only, so they are found first (which also wakes whatever an awake body is
    /// about to touch); the soft-step solver runs (1), (3) and (4) inside each substep. Then
    /// resting islands fall asleep. Forces and torques are cleared after the step.
    pub fn step(&mut self, dt: Real) -> Result<(), PhysicsError> {
        positive("dt", dt)?;
        if self.broad_phase.active_is_empty() {
            // Everything is static or asleep (anything pushed would have been woken): nothing
            // moves, nothing to find or solve.
            self.time += dt as f64;
            self.steps += 1;
            return Ok(());
        }
        let limits = Limits {
            max_linear_speed: self.settings.max_linear_speed,
            max_rotation: self.settings.max_rotation,
        };
        self.find_contacts(dt, self.settings.speculative_distance);
        // One constraint slot per contact. Only the scalar code's contacts use theirs, and
        // each writes its own before reading it, so the slots are not cleared.
        self.constraints
            .resize(self.contacts.len(), ContactConstraint::default());
        self.load_solver_bodies();
        match self.settings.solver {
            SolverKind::Sequential => {
                solver::integrate_velocities(&mut self.solver_bodies, Moving::All, dt, limits);
                solver::sequential::solve(
                    &mut self.solver_bodies,
                    &mut self.contacts,
                    &mut self.constraints,
                    &self.settings,
                    dt,
                );
                solver::integrate_positions(&mut self.solver_bodies, Moving::All, dt, limits);
                self.split_impulse.correct(
                    &mut self.solver_bodies,
                    &self.contacts,
                    &self.constraints,
                    &self.settings,
                    dt,
                );
            }
            SolverKind::SoftStep => self.solve_soft_step(dt, limits),
        }
        self.store_solver_bodies();
        self.move_kinematic(dt);
        if self.settings.enable_sleep {
            self.update_sleep(dt);
        }
        self.time += dt as f64;
        self.steps += 1;
        Ok(())
    }

    /// The soft step, with adaptive stiffness: islands whose load calls for it are solved apart,
    /// with 1.5, 1.75 or 4 times the substeps and contact stiffness (and, at 4, more relax passes)
    /// (`Settings::adaptive_stiffness`); the rest, usually everything, in one solve as before.
    pub(super) fn solve_soft_step(&mut self, dt: Real, limits: Limits) {
        let top = if self.settings.adaptive_stiffness {
            self.assign_tiers()
        } else {
            0
        };
        if top == 0 {
            solver::soft_step::solve(
                &mut self.solver_bodies,
                Moving::All,
                &mut self.contacts,
                &mut self.constraints,
                Selected::All,
                &mut self.wide,
                Work {
                    settings: &self.settings,
                    creep: CREEP[0],
                    normal_relax: self.settings.relax_iterations * NORMAL_RELAX_SCALE[0],
                },
                dt,
                limits,
            );
            return;
        }
        let mut counts = [0usize; TIERS];
        for &t in &self.contact_tier {
            counts[t as usize] += 1;
        }
        let has_contacts = counts.map(|n| n > 0);
        // Usually every contact is in one tier (a stack, a pyramid, a pile): solve them all.
        // Otherwise each tier solves the list of its contacts' indices, in key order, and the
        // contacts stay where they are. The lists are one counting sort: a pile with one box
        // off on its own (tier 0) paid a pass over every contact per tier.
        let split = has_contacts.iter().filter(|&&h| h).count() > 1;
        let mut ranges: [std::ops::Range<usize>; TIERS] = Default::default();
        if split {
            let mut start = 0;
            for (range, &n) in ranges.iter_mut().zip(&counts) {
                *range = start..start + n;
                start += n;
            }
            let mut next = ranges.clone().map(|r| r.start);
            // Every slot is written below.
            self.tier_contacts.resize(self.contact_tier.len(), 0);
            for (k, &t) in self.contact_tier.iter().enumerate() {
                let slot = &mut next[t as usize];
                self.tier_contacts[*slot] = k as u32;
                *slot += 1;
            }
        }
        let dynamic = self
            .solver_bodies
            .iter()
            .filter(|b| b.inv_mass > 0.0)
            .count();
        for tier in 0..=top {
            self.tier_bodies.clear();
            let (bodies, body_tier) = (&self.solver_bodies, &self.body_tier);
            self.tier_bodies.extend(
                (0..body_tier.len() as u32).filter(|&i| {
                    body_tier[i as usize] == tier && bodies[i as usize].inv_mass > 0.0
                }),
            );
            if self.tier_bodies.is_empty() {
                continue;
            }
            let settings = if tier == 0 {
                self.settings.clone()
            } else {
                let t = tier as usize;
                Settings {
                    substeps: self.settings.substeps * SUBSTEP_QUARTERS[t] / 4,
                    relax_iterations: self.settings.relax_iterations * RELAX_SCALE[t],
                    contact_hertz: self.settings.contact_hertz * SUBSTEP_QUARTERS[t] as Real / 4.0,
                    ..self.settings.clone()
                }
            };
            let selected = if split {
                Selected::Only(&self.tier_contacts[ranges[tier as usize].clone()])
            } else if has_contacts[tier as usize] {
                Selected::All
            } else {
                // Bodies touching nothing: only integrated.
                Selected::Only(&[])
            };
            solver::soft_step::solve(
                &mut self.solver_bodies,
                // Every moving body in this tier (a pyramid, a pile): the plain loop.
                if self.tier_bodies.len() == dynamic {
                    Moving::All
                } else {
                    Moving::Only(&self.tier_bodies)
                },
                &mut self.contacts,
                &mut self.constraints,
                selected,
                &mut self.wide,
                Work {
                    settings: &settings,
                    creep: CREEP[tier as usize],
                    normal_relax: self.settings.relax_iterations
                        * NORMAL_RELAX_SCALE[tier as usize],
                },
                dt,
                limits,
            );
        }
    }

    /// Copy what the solver needs into the compact solver array (awake dynamic bodies only;
    /// everything else is fixed).
    pub(super) fn load_solver_bodies(&mut self) {
        let g = self.gravity;
        self.solver_bodies.clear();
        self.solver_bodies
            .extend(self.slots.iter().map(|slot| match &slot.body {
                Some(b) if b.is_active() => SolverBody {
                    v: b.linear_velocity,
                    w: b.angular_velocity,
                    inv_mass: b.inv_mass,
                    inv_inertia: b.inv_inertia,
                    accel: g + b.inv_mass * b.force,
                    alpha: b.inv_inertia * b.torque,
                    dp: Vec2::ZERO,
                    dtheta: 0.0,
                    dq: Rot::IDENTITY,
                },
                // Infinite mass that moves: contacts see its velocity, nothing changes it.
                Some(b) if b.kinematic => SolverBody {
                    v: b.linear_velocity,
                    w: b.angular_velocity,
                    ..SolverBody::FIXED
                },
                _ => SolverBody::FIXED,
            }));
        // One more fixed body, last, for the empty lanes of the wide solver's bundles.
        self.solver_bodies.push(SolverBody::FIXED);
    }

    /// Write velocities and the step's motion back to the bodies; clear forces.
    pub(super) fn store_solver_bodies(&mut self) {
        for (slot, sb) in self.slots.iter_mut().zip(&self.solver_bodies) {
            let Some(b) = slot.body.as_mut() else {
                continue;
            };
            b.force = Vec2::ZERO;
            b.torque = 0.0;
            if !b.is_active() {
                continue;
            }
            b.linear_velocity = sb.v;
            b.angular_velocity = sb.w;
            b.position += sb.dp;
            b.angle += sb.dtheta;
            b.rot = Rot::from_angle(b.angle);
        }
    }

    /// Kinematic bodies move by their own velocity over the step (they are fixed bodies to the
    /// solver, which only reads their velocity).
    fn move_kinematic(&mut self, dt: Real) {
        for b in self.slots.iter_mut().filter_map(|s| s.body.as_mut()) {
            if b.is_moving_kinematic() {
                b.position += dt * b.linear_velocity;
                b.angle += dt * b.angular_velocity;
                b.rot = Rot::from_angle(b.angle);
            }
        }
    }
}
