//! Persistent contacts: one per touching (or about to touch) pair of bodies, carrying the
//! solver's accumulated impulses from one step to the next so the next solve can warm start.

use super::body::BodyId;
use super::collide::FeatureId;
use super::math::{Real, Rot, Vec2};
use super::solver::soft_step::Softness;
use super::solver::BlockMass;

/// One contact point and the solver state attached to it.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ContactPoint {
    /// Which features produced the point (matches points across steps).
    pub id: FeatureId,
    /// World position at collision time (m).
    pub point: Vec2,
    /// Signed separation at collision time (m); negative = overlap.
    pub separation: Real,
    /// Contact point relative to body A's centre, world frame (m).
    pub anchor_a: Vec2,
    /// Contact point relative to body B's centre, world frame (m).
    pub anchor_b: Vec2,
    /// Accumulated normal impulse (N s); never negative: contacts only push.
    pub normal_impulse: Real,
    /// Accumulated friction impulse (N s); within the Coulomb cone +-mu Pn.
    pub tangent_impulse: Real,
    /// Everything the normal constraint applied this step, warm start included (N s): the
    /// contact force times dt, whatever the solver's substeps.
    pub total_normal_impulse: Real,
    /// Largest normal impulse applied in this step (N s): restitution only acts where the
    /// contact actually pushed.
    pub max_normal_impulse: Real,
    /// Lever arms, precomputed once per step: rA x n, rB x n, rA x t, rB x t, rA . n, rB . n,
    /// rA . t, rB . t.
    /// With them a point's normal velocity is (vB - vA) . n + wB (rB x n) - wA (rA x n), and
    /// an impulse's torque is lambda (r x n): no cross products in the inner loop.
    pub arms: Arms,
    /// Effective mass along the normal, 1 / (1/mA + 1/mB + (rA x n)^2/IA + (rB x n)^2/IB) (appendix eq. 56).
    pub normal_mass: Real,
    /// Effective mass along the tangent (appendix eq. 57).
    pub tangent_mass: Real,
    /// Soft step: separation minus the anchors' contribution, so the current separation is
    /// (dpB - dpA + qB rB - qA rA) . n + adjusted_separation.
    pub adjusted_separation: Real,
    /// Soft step: how far B's surface has slipped along the tangent over A's at this point
    /// since the point stuck (m), carried from step to step while static friction holds; 0
    /// for a new point or one that slid (the friction anchor).
    pub slip: Real,
    /// Soft step: static friction held this point at the end of the last step.
    pub stuck: bool,
    /// Soft step: `slip` minus the anchors' contribution, so the current slip is
    /// (dpB - dpA + qB rB - qA rA) . t + adjusted_slip.
    pub adjusted_slip: Real,
    /// Normal relative velocity before the solve (m/s): the approach speed restitution reverses.
    pub relative_velocity: Real,
    /// Sequential solver: the normal velocity with which a speculative point closed its gap
    /// last step (m/s), for restitution when the surfaces meet; 0 otherwise.
    pub approach_velocity: Real,
    /// Sequential solver: target normal velocity (m/s) from position bias or restitution.
    pub bias: Real,
    /// Contact recycling: the point in body A's frame when the manifold was last computed (m).
    pub local_a: Vec2,
    /// Contact recycling: the same point in body B's frame (m); `local_a` and `local_b` were
    /// one world point then.
    pub local_b: Vec2,
    /// Contact recycling: the separation when the manifold was last computed (m).
    pub base_separation: Real,
}

/// A point's lever arms along the normal n and tangent t (see `ContactPoint::arms`).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Arms {
    pub rn_a: Real,
    pub rn_b: Real,
    pub rt_a: Real,
    pub rt_b: Real,
    pub ra_n: Real,
    pub rb_n: Real,
    pub ra_t: Real,
    pub rb_t: Real,
}

impl Arms {
    /// The eight arms as words, in field order (for saved states and lane packing).
    #[inline]
    pub fn to_words(self) -> [Real; 8] {
        [
            self.rn_a, self.rn_b, self.rt_a, self.rt_b, self.ra_n, self.rb_n, self.ra_t, self.rb_t,
        ]
    }

    /// The inverse of [`Arms::to_words`].
    pub fn from_words([rn_a, rn_b, rt_a, rt_b, ra_n, rb_n, ra_t, rb_t]: [Real; 8]) -> Arms {
        Arms {
            rn_a,
            rn_b,
            rt_a,
            rt_b,
            ra_n,
            rb_n,
            ra_t,
            rb_t,
        }
    }

    /// The arms of anchors `ra`, `rb` for normal `n` and tangent `t`.
    #[inline]
    pub fn new(ra: Vec2, rb: Vec2, n: Vec2, t: Vec2) -> Arms {
        use super::math::cross;
        Arms {
            rn_a: cross(ra, n),
            rn_b: cross(rb, n),
            rt_a: cross(ra, t),
            rt_b: cross(rb, t),
            ra_n: ra.dot(n),
            rb_n: rb.dot(n),
            ra_t: ra.dot(t),
            rb_t: rb.dot(t),
        }
    }
}

/// A contact between two bodies: a manifold plus solver state.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Contact {
    /// Pair key (lower slot index first); contacts are kept sorted by it.
    pub key: u64,
    /// Slot index of body A (the lower index).
    pub a: u32,
    /// Slot index of body B.
    pub b: u32,
    /// Unit normal from A to B.
    pub normal: Vec2,
    /// Mixed friction coefficient.
    pub friction: Real,
    /// Mixed restitution coefficient.
    pub restitution: Real,
    /// True when A or B is static (the soft step makes those contacts stiffer).
    pub touches_static: bool,
    /// The points; the first `count` are live.
    pub points: [ContactPoint; 2],
    /// Number of live points.
    pub count: usize,
    /// Soft step: this contact's spring for the current step.
    pub softness: Softness,
    /// Soft step: how far the spring has crept under its load this step (m), added to each
    /// point's separation in the biased pass (see `soft_step::creep`).
    pub creep: Real,
    /// Soft step: the spring's frequency last step (Hz), carried over so that load-aware
    /// stiffening can let it fall only slowly (0 for a new contact).
    pub hertz: Real,
    /// The normal force this contact carried (N), held from step to step: it rises at once and
    /// falls by at most 2 % per step. Adaptive stiffness reads it (`Settings::adaptive_stiffness`).
    pub load: Real,
    /// The normal force of the last step alone (N).
    pub force: Real,
    /// Steps this pair has been in contact, saturating at 255.
    pub age: u8,
    /// Two-point contacts: the normal block and its inverse for this step (None: solve the
    /// points one at a time).
    pub block: Option<BlockMass>,
    /// Contact recycling: the normal in body A's frame when the manifold was last computed.
    pub local_normal: Vec2,
    /// Contact recycling: B's rotation relative to A's when the manifold was last computed.
    pub base_rotation: Rot,
}

impl Contact {
    /// The tangent direction: the normal turned clockwise, t = n x z (appendix, step 2).
    #[inline]
    pub fn tangent(&self) -> Vec2 {
        Vec2::new(self.normal.y, -self.normal.x)
    }
}

/// A read-only view of one contact point, for callers of `World::contacts`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPointInfo {
    /// World position (m).
    pub point: Vec2,
    /// Separation at the start of the last step (m); negative = overlap.
    pub separation: Real,
    /// Normal impulse applied over the last step (N s): the contact force is this / dt.
    pub normal_impulse: Real,
    /// Accumulated friction impulse at the end of the last step (N s; per substep for the soft step).
    pub tangent_impulse: Real,
}

/// A read-only view of one contact between two bodies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactInfo {
    /// Body A.
    pub body_a: BodyId,
    /// Body B.
    pub body_b: BodyId,
    /// Unit normal from A to B.
    pub normal: Vec2,
    /// Up to two points; the first `count` are live.
    pub points: [ContactPointInfo; 2],
    /// Number of live points.
    pub count: usize,
}
