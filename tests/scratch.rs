use tiltbox::cases::*;
use tiltbox::physics::*;

#[test]
fn scratch() {
    let mut w = World::new(Settings::soft_step(), vec2(0.0, -10.0)).unwrap();
    ground(&mut w, 0.0, 40.0, 2.0).unwrap();
    let ids = stack(&mut w, 20, 1.0, 0.0, 0.0).unwrap();
    for i in 0..1800 {
        w.step(1.0 / 60.0).unwrap();
        if i % 120 == 0 {
            let xs: Vec<String> = ids
                .iter()
                .step_by(3)
                .map(|id| {
                    let b = w.body(*id).unwrap();
                    format!("{:+.4}/{:+.4}", b.position().x, b.angle())
                })
                .collect();
            println!("{i}: {}", xs.join(" "));
        }
    }
}
