//! Joints: what a caller asks for ([`JointDef`]) and what the World keeps ([`Joint`]).
//!
//! A joint holds an anchor point of body A to an anchor point of body B (each in its body's
//! frame, metres from the centre of mass) in the way its [`JointKind`] says. Body A may be
//! the world itself (`body_a: None`), whose frame is the world frame: a pendulum hung from a
//! point needs no ground body. Both solvers solve every kind from the same rows
//! (`solver/joint.rs`): the soft step as Box2D v3 does (soft in the biased pass, rigid in the
//! relax pass, warm started, limits speculative), the sequential solver with box2d-lite's
//! Baumgarte bias.

use super::error::{
    finite, finite_vec, non_negative, non_negative_or_infinite, positive, positive_or_infinite,
    unit_interval, PhysicsError,
};
use super::math::{Real, Vec2};
use serde::{Deserialize, Serialize};

pub use super::id::{BodyId, JointId};

/// Everything needed to create a joint. Validated by the World before it takes it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointDef {
    /// Body A, or `None` for the world (a fixed frame: the world's own axes at the origin).
    pub body_a: Option<BodyId>,
    /// Body B.
    pub body_b: BodyId,
    /// The anchor on A, in A's frame (m from its origin, [`super::Body::position`], which is
    /// its centre of mass unless it has parts; world coordinates when A is the world). A
    /// target joint's target.
    pub anchor_a: Vec2,
    /// The anchor on B, in B's frame (m from its origin).
    pub anchor_b: Vec2,
    /// What the joint holds.
    pub kind: JointKind,
    /// Whether the two bodies still collide with each other (Box2D's default: no).
    pub collide_connected: bool,
    /// The joint breaks when the step's force on it passes this (N); infinity: never.
    pub break_force: Real,
    /// The joint breaks when the step's torque on it passes this (N m); infinity: never.
    pub break_torque: Real,
    /// Stiffness of the joint's rigid rows in the soft step (Hz), capped at a quarter of the
    /// substep rate (Box2D's `constraintHertz`, 60).
    pub constraint_hertz: Real,
    /// Their damping ratio (Box2D's `constraintDampingRatio`, 2).
    pub constraint_damping_ratio: Real,
}

/// The kinds of joint, each with its own settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKind {
    /// A hinge: the anchors meet; B turns freely about them, within a limit, driven by a
    /// motor, or pulled back to the reference angle by a spring.
    Revolute(Revolute),
    /// A slider: B's anchor moves along an axis fixed in A, and B does not turn relative to A.
    Prismatic(Prismatic),
    /// A rod or a rope: the anchors keep a distance (rigid, or a spring between limits).
    Distance(Distance),
    /// Glue: the anchors meet and the bodies keep their relative angle (rigid or springy).
    Weld(Weld),
    /// A wheel on a suspension: B's anchor slides along an axis fixed in A on a spring, and B
    /// turns freely about it, driven by a motor.
    Wheel(Wheel),
    /// Drives B's anchor toward A's anchor, and B's angle toward A's plus an offset, with a
    /// capped force and torque.
    Motor(MotorJoint),
    /// Pulls B's anchor toward a target point (A's anchor) with a capped force: a mouse or a
    /// finger dragging a body.
    Target(Target),
}

impl JointKind {
    /// The kind's name, as scene files and errors spell it.
    pub fn name(&self) -> &'static str {
        match self {
            JointKind::Revolute(_) => "revolute",
            JointKind::Prismatic(_) => "prismatic",
            JointKind::Distance(_) => "distance",
            JointKind::Weld(_) => "weld",
            JointKind::Wheel(_) => "wheel",
            JointKind::Motor(_) => "motor",
            JointKind::Target(_) => "target",
        }
    }
}

/// A range a joint's coordinate keeps within (rad for angles, m for lengths and slides).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Limit {
    /// Lowest value.
    pub lower: Real,
    /// Highest value.
    pub upper: Real,
}

/// A motor: drives a joint's coordinate at `speed` (rad/s or m/s) with at most `max` (N m or
/// N; infinity: unlimited).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Motor {
    /// Target speed (rad/s or m/s).
    pub speed: Real,
    /// Largest torque or force it gives (N m or N).
    pub max: Real,
}

/// A spring on a joint's coordinate, toward its rest value (Hz and damping ratio; 0 Hz is no
/// spring).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spring {
    /// Natural frequency (Hz).
    pub hertz: Real,
    /// Damping ratio (1: critical).
    pub damping_ratio: Real,
}

/// A revolute joint's settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Revolute {
    /// The angle of B relative to A that counts as zero (rad); `None`: as they are when the
    /// joint is added.
    pub reference_angle: Option<Real>,
    /// Keeps the joint angle within a range (rad).
    pub limit: Option<Limit>,
    /// Turns B relative to A (rad/s, N m).
    pub motor: Option<Motor>,
    /// Pulls the joint angle back to zero.
    pub spring: Option<Spring>,
}

/// A prismatic joint's settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Prismatic {
    /// The axis of travel, in A's frame (any length but zero; made unit).
    pub axis: Vec2,
    /// As [`Revolute::reference_angle`].
    pub reference_angle: Option<Real>,
    /// Keeps the travel along the axis within a range (m).
    pub limit: Option<Limit>,
    /// Drives B along the axis (m/s, N).
    pub motor: Option<Motor>,
    /// Pulls the travel back to zero.
    pub spring: Option<Spring>,
}

/// A distance joint's settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Distance {
    /// Rest length (m); `None`: the anchors' distance when the joint is added.
    pub length: Option<Real>,
    /// With no spring the length is held rigidly; with one, the spring pulls toward it and
    /// `limit` (if any) bounds the length (m).
    pub spring: Option<Spring>,
    /// Shortest and longest length with a spring (m).
    pub limit: Option<Limit>,
}

/// A weld joint's settings: stiffness 0 Hz is rigid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Weld {
    /// As [`Revolute::reference_angle`].
    pub reference_angle: Option<Real>,
    /// Linear spring (Hz; 0: rigid) and its damping ratio.
    pub linear_hertz: Real,
    pub linear_damping_ratio: Real,
    /// Angular spring (Hz; 0: rigid) and its damping ratio.
    pub angular_hertz: Real,
    pub angular_damping_ratio: Real,
}

/// A wheel joint's settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Wheel {
    /// The suspension axis, in A's frame (made unit).
    pub axis: Vec2,
    /// The suspension spring (Box2D's default: 1 Hz, damping ratio 0.7).
    pub spring: Option<Spring>,
    /// Keeps the suspension's travel within a range (m).
    pub limit: Option<Limit>,
    /// Turns the wheel (rad/s, N m).
    pub motor: Option<Motor>,
}

/// A motor joint's settings: B's anchor is driven onto A's, and B's angle to A's plus
/// `angular_offset`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotorJoint {
    /// B's angle relative to A's that the joint drives to (rad).
    pub angular_offset: Real,
    /// Largest force (N).
    pub max_force: Real,
    /// Largest torque (N m).
    pub max_torque: Real,
    /// The fraction of the error corrected per substep's time, in [0, 1] (Box2D's 0.3).
    pub correction_factor: Real,
}

/// A target joint's settings: a spring of `hertz` and `damping_ratio` pulls B's anchor
/// toward the target (A's anchor) with at most `max_force`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Target {
    /// Stiffness (Hz).
    pub hertz: Real,
    /// Damping ratio.
    pub damping_ratio: Real,
    /// Largest force (N).
    pub max_force: Real,
}

impl JointDef {
    /// A joint of `kind` between `body_a` (None: the world) and `body_b` at their origins,
    /// with Box2D's defaults: bodies do not collide, never breaks, 60 Hz, damping ratio 2.
    pub fn new(kind: JointKind, body_a: Option<BodyId>, body_b: BodyId) -> JointDef {
        JointDef {
            body_a,
            body_b,
            anchor_a: Vec2::ZERO,
            anchor_b: Vec2::ZERO,
            kind,
            collide_connected: false,
            break_force: Real::INFINITY,
            break_torque: Real::INFINITY,
            constraint_hertz: 60.0,
            constraint_damping_ratio: 2.0,
        }
    }

    /// The same joint with these anchors (each in its body's frame, m).
    pub fn with_anchors(mut self, anchor_a: Vec2, anchor_b: Vec2) -> JointDef {
        self.anchor_a = anchor_a;
        self.anchor_b = anchor_b;
        self
    }

    /// The same joint, breaking above `force` (N) or `torque` (N m).
    pub fn with_break(mut self, force: Real, torque: Real) -> JointDef {
        self.break_force = force;
        self.break_torque = torque;
        self
    }

    /// Refuse what cannot be simulated, naming the field and the value. (The World checks
    /// the bodies.)
    pub fn validate(&self) -> Result<(), PhysicsError> {
        if self.body_a == Some(self.body_b) {
            return Err(PhysicsError::SameBody(self.body_b));
        }
        finite_vec(["anchor_a.x", "anchor_a.y"], self.anchor_a)?;
        finite_vec(["anchor_b.x", "anchor_b.y"], self.anchor_b)?;
        positive_or_infinite("break_force", self.break_force)?;
        positive_or_infinite("break_torque", self.break_torque)?;
        non_negative("constraint_hertz", self.constraint_hertz)?;
        non_negative("constraint_damping_ratio", self.constraint_damping_ratio)?;
        self.kind.validate()
    }
}

impl JointKind {
    /// Refuse settings that cannot be simulated, naming the field and the value.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        match self {
            JointKind::Revolute(r) => {
                option(finite, "reference_angle", r.reference_angle)?;
                limit(r.limit)?;
                motor(r.motor)?;
                spring(r.spring)
            }
            JointKind::Prismatic(p) => {
                axis(p.axis)?;
                option(finite, "reference_angle", p.reference_angle)?;
                limit(p.limit)?;
                motor(p.motor)?;
                spring(p.spring)
            }
            JointKind::Distance(d) => {
                option(positive, "length", d.length)?;
                spring(d.spring)?;
                limit(d.limit)?;
                match d.limit {
                    Some(l) if l.lower < 0.0 => Err(PhysicsError::OutOfRange {
                        field: "limit.lower",
                        value: l.lower,
                        expected: "must be >= 0 (a length)",
                    }),
                    _ => Ok(()),
                }
            }
            JointKind::Weld(w) => {
                option(finite, "reference_angle", w.reference_angle)?;
                non_negative("linear_hertz", w.linear_hertz)?;
                non_negative("linear_damping_ratio", w.linear_damping_ratio)?;
                non_negative("angular_hertz", w.angular_hertz)?;
                non_negative("angular_damping_ratio", w.angular_damping_ratio).map(drop)
            }
            JointKind::Wheel(w) => {
                axis(w.axis)?;
                spring(w.spring)?;
                limit(w.limit)?;
                motor(w.motor)
            }
            JointKind::Motor(m) => {
                finite("angular_offset", m.angular_offset)?;
                non_negative_or_infinite("max_force", m.max_force)?;
                non_negative_or_infinite("max_torque", m.max_torque)?;
                unit_interval("correction_factor", m.correction_factor).map(drop)
            }
            JointKind::Target(t) => {
                positive("hertz", t.hertz)?;
                non_negative("damping_ratio", t.damping_ratio)?;
                non_negative_or_infinite("max_force", t.max_force).map(drop)
            }
        }
    }
}

/// Box2D's revolute joint with nothing on it: a free hinge.
impl Revolute {
    /// A free hinge (no limit, motor or spring).
    pub fn free() -> Revolute {
        Revolute::default()
    }
}

impl Wheel {
    /// A wheel on `axis` (A's frame) with Box2D's default suspension: 1 Hz, damping ratio 0.7.
    pub fn on_axis(axis: Vec2) -> Wheel {
        Wheel {
            axis,
            spring: Some(Spring {
                hertz: 1.0,
                damping_ratio: 0.7,
            }),
            limit: None,
            motor: None,
        }
    }
}

impl Prismatic {
    /// A free slider along `axis` (A's frame).
    pub fn on_axis(axis: Vec2) -> Prismatic {
        Prismatic {
            axis,
            reference_angle: None,
            limit: None,
            motor: None,
            spring: None,
        }
    }
}

impl MotorJoint {
    /// Box2D's defaults: no offset, 1 N, 1 N m, correction 0.3.
    pub fn new(max_force: Real, max_torque: Real) -> MotorJoint {
        MotorJoint {
            angular_offset: 0.0,
            max_force,
            max_torque,
            correction_factor: 0.3,
        }
    }
}

fn option(
    check: fn(&'static str, Real) -> Result<Real, PhysicsError>,
    field: &'static str,
    value: Option<Real>,
) -> Result<(), PhysicsError> {
    value.map_or(Ok(()), |v| check(field, v).map(drop))
}

fn axis(axis: Vec2) -> Result<(), PhysicsError> {
    finite_vec(["axis.x", "axis.y"], axis)?;
    if axis.length() > 1e-6 {
        Ok(())
    } else {
        Err(PhysicsError::OutOfRange {
            field: "axis (length)",
            value: axis.length(),
            expected: "must be > 1e-6 (a direction)",
        })
    }
}

fn limit(limit: Option<Limit>) -> Result<(), PhysicsError> {
    let Some(l) = limit else { return Ok(()) };
    finite("limit.lower", l.lower)?;
    finite("limit.upper", l.upper)?;
    if l.lower > l.upper {
        return Err(PhysicsError::Reversed {
            lower_field: "limit.lower",
            lower: l.lower,
            upper_field: "limit.upper",
            upper: l.upper,
        });
    }
    Ok(())
}

fn motor(motor: Option<Motor>) -> Result<(), PhysicsError> {
    let Some(m) = motor else { return Ok(()) };
    finite("motor.speed", m.speed)?;
    non_negative_or_infinite("motor.max", m.max).map(drop)
}

fn spring(spring: Option<Spring>) -> Result<(), PhysicsError> {
    let Some(s) = spring else { return Ok(()) };
    non_negative("spring.hertz", s.hertz)?;
    non_negative("spring.damping_ratio", s.damping_ratio).map(drop)
}

/// A joint as the World keeps it: its definition (with the reference angle and the length
/// worked out when it was added) and what the solver carries from step to step.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    pub(crate) id: JointId,
    pub(crate) def: JointDef,
    /// The solver's impulses at the end of the last step, per step (N s, N m s): the point
    /// block's, then each row's (`solver/joint.rs` orders them).
    pub(crate) impulses: JointImpulses,
    /// Force (N) and torque (N m) on B at the end of the last step.
    pub(crate) force: Vec2,
    pub(crate) torque: Real,
    /// Its colour in the constraint graph while either body is awake; `UNCOLOURED` asleep
    /// and before its first step.
    pub(crate) colour: u8,
}

/// The impulses a joint carries from one step to the next (N s; per step).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointImpulses {
    /// The point block's.
    pub point: [Real; 2],
    /// Each row's, in the kind's row order.
    pub rows: [Real; MAX_ROWS],
}

/// The most one-dimensional rows a joint has (a prismatic joint: across, angle, spring,
/// motor, lower and upper limit).
pub const MAX_ROWS: usize = 6;

impl Joint {
    /// Its id.
    pub fn id(&self) -> JointId {
        self.id
    }

    /// Its definition, with the reference angle and the length as worked out when it was
    /// added.
    pub fn def(&self) -> &JointDef {
        &self.def
    }

    /// The force the joint put on body B in the last step (N; B's reaction on A is its
    /// opposite).
    pub fn reaction_force(&self) -> Vec2 {
        self.force
    }

    /// The torque the joint's angular rows put on body B in the last step (N m).
    pub fn reaction_torque(&self) -> Real {
        self.torque
    }

    /// Whether the last step's force or torque passed the joint's break force or torque.
    pub(crate) fn overloaded(&self) -> bool {
        self.force.length() > self.def.break_force || self.torque.abs() > self.def.break_torque
    }
}
