//! The keyboard source: a virtual device turned by the arrow keys or put in a discrete
//! orientation ([`KeyboardTilt`]), and, with the `tui` feature, the terminal it runs in
//! (raw mode, a status line). [`key_command`] is the one mapping from keys to commands that
//! `tiltbox-tilt`, `tiltbox-view --control` and `tiltbox demo` share.

use super::STANDARD_GRAVITY;
use crate::protocol::{Orientation, Tilt};

/// A key of the keyboard source.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TiltKey {
    /// Turn the device counter-clockwise (from portrait, gravity swings to the left).
    Left,
    /// Turn the device clockwise (from portrait, gravity swings to the right).
    Right,
    /// Lay the device back towards face up: less gravity in the screen's plane.
    Up,
    /// Raise the device back towards upright: more gravity in the screen's plane.
    Down,
    /// Put the device in a discrete orientation.
    Orientation(Orientation),
}

impl TiltKey {
    /// The orientation keys: `p` portrait, `u` upside down, `l` landscape left, `r`
    /// landscape right, `f` face up (flat), `d` face down; also `1`..`6` in that order.
    pub fn from_char(c: char) -> Option<TiltKey> {
        use Orientation::*;
        let o = match c {
            'p' | '1' => Portrait,
            'u' | '2' => PortraitUpsideDown,
            'l' | '3' => LandscapeLeft,
            'r' | '4' => LandscapeRight,
            'f' | '5' => FaceUp,
            'd' | '6' => FaceDown,
            _ => return None,
        };
        Some(TiltKey::Orientation(o))
    }
}

/// A key press, as any terminal library reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// Left arrow.
    Left,
    /// Right arrow.
    Right,
    /// Up arrow.
    Up,
    /// Down arrow.
    Down,
    /// Escape.
    Esc,
    /// A character key (space is `' '`), as typed (shift gives capitals).
    Char(char),
    /// A character key with Control held.
    Ctrl(char),
}

/// What a key asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyCommand {
    /// Turn the virtual device (then publish its tilt on `…/tilt`).
    Tilt(TiltKey),
    /// Drop a brick into the world (`…/spawn`).
    Spawn,
    /// Reload the scene (`…/reset`).
    Reset,
    /// Leave.
    Quit,
}

/// The keys, as a status line lists them.
pub const KEY_HELP: &str = "←→ roll ↑↓ lean, p/u/l/r/f/d portrait/upside down/landscape \
left/right/face up/down, space brick, R reset, q quit";

/// The command a key gives, if any: arrows and `p u l r f d` (or `1`-`6`) tilt as
/// [`TiltKey`] says, space spawns a brick, `R` (shift-r: lower-case `r` is landscape right)
/// resets, `q`, Esc and Ctrl-C quit. A front end that cannot spawn or reset ignores those.
pub fn key_command(key: Key) -> Option<KeyCommand> {
    Some(match key {
        Key::Left => KeyCommand::Tilt(TiltKey::Left),
        Key::Right => KeyCommand::Tilt(TiltKey::Right),
        Key::Up => KeyCommand::Tilt(TiltKey::Up),
        Key::Down => KeyCommand::Tilt(TiltKey::Down),
        Key::Esc | Key::Char('q') | Key::Ctrl('c') => KeyCommand::Quit,
        Key::Char(' ') => KeyCommand::Spawn,
        Key::Char('R') => KeyCommand::Reset,
        Key::Char(c) => KeyCommand::Tilt(TiltKey::from_char(c)?),
        Key::Ctrl(_) => return None,
    })
}

#[cfg(feature = "tui")]
impl Key {
    /// A crossterm key event as a [`Key`]; `None` for releases and keys no command uses.
    pub fn from_crossterm(k: crossterm::event::KeyEvent) -> Option<Key> {
        use crossterm::event::{KeyCode, KeyEventKind, KeyModifiers};
        if k.kind == KeyEventKind::Release {
            return None;
        }
        Some(match k.code {
            KeyCode::Left => Key::Left,
            KeyCode::Right => Key::Right,
            KeyCode::Up => Key::Up,
            KeyCode::Down => Key::Down,
            KeyCode::Esc => Key::Esc,
            KeyCode::Char(c) if k.modifiers.contains(KeyModifiers::CONTROL) => Key::Ctrl(c),
            KeyCode::Char(c) => Key::Char(c),
            _ => return None,
        })
    }
}

/// A virtual device: `roll` degrees counter-clockwise from portrait about the screen's
/// normal, and `lean` degrees laid back from upright (90 = flat face up, -90 = face down).
/// Its reading is `g (sin roll cos lean, cos roll cos lean, sin lean)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyboardTilt {
    /// Degrees counter-clockwise from portrait, in [0, 360).
    pub roll: f32,
    /// Degrees laid back from upright, within [-90, 90].
    pub lean: f32,
    /// Degrees per arrow key press.
    pub step: f32,
    /// The last discrete orientation chosen, until an arrow key moves away from it.
    pub orientation: Option<Orientation>,
}

impl Default for KeyboardTilt {
    fn default() -> Self {
        KeyboardTilt {
            roll: 0.0,
            lean: 0.0,
            step: 15.0,
            orientation: Some(Orientation::Portrait),
        }
    }
}

impl KeyboardTilt {
    /// Apply a key; returns the message to publish.
    pub fn key(&mut self, key: TiltKey) -> Tilt {
        match key {
            TiltKey::Left => self.roll += self.step,
            TiltKey::Right => self.roll -= self.step,
            TiltKey::Up => self.lean = (self.lean + self.step).min(90.0),
            TiltKey::Down => self.lean = (self.lean - self.step).max(-90.0),
            TiltKey::Orientation(o) => {
                use Orientation::*;
                (self.roll, self.lean) = match o {
                    Portrait => (0.0, 0.0),
                    PortraitUpsideDown => (180.0, 0.0),
                    LandscapeLeft => (90.0, 0.0),
                    LandscapeRight => (270.0, 0.0),
                    FaceUp => (self.roll, 90.0),
                    FaceDown => (self.roll, -90.0),
                };
                self.orientation = Some(o);
                return Tilt::Orientation(o);
            }
        }
        self.roll = self.roll.rem_euclid(360.0);
        self.orientation = None;
        self.tilt()
    }

    /// The current message: the discrete orientation if one was chosen last, else the reading.
    pub fn tilt(&self) -> Tilt {
        match self.orientation {
            Some(o) => Tilt::Orientation(o),
            None => self.reading(),
        }
    }

    /// The accelerometer reading of the virtual device.
    pub fn reading(&self) -> Tilt {
        let (sr, cr) = self.roll.to_radians().sin_cos();
        let (sl, cl) = self.lean.to_radians().sin_cos();
        let g = STANDARD_GRAVITY;
        let clean = |v: f32| if v.abs() < 1e-5 { 0.0 } else { v };
        Tilt::Accelerometer {
            x: clean(g * sr * cl),
            y: clean(g * cr * cl),
            z: clean(g * sl),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::client::tilt::test_support::{gravity as g, near as close};

    #[test]
    fn arrows_and_orientation_keys_point_gravity_where_expected() {
        let mut k = KeyboardTilt::default();
        assert_eq!(k.tilt(), Tilt::Orientation(Orientation::Portrait));
        for _ in 0..6 {
            k.key(TiltKey::Left);
        }
        assert!(close(g(k.tilt()), -9.81, 0.0), "{:?}", k.tilt());
        k.key(TiltKey::Orientation(Orientation::FaceUp));
        assert_eq!(k.tilt(), Tilt::Orientation(Orientation::FaceUp));
        k.key(TiltKey::Down); // from flat, raise by one step: a little gravity to the left
        let v = g(k.tilt());
        assert!(v.x < -2.0 && v.x > -3.0 && v.y.abs() < 1e-4, "{v:?}");
        assert_eq!(
            TiltKey::from_char('u'),
            Some(TiltKey::Orientation(Orientation::PortraitUpsideDown))
        );
    }

    #[test]
    fn one_mapping_gives_every_key_its_command() {
        use Orientation::*;
        let tilt = |k| Some(KeyCommand::Tilt(k));
        let table = [
            (Key::Left, tilt(TiltKey::Left)),
            (Key::Right, tilt(TiltKey::Right)),
            (Key::Up, tilt(TiltKey::Up)),
            (Key::Down, tilt(TiltKey::Down)),
            (Key::Char('p'), tilt(TiltKey::Orientation(Portrait))),
            (
                Key::Char('u'),
                tilt(TiltKey::Orientation(PortraitUpsideDown)),
            ),
            (Key::Char('l'), tilt(TiltKey::Orientation(LandscapeLeft))),
            (Key::Char('r'), tilt(TiltKey::Orientation(LandscapeRight))),
            (Key::Char('f'), tilt(TiltKey::Orientation(FaceUp))),
            (Key::Char('d'), tilt(TiltKey::Orientation(FaceDown))),
            (Key::Char('4'), tilt(TiltKey::Orientation(LandscapeRight))),
            (Key::Char(' '), Some(KeyCommand::Spawn)),
            (Key::Char('R'), Some(KeyCommand::Reset)),
            (Key::Char('q'), Some(KeyCommand::Quit)),
            (Key::Esc, Some(KeyCommand::Quit)),
            (Key::Ctrl('c'), Some(KeyCommand::Quit)),
            (Key::Ctrl('r'), None),
            (Key::Char('x'), None),
        ];
        for (key, want) in table {
            assert_eq!(key_command(key), want, "{key:?}");
        }
        // every key the help names does something
        for c in ['p', 'u', 'l', 'r', 'f', 'd', ' ', 'R', 'q'] {
            assert!(key_command(Key::Char(c)).is_some(), "{c:?}");
        }
        // the right arrow then landscape right: gravity to the right either way round
        let mut device = KeyboardTilt::default();
        let Some(KeyCommand::Tilt(k)) = key_command(Key::Char('r')) else {
            panic!()
        };
        assert!(close(g(device.key(k)), 9.81, 0.0));
    }
}
