//! The soft step's contact constraint, one kernel for one, four or eight contacts at a time.
//!
//! A [`Bundle`] holds up to `L::WIDTH` contacts of one colour (no two share a dynamic body), a
//! contact per lane; every stage of the soft step runs on a bundle as on one contact, with
//! each `if` of the scalar algorithm turned into a lane-wise select. The overflow (contacts the
//! constraint graph could not colour) runs the same functions at width one ([`Lanes1`]), so
//! there is one copy of the contact math (`sequential.rs` keeps the appendix's own). A
//! contact's arithmetic does not depend on its bundle's width or its neighbours, so every width
//! gives the same World bit for bit.
//!
//! The stages, for a bundle: [`Bundle::warm_start`], [`Bundle::solve`] (biased, relax, or
//! normal relax: `PassKind`), [`Bundle::apply_restitution`], and [`Bundle::impulses`] (what
//! the store stage writes back). Preparing a contact is scalar (`soft_step::prepare_contact`);
//! its constraint is written straight into its lane by [`Bundle::set_contact`].
//!
//! [`Lanes1`]: super::lanes::Lanes1

use super::constraint::ContactConstraint;
use super::lanes::Wide;
use super::{BodyRows, SolverBody};
use crate::physics::contact::Contact;
use crate::physics::math::Real;

/// Which normal solve a bundle's contacts take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BundleKind {
    /// Two points with a well-conditioned block, both normal impulses at once (2x2 LCP), or
    /// one point, as a block whose second point never pushes: the same solve, so that in a
    /// small solve one-point and two-point contacts of a colour share bundles.
    Block,
    /// Two points too nearly coincident for the block: solved one after the other.
    Points,
    /// One point (a disc's contact, a corner on a face), in a large solve: every stage leaves
    /// the second point's lanes, inert, alone, so such a contact costs about half a two-point
    /// one.
    Single,
}

/// Per-point lanes of a bundle: lane i is the point of contact i. In declared order, what the
/// warm start reads first.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(crate) struct PointLanes<L> {
    /// rA x n and rB x n (m).
    a_cross_n: L,
    b_cross_n: L,
    /// rA . n and rB . n (m). With t = (n_y, -n_x), rA x t = -(rA . n): the tangent arms.
    a_dot_n: L,
    b_dot_n: L,
    /// Accumulated impulses (N s, per substep).
    normal_impulse: L,
    tangent_impulse: L,
    /// Separation less the anchors' part (m; `PointConstraint::adjusted_separation`).
    adjusted_separation: L,
    /// Effective masses along the normal and the tangent (kg).
    normal_mass: L,
    tangent_mass: L,
}

impl<L: Wide> PointLanes<L> {
    /// The tangent arms rA x t and rB x t: -(rA . n) and -(rB . n) to the bit (but for the
    /// sign of an exact zero), so a bundle carries four arms per point, not six.
    #[inline(always)]
    fn tangent_arms(&self) -> (L, L) {
        (-self.a_dot_n, -self.b_dot_n)
    }
}

/// Where a kernel reads and writes its bundles' bodies: the solver bodies themselves, on one
/// thread, or rows that other workers share ([`BodyRows`]), where no fixed body's row is
/// written.
pub(crate) trait Rows {
    /// Body `i`'s first eight words (`SolverBody::state`).
    fn state(&self, i: u32) -> &[Real; 8];
    /// Four columns back into the lanes' bodies ([`Wide::scatter_rows`]); `inv_mass` is the
    /// lanes' bodies' inverse masses (zero: a fixed body, or an empty lane's dummy).
    fn scatter<L: Wide>(&mut self, columns: [L; 4], idx: &L::Index, inv_mass: L);
}

impl Rows for [SolverBody] {
    #[inline(always)]
    fn state(&self, i: u32) -> &[Real; 8] {
        self[i as usize].state()
    }
    /// Every lane, fixed or not: on one thread, writing a fixed body's row back unchanged
    /// costs less than asking which lanes hold one.
    #[inline(always)]
    fn scatter<L: Wide>(&mut self, columns: [L; 4], idx: &L::Index, _inv_mass: L) {
        L::scatter_rows(columns, self, idx);
    }
}

impl Rows for BodyRows<'_> {
    #[inline(always)]
    fn state(&self, i: u32) -> &[Real; 8] {
        BodyRows::state(self, i)
    }
    #[inline(always)]
    /// Not the fixed bodies' lanes: bundles solved at once may share a fixed body.
    fn scatter<L: Wide>(&mut self, columns: [L; 4], idx: &L::Index, inv_mass: L) {
        let fixed = inv_mass.to_lanes();
        let skip = fixed
            .as_ref()
            .iter()
            .enumerate()
            .fold(0u8, |bits, (lane, &m)| bits | u8::from(m == 0.0) << lane);
        L::scatter_rows_shared(columns, *self, idx, skip);
    }
}

/// Up to `L::WIDTH` contacts packed for the lanes. In declared order: what the warm start
/// reads first, what the biased pass alone reads after the rest (the kind and side indices,
/// which a list's passes look up once or not at all, at the end).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(crate) struct Bundle<L: Wide> {
    /// Solver-body indices of A and B per lane (the fixed dummy body for empty lanes).
    a: L::Index,
    b: L::Index,
    /// The normal (unit, A to B).
    nx: L,
    ny: L,
    /// Inverse inertias of A and B (zero for fixed bodies and empty lanes). Their inverse
    /// masses come with their rows (`SolverBody::state`'s eighth word), not in the bundle.
    inv_i_a: L,
    inv_i_b: L,
    p: [PointLanes<L>; 2],
    friction: L,
    /// The block K (symmetric) and its inverse (identity for a contact without one).
    k00: L,
    k01: L,
    k11: L,
    i00: L,
    i01: L,
    i11: L,
    /// The contact spring ([`super::softness::Softness`]).
    bias_rate: L,
    mass_scale: L,
    impulse_scale: L,
    /// How far the spring has crept (m; `ContactConstraint::creep`).
    creep: L,
    pub kind: BundleKind,
    /// Where the bundle's restitution lanes are ([`BounceLanes`]), or [`NO_BOUNCE`].
    pub bounce_index: u32,
    /// Where the bundle's rounding lanes are ([`RoundLanes`]), or [`NO_ROUNDING`].
    pub round_index: u32,
}

// Every solve pass streams the bundles: at eight lanes, 35 lane values, the two sides' body
// indices and the header. A field added here costs every pass (docs/design.md).
#[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
const _: () = assert!(std::mem::size_of::<Bundle<super::lanes::Lanes8>>() == 1152);

/// What the store stage reads of a bundle beside its impulses, kept apart from it so that the
/// solve passes, which read neither, do not stream it: the contact each lane holds, and what
/// the step's substeps have applied along each point's normal.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ledger<L: Wide> {
    /// Contact index per lane; `u32::MAX` for an empty lane.
    pub contact: L::Index,
    /// The normal impulses this step's substeps ended with, summed, less the one the step
    /// began with (N s): each substep's warm start adds the impulse the last one ended with
    /// (the first cancels the initial -P exactly), and [`Bundle::impulses`] adds the last.
    /// That is all the normal constraint applied in the step, without a write per solve pass.
    total_normal_impulse: [L; 2],
}

impl<L: Wide> Ledger<L> {
    /// Every lane empty.
    pub fn empty() -> Ledger<L> {
        Ledger {
            contact: L::index_splat(u32::MAX),
            total_normal_impulse: [L::ZERO; 2],
        }
    }
}

/// The separation (m) given to the absent second point of a one-point contact solved in a
/// block bundle: so far apart that the block LCP never lets it push (its row's right-hand side
/// stays positive), and finite, so nothing times zero mass makes a NaN.
const NEVER_TOUCHES: Real = 1.0e18;

/// A bundle none of whose contacts bounces.
pub(crate) const NO_BOUNCE: u32 = u32::MAX;

/// What restitution reads of a bundle's contacts that bounce, kept apart from the bundle so
/// that the solve passes do not stream it and a world without restitution pays nothing.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BounceLanes<L> {
    /// Coefficient of restitution per lane (0 for a lane that does not bounce).
    restitution: L,
    /// Each point's approach speed: the most negative normal velocity any pass met it at
    /// before pushing (m/s), from the approach it carried over from last step (0 if none).
    /// That is the speed it hit at: a body landing within a step is faster when its contact
    /// first pushes than when the step began (the step's gravity), and slower once pushed.
    approach: [L; 2],
    /// Whether its surfaces met this step (1) or not (0): a biased pass pushed the point, or
    /// a relax pass pushed it where it touches. A relax pass's push on a point still apart
    /// only keeps the next substep from passing the surface; the point bounces when it meets
    /// it, next step, at the approach it keeps.
    touched: [L; 2],
}

impl<L: Wide> BounceLanes<L> {
    /// No lane bounces.
    pub const NONE: BounceLanes<L> = BounceLanes {
        restitution: L::ZERO,
        approach: [L::ZERO; 2],
        touched: [L::ZERO; 2],
    };

    /// Lane `lane` bounces with contact `c`'s restitution, from the approach its points
    /// carried over from last step.
    #[inline(always)]
    pub fn set(&mut self, lane: usize, c: &Contact) {
        self.restitution.set_lane(lane, c.restitution);
        for (v, p) in self.approach.iter_mut().zip(c.live()) {
            v.set_lane(lane, p.approach_velocity);
        }
    }
}

/// The side lanes a bundle may have, for one solve pass: its rounding ([`RoundLanes`]), and
/// its restitution lanes ([`BounceLanes`]), whose approach speeds (and, in the biased pass,
/// touches) the pass updates.
pub(crate) struct Sides<'a, L> {
    pub round: Option<&'a RoundLanes<L>>,
    pub bounce: Option<&'a mut BounceLanes<L>>,
}

/// A bundle none of whose contacts has a rounded side.
pub(crate) const NO_ROUNDING: u32 = u32::MAX;

/// How far each side's surface is grown out from its core (m; `Contact::rounding`), per lane,
/// kept apart from the bundle like [`BounceLanes`]: only bundles with a rounded side have them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RoundLanes<L> {
    a: L,
    b: L,
}

impl<L: Wide> RoundLanes<L> {
    /// No lane rounded.
    pub const NONE: RoundLanes<L> = RoundLanes {
        a: L::ZERO,
        b: L::ZERO,
    };

    /// Lane `lane` has contact `c`'s rounding.
    #[inline(always)]
    pub fn set(&mut self, lane: usize, c: &Contact) {
        self.a.set_lane(lane, c.rounding[0]);
        self.b.set_lane(lane, c.rounding[1]);
    }
}

/// A point's impulses at the end of the solve, read out of its lane for the store stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct PointImpulses {
    /// Accumulated normal impulse (N s, per substep).
    pub normal: Real,
    /// Accumulated friction impulse (N s, per substep).
    pub tangent: Real,
    /// Everything the normal constraint applied this step (N s).
    pub total_normal: Real,
    /// The approach speed a point that has not met its surface yet carries to the next step
    /// (m/s, <= 0; see [`BounceLanes`]), 0 otherwise.
    pub approach: Real,
}

impl PointImpulses {
    /// These impulses, or all zero if any is not finite.
    #[inline]
    pub fn finite_or_zero(&self) -> PointImpulses {
        let all = [self.normal, self.tangent, self.total_normal, self.approach];
        if all.iter().all(|x| x.is_finite()) {
            *self
        } else {
            PointImpulses::default()
        }
    }
}

/// What a solve pass does: 1 / substep (1/s), whether it applies the soft bias, and the
/// push-out cap as a negative velocity (m/s).
#[derive(Clone, Copy)]
pub(crate) struct Pass<L> {
    pub inv_h: L,
    pub use_bias: bool,
    pub push_out: L,
}

impl<L> Pass<L> {
    /// A pass at 1 / substep `inv_h` (1/s), with the soft bias or without, capped at
    /// `push_out` (a negative velocity, m/s).
    #[inline(always)]
    pub fn new(inv_h: L, use_bias: bool, push_out: L) -> Pass<L> {
        Pass {
            inv_h,
            use_bias,
            push_out,
        }
    }
}

/// The body state a kernel reads for a bundle's lanes.
struct BodyLanes<L> {
    vx: L,
    vy: L,
    w: L,
    dpx: L,
    dpy: L,
    qc: L,
    qs: L,
    inv_mass: L,
    inv_inertia: L,
}

impl<L: Wide> BodyLanes<L> {
    /// Load the lanes' bodies' velocities, how far they moved this step and their inverse
    /// masses: each lane's body's first eight words (`SolverBody::state`), transposed into one
    /// value per field. The inverse inertias, which the rows have no room for, come packed in
    /// the bundle, which every pass streams.
    #[inline(always)]
    fn gather<R: Rows + ?Sized>(rows: &R, idx: &L::Index, inv_inertia: L) -> Self {
        let [vx, vy, w, dpx, dpy, qc, qs, inv_mass] =
            L::columns(|lane| rows.state(idx.as_ref()[lane]));
        BodyLanes {
            vx,
            vy,
            w,
            dpx,
            dpy,
            qc,
            qs,
            inv_mass,
            inv_inertia,
        }
    }

    /// Write velocities back, with the motion as it was read (a solve pass does not move
    /// bodies): the first four words of each lane's body, one store a body. A fixed body's
    /// lanes come back as they were read (its zero inverse mass and inertia take nothing from
    /// an impulse); where other workers share the rows, a fixed body's lanes (zero inverse
    /// mass) are not written at all.
    #[inline(always)]
    fn scatter<R: Rows + ?Sized>(&self, rows: &mut R, idx: &L::Index) {
        rows.scatter([self.vx, self.vy, self.w, self.dpx], idx, self.inv_mass);
    }

    /// Relative velocity of B over A along (dx, dy) at arms (rA x d, rB x d):
    /// (vB - vA) . d + wB (rB x d) - wA (rA x d).
    #[inline(always)]
    fn relative(a: &Self, b: &Self, (dx, dy): (L, L), (rd_a, rd_b): (L, L)) -> L {
        (b.vx - a.vx) * dx + (b.vy - a.vy) * dy + b.w * rd_b - a.w * rd_a
    }

    /// Apply impulse lambda along (dx, dy) at arms (rA x d, rB x d): B gets +, A gets -.
    #[inline(always)]
    fn apply(a: &mut Self, b: &mut Self, (dx, dy): (L, L), (rd_a, rd_b): (L, L), lambda: L) {
        a.vx -= a.inv_mass * lambda * dx;
        a.vy -= a.inv_mass * lambda * dy;
        a.w -= a.inv_inertia * lambda * rd_a;
        b.vx += b.inv_mass * lambda * dx;
        b.vy += b.inv_mass * lambda * dy;
        b.w += b.inv_inertia * lambda * rd_b;
    }
}

/// A point's normal arms as a pair.
#[inline(always)]
fn normal_arms<L: Wide>(p: &PointLanes<L>) -> (L, L) {
    (p.a_cross_n, p.b_cross_n)
}

impl<L: Wide> Bundle<L> {
    /// A bundle with every lane empty: the fixed dummy body on both sides, zero masses and
    /// impulses, and an identity block so the LCP stays finite.
    pub fn inert(kind: BundleKind, dummy: u32) -> Bundle<L> {
        let (zero, one) = (L::ZERO, L::ONE);
        let point = PointLanes {
            a_cross_n: zero,
            b_cross_n: zero,
            a_dot_n: zero,
            b_dot_n: zero,
            adjusted_separation: zero,
            normal_mass: zero,
            tangent_mass: zero,
            normal_impulse: zero,
            tangent_impulse: zero,
        };
        Bundle {
            kind,
            bounce_index: NO_BOUNCE,
            round_index: NO_ROUNDING,
            a: L::index_splat(dummy),
            b: L::index_splat(dummy),
            nx: zero,
            ny: zero,
            friction: zero,
            bias_rate: zero,
            mass_scale: zero,
            impulse_scale: zero,
            creep: zero,
            k00: one,
            k01: zero,
            k11: one,
            i00: one,
            i01: zero,
            i11: one,
            inv_i_a: zero,
            inv_i_b: zero,
            p: [point; 2],
        }
    }

    /// Write contact `c` (index `ci`) with its constraint `k` into lane `lane`, and into the
    /// bundle's `ledger` its index and starting impulses. A contact
    /// without a usable block keeps the inert identity; a one-point contact leaves its second
    /// point's lanes zero (in a block bundle, all but a separation that never closes).
    #[inline(always)]
    pub fn set_contact(
        &mut self,
        (lane, ledger): (usize, &mut Ledger<L>),
        (ci, c): (u32, &Contact),
        k: &ContactConstraint,
        bodies: &[SolverBody],
    ) {
        ledger.contact.as_mut()[lane] = ci;
        self.a.as_mut()[lane] = c.a;
        self.b.as_mut()[lane] = c.b;
        let sf = k.softness;
        let (body_a, body_b) = (&bodies[c.a as usize], &bodies[c.b as usize]);
        for (field, x) in [
            (&mut self.nx, c.normal.x),
            (&mut self.ny, c.normal.y),
            (&mut self.friction, c.friction),
            (&mut self.bias_rate, sf.bias_rate),
            (&mut self.mass_scale, sf.mass_scale),
            (&mut self.impulse_scale, sf.impulse_scale),
            (&mut self.creep, k.creep),
            (&mut self.inv_i_a, body_a.inv_inertia),
            (&mut self.inv_i_b, body_b.inv_inertia),
        ] {
            field.set_lane(lane, x);
        }
        if let Some(m) = &k.block {
            for (field, x) in [
                (&mut self.k00, m.k[0][0]),
                (&mut self.k01, m.k[0][1]),
                (&mut self.k11, m.k[1][1]),
                (&mut self.i00, m.inv[0][0]),
                (&mut self.i01, m.inv[0][1]),
                (&mut self.i11, m.inv[1][1]),
            ] {
                field.set_lane(lane, x);
            }
        } else if c.count == 1 && self.kind == BundleKind::Block {
            // A one-point contact in a block bundle: its point alone, K = 1 / normal mass, and
            // a second point that never pushes (far apart, no mass, decoupled).
            let m = k.points[0].normal_mass;
            self.k00.set_lane(lane, 1.0 / m);
            self.i00.set_lane(lane, m);
            self.p[1].adjusted_separation.set_lane(lane, NEVER_TOUCHES);
        }
        debug_assert!(
            self.kind != BundleKind::Single || c.count == 1,
            "one point alone"
        );
        let points = self.p.iter_mut().zip(&mut ledger.total_normal_impulse);
        for (((v, total), p), kp) in points.zip(c.live()).zip(&k.points) {
            total.set_lane(lane, -p.normal_impulse);
            let arms = kp.arms;
            for (field, x) in [
                (&mut v.a_cross_n, arms.a_cross_n),
                (&mut v.b_cross_n, arms.b_cross_n),
                (&mut v.a_dot_n, arms.a_dot_n),
                (&mut v.b_dot_n, arms.b_dot_n),
                (&mut v.adjusted_separation, kp.adjusted_separation),
                (&mut v.normal_mass, kp.normal_mass),
                (&mut v.tangent_mass, kp.tangent_mass),
                (&mut v.normal_impulse, p.normal_impulse),
                (&mut v.tangent_impulse, p.tangent_impulse),
            ] {
                field.set_lane(lane, x);
            }
        }
    }

    /// Both sides' body lanes.
    #[inline(always)]
    fn gather<R: Rows + ?Sized>(&self, rows: &R) -> (BodyLanes<L>, BodyLanes<L>) {
        (
            BodyLanes::gather(rows, &self.a, self.inv_i_a),
            BodyLanes::gather(rows, &self.b, self.inv_i_b),
        )
    }

    /// Write both sides' velocities back.
    #[inline(always)]
    fn scatter<R: Rows + ?Sized>(&self, rows: &mut R, a: &BodyLanes<L>, b: &BodyLanes<L>) {
        a.scatter(rows, &self.a);
        b.scatter(rows, &self.b);
    }

    /// The normal and the tangent t = (n_y, -n_x).
    #[inline(always)]
    fn axes(&self) -> ((L, L), (L, L)) {
        ((self.nx, self.ny), (self.ny, -self.nx))
    }

    /// Warm start: apply the first `N` points' accumulated impulses (the start of a substep;
    /// `N` is 1 for [`BundleKind::Single`], else 2), and count them in the step's total
    /// (`ledger`, the bundle's own).
    #[inline(always)]
    pub fn warm_start<const N: usize, R: Rows + ?Sized>(
        &mut self,
        rows: &mut R,
        ledger: &mut Ledger<L>,
    ) {
        let (mut a, mut b) = self.gather(rows);
        let (n, t) = self.axes();
        for (p, total) in self.p[..N].iter().zip(&mut ledger.total_normal_impulse) {
            *total += p.normal_impulse;
            BodyLanes::apply(&mut a, &mut b, n, normal_arms(p), p.normal_impulse);
            BodyLanes::apply(&mut a, &mut b, t, p.tangent_arms(), p.tangent_impulse);
        }
        self.scatter(rows, &a, &b);
    }

    /// Warm starting off: zero the accumulated impulses instead (the start of a substep).
    #[inline(always)]
    pub fn clear_impulses(&mut self, ledger: &mut Ledger<L>) {
        for (p, total) in self.p.iter_mut().zip(&mut ledger.total_normal_impulse) {
            // The impulse the last substep ended with counts as its share of the total.
            *total += p.normal_impulse;
            p.normal_impulse = L::ZERO;
            p.tangent_impulse = L::ZERO;
        }
    }

    /// One solve pass: the normal impulses (soft where `pass.use_bias`, rigid otherwise),
    /// then friction unless `friction` is false (a normal relax pass), with the bundle's side
    /// lanes (`sides`).
    #[inline(always)]
    pub fn solve<R: Rows + ?Sized>(
        &mut self,
        rows: &mut R,
        pass: &Pass<L>,
        sides: Sides<L>,
        friction: bool,
    ) {
        // One copy of the kernel for sharp bundles and one for rounded ones, so that neither
        // asks per point which it is; each for one point and for two.
        let bounce = sides.bounce;
        match (sides.round, self.kind) {
            (None, BundleKind::Single) => {
                self.solve_turning::<1, _, R>(rows, (pass, Sharp), bounce, friction)
            }
            (None, _) => self.solve_turning::<2, _, R>(rows, (pass, Sharp), bounce, friction),
            (Some(r), BundleKind::Single) => {
                self.solve_turning::<1, _, R>(rows, (pass, r), bounce, friction)
            }
            (Some(r), _) => self.solve_turning::<2, _, R>(rows, (pass, r), bounce, friction),
        }
    }

    /// [`Bundle::solve`] of a bundle without rounded sides or restitution lanes, of `N` points
    /// (1 for [`BundleKind::Single`], else 2).
    #[inline(always)]
    pub fn solve_plain<const N: usize, R: Rows + ?Sized>(
        &mut self,
        rows: &mut R,
        pass: &Pass<L>,
        friction: bool,
    ) {
        debug_assert_eq!(N == 1, self.kind == BundleKind::Single);
        self.solve_turning::<N, _, R>(rows, (pass, Sharp), None, friction)
    }

    /// [`Bundle::solve`] of the first `N` points, which turn as `round` says.
    #[inline(always)]
    fn solve_turning<const N: usize, T: Turning<L>, R: Rows + ?Sized>(
        &mut self,
        rows: &mut R,
        (pass, round): (&Pass<L>, T),
        bounce: Option<&mut BounceLanes<L>>,
        friction: bool,
    ) {
        let (mut a, mut b) = self.gather(rows);
        let (n, t) = self.axes();
        let dp_n = (b.dpx - a.dpx) * n.0 + (b.dpy - a.dpy) * n.1;
        // (Written out, here and below, rather than mapped by a closure: a closure does not
        // take the AVX2 compilation of the kernel it is called from, and nothing but inlined
        // functions may stand between the eight-lane kernels and their instructions.)
        let mut coeffs = [(L::ZERO, L::ZERO, L::ZERO); 2];
        for (j, k) in coeffs[..N].iter_mut().enumerate() {
            *k = self.coefficients(&self.p[j], (&a, &b), dp_n, (pass, round));
        }
        // Where the bundle bounces, each point's normal velocity before this pass pushes it,
        // and whether its surfaces meet (a biased pass that pushes closes the gap within its
        // substep; a relax pass's push on a point still apart only guards the next substep).
        let before = match bounce {
            Some(_) => Some([
                self.before_push(&self.p[0], (&a, &b), dp_n, round),
                self.before_push(&self.p[1], (&a, &b), dp_n, round),
            ]),
            None => None,
        };
        match self.kind {
            BundleKind::Block => self.solve_block(&mut a, &mut b, &coeffs),
            BundleKind::Points | BundleKind::Single => {
                for (p, &(bias, mass_scale, impulse_scale)) in self.p[..N].iter_mut().zip(&coeffs) {
                    let vn = BodyLanes::relative(&a, &b, n, normal_arms(p));
                    let impulse = -p.normal_mass * (mass_scale * vn + bias)
                        - impulse_scale * p.normal_impulse;
                    let total = (p.normal_impulse + impulse).max(L::ZERO);
                    let applied = total - p.normal_impulse;
                    p.normal_impulse = total;
                    BodyLanes::apply(&mut a, &mut b, n, normal_arms(p), applied);
                }
            }
        }
        if let (Some(bounce), Some(before)) = (bounce, before) {
            for (j, (v, met)) in before.into_iter().enumerate() {
                let pushes = self.p[j].normal_impulse.cmpgt(L::ZERO);
                let approach = bounce.approach[j];
                bounce.approach[j] = L::select(pushes, v.min(approach), approach);
                let touches = if pass.use_bias { pushes } else { pushes & met };
                bounce.touched[j] = L::select(touches, L::ONE, bounce.touched[j]);
            }
        }
        // Skipped when no lane has friction.
        if friction && L::any(self.friction.cmpgt(L::ZERO)) {
            for p in &mut self.p[..N] {
                let vt = BodyLanes::relative(&a, &b, t, p.tangent_arms());
                let max_f = self.friction * p.normal_impulse;
                let total = (p.tangent_impulse - p.tangent_mass * vt).clamp(-max_f, max_f);
                let applied = total - p.tangent_impulse;
                p.tangent_impulse = total;
                BodyLanes::apply(&mut a, &mut b, t, p.tangent_arms(), applied);
            }
        }
        self.scatter(rows, &a, &b);
    }

    /// Point `p`'s normal velocity (m/s) and whether its surfaces meet (separation <= 0),
    /// before a pass pushes it.
    #[inline(always)]
    fn before_push<T: Turning<L>>(
        &self,
        p: &PointLanes<L>,
        (a, b): (&BodyLanes<L>, &BodyLanes<L>),
        dp_n: L,
        round: T,
    ) -> (L, L::Mask) {
        let vn = BodyLanes::relative(a, b, self.axes().0, normal_arms(p));
        (vn, L::ZERO.cmpge(separation(p, (a, b), dp_n, round)))
    }

    /// A point's (bias, mass scale, impulse scale) for this pass (Catto's soft step):
    /// impulse = -m_eff (mass_scale vn + bias) - impulse_scale P. Where the surfaces are apart
    /// (a speculative point) the bias lets them close the gap in one substep, no more; where
    /// they overlap it is the spring's, mass_scale bias_rate (s + creep), capped at the
    /// push-out speed, in the biased pass, and nothing in a relax pass (a contact deeper than
    /// its spring reaches is prepared rigid: `recover.rs`). The separation is worked out from
    /// how far the bodies moved this step: s = s0 + (dpB - dpA) . n + (qB rB - rB) . n -
    /// (qA rA - rA) . n, where for a rotation q = (c, s),
    /// (q r) . n = c (r . n) + s (r x n). `dp_n` is (dpB - dpA) . n. On a rounded side
    /// (`round`) the point is its core's nearest point grown out along the normal, so only the
    /// core's point turns with the body: for B, rB + rad n turns and -rad n does not (a disc's
    /// contact stays at its bottom as it rolls, where the turned material point would rise).
    #[inline(always)]
    fn coefficients<T: Turning<L>>(
        &self,
        p: &PointLanes<L>,
        (a, b): (&BodyLanes<L>, &BodyLanes<L>),
        dp_n: L,
        (pass, round): (&Pass<L>, T),
    ) -> (L, L, L) {
        let s = separation(p, (a, b), dp_n, round);
        let speculative = s.cmpgt(L::ZERO);
        let (soft_bias, soft_ms, soft_is) = if pass.use_bias {
            (
                (self.mass_scale * self.bias_rate * (s + self.creep)).max(pass.push_out),
                self.mass_scale,
                self.impulse_scale,
            )
        } else {
            (L::ZERO, L::ONE, L::ZERO)
        };
        (
            L::select(speculative, s * pass.inv_h, soft_bias),
            L::select(speculative, L::ONE, soft_ms),
            L::select(speculative, L::ZERO, soft_is),
        )
    }

    /// Both normal impulses of each lane's two-point contact at once. Row i of the soft update
    /// asks for the normal velocity vn_i' = impulse_scale_i (vn_i - (K P)_i) - bias_i, which
    /// is what the one-point impulse gives (using mass_scale + impulse_scale = 1), while both
    /// accumulated impulses stay >= 0: the LCP of [`block_lcp`].
    #[inline(always)]
    fn solve_block(&mut self, a: &mut BodyLanes<L>, b: &mut BodyLanes<L>, coeffs: &[(L, L, L); 2]) {
        let (vn, kl) = self.block_velocities(a, b);
        let r = [
            soft_rhs(vn[0], kl[0], coeffs[0]),
            soft_rhs(vn[1], kl[1], coeffs[1]),
        ];
        let [l0, l1] = [self.p[0].normal_impulse, self.p[1].normal_impulse];
        let (x0, x1, _) = block_lcp(self, r, [l0, l1]);
        self.apply_block(a, b, [x0 - l0, x1 - l1]);
        self.p[0].normal_impulse = x0;
        self.p[1].normal_impulse = x1;
    }

    /// Each point's normal velocity and (K P)_i for the accumulated impulses P.
    #[inline(always)]
    fn block_velocities(&self, a: &BodyLanes<L>, b: &BodyLanes<L>) -> ([L; 2], [L; 2]) {
        let (n, _) = self.axes();
        let [p0, p1] = &self.p;
        let (l0, l1) = (p0.normal_impulse, p1.normal_impulse);
        let kl = [self.k00 * l0 + self.k01 * l1, self.k01 * l0 + self.k11 * l1];
        let vn = [
            BodyLanes::relative(a, b, n, normal_arms(p0)),
            BodyLanes::relative(a, b, n, normal_arms(p1)),
        ];
        (vn, kl)
    }

    /// Apply normal impulse increments `d` at the two points together.
    #[inline(always)]
    fn apply_block(&self, a: &mut BodyLanes<L>, b: &mut BodyLanes<L>, [d0, d1]: [L; 2]) {
        let [p0, p1] = &self.p;
        let (nx, ny) = (self.nx, self.ny);
        let d = d0 + d1;
        a.vx -= a.inv_mass * d * nx;
        a.vy -= a.inv_mass * d * ny;
        a.w -= a.inv_inertia * (d0 * p0.a_cross_n + d1 * p1.a_cross_n);
        b.vx += b.inv_mass * d * nx;
        b.vy += b.inv_mass * d * ny;
        b.w += b.inv_inertia * (d0 * p0.b_cross_n + d1 * p1.b_cross_n);
    }

    /// Restitution, after the substeps: reverse e times the pre-solve approach speed at each
    /// point that approached faster than `threshold` (m/s) and pushed in the step (its total
    /// normal impulse is positive: a speculative point that never touched does not bounce).
    /// Box2D asks for a positive largest increment instead, which cost every solve pass a max
    /// and two lanes. Where both points of a block bounce they are aimed at vn' = -e vn0
    /// together, so a flat face hitting a flat face rebounds by exactly e.
    #[inline(always)]
    pub fn apply_restitution<R: Rows + ?Sized>(
        &mut self,
        bounce: &BounceLanes<L>,
        rows: &mut R,
        threshold: L,
    ) {
        let bounces = [
            self.bounces(0, bounce, threshold),
            self.bounces(1, bounce, threshold),
        ];
        if !L::any(bounces[0] | bounces[1]) {
            // Nothing hit hard enough: a resting bundle costs a compare.
            return;
        }
        let (mut a, mut b) = self.gather(rows);
        let (n, _) = self.axes();
        let e = bounce.restitution;
        let v0 = bounce.approach;
        let aim = [e * v0[0], e * v0[1]];
        let mut by_block = None;
        if self.kind == BundleKind::Block {
            let (vn, kl) = self.block_velocities(&a, &b);
            let r = [vn[0] - kl[0] + aim[0], vn[1] - kl[1] + aim[1]];
            let l = [self.p[0].normal_impulse, self.p[1].normal_impulse];
            let (x0, x1, fits) = block_lcp(self, r, l);
            let both = bounces[0] & bounces[1] & fits;
            let x = [L::select(both, x0, l[0]), L::select(both, x1, l[1])];
            self.apply_block(&mut a, &mut b, [x[0] - l[0], x[1] - l[1]]);
            self.p[0].normal_impulse = x[0];
            self.p[1].normal_impulse = x[1];
            by_block = Some(both);
        }
        // The points not bounced together, one after the other.
        for (j, p) in self.p.iter_mut().enumerate() {
            let vn = BodyLanes::relative(&a, &b, n, normal_arms(p));
            let impulse = -p.normal_mass * (vn + aim[j]);
            let total = (p.normal_impulse + impulse).max(L::ZERO);
            let mut new = L::select(bounces[j], total, p.normal_impulse);
            if let Some(both) = by_block {
                new = L::select(both, p.normal_impulse, new);
            }
            let applied = new - p.normal_impulse;
            p.normal_impulse = new;
            BodyLanes::apply(&mut a, &mut b, n, normal_arms(p), applied);
        }
        self.scatter(rows, &a, &b);
    }

    /// Which lanes' point `j` bounces: its surfaces met this step (a biased pass pushed it),
    /// it approached faster than `threshold`, and its contact has restitution.
    #[inline(always)]
    fn bounces(&self, j: usize, bounce: &BounceLanes<L>, threshold: L) -> L::Mask {
        let touched = bounce.touched[j].cmpgt(L::ZERO);
        let fast = (-threshold).cmpgt(bounce.approach[j]);
        fast & touched & bounce.restitution.cmpgt(L::ZERO)
    }

    /// Each lane's points' impulses at the end of the solve (lanes beyond `L::WIDTH` unused),
    /// read out field by field: each field's lanes once, not once per lane.
    #[inline(always)]
    pub fn impulses(
        &self,
        ledger: &Ledger<L>,
        bounce: Option<&BounceLanes<L>>,
    ) -> [[PointImpulses; 2]; 8] {
        let mut ends = [[PointImpulses::default(); 2]; 8];
        for (j, p) in self.p.iter().enumerate() {
            let total_normal_impulse = ledger.total_normal_impulse[j];
            let (normal, tangent, total) = (
                p.normal_impulse.to_lanes(),
                p.tangent_impulse.to_lanes(),
                total_normal_impulse.to_lanes(),
            );
            // Carried to the next step: the approach of a point some pass pushed this step
            // whose surfaces have not met yet; nothing from a step that did not push it (an
            // approach kept past such a step could bounce a later, slower landing).
            let carried = match bounce {
                Some(b) => {
                    let pushed = (total_normal_impulse + p.normal_impulse).cmpgt(L::ZERO);
                    let keep = pushed & L::ONE.cmpgt(b.touched[j]);
                    L::select(keep, b.approach[j], L::ZERO)
                }
                None => L::ZERO,
            }
            .to_lanes();
            for (lane, end) in ends.iter_mut().take(L::WIDTH).enumerate() {
                end[j] = PointImpulses {
                    normal: normal.as_ref()[lane],
                    tangent: tangent.as_ref()[lane],
                    total_normal: total.as_ref()[lane] + normal.as_ref()[lane],
                    approach: carried.as_ref()[lane],
                };
            }
        }
        ends
    }

    /// [`Bundle::impulses`] of lane `lane` alone, read lane by lane where it lives.
    #[inline(always)]
    pub fn lane_impulses(
        &self,
        lane: usize,
        ledger: &Ledger<L>,
        bounce: Option<&BounceLanes<L>>,
    ) -> [PointImpulses; 2] {
        std::array::from_fn(|j| {
            let p = &self.p[j];
            let (normal, total) = (
                p.normal_impulse.lane(lane),
                ledger.total_normal_impulse[j].lane(lane),
            );
            let pushed = total + normal > 0.0;
            let carried = bounce.filter(|b| pushed && 1.0 > b.touched[j].lane(lane));
            PointImpulses {
                normal,
                tangent: p.tangent_impulse.lane(lane),
                total_normal: total + normal,
                approach: carried.map_or(0.0, |b| b.approach[j].lane(lane)),
            }
        })
    }
}

/// Point `p`'s separation now (m; see `Bundle::coefficients`): its separation when the step
/// was prepared, moved by how far the bodies `a` and `b` moved and turned (`dp_n`: their
/// relative motion along the normal), a rounded side (`round`) turning only its core's point.
#[inline(always)]
fn separation<L: Wide, T: Turning<L>>(
    p: &PointLanes<L>,
    (a, b): (&BodyLanes<L>, &BodyLanes<L>),
    dp_n: L,
    turning: T,
) -> L {
    let (turned_a, turned_b) = turning.turned(p, (a, b));
    dp_n + turned_b - turned_a + p.adjusted_separation
}

/// How a bundle's points move as their bodies turn: (qA rA) . n and (qB rB) . n, for
/// rotations q = (c, s) with (q r) . n = c (r . n) + s (r x n).
trait Turning<L: Wide>: Copy {
    fn turned(self, p: &PointLanes<L>, bodies: (&BodyLanes<L>, &BodyLanes<L>)) -> (L, L);
}

/// Sharp corners: a point turns with its body.
#[derive(Clone, Copy)]
struct Sharp;

impl<L: Wide> Turning<L> for Sharp {
    #[inline(always)]
    fn turned(self, p: &PointLanes<L>, (a, b): (&BodyLanes<L>, &BodyLanes<L>)) -> (L, L) {
        (
            a.qc * p.a_dot_n + a.qs * p.a_cross_n,
            b.qc * p.b_dot_n + b.qs * p.b_cross_n,
        )
    }
}

/// Rounded sides: a point turns with its core's nearest point, the rounding along the normal
/// staying put (on A the surface is rad out along +n from the core, on B along -n).
impl<L: Wide> Turning<L> for &RoundLanes<L> {
    #[inline(always)]
    fn turned(self, p: &PointLanes<L>, (a, b): (&BodyLanes<L>, &BodyLanes<L>)) -> (L, L) {
        let r = self;
        (
            a.qc * (p.a_dot_n - r.a) + a.qs * p.a_cross_n + r.a,
            b.qc * (p.b_dot_n + r.b) + b.qs * p.b_cross_n - r.b,
        )
    }
}

/// Row i's right-hand side of the soft block update for normal velocity `vn`, (K P)_i `kl`
/// and the point's (bias, mass scale, impulse scale): the velocity with the accumulated
/// impulse taken out, less the velocity the soft update aims at.
#[inline(always)]
fn soft_rhs<L: Wide>(vn: L, kl: L, (bias, _, impulse_scale): (L, L, L)) -> L {
    vn - kl - (impulse_scale * (vn - kl) - bias)
}

/// The two-point contact LCP, lane by lane: find x >= 0 with w = K x + r >= 0 and x . w = 0
/// (x the new accumulated normal impulses, w the normal velocities beyond their aims), by
/// Box2D v2's four cases: both push, only point 0, only point 1, neither. Solving both points
/// together removes the bias of solving them one after the other, which puts a spurious spin
/// into every resting box. A point's normal mass is 1 / K_ii to the bit (the same sum, then its
/// reciprocal), so the one-point cases multiply by it. Returns the impulses and which lanes a
/// case fits; a lane no case fits (round-off only) keeps its impulses `l`.
#[inline(always)]
fn block_lcp<L: Wide>(bundle: &Bundle<L>, [r0, r1]: [L; 2], [l0, l1]: [L; 2]) -> (L, L, L::Mask) {
    let zero = L::ZERO;
    let x0_1 = -(bundle.i00 * r0 + bundle.i01 * r1);
    let x1_1 = -(bundle.i01 * r0 + bundle.i11 * r1);
    let case1 = x0_1.cmpge(zero) & x1_1.cmpge(zero);
    let x0_2 = -r0 * bundle.p[0].normal_mass;
    let case2 = x0_2.cmpge(zero) & (bundle.k01 * x0_2 + r1).cmpge(zero);
    let x1_3 = -r1 * bundle.p[1].normal_mass;
    let case3 = x1_3.cmpge(zero) & (bundle.k01 * x1_3 + r0).cmpge(zero);
    let case4 = r0.cmpge(zero) & r1.cmpge(zero);
    let x0 = L::select(
        case1,
        x0_1,
        L::select(case2, x0_2, L::select(case3 | case4, zero, l0)),
    );
    let x1 = L::select(
        case1,
        x1_1,
        L::select(case2 | case4, zero, L::select(case3, x1_3, l1)),
    );
    (x0, x1, case1 | case2 | case3 | case4)
}
