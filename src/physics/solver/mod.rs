//! Contact solvers and the integration they share.
//!
//! Both solvers work on [`SolverBody`]: a compact copy of what the inner loops touch
//! (velocities, inverse masses, and how far each body has moved during the step).

pub(crate) mod sequential;
pub(crate) mod soft_step;

use super::math::{Real, Rot, Vec2};

/// The per-body data the solver's inner loop reads and writes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SolverBody {
    /// Linear velocity (m/s).
    pub v: Vec2,
    /// Angular velocity (rad/s).
    pub w: Real,
    /// 1 / mass (1/kg); zero for static bodies and empty slots.
    pub inv_mass: Real,
    /// 1 / inertia (1/(kg m^2)).
    pub inv_inertia: Real,
    /// Acceleration from gravity and applied forces (m/s^2).
    pub accel: Vec2,
    /// Angular acceleration from applied torque (rad/s^2).
    pub alpha: Real,
    /// Displacement since the start of the step (m).
    pub dp: Vec2,
    /// Rotation since the start of the step (rad).
    pub dtheta: Real,
    /// Rotation since the start of the step, as cos/sin.
    pub dq: Rot,
}

impl SolverBody {
    /// A body that nothing can move (static bodies and empty slots).
    pub const FIXED: SolverBody = SolverBody {
        v: Vec2::ZERO,
        w: 0.0,
        inv_mass: 0.0,
        inv_inertia: 0.0,
        accel: Vec2::ZERO,
        alpha: 0.0,
        dp: Vec2::ZERO,
        dtheta: 0.0,
        dq: Rot::IDENTITY,
    };
}

/// Limits applied while integrating.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    /// Speed cap (m/s).
    pub max_linear_speed: Real,
    /// Largest rotation per (sub)step (rad).
    pub max_rotation: Real,
}

/// Semi-implicit Euler, velocity half: v += h a, w += h alpha (appendix eqs. 1-2).
pub(crate) fn integrate_velocities(bodies: &mut [SolverBody], h: Real, limits: Limits) {
    let max_v = limits.max_linear_speed;
    for b in bodies.iter_mut() {
        if b.inv_mass == 0.0 {
            continue;
        }
        b.v += h * b.accel;
        b.w += h * b.alpha;
        b.v = clamp_speed(b.v, max_v);
    }
}

/// Semi-implicit Euler, position half: x += h v, theta += h w (appendix eqs. 65-68),
/// recording the motion as deltas from the start of the step.
pub(crate) fn integrate_positions(bodies: &mut [SolverBody], h: Real, limits: Limits) {
    let max_w = limits.max_rotation / h;
    for b in bodies.iter_mut() {
        if b.inv_mass == 0.0 {
            continue;
        }
        b.v = clamp_speed(b.v, limits.max_linear_speed);
        if !(b.w.abs() <= max_w) {
            b.w = if b.w.is_nan() {
                0.0
            } else {
                max_w.copysign(b.w)
            };
        }
        b.dp += h * b.v;
        b.dtheta += h * b.w;
        // First-order rotation update q += h w q_perp, then renormalise (cheap; exact angle is
        // kept in dtheta).
        let dq = b.dq;
        let (c, s) = (dq.c - h * b.w * dq.s, dq.s + h * b.w * dq.c);
        let len = (c * c + s * s).sqrt();
        b.dq = Rot {
            c: c / len,
            s: s / len,
        };
    }
}

/// `v` with its length capped at `max`; non-finite components are clamped first so the
/// result is always finite.
#[inline]
pub(crate) fn clamp_speed(v: Vec2, max: Real) -> Vec2 {
    let len2 = v.length_squared();
    if len2 <= max * max {
        return v;
    }
    let v = Vec2::new(clamp_finite(v.x, max), clamp_finite(v.y, max));
    let len = v.length();
    if len > max {
        v * (max / len)
    } else {
        v
    }
}

#[inline]
fn clamp_finite(x: Real, max: Real) -> Real {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(-max, max)
    }
}

/// Apply impulse `p` at anchors `ra` (on A, pushed by -p) and `rb` (on B, pushed by +p).
#[inline]
pub(crate) fn apply_impulse(a: &mut SolverBody, b: &mut SolverBody, ra: Vec2, rb: Vec2, p: Vec2) {
    use super::math::cross;
    a.v -= a.inv_mass * p;
    a.w -= a.inv_inertia * cross(ra, p);
    b.v += b.inv_mass * p;
    b.w += b.inv_inertia * cross(rb, p);
}

/// Mutable references to two distinct bodies of the solver array.
#[inline]
pub(crate) fn pair_mut(
    bodies: &mut [SolverBody],
    a: u32,
    b: u32,
) -> (&mut SolverBody, &mut SolverBody) {
    let (a, b) = (a as usize, b as usize);
    debug_assert!(a < b, "contacts store the lower slot first");
    let (lo, hi) = bodies.split_at_mut(b);
    (&mut lo[a], &mut hi[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamp_speed_caps_length_and_removes_infinities() {
        let v = clamp_speed(Vec2::new(300.0, 400.0), 100.0);
        assert!((v.length() - 100.0).abs() < 1e-3);
        let v = clamp_speed(Vec2::new(Real::INFINITY, 0.0), 100.0);
        assert!(v.is_finite() && (v.x - 100.0).abs() < 1e-3);
        assert_eq!(clamp_speed(Vec2::new(1.0, 2.0), 100.0), Vec2::new(1.0, 2.0));
    }
}
