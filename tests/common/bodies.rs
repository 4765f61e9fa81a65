//! Bodies to spawn, as a client would send them.

use super::rng::Rng;
use tiltbox::protocol::{ShapeSpec, SpawnBody, Vector};

/// A random brick named `b<n>`: every field drawn from `rng`, in order, so runs repeat.
pub fn random_brick(rng: &mut Rng) -> SpawnBody {
    let name = Some(format!("b{}", rng.next() % 1000));
    let shape = ShapeSpec::Rect {
        width: rng.f(0.3, 1.5),
        height: rng.f(0.3, 1.0),
    };
    let position = Vector::new(rng.f(-4.0, 4.0), rng.f(2.0, 9.0));
    SpawnBody {
        name,
        angle: rng.f(-1.0, 1.0),
        velocity: Vector::new(rng.f(-3.0, 3.0), rng.f(-3.0, 3.0)),
        angular_velocity: rng.f(-2.0, 2.0),
        density: rng.f(0.5, 3.0),
        friction: rng.f(0.0, 1.0),
        restitution: rng.f(0.0, 0.5),
        ..SpawnBody::at(shape, position)
    }
}
