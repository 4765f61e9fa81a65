//! What a checkpoint stores of a simulation ([`SimState`]), and why a simulation cannot start
//! ([`StartError`]).

use crate::scene::SceneError;
use crate::service::wire::BodyMeta;

/// Everything a [`super::Simulation`] carries from one tick to the next: what a checkpoint
/// stores. Snapshot delta bookkeeping is not kept (a restored simulation starts with a
/// keyframe).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SimState {
    /// World name it ran as.
    pub world_name: String,
    /// Scene name.
    pub scene_name: String,
    /// |gravity| of the scene (m/s^2), which tilts scale.
    pub scene_gravity: f32,
    /// dt (s) it ran with.
    pub dt: f64,
    /// Last frame stepped.
    pub frame: u64,
    /// Per slot: the generation and what the body looks like.
    pub meta: Vec<Option<(u32, BodyMeta)>>,
    /// Frames of the spawns applied in the last second (the rate limit's window).
    pub spawn_frames: Vec<u64>,
    /// Commands applied.
    pub applied: u64,
    /// Commands rejected.
    pub rejected: u64,
    /// The World.
    pub world: crate::physics::WorldState,
}

/// Why the daemon could not start its simulation.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// The scene could not be loaded or built.
    #[error("scene: {0}")]
    Scene(#[from] SceneError),
    /// The scene has more bodies than the limit.
    #[error("the scene has {bodies} bodies, more than limits.max_bodies = {max}")]
    TooManyBodies {
        /// Bodies in the scene.
        bodies: usize,
        /// The limit.
        max: u32,
    },
    /// A checkpoint (or a journal's starting state) cannot be used.
    #[error("checkpoint: {0}")]
    Checkpoint(String),
}
