//! Runs the stiff and extreme suite with the default settings and with adaptive stiffness off,
//! and prints each case's verdict and numbers: a quick loop while tuning the soft step. Cases
//! named on the command line run even when they are report-only (pyramid_100, pyramid_134, pyramid_200).
//! Usage: cargo run --release --no-default-features --features measure --example stiff_suite [CASE...]
use tiltbox::measure::accuracy::extreme;
use tiltbox::physics::Settings;

fn main() {
    let only: Vec<String> = std::env::args().skip(1).collect();
    let configs = [
        ("default", Settings::default()),
        (
            "adaptive off",
            Settings {
                adaptive_stiffness: false,
                ..Settings::default()
            },
        ),
    ];
    for (label, settings) in &configs {
        println!("== {label}");
        for case in extreme::all() {
            let named = only.iter().any(|o| o == case.name);
            if (only.is_empty() && case.report_only) || !(only.is_empty() || named) {
                continue;
            }
            let t = std::time::Instant::now();
            let v = (case.run)(settings);
            let numbers: Vec<String> = v
                .measured
                .iter()
                .map(|(n, x)| format!("{n}={x:.4}"))
                .collect();
            println!(
                "{:5} {:20} {:6.1}s  {}",
                if v.passed { "pass" } else { "FAIL" },
                v.case,
                t.elapsed().as_secs_f64(),
                numbers.join(" ")
            );
        }
    }
}
