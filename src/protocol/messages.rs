//! The wire messages of protocol v1. Field order is wire order: see `docs/protocol.md`.
//!
//! Numbers on the wire are `f32` whatever the engine's [`crate::physics::Real`] is, and times
//! are `f64` seconds. Body ids are the engine's generational ids, `(index, generation)`.

use crate::physics::BodyId;
use serde::{Deserialize, Serialize};

/// A 2D vector of `f32` (metres, m/s or m/s^2 depending on the field). 8 bytes on the wire.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector {
    /// x component (to the right).
    pub x: f32,
    /// y component (up).
    pub y: f32,
}

impl Vector {
    /// A vector from its components.
    pub const fn new(x: f32, y: f32) -> Vector {
        Vector { x, y }
    }
}

/// A body id on the wire: the engine's [`BodyId`], two varints. Only the daemon turns one
/// back into an engine id, by finding the live body it names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct BodyRef {
    /// Slot index.
    pub index: u32,
    /// Slot generation (how many times the slot was reused).
    pub generation: u32,
}

impl From<BodyId> for BodyRef {
    fn from(id: BodyId) -> BodyRef {
        BodyRef {
            index: id.index(),
            generation: id.generation(),
        }
    }
}

impl std::fmt::Display for BodyRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}v{}", self.index, self.generation)
    }
}

/// An sRGB colour: three bytes on the wire, red first. The scene files' own type, whose
/// binary serde form this is.
pub use crate::scene::Colour;

/// A collision shape, in the body's frame (metres). New kinds are appended, so a variant's
/// number on the wire never changes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ShapeSpec {
    /// Variant 0: a `width` x `height` rectangle centred on the centre of mass.
    Rect {
        /// Full width, metres.
        width: f32,
        /// Full height, metres.
        height: f32,
    },
    /// Variant 1: a disc of `radius` metres centred on the centre of mass.
    Circle {
        /// Radius, metres.
        radius: f32,
    },
    /// Variant 2: a capsule along the body's x axis, `length` metres end to end (rounded ends
    /// included, so `length > 2 radius`), `radius` metres on each side of the axis.
    Capsule {
        /// Length end to end, metres.
        length: f32,
        /// Radius of the rounded ends, metres.
        radius: f32,
    },
    /// Variant 3: a convex polygon, 3 to 8 vertices counter-clockwise, in the body's frame
    /// (m). From the daemon the vertices are centred on the centroid (the body's position is
    /// its centre of mass); in a spawn they are relative to the spawn position, and the
    /// daemon moves the body to the centroid.
    Polygon {
        /// Vertices, counter-clockwise, metres.
        #[serde(deserialize_with = "super::bounded::vertices")]
        vertices: Vec<Vector>,
    },
    /// Variant 4: a line segment from `a` to `b` (m, body frame) grown by `radius` (m, may be
    /// 0), for static and kinematic bodies only; a piece of a chain carries the chain's
    /// vertex before `a` (`prev`) and after `b` (`next`) so bodies slide over its joints, and
    /// `one_sided` pushes only to the left of a -> b. A scene's `chain` arrives as one body
    /// per piece.
    Segment {
        /// First end, metres.
        a: Vector,
        /// Second end, metres.
        b: Vector,
        /// Thickness on each side of the line, metres.
        radius: f32,
        /// The chain's vertex before `a`, metres.
        prev: Option<Vector>,
        /// The chain's vertex after `b`, metres.
        next: Option<Vector>,
        /// Push only to the left of a -> b.
        one_sided: bool,
    },
    /// Variant 5: a body of several shapes, each placed in the body's frame (2 to
    /// [`super::build::MAX_PARTS`], none itself a compound). The daemon describes every body
    /// of more than one shape so; it is spawned on `…/build`, never on `…/spawn`. Appended.
    Compound {
        /// The shapes.
        #[serde(deserialize_with = "super::bounded::compound_parts")]
        parts: Vec<super::build::PartShape>,
    },
}

/// One body's pose in a [`Snapshot`], as a client reconstructs it from the quantized wire
/// form ([`super::snapshot`]): within half a grid step of the daemon's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// The body.
    pub id: BodyRef,
    /// Centre of mass x (m).
    pub x: f32,
    /// Centre of mass y (m).
    pub y: f32,
    /// Orientation (rad, counter-clockwise), within [-pi, pi): whole turns are not sent.
    pub angle: f32,
}

/// `…/poses`, decoded: what a [`super::SnapshotDecoder`] makes of each payload (the wire form
/// is [`super::SnapshotFrame`], quantized and delta-coded).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    /// Frame number: steps since the daemon started (1 for the first step; never reset).
    pub frame: u64,
    /// Simulated time (s) since the daemon started: `frame * dt`.
    pub time: f64,
    /// Gravity in force during this step (m/s^2, world frame).
    pub gravity: Vector,
    /// True when `poses` holds every dynamic body (every `keyframe_every` frames and after a
    /// reset); false when it holds only the bodies whose pose changed since the previous
    /// snapshot the decoder gave out.
    pub keyframe: bool,
    /// Poses of dynamic bodies, in slot order. Static bodies never appear here.
    pub poses: Vec<Pose>,
}

/// `…/gravity`: set gravity (m/s^2, world frame: x right, y up).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SetGravity {
    /// x component.
    pub x: f32,
    /// y component.
    pub y: f32,
}

/// A discrete device orientation (the names of iOS's `UIDeviceOrientation`). The screen is the
/// world: world x is the screen's right, world y the screen's top.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Orientation {
    /// 0: upright, home button (or bottom edge) down: gravity points to the screen's bottom.
    Portrait,
    /// 1: upside down: gravity points to the screen's top.
    PortraitUpsideDown,
    /// 2: turned 90 degrees counter-clockwise (home button on the right): gravity points to
    /// the screen's left.
    LandscapeLeft,
    /// 3: turned 90 degrees clockwise (home button on the left): gravity points to the
    /// screen's right.
    LandscapeRight,
    /// 4: lying flat, screen up: no gravity in the screen's plane.
    FaceUp,
    /// 5: lying flat, screen down: no gravity in the screen's plane.
    FaceDown,
}

/// `…/tilt`: a device's tilt, which the daemon turns into gravity (see [`super::tilt`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Tilt {
    /// 0: a discrete orientation; gravity has the scene's gravity magnitude.
    Orientation(Orientation),
    /// 1: a raw accelerometer reading in the device frame, m/s^2, Android's convention
    /// (x right, y up the screen, z out of the screen; at rest it reads +9.81 upwards).
    Accelerometer {
        /// Along the screen's right edge.
        x: f32,
        /// Along the screen's up edge.
        y: f32,
        /// Out of the screen.
        z: f32,
    },
}

/// One body asked for on `…/spawn`: always dynamic.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpawnBody {
    /// A name for viewers and logs (optional).
    pub name: Option<String>,
    /// Shape.
    pub shape: ShapeSpec,
    /// Where the body goes (m): its centre of mass, except for a polygon, whose vertices are
    /// relative to this point and whose centre of mass the daemon puts at their centroid
    /// (`position + R(angle) centroid`).
    pub position: Vector,
    /// Orientation (rad).
    pub angle: f32,
    /// Linear velocity (m/s).
    pub velocity: Vector,
    /// Angular velocity (rad/s).
    pub angular_velocity: f32,
    /// Density (kg/m^2), > 0.
    pub density: f32,
    /// Friction coefficient, >= 0.
    pub friction: f32,
    /// Restitution, within [0, 1].
    pub restitution: f32,
    /// Colour for viewers.
    pub colour: Colour,
}

impl SpawnBody {
    /// A body of `shape` at rest at `position` (m), not turned: density 1 kg/m^2, friction
    /// 0.6, restitution 0, grey, no name. Change what differs with struct update syntax.
    pub fn at(shape: ShapeSpec, position: Vector) -> SpawnBody {
        SpawnBody {
            name: None,
            shape,
            position,
            angle: 0.0,
            velocity: Vector::default(),
            angular_velocity: 0.0,
            density: 1.0,
            friction: 0.6,
            restitution: 0.0,
            colour: Colour::default(),
        }
    }
}

/// `…/spawn`: add bodies, all or nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spawn {
    /// The bodies, at least one.
    #[serde(deserialize_with = "super::bounded::spawn_bodies")]
    pub bodies: Vec<SpawnBody>,
}

/// `…/remove`: remove bodies by id, all or nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Remove {
    /// The bodies, at least one.
    pub ids: Vec<BodyRef>,
}

/// `…/reset`: reload the scene. No fields: the payload is the version byte alone.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Reset;

/// Everything about one body: what `…/scene` and the `Added`/`Reset` events carry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyInfo {
    /// Id.
    pub id: BodyRef,
    /// Name (may be empty).
    pub name: String,
    /// Shape.
    pub shape: ShapeSpec,
    /// Immovable.
    pub is_static: bool,
    /// Colour.
    pub colour: Colour,
    /// Centre of mass (m).
    pub position: Vector,
    /// Orientation (rad).
    pub angle: f32,
    /// Linear velocity (m/s).
    pub velocity: Vector,
    /// Angular velocity (rad/s).
    pub angular_velocity: f32,
    /// Mass (kg); 0 for static bodies.
    pub mass: f32,
    /// Friction coefficient.
    pub friction: f32,
    /// Restitution.
    pub restitution: f32,
}

#[cfg(test)]
impl BodyInfo {
    /// For tests: a body `id` of `shape` at rest at `position` (m), as the daemon describes a
    /// static wall: unnamed, grey, unturned, mass 0, friction 0.6, restitution 0.
    pub(crate) fn wall(id: BodyRef, shape: ShapeSpec, position: Vector) -> BodyInfo {
        BodyInfo {
            id,
            name: String::new(),
            shape,
            is_static: true,
            colour: Colour::default(),
            position,
            angle: 0.0,
            velocity: Vector::default(),
            angular_velocity: 0.0,
            mass: 0.0,
            friction: 0.6,
            restitution: 0.0,
        }
    }
}

/// What an [`Event`] reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum EventKind {
    /// 0: bodies were added by one `…/spawn` command.
    Added {
        /// The new bodies.
        bodies: Vec<BodyInfo>,
    },
    /// 1: bodies were removed by one `…/remove` command.
    Removed {
        /// Their ids.
        ids: Vec<BodyRef>,
    },
    /// 2: the scene was reloaded; every body before it is gone.
    Reset {
        /// The scene's name.
        scene: String,
        /// Gravity after the reset (m/s^2).
        gravity: Vector,
        /// Every body of the new world.
        bodies: Vec<BodyInfo>,
    },
    /// 3: a command was refused and nothing was changed.
    Rejected {
        /// The key it arrived on (full key expression).
        key: String,
        /// Why, naming the field and value where there is one.
        reason: String,
    },
    /// 4: pairs of shapes that began or stopped touching in the step of `frame` (shapes whose
    /// scene asked, `contact_events`). Appended.
    Contacts {
        /// Pairs that began touching.
        begin: Vec<ShapePair>,
        /// Pairs that stopped touching (or whose body was removed).
        end: Vec<ShapePair>,
        /// How many more there were than the per-frame cap let through.
        dropped: u32,
    },
    /// 5: hits in the step of `frame` (`hit_events`). Appended.
    Hits {
        /// The hits.
        hits: Vec<HitInfo>,
        /// How many more there were than the per-frame cap let through.
        dropped: u32,
    },
    /// 6: shapes that entered or left a sensor in the step of `frame`. Appended.
    Sensors {
        /// (sensor, visitor) pairs that began overlapping.
        begin: Vec<ShapePair>,
        /// Pairs that stopped overlapping (or whose body was removed).
        end: Vec<ShapePair>,
        /// How many more there were than the per-frame cap let through.
        dropped: u32,
    },
    /// 7: bodies and joints were added by one `…/build` command (or, with no bodies, the
    /// joints of the scene a `Reset` just loaded). Appended.
    Built {
        /// The new bodies.
        bodies: Vec<BodyInfo>,
        /// The new joints.
        joints: Vec<super::build::JointInfo>,
    },
    /// 8: joints were removed by one `…/remove_joints` command. Appended.
    JointsRemoved {
        /// Their ids.
        ids: Vec<super::build::JointRef>,
    },
    /// 9: joints broke in the step of `frame`, in id order. Appended.
    JointsBroken {
        /// The joints, with what broke them.
        joints: Vec<super::build::BrokenJoint>,
    },
}

/// Two shapes: a contact's (A's body has the lower slot) or a sensor and what overlaps it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShapePair {
    /// Shape A (or the sensor).
    pub a: ShapeHit,
    /// Shape B (or the visitor).
    pub b: ShapeHit,
}

/// A hit: two shapes that met faster than the World's `hit_event_threshold`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HitInfo {
    /// The shapes (A's body has the lower slot).
    pub pair: ShapePair,
    /// The point that approached fastest (m, world).
    pub point: Vector,
    /// The contact normal, from A to B.
    pub normal: Vector,
    /// How fast that point approached (m/s).
    pub approach_speed: f32,
}

/// `…/events`: what changed, stamped with the frame of the step it preceded.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Event {
    /// The frame of the first snapshot that includes the change (commands are applied at
    /// the tick boundary just before that step).
    pub frame: u64,
    /// What happened.
    pub kind: EventKind,
}

/// `…/scene` reply: the full state after a step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneState {
    /// World name.
    pub world: String,
    /// Scene name.
    pub scene: String,
    /// The frame this state is from (same numbering as [`Snapshot::frame`]).
    pub frame: u64,
    /// Simulated time (s).
    pub time: f64,
    /// Gravity (m/s^2).
    pub gravity: Vector,
    /// Every body, static ones included, in slot order.
    pub bodies: Vec<BodyInfo>,
}

/// `…/velocity`: set a kinematic body's velocity (how a client drives a paddle or a
/// platform). Refused for bodies that are not kinematic, and for speeds over the World's cap.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SetVelocity {
    /// The kinematic body.
    pub id: BodyRef,
    /// Linear velocity (m/s, world frame).
    pub velocity: Vector,
    /// Angular velocity (rad/s, counter-clockwise).
    pub angular_velocity: f32,
}

/// `…/drag`: a hand (a client's finger or pointer, named by an id the client picks) takes hold
/// of a dynamic body, moves, and lets go. The daemon holds the body's grabbed point to the
/// hand's target with a spring (a target joint: 5 Hz, damping ratio 0.7, at most 100 times the
/// body's weight at standard gravity), so a body released while moving flies on.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Drag {
    /// 0: take hold of body `id` at `point` (m, world), which also becomes the target. A hand
    /// that holds a body lets it go first.
    Grab {
        /// The client's own id for this hand.
        hand: u64,
        /// The body (dynamic).
        id: BodyRef,
        /// The point taken hold of (m, world).
        point: Vector,
    },
    /// 1: move the hand's target to `target` (m, world).
    Move {
        /// The hand.
        hand: u64,
        /// Where the grabbed point is pulled (m, world).
        target: Vector,
    },
    /// 2: let go.
    Release {
        /// The hand.
        hand: u64,
    },
}

/// Which shapes a query sees: those whose category is in `mask` and whose mask holds
/// `category` (both ways, as Box2D's `b2QueryFilter`; category 1 and mask all see every shape
/// with the default filter). Sensors are never seen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct QueryFilterSpec {
    /// The query's categories.
    pub category: u64,
    /// The categories it sees.
    pub mask: u64,
}

impl Default for QueryFilterSpec {
    fn default() -> Self {
        QueryFilterSpec {
            category: 1,
            mask: u64::MAX,
        }
    }
}

/// `…/query` request, the payload of a Zenoh `get`: what to look for in the world, answered at
/// the next tick boundary.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum WorldQuery {
    /// 0: the closest shape the ray from `origin` along `translation` (m) meets.
    RayClosest {
        /// Start (m, world).
        origin: Vector,
        /// Direction and length (m).
        translation: Vector,
        /// What it sees.
        filter: QueryFilterSpec,
    },
    /// 1: every shape the ray meets, closest first, at most `limit` (and at most 64).
    RayAll {
        /// Start (m, world).
        origin: Vector,
        /// Direction and length (m).
        translation: Vector,
        /// What it sees.
        filter: QueryFilterSpec,
        /// The most hits wanted.
        limit: u32,
    },
    /// 2: every shape that holds `point` (m, world).
    Point {
        /// The point.
        point: Vector,
        /// What it sees.
        filter: QueryFilterSpec,
    },
    /// 3: every shape that overlaps the box from `min` to `max` (m, world).
    Box {
        /// Lower-left corner.
        min: Vector,
        /// Upper-right corner.
        max: Vector,
        /// What it sees.
        filter: QueryFilterSpec,
    },
}

/// One shape a query found: its body, and its index in the body (0: the body's own shape).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShapeHit {
    /// The body.
    pub id: BodyRef,
    /// The shape's index in the body.
    pub shape: u32,
}

/// Where a ray met a shape.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RayHitInfo {
    /// The shape met.
    pub hit: ShapeHit,
    /// The point met (m, world).
    pub point: Vector,
    /// The shape's outward normal there.
    pub normal: Vector,
    /// How far along the translation (0 to 1).
    pub fraction: f32,
}

/// `…/query` reply.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum QueryAnswer {
    /// 0: a ray's hits, closest first (none, or one for `RayClosest`), in the world after
    /// `frame`.
    Hits {
        /// The frame the world was at.
        frame: u64,
        /// The hits.
        hits: Vec<RayHitInfo>,
    },
    /// 1: the shapes a point or box query found, by body and shape.
    Shapes {
        /// The frame the world was at.
        frame: u64,
        /// The shapes.
        shapes: Vec<ShapeHit>,
    },
    /// 2: the query was refused: why, naming the field and value.
    Refused {
        /// Why.
        reason: String,
    },
}

/// `…/stats`: once a second. Durations are microseconds over the last second.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Latest frame.
    pub frame: u64,
    /// Bodies in the world.
    pub bodies: u32,
    /// Dynamic bodies that are awake (sleeping ones do not move and are not stepped).
    pub awake: u32,
    /// Contact pairs after the latest step.
    pub contacts: u32,
    /// Median `World::step` time over the window (us).
    pub step_us_median: u32,
    /// Longest `World::step` time over the window (us).
    pub step_us_max: u32,
    /// Worst tick lateness over the window: how long after its deadline a tick started (us).
    pub lateness_us_max: u32,
    /// Commands applied since start.
    pub commands_applied: u64,
    /// Commands rejected since start.
    pub commands_rejected: u64,
    /// Steps skipped since start because the loop fell too far behind.
    pub steps_dropped: u64,
    /// Command samples the daemon's subscribers received since this process started (each
    /// ends applied, rejected or dropped). Appended: older readers stop before it.
    pub commands_received: u64,
    /// Commands dropped since this process started because the command queue was full
    /// (reported in aggregate by `Rejected` events; not in `commands_rejected`).
    pub commands_dropped: u64,
}
