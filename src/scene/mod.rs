//! Scene files: TOML descriptions of a World (gravity, solver settings, bodies) that are
//! read, validated and turned into a [`World`].
//!
//! The format is documented in `docs/scenes.md`. In short:
//!
//! ```toml
//! name = "two boxes"
//! gravity = [0, -9.81]          # m/s^2
//!
//! [settings]                    # optional: any field of physics::Settings
//! solver = "soft_step"
//!
//! [[body]]
//! name = "ground"
//! static = true
//! shape = { type = "rect", width = 20, height = 1 }   # metres
//! position = [0, -0.5]                               # metres
//!
//! [[body]]
//! name = "box"
//! shape = { type = "rect", width = 1, height = 0.5 }
//! position = [0, 2]
//! angle = 0.3                  # radians
//! density = 1                  # kg/m^2 (or mass = ... kg)
//! colour = "#d64541"
//!
//! [[body]]
//! name = "ball"
//! shape = { type = "circle", radius = 0.3 }           # also "capsule" (length, radius)
//! position = [-2, 3]
//! density = 1
//!
//! [[body]]
//! name = "wedge"               # vertices in metres around position, counter-clockwise;
//! shape = { type = "polygon", vertices = [[0, 0], [1, 0], [0, 1]] }
//! position = [2, 3]            # the centre of mass goes to their centroid, (2.33, 3.33)
//! density = 1
//!
//! [[stack]]                    # generators expand into bodies (square boxes)
//! count = 5
//! size = 0.5
//! x = 4
//! ```
//!
//! Every value is checked before a World sees it, and errors name the body, the field and the
//! value: `body "box" (#1): friction = -1: must be >= 0`.

#![warn(missing_docs)]

mod colour;
mod error;
mod file;
mod joints;

pub use colour::{Colour, ParseColourError};
pub use error::SceneError;
pub use joints::SceneJoint;

use crate::physics::{BodyDef, BodyId, JointDef, Settings, Vec2, World};
use serde::Serialize;
use std::path::Path;

/// The most bodies a scene may hold (explicit plus generated): keeps a typo such as
/// `base = 100000` from exhausting memory. A pyramid of base 446 has 99,681 boxes.
pub const MAX_BODIES: usize = 100_000;

/// The Falling Bricks scene as shipped in `config/scenes/falling_bricks.toml`.
const FALLING_BRICKS: &str = include_str!("../../config/scenes/falling_bricks.toml");

/// One body of a scene: what to simulate plus how to show it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneBody {
    /// The name from the file; generated bodies are named `stack[i]` / `pyramid[row,col]`
    /// (or with the generator's own `name` as prefix), unnamed ones `body INDEX`.
    pub name: String,
    /// The validated definition (shape and position in metres, angle in radians, velocities
    /// in m/s and rad/s, density in kg/m^2 or mass in kg).
    pub def: BodyDef,
    /// Display colour; no effect on physics.
    pub colour: Colour,
    /// True for immovable bodies (walls, ground): `def.mass` is `MassSpec::Static`.
    pub is_static: bool,
}

/// A validated scene: everything needed to build a [`World`].
///
/// Serialize is derived so a scene can be sent or logged as it is held in memory; to read a
/// scene use [`Scene::from_toml_str`] or [`Scene::load`], which validate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Scene {
    /// The scene's name (`untitled` when the file gives none).
    pub name: String,
    /// Gravity, m/s^2. Default (0, -9.81).
    pub gravity: Vec2,
    /// Engine settings: the file's `[settings]` table over `Settings::default()`.
    pub settings: Settings,
    /// The bodies in file order, generators expanded in place, ropes' links last.
    pub bodies: Vec<SceneBody>,
    /// The joints: every rope's, then the `[[joint]]` tables in file order.
    pub joints: Vec<SceneJoint>,
}

impl Scene {
    /// Parse and validate a scene from TOML text.
    pub fn from_toml_str(text: &str) -> Result<Scene, SceneError> {
        file::parse(text)
    }

    /// Read, parse and validate the scene file at `path`.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_owned(),
            source,
        })?;
        Scene::from_toml_str(&text)
    }

    /// The Falling Bricks scene compiled into the binary (`config/scenes/falling_bricks.toml`):
    /// a closed 8 m x 6 m box and six bricks.
    pub fn embedded_default() -> Result<Scene, SceneError> {
        Scene::from_toml_str(FALLING_BRICKS)
    }

    /// A fresh World with the scene's settings and gravity, its bodies and joints; `ids[i]`
    /// is `bodies[i]`.
    /// Nothing half-built on error: the World is returned only when every body was added.
    pub fn build_world(&self) -> Result<(World, Vec<BodyId>), SceneError> {
        let mut world = World::new(self.settings.clone(), self.gravity)
            .map_err(|e| SceneError::physics("scene", e))?;
        let ids = self
            .bodies
            .iter()
            .enumerate()
            .map(|(i, body)| {
                world
                    .add_body(&body.def)
                    .map_err(|e| SceneError::physics(error::body_label(Some(&body.name), i), e))
            })
            .collect::<Result<Vec<BodyId>, SceneError>>()?;
        for j in &self.joints {
            let def = JointDef {
                anchor_a: j.anchor_a,
                anchor_b: j.anchor_b,
                collide_connected: j.collide_connected,
                ..JointDef::new(j.kind.clone(), j.a.map(|i| ids[i]), ids[j.b])
                    .with_break(j.break_force, j.break_torque)
            };
            world
                .add_joint(&def)
                .map_err(|e| SceneError::physics(format!("joint {:?}", j.name), e))?;
        }
        Ok((world, ids))
    }

    /// The dynamic (non-static) bodies with their index in [`Scene::bodies`].
    pub fn dynamic_bodies(&self) -> impl Iterator<Item = (usize, &SceneBody)> + '_ {
        self.bodies.iter().enumerate().filter(|(_, b)| !b.is_static)
    }
}

impl SceneBody {
    /// A body named `name` from `def`, grey; static when `def.mass` is `MassSpec::Static`.
    pub fn new(name: impl Into<String>, def: BodyDef) -> SceneBody {
        SceneBody {
            name: name.into(),
            is_static: def.mass == crate::physics::MassSpec::Static,
            def,
            colour: Colour::GREY,
        }
    }
}
