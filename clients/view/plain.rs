//! `tiltbox-view --plain`: one text line per snapshot, for pipes and logs.
//!
//! ```text
//! 1234 20.566666666666666 4v0:-2.3816,0.19999,0.29 7v0:1.5,0.15,-0.0001
//! ```
//!
//! The frame, the simulated time (s), then `id:x,y,angle` (m, m, rad) for each body in the
//! snapshot (a delta lists the bodies whose pose changed, a keyframe every dynamic body),
//! as the snapshot decoder reconstructs them from the quantized wire form; lines start with
//! the first keyframe received. Numbers are
//! printed in Rust's shortest round-trip form, so parsing a line gives back exactly the `f32`s
//! decoded. With `--every N` a line is printed for every N-th snapshot received and lists
//! each body that moved since the previous line, with its newest pose. No colour, no cursor
//! movement: nothing but ASCII and spaces.

use crate::protocol::{BodyRef, Pose, Snapshot};
use std::collections::BTreeMap;
use std::fmt::Write as _;
#[cfg(feature = "tui")]
use {
    super::{Msg, ViewArgs},
    crate::client::ClientError,
    std::io::Write,
    std::sync::mpsc::{Receiver, RecvTimeoutError},
    std::time::{Duration, Instant},
};

/// Builds the lines of `--plain [--every N]`.
#[derive(Debug)]
pub struct PlainPrinter {
    every: u64,
    seen: u64,
    moved: BTreeMap<BodyRef, Pose>,
}

impl PlainPrinter {
    /// A printer of one line every `every` snapshots (0 is taken as 1).
    pub fn new(every: u64) -> PlainPrinter {
        PlainPrinter {
            every: every.max(1),
            seen: 0,
            moved: BTreeMap::new(),
        }
    }

    /// Feed a snapshot; returns the line to print, if this one is printed.
    pub fn snapshot(&mut self, s: &Snapshot) -> Option<String> {
        for p in &s.poses {
            self.moved.insert(p.id, *p);
        }
        self.seen += 1;
        if self.seen % self.every != 0 {
            return None;
        }
        let poses: Vec<Pose> = std::mem::take(&mut self.moved).into_values().collect();
        Some(format_line(s.frame, s.time, &poses))
    }
}

/// One line: `frame time id:x,y,angle ...`.
pub fn format_line(frame: u64, time: f64, poses: &[Pose]) -> String {
    let mut line = String::with_capacity(24 + poses.len() * 32);
    let _ = write!(line, "{frame} {time}");
    for p in poses {
        let _ = write!(line, " {}:{},{},{}", p.id, p.x, p.y, p.angle);
    }
    line
}

/// A line of `--plain` output read back.
#[derive(Clone, Debug, PartialEq)]
pub struct PlainLine {
    /// Frame.
    pub frame: u64,
    /// Simulated time (s).
    pub time: f64,
    /// The poses on the line.
    pub poses: Vec<Pose>,
}

/// Parse a `--plain` line; the error says which field was wrong.
pub fn parse_line(line: &str) -> Result<PlainLine, String> {
    let mut fields = line.split_ascii_whitespace();
    let frame = fields
        .next()
        .ok_or("empty line")?
        .parse::<u64>()
        .map_err(|e| format!("frame: {e}"))?;
    let time = fields
        .next()
        .ok_or("no time")?
        .parse::<f64>()
        .map_err(|e| format!("time: {e}"))?;
    let poses = fields
        .map(|f| parse_pose(f).ok_or_else(|| format!("not id:x,y,angle: {f:?}")))
        .collect::<Result<_, _>>()?;
    Ok(PlainLine { frame, time, poses })
}

fn parse_pose(field: &str) -> Option<Pose> {
    let (id, rest) = field.split_once(':')?;
    let (index, generation) = id.split_once('v')?;
    let mut nums = rest.split(',').map(|n| n.parse::<f32>().ok());
    let (x, y, angle) = (nums.next()??, nums.next()??, nums.next()??);
    if nums.next().is_some() {
        return None;
    }
    Some(Pose {
        id: BodyRef {
            index: index.parse().ok()?,
            generation: generation.parse().ok()?,
        },
        x,
        y,
        angle,
    })
}

/// Print a line per `--every` snapshots to `out` until `--count` lines, a quit or a closed
/// pipe; say on stderr when the daemon at `endpoint` is missing, up or gone.
#[cfg(feature = "tui")]
pub(super) fn run(
    rx: &Receiver<Msg>,
    args: &ViewArgs,
    endpoint: &str,
    out: &mut dyn Write,
) -> Result<(), ClientError> {
    let mut printer = PlainPrinter::new(args.every);
    let mut decoder = crate::protocol::SnapshotDecoder::new();
    let mut printed = 0u64;
    let mut alive = false;
    let started = Instant::now();
    let mut warned = false;
    loop {
        let msg = match rx.recv_timeout(Duration::from_millis(500)) {
            Ok(m) => m,
            Err(RecvTimeoutError::Timeout) => {
                if !alive && !warned && started.elapsed() > Duration::from_secs(1) {
                    eprintln!("waiting for server at {endpoint} ...");
                    warned = true;
                }
                continue;
            }
            Err(RecvTimeoutError::Disconnected) => return Ok(()),
        };
        match msg {
            Msg::Snapshot(frame, _, _) => {
                let crate::protocol::snapshot::Decoded::Snapshot(s) = decoder.apply(&frame) else {
                    continue; // a delta without its keyframe: wait for the next one
                };
                if let Some(line) = printer.snapshot(&s) {
                    if writeln!(out, "{line}").and_then(|_| out.flush()).is_err() {
                        return Ok(()); // the pipe closed
                    }
                    printed += 1;
                    if args.count.is_some_and(|n| printed >= n) {
                        return Ok(());
                    }
                }
            }
            Msg::Alive(up) => {
                if up != alive && (warned || !up) {
                    eprintln!(
                        "{}",
                        if up {
                            "server is up"
                        } else {
                            "server is gone; waiting"
                        }
                    );
                }
                alive = up;
            }
            Msg::Quit => return Ok(()),
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::Vector;

    fn pose(i: u32, x: f32) -> Pose {
        Pose {
            id: BodyRef {
                index: i,
                generation: 0,
            },
            x,
            y: -x / 3.0,
            angle: 0.1,
        }
    }

    fn snap(frame: u64, poses: Vec<Pose>) -> Snapshot {
        Snapshot {
            frame,
            time: frame as f64 / 60.0,
            gravity: Vector::new(0.0, -9.81),
            keyframe: false,
            poses,
        }
    }

    #[test]
    fn lines_round_trip_exactly() {
        let s = snap(7, vec![pose(4, 1.0 / 3.0), pose(5, -2.5e-7)]);
        let line = PlainPrinter::new(1).snapshot(&s).unwrap();
        assert!(line.is_ascii() && !line.contains('\x1b'), "{line}");
        let back = parse_line(&line).unwrap();
        assert_eq!((back.frame, back.time, back.poses), (7, s.time, s.poses));
        assert!(parse_line("7 0.1 4v0:1,2").is_err());
        assert!(parse_line("x 0.1").unwrap_err().contains("frame"));
    }

    #[test]
    fn every_n_merges_what_moved_in_between() {
        let mut p = PlainPrinter::new(3);
        assert_eq!(p.snapshot(&snap(1, vec![pose(1, 1.0)])), None);
        assert_eq!(p.snapshot(&snap(2, vec![pose(2, 2.0)])), None);
        let line = p.snapshot(&snap(3, vec![pose(1, 3.0)])).unwrap();
        let back = parse_line(&line).unwrap();
        assert_eq!(back.frame, 3);
        assert_eq!(back.poses, vec![pose(1, 3.0), pose(2, 2.0)]);
    }
}
