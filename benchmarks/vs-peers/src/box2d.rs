//! Box2D v3 (through `boxdd-sys`, compiled from C with `cc`) behind the benchmark's `Engine`
//! interface, built from the same `tiltbox::physics::BodyDef`s as the other engines.
//!
//! Which SIMD build this is depends on the cargo feature `avx2` (boxdd-sys' `simd-avx2`); see
//! [`LABEL`]. Box2D's C allocations go through [`install_allocator`] to the process' counting
//! allocator, so live bytes and allocation calls count for Box2D as for the Rust engines.

use crate::{BodyState, Engine, Sanity};
use boxdd_sys::ffi::*;
use std::alloc::{GlobalAlloc, Layout};
use tiltbox::measure::cases::{Setup, SetupJoint};
use tiltbox::physics::{BodyDef, MassSpec, Mixing, Real, Rot, Settings, Shape, Transform};

/// How the tables name this build of Box2D.
pub const LABEL: &str = if cfg!(feature = "avx2") {
    "Box2D v3 (AVX2)"
} else {
    "Box2D v3 (SSE2)"
};

/// Box2D's version as `major.minor.revision`.
pub fn version() -> String {
    // SAFETY: a plain query of constants.
    let v = unsafe { b2GetVersion() };
    format!("{}.{}.{}", v.major, v.minor, v.revision)
}

// ---------------------------------------------------------------------------------------------
// Allocations: Box2D's b2Alloc/b2Free through the counting global allocator.

fn layout(size: usize, alignment: i32) -> Layout {
    Layout::from_size_align(size.max(1), (alignment.max(1) as usize).next_power_of_two())
        .expect("Box2D asked for an impossible layout")
}

unsafe extern "C" fn b2_alloc(size: usize, alignment: i32) -> *mut std::ffi::c_void {
    // SAFETY: a non-zero size and a power-of-two alignment (see `layout`).
    unsafe { crate::GLOBAL.alloc(layout(size, alignment)) as *mut std::ffi::c_void }
}

unsafe extern "C" fn b2_free(mem: *mut std::ffi::c_void, size: usize) {
    if !mem.is_null() {
        // Box2D's b2Alloc rounds sizes up to a multiple of 32 bytes and asks for 32-byte
        // alignment (B2_ALIGNMENT) before calling us, while b2Free passes the size unrounded:
        // free with what `b2_alloc` was given.
        let size32 = ((size.max(1) - 1) | 0x1F) + 1;
        // SAFETY: `mem` came from `b2_alloc` with this size and alignment.
        unsafe { crate::GLOBAL.dealloc(mem as *mut u8, layout(size32, 32)) }
    }
}

/// Route Box2D's allocations through the counting allocator. Call once, before any world.
pub fn install_allocator() {
    // SAFETY: both functions have the C signatures Box2D expects and no world exists yet.
    unsafe { b2SetAllocator(Some(b2_alloc), Some(b2_free)) }
}

// ---------------------------------------------------------------------------------------------
// Mixing rules: tiltbox's `Mixing` as Box2D callbacks.

unsafe extern "C" fn mix_geometric(a: f32, _: u64, b: f32, _: u64) -> f32 {
    (a * b).sqrt()
}
unsafe extern "C" fn mix_product(a: f32, _: u64, b: f32, _: u64) -> f32 {
    a * b
}
unsafe extern "C" fn mix_min(a: f32, _: u64, b: f32, _: u64) -> f32 {
    a.min(b)
}
unsafe extern "C" fn mix_max(a: f32, _: u64, b: f32, _: u64) -> f32 {
    a.max(b)
}

/// The Box2D mixing callback (same signature for friction and restitution) of a tiltbox rule.
fn mixing(m: Mixing) -> unsafe extern "C" fn(f32, u64, f32, u64) -> f32 {
    match m {
        Mixing::GeometricMean => mix_geometric,
        Mixing::Product => mix_product,
        Mixing::Min => mix_min,
        Mixing::Max => mix_max,
    }
}

// ---------------------------------------------------------------------------------------------

/// The bodies one group of spawns holds, and their joints (bodies and local anchors).
type Group = (Vec<b2BodyId>, Vec<(b2BodyId, b2BodyId, b2Vec2, b2Vec2)>);

/// A Box2D world holding one scene.
pub struct Box2d {
    world: b2WorldId,
    /// A static body without shapes at the origin, for joints to the world.
    ground: b2BodyId,
    /// The scene's spawns, its sleep flag, and the bodies each group of spawns holds.
    spawner: Option<fn(usize) -> Vec<tiltbox::measure::cases::SetupSpawn>>,
    sleep: bool,
    groups: Vec<Group>,
    /// The driven kinematic body and its driver, and the steps taken.
    driver: Option<(b2BodyId, tiltbox::measure::cases::SetupDriver)>,
    steps: usize,
    dynamic: Vec<b2BodyId>,
    /// Each joint's bodies and local anchors, for the gap in the sanity column.
    joints: Vec<(b2BodyId, b2BodyId, b2Vec2, b2Vec2)>,
    floor: f32,
    dt: f32,
    substeps: i32,
}

fn v(x: f32, y: f32) -> b2Vec2 {
    b2Vec2 { x, y }
}

impl Box2d {
    /// The scene at dt 1/60 with 4 substeps (the benchmark's step).
    pub fn new(setup: &Setup) -> Box2d {
        Box2d::with_step(setup, crate::DT, 4)
    }

    /// The scene stepped at `dt` with `substeps` substeps.
    pub fn with_step(setup: &Setup, dt: f32, substeps: i32) -> Box2d {
        // tiltbox's `Setup::build` uses the default settings plus the scene's sleep flag: mirror
        // its mixing rules (Box2D's own defaults are sqrt(a b) for friction, as tiltbox, and
        // max(a, b) for restitution, where tiltbox takes sqrt(a b)).
        let settings = Settings::default();
        // SAFETY: every call below is Box2D's C API used as documented: definitions come from
        // the b2Default* constructors, ids from the create calls, pointers point at live locals.
        unsafe {
            let mut def = b2DefaultWorldDef();
            def.gravity = v(setup.gravity.x as f32, setup.gravity.y as f32);
            def.enableSleep = setup.sleep;
            // Single-threaded (one worker, no task system), or `--workers N` through the pool.
            let workers = crate::workers();
            def.workerCount = workers as i32;
            if workers > 1 {
                tasks::start(workers - 1);
                def.enqueueTask = Some(tasks::enqueue);
                def.finishTask = Some(tasks::finish);
            } else {
                def.enqueueTask = None;
                def.finishTask = None;
            }
            def.frictionCallback = Some(mixing(settings.friction_mixing));
            def.restitutionCallback = Some(mixing(settings.restitution_mixing));
            // Continuous collision and everything else: Box2D's defaults.
            let world = b2CreateWorld(&def);
            let mut dynamic = Vec::new();
            let mut all = Vec::with_capacity(setup.bodies.len());
            for d in &setup.bodies {
                let body = create_body(world, d, setup.sleep);
                if d.mass != MassSpec::Static && d.mass != MassSpec::Kinematic {
                    dynamic.push(body);
                }
                all.push(body);
            }
            // The world, for joints to it: a static body without shapes at the origin.
            let ground = b2CreateBody(world, &b2DefaultBodyDef());
            let joints = setup
                .joints
                .iter()
                .map(|j| create_joint(world, ground, &all, j))
                .collect();
            Box2d {
                world,
                ground,
                spawner: setup.spawner,
                sleep: setup.sleep,
                groups: Vec::new(),
                driver: setup.driver.map(|d| (all[d.body], d)),
                steps: 0,
                dynamic,
                joints,
                floor: crate::lowest_static(&setup.bodies),
                dt,
                substeps,
            }
        }
    }
}

impl Drop for Box2d {
    fn drop(&mut self) {
        // SAFETY: the world was created in `with_step` and is destroyed once.
        unsafe { b2DestroyWorld(self.world) }
    }
}

/// One tiltbox shape on a Box2D body, placed at `pose` in the body's frame.
///
/// # Safety
/// `body` is a live body and `sd` a shape definition from `b2DefaultShapeDef`.
unsafe fn create_shape(body: b2BodyId, sd: &b2ShapeDef, shape: &Shape, pose: Transform) {
    let at = |x: Real, y: Real| {
        let p = pose.apply(tiltbox::physics::vec2(x, y));
        v(p.x as f32, p.y as f32)
    };
    let rot = b2Rot {
        c: pose.q.c as f32,
        s: pose.q.s as f32,
    };
    match *shape {
        Shape::Rect { half_extents: h } => {
            let p = b2MakeOffsetBox(h.x as f32, h.y as f32, at(0.0, 0.0), rot);
            b2CreatePolygonShape(body, sd, &p);
        }
        Shape::Circle { radius } => {
            let c = b2Circle {
                center: at(0.0, 0.0),
                radius: radius as f32,
            };
            b2CreateCircleShape(body, sd, &c);
        }
        Shape::Capsule {
            half_length,
            radius,
        } => {
            let c = b2Capsule {
                center1: at(-half_length, 0.0),
                center2: at(half_length, 0.0),
                radius: radius as f32,
            };
            b2CreateCapsuleShape(body, sd, &c);
        }
        Shape::Polygon(ref poly) => {
            // tiltbox's vertices (counter-clockwise, centred on the centroid) through Box2D's
            // hull, so a body of one polygon has its origin at its centre of mass in both.
            let points: Vec<b2Vec2> = poly.vertices().iter().map(|p| at(p.x, p.y)).collect();
            let hull = b2ComputeHull(points.as_ptr(), points.len() as i32);
            assert!(
                hull.count as usize == points.len(),
                "Box2D's hull dropped a vertex of a tiltbox polygon"
            );
            let p = b2MakePolygon(&hull, 0.0);
            b2CreatePolygonShape(body, sd, &p);
        }
        Shape::Segment(ref s) => {
            let segment = b2Segment {
                point1: at(s.a.x, s.a.y),
                point2: at(s.b.x, s.b.y),
            };
            b2CreateSegmentShape(body, sd, &segment);
        }
    }
}

/// Create `d` in `world` with its shapes; `sleep`: whether it may sleep.
///
/// # Safety
/// `world` is a live Box2D world.
unsafe fn create_body(world: b2WorldId, d: &BodyDef, sleep: bool) -> b2BodyId {
    let mut bd = b2DefaultBodyDef();
    let is_static = d.mass == MassSpec::Static;
    let is_kinematic = d.mass == MassSpec::Kinematic;
    bd.type_ = if is_static {
        b2BodyType_b2_staticBody
    } else if is_kinematic {
        b2BodyType_b2_kinematicBody
    } else {
        b2BodyType_b2_dynamicBody
    };
    bd.position = v(d.position.x as f32, d.position.y as f32);
    // The exact rotation (Box2D's b2ComputeCosSin approximates to about 1e-3 rad).
    let angle = d.angle as f32;
    bd.rotation = b2Rot {
        c: angle.cos(),
        s: angle.sin(),
    };
    bd.linearVelocity = v(d.linear_velocity.x as f32, d.linear_velocity.y as f32);
    bd.angularVelocity = d.angular_velocity as f32;
    bd.enableSleep = sleep;
    bd.isAwake = d.awake;
    let body = b2CreateBody(world, &bd);
    let own_density = match d.mass {
        MassSpec::Static | MassSpec::Kinematic => 0.0,
        MassSpec::Density(rho) => rho as f32,
        // Box2D takes a density: the one that gives this mass.
        MassSpec::Mass(m) => {
            assert!(d.parts.is_empty(), "the peer scenes give parts by density");
            (m / d.shape.area()) as f32
        }
    };
    let own = (
        &d.shape,
        Transform::IDENTITY,
        d.filter,
        d.friction,
        d.restitution,
        own_density,
        d.flags,
    );
    let parts = d.parts.iter().map(|p| {
        let pose = Transform {
            p: p.offset,
            q: Rot::from_angle(p.angle),
        };
        let fixed = is_static || is_kinematic;
        let density = if fixed { 0.0 } else { p.density as f32 };
        let (f, r) = (p.friction, p.restitution);
        (&p.shape, pose, p.filter, f, r, density, p.flags)
    });
    for (shape, pose, filter, friction, restitution, density, flags) in
        std::iter::once(own).chain(parts)
    {
        let mut sd = b2DefaultShapeDef();
        sd.filter.categoryBits = filter.category;
        sd.filter.maskBits = filter.mask;
        sd.filter.groupIndex = filter.group;
        sd.material.friction = friction as f32;
        sd.material.restitution = restitution as f32;
        sd.density = density;
        sd.isSensor = flags.sensor;
        sd.enableHitEvents = flags.hit_events;
        create_shape(body, &sd, shape, pose);
    }
    body
}

/// Create hinge `j` between bodies of `all` (A None: `ground`); its bodies and anchors.
///
/// # Safety
/// `world` is a live Box2D world holding `ground` and `all`.
unsafe fn create_joint(
    world: b2WorldId,
    ground: b2BodyId,
    all: &[b2BodyId],
    j: &SetupJoint,
) -> (b2BodyId, b2BodyId, b2Vec2, b2Vec2) {
    let mut jd = b2DefaultRevoluteJointDef();
    let a = j.a.map_or(ground, |a| all[a]);
    jd.base.bodyIdA = a;
    jd.base.bodyIdB = all[j.b];
    let (pa, pb) = (
        v(j.anchor_a.x as f32, j.anchor_a.y as f32),
        v(j.anchor_b.x as f32, j.anchor_b.y as f32),
    );
    jd.base.localFrameA.p = pa;
    jd.base.localFrameB.p = pb;
    if let Some((speed, max)) = j.motor {
        jd.enableMotor = true;
        jd.motorSpeed = speed as f32;
        jd.maxMotorTorque = max as f32;
    }
    if let Some((lower, upper)) = j.limit {
        jd.enableLimit = true;
        jd.lowerAngle = lower as f32;
        jd.upperAngle = upper as f32;
    }
    if let Some((hertz, damping_ratio)) = j.spring {
        jd.enableSpring = true;
        jd.hertz = hertz as f32;
        jd.dampingRatio = damping_ratio as f32;
    }
    b2CreateRevoluteJoint(world, &jd);
    (a, all[j.b], pa, pb)
}

fn angle(r: b2Rot) -> f32 {
    r.s.atan2(r.c)
}

impl Engine for Box2d {
    fn step(&mut self) {
        // SAFETY: a live world, the bodies of live groups in it, and a live kinematic body.
        unsafe {
            for spawn in self.spawner.map_or_else(Vec::new, |f| f(self.steps)) {
                if spawn.group >= self.groups.len() {
                    self.groups.resize(spawn.group + 1, Default::default());
                }
                // Destroying a body destroys its joints.
                for body in self.groups[spawn.group].0.drain(..) {
                    b2DestroyBody(body);
                }
                let made: Vec<b2BodyId> = spawn
                    .bodies
                    .iter()
                    .map(|d| create_body(self.world, d, self.sleep))
                    .collect();
                let joints = spawn
                    .joints
                    .iter()
                    .map(|j| create_joint(self.world, self.ground, &made, j))
                    .collect();
                self.groups[spawn.group] = (made, joints);
            }
            if let Some((body, driver)) = self.driver {
                let (p, angle) = driver.target(self.steps);
                let angle = angle as f32;
                let target = b2Transform {
                    p: v(p.x as f32, p.y as f32),
                    q: b2Rot {
                        c: angle.cos(),
                        s: angle.sin(),
                    },
                };
                b2Body_SetTargetTransform(body, target, self.dt, true);
            }
            b2World_Step(self.world, self.dt, self.substeps);
        }
        self.steps += 1;
    }
    fn contact_pairs(&self) -> usize {
        // SAFETY: a live world. Box2D's count includes pairs whose AABBs overlap without a
        // manifold point, so it reads higher than the other engines'.
        unsafe { b2World_GetCounters(self.world).contactCount as usize }
    }
    fn dynamic_bodies(&self) -> Vec<BodyState> {
        self.dynamic
            .iter()
            .map(|&b| {
                // SAFETY: live bodies of a live world.
                unsafe {
                    let p = b2Body_GetPosition(b);
                    let lin = b2Body_GetLinearVelocity(b);
                    BodyState {
                        position: [p.x, p.y],
                        angle: angle(b2Body_GetRotation(b)),
                        velocity: [lin.x, lin.y],
                        angular_velocity: b2Body_GetAngularVelocity(b),
                        awake: b2Body_IsAwake(b),
                        mass: b2Body_GetMass(b),
                        inertia: b2Body_GetRotationalInertia(b),
                    }
                }
            })
            .collect()
    }
    fn sanity(&self) -> Sanity {
        let spawned = self.groups.iter().flat_map(|g| &g.0);
        let mut sanity = crate::summarise(
            self.dynamic.iter().chain(spawned).map(|&b| {
                // SAFETY: live bodies of a live world.
                unsafe { (b2Body_GetPosition(b).y, b2Body_IsAwake(b)) }
            }),
            self.floor,
        );
        sanity.joint_gap = self
            .joints
            .iter()
            .chain(self.groups.iter().flat_map(|g| &g.1))
            .map(|&(a, b, pa, pb)| {
                // SAFETY: live bodies of a live world.
                let (wa, wb) =
                    unsafe { (b2Body_GetWorldPoint(a, pa), b2Body_GetWorldPoint(b, pb)) };
                (wa.x - wb.x).hypot(wa.y - wb.y)
            })
            .fold(0.0, f32::max);
        sanity
    }
    fn max_penetration(&self) -> f64 {
        let mut deepest = 0.0f64;
        let mut buf: Vec<b2ContactData> = Vec::new();
        for &b in &self.dynamic {
            // SAFETY: a live body; the buffer holds `capacity` elements, Box2D writes at most
            // that many and returns how many it wrote.
            unsafe {
                let capacity = b2Body_GetContactCapacity(b);
                if capacity <= 0 {
                    continue;
                }
                buf.clear();
                buf.reserve(capacity as usize);
                let n = b2Body_GetContactData(b, buf.as_mut_ptr(), capacity);
                buf.set_len(n.clamp(0, capacity) as usize);
            }
            for c in &buf {
                let m = &c.manifold;
                for p in m.points.iter().take(m.pointCount.clamp(0, 2) as usize) {
                    deepest = deepest.max(-(p.separation as f64));
                }
            }
        }
        deepest
    }
}

/// A task system for Box2D's workers (`--workers N`): N - 1 threads that run the tasks Box2D
/// enqueues. A thread spins for a while before it sleeps, as a game's task scheduler does, so
/// that Box2D's back-to-back tasks within a step do not each wait for a wake-up.
mod tasks {
    use std::collections::VecDeque;
    use std::ffi::c_void;
    use std::sync::{Arc, Condvar, Mutex, OnceLock};
    use std::time::{Duration, Instant};

    /// A task and its completion.
    struct Job {
        task: unsafe extern "C" fn(*mut c_void),
        context: *mut c_void,
        done: Arc<Done>,
    }
    // SAFETY: Box2D's task contexts are made to be run on other threads.
    unsafe impl Send for Job {}

    #[derive(Default)]
    struct Done {
        flag: Mutex<bool>,
        signal: Condvar,
    }

    #[derive(Default)]
    struct Pool {
        queue: Mutex<VecDeque<Job>>,
        signal: Condvar,
    }

    static POOL: OnceLock<Pool> = OnceLock::new();

    /// Start `threads` threads (once per process).
    pub fn start(threads: u32) {
        let mut started = false;
        POOL.get_or_init(|| {
            started = true;
            Pool::default()
        });
        if started {
            for _ in 0..threads {
                std::thread::spawn(run);
            }
        }
    }

    fn run() {
        let pool = POOL.get().expect("started");
        loop {
            let job = take(pool);
            // SAFETY: Box2D's task, called with its context, as its API asks.
            unsafe { (job.task)(job.context) };
            *job.done.flag.lock().unwrap() = true;
            job.done.signal.notify_all();
        }
    }

    /// The next job: spin up to 100 microseconds for it, then sleep until one comes.
    fn take(pool: &Pool) -> Job {
        let until = Instant::now() + Duration::from_micros(100);
        while Instant::now() < until {
            if let Some(job) = pool.queue.lock().unwrap().pop_front() {
                return job;
            }
            std::hint::spin_loop();
        }
        let mut queue = pool.queue.lock().unwrap();
        loop {
            if let Some(job) = queue.pop_front() {
                return job;
            }
            queue = pool.signal.wait(queue).unwrap();
        }
    }

    /// Box2D's `enqueueTask`: queue the task, return its completion.
    pub unsafe extern "C" fn enqueue(
        task: Option<unsafe extern "C" fn(*mut c_void)>,
        context: *mut c_void,
        _user: *mut c_void,
    ) -> *mut c_void {
        let (Some(task), Some(pool)) = (task, POOL.get()) else {
            return std::ptr::null_mut();
        };
        let done = Arc::new(Done::default());
        pool.queue.lock().unwrap().push_back(Job {
            task,
            context,
            done: Arc::clone(&done),
        });
        pool.signal.notify_one();
        Arc::into_raw(done) as *mut c_void
    }

    /// Box2D's `finishTask`: wait for the task.
    pub unsafe extern "C" fn finish(user_task: *mut c_void, _user: *mut c_void) {
        if user_task.is_null() {
            return;
        }
        // SAFETY: made by `Arc::into_raw` in `enqueue`, finished once.
        let done = unsafe { Arc::from_raw(user_task as *const Done) };
        let mut flag = done.flag.lock().unwrap();
        while !*flag {
            flag = done.signal.wait(flag).unwrap();
        }
    }
}
