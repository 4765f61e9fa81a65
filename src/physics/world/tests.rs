//! The solver's widths, overflow, tiers and constraint graph, from inside the World.

use super::tiers::Tier;
use super::*;
use crate::physics::math::vec2;
use crate::physics::math::PI;
use crate::physics::shape::Shape;
use crate::physics::solver::bundles::Width;
use crate::physics::solver::graph::OVERFLOW;

/// A World on the defaults with sleep off (g = 10 m/s^2 down) and a fixed floor `width` m wide
/// whose top is at y = 0.
/// A World with the default settings but sleep off, under `gravity`.
fn awake_world(gravity: Vec2) -> World {
    let settings = Settings {
        enable_sleep: false,
        ..Settings::default()
    };
    World::new(settings, gravity).unwrap()
}

fn awake_world_on_floor(width: Real) -> World {
    let settings = Settings {
        enable_sleep: false,
        ..Settings::default()
    };
    let mut w = World::new(settings, vec2(0.0, -10.0)).unwrap();
    w.add_body(&BodyDef::fixed(Shape::rect(width, 1.0), vec2(0.0, -0.5)))
        .unwrap();
    w
}

/// A 12 m plank on the ground with 40 small boxes resting on it: the plank has more
/// contacts than the graph has colours for one body, so some of them overflow.
fn crowded_plank() -> World {
    let mut w = awake_world_on_floor(40.0);
    w.add_body(&BodyDef::dynamic(Shape::rect(12.0, 0.5), vec2(0.0, 0.25)))
        .unwrap();
    for i in 0..40 {
        let x = -5.85 + 0.3 * i as Real;
        w.add_body(&BodyDef::dynamic(Shape::rect(0.25, 0.25), vec2(x, 0.625)))
            .unwrap();
    }
    w
}

/// Every awake contact of `w` moved to the overflow, and the graph told to colour none.
fn overflow_everything(w: &mut World) {
    let contacts = &mut w.contacts;
    contacts.graph.limit_colours(0);
    for c in &mut contacts.awake {
        contacts.graph.remove(c.colour, [c.a, c.b]);
        c.colour = OVERFLOW;
    }
}

/// The overflow (contacts the graph could not colour, solved one by one before the colours)
/// and the bundles solve the same physics: stepping the crowded plank with the usual colours
/// (some contacts overflow) and with none (every contact in the overflow) ends with every body
/// within 0.1 mm, in the braced tier, whose relax passes include a normal relax pass. The two
/// differ only in the order the contacts are solved in, which moves a resting scene by
/// round-off (that the kernel is the same at every width is tested bit for bit below).
#[test]
fn overflow_contacts_solve_like_the_wide_bundles() {
    let mut wide = crowded_plank();
    let mut scalar = crowded_plank();
    overflow_everything(&mut scalar);
    let (mut overflowed, mut braced) = (0, 0);
    for _ in 0..120 {
        wide.step(1.0 / 60.0).unwrap();
        scalar.step(1.0 / 60.0).unwrap();
        overflowed = overflowed.max(wide.solver.bundles.overflow_count());
        braced += usize::from(ran_braced(&wide) && ran_braced(&scalar));
        assert_eq!(
            scalar.solver.bundles.overflow_count(),
            scalar.contacts.awake.len()
        );
    }
    assert!(
        overflowed > 0,
        "the plank's 40 contacts must exceed the colours"
    );
    // The plank carries the boxes: the braced tier (a relax pass, then a normal relax pass).
    assert!(braced > 60, "braced in {braced} of 120 steps");
    for (a, b) in wide.bodies().zip(scalar.bodies()) {
        let d = (a.position() - b.position()).length();
        assert!(d < 1e-4, "body {} differs by {d} m", a.id());
        assert!((a.angle() - b.angle()).abs() < 1e-3);
    }
}

/// A pyramid of `base` unit boxes on the floor (sleep off), loaded enough that adaptive
/// stiffness solves it in the braced tier (a relax pass, then a normal relax pass).
fn braced_pyramid(base: usize) -> World {
    let mut w = awake_world_on_floor(2.0 * base as Real + 4.0);
    for row in 0..base {
        for i in 0..base - row {
            let x = (i as Real - (base - row - 1) as Real / 2.0) * 1.0;
            let y = 0.5 + row as Real;
            w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(x, y)))
                .unwrap();
        }
    }
    w
}

/// Whether any body was solved in the braced tier in the last step.
fn ran_braced(w: &World) -> bool {
    w.tiers.body_tier.contains(&Tier::Braced)
}

/// Every friction impulse a step ends with lies in the Coulomb cone of its normal impulse,
/// |Pt| <= mu Pn, in the braced tier too, where the last pass (a normal relax pass) can lower
/// Pn after friction was solved. Checked on every contact of a base-20 pyramid for 2 s, to
/// within f32 rounding of the clamp times the substep count (1e-6 relative).
#[test]
fn friction_impulses_end_each_step_inside_the_coulomb_cone() {
    let mut w = braced_pyramid(20);
    let mut braced = 0;
    for step in 0..120 {
        w.step(1.0 / 60.0).unwrap();
        braced += usize::from(ran_braced(&w));
        for c in &w.contacts.awake {
            for p in c.live() {
                let cone = c.friction * p.normal_impulse;
                assert!(
                    p.tangent_impulse.abs() <= cone * (1.0 + 1e-6),
                    "step {step}: |Pt| = {} N s outside the cone {cone} N s",
                    p.tangent_impulse.abs()
                );
            }
        }
    }
    assert!(braced > 60, "braced in {braced} of 120 steps");
}

/// A mixed pile falling into a box: boxes, discs, capsules and triangles of two densities,
/// friction and restitution varied, so every kernel path (block, points, speculative,
/// friction on and off) runs.
fn mixed_pile() -> World {
    let mut w = awake_world_on_floor(12.0);
    for x in [-6.5, 6.5] {
        w.add_body(&BodyDef::fixed(Shape::rect(1.0, 10.0), vec2(x, 5.0)))
            .unwrap();
    }
    let (triangle, _centroid) = crate::physics::convex::Polygon::new(&[
        vec2(-0.3, -0.25),
        vec2(0.3, -0.25),
        vec2(0.0, 0.3),
    ])
    .unwrap();
    let triangle = Shape::Polygon(Box::new(triangle));
    for i in 0..120 {
        let (col, row) = ((i % 12) as Real, (i / 12) as Real);
        let shape = match i % 4 {
            0 => Shape::rect(0.5, 0.4),
            1 => Shape::circle(0.25),
            2 => Shape::capsule(0.4, 0.15),
            _ => triangle.clone(),
        };
        let def = BodyDef::dynamic(shape, vec2(-5.0 + 0.85 * col + 0.1 * row, 0.5 + 0.8 * row))
            .with_density(if i % 3 == 0 { 3.0 } else { 1.0 })
            .with_friction(if i % 5 == 0 { 0.0 } else { 0.6 })
            .with_restitution(if i % 7 == 0 { 0.5 } else { 0.0 });
        w.add_body(&def).unwrap();
    }
    w
}

/// Bundles of one, four and eight lanes give the same World bit for bit: a contact's
/// arithmetic does not depend on which contacts share its bundle (`solver/lanes/`), so the
/// overflow, which runs the same kernel at width one, is the same code as the lanes. The pile
/// has restitution, friction on and off, one- and two-point contacts: every kernel path runs,
/// with one-point contacts in block bundles (a small solve's packing) and in bundles of their
/// own (a large solve's). On a machine without AVX2 the eight-lane kernels never run, and only
/// one and four are compared.
#[test]
fn one_four_and_eight_lanes_step_bit_identically() {
    for singles_from in [None, Some(0)] {
        lanes_step_bit_identically(singles_from);
    }
}

/// [`one_four_and_eight_lanes_step_bit_identically`] with one-point contacts packed apart from
/// `singles_from` contacts (`None`: the default, above this pile's).
fn lanes_step_bit_identically(singles_from: Option<usize>) {
    let widths: &[Width] = if Width::detect() == Width::Eight {
        &[Width::One, Width::Four, Width::Eight]
    } else {
        eprintln!("no AVX2 here: the eight-lane kernels never run on this machine");
        &[Width::One, Width::Four]
    };
    let mut worlds: Vec<World> = widths
        .iter()
        .map(|&width| {
            let mut w = mixed_pile();
            w.solver.bundles.width = Some(width);
            w.solver.bundles.singles_from = singles_from;
            w
        })
        .collect();
    let (mut most_contacts, mut most_singles) = (0, 0);
    for step in 0..240 {
        for w in &mut worlds {
            w.step(1.0 / 60.0).unwrap();
        }
        most_contacts = most_contacts.max(worlds[0].contacts.awake.len());
        let singles = worlds.iter().map(|w| w.solver.bundles.single_bundles());
        most_singles = most_singles.max(singles.min().unwrap_or(0));
        for (w, width) in worlds.iter().zip(widths).skip(1) {
            assert!(
                worlds[0].state_bits().eq(w.state_bits()),
                "{width:?} differs from one lane after step {step} (singles from {singles_from:?})"
            );
        }
    }
    assert!(
        most_contacts > 100,
        "the pile must be in contact: {most_contacts}"
    );
    // One-point contacts packed apart where asked, and only there.
    assert_eq!(
        most_singles > 0,
        singles_from.is_some(),
        "one-point bundles: {most_singles} (singles from {singles_from:?})"
    );
}

/// A small solve fills its half-empty bundles from other colours (`solver/gaps.rs`) and gives
/// the same World bit for bit as one that does not. Five boxes stand apart on the floor, one
/// with a sixth on top, at four lanes: the floor's five contacts take the top colour (two
/// bundles, the second with one lane) and the stacked pair's colour 0 (one bundle). A lone box's
/// floor contact, which no other constraint shares a body with, moves into colour 0's bundle:
/// two bundles instead of three. Restitution on two boxes runs the bounce lanes too.
#[test]
fn filling_small_solves_gaps_changes_nothing_and_saves_a_bundle() {
    let row = |w: &mut World| {
        for (i, x) in [-4.0, -2.0, 0.0, 2.0, 4.0].into_iter().enumerate() {
            let def = BodyDef::dynamic(Shape::rect(0.8, 0.5), vec2(x, 0.25))
                .with_restitution(if i % 2 == 1 { 0.3 } else { 0.0 });
            w.add_body(&def).unwrap();
        }
        let top = BodyDef::dynamic(Shape::rect(0.6, 0.4), vec2(-4.0, 1.2)).with_angle(0.1);
        w.add_body(&top).unwrap();
    };
    let mut worlds: Vec<World> = [None, Some(0)]
        .into_iter()
        .map(|gaps_up_to| {
            let mut w = awake_world_on_floor(12.0);
            row(&mut w);
            w.solver.bundles.width = Some(Width::Four);
            w.solver.bundles.gaps_up_to = gaps_up_to;
            w
        })
        .collect();
    let mut fewer = 0;
    for step in 0..180 {
        for w in &mut worlds {
            w.step(1.0 / 60.0).unwrap();
        }
        assert!(
            worlds[0].state_bits().eq(worlds[1].state_bits()),
            "filling gaps changed the World at step {step}"
        );
        let [filled, plain] = [&worlds[0], &worlds[1]].map(|w| w.solver.bundles.coloured_bundles());
        assert!(
            filled <= plain,
            "step {step}: {filled} bundles against {plain}"
        );
        if worlds[0].contacts.awake.len() == 6 && (filled, plain) == (2, 3) {
            fewer += 1;
        }
    }
    // Once the top box has landed (some 20 steps), every step.
    assert!(
        fewer > 120,
        "two bundles instead of three on {fewer} of 180 steps"
    );
}

/// A chain of `links` links of 0.25 m x 0.05 m from (-10, 9) rightwards, hinged end to end,
/// the first to the world at its left end. With `wrong_frames`, each link's anchor on the last
/// link is given as a world point, as if in the world's frame (10 m out on a 0.25 m link).
fn hang_chain(w: &mut World, links: usize, wrong_frames: bool) {
    use crate::physics::joint::{JointDef, JointKind, Revolute};
    let mut last = None;
    for i in 0..links {
        let at = vec2(-10.0 + 0.25 * i as Real, 9.0);
        let link = w
            .add_body(&BodyDef::dynamic(Shape::rect(0.25, 0.05), at))
            .unwrap();
        // The first link hangs from the world (its anchor in world coordinates), each other
        // from the last link's right end (in that link's frame).
        let anchor_a = match last {
            Some(_) if !wrong_frames => vec2(0.125, 0.0),
            _ => at - vec2(0.125, 0.0),
        };
        let hinge = JointDef::new(JointKind::Revolute(Revolute::free()), last, link)
            .with_anchors(anchor_a, vec2(-0.125, 0.0));
        w.add_joint(&hinge).unwrap();
        last = Some(link);
    }
}

/// Joints with rows of their own, away from the pile: a motored hinge held within limits, a
/// slider with a spring, a motor and limits (6 rows, the most), a springy rope within limits,
/// a wheel, and a box on a hinge too weak for its weight (4 N against 9.8), which breaks and
/// lands on a ledge.
fn jointed_rig(w: &mut World) {
    use crate::physics::joint::{
        Distance, JointDef, JointKind, Limit, Motor, Prismatic, Revolute, Spring, Wheel,
    };
    let spring = Some(Spring {
        hertz: 2.0,
        damping_ratio: 0.3,
    });
    let limit = |lower, upper| Some(Limit { lower, upper });
    let motor = |speed, max| Some(Motor { speed, max });
    let kinds = [
        JointKind::Revolute(Revolute {
            limit: limit(-0.5, 0.5),
            motor: motor(2.0, 5.0),
            ..Revolute::free()
        }),
        JointKind::Prismatic(Prismatic {
            spring,
            limit: limit(-0.3, 0.3),
            motor: motor(-1.0, 3.0),
            ..Prismatic::on_axis(vec2(1.0, 0.0))
        }),
        JointKind::Distance(Distance {
            length: Some(0.6),
            spring,
            limit: limit(0.4, 0.8),
        }),
        JointKind::Wheel(Wheel::on_axis(vec2(0.0, 1.0))),
    ];
    for (i, kind) in kinds.into_iter().enumerate() {
        let at = vec2(-20.0 + 2.0 * i as Real, 5.0);
        let b = w
            .add_body(&BodyDef::dynamic(Shape::rect(0.3, 0.3), at))
            .unwrap();
        let joint = JointDef::new(kind, None, b).with_anchors(at + vec2(0.0, 0.5), Vec2::ZERO);
        w.add_joint(&joint).unwrap();
    }
    let at = vec2(-28.0, 5.0);
    let heavy = w
        .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), at))
        .unwrap();
    let weak = JointDef::new(JointKind::Revolute(Revolute::free()), None, heavy)
        .with_anchors(at + vec2(0.0, 0.5), vec2(0.0, 0.5))
        .with_break(4.0, Real::INFINITY);
    w.add_joint(&weak).unwrap();
    w.add_body(&BodyDef::fixed(Shape::rect(2.0, 0.2), vec2(-28.0, 3.0)))
        .unwrap();
}

/// Bodies of several shapes: a static flight of ten stairs (one body) with a box on each, and
/// L-shaped bodies of two boxes dropped onto it.
fn compound_stairs(w: &mut World) {
    use crate::physics::part::PartDef;
    let stair = |i: usize| vec2(50.0 + 3.0 * i as Real, 0.5 * i as Real);
    let mut stairs = BodyDef::fixed(Shape::rect(3.0, 0.5), stair(0));
    for i in 1..10 {
        stairs
            .parts
            .push(PartDef::new(Shape::rect(3.0, 0.5), stair(i) - stair(0)));
    }
    w.add_body(&stairs).unwrap();
    for i in 0..10 {
        let at = stair(i) + vec2(-0.6, 0.75);
        w.add_body(&BodyDef::dynamic(Shape::rect(0.5, 1.0), at))
            .unwrap();
        let mut l = BodyDef::dynamic(Shape::rect(1.0, 0.2), stair(i) + vec2(0.6, 2.0));
        l.parts
            .push(PartDef::new(Shape::rect(0.2, 0.8), vec2(-0.4, 0.5)));
        w.add_body(&l).unwrap();
    }
}

/// Bodies for continuous collision and events beside a pile: discs fired at 120 m/s into a
/// thin static wall, thin planks spinning at 40 rad/s just above a floor of their own, and
/// boxes dropped onto the pile; the discs and the boxes report touches and hits.
fn fast_bodies(w: &mut World) {
    w.add_body(&BodyDef::fixed(Shape::rect(24.0, 0.2), vec2(20.0, -0.1)))
        .unwrap();
    w.add_body(&BodyDef::fixed(Shape::rect(0.05, 4.0), vec2(30.0, 2.0)))
        .unwrap();
    let reports = crate::physics::events::ShapeFlags {
        contact_events: true,
        hit_events: true,
        ..crate::physics::events::ShapeFlags::NONE
    };
    for k in 0..4 {
        // Boxes that report their touches and hits, dropped onto the pile.
        let drop = BodyDef::dynamic(Shape::rect(0.4, 0.4), vec2(-3.0 + 2.0 * k as Real, 9.0))
            .with_flags(reports);
        w.add_body(&drop).unwrap();
        let y = 0.5 + 0.8 * k as Real;
        let disc = BodyDef::dynamic(Shape::circle(0.1), vec2(10.0, y))
            .with_velocity(vec2(120.0, 0.0))
            .with_flags(reports);
        w.add_body(&disc).unwrap();
        let plank = BodyDef::dynamic(Shape::rect(2.0, 0.05), vec2(14.0 + 3.0 * k as Real, 1.2))
            .with_angular_velocity(40.0);
        w.add_body(&plank).unwrap();
    }
}

/// A strip of twelve static sensor boxes across the lower pile, which its bodies settle
/// through (sensors do not collide).
fn sensor_strip(w: &mut World) {
    let sensor = crate::physics::events::ShapeFlags {
        sensor: true,
        ..crate::physics::events::ShapeFlags::NONE
    };
    for k in 0..12 {
        let at = vec2(-5.5 + k as Real, 1.0);
        w.add_body(&BodyDef::fixed(Shape::rect(0.9, 0.6), at).with_flags(sensor))
            .unwrap();
    }
}

/// One, two and three workers give the same World bit for bit (`team.rs`): the mixed pile
/// with a hinged chain (joints to each other and to the world, each colour's spread over the
/// workers), a kinematic paddle (a fixed body many bundles of a colour share), fast bodies
/// striking statics (continuous collision), bodies that report touches and hits and sensors
/// across the pile (the same events in the same order), at four and eight lanes, every stage
/// spread over the workers however little its work; at four lanes the one-point contacts share
/// block bundles (a small solve's packing), at eight they have their own (a large solve's).
#[test]
fn one_two_and_three_workers_step_bit_identically() {
    let world = |workers: u32, width: Width| {
        let mut w = mixed_pile();
        w.set_workers(workers).unwrap();
        w.solver.bundles.width = Some(width);
        w.solver.bundles.share_from = Some(0);
        w.solver.bundles.singles_from = (width == Width::Eight).then_some(0);
        let paddle = BodyDef::kinematic(Shape::rect(3.0, 0.2), vec2(0.0, 6.0), vec2(0.0, 0.0))
            .with_angular_velocity(1.5);
        w.add_body(&paddle).unwrap();
        // 80 links: each of the chain's two colours holds 40 joints, enough to be spread.
        hang_chain(&mut w, 80, false);
        jointed_rig(&mut w);
        compound_stairs(&mut w);
        fast_bodies(&mut w);
        sensor_strip(&mut w);
        w
    };
    let widths: &[Width] = if Width::detect() == Width::Eight {
        &[Width::Four, Width::Eight]
    } else {
        &[Width::Four]
    };
    for &width in widths {
        let mut worlds: Vec<World> = [1, 2, 3].map(|n| world(n, width)).into();
        let (mut impacts, mut reported, mut sensed, mut parted) = (0, 0, 0, 0);
        for step in 0..180 {
            for w in &mut worlds {
                w.step(1.0 / 60.0).unwrap();
            }
            // Continuous collision on the workers: pairs struck within this step.
            // Pairs of bodies of several shapes collided on the workers.
            parted += worlds[1]
                .broad_phase
                .parts_found
                .iter()
                .map(Vec::len)
                .sum::<usize>();
            let hits = &worlds[1].solver.pair_hits;
            impacts += hits.iter().filter(|&&t| t < 1.0).count();
            worlds[1].solver.pair_hits.clear();
            let events = format!("{:?}", worlds[0].events());
            reported += worlds[0].events().hits.len() + worlds[0].events().contact_begin.len();
            sensed += worlds[0].events().sensor_begin.len();
            for (w, n) in worlds.iter().zip(1..).skip(1) {
                assert!(
                    worlds[0].state_bits().eq(w.state_bits()),
                    "{n} workers differ from one after step {step} at {width:?}"
                );
                assert_eq!(format!("{:?}", w.events()), events, "{n} workers' events");
            }
        }
        assert!(impacts > 0, "no fast body struck a static on the workers");
        assert!(reported > 0, "no hit or touch was reported");
        assert!(sensed > 0, "no shape entered a sensor");
        assert!(
            parted > 0,
            "no pair of bodies of several shapes on the workers"
        );
        for (w, n) in worlds.iter().zip(1..).skip(1) {
            let Workers::Own(team) = &w.workers else {
                panic!("{n} workers: no team of its own")
            };
            assert_eq!(team.workers(), n);
            assert!(
                team.regions() >= 180,
                "{n} workers: every step shared its solve"
            );
        }
        // The chain's 80 and the rig's 4 left of 5: the weak hinge broke on the workers too.
        assert_eq!(worlds[0].joints().count(), 84);
        assert!(worlds[0].contact_count() > 100);
        // A sane World, not one blown apart (every pair then meets every other).
        let fastest = worlds[0]
            .bodies()
            .map(|b| b.linear_velocity().length())
            .fold(0.0, Real::max);
        assert!(fastest < 20.0, "fastest body {fastest} m/s");
    }
}

/// Worlds that share one pool step as they would alone, bit for bit: two stepped at once on
/// two threads (each takes the pool when the other does not hold it), and one stepped while
/// the pool is held elsewhere, which runs alone instead of waiting.
#[test]
fn worlds_sharing_a_pool_step_as_they_would_alone() {
    let world = || {
        let mut w = mixed_pile();
        w.solver.bundles.share_from = Some(0);
        hang_chain(&mut w, 80, false);
        w
    };
    let mut alone = world();
    for _ in 0..120 {
        alone.step(1.0 / 60.0).unwrap();
    }
    let pool = WorkerPool::new(2).expect("threads start");
    let mut pair = [world(), world()];
    for w in &mut pair {
        w.share_workers(&pool);
        assert_eq!(w.settings().workers, 2);
    }
    std::thread::scope(|s| {
        for w in &mut pair {
            s.spawn(|| (0..120).for_each(|_| w.step(1.0 / 60.0).unwrap()));
        }
    });
    let regions = pool.lock().expect("free after the steps").regions();
    assert!(regions > 0, "no step took the pool");
    assert_eq!(pool.steps_shared(), regions);
    for (k, w) in pair.iter().enumerate() {
        assert!(alone.state_bits().eq(w.state_bits()), "world {k} differs");
    }
    // Held elsewhere: the step runs alone (no region), to the same result.
    let mut held = world();
    held.share_workers(&pool);
    let mut alone = world();
    let guard = pool.lock().expect("free");
    for _ in 0..10 {
        held.step(1.0 / 60.0).unwrap();
        alone.step(1.0 / 60.0).unwrap();
    }
    assert_eq!(guard.regions(), regions, "a step waited for the held pool");
    drop(guard);
    assert!(alone.state_bits().eq(held.state_bits()));
    held.step(1.0 / 60.0).unwrap();
    assert_eq!(pool.lock().expect("free").regions(), regions + 1);
}

/// How far a box `width` m wide and 1 m tall resting on the floor has sunk (m), after 2 s
/// on `settings`.
fn rest_compression(settings: Settings, width: Real) -> Real {
    let mut w = World::new(settings, vec2(0.0, -10.0)).unwrap();
    w.add_body(&BodyDef::fixed(Shape::rect(10.0, 1.0), vec2(0.0, -0.5)))
        .unwrap();
    let id = w
        .add_body(&BodyDef::dynamic(Shape::rect(width, 1.0), vec2(0.0, 0.5)))
        .unwrap();
    for _ in 0..120 {
        w.step(1.0 / 60.0).unwrap();
    }
    0.5 - w.body(id).unwrap().position().y
}

/// Creep makes a spring at rest 1 + beta times softer (`soft_step::creep`), and only in the
/// tiers that creep. A soft spring (omega = 2 pi f) carries the weight of a box resting on
/// the floor at the compression g / omega^2, whatever the box's mass and size: its two
/// points, solved as a block, push it up like one spring of stiffness m omega^2. A contact
/// with the floor gets twice the contact hertz up to a quarter of the substep rate, which at
/// these settings it already is. On the base settings (tier 0: 4 substeps, 60 Hz) a box sinks
/// exactly that. With `stiff_load_ratio` below 1 its own weight loads it: a 1 m box is as
/// wide as tall, so braced (4 substeps, 60 Hz), and a 0.2 m wide one slender, so in the
/// stack tier (6 substeps, 90 Hz); both sink 1.5 times their spring's compression. The
/// tolerance, 1 %, is f32 round-off on compressions of 20-110 micrometres at y = 0.5.
#[test]
fn creep_softens_a_resting_contact_by_one_plus_beta_in_the_creeping_tiers() {
    let base = Settings {
        enable_sleep: false,
        ..Settings::default()
    };
    // The floor's spring at `hertz` and `substeps` per 1/60 s step.
    let compression = |hertz: Real, substeps: u32| {
        let floor = (2.0 * hertz).min(0.25 * 60.0 * substeps as Real);
        10.0 / (2.0 * PI * floor).powi(2)
    };
    let loaded = Settings {
        stiff_load_ratio: 0.9,
        ..base.clone()
    };
    let cases = [
        ("tier 0", base.clone(), 1.0, 0.0, 1.0),
        (
            "braced",
            loaded.clone(),
            1.0,
            Tier::Braced.spec().creep,
            1.0,
        ),
        ("stack", loaded, 0.2, Tier::Stack.spec().creep, 1.5),
    ];
    for (tier, settings, width, creep, scale) in cases {
        let sank = rest_compression(settings, width);
        let expected = (1.0 + creep)
            * compression(
                scale * base.contact_hertz,
                (scale * base.substeps as Real) as u32,
            );
        assert!(
            (sank / expected - 1.0).abs() < 0.01,
            "{tier}: sank {sank} m, expected {expected} m (creep {creep})"
        );
    }
}

/// Adaptive stiffness tells a stack from a pyramid (`tiers::island_tier`): both are loaded
/// (their contacts are new; later a 20-box stack's bottom contact carries about 20 box
/// weights and a base-20 pyramid's most loaded about 14, past `stiff_load_ratio`, 12), but
/// the stack is 20 times as tall as it is wide and the pyramid about as tall as wide. The
/// stack is solved on more substeps ([`Tier::Stack`]) and the pyramid on the base ones with
/// a relax pass and a normal relax pass ([`Tier::Braced`]), from the first step and once the loads count
/// (after 8 steps). Turned on its side by gravity along x, the stack is the wide one.
#[test]
fn a_stack_is_slender_and_a_pyramid_braced() {
    let mut w = awake_world_on_floor(200.0);
    let mut stack = Vec::new();
    for i in 0..20 {
        let centre = vec2(30.0, 0.5 + i as Real);
        stack.push(
            w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), centre))
                .unwrap(),
        );
    }
    let mut pyramid = Vec::new();
    for row in 0..20 {
        for i in 0..20 - row {
            let x = -30.0 + (i as Real - (19 - row) as Real / 2.0) * 1.05;
            let centre = vec2(x, 0.5 + row as Real);
            pyramid.push(
                w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), centre))
                    .unwrap(),
            );
        }
    }
    let tier_of = |w: &World, ids: &[BodyId]| {
        let tiers: Vec<Tier> = ids
            .iter()
            .map(|id| w.tiers.body_tier[id.index as usize])
            .collect();
        assert!(
            tiers.iter().all(|&t| t == tiers[0]),
            "one island, one tier: {tiers:?}"
        );
        tiers[0]
    };
    w.step(1.0 / 60.0).unwrap();
    assert_eq!(tier_of(&w, &stack), Tier::Stack, "a new stack");
    assert_eq!(tier_of(&w, &pyramid), Tier::Braced, "a new pyramid");
    for _ in 0..59 {
        w.step(1.0 / 60.0).unwrap();
    }
    assert_eq!(tier_of(&w, &stack), Tier::Stack, "a 20-box stack");
    assert_eq!(tier_of(&w, &pyramid), Tier::Braced, "a base-20 pyramid");
    w.set_gravity(vec2(-10.0, 0.0)).unwrap();
    w.step(1.0 / 60.0).unwrap();
    assert_eq!(
        tier_of(&w, &stack),
        Tier::Braced,
        "the stack, lying along gravity"
    );
}

/// A braced island is heavily loaded ([`Tier::HeavyBraced`], twice the substeps) when it is
/// [`tiers::HEAVY_DEPTH`] (80) bodies deep or more on average: a pyramid of base n is
/// (n + 1) / 2 deep, so one of base 170 (85.5) is, from its first step, and one of base 150
/// (75.5) is not.
#[test]
fn a_deep_pyramid_is_heavily_loaded() {
    let tier_after_a_step = |base: usize| {
        let mut w = awake_world_on_floor(400.0);
        let mut top = None;
        for row in 0..base {
            for i in 0..base - row {
                let x = (i as Real - (base - 1 - row) as Real / 2.0) * 1.05;
                let centre = vec2(x, 0.5 + row as Real);
                top = Some(
                    w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), centre))
                        .unwrap(),
                );
            }
        }
        w.step(1.0 / 60.0).unwrap();
        w.tiers.body_tier[top.unwrap().index as usize]
    };
    assert_eq!(tier_after_a_step(170), Tier::HeavyBraced, "base 170");
    assert_eq!(tier_after_a_step(150), Tier::Braced, "base 150");
}

/// An island's depth leaves out how far its bodies travel in the step: their broad-phase
/// boxes grow by it, and a pile flung about (Box2D's spinner) read two or three times as deep
/// as it is. A pyramid of base 150 (75.5 deep) carried sideways at 30 m/s, each box grown by
/// 0.5 m a side, is as deep as at rest: below [`tiers::HEAVY_DEPTH`] (with the travel counted
/// it reached the heavy tier).
#[test]
fn a_moving_pile_is_as_deep_as_a_resting_one() {
    let mut w = awake_world_on_floor(400.0);
    let mut top = None;
    let base = 150;
    for row in 0..base {
        for i in 0..base - row {
            let x = (i as Real - (base - 1 - row) as Real / 2.0) * 1.05;
            let def = BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(x, 0.5 + row as Real))
                .with_velocity(vec2(30.0, 0.0));
            top = Some(w.add_body(&def).unwrap());
        }
    }
    w.step(1.0 / 60.0).unwrap();
    assert_eq!(w.tiers.body_tier[top.unwrap().index as usize], Tier::Braced);
}

/// Contacts found in place over last step's (`World::find_contacts`, when the pairs keep their
/// order) step exactly like contacts found into a fresh array every step, as bodies come and
/// go at the front, in the middle and at the end of the key order: a row of resting boxes on
/// the floor; the first thrown up (its contact gone from the front while it flies, back when
/// it lands), then removed; a box added in its freed slot (new contacts at the front), one
/// dropped onto the middle of the row (new contacts in the middle), the last thrown up (gone
/// from the end) and one in the middle thrown so hard that its pair with the floor is gone in
/// one step (a contact ended among pairs that all go on). The same on two workers, whose
/// merge keeps a steady block of pairs (all last step's contacts, none ended) at once, in
/// place and copying. Each step's state is
/// compared to the bit, and the in-place writing and the steady blocks must have run.
#[test]
fn contacts_found_in_place_step_like_contacts_found_anew() {
    let row = |copy: bool, workers: u32| {
        let mut w = awake_world_on_floor(40.0);
        w.contacts.copy_for_tests = copy;
        w.set_workers(workers).unwrap();
        w.solver.bundles.share_from = Some(0);
        let ids: Vec<BodyId> = (0..12)
            .map(|i| {
                let centre = vec2(-11.0 + 2.0 * i as Real, 0.5);
                w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), centre))
                    .unwrap()
            })
            .collect();
        (w, ids)
    };
    let ids = row(false, 1).1;
    // In place and copying, on one worker and on two.
    let mut worlds = [(false, 1), (true, 1), (false, 2), (true, 2)].map(|(c, n)| row(c, n).0);
    let (mut kept_in_place, mut steady) = (0, [0; 2]);
    for step in 0..120 {
        for w in &mut worlds {
            match step {
                10 => w.apply_impulse(ids[0], vec2(0.0, 4.0)).unwrap(),
                30 => drop(w.remove_body(ids[0]).unwrap()),
                40 => drop(
                    w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(-11.0, 0.5)))
                        .unwrap(),
                ),
                60 => drop(
                    w.add_body(&BodyDef::dynamic(Shape::rect(0.5, 0.5), vec2(1.0, 3.0)))
                        .unwrap(),
                ),
                80 => w.apply_impulse(ids[11], vec2(0.0, 4.0)).unwrap(),
                100 => w.apply_impulse(ids[5], vec2(0.0, 20.0)).unwrap(),
                _ => {}
            }
        }
        let previous = worlds[0].contacts.awake.as_ptr();
        for w in &mut worlds {
            w.step(1.0 / 60.0).unwrap();
        }
        if worlds[0].contacts.awake.as_ptr() == previous {
            kept_in_place += 1;
        }
        for (count, w) in steady.iter_mut().zip(&worlds[2..]) {
            *count += usize::from(w.broad_phase.steady == [true]);
        }
        for (k, w) in worlds.iter().enumerate().skip(1) {
            assert!(
                worlds[0].state_bits().eq(w.state_bits()),
                "step {step}: world {k}'s state differs"
            );
            assert_eq!(
                worlds[0].contacts.awake.len(),
                w.contacts.awake.len(),
                "step {step}, world {k}"
            );
        }
    }
    assert!(kept_in_place > 90, "in place {kept_in_place} of 120 steps");
    assert!(
        steady.iter().all(|&n| n > 60),
        "steady blocks: {steady:?} of 120 steps"
    );
}

/// Restitution acts only where a point pushed this step. A disc falls at 2 m/s onto a
/// floor, both of restitution 1, its lowest point 5 cm above it: in one step of 1/60 s it
/// falls 2/60 + 10/2/3600 = 3.47 cm, so its contact is found (within the 2 cm speculative
/// margin) but never closes: even in the last relax pass the 1.53 cm left is more than the
/// 0.9 cm it falls in a substep, so the point pushes nothing. Bouncing it anyway would throw
/// it back up from 1.5 cm above the floor. It must still be falling freely after that step
/// (2 + 10/60 = 2.167 m/s), and bounce the next, leaving at that speed within 5 % (the
/// restitution pass aims at the approach speed measured before the step's gravity).
#[test]
fn a_speculative_point_that_never_touches_does_not_bounce() {
    let mut w = World::new(Settings::default(), vec2(0.0, -10.0)).unwrap();
    let floor = BodyDef::fixed(Shape::rect(4.0, 1.0), vec2(0.0, -0.5)).with_restitution(1.0);
    w.add_body(&floor).unwrap();
    let disc = BodyDef::dynamic(Shape::circle(0.25), vec2(0.0, 0.30)).with_restitution(1.0);
    let id = w.add_body(&disc).unwrap();
    w.set_velocity(id, vec2(0.0, -2.0), 0.0).unwrap();
    w.step(1.0 / 60.0).unwrap();
    assert!(
        !w.contacts.awake.is_empty(),
        "the floor contact must be found, speculatively"
    );
    let body = w.body(id).unwrap();
    let gap = body.position().y - 0.25;
    assert!(gap > 0.012 && gap < 0.018, "gap after the step: {gap} m");
    let v = body.linear_velocity().y;
    let free_fall = -2.0 - 10.0 / 60.0;
    assert!((v - free_fall).abs() < 1e-4, "falling freely: {v} m/s");
    w.step(1.0 / 60.0).unwrap();
    let v = w.body(id).unwrap().linear_velocity().y;
    assert!(
        (v + free_fall).abs() < 0.05 * -free_fall,
        "rebound speed {v} m/s"
    );
}

/// The constraint graph stays exact while contacts and joints begin, end, sleep and wake,
/// bodies are removed and added: after every step each dynamic body's mask is exactly the
/// colours of the awake contacts and joints on it, no two of one colour share a dynamic body,
/// every awake contact has a colour and every sleeping contact and joint none. (A colour not
/// given back would leak: the body's colours would run out and its constraints go to the
/// overflow for good.) Joints to the world take the top colours, as contacts with the ground.
#[test]
fn the_constraint_graph_matches_the_contacts_at_every_step() {
    let (mut w, ids, hinge) = graph_test_world();
    let (mut slept, mut coloured, mut joints_coloured) = (false, 0, 0);
    for step in 0..600 {
        match step {
            100 => drop(w.remove_joint(hinge).unwrap()),
            200 => drop(w.remove_bodies(&ids[10..14]).unwrap()),
            300 => w.apply_impulse(ids[40], vec2(0.0, 3.0)).unwrap(),
            420 => w.set_gravity(vec2(2.0, -10.0)).unwrap(),
            _ => {}
        }
        if step % 50 == 25 {
            let at = vec2(-3.0 + 0.1 * (step / 50) as Real, 8.0);
            w.add_body(&BodyDef::dynamic(Shape::rect(0.6, 0.6), at))
                .unwrap();
        }
        w.step(1.0 / 60.0).unwrap();
        slept |= !w.contacts.sleeping.is_empty();
        let mut masks = vec![0u32; w.bodies.slots.len()];
        coloured += contact_colours(&w, &mut masks, step);
        joints_coloured += joint_colours(&w, &mut masks, step);
        for (i, &mask) in masks.iter().enumerate() {
            assert_eq!(
                w.contacts.graph.mask(i as u32),
                mask,
                "step {step}: body {i}'s mask"
            );
        }
    }
    assert!(slept, "some island fell asleep (and woke)");
    assert!(coloured > 1000, "contacts were coloured: {coloured}");
    assert!(
        joints_coloured > 1000,
        "joints were coloured: {joints_coloured}"
    );
}

/// 60 boxes and discs in rows over a floor; neighbours in a row held apart by distance
/// joints (one pair removed with its bodies later), and one body on a hinge to the world.
fn graph_test_world() -> (World, Vec<BodyId>, crate::physics::joint::JointId) {
    use crate::physics::joint::{Distance, JointDef, JointKind, Revolute};
    let mut w = World::new(Settings::default(), vec2(0.0, -10.0)).unwrap();
    w.add_body(&BodyDef::fixed(Shape::rect(20.0, 1.0), vec2(0.0, -0.5)))
        .unwrap();
    let mut ids = Vec::new();
    for i in 0..60 {
        let (col, row) = ((i % 10) as Real, (i / 10) as Real);
        let shape = if i % 2 == 0 {
            Shape::rect(0.8, 0.5)
        } else {
            Shape::circle(0.3)
        };
        let at = vec2(-4.5 + col + 0.1 * row, 0.5 + 0.9 * row);
        ids.push(w.add_body(&BodyDef::dynamic(shape, at)).unwrap());
    }
    let rod = JointKind::Distance(Distance::default());
    for a in [10, 12, 20, 21, 22, 30] {
        let def = JointDef::new(rod.clone(), Some(ids[a]), ids[a + 1]);
        w.add_joint(&def).unwrap();
    }
    let hinge = JointDef::new(JointKind::Revolute(Revolute::free()), None, ids[35]);
    let hinge = w.add_joint(&hinge).unwrap();
    (w, ids, hinge)
}

/// Add each awake contact's colour to its dynamic bodies' `masks`, checking it is there
/// once, that every awake contact has a colour and no sleeping one; how many are coloured.
fn contact_colours(w: &World, masks: &mut [u32], step: usize) -> usize {
    use crate::physics::solver::graph::{COLOURS, UNCOLOURED};
    let mut coloured = 0;
    for c in &w.contacts.awake {
        assert_ne!(c.colour, UNCOLOURED, "step {step}: an awake contact");
        if (c.colour as usize) < COLOURS {
            coloured += 1;
            let dynamic = |i: u32| {
                w.bodies.slots[i as usize]
                    .body
                    .as_ref()
                    .is_some_and(|b| b.inv_mass > 0.0)
            };
            for i in [c.a, c.b].into_iter().filter(|&i| dynamic(i)) {
                let bit = 1u32 << c.colour;
                assert_eq!(masks[i as usize] & bit, 0, "step {step}: body {i}");
                masks[i as usize] |= bit;
            }
        }
    }
    assert!(w.contacts.sleeping.iter().all(|c| c.colour == UNCOLOURED));
    coloured
}

/// The same for the joints: an awake joint has a colour (a top one if it holds to the
/// world), a sleeping one none; how many are coloured.
fn joint_colours(w: &World, masks: &mut [u32], step: usize) -> usize {
    use crate::physics::solver::graph::{DYNAMIC_COLOURS, UNCOLOURED};
    let mut coloured = 0;
    for j in w.joints.slots.iter().filter_map(|s| s.joint.as_ref()) {
        let (ends, dynamic) = joints::graph_ends(&j.def, &w.bodies.slots);
        if !joints::joint_is_awake(&j.def, &w.bodies.slots) {
            assert_eq!(j.colour, UNCOLOURED, "step {step}: a sleeping joint");
            continue;
        }
        assert_ne!(j.colour, UNCOLOURED, "step {step}: an awake joint");
        if j.def.body_a.is_none() {
            assert!(j.colour as usize >= DYNAMIC_COLOURS, "{}", j.colour);
        }
        coloured += 1;
        let bit = 1u32 << j.colour;
        for (i, node) in ends.into_iter().zip(dynamic) {
            if node {
                assert_eq!(masks[i as usize] & bit, 0, "step {step}: body {i}");
                masks[i as usize] |= bit;
            }
        }
    }
    coloured
}

/// A speed above the World's cap is refused naming the cap this World runs with (not the
/// default): 60 m/s, or a rim speed of 60 m/s, against a cap of 50.
#[test]
fn a_speed_above_the_cap_names_this_worlds_cap() {
    let settings = Settings {
        max_linear_speed: 50.0,
        ..Settings::default()
    };
    let mut w = World::new(settings, vec2(0.0, -10.0)).unwrap();
    let id = w
        .add_body(&BodyDef::dynamic(Shape::circle(0.5), Vec2::ZERO))
        .unwrap();
    let err = w.set_velocity(id, vec2(60.0, 0.0), 0.0).unwrap_err();
    assert_eq!(
        err.to_string(),
        "velocity (speed) = 60 is out of range: must not exceed Settings::max_linear_speed (m/s) = 50"
    );
    let err = w.set_velocity(id, Vec2::ZERO, 120.0).unwrap_err();
    assert_eq!(
        err.to_string(),
        "angular_velocity (rim speed) = 60 is out of range: must not exceed Settings::max_linear_speed (m/s) = 50"
    );
    assert_eq!(w.body(id).unwrap().linear_velocity(), Vec2::ZERO);
}

/// An approach speed is carried to the next step only from a step that pushed the point: a
/// disc of restitution 1 arriving at 6 m/s is pushed by the last relax pass of its first step
/// while still 1 cm above a floor of restitution 1 (no gravity); stopped there for a step,
/// then sent down at 2 m/s, it bounces at 2 m/s, not at the 6 m/s of the approach two steps
/// before.
#[test]
fn a_stale_approach_does_not_bounce_a_later_landing() {
    let mut w = awake_world(Vec2::ZERO);
    w.add_body(&BodyDef::fixed(Shape::rect(10.0, 1.0), vec2(0.0, -0.5)).with_restitution(1.0))
        .unwrap();
    let r = 0.25;
    // Bottom 11 cm up, falling at 6 m/s: 10 cm in the step's four substeps, ending 1 cm up.
    let disc = w
        .add_body(
            &BodyDef::dynamic(Shape::circle(r), vec2(0.0, r + 0.11))
                .with_velocity(vec2(0.0, -6.0))
                .with_restitution(1.0),
        )
        .unwrap();
    w.step(1.0 / 60.0).unwrap();
    let gap = w.body(disc).unwrap().position().y - r;
    assert!((0.005..0.015).contains(&gap), "1 cm up after a step: {gap}");
    w.set_velocity(disc, Vec2::ZERO, 0.0).unwrap();
    w.step(1.0 / 60.0).unwrap();
    w.set_velocity(disc, vec2(0.0, -2.0), 0.0).unwrap();
    let mut fastest_up: Real = 0.0;
    for _ in 0..10 {
        w.step(1.0 / 60.0).unwrap();
        fastest_up = fastest_up.max(w.body(disc).unwrap().linear_velocity().y);
    }
    // e = 1 returns the 2 m/s (restitution_drop holds rebounds within 2 % of e times the
    // impact speed).
    assert!(
        (fastest_up - 2.0).abs() < 0.04,
        "bounced at {fastest_up} m/s"
    );
}

/// Turning moves no point of a disc's core, so continuous collision does not count a spin as
/// motion toward a surface: a disc of radius 0.5 m gliding at 10 m/s 1 cm above a floor
/// (no gravity) while it spins at 50 rad/s goes its full 10 m/s x 1/60 s every step (before,
/// the spin's 25 m/s rim speed read as an approach and it was moved back most of each step).
#[test]
fn a_spinning_disc_gliding_over_a_floor_is_not_held_back() {
    let mut w = awake_world(Vec2::ZERO);
    w.add_body(&BodyDef::fixed(Shape::rect(40.0, 1.0), vec2(0.0, -0.5)))
        .unwrap();
    let disc = w
        .add_body(
            &BodyDef::dynamic(Shape::circle(0.5), vec2(-10.0, 0.51))
                .with_velocity(vec2(10.0, 0.0))
                .with_angular_velocity(50.0),
        )
        .unwrap();
    for step in 0..30 {
        let x0 = w.body(disc).unwrap().position().x;
        w.step(1.0 / 60.0).unwrap();
        let moved = w.body(disc).unwrap().position().x - x0;
        assert!(
            (moved - 10.0 / 60.0).abs() < 1e-4,
            "step {step}: moved {moved} m"
        );
    }
}

/// A body struck within a step leaves faster than the box the broad phase paired it by
/// foretold, so a static it then reaches was never its partner: continuous collision sweeps
/// it against the statics its path meets. A 0.1 m box at rest 10 cm from a 5 cm wall (no
/// gravity), struck by a box ten times as dense at 30 m/s, leaves at about 27 m/s (0.45 m a
/// step): its centre never passes the wall's near face.
#[test]
fn a_struck_body_does_not_pass_a_wall_it_was_not_paired_with() {
    let mut w = awake_world(Vec2::ZERO);
    let face = 0.15;
    w.add_body(&BodyDef::fixed(
        Shape::rect(0.05, 2.0),
        vec2(face + 0.025, 0.0),
    ))
    .unwrap();
    let struck = w
        .add_body(&BodyDef::dynamic(Shape::rect(0.1, 0.1), Vec2::ZERO))
        .unwrap();
    w.add_body(
        &BodyDef::dynamic(Shape::rect(0.1, 0.1), vec2(-0.3, 0.0))
            .with_density(10.0)
            .with_velocity(vec2(30.0, 0.0)),
    )
    .unwrap();
    let mut fastest: Real = 0.0;
    for step in 0..30 {
        w.step(1.0 / 60.0).unwrap();
        let b = w.body(struck).unwrap();
        fastest = fastest.max(b.linear_velocity().x);
        assert!(
            b.position().x < face,
            "step {step}: centre at {}",
            b.position().x
        );
    }
    assert!(fastest > 10.0, "the box was struck: {fastest} m/s");
}

/// A heavy plank resting on light boxes asks for [`Tier::Extreme`] (their masses are 222 to
/// one apart and the boxes carry its weight); the same plank hinged at its centre to the world
/// asks for nothing by its mass, since the hinge carries its weight (Box2D's `spinner`, whose
/// hinged paddle stirs bodies 280 times lighter, ran at twice the cost when it did).
#[test]
fn a_heavy_body_hinged_to_the_world_asks_nothing_by_its_mass() {
    use crate::physics::body::MassSpec;
    use crate::physics::joint::{JointDef, JointKind, Revolute};
    let plank_tier = |hinged: bool| {
        let mut w = awake_world_on_floor(40.0);
        for x in [-4.0, 0.0, 4.0] {
            w.add_body(&BodyDef::dynamic(Shape::rect(0.3, 0.3), vec2(x, 0.15)))
                .unwrap();
        }
        let mut plank = BodyDef::dynamic(Shape::rect(10.0, 0.5), vec2(0.0, 0.55));
        plank.mass = MassSpec::Mass(20.0);
        let plank = w.add_body(&plank).unwrap();
        if hinged {
            let hinge = JointDef::new(JointKind::Revolute(Revolute::free()), None, plank)
                .with_anchors(vec2(0.0, 0.55), Vec2::ZERO);
            w.add_joint(&hinge).unwrap();
        }
        for _ in 0..10 {
            w.step(1.0 / 60.0).unwrap();
        }
        w.tiers.body_tier[plank.index as usize]
    };
    assert_eq!(plank_tier(false), Tier::Extreme, "resting on the boxes");
    assert!(
        plank_tier(true) < Tier::Extreme,
        "hinged: {:?}",
        plank_tier(true)
    );
}

/// Shapes that report hits, with no sensor anywhere, leave the sensor stage alone (it keeps
/// the query tree in step with every body, 6 % of Box2D's washer); a sensor brings it in, and
/// removing the sensor's body takes it out again.
#[test]
fn only_a_sensor_brings_in_the_sensor_stage() {
    use crate::physics::events::ShapeFlags;
    let mut w = awake_world_on_floor(20.0);
    let hits = ShapeFlags {
        hit_events: true,
        ..ShapeFlags::NONE
    };
    let sensor = ShapeFlags {
        sensor: true,
        ..ShapeFlags::NONE
    };
    w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 0.5)).with_flags(hits))
        .unwrap();
    w.step(1.0 / 60.0).unwrap();
    assert_eq!(w.queries.synced_at, None, "hits alone");
    let probe = BodyDef::fixed(Shape::circle(0.5), vec2(5.0, 0.5)).with_flags(sensor);
    let probe = w.add_body(&probe).unwrap();
    w.step(1.0 / 60.0).unwrap();
    assert_eq!(w.queries.synced_at, Some(w.steps), "with a sensor");
    w.remove_body(probe).unwrap();
    w.step(1.0 / 60.0).unwrap();
    w.step(1.0 / 60.0).unwrap();
    assert_ne!(w.queries.synced_at, Some(w.steps), "the sensor gone");
}

/// A kinematic body aimed at a pose reaches it in one step of the `dt` it was given (its
/// velocities are the pose's difference over `dt`, integrated exactly for a kinematic body),
/// turning the shorter way from 3 rad to -3 rad (0.28 rad across pi, not 6 rad back); a
/// dynamic body, a NaN and a zero `dt` are refused with nothing changed.
#[test]
fn a_kinematic_body_reaches_its_target_pose_in_one_step() {
    use crate::physics::error::PhysicsError;
    let mut w = awake_world(vec2(0.0, -10.0));
    let def = BodyDef::kinematic(Shape::rect(2.0, 1.0), vec2(1.0, 1.0), Vec2::ZERO).with_angle(3.0);
    let id = w.add_body(&def).unwrap();
    let dt = 1.0 / 60.0;
    w.set_target_transform(id, vec2(1.5, 0.8), -3.0, dt)
        .unwrap();
    let turn = w.body(id).unwrap().angular_velocity() * dt;
    assert!((turn - (2.0 * PI - 6.0)).abs() < 1e-4, "turned {turn} rad");
    w.step(dt).unwrap();
    let b = w.body(id).unwrap();
    assert!(
        (b.position() - vec2(1.5, 0.8)).length() < 1e-4,
        "{:?}",
        b.position()
    );
    assert!(
        (b.angle() - (3.0 + 2.0 * PI - 6.0)).abs() < 1e-4,
        "{}",
        b.angle()
    );
    let ball = w
        .add_body(&BodyDef::dynamic(Shape::circle(0.5), vec2(5.0, 5.0)))
        .unwrap();
    assert!(matches!(
        w.set_target_transform(ball, Vec2::ZERO, 0.0, dt),
        Err(PhysicsError::NotKinematic(_))
    ));
    assert!(w
        .set_target_transform(id, vec2(Real::NAN, 0.0), 0.0, dt)
        .is_err());
    assert!(w.set_target_transform(id, Vec2::ZERO, 0.0, 0.0).is_err());
    // (The refusals left last step's aim: 0.5 m right and 0.2 m down over dt.)
    let v = w.body(id).unwrap().linear_velocity();
    assert!((v - vec2(30.0, -12.0)).length() < 1e-3, "{v:?}");
}

/// A static ground of several shapes, swept shape by shape: boxes rest on each of its ten
/// strips (their tops at y = 0, 2, ..., 18, each strip 2 m wide and 4 m apart along x) and do
/// not fall through them, a box between two strips' heights falls to the ground below; once the
/// ground is removed its shapes pair with nothing and every box falls; a copy of the world
/// taken before stepping, and the world restored from its exported state, step to the same
/// state.
#[test]
fn a_ground_of_several_shapes_holds_what_rests_on_each_shape() {
    use crate::physics::part::PartDef;
    let mut w = awake_world(vec2(0.0, -10.0));
    let strip = |i: usize| {
        (
            vec2(4.0 * i as Real, 2.0 * i as Real - 0.25),
            Shape::rect(2.0, 0.5),
        )
    };
    let (at, shape) = strip(0);
    let mut ground = BodyDef::fixed(shape, at);
    for i in 1..10 {
        let (at, shape) = strip(i);
        ground.parts.push(PartDef::new(shape, at - strip(0).0));
    }
    let ground = w.add_body(&ground).unwrap();
    let boxes: Vec<BodyId> = (0..10)
        .map(|i| {
            let at = vec2(4.0 * i as Real, 2.0 * i as Real + 0.5);
            w.add_body(&BodyDef::dynamic(Shape::rect(0.5, 1.0), at))
                .unwrap()
        })
        .collect();
    let between = w
        .add_body(&BodyDef::dynamic(Shape::rect(0.5, 0.5), vec2(10.0, 9.0)))
        .unwrap();
    let copy = w.clone();
    for _ in 0..120 {
        w.step(1.0 / 60.0).unwrap();
    }
    for (i, &id) in boxes.iter().enumerate() {
        let y = w.body(id).unwrap().position().y;
        assert!(
            (y - (2.0 * i as Real + 0.5)).abs() < 0.01,
            "box {i} at y = {y}"
        );
    }
    // x = 10 m lies between the strips at 8 and 12 m: nothing under it.
    assert!(w.body(between).unwrap().position().y < 0.0);
    // The copy, and the world restored from the copy's exported state, step to the same bits.
    let mut restored = World::import_state(&copy.export_state()).unwrap();
    for mut again in [copy, restored.clone()] {
        for _ in 0..120 {
            again.step(1.0 / 60.0).unwrap();
        }
        assert_eq!(again.state_hash(), w.state_hash());
    }
    restored.clear();
    restored.step(1.0 / 60.0).unwrap();
    assert_eq!(restored.body_count(), 0);
    w.remove_body(ground).unwrap();
    for _ in 0..30 {
        w.step(1.0 / 60.0).unwrap();
    }
    for (i, &id) in boxes.iter().enumerate() {
        let y = w.body(id).unwrap().position().y;
        // Half a second of free fall is 1.25 m.
        assert!(y < 2.0 * i as Real + 0.5 - 1.0, "box {i} still at y = {y}");
    }
}

/// Bodies created asleep (Box2D's `isAwake = false`, as its `smash` benchmark makes its grid)
/// cost nothing (no pair, no contact, no motion) until a moving body reaches them. Those that
/// touch sleep as one island: reaching one wakes the block, and the blow passes through it in
/// that same step. A block apart, or a box whose filter keeps it from the block, sleeps on.
#[test]
fn bodies_created_asleep_wait_until_reached_and_wake_with_what_they_touch() {
    use crate::physics::filter::Filter;
    let mut w = World::new(Settings::default(), Vec2::ZERO).unwrap();
    let hammer =
        BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(-2.0, 0.0)).with_velocity(vec2(10.0, 0.0));
    let hammer = w.add_body(&hammer).unwrap();
    let asleep = |at: Vec2| BodyDef::dynamic(Shape::rect(0.4, 0.4), at).with_awake(false);
    let mut block = Vec::new();
    for i in 0..6 {
        for j in 0..4 {
            // Side by side, touching: awake, these would be 38 contacts.
            let at = vec2(2.0 + 0.4 * i as Real, 0.4 * j as Real);
            block.push((w.add_body(&asleep(at)).unwrap(), at));
        }
    }
    let apart = w.add_body(&asleep(vec2(3.0, 10.0))).unwrap();
    // On the block's far top corner, touching it, in a category the others do not collide with.
    let aloof = Filter {
        category: 2,
        mask: !1,
        group: 0,
    };
    let aloof_at = vec2(4.0, 1.6);
    let aloof = w.add_body(&asleep(aloof_at).with_filter(aloof)).unwrap();
    let awake = |w: &World, ids: &[(BodyId, Vec2)]| {
        ids.iter()
            .filter(|(id, _)| w.body(*id).unwrap().is_awake())
            .count()
    };
    // The hammer's face is 3.3 m from the block at 10 m/s: 15 steps leave it 0.8 m short.
    for _ in 0..15 {
        w.step(1.0 / 60.0).unwrap();
        assert_eq!(w.awake_count(), 1, "only the hammer is awake");
        assert!(w.contacts.awake.is_empty() && w.contacts.sleeping.is_empty());
    }
    for (id, at) in &block {
        let b = w.body(*id).unwrap();
        assert_eq!((b.position(), b.angle()), (*at, 0.0), "untouched, unmoved");
        assert!(!b.to_def().awake, "its definition says asleep");
    }
    // Restored from its exported state, the World draws the same islands and steps the same.
    let mut restored = World::import_state(&w.export_state()).unwrap();
    let mut steps = 0;
    while awake(&w, &block) == 0 {
        w.step(1.0 / 60.0).unwrap();
        steps += 1;
        assert!(steps < 30, "the hammer never reached the block");
    }
    // The step that reaches the block wakes all of it, and moves its far column already (a
    // layer woken a step would leave that column at rest for five more steps).
    assert_eq!(awake(&w, &block), block.len());
    let far = w.body(block[20].0).unwrap();
    assert!(far.linear_velocity().x > 0.1, "{:?}", far.linear_velocity());
    for _ in 0..60 {
        w.step(1.0 / 60.0).unwrap();
    }
    assert!(w.body(block[20].0).unwrap().position().x > block[20].1.x + 1.0);
    assert!(w.body(hammer).unwrap().linear_velocity().x < 10.0);
    for _ in 0..steps + 60 {
        restored.step(1.0 / 60.0).unwrap();
    }
    assert_eq!(restored.state_hash(), w.state_hash());
    for (id, at) in [(apart, vec2(3.0, 10.0)), (aloof, aloof_at)] {
        let b = w.body(id).unwrap();
        assert!(!b.is_awake());
        assert_eq!(b.position(), at);
    }
}

/// A body created asleep under gravity stays where it was put, through a copy and an
/// exported state alike, until it is pushed; then it falls.
#[test]
fn a_body_created_asleep_hangs_until_pushed() {
    let mut w = World::new(Settings::default(), vec2(0.0, -10.0)).unwrap();
    let at = vec2(0.0, 5.0);
    let def = BodyDef::dynamic(Shape::circle(0.5), at).with_awake(false);
    let id = w.add_body(&def).unwrap();
    let mut restored = World::import_state(&w.export_state()).unwrap();
    for world in [&mut w, &mut restored] {
        for _ in 0..60 {
            world.step(1.0 / 60.0).unwrap();
        }
        let b = world.body(id).unwrap();
        assert_eq!(b.position(), at);
        assert!(!b.is_awake());
    }
    assert_eq!(restored.state_hash(), w.state_hash());
    w.apply_force(id, vec2(1.0, 0.0)).unwrap();
    assert!(w.body(id).unwrap().is_awake(), "a push wakes it");
    for _ in 0..30 {
        w.step(1.0 / 60.0).unwrap();
    }
    // Half a second of free fall is 1.25 m.
    let y = w.body(id).unwrap().position().y;
    assert!((y - (5.0 - 1.25)).abs() < 0.05, "fell to y = {y}");
}

/// A chain whose anchors cannot meet stays finite. Its anchors are given in the wrong frames
/// (each joint's anchor on the last link as a world point, 10 m out on a 0.25 m link): the
/// joints' impulses grew ten-thousandfold a step, and every body was NaN by the third step.
/// Now a joint's impulses beyond 1e18 N s start again from zero, and a body leaves the step
/// within the speed cap: nothing sensible comes of such a chain, but nothing poisons the World.
#[test]
fn a_chain_whose_anchors_cannot_meet_stays_finite() {
    let mut w = awake_world(vec2(0.0, -10.0));
    hang_chain(&mut w, 80, true);
    let cap = w.settings().max_linear_speed;
    for step in 0..600 {
        w.step(1.0 / 60.0).unwrap();
        for b in w.bodies() {
            assert!(b.is_finite(), "step {step}: a body is not finite");
            assert!(
                b.linear_velocity().length() <= cap * 1.0001,
                "step {step}: over the cap"
            );
        }
        for j in w.joints() {
            let (f, t) = (j.reaction_force(), j.reaction_torque());
            assert!(
                f.length().is_finite() && t.is_finite(),
                "step {step}: {f:?} {t}"
            );
        }
    }
}

/// A disc that a kinematic slab presses down into a chain floor (two-sided, then one-sided)
/// keeps its centre in front of the floor: a body's centre does not cross a chain's piece it
/// touched at the start of the step. The slab, which nothing stops, passes through the disc
/// instead. Without that guard the disc was pressed until its centre crossed the line, the
/// two-sided floor pushed it on out below, and it fell to y = -24 m in the 3 s.
#[test]
fn a_disc_crushed_into_a_chain_floor_keeps_its_centre_in_front() {
    for one_sided in [false, true] {
        let mut w = awake_world(vec2(0.0, -10.0));
        let floor = [vec2(-5.0, 0.0), vec2(0.0, 0.0), vec2(5.0, 0.0)];
        for piece in BodyDef::chain(&floor, false, one_sided).unwrap() {
            w.add_body(&piece).unwrap();
        }
        let disc = w
            .add_body(&BodyDef::dynamic(Shape::circle(0.5), vec2(0.2, 0.5)))
            .unwrap();
        let slab = BodyDef::kinematic(Shape::rect(4.0, 0.5), vec2(0.0, 1.26), vec2(0.0, -1.0));
        w.add_body(&slab).unwrap();
        let mut lowest = Real::INFINITY;
        for _ in 0..180 {
            w.step(1.0 / 60.0).unwrap();
            lowest = lowest.min(w.body(disc).unwrap().position().y);
        }
        assert!(
            lowest > 0.0,
            "one-sided {one_sided}: the disc's centre went to y = {lowest} m"
        );
    }
}
