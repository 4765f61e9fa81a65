//! How the per-body paths of the daemon scale with the number of bodies: a scene file read
//! and built, spawning and removing through the daemon's command path, a pose keyframe, the
//! `…/scene` reply, a checkpoint written and read back, and a journal read and replayed. Each
//! should cost the same per body at 10k, 50k and 100k bodies (the last column: per-body time
//! at N over per-body time at 10k; 1.0 is linear, 5 or 10 would be quadratic).
//!
//! ```text
//! cargo run --release --example scaling             # all three sizes (about a minute once built)
//! cargo run --release --example scaling -- 10000    # one size
//! ```
//!
//! A plain binary (no criterion): each path is timed as the best of three runs, since the
//! question is the shape of the curve, not the last percent. The figures go in
//! docs/benchmarks.md ("Scaling with the number of bodies").

use std::hint::black_box;
use std::time::{Duration, Instant};
use tiltbox::protocol::{
    encode, BodyRef, CommandKey, EventKind, Remove, ShapeSpec, Spawn, SpawnBody, Vector,
};
use tiltbox::scene::Scene;
use tiltbox::service::journal::{replay, Journal, JournalWriter};
use tiltbox::service::{
    checkpoint, parse_command, Incoming, SceneSource, ServerConfig, Simulation,
};

/// Body counts measured.
const SIZES: [usize; 3] = [10_000, 50_000, 100_000];
/// Bodies per spawn command (the daemon's default limits.max_bodies_per_spawn).
const PER_SPAWN: usize = 64;

/// A scene file of `n` bodies written body by body, as a user's tool would write it: boxes
/// and circles on a grid 2 m apart, far enough that nothing touches, and a static ground.
fn scene_text(n: usize) -> String {
    let mut text = String::from("name = \"grid\"\n\n");
    let columns = (n as f64).sqrt().ceil() as usize;
    for i in 0..n {
        let (x, y) = (
            (i % columns) as f64 * 2.0,
            (i / columns) as f64 * 2.0 + 10.0,
        );
        let shape = if i % 2 == 0 {
            "{ type = \"rect\", width = 1, height = 0.5 }"
        } else {
            "{ type = \"circle\", radius = 0.4 }"
        };
        text.push_str(&format!(
            "[[body]]\nname = \"b{i}\"\nshape = {shape}\nposition = [{x}, {y}]\ndensity = 1\n\n"
        ));
    }
    text
}

/// The config the daemon would need to hold `n` bodies, spawned at any rate.
fn config(n: usize) -> ServerConfig {
    let mut c = ServerConfig::default();
    c.limits.max_bodies = (2 * n) as u32;
    c.limits.max_spawns_per_second = 1_000_000;
    c.limits.max_coordinate = 10_000.0;
    c.validate().expect("bench config");
    c
}

/// Best of three runs of `f` (each gets a fresh input from `setup`).
fn best<I, O>(mut setup: impl FnMut() -> I, mut f: impl FnMut(I) -> O) -> Duration {
    (0..3)
        .map(|_| {
            let input = setup();
            let t0 = Instant::now();
            black_box(f(input));
            t0.elapsed()
        })
        .min()
        .expect("three runs")
}

/// The spawn payloads for `n` bodies, `PER_SPAWN` to a command, encoded as a client sends them.
fn spawn_payloads(n: usize) -> Vec<Vec<u8>> {
    let columns = (n as f64).sqrt().ceil() as usize;
    let bodies: Vec<SpawnBody> = (0..n)
        .map(|i| {
            let (x, y) = (
                (i % columns) as f32 * 2.0,
                (i / columns) as f32 * 2.0 + 10.0,
            );
            SpawnBody::at(ShapeSpec::Circle { radius: 0.4 }, Vector::new(x, y))
        })
        .collect();
    bodies
        .chunks(PER_SPAWN)
        .map(|c| encode(&Spawn { bodies: c.to_vec() }).expect("encodable"))
        .collect()
}

/// Parse and apply every payload as a `key` command, as the daemon's tick thread does; each
/// must be accepted (an `Added` or `Removed` event, not a rejection).
fn apply_all(sim: &mut Simulation, key: CommandKey, payloads: &[Vec<u8>], c: &ServerConfig) {
    for p in payloads {
        let command = parse_command(key, p, &c.limits);
        let event = sim.apply(Incoming { key, command });
        let accepted = matches!(
            event.as_ref().map(|e| &e.kind),
            Some(EventKind::Added { .. } | EventKind::Removed { .. })
        );
        assert!(accepted, "{event:?}");
    }
}

struct Row {
    path: &'static str,
    times: Vec<Duration>,
}

fn main() {
    let only: Option<usize> = std::env::args().skip(1).find_map(|a| a.parse().ok());
    let sizes: Vec<usize> = SIZES
        .into_iter()
        .filter(|&n| only.map_or(true, |o| o == n))
        .collect();
    let mut rows: Vec<Row> = Vec::new();
    let mut record =
        |path: &'static str, t: Duration| match rows.iter_mut().find(|r| r.path == path) {
            Some(r) => r.times.push(t),
            None => rows.push(Row {
                path,
                times: vec![t],
            }),
        };
    let dir = std::env::temp_dir().join(format!("tiltbox-scaling-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");

    for &n in &sizes {
        eprintln!("{n} bodies ...");
        let text = scene_text(n);
        let c = config(n);

        let scene_path = dir.join(format!("grid-{n}.toml"));
        std::fs::write(&scene_path, &text).expect("scene file");
        record(
            "scene file loaded (Scene::load)",
            best(|| (), |()| Scene::load(&scene_path).expect("scene")),
        );
        let scene = Scene::from_toml_str(&text).expect("scene");
        record(
            "daemon started on it (Simulation::new)",
            best(
                || SceneSource::Given(Box::new(scene.clone())),
                |source| Simulation::new(&c, source).expect("sim"),
            ),
        );

        let payloads = spawn_payloads(n);
        let empty = || {
            let mut c = c.clone();
            c.scene = None;
            // The embedded Falling Bricks (ten bodies): the spawns land outside its box.
            Simulation::new(&c, SceneSource::Embedded).expect("sim")
        };
        record(
            "spawned, 64 a command (parse + apply)",
            best(empty, |mut sim| {
                apply_all(&mut sim, CommandKey::Spawn, &payloads, &c);
                sim
            }),
        );

        let sim = Simulation::new(&c, SceneSource::Given(Box::new(scene.clone()))).expect("sim");
        // Every dynamic body removed, 64 ids a command: every other body first, then the
        // rest, so that removals hit the whole World, not its end.
        let dynamic: Vec<BodyRef> = sim
            .world()
            .bodies()
            .filter(|b| !b.is_static())
            .map(|b| BodyRef::from(b.id()))
            .collect();
        let order: Vec<BodyRef> = dynamic
            .iter()
            .step_by(2)
            .chain(dynamic.iter().skip(1).step_by(2))
            .copied()
            .collect();
        let removals: Vec<Vec<u8>> = order
            .chunks(PER_SPAWN)
            .map(|ids| encode(&Remove { ids: ids.to_vec() }).expect("encodable"))
            .collect();
        record(
            "removed, 64 a command (parse + apply)",
            best(
                || Simulation::new(&c, SceneSource::Given(Box::new(scene.clone()))).expect("sim"),
                |mut sim| {
                    apply_all(&mut sim, CommandKey::Remove, &removals, &c);
                    sim
                },
            ),
        );
        record(
            "pose keyframe built and encoded",
            best(
                // A new daemon's first message is a keyframe of every body.
                || Simulation::new(&c, SceneSource::Given(Box::new(scene.clone()))).expect("sim"),
                |mut s| {
                    let mut payload = Vec::new();
                    s.snapshot_into(&mut payload);
                    payload.len()
                },
            ),
        );
        record(
            "…/scene reply built and encoded",
            best(
                || (),
                |()| encode(&sim.scene_state()).expect("encodable").len(),
            ),
        );
        let bytes = checkpoint::encode(&sim.export_state()).expect("checkpoint");
        record(
            "checkpoint encoded",
            best(
                || (),
                |()| {
                    checkpoint::encode(&sim.export_state())
                        .expect("checkpoint")
                        .len()
                },
            ),
        );
        record(
            "checkpoint decoded and restored",
            best(
                || (),
                |()| {
                    let state = checkpoint::decode(&bytes).expect("decodes");
                    Simulation::restore(&c, SceneSource::Embedded, state).expect("restores")
                },
            ),
        );

        // A journal of a run on this scene: the header (with the scene's text) and its end.
        // Replaying it rebuilds the start from the recorded text; the per-frame cost of a
        // replay beyond the step itself is the state hash, timed on its own. (The step is the
        // engine's and is measured by `cargo bench --bench step`.)
        let journal_path = dir.join(format!("grid-{n}.journal"));
        let mut jc = c.clone();
        jc.scene = Some(scene_path.clone());
        let source = SceneSource::File(scene_path.clone());
        let live = Simulation::new(&jc, source.clone()).expect("sim");
        let mut writer =
            JournalWriter::create(&journal_path, &jc, &source, &live, false).expect("journal");
        writer.finish(&live);
        drop(writer);
        record(
            "journal read, its start rebuilt",
            best(
                || (),
                |()| {
                    let journal = Journal::read(&journal_path).expect("journal");
                    let report = replay(&journal, None, |_| {}).expect("replays");
                    assert!(report.clean_end);
                    report
                },
            ),
        );
        record(
            "state hash (per replayed frame)",
            best(|| (), |()| live.world().state_hash()),
        );
    }
    let _ = std::fs::remove_dir_all(&dir);

    let head: Vec<String> = sizes.iter().map(|n| format!("{n} bodies")).collect();
    println!(
        "| path | {} | per body at {} / at {} |",
        head.join(" | "),
        sizes[sizes.len() - 1],
        sizes[0]
    );
    println!("| --- |{} ---: |", " ---: |".repeat(sizes.len()));
    for r in &rows {
        let cells: Vec<String> = r
            .times
            .iter()
            .map(|t| format!("{:.1} ms", t.as_secs_f64() * 1e3))
            .collect();
        let first = r.times[0].as_secs_f64() / sizes[0] as f64;
        let last = r.times[r.times.len() - 1].as_secs_f64() / sizes[sizes.len() - 1] as f64;
        println!(
            "| {} | {} | {:.2} |",
            r.path,
            cells.join(" | "),
            last / first
        );
    }
}
