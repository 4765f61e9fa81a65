//! The `…/poses` message of each frame: a keyframe with every dynamic body every
//! `keyframe_every` frames and after a (re)load, otherwise the dynamic bodies that moved more
//! than [`POSE_EPSILON`] since they were last sent.

use crate::physics::{BodyId, World};
use crate::protocol::{Pose, Snapshot, Vector};

/// A body is sent in a delta snapshot when it moved more than this since it was last sent
/// (metres along either axis, or radians). Keyframes resend every dynamic body exactly.
pub const POSE_EPSILON: f32 = 1e-4;

/// What was last sent of each body, and the message buffer reused frame after frame.
pub(crate) struct PoseDeltas {
    /// Per slot: the generation of the body and the pose (x, y, angle) last sent.
    last_sent: Vec<Option<(u32, [f32; 3])>>,
    force_keyframe: bool,
    keyframe_every: u64,
    message: Snapshot,
}

impl PoseDeltas {
    /// Nothing sent yet: the first message is a keyframe.
    pub(crate) fn new(keyframe_every: u64) -> PoseDeltas {
        PoseDeltas {
            last_sent: Vec::new(),
            force_keyframe: true,
            keyframe_every,
            message: Snapshot {
                frame: 0,
                time: 0.0,
                gravity: Vector::default(),
                keyframe: true,
                poses: Vec::new(),
            },
        }
    }

    /// Forget everything sent: the next message is a keyframe (a new World).
    pub(crate) fn restart(&mut self) {
        self.last_sent.clear();
        self.force_keyframe = true;
    }

    /// Forget a removed body.
    pub(crate) fn forget(&mut self, id: BodyId) {
        if let Some(s) = self.last_sent.get_mut(id.index() as usize) {
            *s = None;
        }
    }

    /// The message for `frame` (at `time` s) of `world`. Call once per step.
    pub(crate) fn message(&mut self, world: &World, frame: u64, time: f64) -> &Snapshot {
        let keyframe = self.force_keyframe || frame % self.keyframe_every == 0;
        self.force_keyframe = false;
        let s = &mut self.message;
        s.frame = frame;
        s.time = time;
        s.gravity = crate::service::wire::vector(world.gravity());
        s.keyframe = keyframe;
        s.poses.clear();
        for body in world.bodies() {
            if body.is_static() {
                continue;
            }
            let id = body.id();
            let now = [
                body.position().x as f32,
                body.position().y as f32,
                body.angle() as f32,
            ];
            let i = id.index() as usize;
            if self.last_sent.len() <= i {
                self.last_sent.resize(i + 1, None);
            }
            let moved = match self.last_sent[i] {
                Some((generation, was)) if generation == id.generation() => {
                    (0..3).any(|k| (now[k] - was[k]).abs() > POSE_EPSILON)
                }
                _ => true,
            };
            if keyframe || moved {
                self.last_sent[i] = Some((id.generation(), now));
                s.poses.push(Pose {
                    id: id.into(),
                    x: now[0],
                    y: now[1],
                    angle: now[2],
                });
            }
        }
        &self.message
    }
}
