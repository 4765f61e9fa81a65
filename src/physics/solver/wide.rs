//! The soft step's inner loops, four contacts at a time.
//!
//! Contacts are first coloured so that no two contacts of one colour share a dynamic body
//! (greedy, in key order, so the result is deterministic; static bodies may be shared since
//! nothing writes to them). Within a colour the contacts are independent, so they are packed
//! four to a bundle and solved in the lanes of one `Lanes` value: the same arithmetic as the
//! scalar soft step, with every `if` turned into a lane-wise select. Two-point contacts with a
//! well-conditioned block are solved by the 2x2 LCP; the others (one point, or nearly
//! coincident points) one point after the other, in bundles of their own. Contacts beyond the
//! last colour are solved by the scalar code after the bundles.

use super::SolverBody;
use crate::physics::contact::Contact;
use crate::physics::math::{Lanes, Real};

/// How many colours the greedy colouring tries before giving up on a contact.
const COLOURS: usize = 32;

/// Which kernel a bundle needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// Two points with a usable block: solved together.
    Block,
    /// One point, or two solved one after the other.
    Points,
}

/// Per-point data of four contacts, lane i being contact i of the bundle.
#[derive(Clone, Copy, Debug, Default)]
struct PointLanes {
    rn_a: Lanes,
    rn_b: Lanes,
    rt_a: Lanes,
    rt_b: Lanes,
    ra_n: Lanes,
    rb_n: Lanes,
    adjusted_separation: Lanes,
    normal_mass: Lanes,
    tangent_mass: Lanes,
    normal_impulse: Lanes,
    tangent_impulse: Lanes,
    total_normal_impulse: Lanes,
    max_normal_impulse: Lanes,
}

/// Four contacts packed for the lanes.
#[derive(Clone, Copy, Debug)]
struct Bundle {
    kind: Kind,
    /// Contact index per lane; `u32::MAX` for an empty lane.
    contact: [u32; 4],
    /// Solver-body indices of A and B per lane (the fixed dummy body for empty lanes).
    a: [u32; 4],
    b: [u32; 4],
    nx: Lanes,
    ny: Lanes,
    friction: Lanes,
    bias_rate: Lanes,
    mass_scale: Lanes,
    impulse_scale: Lanes,
    k00: Lanes,
    k01: Lanes,
    k11: Lanes,
    i00: Lanes,
    i01: Lanes,
    i11: Lanes,
    /// Inverse masses and inertias of A and B per lane (zero for static bodies and empty lanes).
    inv_mass_a: Lanes,
    inv_i_a: Lanes,
    inv_mass_b: Lanes,
    inv_i_b: Lanes,
    p: [PointLanes; 2],
}

impl Bundle {
    /// Both sides' body lanes (with this step's motion when `motion`).
    #[inline]
    fn gather(&self, bodies: &[SolverBody], motion: bool) -> (BodyLanes, BodyLanes) {
        (
            BodyLanes::gather(bodies, &self.a, self.inv_mass_a, self.inv_i_a, motion),
            BodyLanes::gather(bodies, &self.b, self.inv_mass_b, self.inv_i_b, motion),
        )
    }

    /// Write both sides' velocities back.
    #[inline]
    fn scatter(&self, bodies: &mut [SolverBody], a: &BodyLanes, b: &BodyLanes) {
        a.scatter(bodies, &self.a);
        b.scatter(bodies, &self.b);
    }
}

/// Buffers for the wide solve, kept by the World so a steady step does not allocate.
#[derive(Clone, Debug, Default)]
pub(crate) struct WideSolver {
    bundles: Vec<Bundle>,
    /// Colour mask per solver body: bit c set when a contact of colour c uses the body.
    colour_masks: Vec<u32>,
    /// Contact indices per (colour, kind), flattened as colour * 2 + kind.
    by_colour: Vec<Vec<u32>>,
    /// Contacts that found no colour: solved by the scalar code.
    pub overflow: Vec<u32>,
    /// Colours to try before a contact overflows ([`COLOURS`]; tests lower it to force the
    /// scalar path).
    pub colours: Option<usize>,
}

/// The body state a kernel reads for four lanes.
struct BodyLanes {
    vx: Lanes,
    vy: Lanes,
    w: Lanes,
    dpx: Lanes,
    dpy: Lanes,
    qc: Lanes,
    qs: Lanes,
    inv_mass: Lanes,
    inv_inertia: Lanes,
}

impl BodyLanes {
    /// Load four bodies' velocities (and, with `motion`, how far they moved this step). The
    /// inverse masses do not change within a step: they come packed in the bundle.
    #[inline]
    fn gather(
        bodies: &[SolverBody],
        idx: &[u32; 4],
        inv_mass: Lanes,
        inv_inertia: Lanes,
        motion: bool,
    ) -> BodyLanes {
        let b = idx.map(|i| &bodies[i as usize]);
        let lanes = |f: fn(&SolverBody) -> Real| Lanes::new(f(b[0]), f(b[1]), f(b[2]), f(b[3]));
        let (dpx, dpy, qc, qs) = if motion {
            (
                lanes(|s| s.dp.x),
                lanes(|s| s.dp.y),
                lanes(|s| s.dq.c),
                lanes(|s| s.dq.s),
            )
        } else {
            (Lanes::ZERO, Lanes::ZERO, Lanes::ONE, Lanes::ZERO)
        };
        BodyLanes {
            vx: lanes(|s| s.v.x),
            vy: lanes(|s| s.v.y),
            w: lanes(|s| s.w),
            dpx,
            dpy,
            qc,
            qs,
            inv_mass,
            inv_inertia,
        }
    }

    /// Write velocities back, for dynamic bodies only (static ones were not changed and may
    /// appear in several lanes).
    #[inline]
    fn scatter(&self, bodies: &mut [SolverBody], idx: &[u32; 4]) {
        let (vx, vy, w) = (self.vx.to_array(), self.vy.to_array(), self.w.to_array());
        for lane in 0..4 {
            let body = &mut bodies[idx[lane] as usize];
            if body.inv_mass > 0.0 {
                body.v.x = vx[lane];
                body.v.y = vy[lane];
                body.w = w[lane];
            }
        }
    }

    /// Apply impulse lambda along (dx, dy) with arms rd_a, rd_b: B gets +, A gets -.
    #[inline]
    fn apply(
        a: &mut BodyLanes,
        b: &mut BodyLanes,
        dx: Lanes,
        dy: Lanes,
        rd_a: Lanes,
        rd_b: Lanes,
        lambda: Lanes,
    ) {
        a.vx -= a.inv_mass * lambda * dx;
        a.vy -= a.inv_mass * lambda * dy;
        a.w -= a.inv_inertia * lambda * rd_a;
        b.vx += b.inv_mass * lambda * dx;
        b.vy += b.inv_mass * lambda * dy;
        b.w += b.inv_inertia * lambda * rd_b;
    }

    /// Relative velocity of B over A along (dx, dy) at arms rd_a, rd_b.
    #[inline]
    fn relative(
        a: &BodyLanes,
        b: &BodyLanes,
        dx: Lanes,
        dy: Lanes,
        rd_a: Lanes,
        rd_b: Lanes,
    ) -> Lanes {
        (b.vx - a.vx) * dx + (b.vy - a.vy) * dy + b.w * rd_b - a.w * rd_a
    }
}

impl WideSolver {
    /// Colour the contacts and pack them into bundles. `bodies` must have one extra fixed
    /// body at the end (index `bodies.len() - 1`) for empty lanes.
    pub fn build(&mut self, bodies: &[SolverBody], contacts: &[Contact]) {
        let dummy = (bodies.len() - 1) as u32;
        debug_assert!(
            bodies.last().is_some_and(|d| d.inv_mass == 0.0),
            "the last solver body is the fixed dummy"
        );
        self.colour_masks.clear();
        self.colour_masks.resize(bodies.len(), 0);
        self.by_colour.resize_with(COLOURS * 2, Vec::new);
        for list in &mut self.by_colour {
            list.clear();
        }
        self.overflow.clear();
        for (i, c) in contacts.iter().enumerate() {
            let dynamic_a = bodies[c.a as usize].inv_mass > 0.0;
            let dynamic_b = bodies[c.b as usize].inv_mass > 0.0;
            let used = (if dynamic_a {
                self.colour_masks[c.a as usize]
            } else {
                0
            }) | (if dynamic_b {
                self.colour_masks[c.b as usize]
            } else {
                0
            });
            let colour = (!used).trailing_zeros() as usize;
            if colour >= self.colours.unwrap_or(COLOURS) {
                self.overflow.push(i as u32);
                continue;
            }
            let bit = 1u32 << colour;
            if dynamic_a {
                self.colour_masks[c.a as usize] |= bit;
            }
            if dynamic_b {
                self.colour_masks[c.b as usize] |= bit;
            }
            let kind = if c.count == 2 && c.block.is_some() {
                0
            } else {
                1
            };
            self.by_colour[colour * 2 + kind].push(i as u32);
        }

        self.bundles.clear();
        for (slot, list) in self.by_colour.iter().enumerate() {
            let kind = if slot % 2 == 0 {
                Kind::Block
            } else {
                Kind::Points
            };
            for chunk in list.chunks(4) {
                self.bundles
                    .push(pack(kind, chunk, contacts, bodies, dummy));
            }
        }
    }

    /// Apply each contact's accumulated impulses (the warm start of a substep).
    pub fn warm_start(&mut self, bodies: &mut [SolverBody]) {
        for bundle in &mut self.bundles {
            let (mut a, mut b) = bundle.gather(bodies, false);
            let (nx, ny) = (bundle.nx, bundle.ny);
            let (tx, ty) = (ny, -nx);
            for p in &mut bundle.p {
                p.total_normal_impulse += p.normal_impulse;
                BodyLanes::apply(&mut a, &mut b, nx, ny, p.rn_a, p.rn_b, p.normal_impulse);
                BodyLanes::apply(&mut a, &mut b, tx, ty, p.rt_a, p.rt_b, p.tangent_impulse);
            }
            bundle.scatter(bodies, &a, &b);
        }
    }

    /// Zero the accumulated impulses (warm starting off).
    pub fn clear_impulses(&mut self) {
        for bundle in &mut self.bundles {
            for p in &mut bundle.p {
                p.normal_impulse = Lanes::ZERO;
                p.tangent_impulse = Lanes::ZERO;
            }
        }
    }

    /// One pass over every bundle, with the soft bias (`use_bias`) or the relax pass without.
    pub fn solve(
        &mut self,
        bodies: &mut [SolverBody],
        inv_h: Real,
        use_bias: bool,
        max_push_out: Real,
    ) {
        let inv_h = Lanes::splat(inv_h);
        let push_out = Lanes::splat(-max_push_out);
        for bundle in &mut self.bundles {
            let (mut a, mut b) = bundle.gather(bodies, true);
            let (nx, ny) = (bundle.nx, bundle.ny);
            let dp_n = (b.dpx - a.dpx) * nx + (b.dpy - a.dpy) * ny;

            // Per point: (bias, mass scale, impulse scale), as in the scalar soft step.
            // By reference: mapping the array by value copied both points' lanes (416 bytes)
            // every pass, a fifth of the whole step in a profile of pyramid_20.
            let coeff = |p: &PointLanes| {
                let s = dp_n + (b.qc * p.rb_n + b.qs * p.rn_b) - (a.qc * p.ra_n + a.qs * p.rn_a)
                    + p.adjusted_separation;
                let speculative = s.cmpgt(Lanes::ZERO);
                let (soft_bias, soft_ms, soft_is) = if use_bias {
                    (
                        (bundle.mass_scale * bundle.bias_rate * s).max(push_out),
                        bundle.mass_scale,
                        bundle.impulse_scale,
                    )
                } else {
                    (Lanes::ZERO, Lanes::ONE, Lanes::ZERO)
                };
                (
                    Lanes::select(speculative, s * inv_h, soft_bias),
                    Lanes::select(speculative, Lanes::ONE, soft_ms),
                    Lanes::select(speculative, Lanes::ZERO, soft_is),
                )
            };
            let coeffs = [coeff(&bundle.p[0]), coeff(&bundle.p[1])];

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
                    for (p, (x, dx)) in bundle.p.iter_mut().zip([(x0, d0), (x1, d1)]) {
                        p.normal_impulse = x;
                        p.max_normal_impulse = p.max_normal_impulse.max(dx);
                        p.total_normal_impulse += dx;
                    }
                }
                Kind::Points => {
                    for (p, &(bias, mass_scale, impulse_scale)) in
                        bundle.p.iter_mut().zip(coeffs.iter())
                    {
                        let vn = BodyLanes::relative(&a, &b, nx, ny, p.rn_a, p.rn_b);
                        let impulse = -p.normal_mass * (mass_scale * vn + bias)
                            - impulse_scale * p.normal_impulse;
                        let total = (p.normal_impulse + impulse).max(Lanes::ZERO);
                        let applied = total - p.normal_impulse;
                        p.normal_impulse = total;
                        p.max_normal_impulse = p.max_normal_impulse.max(applied);
                        p.total_normal_impulse += applied;
                        BodyLanes::apply(&mut a, &mut b, nx, ny, p.rn_a, p.rn_b, applied);
                    }
                }
            }

            // Friction, one point after the other; skipped when no lane has any.
            let (tx, ty) = (ny, -nx);
            if bundle.friction.cmpgt(Lanes::ZERO).any() {
                for p in &mut bundle.p {
                    let vt = BodyLanes::relative(&a, &b, tx, ty, p.rt_a, p.rt_b);
                    let max_f = bundle.friction * p.normal_impulse;
                    let total = (p.tangent_impulse - p.tangent_mass * vt).clamp(-max_f, max_f);
                    let applied = total - p.tangent_impulse;
                    p.tangent_impulse = total;
                    BodyLanes::apply(&mut a, &mut b, tx, ty, p.rt_a, p.rt_b, applied);
                }
            }

            bundle.scatter(bodies, &a, &b);
        }
    }

    /// Copy the lanes' impulses back to the contacts (for restitution, warm starting next
    /// step, and what `World::contacts` reports).
    pub fn store(&self, contacts: &mut [Contact]) {
        for bundle in &self.bundles {
            for lane in 0..4 {
                let Some(c) = contacts.get_mut(bundle.contact[lane] as usize) else {
                    continue;
                };
                for (j, p) in c.points[..c.count].iter_mut().enumerate() {
                    let src = &bundle.p[j];
                    p.normal_impulse = src.normal_impulse.to_array()[lane];
                    p.tangent_impulse = src.tangent_impulse.to_array()[lane];
                    p.total_normal_impulse = src.total_normal_impulse.to_array()[lane];
                    p.max_normal_impulse = src.max_normal_impulse.to_array()[lane];
                }
            }
        }
    }
}

/// The two-point LCP of `solve_block_lcp`, lane by lane: case 1 (both push), 2 (only point
/// 0), 3 (only point 1), 4 (neither); a lane no case fits keeps its impulses.
#[inline]
fn block_lcp(bundle: &Bundle, r0: Lanes, r1: Lanes, l0: Lanes, l1: Lanes) -> (Lanes, Lanes) {
    let zero = Lanes::ZERO;
    let x0_1 = -(bundle.i00 * r0 + bundle.i01 * r1);
    let x1_1 = -(bundle.i01 * r0 + bundle.i11 * r1);
    let case1 = x0_1.cmpge(zero) & x1_1.cmpge(zero);
    let x0_2 = -r0 / bundle.k00;
    let case2 = x0_2.cmpge(zero) & (bundle.k01 * x0_2 + r1).cmpge(zero);
    let x1_3 = -r1 / bundle.k11;
    let case3 = x1_3.cmpge(zero) & (bundle.k01 * x1_3 + r0).cmpge(zero);
    let case4 = r0.cmpge(zero) & r1.cmpge(zero);
    let x0 = Lanes::select(
        case1,
        x0_1,
        Lanes::select(case2, x0_2, Lanes::select(case3 | case4, zero, l0)),
    );
    let x1 = Lanes::select(
        case1,
        x1_1,
        Lanes::select(case2 | case4, zero, Lanes::select(case3, x1_3, l1)),
    );
    (x0, x1)
}

/// Pack up to four contacts into one bundle; missing lanes are inert (fixed dummy bodies,
/// zero masses and impulses, an identity block).
fn pack(
    kind: Kind,
    chunk: &[u32],
    contacts: &[Contact],
    bodies: &[SolverBody],
    dummy: u32,
) -> Bundle {
    let mut contact = [u32::MAX; 4];
    let mut a = [dummy; 4];
    let mut b = [dummy; 4];
    // Header fields: nx, ny, friction, bias_rate, mass_scale, impulse_scale, k00, k01, k11,
    // i00, i01, i11 (identity block for empty lanes so the LCP stays finite), then the inverse
    // masses and inertias of A and B.
    let mut f = [[0.0 as Real; 4]; 16];
    for field in [6, 8, 9, 11] {
        f[field] = [1.0; 4];
    }
    let mut pts = [[[0.0 as Real; 4]; 13]; 2];
    for (lane, &ci) in chunk.iter().enumerate() {
        let c = &contacts[ci as usize];
        contact[lane] = ci;
        a[lane] = c.a;
        b[lane] = c.b;
        let sf = c.softness;
        let (k, inv) = match &c.block {
            Some(m) => (m.k, m.inv),
            None => ([[1.0, 0.0], [0.0, 1.0]], [[1.0, 0.0], [0.0, 1.0]]),
        };
        let header = [
            c.normal.x,
            c.normal.y,
            c.friction,
            sf.bias_rate,
            sf.mass_scale,
            sf.impulse_scale,
            k[0][0],
            k[0][1],
            k[1][1],
            inv[0][0],
            inv[0][1],
            inv[1][1],
            bodies[c.a as usize].inv_mass,
            bodies[c.a as usize].inv_inertia,
            bodies[c.b as usize].inv_mass,
            bodies[c.b as usize].inv_inertia,
        ];
        for (field, value) in f.iter_mut().zip(header) {
            field[lane] = value;
        }
        for (j, p) in c.points[..c.count].iter().enumerate() {
            let mut values = [0.0; 13];
            values[..6].copy_from_slice(&p.arms.to_words());
            values[6..].copy_from_slice(&[
                p.adjusted_separation,
                p.normal_mass,
                p.tangent_mass,
                p.normal_impulse,
                p.tangent_impulse,
                p.total_normal_impulse,
                p.max_normal_impulse,
            ]);
            for (field, value) in pts[j].iter_mut().zip(values) {
                field[lane] = value;
            }
        }
    }
    let l = Lanes::from_array;
    let point = |v: &[[Real; 4]; 13]| PointLanes {
        rn_a: l(v[0]),
        rn_b: l(v[1]),
        rt_a: l(v[2]),
        rt_b: l(v[3]),
        ra_n: l(v[4]),
        rb_n: l(v[5]),
        adjusted_separation: l(v[6]),
        normal_mass: l(v[7]),
        tangent_mass: l(v[8]),
        normal_impulse: l(v[9]),
        tangent_impulse: l(v[10]),
        total_normal_impulse: l(v[11]),
        max_normal_impulse: l(v[12]),
    };
    Bundle {
        kind,
        contact,
        a,
        b,
        nx: l(f[0]),
        ny: l(f[1]),
        friction: l(f[2]),
        bias_rate: l(f[3]),
        mass_scale: l(f[4]),
        impulse_scale: l(f[5]),
        k00: l(f[6]),
        k01: l(f[7]),
        k11: l(f[8]),
        i00: l(f[9]),
        i01: l(f[10]),
        i11: l(f[11]),
        inv_mass_a: l(f[12]),
        inv_i_a: l(f[13]),
        inv_mass_b: l(f[14]),
        inv_i_b: l(f[15]),
        p: [point(&pts[0]), point(&pts[1])],
    }
}
