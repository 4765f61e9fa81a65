//! The soft step's inner loops, four or eight contacts at a time.
//!
//! Contacts are first coloured so that no two contacts of one colour share a dynamic body
//! (greedy, in key order, so the result is deterministic; static bodies may be shared since
//! nothing writes to them). Within a colour the contacts are independent, so they are packed
//! four to a bundle and solved in the lanes of one `Lanes` value (eight to a bundle in
//! [`Lanes8`] where the processor has AVX2): the same arithmetic as the scalar soft step, with
//! every `if` turned into a lane-wise select. A contact's arithmetic does not depend on its
//! bundle's width or neighbours, so both widths give the same World bit for bit. Two-point contacts with a
//! well-conditioned block are solved by the 2x2 LCP; the others (one point, or nearly
//! coincident points) one point after the other, in bundles of their own. Contacts beyond the
//! last colour are solved by the scalar code after the bundles.

use super::constraint::{ContactConstraint, PointEnd};
use super::lanes::{eight_lanes_available, prefetch, Lanes8, Wide};
use super::PassKind;
use super::{Selected, SolverBody};
use crate::physics::contact::Contact;
use crate::physics::math::{Lanes, Real};

/// How many colours the greedy colouring tries before giving up on a contact.
const COLOURS: usize = 32;

/// Contacts from which a step packs eight to a bundle (where the processor can): below, the
/// bundles of each colour are mostly empty lanes. falling_bricks (8 contacts) took 0.0068 ms
/// a step on eight lanes against 0.0045 on four; pyramid_20 (590) 0.22 against 0.26.
const EIGHT_LANES_FROM: usize = 64;

/// Which kernel a bundle needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// Two points with a usable block: solved together.
    Block,
    /// One point, or two solved one after the other.
    Points,
}

/// Per-point data of a bundle's contacts, lane i being contact i of the bundle.
#[derive(Clone, Copy, Debug)]
struct PointLanes<L> {
    rn_a: L,
    rn_b: L,
    ra_n: L,
    rb_n: L,
    adjusted_separation: L,
    normal_mass: L,
    tangent_mass: L,
    normal_impulse: L,
    tangent_impulse: L,
    /// The normal impulses this step's substeps ended with, summed, less the one the step
    /// began with: the warm start of each substep adds the impulse the last one ended with
    /// (the first cancels the initial -P exactly), and the store adds the last. That is all
    /// the normal constraint applied in the step, without a write per solve pass.
    total_normal_impulse: L,
}

impl<L: Wide> PointLanes<L> {
    /// The tangent arms r x t of A and B. With t = (n_y, -n_x) they are -(r . n): two of
    /// `Arms`' six words are two others up to sign (to the bit, but for the sign of an exact
    /// zero: IEEE negation and rounding are symmetric), so a bundle carries four per point,
    /// 128 bytes less per eight-lane bundle for the passes to stream.
    #[inline(always)]
    fn tangent_arms(&self) -> (L, L) {
        (-self.ra_n, -self.rb_n)
    }
}

/// Up to `L::WIDTH` contacts packed for the lanes.
#[derive(Clone, Copy, Debug)]
struct Bundle<L: Wide> {
    kind: Kind,
    /// Contact index per lane; `u32::MAX` for an empty lane.
    contact: L::Index,
    /// Solver-body indices of A and B per lane (the fixed dummy body for empty lanes).
    a: L::Index,
    b: L::Index,
    nx: L,
    ny: L,
    friction: L,
    bias_rate: L,
    mass_scale: L,
    impulse_scale: L,
    /// How far the spring has crept (m; `ContactConstraint::creep`).
    creep: L,
    k00: L,
    k01: L,
    k11: L,
    i00: L,
    i01: L,
    i11: L,
    /// Inverse masses and inertias of A and B per lane (zero for static bodies and empty lanes).
    inv_mass_a: L,
    inv_i_a: L,
    inv_mass_b: L,
    inv_i_b: L,
    p: [PointLanes<L>; 2],
}

impl<L: Wide> Bundle<L> {
    /// Both sides' body lanes.
    #[inline(always)]
    fn gather(&self, bodies: &[SolverBody]) -> (BodyLanes<L>, BodyLanes<L>) {
        (
            BodyLanes::gather(bodies, &self.a, self.inv_mass_a, self.inv_i_a),
            BodyLanes::gather(bodies, &self.b, self.inv_mass_b, self.inv_i_b),
        )
    }

    /// Write both sides' velocities back.
    #[inline(always)]
    fn scatter(&self, bodies: &mut [SolverBody], a: &BodyLanes<L>, b: &BodyLanes<L>) {
        a.scatter(bodies, &self.a);
        b.scatter(bodies, &self.b);
    }
}

/// How many contacts a bundle holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Width {
    /// Four ([`Lanes`]: SSE2 on x86-64).
    Four,
    /// Eight ([`Lanes8`]), compiled for AVX2 and run where the processor has it.
    Eight,
}

impl Width {
    /// The widest this machine runs: eight lanes with AVX2, four otherwise.
    pub fn detect() -> Width {
        if eight_lanes_available() {
            Width::Eight
        } else {
            Width::Four
        }
    }
}

/// Buffers for the wide solve, kept by the World so a steady step does not allocate.
#[derive(Clone, Debug, Default)]
pub(crate) struct WideSolver {
    /// Four-lane bundles (used at [`Width::Four`]) per (colour, kind), flattened as
    /// colour * 2 + kind: solved in that order.
    bundles4: Vec<Vec<Bundle<Lanes>>>,
    /// Eight-lane bundles (used at [`Width::Eight`]), likewise.
    bundles8: Vec<Vec<Bundle<Lanes8>>>,
    /// How many of those (colour, kind) lists the last build filled, up to the last one with
    /// a bundle: the passes visit no more (a small scene uses a few of the 64).
    lists: usize,
    /// Colour mask per solver body: bit c set when a contact of colour c uses the body.
    colour_masks: Vec<u32>,
    /// Contacts that found no colour: solved by the scalar code.
    pub overflow: Vec<u32>,
    /// Colours to try before a contact overflows ([`COLOURS`]; tests lower it to force the
    /// scalar path).
    pub colours: Option<usize>,
    /// Bundle width; `None` picks four below [`EIGHT_LANES_FROM`] contacts and
    /// [`Width::detect`] from there, at each build (tests set it to compare).
    pub width: Option<Width>,
    /// The width of the bundles built last.
    built: Option<Width>,
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
    /// Load the lanes' bodies' velocities and how far they moved this step. The inverse
    /// masses do not change within a step: they come packed in the bundle.
    #[inline(always)]
    fn gather(bodies: &[SolverBody], idx: &L::Index, inv_mass: L, inv_inertia: L) -> BodyLanes<L> {
        // Each lane's body's first eight words (`SolverBody::state`), transposed into one
        // value per field: 8 loads and 24 shuffles on eight lanes. Reading each field of each
        // body into per-field rows and loading those cost 6-7 % more of a pyramid's step, in
        // instructions.
        let [vx, vy, w, dpx, dpy, qc, qs, _] =
            L::columns(|lane| bodies[idx.as_ref()[lane] as usize].state());
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

    /// Write velocities back, with the motion as it was read (it does not change in a solve
    /// pass): the first four words of each lane's body, transposed back, one store a body.
    /// A fixed body's lanes (static, kinematic, or the dummy of an empty lane; one may fill
    /// several lanes) come back as they were read, since its zero inverse mass and inertia
    /// take nothing from an impulse, so every lane is written without asking which kind of
    /// body it holds (asking was a mispredicted branch per lane wherever bundles mix
    /// contacts with the ground and between boxes).
    #[inline(always)]
    fn scatter(&self, bodies: &mut [SolverBody], idx: &L::Index) {
        L::scatter_rows([self.vx, self.vy, self.w, self.dpx], bodies, idx);
    }

    /// Apply impulse lambda along (dx, dy) with arms rd_a, rd_b: B gets +, A gets -.
    #[inline(always)]
    fn apply(
        a: &mut BodyLanes<L>,
        b: &mut BodyLanes<L>,
        dx: L,
        dy: L,
        rd_a: L,
        rd_b: L,
        lambda: L,
    ) {
        a.vx -= a.inv_mass * lambda * dx;
        a.vy -= a.inv_mass * lambda * dy;
        a.w -= a.inv_inertia * lambda * rd_a;
        b.vx += b.inv_mass * lambda * dx;
        b.vy += b.inv_mass * lambda * dy;
        b.w += b.inv_inertia * lambda * rd_b;
    }

    /// Relative velocity of B over A along (dx, dy) at arms rd_a, rd_b.
    #[inline(always)]
    fn relative(a: &BodyLanes<L>, b: &BodyLanes<L>, dx: L, dy: L, rd_a: L, rd_b: L) -> L {
        (b.vx - a.vx) * dx + (b.vy - a.vy) * dy + b.w * rd_b - a.w * rd_a
    }
}

impl WideSolver {
    /// Prepare, colour and pack the `selected` contacts, in one pass over them: `prepare`
    /// works out a contact's constraint for this step (from the contact and its bodies A and
    /// B, into the last argument), which goes straight into the lanes of its bundle. Contacts the colouring cannot place
    /// ([`WideSolver::overflow`]) and contacts that bounce (the restitution pass reads them
    /// after the solve) also keep their constraint in `constraints`, indexed like `contacts`.
    /// `bodies` must have one extra fixed body at the end (index `bodies.len() - 1`) for empty
    /// lanes.
    pub fn build(
        &mut self,
        bodies: &[SolverBody],
        contacts: &mut [Contact],
        constraints: &mut [ContactConstraint],
        selected: Selected,
        prepare: impl FnMut(&mut Contact, &SolverBody, &SolverBody, &mut ContactConstraint),
    ) {
        debug_assert!(
            bodies.last().is_some_and(|d| d.inv_mass == 0.0),
            "the last solver body is the fixed dummy"
        );
        self.colour_masks.clear();
        self.colour_masks.resize(bodies.len(), 0);
        self.overflow.clear();
        // Eight lanes only where the processor runs them (a test may ask for them anywhere),
        // and by default only for enough contacts to fill them.
        let width = match self.width {
            Some(Width::Eight) if !eight_lanes_available() => Width::Four,
            Some(width) => width,
            None if selected.count(contacts.len()) < EIGHT_LANES_FROM => Width::Four,
            None => Width::detect(),
        };
        self.built = Some(width);
        let mut colouring = Colouring {
            masks: &mut self.colour_masks,
            overflow: &mut self.overflow,
            colours: self.colours.unwrap_or(COLOURS).min(COLOURS),
        };
        let input = PackInput {
            bodies,
            contacts,
            constraints,
            selected,
        };
        match width {
            Width::Four => pack_all(&mut self.bundles4, &mut colouring, input, prepare),
            Width::Eight => pack_all(&mut self.bundles8, &mut colouring, input, prepare),
        };
        self.lists = match width {
            Width::Four => used_lists(&self.bundles4),
            Width::Eight => used_lists(&self.bundles8),
        }
    }

    /// Apply each contact's accumulated impulses (the warm start of a substep).
    pub fn warm_start(&mut self, bodies: &mut [SolverBody]) {
        match self.built {
            Some(Width::Eight) => eight::warm_start(&mut self.bundles8[..self.lists], bodies),
            _ => warm_start_bundles(&mut self.bundles4[..self.lists], bodies),
        }
    }

    /// Zero the accumulated impulses (warm starting off).
    pub fn clear_impulses(&mut self) {
        fn clear<L: Wide>(bundles: &mut [Vec<Bundle<L>>]) {
            for bundle in bundles.iter_mut().flatten() {
                for p in &mut bundle.p {
                    // The impulse the last substep ended with counts as its share of the
                    // total (`PointLanes::total_normal_impulse`).
                    p.total_normal_impulse += p.normal_impulse;
                    p.normal_impulse = L::ZERO;
                    p.tangent_impulse = L::ZERO;
                }
            }
        }
        clear(&mut self.bundles4);
        clear(&mut self.bundles8);
    }

    /// One `pass` over every bundle.
    pub fn solve(
        &mut self,
        bodies: &mut [SolverBody],
        inv_h: Real,
        pass: PassKind,
        max_push_out: Real,
    ) {
        match self.built {
            Some(Width::Eight) => {
                let bundles = &mut self.bundles8[..self.lists];
                eight::solve(bundles, bodies, inv_h, pass, max_push_out)
            }
            _ => solve_pass(
                &mut self.bundles4[..self.lists],
                bodies,
                inv_h,
                pass,
                max_push_out,
            ),
        }
    }

    /// Hand each contact, with its index, the ends of its points read out of the lanes
    /// (their impulses), for the end-of-step work to write back (for
    /// warm starting next step, what `World::contacts` reports, and restitution).
    pub fn store(
        &self,
        contacts: &mut [Contact],
        then: impl FnMut(&mut Contact, usize, &[PointEnd; 2]),
    ) {
        match self.built {
            Some(Width::Eight) => store_bundles(&self.bundles8[..self.lists], contacts, then),
            _ => store_bundles(&self.bundles4[..self.lists], contacts, then),
        }
    }
}

/// The eight-lane kernels: compiled for AVX2 on x86-64, where [`WideSolver::build`] makes
/// eight-lane bundles only if the processor has it; elsewhere never chosen (the portable
/// `Lanes8` keeps them compiling).
mod eight {
    use super::{solve_pass, warm_start_bundles, Bundle, Lanes8, PassKind, Real, SolverBody};

    /// [`warm_start_bundles`] on eight lanes.
    pub(super) fn warm_start(bundles: &mut [Vec<Bundle<Lanes8>>], bodies: &mut [SolverBody]) {
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        // SAFETY: eight-lane bundles exist only where the processor has AVX2.
        unsafe {
            warm_start_avx2(bundles, bodies)
        }
        #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
        warm_start_bundles(bundles, bodies)
    }

    /// [`solve_pass`] on eight lanes.
    pub(super) fn solve(
        bundles: &mut [Vec<Bundle<Lanes8>>],
        bodies: &mut [SolverBody],
        inv_h: Real,
        pass: PassKind,
        max_push_out: Real,
    ) {
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        // SAFETY: as above.
        unsafe {
            solve_avx2(bundles, bodies, inv_h, pass, max_push_out)
        }
        #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
        solve_pass(bundles, bodies, inv_h, pass, max_push_out)
    }

    /// # Safety
    /// The processor must have AVX2.
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    #[target_feature(enable = "avx2")]
    unsafe fn warm_start_avx2(bundles: &mut [Vec<Bundle<Lanes8>>], bodies: &mut [SolverBody]) {
        warm_start_bundles(bundles, bodies);
    }

    /// # Safety
    /// The processor must have AVX2.
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    #[target_feature(enable = "avx2")]
    unsafe fn solve_avx2(
        bundles: &mut [Vec<Bundle<Lanes8>>],
        bodies: &mut [SolverBody],
        inv_h: Real,
        pass: PassKind,
        max_push_out: Real,
    ) {
        solve_pass(bundles, bodies, inv_h, pass, max_push_out);
    }
}

/// One pass over every bundle: one copy of [`solve_bundles`] per kind of pass, each compiled
/// without the arithmetic its kind leaves out (the relax passes without the bias, the normal
/// relax also without friction).
#[inline(always)]
fn solve_pass<L: Wide>(
    bundles: &mut [Vec<Bundle<L>>],
    bodies: &mut [SolverBody],
    inv_h: Real,
    pass: PassKind,
    max_push_out: Real,
) {
    match pass {
        PassKind::Biased => solve_bundles(bundles, bodies, inv_h, true, true, max_push_out),
        PassKind::Relax => solve_bundles(bundles, bodies, inv_h, false, true, max_push_out),
        PassKind::NormalRelax => solve_bundles(bundles, bodies, inv_h, false, false, max_push_out),
    }
}

/// Apply each contact's accumulated impulses (the warm start of a substep).
#[inline(always)]
fn warm_start_bundles<L: Wide>(bundles: &mut [Vec<Bundle<L>>], bodies: &mut [SolverBody]) {
    for bundle in bundles.iter_mut().flatten() {
        let (mut a, mut b) = bundle.gather(bodies);
        let (nx, ny) = (bundle.nx, bundle.ny);
        let (tx, ty) = (ny, -nx);
        for p in &mut bundle.p {
            p.total_normal_impulse += p.normal_impulse;
            BodyLanes::apply(&mut a, &mut b, nx, ny, p.rn_a, p.rn_b, p.normal_impulse);
            let (rt_a, rt_b) = p.tangent_arms();
            BodyLanes::apply(&mut a, &mut b, tx, ty, rt_a, rt_b, p.tangent_impulse);
        }
        bundle.scatter(bodies, &a, &b);
    }
}

/// One pass over every bundle, with the soft bias (`use_bias`) or the relax pass without,
/// with friction or (a normal relax pass) without.
#[inline(always)]
fn solve_bundles<L: Wide>(
    bundles: &mut [Vec<Bundle<L>>],
    bodies: &mut [SolverBody],
    inv_h: Real,
    use_bias: bool,
    friction: bool,
    max_push_out: Real,
) {
    let inv_h = L::splat(inv_h);
    let push_out = L::splat(-max_push_out);
    for bundle in bundles.iter_mut().flatten() {
        let (mut a, mut b) = bundle.gather(bodies);
        let (nx, ny) = (bundle.nx, bundle.ny);
        let dp_n = (b.dpx - a.dpx) * nx + (b.dpy - a.dpy) * ny;

        let pass = Pass {
            inv_h,
            use_bias,
            push_out,
        };
        let coeffs = [
            coefficients(bundle, &bundle.p[0], &a, &b, dp_n, &pass),
            coefficients(bundle, &bundle.p[1], &a, &b, dp_n, &pass),
        ];

        match bundle.kind {
            Kind::Block => {
                let [p0, p1] = &bundle.p;
                let (l0, l1) = (p0.normal_impulse, p1.normal_impulse);
                let (rn_a0, rn_b0, rn_a1, rn_b1) = (p0.rn_a, p0.rn_b, p1.rn_a, p1.rn_b);
                let kl0 = bundle.k00 * l0 + bundle.k01 * l1;
                let kl1 = bundle.k01 * l0 + bundle.k11 * l1;
                let vn0 = BodyLanes::relative(&a, &b, nx, ny, rn_a0, rn_b0);
                let vn1 = BodyLanes::relative(&a, &b, nx, ny, rn_a1, rn_b1);
                // rhs = vn - K lambda - target, target = impulse_scale (vn - K lambda) - bias.
                let r0 = vn0 - kl0 - (coeffs[0].2 * (vn0 - kl0) - coeffs[0].0);
                let r1 = vn1 - kl1 - (coeffs[1].2 * (vn1 - kl1) - coeffs[1].0);
                let (x0, x1) = block_lcp(bundle, r0, r1, l0, l1);
                let (d0, d1) = (x0 - l0, x1 - l1);
                let d = d0 + d1;
                a.vx -= a.inv_mass * d * nx;
                a.vy -= a.inv_mass * d * ny;
                a.w -= a.inv_inertia * (d0 * rn_a0 + d1 * rn_a1);
                b.vx += b.inv_mass * d * nx;
                b.vy += b.inv_mass * d * ny;
                b.w += b.inv_inertia * (d0 * rn_b0 + d1 * rn_b1);
                bundle.p[0].normal_impulse = x0;
                bundle.p[1].normal_impulse = x1;
            }
            Kind::Points => {
                for (p, &(bias, mass_scale, impulse_scale)) in
                    bundle.p.iter_mut().zip(coeffs.iter())
                {
                    let vn = BodyLanes::relative(&a, &b, nx, ny, p.rn_a, p.rn_b);
                    let impulse = -p.normal_mass * (mass_scale * vn + bias)
                        - impulse_scale * p.normal_impulse;
                    let total = (p.normal_impulse + impulse).max(L::ZERO);
                    let applied = total - p.normal_impulse;
                    p.normal_impulse = total;
                    BodyLanes::apply(&mut a, &mut b, nx, ny, p.rn_a, p.rn_b, applied);
                }
            }
        }

        // Friction, one point after the other; skipped when no lane has any, and in a normal
        // relax pass.
        let (tx, ty) = (ny, -nx);
        if friction && L::any(bundle.friction.cmpgt(L::ZERO)) {
            for p in &mut bundle.p {
                let (rt_a, rt_b) = p.tangent_arms();
                let vt = BodyLanes::relative(&a, &b, tx, ty, rt_a, rt_b);
                let max_f = bundle.friction * p.normal_impulse;
                let total = (p.tangent_impulse - p.tangent_mass * vt).clamp(-max_f, max_f);
                let applied = total - p.tangent_impulse;
                p.tangent_impulse = total;
                BodyLanes::apply(&mut a, &mut b, tx, ty, rt_a, rt_b, applied);
            }
        }

        bundle.scatter(bodies, &a, &b);
    }
}

/// What a solve pass is: 1 / substep (1/s), biased or relax, and the push-out cap as a
/// negative velocity (m/s).
#[derive(Clone, Copy)]
struct Pass<L> {
    inv_h: L,
    use_bias: bool,
    push_out: L,
}

/// A point's (bias, mass scale, impulse scale), as in the scalar soft step: the speculative
/// bias `s / h` where the surfaces are apart, the soft spring's otherwise (none in a relax
/// pass). `dp_n` is the pair's relative motion this step along the normal.
#[inline(always)]
fn coefficients<L: Wide>(
    bundle: &Bundle<L>,
    p: &PointLanes<L>,
    a: &BodyLanes<L>,
    b: &BodyLanes<L>,
    dp_n: L,
    pass: &Pass<L>,
) -> (L, L, L) {
    let Pass {
        inv_h,
        use_bias,
        push_out,
    } = *pass;
    let s = dp_n + (b.qc * p.rb_n + b.qs * p.rn_b) - (a.qc * p.ra_n + a.qs * p.rn_a)
        + p.adjusted_separation;
    let speculative = s.cmpgt(L::ZERO);
    let (soft_bias, soft_ms, soft_is) = if use_bias {
        (
            (bundle.mass_scale * bundle.bias_rate * (s + bundle.creep)).max(push_out),
            bundle.mass_scale,
            bundle.impulse_scale,
        )
    } else {
        (L::ZERO, L::ONE, L::ZERO)
    };
    (
        L::select(speculative, s * inv_h, soft_bias),
        L::select(speculative, L::ONE, soft_ms),
        L::select(speculative, L::ZERO, soft_is),
    )
}

/// One field of a point's lanes and where it goes in a [`PointEnd`].
type EndField<L> = (L, fn(&mut PointEnd) -> &mut Real);

/// Hand each contact its points' ends (see [`WideSolver::store`]). Each field's lanes are
/// read out once per bundle, not once per lane.
fn store_bundles<L: Wide>(
    bundles: &[Vec<Bundle<L>>],
    contacts: &mut [Contact],
    mut then: impl FnMut(&mut Contact, usize, &[PointEnd; 2]),
) {
    // Bundles hold contacts from all over the array: while one bundle's are stored, the next
    // bundle's are fetched (storing waited on those loads for three quarters of its time).
    let mut bundles = bundles.iter().flatten().peekable();
    while let Some(bundle) = bundles.next() {
        if let Some(next) = bundles.peek() {
            for &ci in next.contact.as_ref() {
                if let Some(c) = contacts.get(ci as usize) {
                    prefetch(c);
                }
            }
        }
        // The lanes' point ends, field by field: each field's lanes are read out once.
        let mut ends = [[PointEnd::default(); 2]; 8];
        for (j, p) in bundle.p.iter().enumerate() {
            let fields: [EndField<L>; 3] = [
                (p.normal_impulse, |e| &mut e.normal_impulse),
                (p.tangent_impulse, |e| &mut e.tangent_impulse),
                (p.total_normal_impulse, |e| &mut e.total_normal_impulse),
            ];
            for (lanes, field) in fields {
                for (end, &x) in ends.iter_mut().zip(lanes.to_lanes().as_ref()) {
                    *field(&mut end[j]) = x;
                }
            }
            for end in &mut ends {
                let end = &mut end[j];
                end.total_normal_impulse += end.normal_impulse;
            }
        }
        for (end, &ci) in ends.iter().zip(bundle.contact.as_ref()) {
            if let Some(c) = contacts.get_mut(ci as usize) {
                then(c, ci as usize, end);
            }
        }
    }
}

/// The two-point LCP of `solve_block_lcp`, lane by lane: case 1 (both push), 2 (only point
/// 0), 3 (only point 1), 4 (neither); a lane no case fits keeps its impulses. A point's
/// normal mass is 1 / K_ii to the bit (the same sum, then its reciprocal), so the one-point
/// cases multiply by it where they divided by K_ii: two eight-lane divisions a bundle a pass
/// fewer.
#[inline(always)]
fn block_lcp<L: Wide>(bundle: &Bundle<L>, r0: L, r1: L, l0: L, l1: L) -> (L, L) {
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
    (x0, x1)
}

/// How many of the (colour, kind) lists are in use: up to the last non-empty one.
fn used_lists<L: Wide>(bundles: &[Vec<Bundle<L>>]) -> usize {
    bundles
        .iter()
        .rposition(|list| !list.is_empty())
        .map_or(0, |i| i + 1)
}

/// The greedy colouring's state: a colour mask per solver body, the contacts that found no
/// colour, and how many colours to try.
struct Colouring<'a> {
    masks: &'a mut [u32],
    overflow: &'a mut Vec<u32>,
    colours: usize,
}

impl Colouring<'_> {
    /// The first colour no dynamic body of the pair (`dynamic_a`, `dynamic_b`: whether each
    /// is) has used yet, now marked used by both; None when all are taken.
    #[inline(always)]
    fn colour(&mut self, a: u32, b: u32, dynamic_a: bool, dynamic_b: bool) -> Option<usize> {
        let mask = |dynamic: bool, i: u32| if dynamic { self.masks[i as usize] } else { 0 };
        let used = mask(dynamic_a, a) | mask(dynamic_b, b);
        let colour = (!used).trailing_zeros() as usize;
        if colour >= self.colours {
            return None;
        }
        let bit = 1u32 << colour;
        if dynamic_a {
            self.masks[a as usize] |= bit;
        }
        if dynamic_b {
            self.masks[b as usize] |= bit;
        }
        Some(colour)
    }
}

/// What a build reads: the bodies, the contacts (and the slots for kept constraints), and
/// which contacts to solve.
struct PackInput<'a, 'b> {
    bodies: &'a [SolverBody],
    contacts: &'a mut [Contact],
    constraints: &'a mut [ContactConstraint],
    selected: Selected<'b>,
}

/// Prepare and colour each selected contact in key order and write it into the open bundle
/// of its (colour, kind), `L::WIDTH` contacts to a bundle (so each colour's bundles hold the
/// same contacts, in the same order, as if the contacts had been grouped first).
///
/// Each bundle starts as a copy of one inert bundle and each contact's constraint is written
/// into its lanes where the bundle lives: the constraint never passes through memory, and the
/// open bundles (one per colour and kind) stay in cache while they fill. Preparing the
/// contacts into themselves and packing them in a second pass read and wrote each 400-byte
/// contact twice.
fn pack_all<L: Wide>(
    bundles: &mut Vec<Vec<Bundle<L>>>,
    colouring: &mut Colouring,
    input: PackInput,
    mut prepare: impl FnMut(&mut Contact, &SolverBody, &SolverBody, &mut ContactConstraint),
) {
    let PackInput {
        bodies,
        contacts,
        constraints,
        selected,
    } = input;
    let dummy = (bodies.len() - 1) as u32;
    bundles.resize_with(COLOURS * 2, Vec::new);
    for list in bundles.iter_mut() {
        list.clear();
    }
    let inert = Bundle::<L>::inert(dummy);
    let mut filled = [0usize; COLOURS * 2];
    // Where a contact's constraint is worked out when nothing keeps it.
    let mut scratch = ContactConstraint::default();
    selected.for_each_index(contacts.len(), |i| {
        let c = &mut contacts[i];
        let (a, b) = (&bodies[c.a as usize], &bodies[c.b as usize]);
        let colour = colouring.colour(c.a, c.b, a.inv_mass > 0.0, b.inv_mass > 0.0);
        let Some(colour) = colour else {
            prepare(c, a, b, &mut constraints[i]);
            colouring.overflow.push(i as u32);
            return;
        };
        let k = if c.restitution != 0.0 {
            &mut constraints[i]
        } else {
            &mut scratch
        };
        prepare(c, a, b, k);
        let kind = if c.count == 2 && k.block.is_some() {
            Kind::Block
        } else {
            Kind::Points
        };
        let slot = colour * 2 + kind as usize;
        let lane = filled[slot] % L::WIDTH;
        filled[slot] += 1;
        let list = &mut bundles[slot];
        if lane == 0 {
            list.push(Bundle { kind, ..inert });
        }
        let bundle = list.last_mut().expect("a bundle is open");
        bundle.set_contact(lane, i as u32, c, k, bodies);
    });
}

impl<L: Wide> Bundle<L> {
    /// A bundle with every lane empty: the fixed dummy body on both sides, zero masses and
    /// impulses, and an identity block so the LCP stays finite.
    fn inert(dummy: u32) -> Bundle<L> {
        let (zero, one) = (L::ZERO, L::ONE);
        let point = PointLanes {
            rn_a: zero,
            rn_b: zero,
            ra_n: zero,
            rb_n: zero,
            adjusted_separation: zero,
            normal_mass: zero,
            tangent_mass: zero,
            normal_impulse: zero,
            tangent_impulse: zero,
            total_normal_impulse: zero,
        };
        Bundle {
            kind: Kind::Points,
            contact: L::index_splat(u32::MAX),
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
            inv_mass_a: zero,
            inv_i_a: zero,
            inv_mass_b: zero,
            inv_i_b: zero,
            p: [point; 2],
        }
    }

    /// Write contact `c` (index `ci`) with its constraint `k` into lane `lane`. A contact
    /// without a usable block keeps the inert identity; a one-point contact leaves its second
    /// point's lanes zero.
    #[inline(always)]
    fn set_contact(
        &mut self,
        lane: usize,
        ci: u32,
        c: &Contact,
        k: &ContactConstraint,
        bodies: &[SolverBody],
    ) {
        self.contact.as_mut()[lane] = ci;
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
            (&mut self.inv_mass_a, body_a.inv_mass),
            (&mut self.inv_i_a, body_a.inv_inertia),
            (&mut self.inv_mass_b, body_b.inv_mass),
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
        }
        for ((v, p), kp) in self.p.iter_mut().zip(&c.points[..c.count]).zip(&k.points) {
            let arms = kp.arms;
            for (field, x) in [
                (&mut v.rn_a, arms.rn_a),
                (&mut v.rn_b, arms.rn_b),
                (&mut v.ra_n, arms.ra_n),
                (&mut v.rb_n, arms.rb_n),
                (&mut v.adjusted_separation, kp.adjusted_separation),
                (&mut v.normal_mass, kp.normal_mass),
                (&mut v.tangent_mass, kp.tangent_mass),
                (&mut v.normal_impulse, p.normal_impulse),
                (&mut v.tangent_impulse, p.tangent_impulse),
                (&mut v.total_normal_impulse, -p.normal_impulse),
            ] {
                field.set_lane(lane, x);
            }
        }
    }
}
