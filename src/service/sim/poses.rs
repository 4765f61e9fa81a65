//! The `…/poses` payload of each frame: a keyframe with every dynamic body every
//! `keyframe_every` frames and after a (re)load, otherwise a delta against that keyframe,
//! quantized on the configured grid ([`crate::protocol::snapshot`]).

use crate::physics::{BodyId, World};
use crate::protocol::{Grid, SnapshotEncoder, SnapshotFrame};

/// The keyframe schedule and the encoder, whose buffers are reused frame after frame.
pub(crate) struct PoseDeltas {
    encoder: SnapshotEncoder,
    force_keyframe: bool,
    keyframe_every: u64,
}

impl PoseDeltas {
    /// Nothing sent yet: the first message is a keyframe.
    pub(crate) fn new(keyframe_every: u64, grid: Grid) -> PoseDeltas {
        PoseDeltas {
            encoder: SnapshotEncoder::new(grid),
            force_keyframe: true,
            keyframe_every,
        }
    }

    /// Forget everything sent: the next message is a keyframe (a new World).
    pub(crate) fn restart(&mut self) {
        self.force_keyframe = true;
    }

    /// Forget a removed body (deltas until the next keyframe list it as gone).
    pub(crate) fn forget(&mut self, id: BodyId) {
        self.encoder.forget(id.into());
    }

    /// The payload for `frame` (at `time` s) of `world`, written into `out`; returns the
    /// frame as encoded. Call once per step.
    pub(crate) fn message(
        &mut self,
        world: &World,
        frame: u64,
        time: f64,
        out: &mut Vec<u8>,
    ) -> &SnapshotFrame {
        let keyframe = self.force_keyframe || frame % self.keyframe_every == 0;
        self.force_keyframe = false;
        let gravity = crate::service::wire::vector(world.gravity());
        let bodies = world.bodies().filter(|b| !b.is_static()).map(|b| {
            let (p, a) = (b.position(), b.angle());
            (b.id().into(), [p.x as f64, p.y as f64, a as f64])
        });
        self.encoder
            .encode((frame, time, gravity), keyframe, bodies, out)
    }
}
