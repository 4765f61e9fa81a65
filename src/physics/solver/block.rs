//! The two points of a face contact solved together: the 2x2 effective-mass block along the
//! normal and its linear complementarity problem (Box2D v2's block solver), for the sequential
//! solver and for preparing the soft step's constraints.

use super::SolverBody;
use crate::physics::contact::Contact;
use crate::physics::math::{cross, Real, Vec2};

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
        let rna = [cross(ra[0], n), cross(ra[1], n)];
        let rnb = [cross(rb[0], n), cross(rb[1], n)];
        let m = a.inv_mass + b.inv_mass;
        let kij = |i: usize, j: usize| {
            m + a.inv_inertia * rna[i] * rna[j] + b.inv_inertia * rnb[i] * rnb[j]
        };
        BlockMass::of_matrix([[kij(0, 0), kij(0, 1)], [kij(1, 0), kij(1, 1)]])
    }

    /// The block of matrix `k` (1/kg), or None when it is too ill-conditioned to invert
    /// safely (nearly coincident points): k11^2 < 1000 det, Box2D's bound.
    #[inline(always)]
    pub fn of_matrix(k: [[Real; 2]; 2]) -> Option<BlockMass> {
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
    // divided: the point's normal mass, as the contact kernel has it.
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
