//! The wide and scalar solves agree when contacts overflow the colouring.

use super::*;
use crate::physics::{vec2, Shape};

/// A 12 m plank on the ground with 40 small boxes resting on it: the plank has more
/// contacts than the wide solver has colours, so some of them overflow to the scalar code.
fn crowded_plank() -> World {
    let settings = Settings {
        enable_sleep: false,
        ..Settings::default()
    };
    let mut w = World::new(settings, vec2(0.0, -10.0)).unwrap();
    w.add_body(&BodyDef::fixed(Shape::rect(40.0, 1.0), vec2(0.0, -0.5)))
        .unwrap();
    w.add_body(&BodyDef::dynamic(Shape::rect(12.0, 0.5), vec2(0.0, 0.25)))
        .unwrap();
    for i in 0..40 {
        let x = -5.85 + 0.3 * i as Real;
        w.add_body(&BodyDef::dynamic(Shape::rect(0.25, 0.25), vec2(x, 0.625)))
            .unwrap();
    }
    w
}

/// The overflow path (contacts the colouring could not place, solved one by one after the
/// bundles) and the four-lane bundles solve the same physics: stepping the crowded plank
/// with the usual 32 colours (some contacts overflow) and with none (every contact takes
/// the scalar path) ends with every body within 0.1 mm. The two differ only in the order
/// the contacts are solved in, which moves a resting scene by round-off.
#[test]
fn overflow_contacts_solve_like_the_wide_bundles() {
    let mut wide = crowded_plank();
    let mut scalar = crowded_plank();
    scalar.wide.colours = Some(0);
    let mut overflowed = 0;
    for _ in 0..120 {
        wide.step(1.0 / 60.0).unwrap();
        scalar.step(1.0 / 60.0).unwrap();
        overflowed = overflowed.max(wide.wide.overflow.len());
        assert_eq!(scalar.wide.overflow.len(), scalar.contacts.len());
    }
    assert!(
        overflowed > 0,
        "the plank's 40 contacts must exceed the colours"
    );
    for (a, b) in wide.bodies().zip(scalar.bodies()) {
        let d = (a.position() - b.position()).length();
        assert!(d < 1e-4, "body {} differs by {d} m", a.id());
        assert!((a.angle() - b.angle()).abs() < 1e-3);
    }
}
