//! Deterministic replay: a run recorded by the tick loop (commands stamped with their frame and
//! a hash of every body's state at every frame) replays bit-identically on the same build;
//! a journal missing one command is caught at the frame it diverges; a log cut short by a crash
//! replays up to where it ends. The last test records through a real daemon over Zenoh.
#![cfg(feature = "net")]

mod common;

use common::bodies::random_brick as brick;
use common::net::{
    daemon_config, open, serve, spawn_and_tilt_until_added, spawn_loop, subscribe, WAIT,
};
use common::rng::Rng;
use common::temp_dir;
use std::sync::atomic::Ordering;
use std::sync::mpsc::sync_channel;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tiltbox::protocol::*;
use tiltbox::service::journal::{replay, Journal, JournalWriter, Record};
use tiltbox::service::{
    parse_command, Incoming, Outputs, Recording, SceneSource, ServerConfig, Simulation, TickConfig,
};

/// Records the hash of every frame as the live loop computed it.
#[derive(Clone, Default)]
struct Hashes(Arc<Mutex<Vec<(u64, u64)>>>);

impl Outputs for Hashes {
    fn poses(&mut self, _: u64, _: Vec<u8>) {}
    fn event(&mut self, _: Vec<u8>) {}
    fn stats(&mut self, _: Vec<u8>) {}
    fn stepped(&mut self, sim: &Simulation) {
        let mut v = self.0.lock().unwrap();
        v.push((sim.frame(), sim.world().state_hash()));
    }
}

/// One random command payload, as a client would put it (some of them invalid).
fn command(rng: &mut Rng, ids: &[BodyRef]) -> (CommandKey, Vec<u8>) {
    match rng.next() % 10 {
        0..=2 => {
            let n = 1 + rng.next() % 3;
            let bodies = (0..n).map(|_| brick(rng)).collect();
            (CommandKey::Spawn, encode(&Spawn { bodies }).unwrap())
        }
        3 | 4 => (
            CommandKey::Tilt,
            encode(&Tilt::Accelerometer {
                x: rng.f(-9.0, 9.0),
                y: rng.f(-9.0, 9.0),
                z: rng.f(-3.0, 3.0),
            })
            .unwrap(),
        ),
        5 => (
            CommandKey::Gravity,
            encode(&SetGravity {
                x: rng.f(-5.0, 5.0),
                y: rng.f(-12.0, 0.0),
            })
            .unwrap(),
        ),
        6 if !ids.is_empty() => {
            let id = ids[(rng.next() % ids.len() as u64) as usize];
            (
                CommandKey::Remove,
                encode(&Remove { ids: vec![id] }).unwrap(),
            )
        }
        7 if rng.next() % 8 == 0 => (CommandKey::Reset, encode(&Reset).unwrap()),
        // Hands grab, move and let go (some of them refused: static bodies, empty hands);
        // the ones left silent are let go by the daemon's time-out, which a replay must
        // reproduce at the same frame.
        8 if !ids.is_empty() => {
            let hand = rng.next() % 3;
            let at = Vector::new(rng.f(-3.5, 3.5), rng.f(0.5, 5.0));
            let drag = match rng.next() % 3 {
                0 => Drag::Grab {
                    hand,
                    id: ids[(rng.next() % ids.len() as u64) as usize],
                    point: at,
                },
                1 => Drag::Move { hand, target: at },
                _ => Drag::Release { hand },
            };
            (CommandKey::Drag, encode(&drag).unwrap())
        }
        // A pendulum hinged to a live body or the world (refused when the live body is
        // static or gone), its joint sometimes breaking under a weak break force.
        9 if rng.next() % 2 == 0 && !ids.is_empty() => {
            let x = rng.f(-3.0, 3.0);
            let bob = BuildBody {
                name: None,
                motion: Motion::Dynamic,
                position: Vector::new(x + 0.8, 4.5),
                angle: 0.0,
                velocity: Vector::default(),
                angular_velocity: 0.0,
                colour: Colour::default(),
                parts: vec![
                    PartSpec::at(ShapeSpec::Circle { radius: 0.2 }, Vector::default()),
                    PartSpec::at(
                        ShapeSpec::Rect {
                            width: 0.3,
                            height: 0.1,
                        },
                        Vector::new(0.3, 0.0),
                    ),
                ],
            };
            let a = if rng.next() % 2 == 0 {
                JointEnd::World
            } else {
                JointEnd::Live(ids[(rng.next() % ids.len() as u64) as usize])
            };
            let joint = JointSpec {
                a,
                b: JointEnd::New(0),
                anchor_a: Vector::new(x, 5.0),
                anchor_b: Vector::new(-0.8, 0.5),
                kind: JointKindSpec::Distance {
                    length: None,
                    spring: None,
                    limit: None,
                },
                collide_connected: false,
                break_force: (rng.next() % 2 == 0).then_some(rng.f(2.0, 30.0)),
                break_torque: None,
            };
            let b = Build {
                bodies: vec![bob],
                joints: vec![joint],
            };
            (CommandKey::Build, encode(&b).unwrap())
        }
        _ => (CommandKey::Gravity, vec![1, 0xff, 0xff]), // malformed: recorded as rejected
    }
}

/// Run the real tick loop (fast wall clock, the config's dt for the World) with a journal, a
/// command source thread, until `frames` frames; returns the live hashes.
fn record(path: &std::path::Path, frames: u64, seed: u64) -> Vec<(u64, u64)> {
    record_from(SceneSource::Embedded, path, frames, seed)
}

/// [`record`] of the scene `source`.
fn record_from(
    source: SceneSource,
    path: &std::path::Path,
    frames: u64,
    seed: u64,
) -> Vec<(u64, u64)> {
    let config = ServerConfig::default();
    let sim = Simulation::new(&config, source.clone()).unwrap();
    let journal = JournalWriter::create(path, &config, &source, &sim, false).unwrap();
    let hashes = Hashes::default();
    let out = Recording {
        inner: hashes.clone(),
        journal: Some(journal),
        checkpoints: None,
    };
    let (tx, rx) = sync_channel::<Incoming>(64);
    let cfg = TickConfig {
        dt: Duration::from_millis(2),
        max_catch_up: 1000,
        ..TickConfig::of(&config, false)
    };
    let (stop, handle) = spawn_loop(sim, rx, out, cfg);
    // Commands arrive at whatever tick the loop is at: the journal is what pins them down.
    let mut rng = Rng(seed);
    let mut ids: Vec<BodyRef> = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(10);
    while hashes.0.lock().unwrap().len() < frames as usize {
        assert!(Instant::now() < deadline, "the loop is too slow");
        let (key, payload) = command(&mut rng, &ids);
        let parsed = parse_command(key, &payload, &config.limits);
        if let Ok(tiltbox::service::Command::Spawn(defs)) = &parsed {
            // Ids are not known here; guess plausible ones (stale ones are rejected).
            for (i, _) in defs.iter().enumerate() {
                ids.push(BodyRef {
                    index: 40 + i as u32 + (rng.next() % 20) as u32,
                    generation: 0,
                });
            }
        }
        let _ = tx.try_send(Incoming {
            key,
            command: parsed,
        });
        std::thread::sleep(Duration::from_millis(3));
    }
    stop.store(true, Ordering::Relaxed);
    let (out, summary) = handle.join().unwrap();
    assert!(summary.frames >= frames);
    assert!(out.journal.unwrap().records() > frames);
    let v = hashes.0.lock().unwrap().clone();
    v
}

#[test]
fn a_recorded_run_replays_bit_identically_at_every_frame() {
    let dir = temp_dir("replay");
    let path = dir.join("run.journal");
    let live = record(&path, 400, 0x9e37_79b9_7f4a_7c15);

    let journal = Journal::read(&path).unwrap();
    assert!(!journal.truncated);
    let commands = journal
        .records
        .iter()
        .filter(|r| matches!(r, Record::Command { .. }))
        .count();
    assert!(commands > 50, "only {commands} commands recorded");
    let mut replayed = Vec::new();
    let report = replay(&journal, None, |sim| {
        replayed.push((sim.frame(), sim.world().state_hash()))
    })
    .unwrap();
    assert!(report.clean_end);
    assert_eq!(report.mismatches, 0, "{report:?}");
    assert_eq!(report.frames_checked as usize, live.len());
    // every frame, compared with what the live loop computed (not only with the log)
    assert_eq!(replayed, live);
    // and the run really moved and changed: not a trivially equal pair of idle worlds
    let distinct: std::collections::BTreeSet<u64> = live.iter().map(|f| f.1).collect();
    assert!(distinct.len() > live.len() / 2);

    // A journal with one applied command missing diverges, and the replay says where. The
    // tilt removed is the last gravity change before its frame (a tilt superseded by another
    // one before the same step changes nothing when it is missing).
    let mut broken = journal.clone();
    let sets_gravity = |r: &Record, at: u64| {
        matches!(
            r,
            Record::Command {
                frame,
                command: Ok(tiltbox::service::Command::Tilt(_)
                    | tiltbox::service::Command::SetGravity(_)
                    | tiltbox::service::Command::Reset),
                ..
            } if *frame == at
        )
    };
    let i = (0..broken.records.len())
        .find(|&i| {
            let Record::Command {
                frame,
                command: Ok(tiltbox::service::Command::Tilt(_)),
                ..
            } = &broken.records[i]
            else {
                return false;
            };
            !broken.records[i + 1..]
                .iter()
                .any(|r| sets_gravity(r, *frame))
        })
        .expect("a tilt was recorded");
    let Record::Command { frame, .. } = broken.records.remove(i) else {
        unreachable!()
    };
    let report = replay(&broken, None, |_| {}).unwrap();
    let (at, _, _) = report.first_mismatch.expect("divergence detected");
    assert_eq!(at, frame, "diverges at the frame the command was applied");

    // A log cut short (as by SIGKILL mid-write) replays up to its last whole record. The cut
    // falls in the middle of the record that starts after two thirds of the file (a fixed
    // byte count could land on a record boundary, which is a clean cut, not a torn one).
    let bytes = std::fs::read(&path).unwrap();
    let offsets = record_offsets(&bytes);
    let k = offsets
        .iter()
        .position(|&at| at >= bytes.len() * 2 / 3)
        .expect("a record after two thirds");
    let end = offsets.get(k + 1).copied().unwrap_or(bytes.len());
    let cut = &bytes[..(offsets[k] + end) / 2];
    let partial = Journal::parse(cut).unwrap();
    assert!(partial.truncated);
    let report = replay(&partial, None, |_| {}).unwrap();
    assert_eq!(report.mismatches, 0);
    assert!(!report.clean_end);
    assert!(report.frames_checked > 100);

    damage_inside_is_refused(&path, &bytes);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_recorded_run_with_joints_replays_bit_identically() {
    // The door-and-rope example of docs/scenes.md (a hinge with a limit, a 10-link rope with
    // a weight), tilted and spawned into by random commands while it swings.
    let dir = temp_dir("replay-joints");
    let scene = dir.join("joints.toml");
    let doc = tiltbox_doc_example("## Example with joints");
    std::fs::write(&scene, doc).unwrap();
    let path = dir.join("run.journal");
    let live = record_from(SceneSource::File(scene), &path, 300, 0x5151_7e3a);
    let journal = Journal::read(&path).unwrap();
    let mut replayed = Vec::new();
    let mut most_joints = 0;
    let report = replay(&journal, None, |sim| {
        most_joints = most_joints.max(sim.world().joint_count());
        // the scene's 12, and any a random build added
        assert!(
            sim.world().joint_count() >= 12,
            "the scene's joints are rebuilt: {}",
            sim.world().joint_count()
        );
        replayed.push((sim.frame(), sim.world().state_hash()))
    })
    .unwrap();
    assert_eq!(report.mismatches, 0, "{report:?}");
    assert_eq!(replayed, live);
    assert!(most_joints > 12, "no build was applied in the run");
    let distinct: std::collections::BTreeSet<u64> = live.iter().map(|f| f.1).collect();
    assert!(distinct.len() > live.len() / 2, "the run moved");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The first TOML example after `heading` in docs/scenes.md.
fn tiltbox_doc_example(heading: &str) -> String {
    let doc = common::read_repo_file("docs/scenes.md");
    let at = doc.find(heading).expect("the section");
    let start = at + doc[at..].find("```toml\n").expect("a toml example") + "```toml\n".len();
    let end = start + doc[start..].find("```").unwrap();
    doc[start..end].to_owned()
}

/// Byte offsets of every record of a journal (the header is record 0), walked with the
/// documented framing: 12 bytes of magic and version, then per record a u32 length, its
/// complement, an 8-byte checksum and the payload.
fn record_offsets(bytes: &[u8]) -> Vec<usize> {
    let mut offsets = Vec::new();
    let mut at = 12;
    while at + 16 <= bytes.len() {
        let len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        offsets.push(at);
        at += 16 + len;
    }
    assert_eq!(at, bytes.len(), "the framing walks to the end of the file");
    offsets
}

/// The issue's experiment: one byte set to 0x7f in a record halfway through a cleanly ended
/// journal. The reader must refuse it naming that record and offset (not call it a torn
/// tail), and so must `tiltbox replay`, with a non-zero exit; a torn tail still replays.
fn damage_inside_is_refused(path: &std::path::Path, bytes: &[u8]) {
    let offsets = record_offsets(bytes);
    let half = offsets.len() / 2;
    let at = offsets[half];
    let named = format!("record {half} at byte offset {at}");

    // The first payload byte.
    let mut damaged = bytes.to_vec();
    damaged[at + 16] = if bytes[at + 16] == 0x7f { 0x7e } else { 0x7f };
    let e = Journal::parse(&damaged).unwrap_err();
    assert!(e.contains(&named) && e.contains("checksum mismatch"), "{e}");

    // A length byte: caught by its complement, not read as a record running past the end.
    let mut damaged = bytes.to_vec();
    damaged[at + 2] ^= 0x40;
    let e = Journal::parse(&damaged).unwrap_err();
    assert!(
        e.contains(&named) && e.contains("length field is damaged"),
        "{e}"
    );

    // A checksum byte.
    let mut damaged = bytes.to_vec();
    damaged[at + 9] ^= 0x01;
    let e = Journal::parse(&damaged).unwrap_err();
    assert!(e.contains(&named), "{e}");

    // A torn tail: the file ends inside the last record (any cut inside it).
    let last = *offsets.last().unwrap();
    for cut in [last + 1, last + 7, last + 16, bytes.len() - 1] {
        let torn = Journal::parse(&bytes[..cut]).unwrap();
        assert!(torn.truncated, "cut at {cut}");
        assert_eq!(torn.records.len(), offsets.len() - 2, "cut at {cut}");
    }

    // The binary: exit 0 on the intact log, non-zero naming the record on the damaged one.
    let bin = env!("CARGO_BIN_EXE_tiltbox");
    let run = |file: &std::path::Path| {
        let out = std::process::Command::new(bin)
            .arg("replay")
            .arg(file)
            .output()
            .unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (code, err) = run(path);
    assert_eq!(code, Some(0), "{err}");
    let mut damaged = bytes.to_vec();
    damaged[at + 16] = if bytes[at + 16] == 0x7f { 0x7e } else { 0x7f };
    let bad = path.with_extension("damaged");
    std::fs::write(&bad, &damaged).unwrap();
    let (code, err) = run(&bad);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains(&named), "{err}");
}

#[test]
fn a_damaged_journal_header_is_refused() {
    assert!(Journal::parse(b"not a journal").is_err());
    let mut b = b"TILTJRNL".to_vec();
    b.extend_from_slice(&99u32.to_le_bytes());
    let e = Journal::parse(&b).unwrap_err();
    assert!(e.contains("version 99"), "{e}");
    b.truncate(8);
    b.extend_from_slice(&tiltbox::service::journal::FORMAT_VERSION.to_le_bytes());
    b.extend_from_slice(&1_000_000u32.to_le_bytes());
    b.extend_from_slice(&0u32.to_le_bytes());
    let e = Journal::parse(&b).unwrap_err();
    assert!(
        e.contains("record 0 (the header)") && e.contains("length"),
        "{e}"
    );
    b.truncate(12);
    b.extend_from_slice(&1_000u32.to_le_bytes());
    b.extend_from_slice(&(!1_000u32).to_le_bytes());
    assert!(Journal::parse(&b).unwrap_err().contains("truncated header"));
    // A journal of the previous format (no per-record checksums) is refused, saying why.
    let mut old = b"TILTJRNL".to_vec();
    old.extend_from_slice(&3u32.to_le_bytes());
    let e = Journal::parse(&old).unwrap_err();
    assert!(e.contains("version 3") && e.contains("older"), "{e}");
}

/// Through a real daemon: `record` in the config, commands over Zenoh, clean shutdown, replay.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_daemon_records_a_journal_that_replays() {
    let port = 17510;
    let dir = temp_dir("replayd");
    let path = dir.join("daemon.journal");
    let mut config = daemon_config(port);
    config.record = Some(path.clone());
    let server = serve(&config).await;
    let keys = server.keys().clone();

    let session = open(port).await;
    let (mut events, _sub) = subscribe::<Event>(&session, keys.events()).await;
    // Wait until the daemon hears us: put spawns until one is acknowledged.
    spawn_and_tilt_until_added(&session, &keys, &mut events, &mut Rng(7), 3, WAIT).await;
    let summary = server.shutdown().await.unwrap();
    let journal = Journal::read(&path).unwrap();
    let report = replay(&journal, None, |_| {}).unwrap();
    assert!(report.clean_end);
    assert_eq!(report.mismatches, 0, "{report:?}");
    assert_eq!(report.last_frame, summary.frames);
    assert!(report.commands >= 6);
    session.close().await.unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two worlds of one daemon share a pool of two workers (`workers = 2`), each stepping 400
/// discs that never rest (enough awake bodies for a step to take the pool), while the other
/// world's tick may hold it. Each world's journal replays alone, without workers, with the same
/// state hash at every frame: sharing the pool, or finding it busy, changes no bit.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn worlds_sharing_a_pool_of_workers_replay_alone_bit_for_bit() {
    let port = 17630;
    let dir = temp_dir("pooled");
    let scene = dir.join("gas.toml");
    std::fs::write(&scene, tiltbox::service::gas_scene(400)).unwrap();
    let path = dir.join("pooled.journal");
    let mut config = daemon_config(port);
    config.scene = Some(scene);
    config.record = Some(path.clone());
    config.worlds = vec!["second".into()];
    config.workers = 2;
    let pool = tiltbox::physics::WorkerPool::new(config.workers).unwrap();
    let options = tiltbox::service::ServerOptions {
        workers: Some(pool.clone()),
        ..Default::default()
    };
    let servers = tiltbox::service::start_worlds(&config, options)
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let summaries = tiltbox::service::shutdown_worlds(servers).await.unwrap();
    assert!(
        pool.steps_shared() >= 60,
        "{} steps took the pool",
        pool.steps_shared()
    );
    let second = dir.join("pooled.journal.second");
    for (path, summary) in [(path, &summaries[0]), (second, &summaries[1])] {
        let journal = Journal::read(&path).unwrap();
        let report = replay(&journal, None, |_| {}).unwrap();
        assert!(report.clean_end, "{}", path.display());
        assert_eq!(report.mismatches, 0, "{}: {report:?}", path.display());
        assert_eq!(report.last_frame, summary.frames);
        assert!(summary.frames >= 60, "{} frames", summary.frames);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
