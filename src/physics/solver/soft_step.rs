//! The soft-step solver, after Erin Catto's Box2D v3 "Solver2D" write-ups.
//!
//! Per step: prepare contacts once; then for each of `substeps` substeps of length h:
//! integrate velocities, warm start, solve contacts as soft constraints (with bias),
//! integrate positions, relax (solve again without bias). After the substeps, one
//! restitution pass. Contacts are springs tuned in hertz and damping ratio rather than a
//! Baumgarte factor, so their stiffness does not depend on the step or iteration count; the
//! push-out speed is capped; and speculative points (separation > 0) only let the bodies
//! close the gap in one substep, which stops fast bodies at the surface.

use super::constraint::{Arms, ContactConstraint, PointConstraint, PointEnd};
use super::sequential::point_masses;
use super::wide::WideSolver;
use super::{
    apply_along, integrate_positions, integrate_velocities, pair_mut, relative_velocity, BlockMass,
    Limits, Moving, PassKind, Selected, SolverBody,
};
use crate::physics::contact::{Contact, ContactPoint};
use crate::physics::math::{Real, Vec2, PI};
use crate::physics::settings::Settings;

/// Soft constraint coefficients for a spring of `hertz` with damping ratio `zeta`, stepped at h.
///
/// With omega = 2 pi f: bias_rate = omega / (2 zeta + h omega), and the impulse is
/// -m_eff mass_scale (vn + bias_rate s) - impulse_scale P_accumulated, where
/// mass_scale = h omega (2 zeta + h omega) / (1 + h omega (2 zeta + h omega)) and
/// impulse_scale = 1 / (1 + h omega (2 zeta + h omega)) (Catto, "Solver2D", soft step).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Softness {
    pub bias_rate: Real,
    pub mass_scale: Real,
    pub impulse_scale: Real,
}

impl Softness {
    /// A rigid constraint: full correction, no compliance.
    pub const RIGID: Softness = Softness {
        bias_rate: 0.0,
        mass_scale: 1.0,
        impulse_scale: 0.0,
    };

    /// Coefficients for stiffness `hertz` (Hz), damping ratio `zeta`, substep `h` (s).
    pub fn new(hertz: Real, zeta: Real, h: Real) -> Softness {
        if hertz == 0.0 {
            return Softness {
                bias_rate: 0.0,
                mass_scale: 1.0,
                impulse_scale: 0.0,
            };
        }
        let omega = 2.0 * PI * hertz;
        let a1 = 2.0 * zeta + h * omega;
        let a2 = h * omega * a1;
        let a3 = 1.0 / (1.0 + a2);
        Softness {
            bias_rate: omega / a1,
            mass_scale: a2 * a3,
            impulse_scale: a3,
        }
    }
}

/// The work one solve does: the settings (the World's, or a tier's), how much the springs
/// creep (see [`creep`]; 0: none) and how many normal relax passes follow the relax passes.
pub(crate) struct Work<'a> {
    pub settings: &'a Settings,
    pub creep: Real,
    /// Relax passes, after the `settings.relax_iterations` full ones, that solve the normal
    /// constraints only: friction keeps what the full passes left it.
    pub normal_relax: u32,
}

/// Run one full step of `dt` seconds on the `selected` contacts and the `moving` bodies (the
/// bodies those contacts join must be among them). `constraints` has one slot per contact:
/// the contacts solved by the scalar code keep their constraint there.
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve(
    bodies: &mut [SolverBody],
    moving: Moving,
    contacts: &mut [Contact],
    constraints: &mut [ContactConstraint],
    selected: Selected,
    wide: &mut WideSolver,
    work: Work,
    dt: Real,
    limits: Limits,
) {
    let Work {
        settings,
        creep,
        normal_relax,
    } = work;
    let substeps = settings.substeps.max(1);
    let h = dt / substeps as Real;
    let inv_h = 1.0 / h;
    // A spring stiffer than a quarter of the substep rate is not resolved by the substep:
    // neither the base spring nor the doubled one against static bodies may pass it.
    let cap = 0.25 * inv_h;
    let hertz = settings.contact_hertz.min(cap);
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
        creep,
    };
    let push_out = settings.max_push_out_speed;

    // Between steps a contact keeps its impulses per step, not per substep, so that an island
    // whose substep count changes (adaptive stiffness) warm starts with the same force.
    // The scaling there and back is exact for substep counts that are powers of two (4, 16)
    // and within rounding for the middle tiers' 6 and 7.
    let per_substep = 1.0 / substeps as Real;
    let warm_starting = settings.warm_starting;
    // Each contact is prepared as it is coloured and its constraint written straight into
    // its bundle's lanes (see `wide`): one pass over the contacts. The few the colouring could
    // not place are solved here one by one, after the bundles.
    let mut bouncy = false;
    wide.build(bodies, contacts, constraints, selected, |c, a, b, k| {
        bouncy |= c.restitution != 0.0;
        prepare(a, b, c, k, warm_starting, per_substep, &stiffness);
    });

    for _ in 0..substeps {
        integrate_velocities(bodies, moving, h, limits);
        if settings.warm_starting {
            wide.warm_start(bodies);
            for &i in &wide.overflow {
                let i = i as usize;
                warm_start(bodies, &mut contacts[i], &constraints[i]);
            }
        } else {
            wide.clear_impulses();
            for &i in &wide.overflow {
                for p in &mut contacts[i as usize].points {
                    p.normal_impulse = 0.0;
                    p.tangent_impulse = 0.0;
                }
            }
        }
        for pass in 0..=settings.relax_iterations + normal_relax {
            // The biased pass, then (after the positions move) the relax passes, the normal
            // relax passes last.
            let kind = PassKind::nth(pass, settings.relax_iterations);
            wide.solve(bodies, inv_h, kind, push_out);
            for &i in &wide.overflow {
                let i = i as usize;
                let pass = Pass {
                    inv_h,
                    kind,
                    max_push_out: push_out,
                };
                solve_contact(bodies, &mut contacts[i], &mut constraints[i], pass);
            }
            if kind.biased() {
                integrate_positions(bodies, moving, h, limits);
            }
        }
    }
    let (substeps, inv_dt) = (substeps as Real, 1.0 / dt);
    // Each contact is finished as its impulses are stored (finishing one reads nothing of the
    // others and no velocity): one pass over the contacts. Those that bounce wait for the
    // restitution pass, which changes their impulses; they and the scalar code's contacts
    // finish from the impulses kept in the contact.
    wide.store(contacts, |c, _, ends| {
        if c.restitution == 0.0 {
            finish(c, ends, substeps, inv_dt);
        } else {
            for (p, end) in c.points[..c.count].iter_mut().zip(ends) {
                p.normal_impulse = end.normal_impulse;
                p.tangent_impulse = end.tangent_impulse;
                p.total_normal_impulse = end.total_normal_impulse;
            }
        }
    });
    // The point ends of a contact the scalar code solved, or that bounced.
    let kept = |c: &Contact| {
        c.points.map(|p| PointEnd {
            normal_impulse: p.normal_impulse,
            tangent_impulse: p.tangent_impulse,
            total_normal_impulse: p.total_normal_impulse,
        })
    };
    if bouncy {
        restitution(
            bodies,
            contacts,
            constraints,
            selected,
            settings.restitution_threshold,
        );
        selected.for_each_index(contacts.len(), |i| {
            let c = &mut contacts[i];
            if c.restitution != 0.0 {
                let ends = kept(c);
                finish(c, &ends, substeps, inv_dt);
            }
        });
    }
    for &i in &wide.overflow {
        let c = &mut contacts[i as usize];
        if c.restitution == 0.0 {
            let ends = kept(c);
            finish(c, &ends, substeps, inv_dt);
        }
    }
}

/// The end of a step for contact `c`, from its points' `ends`: their impulses back from per
/// substep to per step, and the contact's load (`substeps` as a number, `inv_dt` in 1/s).
/// The friction impulse is clamped to the Coulomb cone of the normal impulse it ends with: a
/// normal relax pass, after the last friction solve, can lower the normal impulse under it.
#[inline]
fn finish(c: &mut Contact, ends: &[PointEnd; 2], substeps: Real, inv_dt: Real) {
    let mut force = 0.0;
    for (p, end) in c.points[..c.count].iter_mut().zip(ends) {
        let max_f = c.friction * end.normal_impulse;
        p.normal_impulse = end.normal_impulse * substeps;
        p.tangent_impulse = end.tangent_impulse.clamp(-max_f, max_f) * substeps;
        p.total_normal_impulse = end.total_normal_impulse;
        force += end.total_normal_impulse;
    }
    // The force the contact carried, held so that a load that comes and goes does not
    // switch an island's work on and off every step (`Settings::adaptive_stiffness`), and
    // counted only when it lasted two steps running: the impact of a falling body is a
    // one-step spike, not a load to stiffen for.
    let force = force * inv_dt;
    c.load = force.min(c.force).max(HERTZ_DECAY * c.load);
    c.force = force;
}

/// How stiff contacts are made this step.
struct Stiffness {
    /// Base stiffness (Hz).
    hertz: Real,
    /// Stiffness against a static body (Hz): twice the base (Box2D), within the same cap of
    /// a quarter of the substep rate. Uncapped, at the default 60 Hz and 4 substeps it was
    /// 120 Hz, half the substep rate, and a plank leaning from a box against a wall rocked at
    /// 4 Hz forever in 2 of 200 simulated tilt histories of the Falling Bricks box (0 of 200
    /// capped).
    static_hertz: Real,
    /// The springs of `hertz` and `static_hertz`, worked out once per solve instead of once
    /// per contact.
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
    /// falls by at most [`HERTZ_DECAY`] per step: under a steady or bouncing load the spring
    /// stays put. That hold is not enough for a big pile (1,668 of 2,000 piled boxes still
    /// moving after 10 s, against 1,861 without it), which is why stiffening is off by default
    /// (`Settings::load_aware_stiffness`). `points` are the contact's constraints this step.
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
        for (p, k) in c.points[..c.count].iter().zip(points) {
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

/// Work out contact `c`'s constraint `k` for this step (effective masses, adjusted
/// separations, approach speeds, spring, block) between bodies `a` and `b`; the impulses it
/// carries from the last step become per substep (`per_substep` = 1 / substeps).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn prepare(
    a: &SolverBody,
    b: &SolverBody,
    c: &mut Contact,
    k: &mut ContactConstraint,
    warm_starting: bool,
    per_substep: Real,
    stiffness: &Stiffness,
) {
    let n = c.normal;
    let t = c.tangent();
    for (p, kp) in c.points[..c.count].iter_mut().zip(&mut k.points) {
        p.normal_impulse *= per_substep;
        p.tangent_impulse *= per_substep;
        let arms = Arms::new(p.anchor_a, p.anchor_b, n, t);
        kp.arms = arms;
        point_masses(a, b, p, kp, n, t);
        kp.adjusted_separation = p.separation - (arms.rb_n - arms.ra_n);
        kp.relative_velocity = relative_velocity(a, b, n, arms.rn_a, arms.rn_b);
        p.total_normal_impulse = 0.0;
        if !warm_starting {
            p.normal_impulse = 0.0;
            p.tangent_impulse = 0.0;
        }
    }
    k.softness = stiffness.softness(c, &k.points);
    k.creep = if stiffness.creep > 0.0 {
        stiffness.creep * creep(c, k.softness, a.inv_mass + b.inv_mass)
    } else {
        0.0
    };
    k.block = BlockMass::of_contact(a, b, c);
}

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
/// a two-point contact, and a jittered 20-box stack on the base settings was thrown over.
/// The load is the contact's held load (`Contact::load`), so the one-step spike of an impact
/// makes nothing creep, and a contact younger than [`CREEP_FROM_AGE`] steps does not creep.
/// `sf` is the contact's spring this step; `inv_mass` is 1/mA + 1/mB (1/kg).
fn creep(c: &Contact, sf: Softness, inv_mass: Real) -> Real {
    if c.force <= 0.0 || inv_mass <= 0.0 || c.age < CREEP_FROM_AGE {
        return 0.0;
    }
    let steady = (c.load / c.force).min(1.0);
    let impulse: Real = c.points[..c.count].iter().map(|p| p.normal_impulse).sum();
    let stiffness = sf.mass_scale * sf.bias_rate;
    if stiffness > 0.0 {
        steady * sf.impulse_scale * impulse * inv_mass / stiffness
    } else {
        0.0
    }
}

/// Creep acts on contacts that have lasted this many steps. Contacts that creep while bodies
/// are still landing let them sink and reach further: in many_boxes' falling pile 16 % more
/// contacts were solved over the run, and the solve grew with them. From 4 steps the pile
/// solves as many as without creep, pyramid_30's top moves 0.98 cm (bound 2) and the
/// base-134 pyramid still stands (fastest body 0.23 m/s at the end, bound 0.5); from 8, 1.40
/// cm and 0.30 m/s. Gating on static friction instead (every point stuck) toppled the
/// base-134 pyramid. (Measured with friction anchors, since removed; without them, and with
/// the normal relax pass, pyramid_30's top moves 0.74 cm and the base-134 pyramid's fastest
/// body ends at 0.042 m/s.)
const CREEP_FROM_AGE: u8 = 4;

/// Apply one contact's accumulated impulses at the start of a substep (`k`: its constraint).
fn warm_start(bodies: &mut [SolverBody], c: &mut Contact, k: &ContactConstraint) {
    let (n, t) = (c.normal, c.tangent());
    let (a, b) = pair_mut(bodies, c.a, c.b);
    for (p, k) in c.points[..c.count].iter_mut().zip(&k.points) {
        p.total_normal_impulse += p.normal_impulse;
        apply_along(a, b, n, k.arms.rn_a, k.arms.rn_b, p.normal_impulse);
        apply_along(a, b, t, k.arms.rt_a, k.arms.rt_b, p.tangent_impulse);
    }
}

/// What one solve pass does to a contact: 1 / substep (1/s), which kind of pass, and the
/// push-out cap (m/s).
#[derive(Clone, Copy, Debug)]
struct Pass {
    inv_h: Real,
    kind: PassKind,
    max_push_out: Real,
}

/// Solve one contact (`k`: its constraint) in `pass`.
fn solve_contact(
    bodies: &mut [SolverBody],
    c: &mut Contact,
    k: &mut ContactConstraint,
    pass: Pass,
) {
    let Pass {
        inv_h,
        kind,
        max_push_out,
    } = pass;
    let (use_bias, friction) = (kind.biased(), kind.solves_friction());
    {
        let n = c.normal;
        let t = c.tangent();
        let (sf, creep) = (k.softness, k.creep);
        let (a, b) = pair_mut(bodies, c.a, c.b);
        let dp_n = (b.dp - a.dp).dot(n);

        // Per point: (velocity bias, mass scale, impulse scale) of the soft constraint (Catto):
        // impulse = -m_eff (mass_scale vn + bias) - impulse_scale P, with
        // bias = mass_scale bias_rate s capped at the push-out speed.
        let mut coeffs = [(0.0, 1.0, 0.0); 2];
        for (p, coeff) in k.points[..c.count].iter().zip(coeffs.iter_mut()) {
            // Current separation from how far the bodies moved this step:
            // s = s0 + (dpB - dpA) . n + (qB rB - rB) . n - (qA rA - rA) . n, where for a
            // rotation q = (c, s): (q r) . n = c (r . n) + s (r x n).
            let arms = &p.arms;
            let rot_b = b.dq.c * arms.rb_n + b.dq.s * arms.rn_b;
            let rot_a = a.dq.c * arms.ra_n + a.dq.s * arms.rn_a;
            let s = dp_n + rot_b - rot_a + p.adjusted_separation;
            *coeff = if s > 0.0 {
                // Speculative: allow closing the gap in this substep, no more.
                (s * inv_h, 1.0, 0.0)
            } else if use_bias {
                (
                    (sf.mass_scale * sf.bias_rate * (s + creep)).max(-max_push_out),
                    sf.mass_scale,
                    sf.impulse_scale,
                )
            } else {
                (0.0, 1.0, 0.0)
            };
        }

        let solved = match &k.block {
            Some(block) if c.count == 2 => {
                block_normal(a, b, &mut c.points, &mut k.points, n, block, &coeffs)
            }
            _ => false,
        };
        if !solved {
            for ((p, kp), &(bias, mass_scale, impulse_scale)) in c.points[..c.count]
                .iter_mut()
                .zip(&mut k.points)
                .zip(coeffs.iter())
            {
                let vn = relative_velocity(a, b, n, kp.arms.rn_a, kp.arms.rn_b);
                let impulse =
                    -kp.normal_mass * (mass_scale * vn + bias) - impulse_scale * p.normal_impulse;
                accumulate_normal(a, b, n, p, kp, impulse);
            }
        }

        if !friction || c.friction == 0.0 {
            return;
        }
        for (p, kp) in c.points[..c.count].iter_mut().zip(&k.points) {
            let vt = relative_velocity(a, b, t, kp.arms.rt_a, kp.arms.rt_b);
            let max_f = c.friction * p.normal_impulse;
            let impulse = -kp.tangent_mass * vt;
            let total = (p.tangent_impulse + impulse).clamp(-max_f, max_f);
            let applied = total - p.tangent_impulse;
            p.tangent_impulse = total;
            apply_along(a, b, t, kp.arms.rt_a, kp.arms.rt_b, applied);
        }
    }
}

/// Add `impulse` (N s) to a point's accumulated normal impulse, clamped so that the total
/// stays >= 0 (a contact pushes, never pulls), and apply to A and B only what was added
/// (`k`: the point's constraint).
#[inline]
fn accumulate_normal(
    a: &mut SolverBody,
    b: &mut SolverBody,
    n: Vec2,
    p: &mut ContactPoint,
    k: &mut PointConstraint,
    impulse: Real,
) {
    let total = (p.normal_impulse + impulse).max(0.0);
    let applied = total - p.normal_impulse;
    p.normal_impulse = total;
    p.total_normal_impulse += applied;
    apply_along(a, b, n, k.arms.rn_a, k.arms.rn_b, applied);
}

/// Both normal impulses of a two-point contact at once (see `solve_block_lcp`).
///
/// Row i of the soft update asks for the new normal velocity
/// vn_i' = impulse_scale_i (vn_i - (K P)_i) - bias_i, which is what
/// impulse_i = -m_i (mass_scale_i vn_i + bias_i) - impulse_scale_i P_i gives for one point
/// (using mass_scale + impulse_scale = 1), while both accumulated impulses stay >= 0.
/// Returns false, having applied nothing, when no LCP case fits (round-off).
#[inline]
fn block_normal(
    a: &mut SolverBody,
    b: &mut SolverBody,
    points: &mut [ContactPoint; 2],
    k: &mut [PointConstraint; 2],
    n: Vec2,
    block: &BlockMass,
    coeffs: &[(Real, Real, Real); 2],
) -> bool {
    let lambda = [points[0].normal_impulse, points[1].normal_impulse];
    let vn = [0, 1].map(|i| relative_velocity(a, b, n, k[i].arms.rn_a, k[i].arms.rn_b));
    let aim = |i: usize, free: Real| {
        let (bias, _, impulse_scale) = coeffs[i];
        impulse_scale * free - bias
    };
    let Some(x) = block.solve(lambda, vn, aim) else {
        return false;
    };
    for (i, (p, k)) in points.iter_mut().zip(k.iter_mut()).enumerate() {
        let applied = x[i] - lambda[i];
        p.normal_impulse = x[i];
        p.total_normal_impulse += applied;
        apply_along(a, b, n, k.arms.rn_a, k.arms.rn_b, applied);
    }
    true
}

/// Reverse e times the pre-solve approach speed where it exceeded the threshold and the
/// point pushed this step (its total normal impulse is positive: a speculative point that
/// never touched does not bounce). Box2D asks instead for a positive largest increment;
/// the total is kept anyway, where the largest increment cost the solve passes a max and
/// two lanes per bundle. A contact with restitution keeps its constraint in `constraints`.
fn restitution(
    bodies: &mut [SolverBody],
    contacts: &mut [Contact],
    constraints: &mut [ContactConstraint],
    selected: Selected,
    threshold: Real,
) {
    selected.for_each_index(contacts.len(), |i| {
        let (c, k) = (&mut contacts[i], &mut constraints[i]);
        if c.restitution == 0.0 {
            return;
        }
        let n = c.normal;
        let e = c.restitution;
        let (a, b) = pair_mut(bodies, c.a, c.b);
        let bounces = |p: &ContactPoint, k: &PointConstraint| {
            k.relative_velocity < -threshold && p.total_normal_impulse > 0.0
        };
        let both = [0, 1].map(|j| bounces(&c.points[j], &k.points[j]));
        if c.count == 2 && both[0] && both[1] {
            // Both points bounce: aim each at vn' = -e vn0 together, so a flat face hitting a
            // flat face rebounds by exactly e instead of whatever order the points were solved in.
            let coeffs = [
                (e * k.points[0].relative_velocity, 1.0, 0.0),
                (e * k.points[1].relative_velocity, 1.0, 0.0),
            ];
            if let Some(block) = k.block {
                if block_normal(a, b, &mut c.points, &mut k.points, n, &block, &coeffs) {
                    return;
                }
            }
        }
        for (p, kp) in c.points[..c.count].iter_mut().zip(&mut k.points) {
            if !bounces(p, kp) {
                continue;
            }
            let vn = relative_velocity(a, b, n, kp.arms.rn_a, kp.arms.rn_b);
            let impulse = -kp.normal_mass * (vn + e * kp.relative_velocity);
            accumulate_normal(a, b, n, p, kp, impulse);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn softness_matches_the_spring_damper_closed_form() {
        // f = 30 Hz, zeta = 10, h = 1/240 s
        let h: Real = 1.0 / 240.0;
        let s = Softness::new(30.0, 10.0, h);
        let omega = 2.0 * PI * 30.0;
        let a1 = 2.0 * 10.0 + h * omega;
        assert!((s.bias_rate - omega / a1).abs() < 1e-4);
        let a2 = h * omega * a1;
        assert!((s.mass_scale - a2 / (1.0 + a2)).abs() < 1e-6);
        assert!((s.impulse_scale - 1.0 / (1.0 + a2)).abs() < 1e-6);
        // a rigid limit: infinitely stiff springs have mass_scale -> 1, impulse_scale -> 0
        let rigid = Softness::new(1e9, 1.0, h);
        assert!(rigid.mass_scale > 0.999 && rigid.impulse_scale < 1e-3);
    }
}
