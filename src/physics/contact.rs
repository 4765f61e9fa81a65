//! Persistent contacts: one per touching (or about to touch) pair of bodies, carrying the
//! solver's accumulated impulses from one step to the next so the next solve can warm start.

use super::body::BodyId;
use super::collide::FeatureId;
use super::math::{Real, Rot, Vec2};

/// One contact point and what it carries from one step to the next. What the solver works
/// out afresh each step (arms, effective masses, bias) is in
/// [`PointConstraint`](super::solver::constraint::PointConstraint).
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
    /// Sequential solver: the normal velocity with which a speculative point closed its gap
    /// last step (m/s), for restitution when the surfaces meet; 0 otherwise.
    pub approach_velocity: Real,
    /// Contact recycling: the point in body A's frame when the manifold was last computed (m).
    pub local_a: Vec2,
    /// Contact recycling: the same point in body B's frame (m); `local_a` and `local_b` were
    /// one world point then.
    pub local_b: Vec2,
    /// Contact recycling: the separation when the manifold was last computed (m).
    pub base_separation: Real,
}

/// A contact between two bodies: a manifold and what lasts from step to step (the per-step
/// constraint is [`ContactConstraint`](super::solver::constraint::ContactConstraint)).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Contact {
    /// Pair key (lower slot index first); contacts are kept sorted by it.
    pub key: u64,
    /// Slot index of body A (the lower index).
    pub a: u32,
    /// Slot index of body B.
    pub b: u32,
    /// Which of the bodies' shapes touch, for bodies of several: A's shape index in the high
    /// 16 bits, B's in the low 16 (0 for bodies of one shape). Contacts with the same key are
    /// kept sorted by it.
    pub shapes: u32,
    /// Unit normal from A to B.
    pub normal: Vec2,
    /// Mixed friction coefficient.
    pub friction: Real,
    /// Mixed restitution coefficient.
    pub restitution: Real,
    /// True when A or B is static (the soft step makes those contacts stiffer).
    pub touches_static: bool,
    /// How far A's and B's surfaces are grown out from their cores (m; `Shape::rounding`):
    /// the soft step follows a rounded surface's point as the core turns, not as the
    /// material turns (a rolling disc's contact stays at its bottom).
    pub rounding: [Real; 2],
    /// The points; the first `count` are live.
    pub points: [ContactPoint; 2],
    /// Number of live points (a byte: it packs into the padding beside `age` and `colour`).
    pub count: u8,
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
    /// Soft step: the contact's colour in the constraint graph (`solver::graph`), from its
    /// first step to its last; `UNCOLOURED` while it sleeps.
    pub colour: u8,
    /// Contact recycling: the normal in body A's frame when the manifold was last computed.
    pub local_normal: Vec2,
    /// Contact recycling: B's rotation relative to A's when the manifold was last computed.
    pub base_rotation: Rot,
}

impl Contact {
    /// The order contacts are kept in: by pair key, then by shapes.
    #[inline]
    pub fn order(&self) -> (u64, u32) {
        (self.key, self.shapes)
    }

    /// The live points.
    #[inline]
    pub fn live(&self) -> &[ContactPoint] {
        &self.points[..self.count as usize]
    }

    /// The live points, to update.
    #[inline]
    pub fn live_mut(&mut self) -> &mut [ContactPoint] {
        &mut self.points[..self.count as usize]
    }

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
    /// Accumulated friction impulse at the end of the last step (N s).
    pub tangent_impulse: Real,
}

/// A read-only view of one contact between two bodies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactInfo {
    /// Body A.
    pub body_a: BodyId,
    /// Body B.
    pub body_b: BodyId,
    /// Which of A's shapes touches: 0 its own, i its part i - 1.
    pub shape_a: usize,
    /// Which of B's shapes touches.
    pub shape_b: usize,
    /// Unit normal from A to B.
    pub normal: Vec2,
    /// Up to two points; the first `count` are live.
    pub points: [ContactPointInfo; 2],
    /// Number of live points.
    pub count: usize,
}
