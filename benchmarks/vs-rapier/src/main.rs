//! tiltbox vs rapier2d on the benchmark scenes of `tiltbox::cases::benchmark_setups()`, built from
//! the same body definitions, stepped in the same process, timed step by step.
//!
//! ```text
//! cargo run --release -- [--quick] [--no-extras] [--chunks] [SCENE|memory|largest_pyramid ...]
//! ```
//!
//! - every scene runs its warm-up steps untimed in both engines, then its timed steps in chunks
//!   of `CHUNK` steps, alternating engines chunk by chunk (and which one goes first), so that a
//!   noisy neighbour on the machine hits both engines alike;
//! - the table gives median and minimum ms/step per engine, the ratio of the medians, and a
//!   sanity column per engine (top body height / mean body height / bodies awake) so that a
//!   collapsed pyramid is never compared with a standing one;
//! - `memory`: live heap bytes per body after building `large_pyramid` and 10 steps (counting
//!   global allocator);
//! - `largest_pyramid`: the largest pyramid base each engine steps in under 16.7 ms (median,
//!   sleep off), by bisection.
//!
//! Positional arguments select scenes by name (substring match); with any selection given, the
//! extras run only when named (`memory`, `largest_pyramid`).

use rapier2d::prelude::{
    CoefficientCombineRule, ColliderBuilder, IntegrationParameters, PhysicsWorld, RigidBodyBuilder,
    RigidBodyHandle, Vector,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use std::time::Instant;
use tiltbox::cases::{benchmark_setups, Setup};
use tiltbox::physics::{BodyDef, MassSpec, Mixing, Settings, Shape, Vec2, World};

// ---------------------------------------------------------------------------------------------
// Counting allocator: live bytes and number of allocation calls.

struct Counting;

static LIVE_BYTES: AtomicUsize = AtomicUsize::new(0);
static ALLOCS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            LIVE_BYTES.fetch_add(layout.size(), Relaxed);
            ALLOCS.fetch_add(1, Relaxed);
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            LIVE_BYTES.fetch_add(layout.size(), Relaxed);
            ALLOCS.fetch_add(1, Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE_BYTES.fetch_sub(layout.size(), Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE_BYTES.fetch_sub(layout.size(), Relaxed);
            LIVE_BYTES.fetch_add(new_size, Relaxed);
            ALLOCS.fetch_add(1, Relaxed);
        }
        p
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

// ---------------------------------------------------------------------------------------------
// Constants.

const DT: f32 = 1.0 / 60.0;
/// Steps per engine before switching to the other one.
const CHUNK: usize = 25;
/// The 60 Hz budget (ms).
const BUDGET_MS: f64 = 1000.0 / 60.0;

// ---------------------------------------------------------------------------------------------
// The two engines behind one small interface.

/// What the sanity columns show.
#[derive(Clone, Copy, Debug)]
struct Sanity {
    /// Highest centre of a dynamic body (m).
    top_y: f32,
    /// Mean height of the dynamic bodies' centres (m).
    mean_y: f32,
    /// Dynamic bodies awake.
    awake: usize,
    /// Dynamic bodies with non-finite positions or more than 50 m below the lowest static body.
    lost: usize,
}

trait Engine {
    fn step(&mut self);
    fn sanity(&self) -> Sanity;
    /// Body pairs with at least one contact point (touching or speculative).
    fn contact_pairs(&self) -> usize;
}

struct Tiltbox {
    world: World,
}

impl Tiltbox {
    fn new(setup: &Setup) -> Tiltbox {
        Tiltbox {
            world: setup.build().expect("tiltbox refused a benchmark set-up"),
        }
    }
}

fn lowest_static(defs: &[BodyDef]) -> f32 {
    defs.iter()
        .filter(|d| d.mass == MassSpec::Static)
        .map(|d| d.position.y as f32)
        .fold(f32::INFINITY, f32::min)
}

fn summarise(ys: impl Iterator<Item = (f32, bool)>, floor: f32) -> Sanity {
    let (mut top, mut sum, mut n, mut awake, mut lost) = (f32::NEG_INFINITY, 0.0f64, 0, 0, 0);
    for (y, is_awake) in ys {
        if !y.is_finite() || y < floor - 50.0 {
            lost += 1;
            continue;
        }
        top = top.max(y);
        sum += y as f64;
        n += 1;
        awake += is_awake as usize;
    }
    Sanity {
        top_y: top,
        mean_y: if n > 0 {
            (sum / n as f64) as f32
        } else {
            f32::NAN
        },
        awake,
        lost,
    }
}

impl Engine for Tiltbox {
    fn step(&mut self) {
        self.world.step(DT as _).expect("tiltbox step failed");
    }
    fn contact_pairs(&self) -> usize {
        self.world.contact_count()
    }
    fn sanity(&self) -> Sanity {
        let floor = self
            .world
            .bodies()
            .filter(|b| b.is_static())
            .map(|b| b.position().y as f32)
            .fold(f32::INFINITY, f32::min);
        summarise(
            self.world
                .bodies()
                .filter(|b| !b.is_static())
                .map(|b| (b.position().y as f32, b.is_awake())),
            floor,
        )
    }
}

struct Rapier {
    world: PhysicsWorld,
    dynamic: Vec<RigidBodyHandle>,
    floor: f32,
}

/// tiltbox's mixing rule as rapier's combine rule. Rapier 0.36 has `GeometricMean`
/// (sqrt(a b)), tiltbox's default for friction and restitution, so the match is exact.
fn combine_rule(m: Mixing) -> CoefficientCombineRule {
    match m {
        Mixing::GeometricMean => CoefficientCombineRule::GeometricMean,
        Mixing::Product => CoefficientCombineRule::Multiply,
        Mixing::Min => CoefficientCombineRule::Min,
        Mixing::Max => CoefficientCombineRule::Max,
    }
}

impl Rapier {
    fn new(setup: &Setup) -> Rapier {
        // `Setup::build` uses the default settings plus the sleep flag; mirror their mixing rules.
        let settings = Settings::default();
        let friction_rule = combine_rule(settings.friction_mixing);
        let restitution_rule = combine_rule(settings.restitution_mixing);

        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(setup.gravity.x as f32, setup.gravity.y as f32);
        // Rapier's defaults (4 solver iterations = 4 substeps, 1 PGS + 1 stabilisation
        // iteration each, soft contacts); only dt is pinned.
        world.integration_parameters = IntegrationParameters {
            dt: DT,
            ..IntegrationParameters::default()
        };
        let mut dynamic = Vec::new();
        for def in &setup.bodies {
            let builder = match def.mass {
                MassSpec::Static => RigidBodyBuilder::fixed(),
                _ => RigidBodyBuilder::dynamic()
                    .linvel(Vector::new(
                        def.linear_velocity.x as f32,
                        def.linear_velocity.y as f32,
                    ))
                    .angvel(def.angular_velocity as f32)
                    .can_sleep(setup.sleep),
            }
            .translation(Vector::new(def.position.x as f32, def.position.y as f32))
            .rotation(def.angle as f32);
            let Shape::Rect { half_extents: h } = def.shape;
            let collider = ColliderBuilder::cuboid(h.x as f32, h.y as f32)
                .friction(def.friction as f32)
                .friction_combine_rule(friction_rule)
                .restitution(def.restitution as f32)
                .restitution_combine_rule(restitution_rule);
            let collider = match def.mass {
                MassSpec::Static => collider,
                MassSpec::Density(d) => collider.density(d as f32),
                MassSpec::Mass(m) => collider.mass(m as f32),
            };
            let (handle, _) = world.insert(builder, collider);
            if def.mass != MassSpec::Static {
                dynamic.push(handle);
            }
        }
        Rapier {
            world,
            dynamic,
            floor: lowest_static(&setup.bodies),
        }
    }
}

impl Engine for Rapier {
    fn step(&mut self) {
        self.world.step();
    }
    fn contact_pairs(&self) -> usize {
        self.world
            .narrow_phase
            .contact_pairs()
            .filter(|p| p.manifolds().iter().any(|m| !m.points.is_empty()))
            .count()
    }
    fn sanity(&self) -> Sanity {
        summarise(
            self.dynamic.iter().map(|&h| {
                let b = &self.world.bodies[h];
                (b.translation().y, !b.is_sleeping())
            }),
            self.floor,
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Timing.

/// Per-step timings (ms) and allocation calls of one engine on one scene.
#[derive(Default)]
struct Times {
    ms: Vec<f64>,
    allocs: usize,
}

impl Times {
    fn run(&mut self, engine: &mut dyn Engine, n: usize) {
        // Reserve first, so that our own bookkeeping never counts as an engine's allocation.
        self.ms.reserve(n);
        let a0 = ALLOCS.load(Relaxed);
        for _ in 0..n {
            let t = Instant::now();
            engine.step();
            self.ms.push(t.elapsed().as_secs_f64() * 1e3);
        }
        self.allocs += ALLOCS.load(Relaxed) - a0;
    }
    fn median(&self) -> f64 {
        let mut v = self.ms.clone();
        v.sort_by(f64::total_cmp);
        if v.is_empty() {
            return f64::NAN;
        }
        let n = v.len();
        if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        }
    }
    fn min(&self) -> f64 {
        self.ms.iter().copied().fold(f64::INFINITY, f64::min)
    }
    fn allocs_per_step(&self) -> f64 {
        self.allocs as f64 / self.ms.len().max(1) as f64
    }
}

struct Row {
    name: String,
    bodies: usize,
    steps: usize,
    tb: Times,
    ra: Times,
    tb_sanity: Sanity,
    ra_sanity: Sanity,
}

/// Warm both engines up (untimed), then time `steps` steps of each, alternating in chunks.
fn compare(setup: &Setup, steps: usize, chunks: bool) -> Row {
    let mut tb = Tiltbox::new(setup);
    let mut ra = Rapier::new(setup);
    for _ in 0..setup.warm_up {
        tb.step();
    }
    for _ in 0..setup.warm_up {
        ra.step();
    }
    let (mut tt, mut rt) = (Times::default(), Times::default());
    let mut done = 0;
    let mut tiltbox_first = true;
    let (mut tb_allocs, mut ra_allocs) = (0, 0);
    while done < steps {
        let n = CHUNK.min(steps - done);
        if tiltbox_first {
            tt.run(&mut tb, n);
            rt.run(&mut ra, n);
        } else {
            rt.run(&mut ra, n);
            tt.run(&mut tb, n);
        }
        tiltbox_first = !tiltbox_first;
        if chunks {
            let last = |t: &Times| {
                let mut v = t.ms[t.ms.len() - n..].to_vec();
                v.sort_by(f64::total_cmp);
                v[n / 2]
            };
            eprintln!(
                "  steps {:4}..{:4}: tiltbox {} ms, {} allocs, {} contacts; rapier {} ms, {} allocs, {} contacts",
                done,
                done + n,
                fmt_ms(last(&tt)),
                tt.allocs - tb_allocs,
                tb.contact_pairs(),
                fmt_ms(last(&rt)),
                rt.allocs - ra_allocs,
                ra.contact_pairs(),
            );
            (tb_allocs, ra_allocs) = (tt.allocs, rt.allocs);
        }
        done += n;
    }
    Row {
        name: setup.name.to_string(),
        bodies: setup.bodies.len(),
        steps,
        tb_sanity: tb.sanity(),
        ra_sanity: ra.sanity(),
        tb: tt,
        ra: rt,
    }
}

/// Milliseconds to three significant digits (sub-microsecond steps stay readable).
fn fmt_ms(ms: f64) -> String {
    if !ms.is_finite() || ms <= 0.0 {
        return format!("{ms:.3}");
    }
    let decimals = (2 - ms.log10().floor() as i32).clamp(0, 7) as usize;
    format!("{ms:.decimals$}")
}

fn fmt_sanity(s: &Sanity) -> String {
    let mut out = format!("{:.2} / {:.2} / {}", s.top_y, s.mean_y, s.awake);
    if s.lost > 0 {
        out += &format!(" ({} lost)", s.lost);
    }
    out
}

fn print_table(rows: &[Row]) {
    println!(
        "| scene | bodies | steps | tiltbox median | tiltbox min | rapier median | rapier min | ratio (median) | ratio (min) | tiltbox top / mean y / awake | rapier top / mean y / awake | allocs/step tiltbox / rapier |"
    );
    println!("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | --- | ---: |");
    for r in rows {
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {:.2} | {:.2} | {} | {} | {:.1} / {:.1} |",
            r.name,
            r.bodies,
            r.steps,
            fmt_ms(r.tb.median()),
            fmt_ms(r.tb.min()),
            fmt_ms(r.ra.median()),
            fmt_ms(r.ra.min()),
            r.tb.median() / r.ra.median(),
            r.tb.min() / r.ra.min(),
            fmt_sanity(&r.tb_sanity),
            fmt_sanity(&r.ra_sanity),
            r.tb.allocs_per_step(),
            r.ra.allocs_per_step(),
        );
    }
    println!(
        "(times in ms/step; ratio = tiltbox / rapier, < 1 means tiltbox is faster; sanity columns at the end of the run)"
    );
}

// ---------------------------------------------------------------------------------------------
// Memory per body.

fn live_bytes_after_10_steps(setup: &Setup, which: &str) -> usize {
    let before = LIVE_BYTES.load(Relaxed);
    let used = if which == "tiltbox" {
        let mut e = Tiltbox::new(setup);
        for _ in 0..10 {
            e.step();
        }
        let used = LIVE_BYTES.load(Relaxed) - before;
        drop(e);
        used
    } else {
        let mut e = Rapier::new(setup);
        for _ in 0..10 {
            e.step();
        }
        let used = LIVE_BYTES.load(Relaxed) - before;
        drop(e);
        used
    };
    used
}

fn memory(setups: &[Setup]) {
    let Some(setup) = setups.iter().find(|s| s.name == "large_pyramid") else {
        println!("memory: no large_pyramid set-up");
        return;
    };
    let n = setup.bodies.len();
    println!("\n## Memory per body (large_pyramid, {n} bodies, after building + 10 steps)\n");
    println!("| engine | live heap bytes | bytes per body |");
    println!("| --- | ---: | ---: |");
    for which in ["tiltbox", "rapier"] {
        let bytes = live_bytes_after_10_steps(setup, which);
        println!("| {which} | {bytes} | {:.0} |", bytes as f64 / n as f64);
    }
}

// ---------------------------------------------------------------------------------------------
// Largest pyramid at 60 Hz.

/// `large_pyramid` with another base: ground 2 m thick, at least 200 m wide, pyramid of 1 m boxes
/// (density 1, friction 0.6), sleep off.
fn pyramid_setup(base: usize) -> Setup {
    let mut bodies = vec![BodyDef::fixed(
        Shape::rect((base as f32 + 20.0).max(200.0) as _, 2.0),
        Vec2::new(0.0, -1.0),
    )];
    for row in 0..base {
        let count = base - row;
        let y = 0.5 + row as f32;
        let x0 = -0.5 * (count as f32 - 1.0);
        for j in 0..count {
            bodies.push(
                BodyDef::dynamic(
                    Shape::rect(1.0, 1.0),
                    Vec2::new((x0 + j as f32) as _, y as _),
                )
                .with_friction(0.6),
            );
        }
    }
    Setup {
        name: "pyramid",
        gravity: Vec2::new(0.0, -10.0),
        bodies,
        steps: 0,
        sleep: false,
        warm_up: 0,
    }
}

/// Median ms/step of a pyramid of `base` (after `warm` untimed steps, `timed` timed ones).
fn pyramid_median(engine: &str, base: usize, warm: usize, timed: usize) -> (f64, Sanity) {
    let setup = pyramid_setup(base);
    let mut e: Box<dyn Engine> = if engine == "tiltbox" {
        Box::new(Tiltbox::new(&setup))
    } else {
        Box::new(Rapier::new(&setup))
    };
    for _ in 0..warm {
        e.step();
    }
    let mut t = Times::default();
    t.run(e.as_mut(), timed);
    (t.median(), e.sanity())
}

/// Bisect the base until the median step time is just under the 60 Hz budget.
fn largest_pyramid(engine: &str, quick: bool, guess: usize) -> (usize, f64, Sanity) {
    let (warm, timed, resolution) = if quick { (5, 10, 8) } else { (20, 100, 1) };
    let probe = |base: usize| {
        let (ms, s) = pyramid_median(engine, base, warm, timed);
        eprintln!(
            "  {engine}: base {base:4} ({:6} boxes): {ms:7.3} ms/step",
            base * (base + 1) / 2
        );
        (ms, s)
    };
    // Bracket [lo, hi): lo fits, hi does not.
    let mut lo: Option<(usize, f64, Sanity)> = None;
    let mut hi: Option<usize> = None;
    let mut base = guess.max(10);
    while lo.is_none() || hi.is_none() {
        let (ms, s) = probe(base);
        if ms < BUDGET_MS {
            lo = Some((base, ms, s));
            if hi.is_none() {
                base = (base as f64 * 1.2).ceil() as usize;
            }
        } else {
            hi = Some(base);
            if lo.is_none() {
                if base <= 10 {
                    return (0, ms, s);
                }
                base = (base as f64 / 1.2).floor() as usize;
            }
        }
    }
    let (mut lo, mut hi) = (lo.unwrap(), hi.unwrap());
    while hi - lo.0 > resolution {
        let mid = (lo.0 + hi) / 2;
        let (ms, s) = probe(mid);
        if ms < BUDGET_MS {
            lo = (mid, ms, s);
        } else {
            hi = mid;
        }
    }
    lo
}

/// First guess: step time grows about linearly with the number of boxes, b (b + 1) / 2.
fn guess_base(ms_at_100: Option<f64>) -> usize {
    match ms_at_100 {
        Some(ms) if ms.is_finite() && ms > 0.0 => {
            (100.0 * (BUDGET_MS / ms).sqrt()).round().clamp(10.0, 400.0) as usize
        }
        _ => 100,
    }
}

// ---------------------------------------------------------------------------------------------

fn main() {
    let mut quick = false;
    let mut extras = true;
    let mut chunks = false;
    let mut filters: Vec<String> = Vec::new();
    for arg in std::env::args().skip(1) {
        match arg.as_str() {
            "--quick" => quick = true,
            "--no-extras" => extras = false,
            "--chunks" => chunks = true,
            "-h" | "--help" => {
                println!(
                    "usage: vs-rapier [--quick] [--no-extras] [--chunks] [SCENE|memory|largest_pyramid ...]\n\
                     --chunks prints per 25-step chunk and engine: median ms, allocation calls and\n\
                     contact pairs at the chunk's end (stderr).\n\
                     SCENE is a substring of a benchmark scene name; with any name given, the\n\
                     memory and largest-pyramid extras run only when named."
                );
                return;
            }
            a if a.starts_with('-') => {
                eprintln!("unknown option {a} (try --help)");
                std::process::exit(2);
            }
            a => filters.push(a.to_string()),
        }
    }
    if cfg!(debug_assertions) {
        eprintln!("warning: debug build; run with `cargo run --release` for meaningful figures");
    }

    let setups = benchmark_setups();
    let wanted =
        |name: &str| filters.is_empty() || filters.iter().any(|f| name.contains(f.as_str()));
    let extra_wanted =
        |name: &str| extras && (filters.is_empty() || filters.iter().any(|f| f == name));

    println!(
        "# tiltbox vs rapier2d {} (single thread, dt 1/60{})\n",
        rapier2d::VERSION,
        if quick { ", --quick" } else { "" }
    );
    let s = Settings::default();
    println!(
        "tiltbox: {:?} solver, {} substeps, friction mixing {:?}, restitution mixing {:?}; \
         rapier: default IntegrationParameters ({} solver iterations), combine rules {:?} / {:?}; \
         engines alternate every {CHUNK} steps.\n",
        s.solver,
        s.substeps,
        s.friction_mixing,
        s.restitution_mixing,
        IntegrationParameters::default().num_solver_iterations,
        combine_rule(s.friction_mixing),
        combine_rule(s.restitution_mixing),
    );

    println!("load average before: {}", load_average());
    let mut rows = Vec::new();
    for setup in setups.iter().filter(|s| wanted(s.name)) {
        let steps = if quick {
            setup.steps.min(30)
        } else {
            setup.steps
        };
        eprintln!(
            "running {} ({} bodies, {} warm-up + {} timed steps per engine)...",
            setup.name,
            setup.bodies.len(),
            setup.warm_up,
            steps
        );
        rows.push(compare(setup, steps, chunks));
    }
    if !rows.is_empty() {
        print_table(&rows);
    }

    if extra_wanted("memory") {
        memory(&setups);
    }

    if extra_wanted("largest_pyramid") {
        let large = rows.iter().find(|r| r.name == "large_pyramid");
        println!("\n## Largest pyramid stepped at 60 Hz on one core (median < 16.7 ms/step, sleep off)\n");
        println!("| engine | base | boxes | median ms/step | top / mean y / awake |");
        println!("| --- | ---: | ---: | ---: | --- |");
        for engine in ["tiltbox", "rapier"] {
            let guess = guess_base(large.map(|r| {
                if engine == "tiltbox" {
                    r.tb.median()
                } else {
                    r.ra.median()
                }
            }));
            let (base, ms, s) = largest_pyramid(engine, quick, guess);
            println!(
                "| {engine} | {base} | {} | {ms:.3} | {} |",
                base * (base + 1) / 2,
                fmt_sanity(&s)
            );
        }
    }
    println!("\nload average after: {}", load_average());
}

/// `/proc/loadavg` (1, 5 and 15 minute load averages), to judge how noisy the run was.
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}
