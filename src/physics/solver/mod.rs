//! Contact solvers and the integration they share.
//!
//! Both solvers work on [`SolverBody`]: a compact copy of what the inner loops touch
//! (velocities, inverse masses, and how far each body has moved during the step).
//!
//! - `sequential.rs`: the appendix's sequential impulses (box2d-lite), plain scalar code;
//! - `soft_step.rs`: Box2D v3's soft step, its stages in order, on `bundles.rs` (contacts
//!   packed by the colours of `graph.rs`) and the one contact kernel of `contact_solver.rs`,
//!   generic over the lane width (`lanes/`);
//! - `constraint.rs`, `block.rs`, `softness.rs`: what both prepare per contact.

pub(crate) mod block;
pub(crate) mod bundles;
pub(crate) mod constraint;
pub(crate) mod contact_solver;
pub(crate) mod gaps;
pub(crate) mod graph;
pub(crate) mod joint;
pub(crate) mod lanes;
pub(crate) mod recover;
pub(crate) mod sequential;
pub(crate) mod soft_step;
pub(crate) mod softness;

use std::marker::PhantomData;

use super::math::{Real, Rot, Vec2};
use super::team::{block, Region, SharedSlice};

/// How many bodies a worker integrates at a time in the parallel step.
pub(crate) const BODIES_PER_BLOCK: usize = 256;

/// What a soft-step solve pass solves: the biased pass (normal and friction, with the soft
/// bias), a relax pass (both, without), or a normal relax pass (the normal constraints only,
/// without; friction keeps what the relax passes left it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PassKind {
    Biased,
    Relax,
    NormalRelax,
}

/// The per-body data the solver's inner loop reads and writes.
///
/// Laid out as written: the first eight words (velocity, spin, motion this step, inverse
/// mass) are what the contact kernel loads for a body, together ([`SolverBody::state`]).
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
    /// [`SolverBody::state`], to write (the contact kernel stores velocities through it).
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

/// The solver bodies as rows the contact kernels read and write by index (each row's first
/// eight words, [`SolverBody::state`]). Within one thread it is the slice it was made from;
/// [`SharedRows`] hands the same rows to several workers at once, which the constraint graph
/// makes safe: the bundles of one colour share no dynamic body, and no kernel writes a fixed
/// body's row (`Bundle::fixed`).
#[derive(Clone, Copy)]
pub(crate) struct BodyRows<'a> {
    ptr: *mut SolverBody,
    len: usize,
    _rows: PhantomData<&'a mut [SolverBody]>,
}

impl<'a> BodyRows<'a> {
    /// The rows of `bodies`, for this thread.
    #[inline(always)]
    pub fn new(bodies: &'a mut [SolverBody]) -> BodyRows<'a> {
        BodyRows {
            ptr: bodies.as_mut_ptr(),
            len: bodies.len(),
            _rows: PhantomData,
        }
    }

    /// Row `i`'s eight words, to read. Panics past the end, as indexing does.
    #[inline(always)]
    pub fn state(&self, i: u32) -> &[Real; 8] {
        assert!((i as usize) < self.len, "body row {i} of {}", self.len);
        // SAFETY: in bounds; the row is not written while this thread reads it (within a
        // thread the kernels read a bundle's rows before they write them; across threads see
        // `SharedRows`).
        unsafe { (*self.ptr.add(i as usize)).state() }
    }

    /// Where row `i`'s words start, to write the first four of them. Panics past the end.
    #[inline(always)]
    pub fn words(&self, i: u32) -> *mut Real {
        assert!((i as usize) < self.len, "body row {i} of {}", self.len);
        // SAFETY: in bounds of the slice the rows were made from.
        unsafe { self.ptr.add(i as usize).cast::<Real>() }
    }
}

/// [`BodyRows`] that several workers may use at once (the parallel step).
#[derive(Clone, Copy)]
pub(crate) struct SharedRows<'a>(BodyRows<'a>);

// SAFETY: made only by the unsafe `SharedRows::new`, whose caller promises that no row is
// written through one worker's copy while another reads or writes it.
unsafe impl Send for SharedRows<'_> {}
unsafe impl Sync for SharedRows<'_> {}

impl<'a> SharedRows<'a> {
    /// The rows of `bodies`, for several workers.
    ///
    /// # Safety
    /// While any copy is in use, no two workers may touch one row at the same time unless
    /// both only read it, and nothing else may use `bodies`' rows.
    pub unsafe fn new(bodies: &'a mut [SolverBody]) -> SharedRows<'a> {
        SharedRows(BodyRows::new(bodies))
    }

    /// This worker's handle on the rows.
    #[inline(always)]
    pub fn rows(self) -> BodyRows<'a> {
        self.0
    }

    /// Body `i`'s inverse mass (1/kg). Panics past the end.
    ///
    /// # Safety
    /// No other worker may write body `i` meanwhile.
    #[inline(always)]
    pub unsafe fn inv_mass(&self, i: u32) -> Real {
        assert!((i as usize) < self.0.len, "body row {i} of {}", self.0.len);
        (*self.0.ptr.add(i as usize)).inv_mass
    }

    /// A copy of body `i`. Panics past the end.
    ///
    /// # Safety
    /// No other worker may write body `i` meanwhile.
    pub unsafe fn read(&self, i: u32) -> SolverBody {
        assert!((i as usize) < self.0.len, "body row {i} of {}", self.0.len);
        std::ptr::read(self.0.ptr.add(i as usize))
    }

    /// Body `i`, to read and write. Panics past the end.
    ///
    /// # Safety
    /// No other worker may reach body `i` while the reference lives, unless all only read.
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn body(&self, i: u32) -> &'a mut SolverBody {
        assert!((i as usize) < self.0.len, "body row {i} of {}", self.0.len);
        &mut *self.0.ptr.add(i as usize)
    }

    /// The rows as a slice again, for work that one worker does while every other waits.
    ///
    /// # Safety
    /// No other worker may use the rows until the slice is dropped.
    pub unsafe fn exclusive(&self) -> &'a mut [SolverBody] {
        std::slice::from_raw_parts_mut(self.0.ptr, self.0.len)
    }
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
    /// [`Moving::for_each`], in blocks of [`BODIES_PER_BLOCK`] spread over `region`'s
    /// workers.
    fn for_each_shared(
        self,
        region: &Region,
        bodies: &mut [SolverBody],
        f: &(impl Fn(&mut SolverBody) + Sync),
    ) {
        let len = match self {
            Moving::All => bodies.len(),
            Moving::Only(list) => list.len(),
        };
        // SAFETY: each block reaches its own bodies: a run of the array, or of a list that
        // names each body once.
        let rows = unsafe { SharedSlice::new(bodies) };
        region.for_blocks(len.div_ceil(BODIES_PER_BLOCK), &|k| {
            let run = block(k, BODIES_PER_BLOCK, len);
            match self {
                // SAFETY: block k's run is reached by the worker that took k alone.
                Moving::All => unsafe { rows.range(run) }
                    .iter_mut()
                    .filter(|b| b.inv_mass != 0.0)
                    .for_each(f),
                Moving::Only(list) => {
                    for &i in &list[run] {
                        // SAFETY: as above.
                        let b = unsafe { rows.get(i as usize) }.expect("a listed body exists");
                        if b.inv_mass != 0.0 {
                            f(b);
                        }
                    }
                }
            }
        });
    }

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
/// contacts of one stiffness tier). Listing them leaves the contacts where they are, which is
/// cheaper than grouping whole contacts by tier and merging them back.
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

    /// The index of the `n`th selected contact.
    #[inline]
    pub fn at(self, n: usize) -> usize {
        match self {
            Selected::All => n,
            Selected::Only(list) => list[n] as usize,
        }
    }

    /// Run `f` on every selected contact's index, in order. (One loop, so that `f` has one
    /// call site and is inlined.)
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

/// Semi-implicit Euler, velocity half: v += h a, w += h alpha (appendix eqs. 1-2), on the
/// moving bodies, spread over `region`'s workers if given.
#[inline(always)]
pub(crate) fn integrate_velocities(
    bodies: &mut [SolverBody],
    moving: Moving,
    (h, limits): (Real, Limits),
    region: Option<&Region>,
) {
    let max_v = limits.max_linear_speed;
    match region {
        Some(r) => moving.for_each_shared(r, bodies, &|b| accelerate(b, h, max_v)),
        None => moving.for_each(bodies, |b| accelerate(b, h, max_v)),
    }
}

/// One body's velocity half of the step: v += h a, w += h alpha, the speed capped at `max_v`.
#[inline(always)]
fn accelerate(b: &mut SolverBody, h: Real, max_v: Real) {
    b.v += h * b.accel;
    b.w += h * b.alpha;
    b.v = clamp_speed(b.v, max_v);
}

/// One body's position half: its speed capped (`max_v`, and `max_w` rad/s of spin), then
/// moved by `h` s.
#[inline(always)]
fn advance(b: &mut SolverBody, h: Real, (max_v, max_w): (Real, Real)) {
    b.v = clamp_speed(b.v, max_v);
    if b.w.is_nan() {
        b.w = 0.0;
    } else if b.w.abs() > max_w {
        b.w = max_w.copysign(b.w);
    }
    b.advance(h);
}

/// A kinematic body the solver moves: its index among the solver bodies and the velocity it
/// was given (m/s, rad/s), kept apart from its solver body so that nothing a solve pass writes
/// there can change how it moves.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Kinematic {
    pub index: u32,
    pub v: Vec2,
    pub w: Real,
}

impl Kinematic {
    /// The kinematic body in slot `index`, moving as its solver body `body` says.
    pub fn of(index: usize, body: &SolverBody) -> Kinematic {
        Kinematic {
            index: index as u32,
            v: body.v,
            w: body.w,
        }
    }
}

/// Semi-implicit Euler, position half: x += h v, theta += h w (appendix eqs. 65-68),
/// recording the motion as deltas from the start of the step. The `moving` dynamic bodies'
/// speeds are capped first (speed, and rotation per substep); the `kinematic` bodies move by
/// the velocity they were given, turned exactly by their angle, so that contacts see them where
/// they are at every substep (Box2D moves them so too).
#[inline(always)]
pub(crate) fn integrate_positions(
    bodies: &mut [SolverBody],
    (moving, kinematic): (Moving, &[Kinematic]),
    (h, limits): (Real, Limits),
    region: Option<&Region>,
) {
    let caps = (limits.max_linear_speed, limits.max_rotation / h);
    match region {
        Some(r) => moving.for_each_shared(r, bodies, &|b| advance(b, h, caps)),
        None => moving.for_each(bodies, |b| advance(b, h, caps)),
    }
    for k in kinematic {
        let b = &mut bodies[k.index as usize];
        (b.v, b.w) = (k.v, k.w);
        b.dp += h * k.v;
        b.dtheta += h * k.w;
        b.dq = Rot::from_angle(b.dtheta);
    }
}

/// Kinematic bodies start a solve where the step starts, at the velocity they were given:
/// each solve (one per stiffness tier) moves them through the whole step again.
pub(crate) fn restart_motion(bodies: &mut [SolverBody], kinematic: &[Kinematic]) {
    for k in kinematic {
        let b = &mut bodies[k.index as usize];
        (b.v, b.w) = (k.v, k.w);
        b.dp = Vec2::ZERO;
        b.dtheta = 0.0;
        b.dq = Rot::IDENTITY;
    }
}

impl SolverBody {
    /// Move by `dp` (m) and turn by `dtheta` (rad), besides the velocity.
    #[inline]
    pub(crate) fn displace(&mut self, dp: Vec2, dtheta: Real) {
        self.dp += dp;
        self.dtheta += dtheta;
        let turn = Rot::from_angle(dtheta);
        self.dq = Rot {
            c: turn.c * self.dq.c - turn.s * self.dq.s,
            s: turn.s * self.dq.c + turn.c * self.dq.s,
        };
    }

    /// Move by the velocity for `h` seconds: dp += h v, dtheta += h w, and the rotation by
    /// the first-order update q += h w q_perp, renormalised (cheap; the exact angle is kept in
    /// dtheta).
    #[inline(always)]
    fn advance(&mut self, h: Real) {
        self.dp += h * self.v;
        self.dtheta += h * self.w;
        let dq = self.dq;
        let (c, s) = (dq.c - h * self.w * dq.s, dq.s + h * self.w * dq.c);
        let len = (c * c + s * s).sqrt();
        self.dq = Rot {
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
