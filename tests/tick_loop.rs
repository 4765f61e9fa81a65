//! The tick loop on its own, without Zenoh (`service::run_loop` with outputs of the test's
//! own): it keeps time on absolute deadlines, catches up a few late ticks, drops the rest,
//! and never skips a frame number.
#![cfg(feature = "net")]

mod common;

use common::net::spawn_loop;
use std::sync::atomic::Ordering;
use std::sync::mpsc::sync_channel;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tiltbox::protocol::decode_frame;
use tiltbox::service::{Outputs, SceneSource, ServerConfig, Simulation, TickConfig};

/// Collects snapshots; stalls the loop once, on `stall_at`.
struct Fake {
    frames: Arc<Mutex<Vec<u64>>>,
    stall_at: u64,
}

impl Outputs for Fake {
    fn poses(&mut self, frame: u64, payload: Vec<u8>) {
        let s = decode_frame(&payload).unwrap();
        assert_eq!(s.frame, frame);
        self.frames.lock().unwrap().push(frame);
        if frame == self.stall_at {
            std::thread::sleep(Duration::from_millis(150));
        }
    }
    fn event(&mut self, _: Vec<u8>) {}
    fn stats(&mut self, _: Vec<u8>) {}
}

#[test]
fn the_loop_keeps_time_catches_up_a_little_and_drops_the_rest() {
    let config = ServerConfig {
        tick_hz: 100.0,
        max_catch_up: 3,
        ..Default::default()
    };
    let sim = Simulation::new(&config, SceneSource::Embedded).unwrap();
    let (_tx, rx) = sync_channel(4);
    let frames = Arc::new(Mutex::new(Vec::new()));
    let out = Fake {
        frames: frames.clone(),
        stall_at: 10,
    };
    let (stop, handle) = spawn_loop(sim, rx, out, TickConfig::of(&config, true));
    let t0 = Instant::now();
    while frames.lock().unwrap().len() < 40 {
        assert!(t0.elapsed() < Duration::from_secs(5), "loop too slow");
        std::thread::sleep(Duration::from_millis(5));
    }
    let elapsed = t0.elapsed();
    stop.store(true, Ordering::Relaxed);
    let (_, summary) = handle.join().unwrap();
    let frames = frames.lock().unwrap().clone();
    // consecutive frames, no gaps: dropped time is not a dropped frame number
    assert!(frames.windows(2).all(|w| w[1] == w[0] + 1), "{frames:?}");
    // the 150 ms stall is 15 ticks: 3 are caught up, about 11 are dropped
    assert!(
        (9..=13).contains(&summary.steps_dropped),
        "dropped {}",
        summary.steps_dropped
    );
    // 40 frames at 100 Hz plus the dropped 110 ms: about 0.5 s, not 0.4 s
    assert!(elapsed > Duration::from_millis(400), "{elapsed:?}");
    assert_eq!(summary.lateness_us.len() as u64, summary.frames);
}
