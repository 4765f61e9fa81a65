//! From a device's tilt to gravity in the world's plane.
//!
//! The screen is the world: world x runs along the screen's right edge, world y up the
//! screen. A device frame has the same x and y, and z out of the screen towards the viewer.
//!
//! **Accelerometer** (Android's `TYPE_ACCELEROMETER` convention, m/s^2): a device at rest reads
//! the reaction to gravity, pointing up, so gravity in the device frame is `-a`. The world is
//! the screen's plane, so gravity in the world is the in-plane part of `-a`:
//!
//! ```text
//! g_world = (-a.x, -a.y)          (a.z is dropped: it is the part normal to the screen)
//! ```
//!
//! Held upright (portrait) the device reads a = (0, +9.81, 0) and g = (0, -9.81): bricks fall
//! to the bottom of the screen. Upside down, a = (0, -9.81, 0) and g = (0, +9.81). Lying flat,
//! a = (0, 0, +9.81) and g = (0, 0): no gravity in the plane, bricks keep drifting. Tilted by
//! theta from flat, the in-plane gravity is 9.81 sin(theta): the true projection, so small
//! tilts make gentle slopes. iOS's `CMAccelerometerData` reports g units with the opposite
//! sign: send `(-9.81 x, -9.81 y, -9.81 z)` of its values.
//!
//! **Discrete orientations** give the scene's gravity magnitude `g` along the screen edge that
//! points down (see [`super::Orientation`]); face up and face down give zero.

use super::messages::{Orientation, Tilt, Vector};

impl Orientation {
    /// Gravity in the world's plane for this orientation, with magnitude `g` (m/s^2).
    pub fn gravity(self, g: f32) -> Vector {
        match self {
            Orientation::Portrait => Vector::new(0.0, -g),
            Orientation::PortraitUpsideDown => Vector::new(0.0, g),
            Orientation::LandscapeLeft => Vector::new(-g, 0.0),
            Orientation::LandscapeRight => Vector::new(g, 0.0),
            Orientation::FaceUp | Orientation::FaceDown => Vector::new(0.0, 0.0),
        }
    }
}

/// Gravity in the world's plane from an accelerometer reading (device frame, m/s^2):
/// `(-x, -y)`. `z` is normal to the screen and does not enter.
pub fn gravity_from_accelerometer(x: f32, y: f32, _z: f32) -> Vector {
    Vector::new(-x, -y)
}

impl Tilt {
    /// The gravity this tilt asks for; `g` is the magnitude used for discrete orientations.
    pub fn gravity(&self, g: f32) -> Vector {
        match *self {
            Tilt::Orientation(o) => o.gravity(g),
            Tilt::Accelerometer { x, y, z } => gravity_from_accelerometer(x, y, z),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f32 = 9.81;

    #[test]
    fn orientations_point_gravity_at_the_lower_screen_edge() {
        assert_eq!(Orientation::Portrait.gravity(G), Vector::new(0.0, -G));
        assert_eq!(
            Orientation::PortraitUpsideDown.gravity(G),
            Vector::new(0.0, G)
        );
        assert_eq!(Orientation::LandscapeLeft.gravity(G), Vector::new(-G, 0.0));
        assert_eq!(Orientation::LandscapeRight.gravity(G), Vector::new(G, 0.0));
        assert_eq!(Orientation::FaceUp.gravity(G), Vector::default());
        assert_eq!(Orientation::FaceDown.gravity(G), Vector::default());
    }

    #[test]
    fn accelerometer_readings_match_the_orientations() {
        // What a phone at rest reads in each orientation (reaction to gravity, pointing up).
        let cases = [
            ((0.0, G, 0.0), Orientation::Portrait),
            ((0.0, -G, 0.0), Orientation::PortraitUpsideDown),
            // turned counter-clockwise: the device's +x edge points up
            ((G, 0.0, 0.0), Orientation::LandscapeLeft),
            ((-G, 0.0, 0.0), Orientation::LandscapeRight),
            ((0.0, 0.0, G), Orientation::FaceUp),
            ((0.0, 0.0, -G), Orientation::FaceDown),
        ];
        for ((x, y, z), o) in cases {
            let t = Tilt::Accelerometer { x, y, z };
            assert_eq!(t.gravity(G), o.gravity(G), "{o:?}");
        }
    }

    #[test]
    fn flat_phone_gives_no_in_plane_gravity_and_tilts_project() {
        let g = gravity_from_accelerometer(0.0, 0.0, G);
        assert_eq!(g.x, 0.0);
        assert_eq!(g.y, 0.0);
        // tilted 30 degrees about the x axis, top edge raised: in-plane gravity is g sin 30
        // pointing to the bottom of the screen.
        let th = 30f32.to_radians();
        let g = gravity_from_accelerometer(0.0, G * th.sin(), G * th.cos());
        assert!((g.y + G * 0.5).abs() < 1e-5 && g.x == 0.0, "{g:?}");
    }
}
