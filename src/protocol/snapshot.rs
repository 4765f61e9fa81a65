//! The `…/poses` payload, snapshot encoding version 2: poses quantized on a grid and
//! delta-coded against the latest keyframe (`docs/protocol.md`, "Snapshot", byte for byte).
//!
//! - [`Grid`]: positions in steps of `2^-bits` m (default 1/1024 m), angles in 2^16 steps per
//!   turn; a reconstructed pose is within half a step of the daemon's.
//! - [`SnapshotFrame`]: one payload as it is on the wire, [`encode_frame`] and
//!   [`decode_frame`] (stateless).
//! - [`SnapshotEncoder`] (the daemon) and [`SnapshotDecoder`] (every client): a keyframe holds
//!   every dynamic body; a delta holds the bodies whose quantized pose differs from the
//!   keyframe's, as differences from it, and the keyframe's bodies removed since. A delta
//!   needs only its keyframe, never an earlier delta, so a lost delta costs nothing and a lost
//!   keyframe only freezes the view until the next one.
//!
//! One concept, the snapshot encoding, on both ends and with its tests: over 600 lines.

use super::{BodyRef, DecodeError, Pose, Snapshot, Vector};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// The first byte of every `…/poses` payload: the snapshot encoding's version. The other keys
/// stay at protocol version [`super::VERSION`].
pub const SNAPSHOT_VERSION: u8 = 2;

/// Angle steps per turn (2 pi rad): an angle is a `u16`.
pub const ANGLE_STEPS: i64 = 1 << 16;

/// The finest position grid a daemon may use: `2^-24` m.
pub const MAX_GRID_BITS: u8 = 24;

/// The default position grid: `2^-10` m = 1/1024 m.
pub const DEFAULT_GRID_BITS: u8 = 10;

/// A quantization grid: positions in steps of `2^-bits` metres, angles in 2^16 steps a turn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    bits: u8,
}

impl Grid {
    /// The grid of `2^-bits` m, `bits` at most [`MAX_GRID_BITS`].
    pub fn new(bits: u8) -> Option<Grid> {
        (bits <= MAX_GRID_BITS).then_some(Grid { bits })
    }
    /// `bits`: positions are in steps of `2^-bits` m.
    pub fn bits(self) -> u8 {
        self.bits
    }
    /// One position step (m).
    pub fn step(self) -> f64 {
        (-(self.bits as f64)).exp2()
    }
    /// One angle step (rad): 2 pi / 2^16.
    pub fn angle_step() -> f64 {
        std::f64::consts::TAU / ANGLE_STEPS as f64
    }
    /// The grid point nearest to `x` metres (saturating far outside any world).
    pub fn quantize(self, x: f64) -> i64 {
        (x * (self.bits as f64).exp2()).round() as i64
    }
    /// Grid point `q` in metres.
    pub fn position(self, q: i64) -> f32 {
        (q as f64 * self.step()) as f32
    }
    /// The angle step nearest to `angle` rad, as a turn fraction in `0..2^16` (wrapped: an
    /// accumulated angle loses its whole turns).
    pub fn quantize_angle(angle: f64) -> u16 {
        let q = (angle / Self::angle_step()).round();
        (q.rem_euclid(ANGLE_STEPS as f64) as i64 & (ANGLE_STEPS - 1)) as u16
    }
    /// Angle step `q` in radians, within `[-pi, pi)`.
    pub fn angle(q: u16) -> f32 {
        (q as i16 as f64 * Self::angle_step()) as f32
    }
}

impl Default for Grid {
    fn default() -> Grid {
        Grid {
            bits: DEFAULT_GRID_BITS,
        }
    }
}

/// One body in a [`SnapshotFrame`], in grid units. In a keyframe: the grid point and the
/// angle step (`0..2^16`). In a delta: the difference from the body's pose in the keyframe
/// (from zero when the keyframe does not hold the body), the angle's wrapped to
/// `-2^15..2^15`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct GridPose {
    /// The body.
    pub id: BodyRef,
    /// x, in steps of the frame's grid.
    pub x: i64,
    /// y, in steps of the frame's grid.
    pub y: i64,
    /// Angle, in 2^-16 turns.
    pub angle: i64,
}

/// One `…/poses` payload as the wire carries it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SnapshotFrame {
    /// Steps since the daemon started (1 for the first; never reset).
    pub frame: u64,
    /// Simulated time, `frame * dt` (s).
    pub time: f64,
    /// Gravity in force for this step (m/s^2).
    pub gravity: Vector,
    /// 0 for a keyframe; for a delta, how many frames back its keyframe is.
    pub reference: u64,
    /// Positions are in steps of `2^-grid` m.
    pub grid: u8,
    /// Keyframe: every dynamic body. Delta: the bodies whose pose differs from the keyframe's.
    /// In slot order.
    pub poses: Vec<GridPose>,
    /// Delta only: the keyframe's bodies removed since it, in slot order.
    pub gone: Vec<BodyRef>,
}

impl SnapshotFrame {
    /// True for a keyframe.
    pub fn is_keyframe(&self) -> bool {
        self.reference == 0
    }
    /// The frame of the keyframe a delta is against (its own frame for a keyframe).
    pub fn keyframe(&self) -> u64 {
        self.frame.saturating_sub(self.reference)
    }
}

fn varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push(v as u8 | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

fn zigzag(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

/// An id in a list sorted by slot: `(index - next) * 2 + (generation != 0)`, then the
/// generation if it is not 0; `next` is one past the previous index (0 first).
fn write_id(out: &mut Vec<u8>, next: &mut u64, id: BodyRef) {
    let gap = (id.index as u64).saturating_sub(*next);
    varint(out, gap * 2 + (id.generation != 0) as u64);
    if id.generation != 0 {
        varint(out, id.generation as u64);
    }
    *next = id.index as u64 + 1;
}

/// `frame` as a payload into `out` (cleared first). Poses must be in slot order, indices
/// strictly increasing (so must `gone`); keyframe angles within `0..2^16`.
pub fn encode_frame(f: &SnapshotFrame, out: &mut Vec<u8>) {
    out.clear();
    out.push(SNAPSHOT_VERSION);
    varint(out, f.frame);
    out.extend_from_slice(&f.time.to_le_bytes());
    out.extend_from_slice(&f.gravity.x.to_le_bytes());
    out.extend_from_slice(&f.gravity.y.to_le_bytes());
    varint(out, f.reference);
    out.push(f.grid);
    varint(out, f.poses.len() as u64);
    let (mut next, mut px, mut py) = (0, 0i64, 0i64);
    for p in &f.poses {
        write_id(out, &mut next, p.id);
        if f.is_keyframe() {
            varint(out, zigzag(p.x.wrapping_sub(px)));
            varint(out, zigzag(p.y.wrapping_sub(py)));
            out.extend_from_slice(&(p.angle as u16).to_le_bytes());
            (px, py) = (p.x, p.y);
        } else {
            varint(out, zigzag(p.x));
            varint(out, zigzag(p.y));
            varint(out, zigzag(p.angle));
        }
    }
    if !f.is_keyframe() {
        varint(out, f.gone.len() as u64);
        let mut next = 0;
        for &id in &f.gone {
            write_id(out, &mut next, id);
        }
    }
}

struct Reader<'a> {
    b: &'a [u8],
}

const MESSAGE: &str = "Snapshot";

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], DecodeError> {
        if self.b.len() < n {
            return Err(DecodeError::Truncated { message: MESSAGE });
        }
        let (a, rest) = self.b.split_at(n);
        self.b = rest;
        Ok(a)
    }
    fn u8(&mut self) -> Result<u8, DecodeError> {
        Ok(self.take(1)?[0])
    }
    fn varint(&mut self, max_bytes: u32) -> Result<u64, DecodeError> {
        let mut v = 0u64;
        for k in 0..max_bytes {
            let byte = self.u8()?;
            let bits = (byte & 0x7f) as u64;
            if k == 9 && bits > 1 {
                break;
            }
            v |= bits << (7 * k);
            if byte & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(DecodeError::Malformed {
            message: MESSAGE,
            what: "a varint is longer than its type allows",
        })
    }
    fn u32(&mut self) -> Result<u32, DecodeError> {
        let v = self.varint(5)?;
        u32::try_from(v).map_err(|_| DecodeError::Malformed {
            message: MESSAGE,
            what: "a varint is longer than its type allows",
        })
    }
    fn signed(&mut self) -> Result<i64, DecodeError> {
        let v = self.varint(10)?;
        Ok((v >> 1) as i64 ^ -((v & 1) as i64))
    }
    fn f32(&mut self) -> Result<f32, DecodeError> {
        Ok(f32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn id(&mut self, next: &mut u64) -> Result<BodyRef, DecodeError> {
        let head = self.varint(6)?;
        let generation = if head & 1 == 1 { self.u32()? } else { 0 };
        let index = *next + (head >> 1);
        let index = u32::try_from(index).map_err(|_| DecodeError::Malformed {
            message: MESSAGE,
            what: "a body index beyond u32",
        })?;
        *next = index as u64 + 1;
        Ok(BodyRef { index, generation })
    }
    /// A list's length, refused when the bytes left cannot hold that many items of
    /// `min_size` bytes (so a forged count allocates nothing).
    fn count(&mut self, min_size: usize) -> Result<usize, DecodeError> {
        let n = self.varint(5)? as usize;
        if n.saturating_mul(min_size) > self.b.len() {
            return Err(DecodeError::Truncated { message: MESSAGE });
        }
        Ok(n)
    }
}

/// Decode one `…/poses` payload without any state: the version byte (must be
/// [`SNAPSHOT_VERSION`]), then the frame. Keyframe positions come out absolute; a delta's as
/// the differences the wire carries.
pub fn decode_frame(bytes: &[u8]) -> Result<SnapshotFrame, DecodeError> {
    let (&version, body) = bytes
        .split_first()
        .ok_or(DecodeError::Empty { message: MESSAGE })?;
    if version != SNAPSHOT_VERSION {
        return Err(DecodeError::SnapshotVersion { found: version });
    }
    let mut r = Reader { b: body };
    let frame = r.varint(10)?;
    let time = f64::from_le_bytes(r.take(8)?.try_into().expect("8 bytes"));
    let gravity = Vector::new(r.f32()?, r.f32()?);
    let reference = r.varint(10)?;
    let grid = r.u8()?;
    if grid > MAX_GRID_BITS {
        return Err(DecodeError::Malformed {
            message: MESSAGE,
            what: "the grid is finer than 2^-24 m",
        });
    }
    let keyframe = reference == 0;
    let n = r.count(if keyframe { 5 } else { 4 })?;
    let mut poses = Vec::with_capacity(n);
    let (mut next, mut px, mut py) = (0, 0i64, 0i64);
    for _ in 0..n {
        let id = r.id(&mut next)?;
        let (dx, dy) = (r.signed()?, r.signed()?);
        let pose = if keyframe {
            let angle = u16::from_le_bytes(r.take(2)?.try_into().expect("2 bytes")) as i64;
            (px, py) = (px.wrapping_add(dx), py.wrapping_add(dy));
            GridPose {
                id,
                x: px,
                y: py,
                angle,
            }
        } else {
            GridPose {
                id,
                x: dx,
                y: dy,
                angle: r.signed()?,
            }
        };
        poses.push(pose);
    }
    let mut gone = Vec::new();
    if !keyframe {
        let n = r.count(1)?;
        gone.reserve(n);
        let mut next = 0;
        for _ in 0..n {
            gone.push(r.id(&mut next)?);
        }
    }
    if !r.b.is_empty() {
        return Err(DecodeError::TrailingBytes {
            message: MESSAGE,
            count: r.b.len(),
        });
    }
    Ok(SnapshotFrame {
        frame,
        time,
        gravity,
        reference,
        grid,
        poses,
        gone,
    })
}

/// A quantized pose: grid x, grid y, angle step (`0..2^16`).
type Q = [i64; 3];

fn wrap_angle(d: i64) -> i64 {
    (d as u16 as i16) as i64
}

/// The daemon's side: quantizes poses and writes keyframes and deltas against the latest
/// keyframe. The caller decides which frames are keyframes.
#[derive(Debug)]
pub struct SnapshotEncoder {
    grid: Grid,
    /// The latest keyframe's frame and poses.
    key_frame: u64,
    key: HashMap<BodyRef, Q>,
    /// The keyframe's bodies removed since it, unsorted.
    gone: Vec<BodyRef>,
    message: SnapshotFrame,
    started: bool,
}

impl SnapshotEncoder {
    /// An encoder on `grid` that has sent nothing: its first frame must be a keyframe.
    pub fn new(grid: Grid) -> SnapshotEncoder {
        SnapshotEncoder {
            grid,
            key_frame: 0,
            key: HashMap::new(),
            gone: Vec::new(),
            message: SnapshotFrame {
                frame: 0,
                time: 0.0,
                gravity: Vector::default(),
                reference: 0,
                grid: grid.bits(),
                poses: Vec::new(),
                gone: Vec::new(),
            },
            started: false,
        }
    }

    /// The grid.
    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// A body was removed: deltas until the next keyframe say so if the keyframe held it.
    pub fn forget(&mut self, id: BodyRef) {
        // A set, deduplicated when encoded: looking for `id` here made removing k bodies
        // cost k^2.
        if self.key.contains_key(&id) {
            self.gone.push(id);
        }
    }

    /// Encode `frame` into `out`: a keyframe when `keyframe` (or when nothing was sent yet),
    /// otherwise a delta against the latest keyframe. `bodies` are the dynamic bodies in slot
    /// order with their pose (m, m, rad). Returns the frame as encoded.
    pub fn encode(
        &mut self,
        (frame, time, gravity): (u64, f64, Vector),
        keyframe: bool,
        bodies: impl IntoIterator<Item = (BodyRef, [f64; 3])>,
        out: &mut Vec<u8>,
    ) -> &SnapshotFrame {
        let keyframe = keyframe || !self.started;
        self.started = true;
        let m = &mut self.message;
        (m.frame, m.time, m.gravity, m.grid) = (frame, time, gravity, self.grid.bits());
        m.poses.clear();
        m.gone.clear();
        if keyframe {
            self.key.clear();
            self.gone.clear();
            self.key_frame = frame;
            m.reference = 0;
        } else {
            m.reference = frame.saturating_sub(self.key_frame).max(1);
            m.gone.extend_from_slice(&self.gone);
            m.gone.sort_unstable();
            m.gone.dedup();
        }
        for (id, [x, y, a]) in bodies {
            let q = [
                self.grid.quantize(x),
                self.grid.quantize(y),
                Grid::quantize_angle(a) as i64,
            ];
            if keyframe {
                self.key.insert(id, q);
                m.poses.push(GridPose {
                    id,
                    x: q[0],
                    y: q[1],
                    angle: q[2],
                });
                continue;
            }
            let base = match self.key.get(&id) {
                Some(&base) if base == q => continue,
                Some(&base) => base,
                None => Q::default(),
            };
            m.poses.push(GridPose {
                id,
                x: q[0].wrapping_sub(base[0]),
                y: q[1].wrapping_sub(base[1]),
                angle: wrap_angle(q[2] - base[2]),
            });
        }
        encode_frame(m, out);
        &self.message
    }
}

/// The latest keyframe a decoder holds.
#[derive(Debug)]
struct Keyframe {
    frame: u64,
    grid: Grid,
    poses: HashMap<BodyRef, Q>,
}

/// A client's side: turns `…/poses` payloads into [`Snapshot`]s. It keeps the latest
/// keyframe and the poses it last gave out; a delta whose keyframe it does not hold (lost, or
/// sent before this decoder started) is skipped, so the view waits for the next keyframe
/// rather than go wrong.
#[derive(Debug, Default)]
pub struct SnapshotDecoder {
    key: Option<Keyframe>,
    /// The poses last given out that differ from the keyframe's, or are not in it.
    changed: HashMap<BodyRef, Q>,
    last_frame: u64,
    skipped: u64,
}

/// What [`SnapshotDecoder::apply`] made of a frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Decoded {
    /// A snapshot to apply: a keyframe (every dynamic body) or the bodies whose pose changed
    /// since the previous snapshot this decoder gave out.
    Snapshot(Snapshot),
    /// A delta against a keyframe this decoder does not hold: skipped.
    MissingKeyframe {
        /// The delta's frame.
        frame: u64,
        /// The keyframe it needs.
        keyframe: u64,
    },
    /// A delta at or before the last frame given out: skipped.
    Stale {
        /// The delta's frame.
        frame: u64,
    },
}

impl SnapshotDecoder {
    /// A decoder that holds nothing: it starts with the next keyframe.
    pub fn new() -> SnapshotDecoder {
        SnapshotDecoder::default()
    }

    /// Deltas skipped so far (their keyframe was missing, or they came out of order).
    pub fn skipped(&self) -> u64 {
        self.skipped
    }

    /// Decode a payload and apply it; `Ok(None)` for a skipped delta.
    pub fn decode(&mut self, bytes: &[u8]) -> Result<Option<Snapshot>, DecodeError> {
        let frame = decode_frame(bytes)?;
        Ok(match self.apply(&frame) {
            Decoded::Snapshot(s) => Some(s),
            _ => None,
        })
    }

    /// Apply a decoded frame. A keyframe is always taken (it is complete, and a daemon that
    /// restarted begins with one).
    pub fn apply(&mut self, f: &SnapshotFrame) -> Decoded {
        let Some(grid) = Grid::new(f.grid) else {
            self.skipped += 1;
            return Decoded::MissingKeyframe {
                frame: f.frame,
                keyframe: f.keyframe(),
            };
        };
        let mut out = Vec::with_capacity(f.poses.len());
        let pose = |id: BodyRef, q: Q| Pose {
            id,
            x: grid.position(q[0]),
            y: grid.position(q[1]),
            angle: Grid::angle(q[2] as u16),
        };
        if f.is_keyframe() {
            let mut poses = HashMap::with_capacity(f.poses.len());
            for p in &f.poses {
                let q = [p.x, p.y, p.angle & (ANGLE_STEPS - 1)];
                poses.insert(p.id, q);
                out.push(pose(p.id, q));
            }
            self.key = Some(Keyframe {
                frame: f.frame,
                grid,
                poses,
            });
            self.changed.clear();
        } else {
            let key = match &self.key {
                Some(k) if k.frame == f.keyframe() && k.grid == grid => k,
                _ => {
                    self.skipped += 1;
                    return Decoded::MissingKeyframe {
                        frame: f.frame,
                        keyframe: f.keyframe(),
                    };
                }
            };
            if f.frame <= self.last_frame {
                self.skipped += 1;
                return Decoded::Stale { frame: f.frame };
            }
            // The poses now: the keyframe's, less `gone`, with `poses` added to them.
            let mut now: HashMap<BodyRef, Q> = HashMap::with_capacity(f.poses.len());
            for p in &f.poses {
                let base = key.poses.get(&p.id).copied().unwrap_or_default();
                let q = [
                    base[0].wrapping_add(p.x),
                    base[1].wrapping_add(p.y),
                    (base[2] + p.angle).rem_euclid(ANGLE_STEPS),
                ];
                now.insert(p.id, q);
                if self.changed.get(&p.id).or(key.poses.get(&p.id)) != Some(&q) {
                    out.push(pose(p.id, q));
                }
            }
            // Bodies back at their keyframe pose (listed before, not now, not gone).
            for id in self.changed.keys() {
                if !now.contains_key(id) && f.gone.binary_search(id).is_err() {
                    if let Some(&q) = key.poses.get(id) {
                        out.push(pose(*id, q));
                    }
                }
            }
            self.changed = now;
        }
        out.sort_unstable_by_key(|p| p.id);
        self.last_frame = f.frame;
        Decoded::Snapshot(Snapshot {
            frame: f.frame,
            time: f.time,
            gravity: f.gravity,
            keyframe: f.is_keyframe(),
            poses: out,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn id(index: u32, generation: u32) -> BodyRef {
        BodyRef { index, generation }
    }

    #[test]
    fn the_grid_rounds_to_the_nearest_step_and_angles_wrap() {
        let g = Grid::default();
        assert_eq!(g.step(), 1.0 / 1024.0);
        for x in [0.0, 1e-4, 0.3333, -7.77, 123.456, -999.9995] {
            let err = (g.position(g.quantize(x)) as f64 - x).abs();
            assert!(err <= g.step() / 2.0 + 1e-12, "{x}: {err}");
        }
        // half a turn either way is the same step; whole turns are dropped
        let tau = std::f64::consts::TAU;
        assert_eq!(Grid::quantize_angle(0.0), 0);
        assert_eq!(Grid::quantize_angle(-Grid::angle_step()), 65535);
        assert_eq!(Grid::quantize_angle(0.25 * tau + 3.0 * tau), 16384);
        for a in [0.1, -0.1, 3.0, -3.0, 100.0, -1e4] {
            let back = Grid::angle(Grid::quantize_angle(a)) as f64;
            let d = (back - a).rem_euclid(tau);
            let err = d.min(tau - d);
            assert!(err <= Grid::angle_step() / 2.0 + 1e-6, "{a}: {err}");
        }
        assert_eq!(Grid::new(25), None);
        // Halves round away from zero, as docs/protocol.md says.
        assert_eq!(g.quantize(1.5 / 1024.0), 2);
        assert_eq!(g.quantize(-1.5 / 1024.0), -2);
        assert_eq!(Grid::quantize_angle(1.5 * Grid::angle_step()), 2);
    }

    /// A body spawned since the keyframe is listed even at grid (0, 0, 0), and decoded there.
    #[test]
    fn a_body_new_since_the_keyframe_is_listed_even_at_the_origin() {
        let mut enc = SnapshotEncoder::new(Grid::default());
        let mut dec = SnapshotDecoder::new();
        let (old, new) = (id(1, 0), id(2, 0));
        let mut out = Vec::new();
        let g = Vector::new(0.0, -9.81);
        enc.encode((1, 1.0 / 60.0, g), true, [(old, [1.0, 1.0, 0.0])], &mut out);
        dec.decode(&out).unwrap();
        let bodies = [(old, [1.0, 1.0, 0.0]), (new, [0.0, 0.0, 0.0])];
        let f = enc
            .encode((2, 2.0 / 60.0, g), false, bodies, &mut out)
            .clone();
        assert_eq!(
            f.poses.len(),
            1,
            "the resting body is left out, the new one listed"
        );
        assert_eq!(
            (f.poses[0].id, f.poses[0].x, f.poses[0].y, f.poses[0].angle),
            (new, 0, 0, 0)
        );
        let s = dec.decode(&out).unwrap().unwrap();
        assert_eq!(s.poses.len(), 1);
        assert_eq!((s.poses[0].id, s.poses[0].x, s.poses[0].y), (new, 0.0, 0.0));
    }

    /// A world of bodies moving on a random walk, spawned and removed now and then.
    struct Walk {
        seed: u64,
        bodies: BTreeMap<BodyRef, [f64; 3]>,
        next_index: u32,
    }

    impl Walk {
        fn rand(&mut self) -> f64 {
            self.seed = self
                .seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.seed >> 11) as f64 / (1u64 << 53) as f64
        }
        /// One step: most bodies still, some creeping, some falling; returns removed ids.
        fn step(&mut self, frame: u64) -> Vec<BodyRef> {
            let ids: Vec<BodyRef> = self.bodies.keys().copied().collect();
            for (k, id) in ids.iter().enumerate() {
                let r = self.rand();
                let p = self.bodies.get_mut(id).unwrap();
                match k % 4 {
                    0 => {}                                       // asleep
                    1 => p[0] += (r - 0.5) * 2e-3,                // creeping
                    2 => (p[1], p[2]) = (p[1] - 0.1, p[2] + 0.2), // falling, spinning
                    _ => p[2] -= r * 1e-3,
                }
            }
            let mut removed = Vec::new();
            if frame % 7 == 0 {
                let victim = ids[(self.rand() * ids.len() as f64) as usize];
                self.bodies.remove(&victim);
                removed.push(victim);
            }
            if frame % 5 == 0 {
                let x = self.rand() * 20.0 - 10.0;
                self.bodies.insert(id(self.next_index, 1), [x, 5.0, 1.0]);
                self.next_index += 1;
            }
            removed
        }
        fn quantized(&self, grid: Grid) -> BTreeMap<BodyRef, (f32, f32, f32)> {
            self.bodies
                .iter()
                .map(|(id, p)| {
                    let (x, y) = (grid.quantize(p[0]), grid.quantize(p[1]));
                    let a = Grid::angle(Grid::quantize_angle(p[2]));
                    (*id, (grid.position(x), grid.position(y), a))
                })
                .collect()
        }
    }

    /// The client's view: decoded snapshots applied, removals applied as their events would.
    fn apply_view(view: &mut BTreeMap<BodyRef, (f32, f32, f32)>, s: &Snapshot) {
        if s.keyframe {
            view.clear();
        }
        for p in &s.poses {
            view.insert(p.id, (p.x, p.y, p.angle));
        }
    }

    /// Run 300 frames (keyframe every 30), dropping the payloads `drop` picks; returns how
    /// many frames the view matched the daemon exactly and how many payloads were applied.
    fn run(drop: impl Fn(u64) -> bool) -> (u64, u64, u64) {
        let grid = Grid::default();
        let mut walk = Walk {
            seed: 7,
            bodies: (0..40)
                .map(|i| (id(i, 0), [i as f64 * 0.51, 0.3, 0.0]))
                .collect(),
            next_index: 40,
        };
        let mut enc = SnapshotEncoder::new(grid);
        let mut dec = SnapshotDecoder::new();
        let mut view = BTreeMap::new();
        let (mut exact, mut applied, mut wrong_after_key) = (0, 0, 0);
        let mut out = Vec::new();
        let mut since_key_held = false;
        for frame in 1..=300u64 {
            for gone in walk.step(frame) {
                enc.forget(gone);
                view.remove(&gone); // the Removed event
            }
            let keyframe = frame % 30 == 0;
            let bodies: Vec<_> = walk.bodies.iter().map(|(id, p)| (*id, *p)).collect();
            enc.encode(
                (frame, frame as f64 / 60.0, Vector::default()),
                keyframe,
                bodies,
                &mut out,
            );
            if drop(frame) {
                continue;
            }
            let Some(s) = dec.decode(&out).unwrap() else {
                continue;
            };
            applied += 1;
            apply_view(&mut view, &s);
            since_key_held |= s.keyframe;
            let truth = walk.quantized(grid);
            // spawned bodies exist in a client once their Added event came: compare those
            let same = truth
                .iter()
                .all(|(id, p)| view.get(id).is_none_or(|v| v == p))
                && view.keys().all(|id| truth.contains_key(id));
            if same {
                exact += 1;
            } else if since_key_held {
                wrong_after_key += 1;
            }
        }
        (exact, applied, wrong_after_key)
    }

    #[test]
    fn a_view_follows_the_daemon_exactly_on_the_grid() {
        let (exact, applied, wrong) = run(|_| false);
        assert_eq!(applied, 300);
        assert_eq!((exact, wrong), (300, 0));
    }

    #[test]
    fn dropping_every_third_sample_never_corrupts_the_view() {
        // every third payload lost: frames 1, 4, 7, ... (the keyframes 30, 60, ... get
        // through). Frame 1, the first keyframe, is lost, so the 19 deltas received before
        // keyframe 30 are skipped; every other delta decodes against its keyframe although
        // the delta before it was lost, and the view is exact at every frame applied.
        let (exact, applied, wrong) = run(|f| f % 3 == 1);
        assert_eq!(applied, 200 - 19);
        assert_eq!((exact, wrong), (181, 0));
        // keyframes 30, 90, 150, ... lost too: their deltas are skipped, never applied wrong.
        // Held: keyframes 60, 120, 180, 240 with the 19 deltas after each that arrive, and 300
        let (exact, applied, wrong) = run(|f| f % 60 == 30 || f % 3 == 1);
        assert_eq!(applied, 4 * 20 + 1);
        assert_eq!((exact, wrong), (applied, 0));
    }

    #[test]
    fn bad_payloads_are_errors_never_panics_or_garbage() {
        let mut enc = SnapshotEncoder::new(Grid::default());
        let mut out = Vec::new();
        let bodies = [
            (id(0, 0), [1.0, 2.0, 0.5]),
            (id(300, 2), [-3.0, 0.25, -1.0]),
        ];
        enc.encode((9, 0.15, Vector::new(0.0, -9.81)), true, bodies, &mut out);
        let key = out.clone();
        enc.forget(id(0, 0));
        enc.encode((10, 0.16, Vector::default()), false, [bodies[1]], &mut out);
        for full in [&key, &out] {
            let f = decode_frame(full).unwrap();
            let mut again = Vec::new();
            encode_frame(&f, &mut again);
            assert_eq!(&again, full, "{f:?}");
            for n in 0..full.len() {
                assert!(decode_frame(&full[..n]).is_err(), "prefix {n}");
            }
        }
        let delta = decode_frame(&out).unwrap();
        assert_eq!((delta.reference, delta.gone.clone()), (1, vec![id(0, 0)]));
        assert_eq!(delta.poses, []); // 300v2 did not move
        let mut v1 = key.clone();
        v1[0] = 1;
        let e = decode_frame(&v1).unwrap_err();
        assert_eq!(e, DecodeError::SnapshotVersion { found: 1 });
        assert!(e.to_string().contains("version 1"), "{e}");
        // an old client meets version 2 as a version error
        assert_eq!(
            super::super::decode::<super::super::Stats>(&key),
            Err(DecodeError::Version { found: 2 })
        );
        // a forged count on a short payload allocates nothing
        let mut forged = key[..key.len() - 16].to_vec();
        let at = forged.len() - 1;
        forged.truncate(at);
        forged.extend([0xff, 0xff, 0xff, 0x0f]);
        assert!(decode_frame(&forged).is_err());
        let mut trailing = key.clone();
        trailing.push(0);
        assert!(matches!(
            decode_frame(&trailing),
            Err(DecodeError::TrailingBytes { count: 1, .. })
        ));
    }
}
