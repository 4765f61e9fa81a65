//! The per-step half of a contact: what the prepare stage works out from a contact's anchors
//! and its bodies' masses, used by the solve and dropped after the step (Box2D v3 keeps the
//! same split between `b2ContactSim` and `b2ContactConstraint`).
//!
//! A [`Contact`](crate::physics::contact::Contact) keeps only what lasts from step to step
//! (bodies, normal, feature ids, anchors, impulses). The sequential solver keeps a
//! [`ContactConstraint`] per contact for its step; the soft step works each one out as it
//! packs the contact and writes it straight into the contact's lane.

use super::block::BlockMass;
use super::softness::Softness;
use super::SolverBody;
use crate::physics::contact::{Contact, ContactPoint};
use crate::physics::math::{cross, Real, Vec2};

/// A point's lever arms along the normal n: rA x n, rB x n, rA . n, rB . n (m). With them a
/// point's normal velocity is (vB - vA) . n + wB (rB x n) - wA (rA x n), and an impulse's
/// torque is lambda (r x n): no cross products in the inner loop. Along the tangent
/// t = (n_y, -n_x) the arms are r x t = -(r . n).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Arms {
    pub a_cross_n: Real,
    pub b_cross_n: Real,
    pub a_dot_n: Real,
    pub b_dot_n: Real,
}

impl Arms {
    /// The arms of anchors `ra`, `rb` (m) for normal `n`.
    #[inline]
    pub fn new(ra: Vec2, rb: Vec2, n: Vec2) -> Arms {
        Arms {
            a_cross_n: cross(ra, n),
            b_cross_n: cross(rb, n),
            a_dot_n: ra.dot(n),
            b_dot_n: rb.dot(n),
        }
    }
}

/// One point's constraint for the current step.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PointConstraint {
    /// The point's lever arms (m).
    pub arms: Arms,
    /// Effective mass along the normal, 1 / (1/mA + 1/mB + (rA x n)^2/IA + (rB x n)^2/IB)
    /// (kg; appendix eq. 56).
    pub normal_mass: Real,
    /// Effective mass along the tangent (kg; appendix eq. 57).
    pub tangent_mass: Real,
    /// Soft step: separation minus the anchors' contribution (m), so the current separation
    /// is (dpB - dpA + qB rB - qA rA) . n + adjusted_separation.
    pub adjusted_separation: Real,
    /// Sequential solver: target normal velocity (m/s) from position bias or restitution.
    pub bias: Real,
}

impl PointConstraint {
    /// The normal and tangent effective masses (eqs. 56-57) of point `p` between `a` and `b`,
    /// for normal `n` and tangent `t`.
    #[inline]
    pub fn set_masses(
        &mut self,
        a: &SolverBody,
        b: &SolverBody,
        p: &ContactPoint,
        n: Vec2,
        t: Vec2,
    ) {
        self.normal_mass = effective_mass(a, b, p.anchor_a, p.anchor_b, n);
        self.tangent_mass = effective_mass(a, b, p.anchor_a, p.anchor_b, t);
    }
}

/// Effective mass 1 / (1/mA + 1/mB + (rA x d)^2 / IA + (rB x d)^2 / IB) along direction `d`
/// (appendix eqs. 56-57, with r.r - (r.d)^2 = (r x d)^2 for unit d); 0 between fixed bodies.
#[inline]
pub(crate) fn effective_mass(a: &SolverBody, b: &SolverBody, ra: Vec2, rb: Vec2, d: Vec2) -> Real {
    mass_of(inverse_mass_along(a, b, ra, rb, d))
}

/// The inverse effective mass along `d` (1/kg): effective_mass's denominator.
#[inline(always)]
fn inverse_mass_along(a: &SolverBody, b: &SolverBody, ra: Vec2, rb: Vec2, d: Vec2) -> Real {
    let rna = cross(ra, d);
    let rnb = cross(rb, d);
    a.inv_mass + b.inv_mass + a.inv_inertia * rna * rna + b.inv_inertia * rnb * rnb
}

/// 1 / k, or 0 where nothing moves along the direction (k = 0).
#[inline(always)]
fn mass_of(k: Real) -> Real {
    if k > 0.0 {
        1.0 / k
    } else {
        0.0
    }
}

/// [`PointConstraint::set_masses`] for each live point of contact `c` between `a` and `b`,
/// and of a two-point contact its normal block ([`BlockMass::new`]), whose diagonal is the
/// points' inverse normal masses. The four reciprocals are taken side by side: one vector
/// division, where one at a time they were a chain of four.
#[inline(always)]
pub(crate) fn set_contact_masses(
    points: &mut [PointConstraint; 2],
    a: &SolverBody,
    b: &SolverBody,
    c: &Contact,
) -> Option<BlockMass> {
    let (n, t) = (c.normal, c.tangent());
    let along = |p: &ContactPoint, d: Vec2| inverse_mass_along(a, b, p.anchor_a, p.anchor_b, d);
    let [p0, p1] = &c.points;
    let normal = [along(p0, n), along(p1, n)];
    let masses = [normal[0], along(p0, t), normal[1], along(p1, t)].map(mass_of);
    for (kp, m) in points[..c.count as usize]
        .iter_mut()
        .zip(masses.chunks_exact(2))
    {
        kp.normal_mass = m[0];
        kp.tangent_mass = m[1];
    }
    if c.count != 2 {
        return None;
    }
    let (rna, rnb) = (
        [p0, p1].map(|p| cross(p.anchor_a, n)),
        [p0, p1].map(|p| cross(p.anchor_b, n)),
    );
    let m = a.inv_mass + b.inv_mass;
    let kij =
        |i: usize, j: usize| m + a.inv_inertia * rna[i] * rna[j] + b.inv_inertia * rnb[i] * rnb[j];
    BlockMass::of_matrix([[normal[0], kij(0, 1)], [kij(1, 0), normal[1]]])
}

/// One contact's constraint for the current step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ContactConstraint {
    /// The points, as many as the contact's.
    pub points: [PointConstraint; 2],
    /// Soft step: the contact's spring.
    pub softness: Softness,
    /// Soft step: how far the spring has crept under its load this step (m), added to each
    /// point's separation in the biased pass (see `soft_step::creep`).
    pub creep: Real,
    /// Soft step: where the contact overlaps deeper than its spring reaches, that reach (m),
    /// and the contact is held rigidly and pushed out in position (`recover.rs`); else 0.
    pub reach: Real,
    /// Two-point contacts: the normal block and its inverse (None: solve the points one at a
    /// time).
    pub block: Option<BlockMass>,
}

impl Default for ContactConstraint {
    fn default() -> ContactConstraint {
        ContactConstraint {
            points: [PointConstraint::default(); 2],
            softness: Softness::RIGID,
            creep: 0.0,
            reach: 0.0,
            block: None,
        }
    }
}
