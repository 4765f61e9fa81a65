//! `--control` (always on in `tiltbox demo`): the viewer's keys drive the world. A key becomes
//! a command through the mapping `tiltbox-tilt` uses ([`key_command`]), and a command becomes
//! a payload to put here, a pure function tested as such; the daemon's ACL decides whether
//! the put is let through.

use super::world::WorldView;
use crate::client::tilt::keyboard::{KeyCommand, KeyboardTilt};
use crate::protocol::{encode, Colour, Drag, Keys, Reset, ShapeSpec, Spawn, SpawnBody, Vector};

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

/// The virtual device the arrows turn, how many bricks were dropped, and the body the mouse
/// holds.
#[derive(Debug, Default)]
pub struct Control {
    /// The device, as `tiltbox-tilt`'s keyboard has it.
    pub device: KeyboardTilt,
    spawned: u32,
    /// The mouse's hand on `…/drag` while its button holds a body, its target, and when the
    /// target was last sent.
    holding: Option<(u64, Vector, std::time::Instant)>,
}

/// What the mouse did, at a world point (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mouse {
    /// The left button went down.
    Down((f32, f32)),
    /// It moved with the button down.
    Drag((f32, f32)),
    /// The button came up.
    Up((f32, f32)),
}

/// The mouse's hand id on `…/drag`: this process's id in the high bits, so two viewers on one
/// world do not share a hand.
pub(super) fn mouse_hand() -> u64 {
    (std::process::id() as u64) << 16 | 1
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

impl Control {
    /// What to put for a mouse action on the world of `keys`, seen as `view`: the button down
    /// on a dynamic body grabs it there (within half a metre's tenth of its outline), a drag
    /// moves the grab's target, the button up lets go (so a flick throws). Down on empty
    /// space, or a drag or release holding nothing: nothing.
    pub fn mouse(&mut self, action: Mouse, keys: &Keys, view: Option<&WorldView>) -> Option<Put> {
        let at = |(x, y): (f32, f32)| Vector::new(x, y);
        let now = std::time::Instant::now();
        let drag = match action {
            Mouse::Down(p) => {
                let id = super::render::body_at(view?, p, 0.05)?;
                let hand = mouse_hand();
                self.holding = Some((hand, at(p), now));
                Drag::Grab {
                    hand,
                    id,
                    point: at(p),
                }
            }
            Mouse::Drag(p) => {
                let (hand, _, _) = self.holding?;
                self.holding = Some((hand, at(p), now));
                Drag::Move {
                    hand,
                    target: at(p),
                }
            }
            Mouse::Up(_) => Drag::Release {
                hand: self.holding.take()?.0,
            },
        };
        Some(Put {
            key: keys.drag(),
            payload: encode(&drag).ok()?,
            block: true,
        })
    }

    /// While the button holds a body still: its target again once a second, so the daemon
    /// does not let go of a hand it has not heard from for 3 s.
    pub fn keepalive(&mut self, keys: &Keys) -> Option<Put> {
        let (hand, target, sent) = self.holding.as_mut()?;
        if sent.elapsed() < std::time::Duration::from_secs(1) {
            return None;
        }
        *sent = std::time::Instant::now();
        let drag = Drag::Move {
            hand: *hand,
            target: *target,
        };
        Some(Put {
            key: keys.drag(),
            payload: encode(&drag).ok()?,
            block: true,
        })
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

    #[test]
    fn the_mouse_grabs_the_brick_under_it_drags_it_and_lets_go() {
        let keys = Keys::for_world("bricks").unwrap();
        let mut view = walls();
        let brick = BodyInfo {
            is_static: false,
            mass: 0.32,
            ..BodyInfo::wall(
                BodyRef {
                    index: 7,
                    generation: 0,
                },
                ShapeSpec::Rect {
                    width: 0.8,
                    height: 0.4,
                },
                Vector::new(1.0, 2.0),
            )
        };
        view.bodies.insert(
            brick.id,
            crate::client::view::world::ViewBody::from_info(brick),
        );
        // The screen point over the brick, through the mapping the drawing uses.
        let area = ratatui::layout::Rect::new(0, 0, 80, 24);
        let over = (0..80u16)
            .flat_map(|c| (0..24u16).map(move |r| (c, r)))
            .filter_map(|(c, r)| super::super::render::cell_to_world(&view, area, c, r))
            .find(|&(x, y)| (x - 1.0).abs() < 0.3 && (y - 2.0).abs() < 0.2)
            .expect("a cell over the brick");
        let mut c = Control::default();
        let put = c.mouse(Mouse::Down(over), &keys, Some(&view)).unwrap();
        assert_eq!((put.key.as_str(), put.block), ("tiltbox/bricks/drag", true));
        let Drag::Grab { hand, id, point } = decode(&put.payload).unwrap() else {
            panic!("not a grab");
        };
        assert_eq!((id.index, point), (7, Vector::new(over.0, over.1)));
        let moved: Drag = decode(
            &c.mouse(Mouse::Drag((2.0, 3.0)), &keys, Some(&view))
                .unwrap()
                .payload,
        )
        .unwrap();
        assert_eq!(
            moved,
            Drag::Move {
                hand,
                target: Vector::new(2.0, 3.0)
            }
        );
        let up: Drag = decode(
            &c.mouse(Mouse::Up((2.0, 3.0)), &keys, Some(&view))
                .unwrap()
                .payload,
        )
        .unwrap();
        assert_eq!(up, Drag::Release { hand });
        // Empty space or a wall grabs nothing; nothing held, nothing to move or let go.
        assert_eq!(c.mouse(Mouse::Down((-2.0, 5.0)), &keys, Some(&view)), None);
        assert_eq!(c.mouse(Mouse::Down((5.0, 4.0)), &keys, Some(&view)), None);
        assert_eq!(c.mouse(Mouse::Drag((0.0, 1.0)), &keys, Some(&view)), None);
        assert_eq!(c.mouse(Mouse::Up((0.0, 1.0)), &keys, Some(&view)), None);
    }
}
