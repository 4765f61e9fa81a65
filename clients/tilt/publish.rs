//! Publishing tilts: every new reading on `…/tilt` at once, and the latest one again at a
//! steady rate when nothing changes (congestion Drop, express: a newer reading supersedes).

use super::STANDARD_GRAVITY;
use crate::client::ClientError;
use crate::protocol::{encode, Keys, Tilt};
use std::time::Duration;
use zenoh::pubsub::Publisher;
use zenoh::qos::CongestionControl;
use zenoh::Session;

/// A short text for a tilt message, e.g. `accel (0.00, 9.81, 0.00) -> gravity (-0.00, -9.81)`.
pub fn describe(t: &Tilt) -> String {
    let g = t.gravity(STANDARD_GRAVITY);
    match t {
        Tilt::Orientation(o) => format!("{o:?} -> gravity ({:.2}, {:.2})", g.x, g.y),
        Tilt::Accelerometer { x, y, z } => format!(
            "accel ({x:.2}, {y:.2}, {z:.2}) -> gravity ({:.2}, {:.2})",
            g.x, g.y
        ),
    }
}

/// Puts [`Tilt`] messages on `…/tilt` (congestion Drop, express: a newer reading supersedes).
pub struct TiltPublisher {
    publisher: Publisher<'static>,
    last: Option<Tilt>,
    sent: u64,
}

impl TiltPublisher {
    /// Declare the publisher on `keys.tilt()`.
    pub async fn new(session: &Session, keys: &Keys) -> Result<TiltPublisher, ClientError> {
        let publisher = session
            .declare_publisher(keys.tilt())
            .congestion_control(CongestionControl::Drop)
            .express(true)
            .await
            .map_err(ClientError::zenoh("tilt publisher"))?;
        Ok(TiltPublisher {
            publisher,
            last: None,
            sent: 0,
        })
    }

    /// Publish `tilt` now and remember it as the latest.
    pub async fn send(&mut self, tilt: Tilt) -> Result<(), ClientError> {
        let payload = encode(&tilt).map_err(|e| ClientError::Zenoh(e.to_string()))?;
        self.publisher
            .put(payload)
            .await
            .map_err(ClientError::zenoh("cannot publish a tilt"))?;
        self.last = Some(tilt);
        self.sent += 1;
        Ok(())
    }

    /// The latest message published.
    pub fn last(&self) -> Option<Tilt> {
        self.last
    }

    /// How many messages were published.
    pub fn sent(&self) -> u64 {
        self.sent
    }
}

/// Publish every message from `readings` as it comes, and the latest one again whenever
/// `1 / rate_hz` seconds pass without a new one. Returns when `readings` closes.
pub async fn publish_loop(
    publisher: &mut TiltPublisher,
    rate_hz: f64,
    mut readings: tokio::sync::mpsc::Receiver<Tilt>,
) -> Result<(), ClientError> {
    let period = Duration::from_secs_f64(1.0 / rate_hz);
    let mut tick = tokio::time::interval(period);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        tokio::select! {
            r = readings.recv() => match r {
                Some(t) => {
                    publisher.send(t).await?;
                    tick.reset();
                }
                None => return Ok(()),
            },
            _ = tick.tick() => {
                if let Some(t) = publisher.last() {
                    publisher.send(t).await?;
                }
            }
        }
    }
}
