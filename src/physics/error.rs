//! Typed errors for input the engine refuses.

use super::id::{BodyId, JointId};
use super::math::{Real, Vec2};
use thiserror::Error;

/// Why the engine refused a call. Every variant names the field and the offending value,
/// so a message built from it tells the user exactly what to fix.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PhysicsError {
    /// A number that must be finite was NaN or infinite.
    #[error("{field} must be a finite number, got {value}")]
    NotFinite {
        /// The field, e.g. `position.x`.
        field: &'static str,
        /// The value that was given.
        value: Real,
    },
    /// A number was outside the range the engine can simulate.
    #[error("{field} = {value} is out of range: {expected}")]
    OutOfRange {
        /// The field, e.g. `friction`.
        field: &'static str,
        /// The value that was given.
        value: Real,
        /// The accepted range, in words, e.g. `must be >= 0`.
        expected: &'static str,
    },
    /// A number above a limit the World was built with (a setting), named with its value.
    #[error("{field} = {value} is out of range: must not exceed {setting} = {limit}")]
    AboveLimit {
        /// The field, e.g. `velocity (speed)`.
        field: &'static str,
        /// The value that was given.
        value: Real,
        /// The setting that sets the limit, e.g. `Settings::max_linear_speed`.
        setting: &'static str,
        /// Its value in this World.
        limit: Real,
    },
    /// A body id that does not (or no longer) name a body in this World.
    #[error("no body with id {0}")]
    UnknownBody(BodyId),
    /// A shape that is not a usable convex shape (a polygon's vertex out of order, a
    /// collinear corner, too many points).
    #[error("{field} {reason}")]
    InvalidShape {
        /// The field, e.g. `shape.vertices[2]`.
        field: String,
        /// What is wrong with it, quoting the value.
        reason: String,
    },
    /// A list of bodies names one of them twice.
    #[error("body {0} is listed twice")]
    ListedTwice(BodyId),
    /// The system would not start the worker threads `Settings::workers` asks for.
    #[error("workers = {workers}: cannot start the worker threads: {reason}")]
    NoWorkers {
        /// The workers asked for.
        workers: u32,
        /// The system's reason.
        reason: String,
    },
    /// The World already holds as many bodies as a body id can address.
    #[error("the world is full ({0} bodies)")]
    Full(usize),
    /// A joint id that does not (or no longer) name a joint in this World.
    #[error("no {0}")]
    UnknownJoint(JointId),
    /// A joint that names the same body as both of its ends.
    #[error("body_a and body_b are both body {0}: a joint joins two different bodies")]
    SameBody(BodyId),
    /// A body's part (one of its further shapes) refused, with why.
    #[error("parts[{index}].{source}")]
    InPart {
        /// The part's place in `BodyDef::parts`.
        index: usize,
        /// What is wrong with it.
        source: Box<PhysicsError>,
    },
    /// A joint neither of whose ends a force can move (static or kinematic bodies, or the
    /// world).
    #[error("{0}: a joint needs at least one dynamic body")]
    NoDynamicBody(String),
    /// A range whose lower end is above its upper end.
    #[error("{lower_field} = {lower} is above {upper_field} = {upper}: the lower end must not exceed the upper")]
    Reversed {
        /// The lower end's field, e.g. `limit.lower`.
        lower_field: &'static str,
        /// Its value.
        lower: Real,
        /// The upper end's field.
        upper_field: &'static str,
        /// Its value.
        upper: Real,
    },
    /// A setting that only one kind of joint has, asked of another (e.g. a motor speed of a
    /// weld joint).
    #[error("{joint} is a {kind} joint, which has no {what}")]
    WrongJointKind {
        /// The joint.
        joint: JointId,
        /// Its kind.
        kind: &'static str,
        /// What was asked of it.
        what: &'static str,
    },
    /// A target pose given to a body that is not kinematic.
    #[error("body {0} is not kinematic: only a kinematic body is moved to a target pose")]
    NotKinematic(BodyId),
    /// A body asked to start asleep that cannot.
    #[error("awake = false is refused: {reason}")]
    CannotStartAsleep {
        /// Why.
        reason: String,
    },
}

/// Check that `value` is finite, naming `field` if not.
pub(crate) fn finite(field: &'static str, value: Real) -> Result<Real, PhysicsError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(PhysicsError::NotFinite { field, value })
    }
}

/// Check that both components of `v` are finite, naming `fields[0]` (x) or `fields[1]` (y).
pub(crate) fn finite_vec(fields: [&'static str; 2], v: Vec2) -> Result<Vec2, PhysicsError> {
    finite(fields[0], v.x)?;
    finite(fields[1], v.y)?;
    Ok(v)
}

/// `value` if `ok`, else an [`PhysicsError::OutOfRange`] naming `field` and `expected`.
fn within(
    field: &'static str,
    value: Real,
    ok: bool,
    expected: &'static str,
) -> Result<Real, PhysicsError> {
    if ok {
        Ok(value)
    } else {
        Err(PhysicsError::OutOfRange {
            field,
            value,
            expected,
        })
    }
}

/// Check that `value` is finite and strictly positive.
pub(crate) fn positive(field: &'static str, value: Real) -> Result<Real, PhysicsError> {
    finite(field, value)?;
    within(field, value, value > 0.0, "must be > 0")
}

/// Check that `value` is strictly positive, infinity allowed ("never"), NaN not.
pub(crate) fn positive_or_infinite(field: &'static str, value: Real) -> Result<Real, PhysicsError> {
    within(field, value, value > 0.0, "must be > 0 (infinity: never)")
}

/// Check that `value` is not NaN and not negative (infinity allowed: "no limit").
pub(crate) fn non_negative_or_infinite(
    field: &'static str,
    value: Real,
) -> Result<Real, PhysicsError> {
    within(
        field,
        value,
        value >= 0.0,
        "must be >= 0 (infinity for no limit)",
    )
}

/// Check that `value` is finite and not negative.
pub(crate) fn non_negative(field: &'static str, value: Real) -> Result<Real, PhysicsError> {
    finite(field, value)?;
    within(field, value, value >= 0.0, "must be >= 0")
}

/// Check that `value` is finite and within `[0, 1]`.
pub(crate) fn unit_interval(field: &'static str, value: Real) -> Result<Real, PhysicsError> {
    finite(field, value)?;
    within(
        field,
        value,
        (0.0..=1.0).contains(&value),
        "must be within [0, 1]",
    )
}

/// Refuse a friction outside [0, [`MAX_FRICTION`]] or a restitution outside [0, 1].
pub(crate) fn check_material(friction: Real, restitution: Real) -> Result<(), PhysicsError> {
    non_negative("friction", friction)?;
    if friction > MAX_FRICTION {
        return Err(PhysicsError::OutOfRange {
            field: "friction",
            value: friction,
            expected: "must be within [0, 1000]",
        });
    }
    unit_interval("restitution", restitution)?;
    Ok(())
}

/// The largest friction coefficient accepted. Real materials stay below about 2; anything near
/// the float range would overflow the friction cone mu x Pn.
pub const MAX_FRICTION: Real = 1000.0;
