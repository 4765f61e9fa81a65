//! The keyboard source: a virtual device turned by the arrow keys or put in a discrete
//! orientation ([`KeyboardTilt`]), and, with the `tui` feature, the terminal it runs in
//! (raw mode, a status line).

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
        let o = match c.to_ascii_lowercase() {
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
}
