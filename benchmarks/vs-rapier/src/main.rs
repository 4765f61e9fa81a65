//! tiltbox vs rapier2d on the benchmark scenes of `tiltbox::measure::cases::benchmark_setups()`, built from
//! the same body definitions, stepped in the same process, timed step by step.
//!
//! ```text
//! cargo run --release -- [--quick] [--no-extras] [--chunks] [--settle[=SECONDS]] [SCENE|memory|largest_pyramid ...]
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
//!   sleep off), by bisection;
//! - `--settle[=SECONDS]`: no timing; whether each selected scene comes to rest (awake and moving
//!   bodies, top speeds, positions, per kind of shape) in both engines, sleep on and off;
//! - before timing, both engines' bodies are checked to match (centre of mass, angle, mass,
//!   moment of inertia), so that both step the same scene whatever the shapes.
//!
//! Positional arguments select scenes by name (substring match); with any selection given, the
//! extras run only when named (`memory`, `largest_pyramid`).

// tiltbox's `Real` is f32 by default and f64 with its `f64` feature: the `as f32` casts are
// needed for the latter and redundant for the former.
#![allow(clippy::unnecessary_cast)]

use rapier2d::prelude::{
    CoefficientCombineRule, ColliderBuilder, IntegrationParameters, MassProperties, PhysicsWorld,
    RigidBodyBuilder, RigidBodyHandle, SharedShape, Vector,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use std::time::Instant;
use tiltbox::measure::cases::{benchmark_setups, Setup};
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

/// One dynamic body's state, for the settle report and the set-up check.
#[derive(Clone, Copy, Debug)]
struct BodyState {
    /// Whether the engine still steps it.
    awake: bool,
    /// Mass (kg) and moment of inertia (kg m^2): what the set-up check compares.
    mass: f32,
    inertia: f32,
    /// Centre of mass (m) and velocity (m/s).
    position: [f32; 2],
    velocity: [f32; 2],
    /// Angle (rad) and angular velocity (rad/s).
    angle: f32,
    angular_velocity: f32,
}

trait Engine {
    fn step(&mut self);
    fn sanity(&self) -> Sanity;
    /// Body pairs with at least one contact point (touching or speculative).
    fn contact_pairs(&self) -> usize;
    /// Every dynamic body, in the order of the set-up's `BodyDef`s.
    fn dynamic_bodies(&self) -> Vec<BodyState>;
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
    fn dynamic_bodies(&self) -> Vec<BodyState> {
        self.world
            .bodies()
            .filter(|b| !b.is_static())
            .map(|b| BodyState {
                position: [b.position().x as f32, b.position().y as f32],
                angle: b.angle() as f32,
                velocity: [b.linear_velocity().x as f32, b.linear_velocity().y as f32],
                angular_velocity: b.angular_velocity() as f32,
                awake: b.is_awake(),
                mass: b.mass() as f32,
                inertia: b.inertia() as f32,
            })
            .collect()
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

/// The rapier2d collider of a tiltbox shape, in the body's frame. Both engines put a body's
/// origin at its centre of mass: tiltbox's shapes are centred on it (a polygon on its centroid),
/// and so are these colliders, so `BodyDef::position` is the body translation in both and the
/// collider needs no offset.
fn rapier_collider(shape: &Shape) -> ColliderBuilder {
    match *shape {
        Shape::Rect { half_extents: h } => ColliderBuilder::cuboid(h.x as f32, h.y as f32),
        Shape::Circle { radius } => ColliderBuilder::ball(radius as f32),
        // Both: the segment (-half_length, 0)..(half_length, 0) grown by the radius.
        Shape::Capsule {
            half_length,
            radius,
        } => ColliderBuilder::capsule_x(half_length as f32, radius as f32),
        // The same vertices, counter-clockwise in both; `_unmodified` keeps every vertex
        // (`convex_polyline` would merge edges within about 1.5 degrees of each other, which
        // tiltbox accepts down to 0.06 degrees).
        Shape::Polygon(ref p) => {
            let points: Vec<Vector> = p
                .vertices()
                .iter()
                .map(|v| Vector::new(v.x as f32, v.y as f32))
                .collect();
            let shape = SharedShape::convex_polyline_unmodified(points)
                .expect("rapier2d refused a polygon tiltbox accepted");
            ColliderBuilder::new(shape)
        }
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
            let collider = rapier_collider(&def.shape)
                .friction(def.friction as f32)
                .friction_combine_rule(friction_rule)
                .restitution(def.restitution as f32)
                .restitution_combine_rule(restitution_rule);
            let collider = match (def.mass, &def.shape) {
                (MassSpec::Static, _) => collider,
                // parry2d 0.31 moves a capsule's two half discs out by 3r/8 (a 3D hemisphere's
                // centroid) where a half disc's is 4r/(3 pi), so its 2D capsule inertia is low
                // (3 % for mixed_shapes' capsule); tiltbox's closed form is checked against a
                // numerical integral. Give rapier tiltbox's mass and inertia so that both step
                // the same bodies; every other shape's mass properties agree to 1e-6.
                (MassSpec::Density(_) | MassSpec::Mass(_), Shape::Capsule { .. }) => {
                    let mass = match def.mass {
                        MassSpec::Density(d) => d * def.shape.area(),
                        MassSpec::Mass(m) => m,
                        MassSpec::Static => unreachable!(),
                    };
                    collider.mass_properties(MassProperties::new(
                        Vector::ZERO,
                        mass as f32,
                        def.shape.inertia(mass) as f32,
                    ))
                }
                (MassSpec::Density(d), _) => collider.density(d as f32),
                (MassSpec::Mass(m), _) => collider.mass(m as f32),
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
    fn dynamic_bodies(&self) -> Vec<BodyState> {
        self.dynamic
            .iter()
            .map(|&h| {
                let b = &self.world.bodies[h];
                let m = &b.mass_properties().local_mprops;
                BodyState {
                    // The centre of mass (equal to the translation when the collider is centred).
                    position: [b.center_of_mass().x, b.center_of_mass().y],
                    angle: b.rotation().angle(),
                    velocity: [b.linvel().x, b.linvel().y],
                    angular_velocity: b.angvel(),
                    awake: !b.is_sleeping(),
                    mass: m.mass(),
                    inertia: m.principal_inertia(),
                }
            })
            .collect()
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

/// Before the first step, both engines must hold the same bodies: same centre of mass, angle,
/// mass and moment of inertia (to 1e-4 relative), or the comparison would be of two scenes.
/// Prints the largest differences to stderr; a mismatch is reported loudly, not hidden.
fn check_same_bodies(name: &str, tb: &dyn Engine, ra: &dyn Engine) {
    let (a, b) = (tb.dynamic_bodies(), ra.dynamic_bodies());
    if a.len() != b.len() {
        eprintln!(
            "  WARNING {name}: tiltbox has {} dynamic bodies, rapier {}",
            a.len(),
            b.len()
        );
        return;
    }
    let rel = |x: f32, y: f32| (x - y).abs() / x.abs().max(y.abs()).max(1e-12);
    let (mut dp, mut da, mut dm, mut di) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for (p, q) in a.iter().zip(&b) {
        dp = dp.max(
            ((p.position[0] - q.position[0]).powi(2) + (p.position[1] - q.position[1]).powi(2))
                .sqrt(),
        );
        let d = (p.angle - q.angle).rem_euclid(std::f32::consts::TAU);
        da = da.max(d.min(std::f32::consts::TAU - d));
        dm = dm.max(rel(p.mass, q.mass));
        di = di.max(rel(p.inertia, q.inertia));
    }
    let bad = dp > 1e-4 || da > 1e-4 || dm > 1e-4 || di > 1e-4;
    eprintln!(
        "  {}{name}: largest difference tiltbox / rapier before the first step: centre of mass \
         {dp:.1e} m, angle {da:.1e} rad, mass {dm:.1e} (relative), inertia {di:.1e} (relative)",
        if bad { "WARNING " } else { "" }
    );
}

/// Warm both engines up (untimed), then time `steps` steps of each, alternating in chunks.
fn compare(setup: &Setup, steps: usize, chunks: bool) -> Row {
    let mut tb = Tiltbox::new(setup);
    let mut ra = Rapier::new(setup);
    check_same_bodies(setup.name, &tb, &ra);
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
// Settling: does a pile come to rest?

/// A shape's kind as the settle report names it (polygons by vertex count).
fn kind_name(shape: &Shape) -> String {
    match shape {
        Shape::Polygon(p) => match p.vertices().len() {
            3 => "triangle".to_string(),
            4 => "quad".to_string(),
            6 => "hexagon".to_string(),
            n => format!("{n}-gon"),
        },
        s => s.kind().to_string(),
    }
}

/// tiltbox's resting speed of a body: |v| + |w| x bounding radius (`Settings::sleep_threshold`
/// compares it with 0.05 m/s).
fn rest_speed(b: &BodyState, radius: f32) -> f32 {
    (b.velocity[0].powi(2) + b.velocity[1].powi(2)).sqrt() + b.angular_velocity.abs() * radius
}

/// Per kind of shape: bodies, awake, above the resting speed, max |v|, max |w|.
#[derive(Default)]
struct KindStats {
    count: usize,
    awake: usize,
    moving: usize,
    max_v: f32,
    max_w: f32,
    max_rest_speed: f32,
}

fn kind_stats(defs: &[&BodyDef], bodies: &[BodyState]) -> Vec<(String, KindStats)> {
    let threshold = Settings::default().sleep_threshold as f32;
    let mut out: Vec<(String, KindStats)> = Vec::new();
    for (def, b) in defs.iter().zip(bodies) {
        let name = kind_name(&def.shape);
        let i = match out.iter().position(|(n, _)| *n == name) {
            Some(i) => i,
            None => {
                out.push((name, KindStats::default()));
                out.len() - 1
            }
        };
        let k = &mut out[i].1;
        let speed = rest_speed(b, def.shape.bounding_radius() as f32);
        k.count += 1;
        k.awake += b.awake as usize;
        k.moving += (speed >= threshold || speed.is_nan()) as usize;
        k.max_v = k
            .max_v
            .max((b.velocity[0].powi(2) + b.velocity[1].powi(2)).sqrt());
        k.max_w = k.max_w.max(b.angular_velocity.abs());
        k.max_rest_speed = k.max_rest_speed.max(speed);
    }
    out
}

/// Step each selected scene for `seconds` of simulated time in both engines, with sleep on and
/// with sleep off, and report every 2 s: bodies awake, bodies faster than tiltbox's resting
/// speed, the fastest body, where the bodies are (escapes through walls show in x, falls through
/// the floor in y), and at the end the same per kind of shape.
fn settle(setups: &[&Setup], seconds: f32) {
    let steps = (seconds * 60.0).round() as usize;
    let every = 120;
    let threshold = Settings::default().sleep_threshold;
    println!(
        "\n## Settling: {seconds} s simulated (dt 1/60), sleep on and off\n\n\
         moving = resting speed (speed + spin x r) >= {threshold} m/s (tiltbox's sleep threshold, r = \
         bounding radius), the same test for both engines.\n"
    );
    for setup in setups {
        let defs: Vec<&BodyDef> = setup
            .bodies
            .iter()
            .filter(|d| d.mass != MassSpec::Static)
            .collect();
        for sleep in [true, false] {
            let s = Setup {
                sleep,
                ..(*setup).clone()
            };
            println!(
                "### {} ({} dynamic bodies), sleep {}\n",
                s.name,
                defs.len(),
                if sleep { "on" } else { "off" }
            );
            println!("| t (s) | engine | awake | moving | top speed (m/s) | top spin (rad/s) | x min / max | y min / max | lost |");
            println!("| ---: | --- | ---: | ---: | ---: | ---: | --- | --- | ---: |");
            let mut engines: [(&str, Box<dyn Engine>); 2] = [
                ("tiltbox", Box::new(Tiltbox::new(&s))),
                ("rapier", Box::new(Rapier::new(&s))),
            ];
            for done in 1..=steps {
                for (_, e) in engines.iter_mut() {
                    e.step();
                }
                if done % every != 0 && done != steps {
                    continue;
                }
                for (name, e) in &engines {
                    let bodies = e.dynamic_bodies();
                    let stats = kind_stats(&defs, &bodies);
                    let (mut xmin, mut xmax, mut ymin, mut ymax) = (
                        f32::INFINITY,
                        f32::NEG_INFINITY,
                        f32::INFINITY,
                        f32::NEG_INFINITY,
                    );
                    for b in &bodies {
                        xmin = xmin.min(b.position[0]);
                        xmax = xmax.max(b.position[0]);
                        ymin = ymin.min(b.position[1]);
                        ymax = ymax.max(b.position[1]);
                    }
                    let sum = |f: &dyn Fn(&KindStats) -> usize| {
                        stats.iter().map(|(_, k)| f(k)).sum::<usize>()
                    };
                    let max = |f: &dyn Fn(&KindStats) -> f32| {
                        stats.iter().map(|(_, k)| f(k)).fold(0.0f32, f32::max)
                    };
                    println!(
                        "| {:.1} | {name} | {} | {} | {:.3} | {:.3} | {xmin:.2} / {xmax:.2} | {ymin:.2} / {ymax:.2} | {} |",
                        done as f32 / 60.0,
                        sum(&|k| k.awake),
                        sum(&|k| k.moving),
                        max(&|k| k.max_v),
                        max(&|k| k.max_w),
                        e.sanity().lost,
                    );
                }
            }
            println!("\nper kind at {seconds} s:\n");
            println!("| engine | kind | bodies | awake | moving | top speed (m/s) | top spin (rad/s) | top resting speed (m/s) |");
            println!("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |");
            for (name, e) in &engines {
                for (kind, k) in kind_stats(&defs, &e.dynamic_bodies()) {
                    println!(
                        "| {name} | {kind} | {} | {} | {} | {:.4} | {:.4} | {:.4} |",
                        k.count, k.awake, k.moving, k.max_v, k.max_w, k.max_rest_speed
                    );
                }
            }
            println!();
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Memory per body.

fn live_bytes_after_10_steps(setup: &Setup, which: &str) -> usize {
    if which == "tiltbox" {
        live_bytes_after(|| Tiltbox::new(setup))
    } else {
        live_bytes_after(|| Rapier::new(setup))
    }
}

/// Heap bytes still held after building an engine with `build` and stepping it 10 times.
fn live_bytes_after<E: Engine>(build: impl FnOnce() -> E) -> usize {
    let before = LIVE_BYTES.load(Relaxed);
    let mut e = build();
    for _ in 0..10 {
        e.step();
    }
    let used = LIVE_BYTES.load(Relaxed) - before;
    drop(e);
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
    let mut settle_seconds: Option<f32> = None;
    let mut filters: Vec<String> = Vec::new();
    for arg in std::env::args().skip(1) {
        match arg.as_str() {
            "--quick" => quick = true,
            "--no-extras" => extras = false,
            "--chunks" => chunks = true,
            "--settle" => settle_seconds = Some(10.0),
            a if a.starts_with("--settle=") => match a["--settle=".len()..].parse::<f32>() {
                Ok(t) if t.is_finite() && t > 0.0 => settle_seconds = Some(t),
                _ => {
                    eprintln!("--settle=SECONDS wants a positive number of seconds, got {a}");
                    std::process::exit(2);
                }
            },
            "-h" | "--help" => {
                println!(
                    "usage: vs-rapier [--quick] [--no-extras] [--chunks] [--settle[=SECONDS]] [SCENE|memory|largest_pyramid ...]\n\
                     --chunks prints per 25-step chunk and engine: median ms, allocation calls and\n\
                     contact pairs at the chunk's end (stderr).\n\
                     --settle[=SECONDS] times nothing: steps the selected scenes for SECONDS (10) of\n\
                     simulated time with sleep on and off and reports awake / moving bodies, top\n\
                     speeds and positions every 2 s, and per kind of shape at the end.\n\
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

    if let Some(seconds) = settle_seconds {
        let selected: Vec<&Setup> = setups.iter().filter(|s| wanted(s.name)).collect();
        settle(&selected, seconds);
        return;
    }

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
