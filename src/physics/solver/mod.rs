//! Contact solvers and the integration they share.
//!
//! Both solvers work on [`SolverBody`]: a compact copy of what the inner loops touch
//! (velocities, inverse masses, and how far each body has moved during the step).

pub(crate) mod constraint;
pub(crate) mod lanes;
pub(crate) mod sequential;
pub(crate) mod soft_step;
pub(crate) mod wide;

use super::contact::Contact;
use super::math::{Real, Rot, Vec2};

/// What a soft-step solve pass solves: the biased pass (normal and friction, with the soft
/// bias), a relax pass (both, without), or a normal relax pass (the normal constraints only,
/// without; friction keeps what the relax passes left it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PassKind {
    Biased,
    Relax,
    NormalRelax,
}

impl PassKind {
    /// Pass number `pass` of a substep: the biased pass, then `relax` relax passes, then the
    /// normal relax passes.
    pub fn nth(pass: u32, relax: u32) -> PassKind {
        if pass == 0 {
            PassKind::Biased
        } else if pass <= relax {
            PassKind::Relax
        } else {
            PassKind::NormalRelax
        }
    }

    /// Whether the pass applies the soft bias.
    pub fn biased(self) -> bool {
        self == PassKind::Biased
    }

    /// Whether the pass solves friction.
    pub fn solves_friction(self) -> bool {
        self != PassKind::NormalRelax
    }
}

/// The per-body data the solver's inner loop reads and writes.
///
/// Laid out as written: the first eight words (velocity, spin, motion this step, inverse
/// mass) are what the wide solver's kernels load for a body, together ([`SolverBody::state`]).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(crate) struct SolverBody {
    /// Linear velocity (m/s).
    pub v: Vec2,
    /// Angular velocity (rad/s).
    pub w: Real,
    /// Displacement since the start of the step (m).
    pub dp: Vec2,
    /// Rotation since the start of the step, as cos/sin.
    pub dq: Rot,
    /// 1 / mass (1/kg); zero for static bodies and empty slots.
    pub inv_mass: Real,
    /// 1 / inertia (1/(kg m^2)).
    pub inv_inertia: Real,
    /// Acceleration from gravity and applied forces (m/s^2).
    pub accel: Vec2,
    /// Angular acceleration from applied torque (rad/s^2).
    pub alpha: Real,
    /// Rotation since the start of the step (rad).
    pub dtheta: Real,
}

// `SolverBody::state` reads the first eight words as one array: they must be where it says.
const _: () = {
    use std::mem::{offset_of, size_of};
    let word = size_of::<Real>();
    assert!(size_of::<Vec2>() == 2 * word && size_of::<Rot>() == 2 * word);
    assert!(offset_of!(SolverBody, v) == 0);
    assert!(offset_of!(SolverBody, w) == 2 * word);
    assert!(offset_of!(SolverBody, dp) == 3 * word);
    assert!(offset_of!(SolverBody, dq) == 5 * word);
    assert!(offset_of!(SolverBody, inv_mass) == 7 * word);
};

impl AsMut<[Real; 8]> for SolverBody {
    /// [`SolverBody::state`], to write (the wide solver stores velocities through it).
    #[inline(always)]
    fn as_mut(&mut self) -> &mut [Real; 8] {
        // SAFETY: as in `state`, through an exclusive reference.
        unsafe { &mut *(self as *mut SolverBody).cast::<[Real; 8]>() }
    }
}

impl SolverBody {
    /// v.x, v.y, w, dp.x, dp.y, dq.c, dq.s, inv_mass as one array (m/s, rad/s, m, -, 1/kg).
    #[inline(always)]
    pub fn state(&self) -> &[Real; 8] {
        // SAFETY: `SolverBody` is `repr(C)` and its first eight words are `Real`s in this
        // order with no padding (`Vec2` and `Rot` are two `Real`s each; asserted above), so
        // they are an initialised `[Real; 8]` at the start of the struct, aligned for `Real`.
        unsafe { &*(self as *const SolverBody).cast::<[Real; 8]>() }
    }

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

/// Which solver bodies a solve moves: all of them, or only those listed (the islands of one
/// stiffness tier, see `Settings::adaptive_stiffness`).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Moving<'a> {
    /// Every body of the solver array.
    All,
    /// Only these indices.
    Only(&'a [u32]),
}

impl Moving<'_> {
    /// Run `f` on every moving, dynamic body.
    #[inline]
    fn for_each(self, bodies: &mut [SolverBody], mut f: impl FnMut(&mut SolverBody)) {
        match self {
            Moving::All => bodies.iter_mut().filter(|b| b.inv_mass != 0.0).for_each(f),
            Moving::Only(list) => {
                for &i in list {
                    let b = &mut bodies[i as usize];
                    if b.inv_mass != 0.0 {
                        f(b);
                    }
                }
            }
        }
    }
}

/// Which contacts a solve works on: all of them, or only those listed, ascending (the
/// contacts of one stiffness tier). Listing them leaves the contacts where they are: grouping
/// the contacts (350 bytes each then) by tier and merging them back cost 5 % of mixed_shapes'
/// step.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Selected<'a> {
    /// Every contact of the slice.
    All,
    /// Only these indices, ascending.
    Only(&'a [u32]),
}

impl Selected<'_> {
    /// How many contacts, of a slice of `all`.
    #[inline]
    pub fn count(self, all: usize) -> usize {
        match self {
            Selected::All => all,
            Selected::Only(list) => list.len(),
        }
    }

    /// Run `f` on every selected contact's index, in order. (One loop, so `f` has one call
    /// site and is inlined: with a loop per case it was not, and single-tier scenes paid 2 %.)
    #[inline]
    pub fn for_each_index(self, all: usize, mut f: impl FnMut(usize)) {
        let (n, list) = match self {
            Selected::All => (all, None),
            Selected::Only(list) => (list.len(), Some(list)),
        };
        for k in 0..n {
            f(list.map_or(k, |list| list[k] as usize));
        }
    }
}

/// Semi-implicit Euler, velocity half: v += h a, w += h alpha (appendix eqs. 1-2).
pub(crate) fn integrate_velocities(
    bodies: &mut [SolverBody],
    moving: Moving,
    h: Real,
    limits: Limits,
) {
    let max_v = limits.max_linear_speed;
    moving.for_each(bodies, |b| {
        b.v += h * b.accel;
        b.w += h * b.alpha;
        b.v = clamp_speed(b.v, max_v);
    });
}

/// Semi-implicit Euler, position half: x += h v, theta += h w (appendix eqs. 65-68),
/// recording the motion as deltas from the start of the step.
pub(crate) fn integrate_positions(
    bodies: &mut [SolverBody],
    moving: Moving,
    h: Real,
    limits: Limits,
) {
    let max_w = limits.max_rotation / h;
    moving.for_each(bodies, |b| {
        b.v = clamp_speed(b.v, limits.max_linear_speed);
        if b.w.is_nan() {
            b.w = 0.0;
        } else if b.w.abs() > max_w {
            b.w = max_w.copysign(b.w);
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
    });
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

/// Relative velocity of B over A at a point along a direction d, from the point's arms
/// rd_a = rA x d and rd_b = rB x d: (vB - vA) . d + wB rd_b - wA rd_a.
#[inline]
pub(crate) fn relative_velocity(
    a: &SolverBody,
    b: &SolverBody,
    d: Vec2,
    rd_a: Real,
    rd_b: Real,
) -> Real {
    (b.v - a.v).dot(d) + b.w * rd_b - a.w * rd_a
}

/// Apply impulse lambda along d at a point with arms rd_a, rd_b: B gets +lambda d, A -lambda d.
#[inline]
pub(crate) fn apply_along(
    a: &mut SolverBody,
    b: &mut SolverBody,
    d: Vec2,
    rd_a: Real,
    rd_b: Real,
    lambda: Real,
) {
    let p = lambda * d;
    // Static bodies are skipped rather than written with zero: a store to the ground for
    // every ground contact would chain those contacts' solves through memory.
    if a.inv_mass > 0.0 {
        a.v -= a.inv_mass * p;
        a.w -= a.inv_inertia * lambda * rd_a;
    }
    if b.inv_mass > 0.0 {
        b.v += b.inv_mass * p;
        b.w += b.inv_inertia * lambda * rd_b;
    }
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

/// The 2x2 effective-mass matrix of a two-point manifold along the normal and its inverse:
/// K_ij = 1/mA + 1/mB + (rA_i x n)(rA_j x n)/IA + (rB_i x n)(rB_j x n)/IB.
/// Constant through a step (the anchors are), so it is built once in the prepare stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BlockMass {
    pub k: [[Real; 2]; 2],
    pub inv: [[Real; 2]; 2],
}

impl BlockMass {
    /// The block of a two-point contact `c` (None for one point, or when ill-conditioned).
    #[inline]
    pub fn of_contact(a: &SolverBody, b: &SolverBody, c: &Contact) -> Option<BlockMass> {
        if c.count != 2 {
            return None;
        }
        let ra = [c.points[0].anchor_a, c.points[1].anchor_a];
        let rb = [c.points[0].anchor_b, c.points[1].anchor_b];
        BlockMass::new(a, b, ra, rb, c.normal)
    }

    /// The block for anchors `ra`, `rb` along `n`, or None when it is too ill-conditioned to
    /// invert safely (nearly coincident points): k11^2 < 1000 det, Box2D's bound.
    #[inline]
    pub fn new(
        a: &SolverBody,
        b: &SolverBody,
        ra: [Vec2; 2],
        rb: [Vec2; 2],
        n: Vec2,
    ) -> Option<BlockMass> {
        use super::math::cross;
        let rna = [cross(ra[0], n), cross(ra[1], n)];
        let rnb = [cross(rb[0], n), cross(rb[1], n)];
        let m = a.inv_mass + b.inv_mass;
        let kij = |i: usize, j: usize| {
            m + a.inv_inertia * rna[i] * rna[j] + b.inv_inertia * rnb[i] * rnb[j]
        };
        let k = [[kij(0, 0), kij(0, 1)], [kij(1, 0), kij(1, 1)]];
        let det = k[0][0] * k[1][1] - k[0][1] * k[1][0];
        let well_conditioned = k[0][0] * k[0][0] < 1000.0 * det;
        if !well_conditioned {
            return None;
        }
        let inv_det = 1.0 / det;
        let inv = [
            [inv_det * k[1][1], -inv_det * k[0][1]],
            [-inv_det * k[1][0], inv_det * k[0][0]],
        ];
        Some(BlockMass { k, inv })
    }

    /// K lambda.
    #[inline]
    pub fn mul(&self, l: [Real; 2]) -> [Real; 2] {
        [
            self.k[0][0] * l[0] + self.k[0][1] * l[1],
            self.k[1][0] * l[0] + self.k[1][1] * l[1],
        ]
    }
}

impl BlockMass {
    /// The new accumulated normal impulses of a two-point contact (see [`solve_block_lcp`]).
    ///
    /// `vn` are the points' normal velocities (m/s) and `lambda` their accumulated impulses
    /// (N s). Row i aims at the normal velocity `aim(i, free_i)`, where
    /// free_i = vn_i - (K lambda)_i is its velocity with the accumulated impulse taken out.
    #[inline]
    pub fn solve(
        &self,
        lambda: [Real; 2],
        vn: [Real; 2],
        aim: impl Fn(usize, Real) -> Real,
    ) -> Option<[Real; 2]> {
        let k_lambda = self.mul(lambda);
        let rhs = [0, 1].map(|i| {
            let free = vn[i] - k_lambda[i];
            free - aim(i, free)
        });
        solve_block_lcp(self, rhs)
    }
}

/// Solve the two-point contact LCP exactly: find x >= 0 with w = K x + b >= 0 and x.w = 0,
/// where x is the new accumulated normal impulse and w the excess normal velocity over the
/// target. Enumerates the four cases (both active, only 1, only 2, none), as Box2D v2's
/// block solver does. Solving both points together removes the left/right bias of solving
/// them one after the other, which otherwise puts a spurious spin into every resting box.
/// Returns None in the (round-off only) case that no case fits.
#[inline]
pub(crate) fn solve_block_lcp(m: &BlockMass, b: [Real; 2]) -> Option<[Real; 2]> {
    let (k, inv) = (&m.k, &m.inv);
    // Case 1: both points push. x = -K^-1 b.
    let x0 = -(inv[0][0] * b[0] + inv[0][1] * b[1]);
    let x1 = -(inv[1][0] * b[0] + inv[1][1] * b[1]);
    if x0 >= 0.0 && x1 >= 0.0 {
        return Some([x0, x1]);
    }
    // Case 2: only point 0 pushes; point 1 separates (w1 >= 0). Times the reciprocal, not
    // divided: the point's normal mass, as the wide solver has it.
    let x0 = -b[0] * (1.0 / k[0][0]);
    if x0 >= 0.0 && k[1][0] * x0 + b[1] >= 0.0 {
        return Some([x0, 0.0]);
    }
    // Case 3: only point 1 pushes.
    let x1 = -b[1] * (1.0 / k[1][1]);
    if x1 >= 0.0 && k[0][1] * x1 + b[0] >= 0.0 {
        return Some([0.0, x1]);
    }
    // Case 4: neither pushes.
    if b[0] >= 0.0 && b[1] >= 0.0 {
        return Some([0.0, 0.0]);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn state_is_the_first_eight_words_in_order() {
        let body = SolverBody {
            v: Vec2::new(1.0, 2.0),
            w: 3.0,
            dp: Vec2::new(4.0, 5.0),
            dq: Rot { c: 6.0, s: 7.0 },
            inv_mass: 8.0,
            inv_inertia: 9.0,
            accel: Vec2::new(10.0, 11.0),
            alpha: 12.0,
            dtheta: 13.0,
        };
        assert_eq!(body.state(), &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]);
    }

    #[test]
    fn clamp_speed_caps_length_and_removes_infinities() {
        let v = clamp_speed(Vec2::new(300.0, 400.0), 100.0);
        assert!((v.length() - 100.0).abs() < 1e-3);
        let v = clamp_speed(Vec2::new(Real::INFINITY, 0.0), 100.0);
        assert!(v.is_finite() && (v.x - 100.0).abs() < 1e-3);
        assert_eq!(clamp_speed(Vec2::new(1.0, 2.0), 100.0), Vec2::new(1.0, 2.0));
    }
}
