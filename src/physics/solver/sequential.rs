//! The appendix's solver (box2d-lite lineage): sequential impulses with a Baumgarte bias.
//!
//! Per step: compute each point's normal and tangent mass and its target normal velocity
//! (position bias or restitution), warm start from last step's impulses, then sweep all
//! points `iterations` times, each time solving the normal impulse (clamped so bodies only
//! push) and the friction impulse (clamped to the Coulomb cone).

use super::block::BlockMass;
use super::constraint::ContactConstraint;
use super::{apply_impulse, pair_mut, SolverBody};
use crate::physics::contact::Contact;
use crate::physics::math::{cross, cross_sv, Real, Vec2};
use crate::physics::settings::Settings;

/// Prepare, warm start and iterate. Velocities in `bodies` are updated in place;
/// `constraints` (one per contact) receive this step's constraints. `joints` solves the
/// joints once after each sweep over the contacts (box2d-lite's order).
pub(crate) fn solve(
    bodies: &mut [SolverBody],
    contacts: &mut [Contact],
    constraints: &mut [ContactConstraint],
    settings: &Settings,
    dt: Real,
    mut joints: impl FnMut(&mut [SolverBody]),
) {
    prepare(bodies, contacts, constraints, settings, dt);
    for _ in 0..settings.iterations {
        iterate(bodies, contacts, constraints, settings);
        joints(bodies);
    }
    for c in contacts.iter_mut() {
        for p in c.live_mut() {
            p.total_normal_impulse = p.normal_impulse;
        }
    }
}

/// Split impulses: the position correction, solved on pseudo velocities that move the bodies
/// this step and are then thrown away (Catto's split impulse, Box2D v2.x). Kept in the World so
/// a steady step does not allocate.
///
/// With the Baumgarte bias in the real velocities (the appendix's eq. 70 as written), the push
/// that removes an overlap stays behind as kinetic energy: a 1000 kg box on a 1 kg box sank 1 m
/// into it and was then thrown 10 m up. Solved apart, the correction only moves positions, and
/// the velocity sweeps (inelastic contacts and friction) never add energy.
#[derive(Clone, Debug, Default)]
pub(crate) struct SplitImpulse {
    /// Pseudo velocity (m/s, rad/s) per solver body.
    velocity: Vec<(Vec2, Real)>,
    /// Accumulated pseudo impulse per contact point (N s), >= 0.
    impulse: Vec<[Real; 2]>,
}

impl SplitImpulse {
    /// Push overlapping bodies apart by `bias_factor` of the overlap beyond the slop, over
    /// `iterations` sweeps of the pseudo velocities, then move the bodies by them for `dt`.
    pub fn correct(
        &mut self,
        bodies: &mut [SolverBody],
        contacts: &[Contact],
        constraints: &[ContactConstraint],
        settings: &Settings,
        dt: Real,
    ) {
        let inv_dt = 1.0 / dt;
        self.velocity.clear();
        self.velocity.resize(bodies.len(), (Vec2::ZERO, 0.0));
        self.impulse.clear();
        self.impulse.resize(contacts.len(), [0.0; 2]);
        let mut any = false;
        for _ in 0..settings.iterations {
            for ((c, k), acc) in contacts
                .iter()
                .zip(constraints)
                .zip(self.impulse.iter_mut())
            {
                let n = c.normal;
                let (ia, ib) = (c.a as usize, c.b as usize);
                for ((p, k), acc) in c.live().iter().zip(&k.points).zip(acc.iter_mut()) {
                    // Position bias (appendix eq. 70), on the overlap beyond the slop only.
                    let target = -settings.bias_factor
                        * inv_dt
                        * (p.separation + settings.linear_slop).min(0.0);
                    if target <= 0.0 {
                        continue;
                    }
                    any = true;
                    let (ra, rb) = (p.anchor_a, p.anchor_b);
                    let (va, wa) = self.velocity[ia];
                    let (vb, wb) = self.velocity[ib];
                    let vn = (vb + cross_sv(wb, rb) - va - cross_sv(wa, ra)).dot(n);
                    let old = *acc;
                    *acc = (old + k.normal_mass * (target - vn)).max(0.0);
                    let pn = (*acc - old) * n;
                    let (a, b) = (&bodies[ia], &bodies[ib]);
                    self.velocity[ia].0 -= a.inv_mass * pn;
                    self.velocity[ia].1 -= a.inv_inertia * cross(ra, pn);
                    self.velocity[ib].0 += b.inv_mass * pn;
                    self.velocity[ib].1 += b.inv_inertia * cross(rb, pn);
                }
            }
            if !any {
                return;
            }
        }
        for (b, &(v, w)) in bodies.iter_mut().zip(&self.velocity) {
            if b.inv_mass == 0.0 {
                continue;
            }
            b.displace(dt * v, dt * w);
        }
    }
}

/// Effective masses and target velocities (bias), then the warm start.
fn prepare(
    bodies: &mut [SolverBody],
    contacts: &mut [Contact],
    constraints: &mut [ContactConstraint],
    settings: &Settings,
    dt: Real,
) {
    let inv_dt = 1.0 / dt;
    for (c, k) in contacts.iter_mut().zip(constraints.iter_mut()) {
        let n = c.normal;
        let t = c.tangent();
        let (a, b) = pair_mut(bodies, c.a, c.b);
        for (p, k) in c.points[..c.count as usize].iter_mut().zip(&mut k.points) {
            k.set_masses(a, b, p, n, t);
            let (ra, rb) = (p.anchor_a, p.anchor_b);
            let dv = b.v + cross_sv(b.w, rb) - a.v - cross_sv(a.w, ra);
            let vn = dv.dot(n);
            // Speculative point: the bodies may close the gap this step, no more. Overlaps are
            // pushed apart by the split impulse (`SplitImpulse`), not through the velocities.
            let mut bias = if p.separation > 0.0 {
                -p.separation * inv_dt
            } else {
                0.0
            };
            // Restitution: aim for -e times the approach speed. A speculative point that closes
            // its gap this step only stops the bodies at the surface and remembers how fast they
            // came; they bounce next step, when the surfaces meet. Bouncing at once would turn
            // them around up to a step's travel short of the surface.
            let approach = p.approach_velocity.min(vn);
            p.approach_velocity = 0.0;
            if c.restitution > 0.0 && approach < -settings.restitution_threshold {
                if p.separation > 0.25 * settings.linear_slop {
                    if p.separation + vn * dt < 0.0 {
                        p.approach_velocity = approach;
                    }
                } else {
                    bias = bias.max(-c.restitution * approach);
                }
            }
            k.bias = bias;
            if settings.warm_starting {
                apply_impulse(a, b, ra, rb, p.normal_impulse * n + p.tangent_impulse * t);
            } else {
                p.normal_impulse = 0.0;
                p.tangent_impulse = 0.0;
            }
        }
        k.block = BlockMass::of_contact(a, b, c);
    }
}

/// One sweep over every contact point: normal impulse, then friction.
fn iterate(
    bodies: &mut [SolverBody],
    contacts: &mut [Contact],
    constraints: &[ContactConstraint],
    settings: &Settings,
) {
    for (c, k) in contacts.iter_mut().zip(constraints) {
        let n = c.normal;
        let t = c.tangent();
        let (a, b) = pair_mut(bodies, c.a, c.b);
        let solved = settings.accumulate_impulses && c.count == 2 && block_normal(a, b, c, k);
        if !solved {
            for (p, k) in c.live_mut().iter_mut().zip(&k.points) {
                let (ra, rb) = (p.anchor_a, p.anchor_b);
                // Normal impulse: drive the normal velocity to the bias, only ever pushing.
                let dv = b.v + cross_sv(b.w, rb) - a.v - cross_sv(a.w, ra);
                let vn = dv.dot(n);
                let mut dpn = k.normal_mass * (-vn + k.bias);
                if settings.accumulate_impulses {
                    let old = p.normal_impulse;
                    p.normal_impulse = (old + dpn).max(0.0);
                    dpn = p.normal_impulse - old;
                } else {
                    dpn = dpn.max(0.0);
                    p.normal_impulse = dpn;
                }
                apply_impulse(a, b, ra, rb, dpn * n);
            }
        }
        for (p, k) in c.points[..c.count as usize].iter_mut().zip(&k.points) {
            let (ra, rb) = (p.anchor_a, p.anchor_b);

            // Friction impulse: stop sliding, within |Pt| <= mu Pn (appendix eq. 60).
            let dv = b.v + cross_sv(b.w, rb) - a.v - cross_sv(a.w, ra);
            let vt = dv.dot(t);
            let mut dpt = -k.tangent_mass * vt;
            let max_pt = c.friction * p.normal_impulse;
            if settings.accumulate_impulses {
                let old = p.tangent_impulse;
                p.tangent_impulse = (old + dpt).clamp(-max_pt, max_pt);
                dpt = p.tangent_impulse - old;
            } else {
                dpt = dpt.clamp(-max_pt, max_pt);
                p.tangent_impulse = dpt;
            }
            apply_impulse(a, b, ra, rb, dpt * t);
        }
    }
}

/// Both normal impulses of a two-point contact at once, each aiming at its bias velocity
/// (see `solve_block_lcp`). Returns false, having applied nothing, when the contact has no
/// well-conditioned block or no LCP case fits.
fn block_normal(
    a: &mut SolverBody,
    b: &mut SolverBody,
    c: &mut Contact,
    k: &ContactConstraint,
) -> bool {
    let (Some(block), n) = (k.block, c.normal) else {
        return false;
    };
    let points = &mut c.points;
    let ra = [points[0].anchor_a, points[1].anchor_a];
    let rb = [points[0].anchor_b, points[1].anchor_b];
    let lambda = [points[0].normal_impulse, points[1].normal_impulse];
    let vn = [0, 1].map(|i| (b.v + cross_sv(b.w, rb[i]) - a.v - cross_sv(a.w, ra[i])).dot(n));
    let Some(x) = block.solve(lambda, vn, |i, _| k.points[i].bias) else {
        return false;
    };
    for i in 0..2 {
        points[i].normal_impulse = x[i];
        apply_impulse(a, b, ra[i], rb[i], (x[i] - lambda[i]) * n);
    }
    true
}
