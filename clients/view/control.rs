//! `--control` (always on in `tiltbox demo`): the viewer's keys drive the world. A key becomes
//! a command through the mapping `tiltbox-tilt` uses ([`key_command`]), and a command becomes
//! a payload to put here, a pure function tested as such; the daemon's ACL decides whether
//! the put is let through.

use super::world::WorldView;
use crate::client::tilt::keyboard::{KeyCommand, KeyboardTilt};
use crate::protocol::{encode, Colour, Keys, Reset, ShapeSpec, Spawn, SpawnBody, Vector};

pub use crate::client::tilt::keyboard::{key_command, Key, KEY_HELP};

/// A payload to put: its key, its bytes, and whether to put it with congestion control
/// Block (spawn and reset must not be lost; a tilt is superseded by the next).
#[derive(Clone, Debug, PartialEq)]
pub struct Put {
    /// Full key expression.
    pub key: String,
    /// The payload (version byte and message).
    pub payload: Vec<u8>,
    /// Congestion control Block.
    pub block: bool,
}

/// The virtual device the arrows turn, and how many bricks were dropped.
#[derive(Debug, Default)]
pub struct Control {
    /// The device, as `tiltbox-tilt`'s keyboard has it.
    pub device: KeyboardTilt,
    spawned: u32,
}

/// Brick colours, in turn.
const COLOURS: [Colour; 4] = [
    Colour {
        r: 0xd6,
        g: 0x45,
        b: 0x41,
    },
    Colour {
        r: 0x3a,
        g: 0x7b,
        b: 0xd5,
    },
    Colour {
        r: 0x2e,
        g: 0xcc,
        b: 0x71,
    },
    Colour {
        r: 0xf3,
        g: 0x9c,
        b: 0x12,
    },
];

impl Control {
    /// What to put for `command` on the world of `keys`, seen as `view`: a tilt from the
    /// device, a 0.8 x 0.4 m brick near the top of the walls (spread across their middle 70 %
    /// by the golden ratio; nothing before the scene reply), or a reset. `None` for quit.
    pub fn put(
        &mut self,
        command: KeyCommand,
        keys: &Keys,
        view: Option<&WorldView>,
    ) -> Option<Put> {
        let put = |key, payload: Vec<u8>, block| {
            Some(Put {
                key,
                payload,
                block,
            })
        };
        match command {
            KeyCommand::Tilt(k) => put(keys.tilt(), encode(&self.device.key(k)).ok()?, false),
            KeyCommand::Reset => put(keys.reset(), encode(&Reset).ok()?, true),
            KeyCommand::Spawn => {
                let (x0, _, x1, y1) = view?.bounds()?;
                let u = (self.spawned as f32 * 0.618_034).fract();
                // clear of the walls (their thickness is not known here): 15 % a side
                let margin = ((x1 - x0) * 0.15).max(1.0).min((x1 - x0) / 4.0);
                let x = x0 + margin + u * (x1 - x0 - 2.0 * margin);
                let brick = SpawnBody {
                    name: Some(format!("brick {}", self.spawned + 1)),
                    colour: COLOURS[self.spawned as usize % COLOURS.len()],
                    ..SpawnBody::at(
                        ShapeSpec::Rect {
                            width: 0.8,
                            height: 0.4,
                        },
                        Vector::new(x, y1 - 0.5),
                    )
                };
                self.spawned += 1;
                let spawn = Spawn {
                    bodies: vec![brick],
                };
                put(keys.spawn(), encode(&spawn).ok()?, true)
            }
            KeyCommand::Quit => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{decode, BodyInfo, BodyRef, Orientation, SceneState, Tilt};

    fn walls() -> WorldView {
        let wall = |index, x, y, width, height| {
            let id = BodyRef {
                index,
                generation: 0,
            };
            BodyInfo::wall(id, ShapeSpec::Rect { width, height }, Vector::new(x, y))
        };
        WorldView::from_scene(SceneState {
            world: "bricks".into(),
            scene: "box".into(),
            frame: 1,
            time: 0.0,
            gravity: Vector::new(0.0, -9.81),
            bodies: vec![
                wall(0, 0.0, -0.25, 10.0, 0.5),
                wall(1, -5.0, 4.0, 0.5, 8.0),
                wall(2, 5.0, 4.0, 0.5, 8.0),
            ],
        })
    }

    #[test]
    fn the_demo_keys_tilt_spawn_and_reset_through_the_shared_mapping() {
        let keys = Keys::for_world("bricks").unwrap();
        let view = walls();
        let mut c = Control::default();
        let mut put = |key| c.put(key_command(key).unwrap(), &keys, Some(&view));
        // r: landscape right, as in tiltbox-tilt; a tilt may be dropped
        let p = put(Key::Char('r')).unwrap();
        assert_eq!((p.key.as_str(), p.block), ("tiltbox/bricks/tilt", false));
        let tilt: Tilt = decode(&p.payload).unwrap();
        assert_eq!(tilt, Tilt::Orientation(Orientation::LandscapeRight));
        // an arrow turns the device from there: a reading, not an orientation
        let tilt: Tilt = decode(&put(Key::Left).unwrap().payload).unwrap();
        assert!(matches!(tilt, Tilt::Accelerometer { .. }), "{tilt:?}");
        // space: a brick inside the walls, near their top, sent with Block
        for _ in 0..5 {
            let p = put(Key::Char(' ')).unwrap();
            assert_eq!((p.key.as_str(), p.block), ("tiltbox/bricks/spawn", true));
            let spawn: Spawn = decode(&p.payload).unwrap();
            let b = &spawn.bodies[0];
            assert!(
                b.position.x > -4.75 + 0.4 && b.position.x < 4.75 - 0.4,
                "{b:?}"
            );
            assert_eq!(b.position.y, 7.5);
        }
        // R: reset, with Block
        let p = put(Key::Char('R')).unwrap();
        assert_eq!((p.key.as_str(), p.block), ("tiltbox/bricks/reset", true));
        assert_eq!(decode::<Reset>(&p.payload), Ok(Reset));
        // no scene yet: nothing to aim a brick at
        let mut c = Control::default();
        assert_eq!(c.put(KeyCommand::Spawn, &keys, None), None);
        assert_eq!(c.put(KeyCommand::Quit, &keys, None), None);
    }
}
