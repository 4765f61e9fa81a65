//! Checkpoints: the whole [`SimState`] in a versioned, checksummed file, written atomically
//! (temporary file, fsync, rename, fsync of the directory), keeping the previous one as
//! `<file>.prev`. Loading reports a damaged file and falls back to the previous one.
//!
//! File layout (all integers little-endian):
//!
//! | bytes | field |
//! | --- | --- |
//! | 8 | magic `TILTCKPT` |
//! | 4 | format version ([`FORMAT_VERSION`]) |
//! | 8 | payload length n |
//! | 8 | FNV-1a 64 of the payload |
//! | n | payload: postcard of [`SimState`] |

use super::config::ServerConfig;
use super::files::FileError;
use super::sim::{SceneSource, SimState, Simulation, StartError};
use crate::physics::hash::fnv1a;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, SyncSender, TrySendError};
use std::thread::JoinHandle;

/// Bumped whenever [`SimState`] (or anything in it, e.g. the engine's `Settings`) changes shape.
/// 4: bodies record whether they are kinematic, shapes may be segments (issue 17).
/// 5: contact points carry their friction anchor (slip, and the tangent arms).
/// 6: contacts carry what contact recycling reuses (points in both bodies' frames, the normal
/// in A's, the pair's rotation), and `Settings` has `contact_recycling`.
/// 7: the per-step constraint left the contact (contacts carry what lasts between steps only).
/// 8: contact points no longer carry a friction anchor (no slip, no stuck flag).
/// 9: the solver's history (contacts, now with their colours in the constraint graph) is one
/// record with a version of its own (`physics::world::snapshot::SolverHistory`).
/// 10: the World carries its joints (definitions and impulses) and their free list.
/// 11: bodies carry their parts (further shapes) and centre of mass, contacts which shapes
/// touch (solver history version 2).
/// 12: the solver history carries the joints' colours in the constraint graph (version 3).
/// 13: bodies carry their own shape's flags (events, sensor); parts carry theirs.
/// 14: `Settings` has `workers` (threads that share the step).
pub const FORMAT_VERSION: u32 = 14;
const MAGIC: &[u8; 8] = b"TILTCKPT";
const HEADER: usize = 8 + 4 + 8 + 8;

/// The file's bytes for `state`.
pub fn encode(state: &SimState) -> Result<Vec<u8>, String> {
    let payload = postcard::to_stdvec(state).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(HEADER + payload.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&fnv1a(&payload).to_le_bytes());
    out.extend_from_slice(&payload);
    Ok(out)
}

/// Parse a checkpoint file's bytes; every way it can be wrong is an error naming the reason.
pub fn decode(bytes: &[u8]) -> Result<SimState, String> {
    if bytes.len() < HEADER {
        return Err(format!(
            "truncated: {} bytes, shorter than the {HEADER}-byte header",
            bytes.len()
        ));
    }
    if &bytes[..8] != MAGIC {
        return Err("not a tiltbox checkpoint (bad magic)".into());
    }
    let u32_at =
        |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    let u64_at = |i: usize| u64::from(u32_at(i)) | u64::from(u32_at(i + 4)) << 32;
    let version = u32_at(8);
    if version != FORMAT_VERSION {
        return Err(format!(
            "format version {version}, this build reads version {FORMAT_VERSION}"
        ));
    }
    let len = u64_at(12);
    let payload = &bytes[HEADER..];
    if payload.len() as u64 != len {
        return Err(format!(
            "truncated or padded: payload is {} bytes, the header says {len}",
            payload.len()
        ));
    }
    if fnv1a(payload) != u64_at(20) {
        return Err("checksum mismatch: the file is damaged".into());
    }
    postcard::from_bytes(payload).map_err(|e| format!("cannot decode the state: {e}"))
}

/// Where the previous generation of `path` is kept.
pub fn previous_path(path: &Path) -> PathBuf {
    let mut p = path.as_os_str().to_owned();
    p.push(".prev");
    PathBuf::from(p)
}

fn temp_path(path: &Path) -> PathBuf {
    let mut p = path.as_os_str().to_owned();
    p.push(".tmp");
    PathBuf::from(p)
}

/// Write `bytes` to `path` atomically: a reader (or a restart after a crash at any point)
/// sees the old file, the new file, or - between the two renames - only `<path>.prev`,
/// which [`load`] falls back to. The current file becomes `<path>.prev`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    let io = FileError::io(path);
    let tmp = temp_path(path);
    let written = (|| {
        let mut f = File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        if path.exists() {
            std::fs::rename(path, previous_path(path))?;
        }
        std::fs::rename(&tmp, path)
    })();
    written.map_err(io)?;
    // Make the renames durable too.
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// A state read back, and from which file.
#[derive(Debug)]
pub struct Loaded {
    /// The state.
    pub state: SimState,
    /// The file it came from (`path` or `<path>.prev`).
    pub from: PathBuf,
    /// What was wrong with the files tried before it (reported in the log).
    pub problems: Vec<FileError>,
}

fn read_one(path: &Path) -> Result<SimState, FileError> {
    let bytes = std::fs::read(path).map_err(FileError::io(path))?;
    decode(&bytes).map_err(FileError::invalid(path))
}

/// Read the checkpoint at `path`, or if it is missing or damaged, `<path>.prev`. `Ok(None)`
/// when neither exists (a first start); an error when files exist but none is usable.
pub fn load(path: &Path) -> Result<Option<Loaded>, Vec<FileError>> {
    let mut problems = Vec::new();
    let mut any = false;
    for p in [path.to_owned(), previous_path(path)] {
        if !p.exists() {
            continue;
        }
        any = true;
        match read_one(&p) {
            Ok(state) => {
                for e in &problems {
                    tracing::warn!("checkpoint unusable, using the previous one: {e}");
                }
                return Ok(Some(Loaded {
                    state,
                    from: p,
                    problems,
                }));
            }
            Err(e) => problems.push(e),
        }
    }
    if any {
        Err(problems)
    } else {
        Ok(None)
    }
}

/// Takes checkpoints from the tick thread: the state is encoded there (a consistent cut
/// between two ticks) and written by a writer thread, so fsync never delays a tick. If the
/// writer is still busy with the previous one, the new one is skipped (and logged).
pub struct Checkpointer {
    path: PathBuf,
    every_frames: u64,
    last_frame: u64,
    tx: Option<SyncSender<Vec<u8>>>,
    writer: Option<JoinHandle<()>>,
    taken: u64,
}

impl Checkpointer {
    /// Checkpoint to `path` every `every_frames` frames, counting from `start_frame`.
    pub fn new(
        path: PathBuf,
        every_frames: u64,
        start_frame: u64,
    ) -> std::io::Result<Checkpointer> {
        let (tx, rx) = sync_channel::<Vec<u8>>(1);
        let wpath = path.clone();
        let writer = std::thread::Builder::new()
            .name("tiltbox-checkpoint".into())
            .spawn(move || {
                while let Ok(bytes) = rx.recv() {
                    if let Err(e) = write_atomic(&wpath, &bytes) {
                        tracing::error!("checkpoint not written: {e}");
                    }
                }
            })?;
        Ok(Checkpointer {
            path,
            every_frames: every_frames.max(1),
            last_frame: start_frame,
            tx: Some(tx),
            writer: Some(writer),
            taken: 0,
        })
    }

    /// Checkpoints written (or handed to the writer) so far.
    pub fn taken(&self) -> u64 {
        self.taken
    }

    /// After a step: checkpoint if `every_frames` have passed since the last one.
    pub fn stepped(&mut self, sim: &Simulation) {
        if sim.frame() < self.last_frame + self.every_frames {
            return;
        }
        self.last_frame = sim.frame();
        let bytes = match encode(&sim.export_state()) {
            Ok(b) => b,
            Err(e) => return tracing::error!("cannot encode a checkpoint: {e}"),
        };
        if let Some(tx) = &self.tx {
            match tx.try_send(bytes) {
                Ok(()) => self.taken += 1,
                Err(TrySendError::Full(_)) => {
                    tracing::warn!(
                        frame = sim.frame(),
                        "checkpoint skipped: the last one is still being written"
                    )
                }
                Err(TrySendError::Disconnected(_)) => {}
            }
        }
    }

    /// On shutdown: wait for the writer, then write the final state synchronously.
    pub fn finish(&mut self, sim: &Simulation) {
        self.tx = None;
        if let Some(w) = self.writer.take() {
            let _ = w.join();
        }
        match encode(&sim.export_state()) {
            Ok(bytes) => match write_atomic(&self.path, &bytes) {
                Ok(()) => {
                    self.taken += 1;
                    tracing::info!(frame = sim.frame(), path = %self.path.display(), "checkpoint written")
                }
                Err(e) => tracing::error!("final checkpoint not written: {e}"),
            },
            Err(e) => tracing::error!("cannot encode the final checkpoint: {e}"),
        }
    }
}

/// The Simulation a daemon starts with: with `resume` and a usable checkpoint (or its
/// previous generation), the checkpointed state; with no checkpoint file yet, the scene (a
/// first start). Files that exist but are all unusable refuse the start, naming each problem:
/// silently starting over would lose the state the user asked to keep. The flag says whether
/// it resumed.
pub fn start(config: &ServerConfig, source: SceneSource) -> Result<(Simulation, bool), StartError> {
    if let (true, Some(path)) = (config.resume, &config.checkpoint) {
        match load(path) {
            Ok(Some(loaded)) => {
                let frame = loaded.state.frame;
                let sim = Simulation::restore(config, source, loaded.state)?;
                tracing::info!(from = %loaded.from.display(), frame, "resumed from checkpoint");
                return Ok((sim, true));
            }
            Ok(None) => {
                tracing::warn!(path = %path.display(), "no checkpoint yet: starting from the scene")
            }
            Err(problems) => {
                let all: Vec<String> = problems.iter().map(|e| e.to_string()).collect();
                return Err(StartError::Checkpoint(format!(
                    "no usable checkpoint: {}",
                    all.join("; ")
                )));
            }
        }
    }
    Ok((Simulation::new(config, source)?, false))
}
