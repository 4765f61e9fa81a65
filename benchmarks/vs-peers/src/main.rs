//! tiltbox vs Box2D v3 (SSE2 and AVX2 builds) and rapier2d on the benchmark scenes of
//! `tiltbox::measure::cases::benchmark_setups()`, built from the same body definitions, stepped in the same
//! run, timed step by step.
//!
//! ```text
//! cargo run --release -- [--quick] [--no-extras] [--chunks] [--settle[=SECONDS]] [--avx2 PATH | --no-avx2]
//!                        [--accuracy OUT.csv] [SCENE|memory|largest_pyramid ...]
//! ```
//!
//! - every scene runs its warm-up steps untimed in every engine, then its timed steps in chunks
//!   of `CHUNK` steps, engine after engine, rotating which one goes first, so that a noisy
//!   neighbour on the machine hits every engine alike;
//! - Box2D v3 comes from `boxdd-sys` (C compiled with `cc`). Its SSE2 and AVX2 builds cannot link
//!   into one binary, so the AVX2 build of this tool (`--features avx2`, its own target dir) runs
//!   as a child process serving one engine over a pipe ([`remote`]): the parent asks it for a
//!   chunk of timed steps in its turn and blocks while the child steps, so the chunks of all four
//!   engines still alternate on the same machine in the same run;
//! - the table gives median and minimum ms/step per engine, the ratios tiltbox / each peer, and a
//!   sanity column per engine (top body height / mean body height / bodies awake) so that a
//!   collapsed pyramid is never compared with a standing one;
//! - `memory`: live heap bytes per body after building `large_pyramid` and 10 steps (counting
//!   global allocator; Box2D's allocations are routed through it with `b2SetAllocator`);
//! - `pile_N`: the growth scene (`cases::pile`) at N boxes, only when named;
//! - `largest_pyramid`: the largest pyramid base each engine steps in under 16.7 ms (median,
//!   sleep off), by bisection;
//! - `--settle[=SECONDS]`: no timing; whether each selected scene comes to rest (awake and moving
//!   bodies, top speeds, positions, per kind of shape) in every engine, sleep on and off;
//! - `--accuracy OUT.csv`: the work-precision points of the peers ([`accuracy`]) for
//!   `tiltbox report`;
//! - before timing, the engines' bodies are checked to match tiltbox's (centre of mass, angle,
//!   mass, moment of inertia), so that all step the same scene whatever the shapes.
//!
//! Positional arguments select scenes by name (substring match); with any selection given, the
//! extras run only when named (`memory`, `largest_pyramid`).

// tiltbox's `Real` is f32 by default and f64 with its `f64` feature: the `as f32` casts are
// needed for the latter and redundant for the former.
#![allow(clippy::unnecessary_cast)]

mod accuracy;
mod box2d;
mod paddle;
mod remote;

use rapier2d::prelude::{
    ActiveHooks, CoefficientCombineRule, ColliderBuilder, ColliderHandle, Group,
    IntegrationParameters, InteractionGroups, InteractionTestMode, MassProperties,
    PairFilterContext, PhysicsHooks, PhysicsWorld, RevoluteJointBuilder, RigidBodyBuilder,
    RigidBodyHandle, SharedShape, SolverFlags, Vector,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use std::time::Instant;
use tiltbox::measure::accuracy::max_penetration;
use tiltbox::measure::cases::{benchmark_setups, Setup, SetupDriver, SetupJoint, Spawned};
use tiltbox::measure::machine::cpu_model;
use tiltbox::physics::{BodyDef, Filter, MassSpec, Mixing, Real, Settings, Shape, Vec2, World};

// ---------------------------------------------------------------------------------------------
// Counting allocator: live bytes and number of allocation calls.

pub(crate) struct Counting;

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
pub(crate) static GLOBAL: Counting = Counting;

// ---------------------------------------------------------------------------------------------
// Constants.

pub(crate) const DT: f32 = 1.0 / 60.0;
/// Steps per engine before switching to the other one.
const CHUNK: usize = 25;
/// The 60 Hz budget (ms).
const BUDGET_MS: f64 = 1000.0 / 60.0;

// ---------------------------------------------------------------------------------------------
// The engines behind one small interface.

/// What the sanity columns show.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sanity {
    /// Highest centre of a dynamic body (m).
    pub(crate) top_y: f32,
    /// Mean height of the dynamic bodies' centres (m).
    pub(crate) mean_y: f32,
    /// Dynamic bodies awake.
    pub(crate) awake: usize,
    /// Dynamic bodies with non-finite positions or more than 50 m below the lowest static body.
    pub(crate) lost: usize,
    /// The widest gap between a joint's two anchors (m; 0 in a scene without joints).
    pub(crate) joint_gap: f32,
}

/// One dynamic body's state, for the settle report and the set-up check.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BodyState {
    pub(crate) position: [f32; 2],
    pub(crate) angle: f32,
    pub(crate) velocity: [f32; 2],
    pub(crate) angular_velocity: f32,
    pub(crate) awake: bool,
    pub(crate) mass: f32,
    pub(crate) inertia: f32,
}

pub(crate) trait Engine {
    fn step(&mut self);
    fn sanity(&self) -> Sanity;
    /// Body pairs with at least one contact point (touching or speculative).
    fn contact_pairs(&self) -> usize;
    /// Every dynamic body, in the order of the set-up's `BodyDef`s (empty if the engine cannot
    /// say, as the AVX2 child process).
    fn dynamic_bodies(&self) -> Vec<BodyState>;
    /// Deepest overlap among the current contact points (m, >= 0).
    fn max_penetration(&self) -> f64;
    /// `n` steps untimed.
    fn warm(&mut self, n: usize) {
        for _ in 0..n {
            self.step();
        }
    }
    /// `n` steps, each timed (ms, appended to `ms`); returns the allocation calls they made.
    fn run_timed(&mut self, n: usize, ms: &mut Vec<f64>) -> usize {
        // Reserve first, so that our own bookkeeping never counts as an engine's allocation.
        ms.reserve(n);
        let a0 = ALLOCS.load(Relaxed);
        for _ in 0..n {
            let t = Instant::now();
            self.step();
            ms.push(t.elapsed().as_secs_f64() * 1e3);
        }
        ALLOCS.load(Relaxed) - a0
    }
}

pub(crate) struct Tiltbox {
    world: World,
    dt: f32,
    /// The set-up, for its driver, and the steps taken.
    setup: Setup,
    steps: usize,
    /// What the set-up's spawns have put in.
    spawned: Spawned,
}

/// Threads each engine steps with (`--workers N`; 1: single threaded, the default).
pub(crate) static WORKERS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(1);

/// [`WORKERS`].
pub(crate) fn workers() -> u32 {
    WORKERS.load(Relaxed)
}

impl Tiltbox {
    fn new(setup: &Setup) -> Tiltbox {
        let mut world = setup.build().expect("tiltbox refused a benchmark set-up");
        world
            .set_workers(workers())
            .expect("a worker count within 1..=64");
        Tiltbox {
            world,
            dt: DT,
            setup: setup.clone(),
            steps: 0,
            spawned: Spawned::default(),
        }
    }

    /// The scene with `settings` (its sleep flag replaced by the scene's), stepped at `dt`.
    pub(crate) fn with_settings(setup: &Setup, settings: Settings, dt: f32) -> Tiltbox {
        let world = setup
            .build_with(settings)
            .expect("tiltbox refused the set-up");
        assert!(
            setup.driver.is_none() || dt == DT,
            "a driven set-up runs at 1/60 s"
        );
        Tiltbox {
            world,
            dt,
            setup: setup.clone(),
            steps: 0,
            spawned: Spawned::default(),
        }
    }
}

pub(crate) fn lowest_static(defs: &[BodyDef]) -> f32 {
    defs.iter()
        .filter(|d| d.mass == MassSpec::Static)
        .map(|d| d.position.y as f32)
        .fold(f32::INFINITY, f32::min)
}

pub(crate) fn summarise(ys: impl Iterator<Item = (f32, bool)>, floor: f32) -> Sanity {
    // A scene without static bodies (smash) has no floor to fall through.
    let floor = if floor.is_finite() {
        floor
    } else {
        f32::NEG_INFINITY
    };
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
        joint_gap: 0.0,
    }
}

impl Engine for Tiltbox {
    fn step(&mut self) {
        if self.setup.driver.is_some() || self.setup.spawner.is_some() {
            self.setup
                .step(&mut self.world, &mut self.spawned, self.steps)
                .expect("tiltbox step failed");
        } else {
            self.world.step(self.dt as _).expect("tiltbox step failed");
        }
        self.steps += 1;
    }
    fn max_penetration(&self) -> f64 {
        max_penetration(&self.world)
    }
    fn contact_pairs(&self) -> usize {
        self.world.contact_count()
    }
    fn dynamic_bodies(&self) -> Vec<BodyState> {
        self.world
            .bodies()
            .filter(|b| !b.is_static() && !b.is_kinematic())
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
        let mut sanity = summarise(
            self.world
                .bodies()
                .filter(|b| !b.is_static() && !b.is_kinematic())
                .map(|b| (b.position().y as f32, b.is_awake())),
            floor,
        );
        let world = &self.world;
        let at = |id: Option<tiltbox::physics::BodyId>, p| match id {
            Some(id) => world.body(id).expect("live").transform().apply(p),
            None => p,
        };
        sanity.joint_gap = world
            .joints()
            .map(|j| {
                let d = j.def();
                (at(d.body_a, d.anchor_a) - at(Some(d.body_b), d.anchor_b)).length() as f32
            })
            .fold(0.0, f32::max);
        sanity
    }
}

/// The bodies one group of spawns holds, and their joints (bodies and local anchors).
type RapierGroup = (
    Vec<RigidBodyHandle>,
    Vec<(RigidBodyHandle, RigidBodyHandle, Vector, Vector)>,
);

pub(crate) struct Rapier {
    world: PhysicsWorld,
    /// The fixed body joints to the world hang from, if any; the combine rules; the sleep
    /// flag; the scene's spawns and the bodies each group of them holds.
    ground: Option<RigidBodyHandle>,
    rules: (CoefficientCombineRule, CoefficientCombineRule),
    sleep: bool,
    spawner: Option<fn(usize) -> Vec<tiltbox::measure::cases::SetupSpawn>>,
    groups: Vec<RapierGroup>,
    /// The driven kinematic body and its driver, and the steps taken.
    driver: Option<(RigidBodyHandle, SetupDriver)>,
    steps: usize,
    dynamic: Vec<RigidBodyHandle>,
    floor: f32,
    /// Each joint's bodies and local anchors, for the gap in the sanity column.
    joints: Vec<(RigidBodyHandle, RigidBodyHandle, Vector, Vector)>,
}

/// A tiltbox filter as rapier's interaction groups (32 bits). rapier has no group index: a
/// negative one is left to the [`GroupIndex`] hook, and a positive one is not used.
fn rapier_groups(f: tiltbox::physics::Filter) -> InteractionGroups {
    assert!(f.group <= 0, "no positive group index in the peer scenes");
    InteractionGroups::new(
        Group::from_bits_truncate(f.category as u32),
        Group::from_bits_truncate(f.mask as u32),
        InteractionTestMode::And,
    )
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
        Shape::Segment(ref s) => ColliderBuilder::segment(
            Vector::new(s.a.x as f32, s.a.y as f32),
            Vector::new(s.b.x as f32, s.b.y as f32),
        ),
    }
}

impl Rapier {
    fn new(setup: &Setup) -> Rapier {
        Rapier::with_step(
            setup,
            DT,
            IntegrationParameters::default().num_solver_iterations,
        )
    }

    /// The scene stepped at `dt` with `substeps` solver iterations (rapier's substeps).
    pub(crate) fn with_step(setup: &Setup, dt: f32, substeps: usize) -> Rapier {
        // `Setup::build` uses the default settings plus the sleep flag; mirror their mixing rules.
        let settings = Settings::default();
        let friction_rule = combine_rule(settings.friction_mixing);
        let restitution_rule = combine_rule(settings.restitution_mixing);

        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(setup.gravity.x as f32, setup.gravity.y as f32);
        // Rapier's defaults (4 solver iterations = 4 substeps, 1 PGS + 1 stabilisation
        // iteration each, soft contacts); only dt (and, for the accuracy runs, the number of
        // substeps) is pinned.
        world.integration_parameters = IntegrationParameters {
            dt,
            num_solver_iterations: substeps,
            ..IntegrationParameters::default()
        };
        let rules = (friction_rule, restitution_rule);
        let mut dynamic = Vec::new();
        let mut handles = Vec::with_capacity(setup.bodies.len());
        for def in &setup.bodies {
            let handle = insert_body(&mut world, def, rules, setup.sleep);
            if !matches!(def.mass, MassSpec::Static | MassSpec::Kinematic) {
                dynamic.push(handle);
            }
            handles.push(handle);
        }
        // The world, for joints to it: a fixed body without colliders at the origin.
        let ground = setup
            .joints
            .iter()
            .any(|j| j.a.is_none())
            .then(|| world.insert_body(RigidBodyBuilder::fixed()));
        let joints = setup
            .joints
            .iter()
            .map(|j| insert_joint(&mut world, ground, &handles, j))
            .collect();
        Rapier {
            world,
            ground,
            rules,
            sleep: setup.sleep,
            spawner: setup.spawner,
            groups: Vec::new(),
            driver: setup.driver.map(|d| (handles[d.body], d)),
            steps: 0,
            dynamic,
            floor: lowest_static(&setup.bodies),
            joints,
        }
    }
}

/// Insert `def` (its shapes, material, filter and mass) into `world`; `rules`: the friction and
/// restitution combine rules; `sleep`: whether it may sleep.
fn insert_body(
    world: &mut PhysicsWorld,
    def: &BodyDef,
    (friction_rule, restitution_rule): (CoefficientCombineRule, CoefficientCombineRule),
    sleep: bool,
) -> RigidBodyHandle {
    let builder = match def.mass {
        MassSpec::Static => RigidBodyBuilder::fixed(),
        MassSpec::Kinematic => RigidBodyBuilder::kinematic_velocity_based()
            .linvel(Vector::new(
                def.linear_velocity.x as f32,
                def.linear_velocity.y as f32,
            ))
            .angvel(def.angular_velocity as f32),
        _ => RigidBodyBuilder::dynamic()
            .linvel(Vector::new(
                def.linear_velocity.x as f32,
                def.linear_velocity.y as f32,
            ))
            .angvel(def.angular_velocity as f32)
            .can_sleep(sleep)
            .sleeping(!def.awake),
    }
    .translation(Vector::new(def.position.x as f32, def.position.y as f32))
    .rotation(def.angle as f32);
    let material = |c: ColliderBuilder, friction: Real, restitution: Real, filter: Filter| {
        let c = c
            .friction(friction as f32)
            .friction_combine_rule(friction_rule)
            .restitution(restitution as f32)
            .restitution_combine_rule(restitution_rule)
            .collision_groups(rapier_groups(filter));
        if filter.group < 0 {
            c.user_data(filter.group as u32 as u128)
                .active_hooks(ActiveHooks::FILTER_CONTACT_PAIRS)
        } else {
            c
        }
    };
    let collider = material(
        rapier_collider(&def.shape),
        def.friction,
        def.restitution,
        def.filter,
    );
    // (rapier has no event for a hit's approach speed: shapes that report hits in
    // tiltbox and Box2D report nothing here.)
    let collider = collider.sensor(def.flags.sensor);
    let collider = match (def.mass, &def.shape) {
        (MassSpec::Static | MassSpec::Kinematic, _) => collider,
        // parry2d 0.31 moves a capsule's two half discs out by 3r/8 (a 3D hemisphere's
        // centroid) where a half disc's is 4r/(3 pi), so its 2D capsule inertia is low
        // (3 % for mixed_shapes' capsule); tiltbox's closed form is checked against a
        // numerical integral. Give rapier tiltbox's mass and inertia so that both step
        // the same bodies; every other shape's mass properties agree to 1e-6.
        (MassSpec::Density(_) | MassSpec::Mass(_), Shape::Capsule { .. }) => {
            let mass = match def.mass {
                MassSpec::Density(d) => d * def.shape.area(),
                MassSpec::Mass(m) => m,
                MassSpec::Static | MassSpec::Kinematic => unreachable!(),
            };
            collider.mass_properties(MassProperties::new(
                Vector::ZERO,
                mass as f32,
                def.shape.inertia(mass) as f32,
            ))
        }
        (MassSpec::Density(d), _) => collider.density(d as f32),
        (MassSpec::Mass(m), _) => {
            assert!(
                def.parts.is_empty(),
                "the peer scenes give parts by density"
            );
            collider.mass(m as f32)
        }
    };
    let (handle, _) = world.insert(builder, collider);
    // A body's further shapes, each at its pose in the body's frame.
    for part in &def.parts {
        assert!(
            !matches!(part.shape, Shape::Capsule { .. }),
            "the peer scenes have no capsule parts"
        );
        let c = material(
            rapier_collider(&part.shape),
            part.friction,
            part.restitution,
            part.filter,
        )
        .translation(Vector::new(part.offset.x as f32, part.offset.y as f32))
        .rotation(part.angle as f32);
        let c = if matches!(def.mass, MassSpec::Static | MassSpec::Kinematic) {
            c.sensor(part.flags.sensor)
        } else {
            c.density(part.density as f32).sensor(part.flags.sensor)
        };
        world.insert_collider(c, Some(handle));
    }
    handle
}

/// Insert hinge `j` between bodies of `handles` (A None: `ground`); its bodies and anchors.
/// rapier has one motor per axis: a joint with both a spring and friction (a motor at rest)
/// gets a position motor toward the angle it was made at with the spring's stiffness and
/// damping (rapier's acceleration-based model: (2 pi f)^2 and 2 zeta 2 pi f), capped at the
/// friction torque.
fn insert_joint(
    world: &mut PhysicsWorld,
    ground: Option<RigidBodyHandle>,
    handles: &[RigidBodyHandle],
    j: &SetupJoint,
) -> (RigidBodyHandle, RigidBodyHandle, Vector, Vector) {
    let anchor = |p: Vec2| Vector::new(p.x as f32, p.y as f32);
    let mut hinge = RevoluteJointBuilder::new()
        .local_anchor1(anchor(j.anchor_a))
        .local_anchor2(anchor(j.anchor_b))
        .contacts_enabled(false);
    if let Some((lower, upper)) = j.limit {
        hinge = hinge.limits([lower as f32, upper as f32]);
    }
    match (j.spring, j.motor) {
        (Some((hertz, zeta)), motor) => {
            let omega = 2.0 * std::f32::consts::PI * hertz as f32;
            hinge = hinge.motor_position(0.0, omega * omega, 2.0 * zeta as f32 * omega);
            if let Some((_, max)) = motor {
                hinge = hinge.motor_max_force(max as f32);
            }
        }
        (None, Some((speed, max))) => {
            // A velocity motor (rapier's damping factor: how hard it pulls to the speed).
            hinge = hinge
                .motor_velocity(speed as f32, 100.0)
                .motor_max_force(max as f32);
        }
        (None, None) => {}
    }
    let a =
        j.a.map_or_else(|| ground.expect("a world body"), |a| handles[a]);
    world.insert_impulse_joint(a, handles[j.b], hinge);
    (a, handles[j.b], anchor(j.anchor_a), anchor(j.anchor_b))
}

/// Box2D's negative group index (shapes of one group never collide), which rapier's
/// interaction groups cannot say: colliders of a negative group carry it as user data and ask
/// this hook, which drops their pairs within a group.
struct GroupIndex;

impl PhysicsHooks for GroupIndex {
    fn filter_contact_pair(&self, c: &PairFilterContext) -> Option<SolverFlags> {
        let group = |h: ColliderHandle| c.colliders[h].user_data as i32;
        let (a, b) = (group(c.collider1), group(c.collider2));
        (a >= 0 || a != b).then(SolverFlags::default)
    }
}

impl Engine for Rapier {
    fn step(&mut self) {
        if let Some((handle, driver)) = self.driver {
            // As Box2D's b2Body_SetTargetTransform: the velocities that reach the pose in dt.
            let (p, angle) = driver.target(self.steps);
            let dt = self.world.integration_parameters.dt;
            let body = &mut self.world.bodies[handle];
            let (here, turned) = (body.translation(), body.rotation().angle());
            let target = Vector::new(p.x as f32, p.y as f32);
            let turn = (angle as f32 - turned + std::f32::consts::PI)
                .rem_euclid(2.0 * std::f32::consts::PI)
                - std::f32::consts::PI;
            body.set_linvel((target - here) / dt, true);
            body.set_angvel(turn / dt, true);
        }
        for spawn in self.spawner.map_or_else(Vec::new, |f| f(self.steps)) {
            if spawn.group >= self.groups.len() {
                self.groups.resize(spawn.group + 1, Default::default());
            }
            // Removing a body removes its colliders and joints.
            for body in self.groups[spawn.group].0.drain(..) {
                self.world.remove_body(body);
            }
            let made: Vec<RigidBodyHandle> = spawn
                .bodies
                .iter()
                .map(|d| insert_body(&mut self.world, d, self.rules, self.sleep))
                .collect();
            let joints = spawn
                .joints
                .iter()
                .map(|j| insert_joint(&mut self.world, self.ground, &made, j))
                .collect();
            self.groups[spawn.group] = (made, joints);
        }
        self.world.step_with_events(&GroupIndex, &());
        self.steps += 1;
    }
    fn max_penetration(&self) -> f64 {
        self.world
            .narrow_phase
            .contact_pairs()
            .flat_map(|p| p.manifolds())
            .flat_map(|m| m.points.iter())
            .map(|pt| -(pt.dist as f64))
            .fold(0.0, f64::max)
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
                    // The body's origin, as tiltbox and Box2D report (its centre of mass unless
                    // it has colliders off its centre).
                    position: [b.translation().x, b.translation().y],
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
        let bodies = &self.world.bodies;
        let gap = self
            .joints
            .iter()
            .chain(self.groups.iter().flat_map(|g| &g.1))
            .map(|&(a, b, pa, pb)| {
                let world = |h: RigidBodyHandle, p: Vector| bodies[h].position() * p;
                (world(a, pa) - world(b, pb)).length()
            })
            .fold(0.0, f32::max);
        let spawned = self.groups.iter().flat_map(|g| &g.0);
        let mut sanity = summarise(
            self.dynamic.iter().chain(spawned).map(|&h| {
                let b = &self.world.bodies[h];
                (b.translation().y, !b.is_sleeping())
            }),
            self.floor,
        );
        sanity.joint_gap = gap;
        sanity
    }
}

// ---------------------------------------------------------------------------------------------
// Timing.

/// Which engine, as the tables name them. `Box2dLocal` is the Box2D build linked into this
/// binary (SSE2, or AVX2 with `--features avx2`); `Box2dRemote` the other build, served by a
/// child process (see [`remote`]).
#[derive(Clone, Debug)]
enum Which {
    Tiltbox,
    Box2dLocal,
    Box2dRemote(PathBuf),
    Rapier,
}

impl Which {
    fn label(&self) -> String {
        match self {
            Which::Tiltbox => "tiltbox".into(),
            Which::Box2dLocal => box2d::LABEL.into(),
            Which::Box2dRemote(_) => remote::other_label().into(),
            Which::Rapier => "rapier2d".into(),
        }
    }

    /// Build `setup` (benchmark scene `name`, or `pyramid-BASE`) in this engine.
    fn build(&self, name: &str, setup: &Setup) -> Box<dyn Engine> {
        match self {
            Which::Tiltbox => Box::new(Tiltbox::new(setup)),
            Which::Box2dLocal => Box::new(box2d::Box2d::new(setup)),
            Which::Box2dRemote(path) => Box::new(
                remote::Remote::spawn(path, name)
                    .unwrap_or_else(|e| panic!("cannot start {}: {e}", path.display())),
            ),
            Which::Rapier => Box::new(Rapier::new(setup)),
        }
    }
}

/// The engines of a run in table order: tiltbox, Box2D SSE2, Box2D AVX2, rapier2d (the two
/// Box2D builds in that order whichever of them is linked into this binary).
fn engines(other_box2d: Option<PathBuf>) -> Vec<Which> {
    let mut v = vec![Which::Tiltbox, Which::Box2dLocal];
    if let Some(path) = other_box2d {
        if cfg!(feature = "avx2") {
            v.insert(1, Which::Box2dRemote(path));
        } else {
            v.push(Which::Box2dRemote(path));
        }
    }
    v.push(Which::Rapier);
    v
}

/// Per-step timings (ms) and allocation calls of one engine on one scene.
#[derive(Default)]
struct Times {
    ms: Vec<f64>,
    allocs: usize,
}

impl Times {
    fn run(&mut self, engine: &mut dyn Engine, n: usize) {
        self.allocs += engine.run_timed(n, &mut self.ms);
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

/// One engine's figures on one scene.
struct Result {
    label: String,
    times: Times,
    sanity: Sanity,
}

struct Row {
    name: String,
    bodies: usize,
    steps: usize,
    /// In table order; the first is tiltbox.
    results: Vec<Result>,
}

/// Before the first step, every engine must hold the same bodies as tiltbox: same centre of
/// mass, angle, mass and moment of inertia (to 1e-4 relative), or the comparison would be of
/// different scenes. Prints the largest differences to stderr; a mismatch is reported loudly,
/// not hidden.
fn check_same_bodies(name: &str, tb: &dyn Engine, other: &dyn Engine, label: &str) {
    let (a, b) = (tb.dynamic_bodies(), other.dynamic_bodies());
    if b.is_empty() && !a.is_empty() {
        // The AVX2 child: the same code as the SSE2 build, checked there.
        return;
    }
    if a.len() != b.len() {
        eprintln!(
            "  WARNING {name}: tiltbox has {} dynamic bodies, {label} {}",
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
        "  {}{name}: largest difference tiltbox / {label} before the first step: centre of mass \
         {dp:.1e} m, angle {da:.1e} rad, mass {dm:.1e} (relative), inertia {di:.1e} (relative)",
        if bad { "WARNING " } else { "" }
    );
}

/// Warm every engine up (untimed), then time `steps` steps of each, in chunks of `CHUNK`,
/// engine after engine, the engine that goes first rotating chunk by chunk.
fn compare(setup: &Setup, which: &[Which], steps: usize, chunks: bool) -> Row {
    let mut engines: Vec<Box<dyn Engine>> =
        which.iter().map(|w| w.build(setup.name, setup)).collect();
    let labels: Vec<String> = which.iter().map(Which::label).collect();
    for (e, label) in engines.iter().zip(&labels).skip(1) {
        check_same_bodies(setup.name, engines[0].as_ref(), e.as_ref(), label);
    }
    for e in engines.iter_mut() {
        e.warm(setup.warm_up);
    }
    let k = engines.len();
    let mut times: Vec<Times> = (0..k).map(|_| Times::default()).collect();
    let mut allocs_before = vec![0usize; k];
    let mut done = 0;
    let mut chunk = 0;
    while done < steps {
        let n = CHUNK.min(steps - done);
        for j in 0..k {
            let i = (chunk + j) % k;
            times[i].run(engines[i].as_mut(), n);
        }
        chunk += 1;
        if chunks {
            let mut line = format!("  steps {:4}..{:4}:", done, done + n);
            for i in 0..k {
                let t = &times[i];
                let mut v = t.ms[t.ms.len() - n..].to_vec();
                v.sort_by(f64::total_cmp);
                line += &format!(
                    " {} {} ms, {} allocs, {} contacts;",
                    labels[i],
                    fmt_ms(v[n / 2]),
                    t.allocs - allocs_before[i],
                    engines[i].contact_pairs()
                );
                allocs_before[i] = t.allocs;
            }
            eprintln!("{line}");
        }
        done += n;
    }
    let results = times
        .into_iter()
        .zip(labels)
        .zip(&engines)
        .map(|((times, label), e)| Result {
            label,
            times,
            sanity: e.sanity(),
        })
        .collect();
    Row {
        name: setup.name.to_string(),
        bodies: setup.bodies.len(),
        steps,
        results,
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
    if s.joint_gap > 0.0 {
        out += &format!(" / gap {:.1} mm", 1e3 * s.joint_gap);
    }
    if s.lost > 0 {
        out += &format!(" ({} lost)", s.lost);
    }
    out
}

/// One table, every engine: ms/step median and min, tiltbox / peer ratios, sanity, allocations.
fn print_table(rows: &[Row]) {
    let Some(first) = rows.first() else { return };
    let labels: Vec<&str> = first.results.iter().map(|r| r.label.as_str()).collect();
    let mut head = "| scene | bodies | steps |".to_string();
    let mut rule = "| --- | ---: | ---: |".to_string();
    for l in &labels {
        head += &format!(" {l} median | {l} min |");
        rule += " ---: | ---: |";
    }
    for l in &labels[1..] {
        head += &format!(" tiltbox / {l} |");
        rule += " ---: |";
    }
    for l in &labels {
        head += &format!(" {l} top / mean y / awake |");
        rule += " --- |";
    }
    head += " allocs/step |";
    rule += " --- |";
    println!("{head}\n{rule}");
    for r in rows {
        let tb = &r.results[0].times;
        let mut line = format!("| {} | {} | {} |", r.name, r.bodies, r.steps);
        for x in &r.results {
            line += &format!(
                " {} | {} |",
                fmt_ms(x.times.median()),
                fmt_ms(x.times.min())
            );
        }
        for x in &r.results[1..] {
            line += &format!(
                " {:.2} ({:.2}) |",
                tb.median() / x.times.median(),
                tb.min() / x.times.min()
            );
        }
        for x in &r.results {
            line += &format!(" {} |", fmt_sanity(&x.sanity));
        }
        let allocs: Vec<String> = r
            .results
            .iter()
            .map(|x| format!("{:.1}", x.times.allocs_per_step()))
            .collect();
        line += &format!(" {} |", allocs.join(" / "));
        println!("{line}");
    }
    println!(
        "\n(times in ms/step; ratio = tiltbox / peer of the medians (of the minima in brackets), \
         < 1 means tiltbox is faster; sanity columns at the end of the run; allocs/step in \
         column order: {})",
        labels.join(", ")
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

/// Step each selected scene for `seconds` of simulated time in every engine linked into this
/// binary (tiltbox, this build's Box2D, rapier2d), with sleep on and
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
         bounding radius), the same test for every engine.\n"
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
            let mut engines: [(&str, Box<dyn Engine>); 3] = [
                ("tiltbox", Box::new(Tiltbox::new(&s))),
                (box2d::LABEL, Box::new(box2d::Box2d::new(&s))),
                ("rapier2d", Box::new(Rapier::new(&s))),
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

fn live_bytes_after_10_steps(setup: &Setup, which: &Which) -> usize {
    let before = LIVE_BYTES.load(Relaxed);
    let mut e = which.build(setup.name, setup);
    e.warm(10);
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
    // The AVX2 child's bytes are not in this process; its data structures are the SSE2 build's.
    for which in [Which::Tiltbox, Which::Box2dLocal, Which::Rapier] {
        let bytes = live_bytes_after_10_steps(setup, &which);
        println!(
            "| {} | {bytes} | {:.0} |",
            which.label(),
            bytes as f64 / n as f64
        );
    }
}

// ---------------------------------------------------------------------------------------------
// The growth scene.

/// `pile_N`: tiltbox's growth scene (`cases::pile`: N boxes of 1 m side by side in a pile 20
/// deep, sleep off), named for its size so that the rows of several sizes tell apart.
pub(crate) fn pile_setup(boxes: usize) -> Setup {
    Setup {
        name: Box::leak(format!("pile_{boxes}").into_boxed_str()),
        ..tiltbox::measure::cases::pile(boxes)
    }
}

// Largest pyramid at 60 Hz.

/// `large_pyramid` with another base: ground 2 m thick, at least 200 m wide, pyramid of 1 m boxes
/// (density 1, friction 0.6), sleep off.
pub(crate) fn pyramid_setup(base: usize) -> Setup {
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
        driver: None,
        spawner: None,
        joints: Vec::new(),
    }
}

/// Median ms/step of a pyramid of `base` (after `warm` untimed steps, `timed` timed ones).
fn pyramid_median(engine: &Which, base: usize, warm: usize, timed: usize) -> (f64, Sanity) {
    let setup = pyramid_setup(base);
    let mut e = engine.build(&format!("pyramid-{base}"), &setup);
    e.warm(warm);
    let mut t = Times::default();
    t.run(e.as_mut(), timed);
    (t.median(), e.sanity())
}

/// Bisect the base until the median step time is just under the 60 Hz budget.
fn largest_pyramid(engine: &Which, quick: bool, guess: usize) -> (usize, f64, Sanity) {
    let (warm, timed, resolution) = if quick { (5, 10, 8) } else { (20, 100, 1) };
    let label = engine.label();
    let probe = |base: usize| {
        let (ms, s) = pyramid_median(engine, base, warm, timed);
        eprintln!(
            "  {label}: base {base:4} ({:6} boxes): {ms:7.3} ms/step",
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
    let mut paddle = false;
    let mut extras = true;
    let mut chunks = false;
    let mut settle_seconds: Option<f32> = None;
    let mut accuracy_out: Option<PathBuf> = None;
    let mut other_box2d: Option<PathBuf> = remote::default_other_binary();
    let mut filters: Vec<String> = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--serve" => {
                let Some(scene) = args.next() else {
                    eprintln!("--serve wants a scene name");
                    std::process::exit(2);
                };
                box2d::install_allocator();
                remote::serve(&scene);
                return;
            }
            "--workers" => match args.next().and_then(|n| n.parse::<u32>().ok()) {
                Some(n) if (1..=64).contains(&n) => WORKERS.store(n, Relaxed),
                _ => {
                    eprintln!("--workers wants a number of threads within 1..=64");
                    std::process::exit(2);
                }
            },
            "--paddle" => paddle = true,
            "--quick" => quick = true,
            "--no-extras" => extras = false,
            "--chunks" => chunks = true,
            "--no-avx2" | "--no-other-box2d" => other_box2d = None,
            "--avx2" | "--other-box2d" => match args.next() {
                Some(p) => other_box2d = Some(PathBuf::from(p)),
                None => {
                    eprintln!("{arg} wants the path of the other Box2D build of vs-peers");
                    std::process::exit(2);
                }
            },
            "--accuracy" => match args.next() {
                Some(p) => accuracy_out = Some(PathBuf::from(p)),
                None => {
                    eprintln!("--accuracy wants an output CSV path");
                    std::process::exit(2);
                }
            },
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
                    "usage: vs-peers [--paddle] [--quick] [--no-extras] [--chunks] [--settle[=SECONDS]] [--avx2 PATH | --no-avx2]\n\
                     \x20               [--workers N]\n\
                     --workers N: tiltbox and Box2D each step with N threads (Box2D through a task pool of\n\
                     this tool's; rapier2d stays single threaded: its parallel feature is not built).\n\
                     \x20               [--accuracy OUT.csv] [SCENE|memory|largest_pyramid ...]\n\
                     --avx2 PATH: the AVX2 build of this tool (`./run.sh` builds it: cargo build --release\n\
                     --features avx2, copied to target/avx2/), run as a child process that times Box2D AVX2 chunk by\n\
                     chunk in turn with the other engines; default: {} if it exists.\n\
                     --no-avx2: leave the AVX2 build out.\n\
                     --chunks prints per 25-step chunk and engine: median ms, allocation calls and\n\
                     contact pairs at the chunk's end (stderr).\n\
                     --paddle times nothing: the stiff suite's spinner case (the paddle's mean and slowest\n\
                     speed, the farthest body from the ring's centre) in tiltbox, Box2D and rapier2d.\n\
                     --settle[=SECONDS] times nothing: steps the selected scenes for SECONDS (10) of\n\
                     simulated time with sleep on and off and reports awake / moving bodies, top\n\
                     speeds and positions every 2 s, and per kind of shape at the end.\n\
                     --accuracy OUT.csv: the peers' work-precision points for `tiltbox report`\n\
                     (engine,case,dt,error,cpu_ms_per_simulated_s); --quick: fewer step sizes.\n\
                     SCENE is a substring of a benchmark scene name; with any name given, the\n\
                     memory and largest-pyramid extras run only when named.",
                    remote::DEFAULT_OTHER_BINARY
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
    box2d::install_allocator();

    if paddle {
        paddle::run();
        return;
    }

    if let Some(out) = accuracy_out {
        if let Err(e) = accuracy::write_csv(&out, quick) {
            eprintln!("--accuracy: {e}");
            std::process::exit(1);
        }
        return;
    }

    let mut setups = benchmark_setups();
    // `pile_N` runs the growth scene at N boxes; it is never part of the default selection.
    setups.extend(
        filters
            .iter()
            .filter_map(|f| f.strip_prefix("pile_")?.parse().ok())
            .map(pile_setup),
    );
    let wanted =
        |name: &str| filters.is_empty() || filters.iter().any(|f| name.contains(f.as_str()));
    let extra_wanted =
        |name: &str| extras && (filters.is_empty() || filters.iter().any(|f| f == name));

    let which = engines(other_box2d);
    println!(
        "# tiltbox vs Box2D v3 {} and rapier2d {} ({}, dt 1/60{})\n",
        box2d::version(),
        rapier2d::VERSION,
        match workers() {
            1 => "single thread".to_string(),
            n => format!("{n} workers for tiltbox and Box2D, rapier2d single thread"),
        },
        if quick { ", --quick" } else { "" }
    );
    println!("machine: {}\n", machine());
    let s = Settings::default();
    println!(
        "tiltbox: {:?} solver, {} substeps, friction mixing {:?}, restitution mixing {:?}, {}; \
         Box2D: b2World_Step(dt, 4 substeps), {}, default continuous \
         collision, friction and restitution mixing callbacks set to tiltbox's rules; \
         rapier: default IntegrationParameters ({} solver iterations), combine rules {:?} / {:?}, \
         one thread; engines: {}; they take turns every {CHUNK} steps{}.\n",
        s.solver,
        s.substeps,
        s.friction_mixing,
        s.restitution_mixing,
        match workers() {
            1 => "one thread".to_string(),
            n => format!("{n} workers"),
        },
        match workers() {
            1 => "one worker, no task system".to_string(),
            n => format!("{n} workers, this tool's task pool"),
        },
        IntegrationParameters::default().num_solver_iterations,
        combine_rule(s.friction_mixing),
        combine_rule(s.restitution_mixing),
        which
            .iter()
            .map(Which::label)
            .collect::<Vec<_>>()
            .join(", "),
        if which.iter().any(|w| matches!(w, Which::Box2dRemote(_))) {
            format!(
                " ({} runs in a child process, {}, served over a pipe in its turn)",
                remote::other_label(),
                which
                    .iter()
                    .find_map(|w| match w {
                        Which::Box2dRemote(p) => Some(p.display().to_string()),
                        _ => None,
                    })
                    .unwrap_or_default()
            )
        } else {
            String::new()
        }
    );

    if let Some(seconds) = settle_seconds {
        let selected: Vec<&Setup> = setups.iter().filter(|s| wanted(s.name)).collect();
        settle(&selected, seconds);
        return;
    }

    println!("load average before: {}\n", load_average());
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
        rows.push(compare(setup, &which, steps, chunks));
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
        for (i, engine) in which.iter().enumerate() {
            let guess = guess_base(large.map(|r| r.results[i].times.median()));
            let (base, ms, s) = largest_pyramid(engine, quick, guess);
            println!(
                "| {} | {base} | {} | {ms:.3} | {} |",
                engine.label(),
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

/// CPU model (from /proc/cpuinfo) and the number of CPUs this process may use.
pub(crate) fn machine() -> String {
    let cpu = cpu_model();
    let n = std::thread::available_parallelism().map_or(0, |n| n.get());
    format!("{cpu}, nproc {n}")
}
