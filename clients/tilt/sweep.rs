//! The sweep source: a virtual device held upright and turned about the screen's normal at a
//! steady rate, so gravity goes down, left, up and right in turn.

use super::STANDARD_GRAVITY;
use crate::protocol::Tilt;
use std::time::Duration;
use tokio::sync::mpsc::Sender;

/// The reading of a device held upright (not tilted towards or away from the viewer) and
/// turned `degrees` counter-clockwise from portrait: `g (sin a, cos a, 0)`. 0 is portrait
/// (gravity down the screen), 90 landscape left (gravity to the left), 180 upside down.
pub fn sweep_reading(degrees: f64) -> Tilt {
    let (s, c) = degrees.to_radians().sin_cos();
    Tilt::Accelerometer {
        x: STANDARD_GRAVITY * s as f32,
        y: STANDARD_GRAVITY * c as f32,
        z: 0.0,
    }
}

/// The sweep source: every `1 / rate_hz` s, the reading of a device turned `deg_per_s * t`
/// degrees from portrait. Ends when the receiver is dropped.
pub async fn sweep(deg_per_s: f64, rate_hz: f64, tx: Sender<Tilt>) {
    let start = tokio::time::Instant::now();
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / rate_hz));
    loop {
        tick.tick().await;
        let deg = (deg_per_s * start.elapsed().as_secs_f64()).rem_euclid(360.0);
        if tx.send(sweep_reading(deg)).await.is_err() {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::client::tilt::test_support::{gravity as g, near as close};

    #[test]
    fn the_sweep_turns_gravity_down_left_then_up() {
        assert!(close(g(sweep_reading(0.0)), 0.0, -9.81));
        assert!(close(g(sweep_reading(90.0)), -9.81, 0.0));
        assert!(close(g(sweep_reading(180.0)), 0.0, 9.81));
    }
}
