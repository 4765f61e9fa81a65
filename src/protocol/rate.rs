//! A token bucket, for rates of messages in wall-clock time: the web gateway's per-page
//! command rate and the daemon's `…/query` rate (here, below both, so that clients need not
//! depend on the daemon).

use std::time::Instant;

/// A token bucket: `rate` tokens a second, holding at most `rate` (one second's burst).
#[derive(Clone, Debug)]
pub struct RateLimit {
    rate: u32,
    tokens: f64,
    last: Instant,
}

impl RateLimit {
    /// A full bucket of `rate` per second (0: nothing passes).
    pub fn new(rate: u32) -> RateLimit {
        RateLimit {
            rate,
            tokens: rate as f64,
            last: Instant::now(),
        }
    }

    /// Take one token at `now`; false when the bucket is empty.
    pub fn take(&mut self, now: Instant) -> bool {
        let dt = now.saturating_duration_since(self.last).as_secs_f64();
        self.last = now;
        self.tokens = (self.tokens + dt * self.rate as f64).min(self.rate as f64);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }

    /// The rate, per second.
    pub fn rate(&self) -> u32 {
        self.rate
    }
}
