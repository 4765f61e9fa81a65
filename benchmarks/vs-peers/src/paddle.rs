//! `--paddle`: the stiff suite's `spinner` case (`tiltbox::measure::accuracy::extreme::spinner`)
//! read in every engine on the same set-up: Box2D's spinner as `cases::spinner` builds it (a
//! 1.2 m x 40.4 m paddle on a motor of unlimited torque at 5 rad/s, 6,076 bodies in a ring of
//! 360 chain pieces of radius 40 m), 500 steps at 1/60 s. From step 60 on (1 s): the paddle's
//! mean speed (its turn over the time), its slowest speed at the end of a step and that step,
//! and, every 10 steps, the farthest body centre from the ring's (0, 32). The figures beside
//! which the case's bounds (mean within 1 %, never below 95 % of 5 rad/s, every centre inside
//! 40 m) can be read.

use crate::{box2d, Engine, Rapier, Tiltbox};
use std::f32::consts::PI;
use tiltbox::measure::cases;

/// Step each engine through the case and print one row per engine.
pub(crate) fn run() {
    let setup = cases::spinner();
    println!("## spinner's paddle, 500 steps (the stiff suite's spinner case)\n");
    println!(
        "| engine | mean speed from 1 s (rad/s) | slowest from 1 s (rad/s) | at step | \
         farthest centre from the ring's (m) |"
    );
    println!("| --- | ---: | ---: | ---: | ---: |");
    let engines: [(&str, Box<dyn Engine>); 3] = [
        ("tiltbox", Box::new(Tiltbox::new(&setup))),
        (box2d::LABEL, Box::new(box2d::Box2d::new(&setup))),
        ("rapier2d", Box::new(Rapier::new(&setup))),
    ];
    for (name, mut engine) in engines {
        let (mut turned, mut slowest, mut at, mut farthest) = (0.0f64, f32::INFINITY, 0, 0.0f32);
        let mut last_angle = 0.0;
        for k in 0..500 {
            engine.step();
            let bodies = engine.dynamic_bodies();
            // The paddle is the set-up's first dynamic body (the ring's pieces are static).
            let paddle = &bodies[0];
            if k >= 60 {
                // A step turns the paddle by about 0.08 rad: unwrap through (-pi, pi].
                let d = (paddle.angle - last_angle + PI).rem_euclid(2.0 * PI) - PI;
                turned += d as f64;
                if paddle.angular_velocity < slowest {
                    (slowest, at) = (paddle.angular_velocity, k);
                }
            }
            last_angle = paddle.angle;
            if k % 10 == 9 {
                let out = bodies[1..]
                    .iter()
                    .map(|b| (b.position[0].powi(2) + (b.position[1] - 32.0).powi(2)).sqrt())
                    .fold(0.0, f32::max);
                farthest = farthest.max(out);
            }
        }
        let mean = turned / (440.0 / 60.0);
        println!("| {name} | {mean:.4} | {slowest:.4} | {at} | {farthest:.4} |");
    }
}
