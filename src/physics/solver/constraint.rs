//! The per-step half of a contact: what the prepare stage works out from a contact's anchors
//! and its bodies' masses, used by the solve and dropped after the step (Box2D v3 keeps the
//! same split between `b2ContactSim` and `b2ContactConstraint`).
//!
//! A [`Contact`](crate::physics::contact::Contact) keeps only what lasts from step to step
//! (bodies, normal, feature ids, anchors, impulses). The wide solver writes each contact's
//! constraint straight into its bundle's lanes; a [`ContactConstraint`] is kept in memory only
//! for the contacts the scalar code solves (the sequential solver's, the soft step's few
//! uncoloured ones, and those that bounce).

use super::soft_step::Softness;
use super::BlockMass;
use crate::physics::math::{cross, Real, Vec2};

/// A point's lever arms along the normal n and tangent t: rA x n, rB x n, rA x t, rB x t,
/// rA . n, rB . n. With them a point's normal velocity is
/// (vB - vA) . n + wB (rB x n) - wA (rA x n), and an impulse's torque is lambda (r x n): no
/// cross products in the inner loop.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Arms {
    pub rn_a: Real,
    pub rn_b: Real,
    pub rt_a: Real,
    pub rt_b: Real,
    pub ra_n: Real,
    pub rb_n: Real,
}

impl Arms {
    /// The arms of anchors `ra`, `rb` (m) for normal `n` and tangent `t`.
    #[inline]
    pub fn new(ra: Vec2, rb: Vec2, n: Vec2, t: Vec2) -> Arms {
        Arms {
            rn_a: cross(ra, n),
            rn_b: cross(rb, n),
            rt_a: cross(ra, t),
            rt_b: cross(rb, t),
            ra_n: ra.dot(n),
            rb_n: rb.dot(n),
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
    /// Normal relative velocity before the solve (m/s): the approach speed restitution
    /// reverses.
    pub relative_velocity: Real,
    /// Sequential solver: target normal velocity (m/s) from position bias or restitution.
    pub bias: Real,
}

/// A point at the end of the solve: its accumulated impulses (per substep, N s). The wide
/// solver hands these out of its lanes to the end-of-step work, which writes the contact
/// once; the scalar code builds them from the contact.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PointEnd {
    /// Accumulated normal impulse (N s, per substep).
    pub normal_impulse: Real,
    /// Accumulated friction impulse (N s, per substep).
    pub tangent_impulse: Real,
    /// Everything the normal constraint applied this step (N s).
    pub total_normal_impulse: Real,
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
            block: None,
        }
    }
}
