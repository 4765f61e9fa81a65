//! The wire messages for bodies of several shapes and for joints: `…/build` adds bodies and
//! the joints between them (and live bodies) all or nothing, `…/remove_joints` removes
//! joints, and [`JointInfo`] describes a joint in events and in the `…/scene?joints` reply.
//! Field order is wire order: see `docs/protocol.md`.

use super::messages::{BodyRef, Colour, SceneState, ShapeSpec, Vector};
use serde::{Deserialize, Serialize};

/// Most shapes one body may have on the wire (a compound's parts, a built body's parts).
pub const MAX_PARTS: usize = 16;

/// One shape of a body of several, placed in the body's frame: what a
/// [`ShapeSpec::Compound`] lists. The shape is as in a spawn (a polygon's vertices around
/// `offset`, the others centred on it); from the daemon a polygon's vertices are centred on
/// its centroid, and `offset` is where that centroid sits.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartShape {
    /// The shape (never itself a compound).
    pub shape: ShapeSpec,
    /// Where the shape's centre sits, in the body's frame from its origin (m).
    pub offset: Vector,
    /// How far the shape is turned in the body's frame (rad).
    pub angle: f32,
}

/// Which shapes a shape collides with: category and mask bits, and a group (Box2D's
/// `b2Filter`): shapes of the same nonzero group always collide (positive) or never
/// (negative); otherwise two shapes collide when each one's category is in the other's mask.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FilterSpec {
    /// The shape's categories, one bit each.
    pub category: u64,
    /// The categories it collides with.
    pub mask: u64,
    /// Group index (zigzag varint on the wire); 0: none.
    pub group: i32,
}

impl Default for FilterSpec {
    /// Category 1, mask all, no group: collides with everything.
    fn default() -> Self {
        FilterSpec {
            category: 1,
            mask: u64::MAX,
            group: 0,
        }
    }
}

/// One shape of a built body, with its own material, filter and reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartSpec {
    /// The shape and where it sits on the body.
    pub place: PartShape,
    /// Density (kg/m^2), > 0 on a dynamic body.
    pub density: f32,
    /// Friction coefficient, >= 0.
    pub friction: f32,
    /// Restitution, within [0, 1].
    pub restitution: f32,
    /// What it collides with.
    pub filter: FilterSpec,
    /// A sensor: touches nothing, reports what overlaps it (`Sensors` events).
    pub sensor: bool,
    /// Report when it starts and stops touching (`Contacts` events).
    pub contact_events: bool,
    /// Report its hits (`Hits` events).
    pub hit_events: bool,
}

impl PartSpec {
    /// A part of `shape` centred at `offset` (m, body frame), unturned: density 1 kg/m^2,
    /// friction 0.6, restitution 0, the default filter, no reports.
    pub fn at(shape: ShapeSpec, offset: Vector) -> PartSpec {
        PartSpec {
            place: PartShape {
                shape,
                offset,
                angle: 0.0,
            },
            density: 1.0,
            friction: 0.6,
            restitution: 0.0,
            filter: FilterSpec::default(),
            sensor: false,
            contact_events: false,
            hit_events: false,
        }
    }
}

/// How a built body moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Motion {
    /// 0: moved by forces, contacts and joints.
    Dynamic,
    /// 1: moves at the velocity it is given (`…/velocity`), pushes and is not pushed.
    Kinematic,
    /// 2: never moves.
    Static,
    /// 3: dynamic, created asleep (Box2D's `isAwake = false`): it stays where it is put and
    /// costs nothing until something reaches it, a joint is made to it or it is pushed. At
    /// rest only. Appended.
    Sleeping,
}

impl Motion {
    /// Moved by forces, contacts and joints: `Dynamic`, or `Sleeping` once woken.
    pub fn is_dynamic(self) -> bool {
        matches!(self, Motion::Dynamic | Motion::Sleeping)
    }
}

/// One body of a [`Build`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BuildBody {
    /// A name for viewers and logs (optional).
    pub name: Option<String>,
    /// How it moves.
    pub motion: Motion,
    /// Its origin (m, world): the point its parts' offsets are measured from.
    pub position: Vector,
    /// Orientation (rad).
    pub angle: f32,
    /// Linear velocity of the origin (m/s).
    pub velocity: Vector,
    /// Angular velocity (rad/s).
    pub angular_velocity: f32,
    /// Colour for viewers.
    pub colour: Colour,
    /// Its shapes, 1 to [`MAX_PARTS`].
    #[serde(deserialize_with = "super::bounded::parts")]
    pub parts: Vec<PartSpec>,
}

impl BuildBody {
    /// A body of `parts` with its origin at `position` (m), unturned, at rest, unnamed, grey.
    /// Change what differs with struct update syntax.
    pub fn new(motion: Motion, position: Vector, parts: Vec<PartSpec>) -> BuildBody {
        BuildBody {
            name: None,
            motion,
            position,
            angle: 0.0,
            velocity: Vector::default(),
            angular_velocity: 0.0,
            colour: Colour::default(),
            parts,
        }
    }
}

/// One end of a joint in a [`Build`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum JointEnd {
    /// 0: the world (a fixed frame at the origin; body A only).
    World,
    /// 1: the body at this index of [`Build::bodies`].
    New(u32),
    /// 2: a live body.
    Live(BodyRef),
}

/// A range a joint's coordinate keeps within (rad, or m).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LimitSpec {
    /// Lowest value.
    pub lower: f32,
    /// Highest value, >= `lower`.
    pub upper: f32,
}

/// A motor: drives a joint's coordinate at `speed` (rad/s or m/s) with at most `max` (N m or
/// N, >= 0; infinity: unlimited).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotorSpec {
    /// Target speed.
    pub speed: f32,
    /// Largest torque or force.
    pub max: f32,
}

/// A spring toward a joint's rest value: natural frequency (Hz, >= 0; 0: none) and damping
/// ratio (>= 0).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpringSpec {
    /// Natural frequency (Hz).
    pub hertz: f32,
    /// Damping ratio (1: critical).
    pub damping_ratio: f32,
}

/// A joint's kind and settings, as the engine's (`src/physics/joint.rs`). Angles of B
/// relative to A (`reference_angle`) left out are taken from the bodies when the joint is
/// made; axes are in A's frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum JointKindSpec {
    /// 0: a hinge at the anchors.
    Revolute {
        /// B's angle relative to A that counts as zero (rad).
        reference_angle: Option<f32>,
        /// Joint angle range (rad).
        limit: Option<LimitSpec>,
        /// Motor (rad/s, N m).
        motor: Option<MotorSpec>,
        /// Spring toward angle zero.
        spring: Option<SpringSpec>,
    },
    /// 1: a slider along `axis`, B not turning relative to A.
    Prismatic {
        /// Axis of travel in A's frame (non-zero).
        axis: Vector,
        /// As `Revolute`'s.
        reference_angle: Option<f32>,
        /// Travel range (m).
        limit: Option<LimitSpec>,
        /// Motor (m/s, N).
        motor: Option<MotorSpec>,
        /// Spring toward travel zero.
        spring: Option<SpringSpec>,
    },
    /// 2: a rod (rigid) or a spring between the anchors.
    Distance {
        /// Rest length (m); left out: the anchors' distance when made.
        length: Option<f32>,
        /// A spring instead of a rod.
        spring: Option<SpringSpec>,
        /// Shortest and longest length with a spring (m).
        limit: Option<LimitSpec>,
    },
    /// 3: glue, rigid where a frequency is 0.
    Weld {
        /// As `Revolute`'s.
        reference_angle: Option<f32>,
        /// Linear spring (Hz; 0: rigid).
        linear_hertz: f32,
        /// Its damping ratio.
        linear_damping_ratio: f32,
        /// Angular spring (Hz; 0: rigid).
        angular_hertz: f32,
        /// Its damping ratio.
        angular_damping_ratio: f32,
    },
    /// 4: a wheel on a suspension along `axis`.
    Wheel {
        /// Suspension axis in A's frame (non-zero).
        axis: Vector,
        /// Suspension spring (Box2D's default: 1 Hz, 0.7).
        spring: Option<SpringSpec>,
        /// Suspension travel range (m).
        limit: Option<LimitSpec>,
        /// Drive (rad/s, N m).
        motor: Option<MotorSpec>,
    },
    /// 5: drives B's anchor onto A's and B's angle to A's plus `angular_offset`.
    Motor {
        /// Angle of B relative to A it drives to (rad).
        angular_offset: f32,
        /// Largest force (N).
        max_force: f32,
        /// Largest torque (N m).
        max_torque: f32,
        /// Fraction of the error corrected per step's time, in [0, 1] (Box2D's 0.3).
        correction_factor: f32,
    },
}

/// A joint: its two ends, its anchors in each end's frame and its kind.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointSpec {
    /// Body A (or the world).
    pub a: JointEnd,
    /// Body B (a body, not the world).
    pub b: JointEnd,
    /// A's anchor in A's frame (m from its origin; a world point when A is the world).
    pub anchor_a: Vector,
    /// B's anchor in B's frame (m from its origin).
    pub anchor_b: Vector,
    /// Kind and settings.
    pub kind: JointKindSpec,
    /// Whether A and B still collide with each other.
    pub collide_connected: bool,
    /// Breaks when the step's mean force on it passes this (N); None: never.
    pub break_force: Option<f32>,
    /// Breaks when the step's mean torque passes this (N m); None: never.
    pub break_torque: Option<f32>,
}

impl JointSpec {
    /// A hinge between `a` and `b` at their anchors (m, each in its own frame): a revolute
    /// joint with no limit, motor or spring, whose bodies do not collide and which never
    /// breaks. Change what differs with struct update syntax.
    pub fn hinge(a: JointEnd, b: JointEnd, anchor_a: Vector, anchor_b: Vector) -> JointSpec {
        JointSpec {
            a,
            b,
            anchor_a,
            anchor_b,
            kind: JointKindSpec::Revolute {
                reference_angle: None,
                limit: None,
                motor: None,
                spring: None,
            },
            collide_connected: false,
            break_force: None,
            break_torque: None,
        }
    }
}

/// `…/build`: add bodies of one or more shapes and joints between them and live bodies, all
/// or nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Build {
    /// The new bodies (may be empty when only joints are added).
    pub bodies: Vec<BuildBody>,
    /// The new joints (may be empty).
    pub joints: Vec<JointSpec>,
}

/// A joint's id on the wire, as [`BodyRef`] is a body's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct JointRef {
    /// Slot index.
    pub index: u32,
    /// Slot generation.
    pub generation: u32,
}

impl std::fmt::Display for JointRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "joint {}v{}", self.index, self.generation)
    }
}

/// `…/remove_joints`: remove joints by id, all or nothing; their bodies wake.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RemoveJoints {
    /// The joints, at least one.
    pub ids: Vec<JointRef>,
}

/// A live joint as events and the `…/scene?joints` reply describe it: its ends are
/// [`JointEnd::World`] or [`JointEnd::Live`], and every angle or length that was left out
/// when it was made is filled in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointInfo {
    /// Its id.
    pub id: JointRef,
    /// The joint.
    pub joint: JointSpec,
}

/// A joint that broke, with the step's mean force (N) and torque (N m) that broke it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BrokenJoint {
    /// Its id (gone from the World).
    pub id: JointRef,
    /// Force (N).
    pub force: f32,
    /// Torque (N m).
    pub torque: f32,
}

/// The reply to a `get` on `…/scene?joints`: the state and every joint, from the same step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneWithJoints {
    /// The state, as a plain `…/scene` reply.
    pub scene: SceneState,
    /// Every joint, in slot order (a daemon's drag hands are not listed).
    pub joints: Vec<JointInfo>,
}
