//! The command journal and deterministic replay.
//!
//! `tiltbox serve --record LOG` writes every command the tick thread takes from its channel,
//! stamped with the frame it is applied before, and a hash of every body's state after every
//! step. `tiltbox replay LOG` rebuilds the same Simulation (same config, same scene, or the
//! same starting checkpoint), applies the same commands at the same frames, and compares the
//! hash at every frame: on the same build the run is bit-identical (docs/reliability.md says
//! why and what would break it).
//!
//! File layout (all integers little-endian): magic `TILTJRNL`, format version (u32), then
//! records, each framed as
//!
//! | bytes | field |
//! | --- | --- |
//! | 4 | payload length n (u32) |
//! | 4 | `!n`, its bitwise complement: a damaged length is caught, not mistaken for a torn tail |
//! | 8 | FNV-1a 64 of the payload |
//! | n | payload: postcard of a [`Header`] (record 0) or a [`Record`] (records 1, 2, ...) |
//!
//! Reading tells two kinds of damage apart. A *torn tail* - the file ends inside the last
//! record, as when the daemon is killed mid-write - ends the log there (`truncated`) and
//! everything before it replays. Anything else - a length and its complement that disagree, a
//! checksum that does not match, a payload that does not decode - is damage *inside* the log
//! and refuses it, naming the record and its byte offset: records after it cannot be trusted
//! to be the ones written.

use super::checkpoint;
use super::command::{Command, Incoming};
use super::config::ServerConfig;
use super::files::FileError;
use super::sim::{SceneSource, Simulation, StartError};
use crate::physics::hash::fnv1a;
use crate::protocol::CommandKey;
use crate::scene::Scene;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Bumped whenever the header, the records or their framing change shape. Version 4 added
/// the per-record length check and checksum, commands that set a kinematic body's velocity,
/// segment and chain shapes and kinematic bodies; older journals are refused (re-record the run).
pub const FORMAT_VERSION: u32 = 4;
const MAGIC: &[u8; 8] = b"TILTJRNL";
/// Bytes before the first record: magic and version.
const FILE_HEAD: usize = 8 + 4;
/// Bytes of a record's framing before its payload: length, its complement, checksum.
const RECORD_HEAD: usize = 4 + 4 + 8;
/// Largest record accepted when reading (a corrupt length must not allocate gigabytes).
const MAX_RECORD: u32 = 256 << 20;

/// Where the recorded run's scene came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum JournalScene {
    /// The embedded Falling Bricks.
    Embedded,
    /// A scene file: its path and its text at start (so the log replays on its own).
    File {
        /// Path as configured.
        path: String,
        /// The file's text when recording started.
        text: String,
    },
    /// A scene given in memory (tests): replay needs it given again.
    Given {
        /// Its name.
        name: String,
    },
}

/// The first record: everything needed to rebuild the starting Simulation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// The daemon's config, as TOML.
    pub config_toml: String,
    /// The scene.
    pub scene: JournalScene,
    /// When the run was resumed from a checkpoint: that checkpoint's bytes.
    pub start: Option<Vec<u8>>,
    /// The frame of the starting state.
    pub start_frame: u64,
}

/// One journal entry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Record {
    /// A command taken from the channel, applied (or rejected) before frame `frame` is stepped.
    Command {
        /// The frame it is applied before.
        frame: u64,
        /// [`CommandKey::index`] of the key it arrived on.
        key: u8,
        /// The validated command, or why the intake refused it.
        command: Result<Command, String>,
    },
    /// The World after frame `frame` was stepped.
    Frame {
        /// The frame.
        frame: u64,
        /// [`crate::physics::World::state_hash`] of the World: every body's state bits and gravity.
        hash: u64,
    },
    /// The daemon stopped cleanly after `frame`.
    End {
        /// The last frame stepped.
        frame: u64,
    },
}

/// Why a journal cannot be written, read or replayed.
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    /// The file cannot be written or read, or is not a usable journal.
    #[error(transparent)]
    File(#[from] FileError),
    /// The recorded run cannot be rebuilt.
    #[error("cannot rebuild the recorded run: {0}")]
    Start(String),
}

/// Append `value` to `out` as one framed record (length, complement, checksum, payload).
fn frame_bytes(out: &mut Vec<u8>, value: &impl Serialize) -> Result<(), String> {
    let bytes = postcard::to_stdvec(value).map_err(|e| e.to_string())?;
    let len = u32::try_from(bytes.len())
        .ok()
        .filter(|&n| n <= MAX_RECORD)
        .ok_or_else(|| format!("a record of {} bytes is too large", bytes.len()))?;
    out.extend_from_slice(&len.to_le_bytes());
    out.extend_from_slice(&(!len).to_le_bytes());
    out.extend_from_slice(&fnv1a(&bytes).to_le_bytes());
    out.extend_from_slice(&bytes);
    Ok(())
}

/// One record's place in the file, for messages: `record 7 at byte offset 412`.
fn record_at(index: u64, offset: usize) -> String {
    if index == 0 {
        format!("record 0 (the header) at byte offset {offset}")
    } else {
        format!("record {index} at byte offset {offset}")
    }
}

/// What the reader found at one record's position.
enum Framed<'a> {
    /// A whole record whose length and checksum are intact.
    Whole(&'a [u8]),
    /// The file ends inside this record (a torn tail).
    Torn,
}

/// Read the record at `bytes[*at..]`, advancing `at`; `None` at the end of the file.
fn next_record<'a>(
    bytes: &'a [u8],
    at: &mut usize,
    index: u64,
) -> Option<Result<Framed<'a>, String>> {
    let rest = &bytes[*at..];
    if rest.is_empty() {
        return None;
    }
    if rest.len() < 8 {
        return Some(Ok(Framed::Torn));
    }
    let word = |i: usize| u32::from_le_bytes([rest[i], rest[i + 1], rest[i + 2], rest[i + 3]]);
    let (len, check) = (word(0), word(4));
    let damaged = |what: String| Some(Err(format!("{}: {what}", record_at(index, *at))));
    if check != !len {
        return damaged(format!(
            "the length field is damaged (length {len:#010x}, check {check:#010x}, \
             which should be its complement {:#010x})",
            !len
        ));
    }
    if len > MAX_RECORD {
        return damaged(format!(
            "length {len} is larger than the largest record, {MAX_RECORD} bytes"
        ));
    }
    if rest.len() < RECORD_HEAD + len as usize {
        return Some(Ok(Framed::Torn));
    }
    let stored = u64::from_le_bytes(rest[8..16].try_into().expect("8 bytes"));
    let payload = &rest[RECORD_HEAD..RECORD_HEAD + len as usize];
    let computed = fnv1a(payload);
    if stored != computed {
        return damaged(format!(
            "checksum mismatch (stored {stored:016x}, computed {computed:016x} over its {len} \
             payload bytes): the record is damaged"
        ));
    }
    *at += RECORD_HEAD + len as usize;
    Some(Ok(Framed::Whole(payload)))
}

/// Writes the journal from the tick thread. Buffered; flushed once per frame, so a SIGKILL
/// loses at most the frame in progress. A write error is logged once and stops the journal.
pub struct JournalWriter {
    path: PathBuf,
    file: Option<BufWriter<File>>,
    buf: Vec<u8>,
    records: u64,
}

impl JournalWriter {
    /// Create (truncate) `path` and write the header for a run of `sim`, started from scratch
    /// (`start = None`) or from a checkpoint's bytes.
    pub fn create(
        path: &Path,
        config: &ServerConfig,
        source: &SceneSource,
        sim: &Simulation,
        resumed: bool,
    ) -> Result<JournalWriter, JournalError> {
        let io = |e| JournalError::File(FileError::io(path)(e));
        let invalid = |reason: String| JournalError::File(FileError::invalid(path)(reason));
        let scene = match source {
            SceneSource::Embedded => JournalScene::Embedded,
            SceneSource::File(p) => JournalScene::File {
                path: p.display().to_string(),
                text: std::fs::read_to_string(p).map_err(FileError::io(p))?,
            },
            SceneSource::Given(s) => JournalScene::Given {
                name: s.name.clone(),
            },
        };
        let start = if resumed {
            Some(checkpoint::encode(&sim.export_state()).map_err(invalid)?)
        } else {
            None
        };
        let header = Header {
            config_toml: toml::to_string(config).map_err(|e| invalid(e.to_string()))?,
            scene,
            start,
            start_frame: sim.frame(),
        };
        let mut buf = Vec::new();
        buf.extend_from_slice(MAGIC);
        buf.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        frame_bytes(&mut buf, &header).map_err(invalid)?;
        let mut file = BufWriter::new(File::create(path).map_err(io)?);
        file.write_all(&buf).map_err(io)?;
        file.flush().map_err(io)?;
        buf.clear();
        Ok(JournalWriter {
            path: path.to_owned(),
            file: Some(file),
            buf,
            records: 0,
        })
    }

    /// Records written so far (the header not counted).
    pub fn records(&self) -> u64 {
        self.records
    }

    fn write(&mut self, record: &Record, flush: bool) {
        let Some(file) = self.file.as_mut() else {
            return;
        };
        self.buf.clear();
        let result = frame_bytes(&mut self.buf, record)
            .map_err(std::io::Error::other)
            .and_then(|()| file.write_all(&self.buf))
            .and_then(|()| if flush { file.flush() } else { Ok(()) });
        match result {
            Ok(()) => self.records += 1,
            Err(e) => {
                tracing::error!(path = %self.path.display(), "journal stopped: {e}");
                self.file = None;
            }
        }
    }

    /// A command taken from the channel before `frame`.
    pub fn command(&mut self, frame: u64, incoming: &Incoming) {
        self.write(
            &Record::Command {
                frame,
                key: incoming.key.index() as u8,
                command: incoming.command.clone(),
            },
            false,
        );
    }

    /// The World after a step.
    pub fn stepped(&mut self, sim: &Simulation) {
        self.write(
            &Record::Frame {
                frame: sim.frame(),
                hash: sim.world().state_hash(),
            },
            true,
        );
    }

    /// A clean stop.
    pub fn finish(&mut self, sim: &Simulation) {
        self.write(&Record::End { frame: sim.frame() }, true);
        if let Some(f) = self.file.as_mut() {
            let _ = f.get_ref().sync_all();
        }
    }
}

/// A journal read back.
#[derive(Clone, Debug)]
pub struct Journal {
    /// The header.
    pub header: Header,
    /// Every complete record.
    pub records: Vec<Record>,
    /// The file ends inside its last record (a crash while writing): a torn tail.
    pub truncated: bool,
}

impl Journal {
    /// Read a journal file. A torn tail ends the records; any other damage is an error.
    pub fn read(path: &Path) -> Result<Journal, JournalError> {
        let bytes = std::fs::read(path).map_err(FileError::io(path))?;
        Ok(Journal::parse(&bytes).map_err(FileError::invalid(path))?)
    }

    /// Parse a journal's bytes: the header and every whole record. A torn tail ends the
    /// records (`truncated`); damage anywhere else is an error naming the record (0 is the
    /// header) and its byte offset.
    pub fn parse(bytes: &[u8]) -> Result<Journal, String> {
        if bytes.len() < FILE_HEAD || &bytes[..8] != MAGIC {
            return Err("not a tiltbox journal (bad magic)".into());
        }
        let version = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
        if version != FORMAT_VERSION {
            let hint = if version < FORMAT_VERSION {
                " (written by an older tiltbox, without per-record checksums: record the run again)"
            } else {
                " (written by a newer tiltbox)"
            };
            return Err(format!(
                "journal format version {version}, this build reads {FORMAT_VERSION}{hint}"
            ));
        }
        let mut at = FILE_HEAD;
        let header: Header = match next_record(bytes, &mut at, 0) {
            Some(Ok(Framed::Whole(b))) => postcard::from_bytes(b)
                .map_err(|e| format!("{}: bad header: {e}", record_at(0, FILE_HEAD)))?,
            Some(Err(e)) => return Err(e),
            _ => return Err("truncated header: the file ends inside record 0".into()),
        };
        let mut records = Vec::new();
        let mut truncated = false;
        let mut index = 1;
        loop {
            let offset = at;
            match next_record(bytes, &mut at, index) {
                None => break,
                Some(Err(e)) => return Err(e),
                Some(Ok(Framed::Torn)) => {
                    truncated = true;
                    break;
                }
                Some(Ok(Framed::Whole(b))) => {
                    let record = postcard::from_bytes::<Record>(b).map_err(|e| {
                        format!(
                            "{}: its checksum matches but it does not decode: {e}",
                            record_at(index, offset)
                        )
                    })?;
                    records.push(record);
                }
            }
            index += 1;
        }
        Ok(Journal {
            header,
            records,
            truncated,
        })
    }

    /// The recorded config.
    pub fn config(&self) -> Result<ServerConfig, JournalError> {
        let c = ServerConfig::from_toml_str(&self.header.config_toml, Path::new("<journal>"))
            .map_err(|e| JournalError::Start(e.to_string()))?;
        c.validate()
            .map_err(|e| JournalError::Start(e.to_string()))?;
        Ok(c)
    }

    /// The scene source of the recorded run (`given` replaces it, and is required for a
    /// scene that was given in memory).
    pub fn scene_source(&self, given: Option<SceneSource>) -> Result<SceneSource, JournalError> {
        if let Some(s) = given {
            return Ok(s);
        }
        match &self.header.scene {
            JournalScene::Embedded => Ok(SceneSource::Embedded),
            JournalScene::File { text, .. } => Scene::from_toml_str(text)
                .map(|s| SceneSource::Given(Box::new(s)))
                .map_err(|e| JournalError::Start(format!("recorded scene: {e}"))),
            JournalScene::Given { name } => Err(JournalError::Start(format!(
                "the run used an in-memory scene ({name:?}): give it with --scene"
            ))),
        }
    }
}

impl Journal {
    /// The last frame the log reaches (its `End` record, else its last `Frame` record), or
    /// `None` if it records no step.
    pub fn last_frame(&self) -> Option<u64> {
        self.records.iter().rev().find_map(|r| match r {
            Record::Frame { frame, .. } | Record::End { frame } => Some(*frame),
            Record::Command { .. } => None,
        })
    }
}

/// What a replay found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReplayReport {
    /// Frame the run started from.
    pub start_frame: u64,
    /// Last frame stepped.
    pub last_frame: u64,
    /// Commands applied (or rejected, as recorded).
    pub commands: u64,
    /// Frames whose hash was compared.
    pub frames_checked: u64,
    /// The first frame whose hash differs: (frame, recorded, replayed).
    pub first_mismatch: Option<(u64, u64, u64)>,
    /// Frames that differed.
    pub mismatches: u64,
    /// The log ended cleanly (an `End` record).
    pub clean_end: bool,
    /// The log's last record was cut short.
    pub truncated: bool,
    /// Hash of the final World.
    pub final_hash: u64,
}

/// Replay `journal`: rebuild the starting Simulation, apply each command at its frame, step,
/// and compare every frame's hash. `on_frame(frame, hash)` sees every replayed frame.
pub fn replay(
    journal: &Journal,
    scene: Option<SceneSource>,
    on_frame: impl FnMut(&Simulation),
) -> Result<ReplayReport, JournalError> {
    replay_with(journal, scene, |_| {}, on_frame)
}

/// [`replay`], with `on_start` seeing the starting Simulation before anything is applied or
/// stepped (`tiltbox simulate --journal` prints it).
pub fn replay_with(
    journal: &Journal,
    scene: Option<SceneSource>,
    on_start: impl FnOnce(&Simulation),
    mut on_frame: impl FnMut(&Simulation),
) -> Result<ReplayReport, JournalError> {
    let config = journal.config()?;
    let source = journal.scene_source(scene)?;
    let start = |e: StartError| JournalError::Start(e.to_string());
    let mut sim = match &journal.header.start {
        Some(bytes) => {
            let state = checkpoint::decode(bytes).map_err(JournalError::Start)?;
            Simulation::restore(&config, source, state).map_err(start)?
        }
        None => Simulation::new(&config, source).map_err(start)?,
    };
    on_start(&sim);
    let mut report = ReplayReport {
        start_frame: sim.frame(),
        truncated: journal.truncated,
        ..Default::default()
    };
    let step = |sim: &mut Simulation| -> Result<(), JournalError> {
        sim.step_guarded()
            .map(|_| ())
            .map_err(|e| JournalError::Start(format!("step {}: {e}", sim.next_frame())))
    };
    for record in &journal.records {
        match record {
            Record::Command {
                frame,
                key,
                command,
            } => {
                if *frame != sim.next_frame() {
                    return Err(JournalError::Start(format!(
                        "a command stamped with frame {frame} arrives when the next frame is {}",
                        sim.next_frame()
                    )));
                }
                let key = *CommandKey::ALL.get(*key as usize).ok_or_else(|| {
                    JournalError::Start(format!("unknown command key index {key}"))
                })?;
                // The event is what the daemon published; a replay only needs the state.
                let _ = sim.apply(Incoming {
                    key,
                    command: command.clone(),
                });
                report.commands += 1;
            }
            Record::Frame { frame, hash } => {
                step(&mut sim)?;
                if sim.frame() != *frame {
                    return Err(JournalError::Start(format!(
                        "replayed frame {} where the log has frame {frame}",
                        sim.frame()
                    )));
                }
                let h = sim.world().state_hash();
                report.frames_checked += 1;
                if h != *hash {
                    report.mismatches += 1;
                    report.first_mismatch.get_or_insert((*frame, *hash, h));
                }
                on_frame(&sim);
            }
            Record::End { frame } => {
                while sim.frame() < *frame {
                    step(&mut sim)?;
                    on_frame(&sim);
                }
                report.clean_end = true;
            }
        }
    }
    report.last_frame = sim.frame();
    report.final_hash = sim.world().state_hash();
    Ok(report)
}
