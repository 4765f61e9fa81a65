//! Smooth drawing: a playout buffer of the poses after each snapshot, drawn a little behind
//! the newest one and interpolated between the two around the drawing time.
//!
//! - [`interpolate`]: the pure function, from two timed poses to the pose at a time: linear in
//!   position, the short way round in angle; past the newer pose it extrapolates at most one
//!   interval (then holds).
//! - [`Playout`]: the buffer. The simulated clock is mapped to the wall clock by the quickest
//!   arrival of recent snapshots (`arrival - time` at its smallest), and the drawing time is
//!   `delay` snapshot intervals behind it (default 2), so a snapshot that is a little late is
//!   still in time. It snaps (never interpolates across) a reset, a restart and a keyframe that
//!   follows a gap, and draws a body that has no earlier pose where the snapshot put it.

use crate::protocol::BodyRef;
use std::collections::{HashMap, VecDeque};

/// A pose: x (m), y (m), angle (rad).
pub type Xya = [f32; 3];

/// Samples kept: enough for a delay of several intervals.
const KEEP: usize = 32;
/// Arrivals over which the clock offset is the smallest.
const OFFSETS: usize = 120;

/// The pose at time `t` (s) between pose `a` at `ta` and pose `b` at `tb` (`ta < tb`):
/// linear interpolation in x and y, the angle turned the short way (less than half a turn).
/// Before `ta` it is `a`; after `tb` it extrapolates the same motion at most `tb - ta` further,
/// then holds. With `ta >= tb` it is `b`.
pub fn interpolate(a: Xya, ta: f64, b: Xya, tb: f64, t: f64) -> Xya {
    if ta >= tb {
        return b;
    }
    let u = ((t - ta) / (tb - ta)).clamp(0.0, 2.0) as f32;
    let tau = std::f32::consts::TAU;
    let mut da = b[2] - a[2];
    da -= tau * (da / tau).round();
    [
        a[0] + (b[0] - a[0]) * u,
        a[1] + (b[1] - a[1]) * u,
        a[2] + da * u,
    ]
}

#[derive(Debug)]
struct Sample {
    /// Simulated time (s).
    time: f64,
    frame: u64,
    poses: HashMap<BodyRef, Xya>,
    /// Do not interpolate from the sample before this one.
    snap: bool,
}

/// The playout buffer of one view.
#[derive(Debug)]
pub struct Playout {
    /// Drawing delay, in snapshot intervals; 0 draws the newest poses as they are.
    delay: f64,
    samples: VecDeque<Sample>,
    offsets: VecDeque<f64>,
}

impl Playout {
    /// A buffer drawing `delay` snapshot intervals behind the newest (0: no buffer).
    pub fn new(delay: f64) -> Playout {
        Playout {
            delay: delay.max(0.0),
            samples: VecDeque::new(),
            offsets: VecDeque::new(),
        }
    }

    /// Forget everything (the view restarted).
    pub fn clear(&mut self) {
        self.samples.clear();
        self.offsets.clear();
    }

    /// The poses of the dynamic bodies after the snapshot of `frame` at simulated `time` (s),
    /// which arrived at wall time `arrival` (s, any fixed origin). `snap` marks a reset, or a
    /// keyframe: it is snapped to when it does not directly follow the previous sample.
    pub fn push(
        &mut self,
        frame: u64,
        time: f64,
        arrival: f64,
        poses: impl IntoIterator<Item = (BodyRef, Xya)>,
        snap: bool,
    ) {
        let follows = self
            .samples
            .back()
            .is_some_and(|s| frame == s.frame + 1 && time > s.time);
        if self.samples.back().is_some_and(|s| time <= s.time) {
            self.clear(); // time went back: a restarted daemon
        }
        self.samples.push_back(Sample {
            time,
            frame,
            poses: poses.into_iter().collect(),
            snap: snap && !follows,
        });
        if self.samples.len() > KEEP {
            self.samples.pop_front();
        }
        self.offsets.push_back(arrival - time);
        if self.offsets.len() > OFFSETS {
            self.offsets.pop_front();
        }
    }

    /// Mark the newest sample as one not to interpolate into (a reset was applied to it).
    pub fn snap_newest(&mut self) {
        if let Some(s) = self.samples.back_mut() {
            s.snap = true;
        }
    }

    /// The snapshot interval (s): the median of the recent differences in simulated time.
    pub fn interval(&self) -> f64 {
        let mut d: Vec<f64> = self
            .samples
            .iter()
            .zip(self.samples.iter().skip(1))
            .map(|(a, b)| b.time - a.time)
            .filter(|d| *d > 0.0)
            .collect();
        if d.is_empty() {
            return 1.0 / 60.0;
        }
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    }

    /// The simulated time drawn at wall time `now` (s): `delay` intervals behind the newest
    /// snapshot's expected arrival. `None` before any sample.
    pub fn draw_time(&self, now: f64) -> Option<f64> {
        let newest = self.samples.back()?;
        if self.delay == 0.0 {
            return Some(newest.time);
        }
        let offset = self.offsets.iter().copied().fold(f64::INFINITY, f64::min);
        Some(now - offset - self.delay * self.interval())
    }

    /// The poses to draw at wall time `now` (s): each body's pose at the drawing time,
    /// interpolated between the samples around it, extrapolated at most one interval past the
    /// newest; bodies absent from the earlier sample, and every body across a snap, as the
    /// later sample has them.
    pub fn poses_at(&self, now: f64) -> Option<HashMap<BodyRef, Xya>> {
        let t = self.draw_time(now)?;
        let n = self.samples.len();
        // the first sample later than t, or the newest (extrapolate from the pair before it)
        let i = self
            .samples
            .iter()
            .position(|s| s.time > t)
            .unwrap_or(n - 1);
        let b = &self.samples[i];
        if i == 0 || b.snap {
            let at = if i == 0 { b } else { &self.samples[i - 1] };
            // before the oldest sample, or before a snap: the sample itself
            return Some(if t >= b.time { b } else { at }.poses.clone());
        }
        let a = &self.samples[i - 1];
        Some(
            b.poses
                .iter()
                .map(|(id, pb)| {
                    let p = match a.poses.get(id) {
                        Some(pa) => interpolate(*pa, a.time, *pb, b.time, t),
                        None => *pb,
                    };
                    (*id, p)
                })
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 1.0 / 60.0;

    fn id(index: u32) -> BodyRef {
        BodyRef {
            index,
            generation: 0,
        }
    }

    #[test]
    fn poses_between_two_snapshots_are_interpolated_the_short_way_round() {
        let a = [0.0, 10.0, 3.0];
        let b = [1.0, 8.0, -3.0]; // 0.28 rad further through pi, not 6 rad back
        let m = interpolate(a, 1.0, b, 2.0, 1.5);
        assert_eq!((m[0], m[1]), (0.5, 9.0));
        let short = (std::f32::consts::TAU - 6.0) / 2.0;
        assert!((m[2] - (3.0 + short)).abs() < 1e-5, "{m:?}");
        assert_eq!(interpolate(a, 1.0, b, 2.0, 0.0), a);
        assert_eq!(interpolate(a, 1.0, b, 2.0, 2.0)[..2], b[..2]);
    }

    #[test]
    fn a_late_snapshot_is_extrapolated_at_most_one_interval() {
        let (a, b) = ([0.0, 0.0, 0.0], [1.0, -1.0, 0.5]);
        // half an interval late: half a step further
        assert_eq!(interpolate(a, 0.0, b, 1.0, 1.5), [1.5, -1.5, 0.75]);
        // three intervals late: one step further, then it holds
        assert_eq!(interpolate(a, 0.0, b, 1.0, 4.0), [2.0, -2.0, 1.0]);
        // through the buffer: the newest is at 0.1 s, the drawing time far past it
        let mut p = Playout::new(2.0);
        for f in 1..=6u64 {
            let t = f as f64 * DT;
            p.push(f, t, t, [(id(1), [t as f32, 0.0, 0.0])], false);
        }
        let late = p.poses_at(10.0).unwrap()[&id(1)][0] as f64;
        assert!((late - 7.0 * DT).abs() < 1e-6, "{late}");
    }

    #[test]
    fn a_reset_snaps_and_new_bodies_appear_where_they_are() {
        let mut p = Playout::new(2.0);
        p.push(1, DT, DT, [(id(1), [0.0, 0.0, 0.0])], false);
        p.push(2, 2.0 * DT, 2.0 * DT, [(id(1), [1.0, 0.0, 0.0])], false);
        // a reset at frame 3: body 1 is elsewhere, body 2 new
        let reset = [(id(1), [50.0, 0.0, 0.0]), (id(2), [7.0, 7.0, 0.0])];
        p.push(3, 3.0 * DT, 3.0 * DT, reset, false);
        p.snap_newest();
        p.push(4, 4.0 * DT, 4.0 * DT, [(id(1), [51.0, 0.0, 0.0])], false);
        // drawn 2 intervals behind: between frames 2 and 3 in time, but never between worlds
        let at = |now: f64| p.poses_at(now).unwrap();
        let before = at(4.5 * DT);
        assert_eq!(
            before[&id(1)],
            [1.0, 0.0, 0.0],
            "frame 2 held up to the reset"
        );
        let after = at(5.5 * DT);
        assert_eq!(after[&id(1)], [50.5, 0.0, 0.0], "interpolated after it");
        // a keyframe after a gap snaps; one that follows its frame does not
        let mut q = Playout::new(2.0);
        for (f, x) in [(1, 0.0), (2, 1.0), (5, 4.0), (6, 5.0), (7, 6.0)] {
            let t = f as f64 * DT;
            q.push(f, t, t, [(id(1), [x, 0.0, 0.0])], f >= 5);
        }
        // drawn at 4.5 frames: frame 2 held up to the keyframe after the gap
        assert_eq!(q.poses_at(6.5 * DT).unwrap()[&id(1)], [1.0, 0.0, 0.0]);
        // drawn at 5.5 frames: between keyframes 5 and 6, which follow each other
        assert_eq!(q.poses_at(7.5 * DT).unwrap()[&id(1)], [4.5, 0.0, 0.0]);
        // no buffer: the newest as it is
        let mut r = Playout::new(0.0);
        r.push(1, DT, 99.0, [(id(1), [3.0, 0.0, 0.0])], false);
        assert_eq!(r.poses_at(0.0).unwrap()[&id(1)], [3.0, 0.0, 0.0]);
    }

    /// A deterministic delay in [0, max) s for the snapshot of `frame`.
    fn network(frame: u64, max: f64) -> f64 {
        let x = frame.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 11;
        x as f64 / (1u64 << 53) as f64 * max
    }

    /// A brick falling from rest under 9.81 m/s^2 for 2 s, snapshots at 60 Hz arriving with up to
    /// `net` s of delay, drawn at 30 Hz (the terminal's rate) by a buffer of `delay`
    /// intervals; returns the RMS of the change in the drawn displacement from one drawing
    /// to the next (m): 0 for motion drawn smoothly, a snapshot step when one is skipped.
    fn jitter(delay: f64, net: f64) -> f64 {
        let y = |t: f64| 100.0 - 0.5 * 9.81 * t * t;
        let mut p = Playout::new(delay);
        let (mut drawn, mut frame) = (Vec::new(), 1u64);
        let mut pending: Vec<(f64, u64)> = Vec::new();
        for k in 0..45 {
            let now = 0.5 + k as f64 / 30.0 + 0.004; // not in phase with the ticks
            while (frame as f64) * DT <= now {
                pending.push(((frame as f64) * DT + network(frame, net), frame));
                frame += 1;
            }
            pending.sort_by(|a, b| a.0.total_cmp(&b.0));
            while pending.first().is_some_and(|(at, _)| *at <= now) {
                let (at, f) = pending.remove(0);
                let t = f as f64 * DT;
                p.push(f, t, at, [(id(1), [0.0, y(t) as f32, 0.0])], false);
            }
            if let Some(poses) = p.poses_at(now) {
                drawn.push(poses[&id(1)][1] as f64);
            }
        }
        let steps: Vec<f64> = drawn.windows(2).map(|w| w[1] - w[0]).collect();
        let change: Vec<f64> = steps.windows(2).map(|w| w[1] - w[0]).collect();
        (change.iter().map(|c| c * c).sum::<f64>() / change.len() as f64).sqrt()
    }

    #[test]
    fn the_buffer_takes_the_network_jitter_out_of_a_falling_brick() {
        // free fall changes the displacement between drawings by g / 30^2 = 10.9 mm: the
        // floor for both. Without the buffer, a drawing shows 1 to 3 new snapshots.
        let floor = 9.81 / 900.0;
        for net in [0.0, 0.008, 0.016] {
            let (raw, smooth) = (jitter(0.0, net), jitter(2.0, net));
            println!(
                "network delay 0-{:.0} ms: frame-to-frame jitter {:.1} mm as received, {:.1} mm \
                 with the 2-interval buffer (free fall alone: {:.1} mm)",
                net * 1e3,
                raw * 1e3,
                smooth * 1e3,
                floor * 1e3
            );
            assert!(smooth < floor * 1.05, "{smooth}");
            if net > 0.0 {
                assert!(raw > 3.0 * smooth, "{raw} vs {smooth}");
            }
        }
    }
}
