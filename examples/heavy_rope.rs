//! The heavy rope: `LINKS` links of 1 m x 0.5 m (0.5 kg) from the world's origin holding a
//! 30 m x 30 m block (900 kg), released level (or laid hanging with a second argument); prints
//! every 2 s the widest joint gap now and so far, and the block's position and speed.
//! Usage: cargo run --release --example heavy_rope [LINKS] [hang]
use tiltbox::physics::*;
fn main() {
    let links: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(20);
    let hang = std::env::args().nth(2).is_some();
    let dir = if hang {
        vec2(0.0, -1.0)
    } else {
        vec2(1.0, 0.0)
    };
    let ang = dir.y.atan2(dir.x);
    let settings = Settings {
        enable_sleep: false,
        ..Settings::default()
    };
    let mut w = World::new(settings, vec2(0.0, -9.81)).unwrap();
    let mut prev: Option<BodyId> = None;
    for i in 0..links {
        let c = (i as f32 + 0.5) * dir;
        let b = w
            .add_body(&BodyDef::dynamic(Shape::rect(1.0, 0.5), c).with_angle(ang))
            .unwrap();
        let aa = if prev.is_some() {
            vec2(0.5, 0.0)
        } else {
            Vec2::ZERO
        };
        w.add_joint(
            &JointDef::new(JointKind::Revolute(Revolute::free()), prev, b)
                .with_anchors(aa, vec2(-0.5, 0.0)),
        )
        .unwrap();
        prev = Some(b);
    }
    let c = (links as f32 + 15.0) * dir;
    let block = w
        .add_body(&BodyDef::dynamic(Shape::rect(30.0, 30.0), c).with_angle(ang))
        .unwrap();
    w.add_joint(
        &JointDef::new(JointKind::Revolute(Revolute::free()), prev, block)
            .with_anchors(vec2(0.5, 0.0), vec2(-15.0, 0.0)),
    )
    .unwrap();
    let mut worst = 0.0f32;
    for i in 0..1200 {
        w.step(1.0 / 60.0).unwrap();
        let gap = w
            .joints()
            .map(|j| {
                let d = j.def();
                let pa = match d.body_a {
                    Some(a) => w.body(a).unwrap().transform().apply(d.anchor_a),
                    None => d.anchor_a,
                };
                (pa - w.body(d.body_b).unwrap().transform().apply(d.anchor_b)).length()
            })
            .fold(0.0f32, f32::max);
        worst = worst.max(gap);
        if i % 60 == 59 {
            let b = w.body(block).unwrap();
            println!(
                "t={} gap={:.4} worst={:.4} block={} v={:.3}",
                (i + 1) / 60,
                gap,
                worst,
                b.position(),
                b.linear_velocity().length()
            );
        }
    }
}
