//! The engine: a from-scratch 2D rigid-body World.
//!
//! No async, no networking, no I/O: this module builds with `--no-default-features` and
//! depends on glam, serde and thiserror only. Units: metres, seconds, radians, kilograms.
//!
//! Every function here fits on a screen: clippy's `too_many_lines` is on for the engine, with
//! the limits of 80 lines and 6 parameters set in `clippy.toml`.
#![warn(clippy::too_many_lines)]

pub mod body;
pub(crate) mod broad_phase;
pub(crate) mod builder;
pub mod collide;
pub mod contact;
pub mod convex;
pub mod error;
pub mod events;
pub mod filter;
pub(crate) mod hash;
pub mod id;
pub mod joint;
pub mod math;
pub mod part;
pub(crate) mod part_tree;
pub mod query;
pub mod ragdoll;
pub mod segment;
pub mod settings;
pub mod shape;
pub(crate) mod solver;
pub(crate) mod team;
pub mod world;

pub use body::{Body, BodyDef, BodyId, MassSpec};
pub use contact::{ContactInfo, ContactPointInfo};
pub use convex::Polygon;
pub use error::PhysicsError;
pub use events::{ContactEvent, HitEvent, SensorEvent, ShapeFlags, StepEvents};
pub use filter::Filter;
pub use id::ShapeRef;
pub use joint::{
    Distance, Joint, JointDef, JointId, JointKind, Limit, Motor, MotorJoint, Prismatic, Revolute,
    Spring, Target, Weld, Wheel,
};
pub use math::{vec2, Real, Rot, Transform, Vec2};
pub use part::PartDef;
pub use query::{QueryFilter, RayHit};
pub use segment::Segment;
pub use settings::{Mixing, Settings, SolverKind};
pub use shape::{Aabb, Shape};
pub use team::WorkerPool;
pub use world::snapshot::{StateError, WorldState};
pub use world::{Query, World};
