//! Recover: overlap deeper than the contact spring reaches, pushed out in position only.
//!
//! The soft bias pushes a point apart on at most its spring's reach ([`SPRING_REACH`] slops
//! of its overlap, or [`LOAD_REACH`] times the compression its load explains; see
//! `PushOut`); bodies placed inside one another, or driven in by a fast impact, overlap far
//! deeper. Pushing them apart through their velocities, as Box2D does, leaves the push behind
//! as speed wherever the relax pass does not converge: in a pyramid of boxes placed 25 %
//! overlapped the pushes of the rows add up, and its top box left at 11 m/s and rose 4.8 m.
//! So what lies deeper is removed as the sequential solver's split impulse removes all
//! overlap (Catto, Box2D v2.x): pseudo velocities, solved over the deep points only, move the
//! bodies at the end of the step and are then thrown away. Each point's pseudo velocity is
//! capped at the push-out speed, so the overlap beyond the reach shrinks by at most
//! `max_push_out_speed` times the step per contact, and nothing of it is kinetic energy.

use super::SolverBody;
use crate::physics::contact::Contact;
use crate::physics::math::{cross, cross_sv, Real, Vec2};

/// The deepest overlap the contact spring always acts on, in linear slops: 4, Box2D's
/// speculative distance. A contact whose last load explains a deeper compression reaches
/// further ([`LOAD_REACH`] times it), so a heavily loaded spring (the ground under a pyramid
/// of base 200) holds its load by itself instead of being held rigidly.
pub(crate) const SPRING_REACH: Real = 4.0;

/// How far past the compression its last load explains a spring acts on an overlap, as a
/// multiple of that compression (`soft_step::spring_reach`): twice, so that a load that
/// grows by half again is still held by the spring.
pub(crate) const LOAD_REACH: Real = 2.0;

/// Gauss-Seidel sweeps over the deep points, forward and back in turn. A push passes along a
/// chain of deep points (a column placed overlapped) in one sweep each way, so the rest buy
/// convergence in a pile, where none is bought cheaply: in Box2D's `spinner` (about 7,000 deep
/// points a solve) the pseudo velocities end 42 % short of their targets after 8 sweeps, 34 %
/// after 16 and 19 % after 64, and what a step leaves the next recovers. 8 sweeps instead of
/// 16 took 11-13 % off the spinner's step, and every stiff case passes with either
/// (docs/benchmarks.md).
const SWEEPS: usize = 8;

/// Sweeps over a solve of at least [`MANY_DEEP`] deep points: a pile crushed that deep
/// converges poorly whatever the count, and each sweep over it is a chain of dependent updates.
/// Over spinner's 500 steps its large solves end 46 % short of their targets after 4 sweeps,
/// 36 % after 8, and 4 take 13 % off its step. Small sets, where the sweeps pass a push along
/// a chain (the stiff suite's overlapped column and pyramid: 14 and about 100 points), keep 8:
/// at 4 the column's top box rose 8.6 cm above its rest, at 8 not at all.
const SWEEPS_MANY: usize = 4;

/// Deep points from which a solve takes [`SWEEPS_MANY`] sweeps.
const MANY_DEEP: usize = 1024;

/// A contact overlapping deeper than the spring's reach, as prepared for this step: one
/// point, where it is pushed.
#[derive(Clone, Copy, Debug)]
struct DeepPoint {
    /// Solver body indices of A and B.
    bodies: [u32; 2],
    /// Unit normal, A to B.
    normal: Vec2,
    /// Anchors from A's and B's centres (m).
    arms: [Vec2; 2],
    /// Effective mass along the normal (kg).
    mass: Real,
    /// A's and B's inverse masses (1/kg) and inverse inertias (1/(kg m^2)), kept beside the
    /// point so that each of the sweeps reads the bodies' pseudo velocities only.
    inv: [Real; 4],
    /// The pseudo normal velocity (m/s) that pushes the point out in one step to half its
    /// spring's reach (the overlap beyond the reach and half the reach besides, so the spring
    /// takes over well inside its range), capped at the push-out speed.
    target: Real,
    /// Accumulated pseudo impulse (N s), >= 0.
    impulse: Real,
}

/// The recover stage's points and pseudo velocities, kept in the World so that a steady step
/// does not allocate.
#[derive(Clone, Debug, Default)]
pub(crate) struct Recovery {
    /// This step's deep contacts, solve after solve (one per stiffness tier).
    points: Vec<DeepPoint>,
    /// Where the current solve's points start.
    solve_from: usize,
    /// Pseudo velocity (m/s, rad/s) per solver body; zero between steps.
    velocity: Vec<(Vec2, Real)>,
}

impl Recovery {
    /// Start a step: no deep contact yet.
    pub fn clear(&mut self) {
        self.points.clear();
        self.solve_from = 0;
    }

    /// Start a solve: the contacts noted from now on are its own.
    pub fn begin_solve(&mut self) {
        self.solve_from = self.points.len();
    }

    /// The solver bodies this step pushed out (A, B; static ones too). They are not at rest,
    /// whatever their velocity says: the push moves them without one.
    pub fn pushed_bodies(&self) -> impl Iterator<Item = u32> + '_ {
        self.points.iter().flat_map(|p| p.bodies)
    }

    /// Note contact `c` between bodies `a` and `b` if it overlaps deeper than `reach` (m);
    /// `inv_dt` is 1 / step (1/s), `speed` the push-out cap (m/s). A contact with both
    /// points that deep is pushed at their middle, by their mean depth: pushed point by point,
    /// the order of the two put a turn into every box of a column placed overlapped, and the
    /// column fell.
    #[cold]
    #[inline(never)]
    pub fn note(
        &mut self,
        c: &Contact,
        (a, b): (&SolverBody, &SolverBody),
        reach: Real,
        (inv_dt, speed): (Real, Real),
    ) {
        let (mut count, mut beyond) = (0.0, 0.0);
        let mut arms = [Vec2::ZERO; 2];
        for p in c.live() {
            let depth = -(p.separation + reach);
            if depth > 0.0 {
                count += 1.0;
                beyond += depth + 0.5 * reach;
                arms[0] += p.anchor_a;
                arms[1] += p.anchor_b;
            }
        }
        if count == 0.0 {
            return;
        }
        let (n, arms) = (c.normal, arms.map(|r| r / count));
        let (rn_a, rn_b) = (cross(arms[0], n), cross(arms[1], n));
        let k = a.inv_mass + b.inv_mass + a.inv_inertia * rn_a * rn_a + b.inv_inertia * rn_b * rn_b;
        if k <= 0.0 {
            return;
        }
        self.points.push(DeepPoint {
            bodies: [c.a, c.b],
            normal: n,
            arms,
            mass: 1.0 / k,
            inv: [a.inv_mass, a.inv_inertia, b.inv_mass, b.inv_inertia],
            target: (beyond / count * inv_dt).min(speed),
            impulse: 0.0,
        });
    }

    /// Solve the pseudo velocities over the deep points and move their bodies by them for
    /// `dt` seconds (s). (Kept out of line: inlined, it changed how the stages around it were
    /// compiled, and a pyramid with no deep point paid 0.9 % more instructions.)
    #[inline(never)]
    pub fn push_out(&mut self, bodies: &mut [SolverBody], dt: Real) {
        let points = &mut self.points[self.solve_from..];
        if points.is_empty() {
            return;
        }
        if self.velocity.len() < bodies.len() {
            self.velocity.resize(bodies.len(), (Vec2::ZERO, 0.0));
        }
        // Forward and back in turn: a chain of deep points (a column placed overlapped) takes
        // a sweep each way to pass a push along, where one way takes a sweep per link.
        let sweeps = if points.len() >= MANY_DEEP {
            SWEEPS_MANY
        } else {
            SWEEPS
        };
        for sweep in 0..sweeps {
            if sweep % 2 == 0 {
                for p in points.iter_mut() {
                    sweep_point(p, &mut self.velocity);
                }
            } else {
                for p in points.iter_mut().rev() {
                    sweep_point(p, &mut self.velocity);
                }
            }
        }
        // Each body moves once, and its pseudo velocity is zeroed for the next step.
        for p in points.iter() {
            for i in p.bodies {
                let (v, w) = std::mem::take(&mut self.velocity[i as usize]);
                let b = &mut bodies[i as usize];
                if b.inv_mass > 0.0 {
                    b.displace(dt * v, dt * w);
                }
            }
        }
    }
}

/// One Gauss-Seidel update of point `p`'s pseudo impulse toward its target, clamped >= 0.
#[inline]
fn sweep_point(p: &mut DeepPoint, velocity: &mut [(Vec2, Real)]) {
    let [ia, ib] = p.bodies.map(|i| i as usize);
    let ([ra, rb], n) = (p.arms, p.normal);
    let (va, wa) = velocity[ia];
    let (vb, wb) = velocity[ib];
    let vn = (vb + cross_sv(wb, rb) - va - cross_sv(wa, ra)).dot(n);
    let old = p.impulse;
    p.impulse = (old + p.mass * (p.target - vn)).max(0.0);
    let pn = (p.impulse - old) * n;
    let [ma, ia_inv, mb, ib_inv] = p.inv;
    velocity[ia].0 -= ma * pn;
    velocity[ia].1 -= ia_inv * cross(ra, pn);
    velocity[ib].0 += mb * pn;
    velocity[ib].1 += ib_inv * cross(rb, pn);
}
