//! Standard set-ups shared by the tests, the accuracy runners, the report and the benchmarks:
//! grounds, stacks (aligned and jittered), pyramids, closed boxes, Falling Bricks and mixed
//! shapes, built the way Box2D's samples and benchmark build them. Every set-up of the
//! measurement code comes from here. Units: metres, kilograms, radians.

use crate::physics::joint::{Limit, Spring};
use crate::physics::math::{Rot, Transform, PI};
use crate::physics::ragdoll::{ragdoll, RagdollDef};
use crate::physics::{
    BodyDef, BodyId, Filter, JointDef, JointKind, Motor, PartDef, PhysicsError, Polygon, Real,
    Revolute, Shape, Vec2, World,
};

/// A static ground box `width` x `thickness` metres whose top surface is at y = 0, centred on x = `x`.
pub fn ground(
    world: &mut World,
    x: Real,
    width: Real,
    thickness: Real,
) -> Result<BodyId, PhysicsError> {
    world.add_body(&BodyDef::fixed(
        Shape::rect(width, thickness),
        Vec2::new(x, -0.5 * thickness),
    ))
}

/// `n` boxes of side `size` stacked on y = 0, centred on x = `x`, each `gap` above the one below.
/// Returns the ids bottom to top.
pub fn stack(
    world: &mut World,
    n: usize,
    size: Real,
    x: Real,
    gap: Real,
) -> Result<Vec<BodyId>, PhysicsError> {
    (0..n)
        .map(|i| {
            let y = 0.5 * size + i as Real * (size + gap);
            world.add_body(&BodyDef::dynamic(Shape::rect(size, size), Vec2::new(x, y)))
        })
        .collect()
}

/// `n` boxes of side `size` stacked on y = 0 around x = `x`, each shifted sideways by a fixed
/// pseudo-random amount within +-1 % of its size (box2d-lite jitters its stack by +-10 %), so a
/// perfectly symmetric stack cannot hide drift. Returns the ids bottom to top.
pub fn jittered_stack(
    world: &mut World,
    n: usize,
    size: Real,
    x: Real,
) -> Result<Vec<BodyId>, PhysicsError> {
    (0..n)
        .map(|i| {
            let jitter = 0.01 * size * (((i * 7919) % 11) as Real / 5.0 - 1.0);
            let y = (0.5 + i as Real) * size;
            world.add_body(&BodyDef::dynamic(
                Shape::rect(size, size),
                Vec2::new(x + jitter, y),
            ))
        })
        .collect()
}

/// A pyramid with `base` boxes of side `size` in its bottom row, resting on y = 0 and centred on
/// x = `x`: row i has base - i boxes (Box2D's benchmark layout). `base` = 100 gives 5,050 boxes.
pub fn pyramid(
    world: &mut World,
    base: usize,
    size: Real,
    x: Real,
    friction: Real,
) -> Result<Vec<BodyId>, PhysicsError> {
    let mut ids = Vec::with_capacity(base * (base + 1) / 2);
    for row in 0..base {
        let count = base - row;
        let y = (0.5 + row as Real) * size;
        let x0 = x - 0.5 * (count as Real - 1.0) * size;
        for j in 0..count {
            let def =
                BodyDef::dynamic(Shape::rect(size, size), Vec2::new(x0 + j as Real * size, y))
                    .with_friction(friction);
            ids.push(world.add_body(&def)?);
        }
    }
    Ok(ids)
}

/// A closed box of four static walls: inner size `width` x `height` metres, walls `thickness`
/// thick, inner floor at y = 0, centred on x = 0. Returns the walls: floor, ceiling, left, right.
pub fn closed_box(
    world: &mut World,
    width: Real,
    height: Real,
    thickness: Real,
) -> Result<[BodyId; 4], PhysicsError> {
    let defs = closed_box_defs(width, height, thickness);
    Ok([
        world.add_body(&defs[0])?,
        world.add_body(&defs[1])?,
        world.add_body(&defs[2])?,
        world.add_body(&defs[3])?,
    ])
}

/// The six bricks of [`falling_bricks`]: (width, height, x, y, angle, restitution), in a
/// 10 m x 10 m box.
const BRICKS: [(Real, Real, Real, Real, Real, Real); 6] = [
    (1.0, 0.5, -3.0, 3.0, 0.3, 0.1),
    (0.6, 0.6, -1.0, 5.0, 0.0, 0.2),
    (2.0, 0.4, 1.0, 6.5, -0.4, 0.0),
    (0.3, 1.2, 3.0, 4.0, 0.8, 0.3),
    (1.5, 1.0, 0.5, 8.5, 0.1, 0.1),
    (0.8, 0.2, -2.5, 8.0, 1.2, 0.0),
];

/// Falling Bricks as the accuracy runners build it: a [`closed_box`] 10 m x 10 m inside with
/// 0.5 m walls, and six differently sized bricks (0.3-2 m, restitution 0-0.3) placed at
/// 3-8.5 m and different angles. Returns the bricks' ids. (The benchmark's `falling_bricks`
/// is the original app's 8 m x 6 m box, see [`benchmark_setups`].)
pub fn falling_bricks(world: &mut World) -> Result<Vec<BodyId>, PhysicsError> {
    closed_box(world, 10.0, 10.0, 0.5)?;
    BRICKS
        .iter()
        .map(|&(width, height, x, y, angle, restitution)| {
            world.add_body(
                &BodyDef::dynamic(Shape::rect(width, height), Vec2::new(x, y))
                    .with_angle(angle)
                    .with_restitution(restitution),
            )
        })
        .collect()
}

/// A regular polygon of `n` vertices on a circle of radius `r` (m), centred on its centroid;
/// a square of side `r` if the engine refuses it (it does not for 3 <= n <= 8 and r > 0).
fn regular_polygon(n: usize, r: Real) -> Shape {
    let points: Vec<Vec2> = (0..n)
        .map(|k| {
            let a = k as Real * 2.0 * PI / n as Real;
            Vec2::new(r * a.cos(), r * a.sin())
        })
        .collect();
    match Polygon::new(&points) {
        Ok((p, _)) => Shape::from(p),
        Err(_) => Shape::rect(r, r),
    }
}

/// The `i`-th body of the accuracy runners' mixed pile: the five shape kinds in turn, about
/// 0.6-0.9 m across (circle, capsule, triangle, hexagon, box), each scaled by a fixed
/// pseudo-random factor between 0.8 and 1.2 picked by `i`.
pub fn mixed_shape(i: usize) -> Shape {
    let scale = 0.8 + 0.4 * ((i * 37) % 11) as Real / 10.0;
    match i % 5 {
        0 => Shape::circle(0.35 * scale),
        1 => Shape::capsule(0.9 * scale, 0.2 * scale),
        2 => regular_polygon(3, 0.45 * scale),
        3 => regular_polygon(6, 0.4 * scale),
        _ => Shape::rect(0.6 * scale, 0.6 * scale),
    }
}

/// A benchmark scene as plain body definitions, so that any engine can build it (the rapier2d
/// comparison in `benchmarks/vs-peers` (Box2D v3 and rapier2d) builds the same list).
#[derive(Clone, Debug)]
pub struct Setup {
    /// Scene name, e.g. `large_pyramid`.
    pub name: &'static str,
    /// Gravity (m/s^2).
    pub gravity: Vec2,
    /// Every body, static ones included.
    pub bodies: Vec<BodyDef>,
    /// Steps to run at dt = 1/60 s.
    pub steps: usize,
    /// Whether bodies may sleep.
    pub sleep: bool,
    /// Steps to run before timing starts (0 = time from the first step).
    pub warm_up: usize,
    /// Revolute joints between the bodies.
    pub joints: Vec<SetupJoint>,
    /// A kinematic body aimed at a pose on a path before each step, if any.
    pub driver: Option<SetupDriver>,
    /// What to put in before step `k` (0 the first), if the scene adds bodies as it runs.
    pub spawner: Option<fn(usize) -> Vec<SetupSpawn>>,
}

/// Bodies, and joints between them, that a [`Setup`] puts in before a step, in place of what
/// an earlier spawn put in the same group (Box2D's `rain` drops ragdolls, and once its columns
/// are full takes a column's away and drops it again).
#[derive(Clone, Debug)]
pub struct SetupSpawn {
    /// The group it fills (an index from 0); whatever the group held goes first.
    pub group: usize,
    /// The bodies.
    pub bodies: Vec<BodyDef>,
    /// Joints between them: body indices into `bodies` (A None: the world).
    pub joints: Vec<SetupJoint>,
}

/// What a [`Setup`]'s spawns have put in a World: each group's bodies (their joints go with
/// them).
#[derive(Clone, Debug, Default)]
pub struct Spawned {
    groups: Vec<Vec<BodyId>>,
}

/// A kinematic body of a [`Setup`] aimed, before each step, at the pose its path gives for the
/// end of the step (Box2D's step functions call `b2Body_SetTargetTransform` alike).
#[derive(Clone, Copy, Debug)]
pub struct SetupDriver {
    /// Index of the kinematic body in `bodies`.
    pub body: usize,
    /// Its origin (m) and angle (rad) at time t (s) from the start.
    pub path: fn(Real) -> (Vec2, Real),
}

impl SetupDriver {
    /// The pose to reach by the end of step `k` (0 the first) at dt = 1/60 s.
    pub fn target(&self, k: usize) -> (Vec2, Real) {
        (self.path)((k + 1) as Real / 60.0)
    }
}

/// A revolute joint of a [`Setup`]: bodies by index into `bodies` (A None: the world, a
/// static body without shapes at the origin in engines that need one), anchors in each body's
/// frame from its origin (m), and an optional motor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SetupJoint {
    /// Index of body A, or None for the world.
    pub a: Option<usize>,
    /// Index of body B.
    pub b: usize,
    /// A's anchor, in A's frame (m).
    pub anchor_a: Vec2,
    /// B's anchor, in B's frame (m).
    pub anchor_b: Vec2,
    /// A motor: its speed (rad/s) and its largest torque (N m).
    pub motor: Option<(Real, Real)>,
    /// Limits on B's angle relative to A's, from the angle they were made at: lower, upper (rad).
    pub limit: Option<(Real, Real)>,
    /// A spring toward the angle they were made at: frequency (Hz), damping ratio.
    pub spring: Option<(Real, Real)>,
}

impl SetupJoint {
    /// A free hinge from A (None: the world) to B at the given anchors.
    pub fn hinge(a: Option<usize>, b: usize, anchor_a: Vec2, anchor_b: Vec2) -> SetupJoint {
        SetupJoint {
            a,
            b,
            anchor_a,
            anchor_b,
            motor: None,
            limit: None,
            spring: None,
        }
    }

    /// The engine's joint, bodies by their ids in `ids`.
    fn to_def(self, ids: &[BodyId]) -> JointDef {
        let hinge = JointKind::Revolute(Revolute {
            motor: self.motor.map(|(speed, max)| Motor { speed, max }),
            limit: self.limit.map(|(lower, upper)| Limit { lower, upper }),
            spring: self.spring.map(|(hertz, damping_ratio)| Spring {
                hertz,
                damping_ratio,
            }),
            ..Revolute::free()
        });
        JointDef::new(hinge, self.a.map(|a| ids[a]), ids[self.b])
            .with_anchors(self.anchor_a, self.anchor_b)
    }
}

impl Setup {
    /// Step a World built by [`Setup::build`] once at 1/60 s, the driver (if any) aimed
    /// first; `k` is the step's index from 0.
    pub fn step(
        &self,
        world: &mut World,
        spawned: &mut Spawned,
        k: usize,
    ) -> Result<(), PhysicsError> {
        const DT: Real = 1.0 / 60.0;
        for spawn in self.spawner.map_or_else(Vec::new, |spawner| spawner(k)) {
            if spawn.group >= spawned.groups.len() {
                spawned.groups.resize(spawn.group + 1, Vec::new());
            }
            let group = &mut spawned.groups[spawn.group];
            world.remove_bodies(group)?;
            *group = add_all(world, &spawn.bodies, &spawn.joints)?;
        }
        if let Some(driver) = &self.driver {
            // A World built from the set-up holds body i in slot i, never reused.
            let id = world
                .live_id(driver.body as u32, 0)
                .expect("Setup::step steps a World built by Setup::build");
            let (position, angle) = driver.target(k);
            world.set_target_transform(id, position, angle, DT)?;
        }
        world.step(DT)
    }

    /// A World with this scene, the default (soft-step) settings and the scene's sleep flag.
    pub fn build(&self) -> Result<World, PhysicsError> {
        self.build_with(Default::default())
    }

    /// A World with this scene (bodies, then joints) and `settings`, their sleep flag
    /// replaced by the scene's.
    pub fn build_with(&self, settings: crate::physics::Settings) -> Result<World, PhysicsError> {
        let settings = crate::physics::Settings {
            enable_sleep: self.sleep,
            ..settings
        };
        let mut world = World::new(settings, self.gravity)?;
        add_all(&mut world, &self.bodies, &self.joints)?;
        Ok(world)
    }
}

/// Add `bodies`, then `joints` between them; their ids.
fn add_all(
    world: &mut World,
    bodies: &[BodyDef],
    joints: &[SetupJoint],
) -> Result<Vec<BodyId>, PhysicsError> {
    let ids = bodies
        .iter()
        .map(|def| world.add_body(def))
        .collect::<Result<Vec<_>, _>>()?;
    for j in joints {
        world.add_joint(&j.to_def(&ids))?;
    }
    Ok(ids)
}

/// A scene as Box2D's `benchmarks.c` runs it: gravity 10 m/s^2 down, sleep on, timed from the
/// first step, no joints and no driver (a scene that differs says so over the result).
fn box2d_scene(name: &'static str, bodies: Vec<BodyDef>, steps: usize) -> Setup {
    Setup {
        name,
        gravity: Vec2::new(0.0, -10.0),
        bodies,
        steps,
        sleep: true,
        warm_up: 0,
        joints: Vec::new(),
        driver: None,
        spawner: None,
    }
}

fn boxes_pyramid(base: usize, x: Real, y0: Real, out: &mut Vec<BodyDef>) {
    for row in 0..base {
        let count = base - row;
        let y = y0 + 0.5 + row as Real;
        let x0 = x - 0.5 * (count as Real - 1.0);
        for j in 0..count {
            out.push(
                BodyDef::dynamic(Shape::rect(1.0, 1.0), Vec2::new(x0 + j as Real, y))
                    .with_friction(0.6),
            );
        }
    }
}

/// The benchmark scenes, defined as in Box2D v3's public benchmark (dt 1/60):
/// - `large_pyramid`: ground 200 m x 2 m (top at y = 0), pyramid of base 100 (5,050 boxes of 1 m,
///   density 1, friction 0.6), 500 steps, sleep off;
/// - `pyramid_20`: the same with base 20 (210 boxes), 500 steps, sleep off;
/// - `falling_bricks`: the original app: a closed 8 m x 6 m box and six bricks, 600 steps, sleep off;
/// - `many_boxes`: 2,000 boxes of 0.5 m rained from a 40 x 50 grid into a 40 m wide container, 500 steps, sleep off;
/// - `resting_pyramid`: `pyramid_20` with sleep on, timed after 300 steps of settling;
/// - `mixed_shapes`: 1,200 bodies cycling through circle, capsule, box, triangle and hexagon
///   (see [`mixed_shapes`]) dropped from a 40 x 30 grid into a 50 m wide container, 500 steps,
///   sleep off;
/// - `joint_grid`: Box2D's benchmark of that name ([`joint_grid`]), 500 steps, sleep off;
/// - `smash`: Box2D's benchmark of that name ([`smash`]), 300 steps, sleep on;
/// - `tumbler` and `compounds`: Box2D's benchmarks of those names ([`tumbler`],
///   [`compounds`]), bodies of several shapes;
/// - `many_pyramids` and `spinner`: Box2D's benchmarks of those names ([`many_pyramids`],
///   [`spinner`]).
pub fn benchmark_setups() -> Vec<Setup> {
    let g = Vec2::new(0.0, -10.0);
    let ground = |width: Real| BodyDef::fixed(Shape::rect(width, 2.0), Vec2::new(0.0, -1.0));

    let mut large = vec![ground(200.0)];
    boxes_pyramid(100, 0.0, 0.0, &mut large);
    let mut small = vec![ground(200.0)];
    boxes_pyramid(20, 0.0, 0.0, &mut small);

    let mut bricks = closed_box_defs(8.0, 6.0, 0.5);
    for (i, (w, h, x, y, angle)) in [
        (1.6, 0.4, -2.0, 4.5, 0.3),
        (1.2, 0.6, 1.5, 5.0, -0.2),
        (0.8, 0.4, 0.0, 3.5, 0.8),
        (1.0, 0.5, -1.0, 2.0, 0.1),
        (0.6, 0.3, 2.5, 2.5, 1.2),
        (1.4, 0.5, 0.5, 1.0, -0.5),
    ]
    .into_iter()
    .enumerate()
    {
        let restitution = if i % 3 == 0 { 0.2 } else { 0.0 };
        bricks.push(
            BodyDef::dynamic(Shape::rect(w, h), Vec2::new(x, y))
                .with_angle(angle)
                .with_friction(0.6)
                .with_restitution(restitution),
        );
    }

    let mut many = closed_box_defs(40.0, 80.0, 1.0);
    for i in 0..2000 {
        let (col, row) = (i % 40, i / 40);
        let x = -19.5 + col as Real + 0.1 * ((row % 3) as Real - 1.0);
        let y = 20.0 + row as Real;
        many.push(BodyDef::dynamic(Shape::rect(0.5, 0.5), Vec2::new(x, y)).with_friction(0.6));
    }

    vec![
        Setup {
            name: "large_pyramid",
            gravity: g,
            bodies: large,
            steps: 500,
            sleep: false,
            warm_up: 0,
            driver: None,
            spawner: None,
            joints: Vec::new(),
        },
        Setup {
            name: "pyramid_20",
            gravity: g,
            bodies: small.clone(),
            steps: 500,
            sleep: false,
            warm_up: 0,
            driver: None,
            spawner: None,
            joints: Vec::new(),
        },
        Setup {
            name: "falling_bricks",
            gravity: g,
            bodies: bricks,
            steps: 600,
            sleep: false,
            warm_up: 0,
            driver: None,
            spawner: None,
            joints: Vec::new(),
        },
        Setup {
            name: "many_boxes",
            gravity: g,
            bodies: many,
            steps: 500,
            sleep: false,
            warm_up: 0,
            driver: None,
            spawner: None,
            joints: Vec::new(),
        },
        Setup {
            name: "resting_pyramid",
            gravity: g,
            bodies: small,
            steps: 300,
            sleep: true,
            warm_up: 300,
            driver: None,
            spawner: None,
            joints: Vec::new(),
        },
        joint_grid(100),
        smash(),
        tumbler(),
        compounds(),
        many_pyramids(),
        spinner(),
        washer(),
        junkyard(),
        rain(),
        Setup {
            name: "mixed_shapes",
            gravity: g,
            bodies: mixed_shapes(),
            steps: 500,
            sleep: false,
            warm_up: 0,
            driver: None,
            spawner: None,
            joints: Vec::new(),
        },
    ]
}

/// Box2D v3's `joint_grid` benchmark (`shared/benchmarks.c`) with `n` bodies a side: discs of
/// radius 0.4 m (density 1) on a 1 m grid, column k at x = k and row i at y = -i, each joined to
/// the one above and the one to its left by a revolute joint at the midpoint between them; the
/// top discs of the 7 middle columns are static, so the grid hangs from them. The discs are in
/// category 2 with a mask without it: they never collide with each other. Gravity 10 m/s^2,
/// 500 steps, sleep off. The 6 joints between two static discs that Box2D's makes are left
/// out (they join nothing that moves).
pub fn joint_grid(n: usize) -> Setup {
    let filter = Filter {
        category: 2,
        mask: !2,
        group: 0,
    };
    let mut bodies = Vec::with_capacity(n * n);
    let mut joints = Vec::with_capacity(2 * n * n);
    let anchored = |k: usize, i: usize| i == 0 && k + 3 >= n / 2 && k <= n / 2 + 3;
    for k in 0..n {
        for i in 0..n {
            let at = Vec2::new(k as Real, -(i as Real));
            let disc = Shape::circle(0.4);
            let def = if anchored(k, i) {
                BodyDef::fixed(disc, at)
            } else {
                BodyDef::dynamic(disc, at)
            };
            let index = bodies.len();
            bodies.push(def.with_filter(filter));
            if i > 0 {
                joints.push(SetupJoint::hinge(
                    Some(index - 1),
                    index,
                    Vec2::new(0.0, -0.5),
                    Vec2::new(0.0, 0.5),
                ));
            }
            // (Box2D also joins the static discs to each other; tiltbox refuses a joint with
            // no dynamic body, and such a joint does nothing.)
            if k > 0 && !(anchored(k, i) && anchored(k - 1, i)) {
                joints.push(SetupJoint::hinge(
                    Some(index - n),
                    index,
                    Vec2::new(0.5, 0.0),
                    Vec2::new(-0.5, 0.0),
                ));
            }
        }
    }
    Setup {
        sleep: false,
        joints,
        ..box2d_scene("joint_grid", bodies, 500)
    }
}

/// Box2D v3's `smash` benchmark (`shared/benchmarks.c`): no gravity; an 8 m square of density
/// 8 (512 kg) at x = -20 m moving at 40 m/s into a block of 120 x 80 boxes of 0.4 m (density 1,
/// 0.16 kg) side by side from x = 30 m, centred on y = 0; 300 steps, sleep on. The boxes
/// start asleep, as Box2D's do (`isAwake = false`). In Box2D each is an island of its own,
/// woken a layer a step as the square (arriving after 1.15 s) drives in; in tiltbox the
/// block, all touching, is one island that the square wakes whole.
pub fn smash() -> Setup {
    let mut bodies = Vec::with_capacity(1 + 120 * 80);
    let hammer = BodyDef::dynamic(Shape::rect(8.0, 8.0), Vec2::new(-20.0, 0.0))
        .with_density(8.0)
        .with_velocity(Vec2::new(40.0, 0.0));
    bodies.push(hammer);
    let d = 0.4;
    for i in 0..120 {
        for j in 0..80 {
            let at = Vec2::new(i as Real * d + 30.0, (j as Real - 40.0) * d);
            bodies.push(BodyDef::dynamic(Shape::rect(d, d), at).with_awake(false));
        }
    }
    Setup {
        gravity: Vec2::ZERO,
        ..box2d_scene("smash", bodies, 300)
    }
}

/// Box2D v3's `tumbler` benchmark (`shared/benchmarks.c`): a drum of four walls (boxes 1 m x
/// 20 m and 20 m x 1 m, 10 m out from its centre; density 50, so 4,000 kg) hinged to the
/// world at (0, 10) m and turned by a revolute motor at 25 degrees/s with up to 1e8 N m, and
/// 45 x 45 boxes of 0.25 m (density 1, 0.0625 kg) on a 0.4 m grid inside it. Gravity 10 m/s^2,
/// 750 steps, sleep on. tiltbox's own shape sits at a body's origin, so the drum's origin is
/// its right wall's centre and the other walls are its parts; its centre of mass, and what it
/// turns about, is the drum's centre all the same.
pub fn tumbler() -> Setup {
    let wall =
        |x: Real, y: Real, w: Real, h: Real| PartDef::new(Shape::rect(w, h), Vec2::new(x, y));
    let drum = BodyDef::dynamic(Shape::rect(1.0, 20.0), Vec2::new(10.0, 10.0))
        .with_density(50.0)
        .with_part(wall(-20.0, 0.0, 1.0, 20.0).with_density(50.0))
        .with_part(wall(-10.0, 10.0, 20.0, 1.0).with_density(50.0))
        .with_part(wall(-10.0, -10.0, 20.0, 1.0).with_density(50.0));
    let mut bodies = vec![drum];
    let n = 45;
    for i in 0..n {
        for j in 0..n {
            let at = Vec2::new(
                -0.2 * n as Real + 0.4 * j as Real,
                10.0 - 0.2 * n as Real + 0.4 * i as Real,
            );
            bodies.push(BodyDef::dynamic(Shape::rect(0.25, 0.25), at));
        }
    }
    Setup {
        joints: vec![SetupJoint {
            motor: Some((25.0 * PI / 180.0, 1e8)),
            ..SetupJoint::hinge(None, 0, Vec2::new(0.0, 10.0), Vec2::new(-10.0, 0.0))
        }],
        ..box2d_scene("tumbler", bodies, 750)
    }
}

/// Box2D v3's `many_pyramids` benchmark (`shared/benchmarks.c`): 20 rows of 20 pyramids of
/// base 10 (55 boxes of 1 m each, density 1, friction 0.6: 22,000 boxes), each row on its own
/// ground segment 220 m long, the rows 11 m apart; the pyramids 11 m apart along a row.
/// Gravity 10 m/s^2, 200 steps, sleep off. The ground is one static body of 20 segments, as
/// Box2D's.
pub fn many_pyramids() -> Setup {
    let (base, extent, rows, columns) = (10, 0.5 as Real, 20, 20);
    let row_gap = 2.0 * extent * (base as Real + 1.0);
    let width = 2.0 * extent * columns as Real * (base as Real + 1.0);
    let segment = |y: Real| {
        let s = crate::physics::Segment::new(
            Vec2::new(-0.5 * width, y),
            Vec2::new(0.5 * width, y),
            0.0,
        );
        Shape::Segment(Box::new(s))
    };
    let mut ground = BodyDef::fixed(segment(0.0), Vec2::ZERO);
    for i in 1..rows {
        ground
            .parts
            .push(PartDef::new(segment(i as Real * row_gap), Vec2::ZERO));
    }
    let mut bodies = vec![ground];
    let base_width = 2.0 * extent * base as Real;
    for i in 0..rows {
        let base_y = i as Real * row_gap;
        for j in 0..columns {
            let centre_x = -0.5 * width + j as Real * (base_width + 2.0 * extent) + 2.0 * extent;
            for level in 0..base {
                let y = (2.0 * level as Real + 1.0) * extent + base_y;
                for k in level..base {
                    let x = (level as Real + 1.0) * extent
                        + 2.0 * (k - level) as Real * extent
                        + centre_x
                        - 0.5;
                    bodies.push(
                        BodyDef::dynamic(Shape::rect(2.0 * extent, 2.0 * extent), Vec2::new(x, y))
                            .with_friction(0.6),
                    );
                }
            }
        }
    }
    Setup {
        sleep: false,
        ..box2d_scene("many_pyramids", bodies, 200)
    }
}

/// Box2D v3's `spinner` benchmark (`shared/benchmarks.c`): a loop of 360 chain pieces of
/// radius 40 m centred 32 m up (friction 0.1); a paddle hinged to the world at (0, 12) and
/// driven at 5 rad/s by a motor of torque up to `f32::MAX`, as Box2D's (its paddle is a 0.8 x
/// 40 m box rounded by 0.2 m; tiltbox has no rounded polygon, so this one is 1.2 x 40.4 m with
/// square corners; friction 0); and 6,076 capsules (1 m end to end, radius 0.25), discs
/// (radius 0.35) and squares (0.7 m) in turn (density 0.25, friction 0.1, restitution 0.1) on a
/// 0.5 m grid from (-23, 2). Gravity 10 m/s^2, 500 steps, sleep on (the paddle never rests).
/// The ring's pieces are separate static bodies here (tiltbox's chains are), one chain body in
/// Box2D.
pub fn spinner() -> Setup {
    let ring: Vec<Vec2> = (0..360)
        .map(|i| {
            let a = -2.0 * PI * i as Real / 360.0;
            Vec2::new(40.0 * a.cos(), 32.0 + 40.0 * a.sin())
        })
        .collect();
    let mut bodies: Vec<BodyDef> = BodyDef::chain(&ring, true, false)
        .expect("a valid ring")
        .into_iter()
        .map(|piece| piece.with_friction(0.1))
        .collect();
    let paddle = bodies.len();
    bodies.push(BodyDef::dynamic(Shape::rect(1.2, 40.4), Vec2::new(0.0, 12.0)).with_friction(0.0));
    let kinds = [
        Shape::capsule(1.0, 0.25),
        Shape::circle(0.35),
        Shape::rect(0.7, 0.7),
    ];
    let (mut x, mut y) = (-23.0 as Real, 2.0 as Real);
    for i in 0..2 * 3038 {
        bodies.push(
            BodyDef::dynamic(kinds[i % 3].clone(), Vec2::new(x, y))
                .with_density(0.25)
                .with_friction(0.1)
                .with_restitution(0.1),
        );
        x += 0.5;
        if x >= 23.0 {
            (x, y) = (-23.0, y + 0.5);
        }
    }
    Setup {
        joints: vec![SetupJoint {
            motor: Some((5.0, f32::MAX as Real)),
            ..SetupJoint::hinge(None, paddle, Vec2::new(0.0, 12.0), Vec2::ZERO)
        }],
        ..box2d_scene("spinner", bodies, 500)
    }
}

/// Box2D v3's `washer` benchmark (`shared/benchmarks.c`): a kinematic drum at (0, 10) turning
/// at 25 deg/s (and drifting at (0.001, -0.002) m/s, as Box2D's), of 40 quadrilaterals: 36
/// round its rim from radius 16 m to 18 m, each 10 degrees wide and overlapping its
/// neighbours by 1 degree on each side, and 4 paddles from 14 m to 16 m at 0, 90, 180 and 270
/// degrees; inside, 90 x 90 boxes of 0.2 m (density 1, friction 0.6) 0.21 m apart from
/// (-9.9, 0.1), each reporting its hits. Gravity 10 m/s^2, 500 steps, sleep on. A tiltbox
/// body's own shape is centred on its origin (a segment: given from it), and a kinematic body
/// turns about its origin; so that the drum turns about its centre as Box2D's does, its own
/// shape is a 20 cm segment given from the centre but buried 1 m deep inside the first rim
/// quadrilateral (no box reaches it), the 40 quadrilaterals its parts. The peers get the same
/// segment.
pub fn washer() -> Setup {
    let deg = PI / 180.0;
    let turn =
        |v: Vec2, a: Real| Vec2::new(v.x * a.cos() - v.y * a.sin(), v.x * a.sin() + v.y * a.cos());
    let quad = |points: [Vec2; 4]| {
        let (polygon, centre) = Polygon::new(&points).expect("a valid quadrilateral");
        PartDef::new(Shape::Polygon(Box::new(polygon)), centre)
    };
    let buried = crate::physics::Segment::new(Vec2::new(16.9, 1.0), Vec2::new(17.1, 1.0), 0.0);
    let mut drum = BodyDef::kinematic(
        Shape::Segment(Box::new(buried)),
        Vec2::new(0.0, 10.0),
        Vec2::new(0.001, -0.002),
    )
    .with_angular_velocity(25.0 * deg);
    let (r0, r1, r2) = (14.0, 16.0, 18.0);
    for i in 0..36 {
        let (u1, u2) = (
            turn(Vec2::X, 10.0 * deg * i as Real),
            turn(Vec2::X, 10.0 * deg * (i + 1) as Real),
        );
        let (a1, a2) = (turn(u1, -deg), turn(u2, deg));
        drum = drum.with_part(quad([a1 * r1, a1 * r2, a2 * r2, a2 * r1]));
        if i % 9 == 0 {
            drum = drum.with_part(quad([u1 * r0, u1 * r1, u2 * r1, u2 * r0]));
        }
    }
    let hits = crate::physics::ShapeFlags {
        hit_events: true,
        ..crate::physics::ShapeFlags::NONE
    };
    let (n, a) = (90, 0.1 as Real);
    let mut bodies = vec![drum];
    for i in 0..n {
        for j in 0..n {
            let x = -1.1 * a * n as Real + 2.1 * a * j as Real;
            let y = -1.1 * a * n as Real + 10.0 + 2.1 * a * i as Real;
            bodies.push(
                BodyDef::dynamic(Shape::rect(2.0 * a, 2.0 * a), Vec2::new(x, y)).with_flags(hits),
            );
        }
    }
    box2d_scene("washer", bodies, 500)
}

/// A pile for measuring how the step's cost grows with the body count: `n` boxes of 1 m in 20
/// rows (as deep at every size, so that every size runs the same stiffness tier), side by side
/// (one island, braced), each row 1 mm above the one below, on a ground as wide, between two
/// walls.
/// Sleep off (every body awake), 120 steps of warm-up, gravity 10 m/s^2.
pub fn pile(n: usize) -> Setup {
    const ROWS: usize = 20;
    let columns = n.div_ceil(ROWS);
    let width = columns as Real;
    let x0 = -0.5 * width + 0.5;
    let mut bodies = vec![
        BodyDef::fixed(Shape::rect(width + 4.0, 2.0), Vec2::new(0.0, -1.0)),
        BodyDef::fixed(Shape::rect(1.0, 30.0), Vec2::new(-0.5 * width - 0.5, 15.0)),
        BodyDef::fixed(Shape::rect(1.0, 30.0), Vec2::new(0.5 * width + 0.5, 15.0)),
    ];
    bodies.extend((0..n).map(|i| {
        let (column, row) = (i / ROWS, i % ROWS);
        let at = Vec2::new(x0 + column as Real, 0.5 + 1.001 * row as Real);
        BodyDef::dynamic(Shape::rect(1.0, 1.0), at)
    }));
    Setup {
        sleep: false,
        warm_up: 120,
        ..box2d_scene("pile", bodies, 100)
    }
}

/// A field of sensors over a resting pile, for measuring what sensors cost: 4,000 discs of
/// 0.45 m radius on a grid 1 m apart in 41 rows, in a box 102 m wide, and `n` static sensor
/// boxes of 2 m spread evenly across it at seven heights from 5 m to 29 m. Sleep on: the pile
/// falls asleep while the sensors go on querying. 60 steps of warm-up, gravity 10 m/s^2.
pub fn sensor_field(n: usize) -> Setup {
    let mut bodies = vec![
        BodyDef::fixed(Shape::rect(104.0, 2.0), Vec2::new(0.0, -1.0)),
        BodyDef::fixed(Shape::rect(2.0, 80.0), Vec2::new(-51.0, 40.0)),
        BodyDef::fixed(Shape::rect(2.0, 80.0), Vec2::new(51.0, 40.0)),
    ];
    bodies.extend((0..4000).map(|i| {
        let at = Vec2::new(-49.0 + (i % 98) as Real, 0.5 + 1.05 * (i / 98) as Real);
        BodyDef::dynamic(Shape::circle(0.45), at)
    }));
    let sensor = crate::physics::events::ShapeFlags {
        sensor: true,
        ..crate::physics::events::ShapeFlags::NONE
    };
    bodies.extend((0..n).map(|i| {
        let x = -49.0 + 98.0 * (i as Real + 0.5) / n as Real;
        let at = Vec2::new(x, 5.0 + 4.0 * (i % 7) as Real);
        BodyDef::fixed(Shape::rect(2.0, 2.0), at).with_flags(sensor)
    }));
    Setup {
        warm_up: 60,
        ..box2d_scene("sensor_field", bodies, 200)
    }
}

/// Box2D v3's `junkyard` benchmark (`shared/benchmarks.c`): a static ground of one body and
/// 261 boxes (a floor of 161 boxes 1.1 m x 1 m from x = -80 m to 80 m at y = 0, two walls of
/// 50 boxes 1 m x 1.1 m at x = +-80 m from y = 1 m), 200 x 40 pentagons of radius 0.25 m
/// (Box2D's Fibonacci points, density 1, friction 0.6) in columns 0.75 m apart from x = -75 m,
/// rows 1 m apart from y = 15 m, shifted -0.1 and +0.1 m in turn, and a kinematic pusher, a
/// 4 m x 8 m box standing on the floor, driven along x to 60 sin(0.2 t) m. Gravity 10 m/s^2,
/// 800 steps, sleep on. Box2D's pusher has its origin at the floor, its box 4 m above it;
/// here its origin is the box's centre, and its path is lifted 4 m to match.
pub fn junkyard() -> Setup {
    let mut ground = BodyDef::fixed(Shape::rect(1.1, 1.0), Vec2::new(-80.0, 0.0));
    let offset = |x: Real, y: Real| Vec2::new(x + 80.0, y);
    for i in 1..161 {
        let at = offset(-80.0 + i as Real, 0.0);
        ground.parts.push(PartDef::new(Shape::rect(1.1, 1.0), at));
    }
    for side in [-80.0, 80.0] {
        for j in 0..50 {
            let at = offset(side, 1.0 + j as Real);
            ground.parts.push(PartDef::new(Shape::rect(1.0, 1.1), at));
        }
    }
    let radius = 0.25;
    let phi = PI * ((5.0 as Real).sqrt() - 1.0);
    let points: Vec<Vec2> = (0..5)
        .map(|i| {
            let theta = phi * i as Real;
            Vec2::new(radius * theta.cos(), radius * theta.sin())
        })
        .collect();
    let pentagon = convex_hull(&points);
    let mut bodies = vec![ground];
    let mut side = -0.1;
    for i in 0..200 {
        let x = 1.5 * (2.0 * i as Real - 200.0) * radius;
        for j in 0..40 {
            let y = 4.0 * j as Real * radius + 15.0;
            // Box2D's hull is centred on the points' origin; tiltbox's polygon on its centroid.
            let (polygon, centroid) = Polygon::new(&pentagon).expect("a valid pentagon");
            let at = Vec2::new(x + side, y) + centroid;
            bodies.push(BodyDef::dynamic(Shape::Polygon(Box::new(polygon)), at));
            side = -side;
        }
    }
    let pusher = bodies.len();
    bodies.push(BodyDef::kinematic(
        Shape::rect(4.0, 8.0),
        Vec2::new(0.0, 4.0),
        Vec2::ZERO,
    ));
    Setup {
        driver: Some(SetupDriver {
            body: pusher,
            path: |t| (Vec2::new(60.0 * (0.2 * t).sin(), 4.0), 0.0),
        }),
        ..box2d_scene("junkyard", bodies, 800)
    }
}

/// The convex hull of `points`, counter-clockwise (gift wrapping: a handful of points).
fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    let start = (0..points.len())
        .min_by(|&i, &j| points[i].x.total_cmp(&points[j].x))
        .expect("points");
    let mut hull = vec![points[start]];
    let mut at = start;
    loop {
        let mut next = (at + 1) % points.len();
        for k in 0..points.len() {
            let (a, b) = (points[next] - points[at], points[k] - points[at]);
            if a.x * b.y - a.y * b.x < 0.0 {
                next = k;
            }
        }
        if next == start {
            return hull;
        }
        hull.push(points[next]);
        at = next;
    }
}

/// Box2D v3's `compounds` benchmark (`shared/benchmarks.c`): a static ground of one body and
/// 282 shapes (a floor of 81 boxes 1.1 m x 1 m from x = -40 m to 40 m, two walls of 100 boxes 1
/// m x 1.1 m at x = +-40 m, and a segment at y = -80 m from x = -800 m to 800 m), and 20
/// columns of 150 bodies of two triangles each ((-1, 0), (0.5, 1), (0, 2) and its mirror image;
/// density 1, friction 0.5) 2 m apart sideways and 2.25 m up from y = 5.575 m, shifted
/// +-0.25 m in turn. Gravity 10 m/s^2, 500 steps, sleep on. The ground's origin is its first
/// floor box's centre; a compound's is its left triangle's centroid, the right one a part.
pub fn compounds() -> Setup {
    let mut ground = BodyDef::fixed(Shape::rect(1.1, 1.0), Vec2::new(-40.0, 0.0));
    let box_at = |w: Real, h: Real, x: Real, y: Real| {
        PartDef::new(Shape::rect(w, h), Vec2::new(x + 40.0, y))
    };
    for i in 1..81 {
        ground.parts.push(box_at(1.1, 1.0, -40.0 + i as Real, 0.0));
    }
    for x in [-40.0, 40.0] {
        for i in 0..100 {
            ground.parts.push(box_at(1.0, 1.1, x, 1.0 + i as Real));
        }
    }
    let segment =
        crate::physics::Segment::new(Vec2::new(-760.0, -80.0), Vec2::new(840.0, -80.0), 0.0);
    ground
        .parts
        .push(PartDef::new(Shape::Segment(Box::new(segment)), Vec2::ZERO));
    let triangle = |points: [Vec2; 3]| match Polygon::new(&points) {
        Ok((p, centroid)) => (Shape::from(p), centroid),
        Err(e) => panic!("compounds: a built-in triangle was refused: {e}"),
    };
    let v = Vec2::new;
    let (left, cl) = triangle([v(-1.0, 0.0), v(0.5, 1.0), v(0.0, 2.0)]);
    let (right, cr) = triangle([v(1.0, 0.0), v(0.0, 2.0), v(-0.5, 1.0)]);
    let mut bodies = vec![ground];
    let (columns, rows) = (20, 150);
    let (shift, extra_y, y_start) = (2.0 as Real, 0.25 as Real, 5.0 as Real);
    let (centre_x, centre_y) = (shift * columns as Real / 2.0 - 1.0, 1.15 / 2.0);
    let mut side: Real = 0.25;
    for i in 0..columns {
        let x = i as Real * shift - centre_x;
        for j in 0..rows {
            let y = j as Real * (shift + extra_y) + centre_y + y_start;
            let at = v(x + side, y);
            side = -side;
            bodies.push(
                BodyDef::dynamic(left.clone(), at + cl)
                    .with_friction(0.5)
                    .with_part(PartDef::new(right.clone(), cr - cl).with_friction(0.5)),
            );
        }
    }
    box2d_scene("compounds", bodies, 500)
}

/// The five shapes of `mixed_shapes`, all between 0.7 m and 1 m across (areas 0.35 to 0.49
/// m^2): a circle of radius 0.35, a capsule 1 m long and 0.5 m thick, a 0.7 m box, an
/// equilateral triangle of side 0.9 and a regular hexagon of circumradius 0.4. The polygons
/// are centred on their centroids, so a body's position is its centre of mass.
pub fn mixed_shape_kinds() -> [Shape; 5] {
    let triangle = [
        Vec2::new(0.0, 0.0),
        Vec2::new(0.9, 0.0),
        Vec2::new(0.45, 0.45 * (3.0 as Real).sqrt()),
    ];
    let hexagon: Vec<Vec2> = (0..6)
        .map(|k| {
            let a = k as Real * (std::f64::consts::FRAC_PI_3 as Real);
            Vec2::new(0.4 * a.cos(), 0.4 * a.sin())
        })
        .collect();
    let polygon = |points: &[Vec2]| match Polygon::new(points) {
        Ok((p, _centroid)) => Shape::from(p),
        Err(e) => panic!("mixed_shapes: a built-in polygon was refused: {e}"),
    };
    [
        Shape::circle(0.35),
        Shape::capsule(1.0, 0.25),
        Shape::rect(0.7, 0.7),
        polygon(&triangle),
        polygon(&hexagon),
    ]
}

/// The `mixed_shapes` scene: a closed container 50 m x 80 m inside (walls 1 m thick, floor top at
/// y = 0) and 1,200 dynamic bodies (density 1, friction 0.6, restitution 0) on a 40 x 30 grid
/// 1.2 m apart, rows from y = 20 m up, cycling through [`mixed_shape_kinds`] (kind (column + 2
/// row) mod 5, so no column holds a single kind), each turned by 0.15 ((7 column + 3 row) mod
/// 9 - 4) rad and the rows shifted sideways by -0.1, 0 and 0.1 m in turn so that they do not
/// land in columns. Computed from the indices alone: the same scene on every run.
pub fn mixed_shapes() -> Vec<BodyDef> {
    let kinds = mixed_shape_kinds();
    let (columns, rows, spacing) = (40usize, 30usize, 1.2 as Real);
    let mut bodies = closed_box_defs(50.0, 80.0, 1.0);
    for row in 0..rows {
        for col in 0..columns {
            let shape = kinds[(col + 2 * row) % kinds.len()].clone();
            let x = spacing * (col as Real - 0.5 * (columns as Real - 1.0))
                + 0.1 * ((row % 3) as Real - 1.0);
            let y = 20.0 + spacing * row as Real;
            let angle = 0.15 * (((col * 7 + row * 3) % 9) as Real - 4.0);
            bodies.push(
                BodyDef::dynamic(shape, Vec2::new(x, y))
                    .with_angle(angle)
                    .with_friction(0.6),
            );
        }
    }
    bodies
}

/// The four walls of `closed_box` as definitions (floor, ceiling, left, right).
pub fn closed_box_defs(width: Real, height: Real, thickness: Real) -> Vec<BodyDef> {
    let t = thickness;
    let outer = width + 2.0 * t;
    vec![
        BodyDef::fixed(Shape::rect(outer, t), Vec2::new(0.0, -0.5 * t)),
        BodyDef::fixed(Shape::rect(outer, t), Vec2::new(0.0, height + 0.5 * t)),
        BodyDef::fixed(
            Shape::rect(t, height),
            Vec2::new(-0.5 * (width + t), 0.5 * height),
        ),
        BodyDef::fixed(
            Shape::rect(t, height),
            Vec2::new(0.5 * (width + t), 0.5 * height),
        ),
    ]
}

/// Box2D v3's `rain` benchmark (`shared/benchmarks.c`, `shared/human.c`): five static rows,
/// 45 m apart, of 501 boxes of 0.5 m side by side (x from -125 m); every 8 steps, a column of
/// five groups of five ragdolls (one per row, 40 m above it; [`ragdoll_joints`] as
/// `CreateHuman` at scale 1 with joint friction 0.05, springs of 5 Hz and damping 0.5, the
/// i-th of a group in filter group -i) dropped into the next of 40 columns 6.25 m apart, and
/// once all 40 are full, a column's groups taken away and dropped again, in turn. Gravity
/// 10 m/s^2, sleep on, 1,000 steps. Box2D's ground is one body of 2,505 boxes; tiltbox's bodies
/// have at most 1,024 shapes, so here (in every engine alike) each row is a body of 501.
pub fn rain() -> Setup {
    let mut bodies = Vec::with_capacity(RAIN_ROWS);
    for row in 0..RAIN_ROWS {
        let y = 45.0 * row as Real;
        let x0 = -0.5 * RAIN_SPAN;
        let cell = Shape::rect(RAIN_CELL, RAIN_CELL);
        let mut ground = BodyDef::fixed(cell.clone(), Vec2::new(x0, y));
        for j in 1..=(RAIN_SPAN / RAIN_CELL) as usize {
            let offset = Vec2::new(j as Real * RAIN_CELL, 0.0);
            ground.parts.push(PartDef::new(cell.clone(), offset));
        }
        bodies.push(ground);
    }
    Setup {
        spawner: Some(rain_spawns),
        ..box2d_scene("rain", bodies, 1000)
    }
}

/// Rain's rows, columns and ragdolls a group; its ground's span and cell (m).
const RAIN_ROWS: usize = 5;
const RAIN_COLUMNS: usize = 40;
const RAIN_GROUP: usize = 5;
const RAIN_SPAN: Real = 250.0;
const RAIN_CELL: Real = 0.5;

/// Rain's spawns before step `k`: a column every 8 steps, the next empty one, then the
/// oldest.
fn rain_spawns(k: usize) -> Vec<SetupSpawn> {
    if k % 8 != 0 {
        return Vec::new();
    }
    let round = k / 8;
    let column = if round < RAIN_COLUMNS {
        round
    } else {
        (round - RAIN_COLUMNS) % RAIN_COLUMNS
    };
    (0..RAIN_ROWS)
        .map(|row| {
            let spacing = RAIN_SPAN / RAIN_COLUMNS as Real;
            let mut at = Vec2::new(
                -0.5 * RAIN_SPAN + spacing * (column as Real + 0.5),
                40.0 + 45.0 * row as Real,
            );
            let mut spawn = SetupSpawn {
                group: row * RAIN_COLUMNS + column,
                bodies: Vec::new(),
                joints: Vec::new(),
            };
            for i in 0..RAIN_GROUP {
                let human = RagdollDef {
                    position: at,
                    scale: 1.0,
                    friction_torque: 0.05,
                    hertz: 5.0,
                    damping_ratio: 0.5,
                    group: -(i as i32 + 1),
                };
                let first = spawn.bodies.len();
                let (bones, joints) = ragdoll_joints(&human);
                spawn.bodies.extend(bones);
                spawn.joints.extend(joints.into_iter().map(|j| SetupJoint {
                    a: j.a.map(|a| a + first),
                    b: j.b + first,
                    ..j
                }));
                at.x += 0.5;
            }
            spawn
        })
        .collect()
}

/// A ragdoll's bodies (hip first) and its joints as a [`Setup`]'s, indices into its bodies.
pub fn ragdoll_joints(def: &RagdollDef) -> (Vec<BodyDef>, Vec<SetupJoint>) {
    let bones = ragdoll(def);
    let frame = |d: &BodyDef| Transform {
        p: d.position,
        q: Rot::from_angle(d.angle),
    };
    let mut joints = Vec::with_capacity(bones.len());
    for (i, bone) in bones.iter().enumerate() {
        let Some((parent, point, JointKind::Revolute(r))) = &bone.joint else {
            continue;
        };
        joints.push(SetupJoint {
            motor: r.motor.map(|m| (m.speed, m.max)),
            limit: r.limit.map(|l| (l.lower, l.upper)),
            spring: r.spring.map(|s| (s.hertz, s.damping_ratio)),
            ..SetupJoint::hinge(
                Some(*parent),
                i,
                frame(&bones[*parent].def).apply_inv(*point),
                frame(&bone.def).apply_inv(*point),
            )
        });
    }
    (bones.into_iter().map(|b| b.def).collect(), joints)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The counts Box2D's `benchmarks.c` makes: 20 x 20 pyramids of 55 boxes on one ground of
    /// 20 segments; 6,076 bodies, a paddle and a ring of 360 pieces, the paddle on a motor;
    /// a drum of 40 shapes and 8,100 boxes.
    #[test]
    fn many_pyramids_and_spinner_have_box2ds_counts_and_build() {
        let p = many_pyramids();
        assert_eq!(p.bodies.len(), 1 + 20 * 20 * 55);
        assert_eq!(p.bodies[0].parts.len(), 19);
        // the first pyramid's bottom-left box sits on the first segment, at the left end
        let first = &p.bodies[1];
        assert_eq!((first.position.x, first.position.y), (-109.0, 0.5));
        let s = spinner();
        assert_eq!(s.bodies.len(), 360 + 1 + 6076);
        assert_eq!(s.joints.len(), 1);
        assert_eq!(s.joints[0].b, 360);
        let junk = junkyard();
        assert_eq!(junk.bodies.len(), 1 + 200 * 40 + 1);
        assert_eq!(junk.bodies[0].parts.len(), 160 + 100);
        assert!(matches!(&junk.bodies[1].shape, Shape::Polygon(p) if p.vertices().len() == 5));
        let washer = washer();
        assert_eq!(washer.bodies.len(), 1 + 90 * 90);
        assert_eq!(washer.bodies[0].parts.len(), 36 + 4);
        for setup in [p, s, washer, junk] {
            let w = setup.build().unwrap();
            assert_eq!(w.body_count(), setup.bodies.len());
        }
    }

    /// Rain as Box2D's makes it: five rows of 501 ground boxes; every 8 steps a column of five
    /// groups of five ragdolls (11 bones, 10 hinges each), the columns full after 40 drops,
    /// then one column taken away and dropped again each time, so the count stays put.
    #[test]
    fn rain_drops_columns_of_ragdolls_every_8_steps_and_then_replaces_them() {
        let rain = rain();
        assert_eq!(rain.bodies.len(), 5);
        assert!(rain.bodies.iter().all(|g| g.parts.len() == 500));
        let spawner = rain.spawner.unwrap();
        assert!(spawner(1).is_empty() && spawner(7).is_empty());
        let first = spawner(0);
        assert_eq!(first.len(), 5);
        assert_eq!((first[0].bodies.len(), first[0].joints.len()), (55, 50));
        // Column 0 of row 0: x = -125 + 6.25 / 2 m, 40 m up; the fifth ragdoll 2 m to the right.
        assert_eq!(first[0].group, 0);
        assert_eq!(first[4].group, 4 * 40);
        assert_eq!(spawner(8 * 39)[0].group, 39);
        assert_eq!(spawner(8 * 40)[0].group, 0, "the oldest column goes again");
        assert_eq!(spawner(8 * 41)[2].group, 2 * 40 + 1);
        let mut world = rain.build().unwrap();
        let mut spawned = Spawned::default();
        for k in 0..8 * 42 + 1 {
            rain.step(&mut world, &mut spawned, k).unwrap();
        }
        // 40 columns of 5 x 55 bodies, and the 5 ground rows.
        assert_eq!(world.body_count(), 5 + 40 * 5 * 55);
        assert_eq!(world.joint_count(), 40 * 5 * 50);
    }
}
