//! Where a simulation's scene comes from; `…/reset` loads it again from there.

use crate::scene::{Scene, SceneError};
use crate::service::config::ServerConfig;
use std::path::PathBuf;

/// Where the scene comes from; `…/reset` loads it again from here.
#[derive(Clone, Debug)]
pub enum SceneSource {
    /// The Falling Bricks scene compiled into the binary.
    Embedded,
    /// A scene file, re-read on every reset.
    File(PathBuf),
    /// A scene held in memory (tests, benchmarks).
    Given(Box<Scene>),
}

impl SceneSource {
    /// The scene source a config names.
    pub fn from_config(config: &ServerConfig) -> SceneSource {
        match &config.scene {
            Some(path) => SceneSource::File(path.clone()),
            None => SceneSource::Embedded,
        }
    }

    /// Load (or reload) the scene.
    pub fn load(&self) -> Result<Scene, SceneError> {
        match self {
            SceneSource::Embedded => Scene::embedded_default(),
            SceneSource::File(path) => Scene::load(path),
            SceneSource::Given(scene) => Ok((**scene).clone()),
        }
    }
}
