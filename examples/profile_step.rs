//! Steps one benchmark scene and prints ms/step: a target for `perf record` while optimising.
//! Usage: cargo run --release --no-default-features --features measure --example profile_step [SCENE] [STEPS] [WARM_UP] [WORKERS]
//! (SCENE: a benchmark set-up's name, `pile_N` for N boxes in a pile 20 deep, or `sensors_N`
//! for N sensors over a resting pile.)
//! (WARM_UP: untimed steps first; the scene's own warm-up when left out).
//! (WORKERS `1+N`: the same World steps on one thread and on N workers by turns, 25 steps
//! each, and both medians and their ratio are printed: the results are the same to the bit
//! either way, and taking turns within one run leaves out the host's slow drifts, which
//! separate runs of a shared machine do not.)
use std::time::Instant;

/// Steps a turn, when one thread and workers take turns.
const TURN: usize = 25;

fn main() {
    let mut args = std::env::args().skip(1);
    let name = args.next().unwrap_or_else(|| "large_pyramid".to_string());
    let steps: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(500);
    let warm_up: Option<usize> = args.next().and_then(|s| s.parse().ok());
    let workers_arg = args.next().unwrap_or_else(|| "1".to_string());
    // `1+N`: by turns on one thread and on N workers.
    let turns: Option<u32> = workers_arg.strip_prefix("1+").and_then(|n| n.parse().ok());
    let workers: u32 = turns.map_or_else(|| workers_arg.parse().unwrap_or(1), |_| 1);
    // `pile_N`: N boxes in a pile 20 deep (how the cost grows with the count).
    let pile = name
        .strip_prefix("pile_")
        .and_then(|n| n.parse().ok())
        .map(tiltbox::measure::cases::pile);
    // `sensors_N`: N static sensors over a resting pile of 4,000 discs.
    let sensors = name
        .strip_prefix("sensors_")
        .and_then(|n| n.parse().ok())
        .map(tiltbox::measure::cases::sensor_field);
    let Some(setup) = pile.or(sensors).or_else(|| {
        tiltbox::measure::cases::benchmark_setups()
            .into_iter()
            .find(|s| s.name == name)
    }) else {
        eprintln!("unknown scene {name}");
        std::process::exit(2);
    };
    let mut world = match setup.build() {
        Ok(w) => w,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    if let Err(e) = world.set_workers(workers) {
        eprintln!("{e}");
        std::process::exit(2);
    }
    let warm_up = warm_up.unwrap_or(setup.warm_up);
    let mut spawned = Default::default();
    for k in 0..warm_up {
        let _ = setup.step(&mut world, &mut spawned, k);
    }
    let pool = match turns.map(tiltbox::physics::WorkerPool::new) {
        Some(Err(e)) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
        pool => pool.map(|p| p.expect("checked")),
    };
    let mut times = Vec::with_capacity(steps);
    let mut shared_times = Vec::with_capacity(steps);
    let mut contacts = 0;
    for k in warm_up..warm_up + steps {
        // By turns: 25 steps alone, 25 on the pool's workers.
        let on_pool = pool.as_ref().filter(|_| (k - warm_up) / TURN % 2 == 1);
        match on_pool {
            Some(pool) => world.share_workers(pool),
            None if pool.is_some() => world.set_workers(1).expect("one worker"),
            None => {}
        }
        let t = Instant::now();
        let _ = setup.step(&mut world, &mut spawned, k);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        if on_pool.is_some() {
            shared_times.push(ms);
        } else {
            times.push(ms);
        }
        contacts += world.contact_count();
    }
    times.sort_by(f64::total_cmp);
    if let (Some(n), false) = (turns, shared_times.is_empty()) {
        shared_times.sort_by(f64::total_cmp);
        let (alone, shared) = (times[times.len() / 2], shared_times[shared_times.len() / 2]);
        println!(
            "{name}: by turns, one thread median {alone:.6} ms/step, {n} workers {shared:.6}, speed-up {:.3}",
            alone / shared
        );
    }
    let top = world
        .bodies()
        .map(|b| b.position().y)
        .fold(f32::MIN as f64, |a, y| a.max(y as f64));
    // FNV-1a over the state's words: equal hashes before and after a change that should not
    // change results say it did not (to the bit).
    let hash = world.state_bits().fold(0xcbf2_9ce4_8422_2325u64, |h, w| {
        (h ^ w).wrapping_mul(0x0000_0100_0000_01b3)
    });
    println!(
        "{name}: {} bodies, median {:.6} ms/step, min {:.6}, contacts {} (mean {:.1}), awake {}, top y {top:.2}, state {hash:016x}",
        world.body_count(),
        times[times.len() / 2],
        times[0],
        world.contact_count(),
        contacts as f64 / steps.max(1) as f64,
        world.awake_count()
    );
}
