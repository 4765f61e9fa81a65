//! Ids: stable, generational handles to the bodies, shapes and joints of a World.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A stable handle to a body in a [`super::World`].
///
/// Ids are generational: removing a body and adding another may reuse the slot, but never the
/// id, so a stale id is reported as unknown instead of silently naming a different body.
/// Only a World makes ids ([`super::World::add_body`]); their parts can be read, not set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct BodyId {
    /// Slot in the World's body array.
    pub(super) index: u32,
    /// How many times the slot has been reused.
    pub(super) generation: u32,
}

impl BodyId {
    /// The slot in the World's body array (a small integer, reused after a removal).
    pub fn index(self) -> u32 {
        self.index
    }

    /// How many times the slot had been reused when this body was added.
    pub fn generation(self) -> u32 {
        self.generation
    }
}

impl fmt::Display for BodyId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}v{}", self.index, self.generation)
    }
}

/// A stable handle to a joint in a [`super::World`], generational as [`BodyId`] is: a removed
/// or broken joint's id is never reused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct JointId {
    /// Slot in the World's joint array.
    pub(super) index: u32,
    /// How many times the slot has been reused.
    pub(super) generation: u32,
}

impl JointId {
    /// The slot in the World's joint array (reused after a removal).
    pub fn index(self) -> u32 {
        self.index
    }

    /// How many times the slot had been reused when this joint was added.
    pub fn generation(self) -> u32 {
        self.generation
    }
}

impl fmt::Display for JointId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "joint {}v{}", self.index, self.generation)
    }
}

/// One shape of one body: the body's own shape is 0, its parts 1, 2, ... in the order given.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct ShapeRef {
    /// The body.
    pub body: BodyId,
    /// The shape's index in the body.
    pub shape: u32,
}
