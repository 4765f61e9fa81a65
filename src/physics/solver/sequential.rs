//! The appendix's solver (box2d-lite lineage): sequential impulses with a Baumgarte bias.
//!
//! Per step: compute each point's normal and tangent mass and its target normal velocity
//! (position bias or restitution), warm start from last step's impulses, then sweep all
//! points `iterations` times, each time solving the normal impulse (clamped so bodies only
//! push) and the friction impulse (clamped to the Coulomb cone).

use super::{apply_impulse, pair_mut, solve_block_lcp, BlockMass, SolverBody};
use crate::physics::contact::{Contact, ContactPoint};
use crate::physics::math::{cross, cross_sv, Real, Vec2};
use crate::physics::settings::Settings;

/// Effective mass 1 / (1/mA + 1/mB + (rA x d)^2 / IA + (rB x d)^2 / IB) along direction `d`
/// (appendix eqs. 56-57, with r.r - (r.d)^2 = (r x d)^2 for unit d).
#[inline]
pub(crate) fn effective_mass(a: &SolverBody, b: &SolverBody, ra: Vec2, rb: Vec2, d: Vec2) -> Real {
    let rna = cross(ra, d);
    let rnb = cross(rb, d);
    let k = a.inv_mass + b.inv_mass + a.inv_inertia * rna * rna + b.inv_inertia * rnb * rnb;
    if k > 0.0 {
        1.0 / k
    } else {
        0.0
    }
}

/// Prepare, warm start and iterate. Velocities in `bodies` are updated in place.
pub(crate) fn solve(
    bodies: &mut [SolverBody],
    contacts: &mut [Contact],
    settings: &Settings,
    dt: Real,
) {
    prepare(bodies, contacts, settings, dt);
    for _ in 0..settings.iterations {
        iterate(bodies, contacts, settings);
    }
    for c in contacts.iter_mut() {
        for p in &mut c.points[..c.count] {
            p.total_normal_impulse = p.normal_impulse;
        }
    }
}

/// Effective masses and target velocities (bias), then the warm start.
fn prepare(bodies: &mut [SolverBody], contacts: &mut [Contact], settings: &Settings, dt: Real) {
    let inv_dt = 1.0 / dt;
    for c in contacts.iter_mut() {
        let n = c.normal;
        let t = c.tangent();
        let (a, b) = pair_mut(bodies, c.a, c.b);
        for p in &mut c.points[..c.count] {
            let (ra, rb) = (p.anchor_a, p.anchor_b);
            p.normal_mass = effective_mass(a, b, ra, rb, n);
            p.tangent_mass = effective_mass(a, b, ra, rb, t);
            let dv = b.v + cross_sv(b.w, rb) - a.v - cross_sv(a.w, ra);
            let vn = dv.dot(n);
            p.relative_velocity = vn;
            let mut bias = if p.separation > 0.0 {
                // Speculative point: the bodies may close the gap this step, no more.
                -p.separation * inv_dt
            } else {
                // Position correction (appendix eq. 70): bias = beta / dt * max(0, -separation - slop).
                -settings.bias_factor * inv_dt * (p.separation + settings.linear_slop).min(0.0)
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
            p.bias = bias;
            if settings.warm_starting {
                apply_impulse(a, b, ra, rb, p.normal_impulse * n + p.tangent_impulse * t);
            } else {
                p.normal_impulse = 0.0;
                p.tangent_impulse = 0.0;
            }
        }
        c.block = if c.count == 2 {
            let ra = [c.points[0].anchor_a, c.points[1].anchor_a];
            let rb = [c.points[0].anchor_b, c.points[1].anchor_b];
            BlockMass::new(a, b, ra, rb, n)
        } else {
            None
        };
    }
}

/// One sweep over every contact point: normal impulse, then friction.
fn iterate(bodies: &mut [SolverBody], contacts: &mut [Contact], settings: &Settings) {
    for c in contacts.iter_mut() {
        let n = c.normal;
        let t = c.tangent();
        let (a, b) = pair_mut(bodies, c.a, c.b);
        let solved = match &c.block {
            Some(block) if settings.accumulate_impulses && c.count == 2 => {
                block_normal(a, b, &mut c.points, n, block)
            }
            _ => false,
        };
        if !solved {
            for p in &mut c.points[..c.count] {
                let (ra, rb) = (p.anchor_a, p.anchor_b);
                // Normal impulse: drive the normal velocity to the bias, only ever pushing.
                let dv = b.v + cross_sv(b.w, rb) - a.v - cross_sv(a.w, ra);
                let vn = dv.dot(n);
                let mut dpn = p.normal_mass * (-vn + p.bias);
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
        for p in &mut c.points[..c.count] {
            let (ra, rb) = (p.anchor_a, p.anchor_b);

            // Friction impulse: stop sliding, within |Pt| <= mu Pn (appendix eq. 60).
            let dv = b.v + cross_sv(b.w, rb) - a.v - cross_sv(a.w, ra);
            let vt = dv.dot(t);
            let mut dpt = -p.tangent_mass * vt;
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
/// (see `solve_block_lcp`). Returns false, having applied nothing, when ill-conditioned.
fn block_normal(
    a: &mut SolverBody,
    b: &mut SolverBody,
    points: &mut [ContactPoint; 2],
    n: Vec2,
    block: &BlockMass,
) -> bool {
    let ra = [points[0].anchor_a, points[1].anchor_a];
    let rb = [points[0].anchor_b, points[1].anchor_b];
    let lambda = [points[0].normal_impulse, points[1].normal_impulse];
    let k_lambda = block.mul(lambda);
    let mut rhs = [0.0; 2];
    for i in 0..2 {
        let vn = (b.v + cross_sv(b.w, rb[i]) - a.v - cross_sv(a.w, ra[i])).dot(n);
        rhs[i] = vn - k_lambda[i] - points[i].bias;
    }
    let Some(x) = solve_block_lcp(block, rhs) else {
        return false;
    };
    for i in 0..2 {
        let applied = x[i] - lambda[i];
        points[i].normal_impulse = x[i];
        apply_impulse(a, b, ra[i], rb[i], applied * n);
    }
    true
}
