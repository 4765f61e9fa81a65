//! The accuracy report (`tiltbox report`): runs the sweeps and the suite
//! ([`crate::measure::accuracy::sweep`]), draws a chart per case ([`chart`]) and writes
//! `accuracy.md` ([`markdown`]). Entry point: [`generate`].

pub mod chart;
pub mod markdown;
pub mod peers;

use crate::measure::accuracy::sweep::{CaseSweep, SuiteResults};
use crate::measure::accuracy::{closed_form, joint_forms, reference, sweep};
use std::io;
use std::path::PathBuf;
use std::time::Instant;

/// What to generate and where.
#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// Directory for `accuracy.md`; charts go to `<out>/img/`.
    pub out: PathBuf,
    /// A short sweep (3 step sizes, 3 configurations, 1 timed run) for a quick look or CI.
    pub quick: bool,
}

impl Default for ReportOptions {
    fn default() -> Self {
        ReportOptions {
            out: PathBuf::from("docs"),
            quick: false,
        }
    }
}

/// Everything the report contains.
#[derive(Clone, Debug)]
pub struct Report {
    /// Closed-form cases, then the two reference cases.
    pub sweeps: Vec<CaseSweep>,
    /// Stiff and extreme suite.
    pub suite: SuiteResults,
    /// Wall-clock seconds the whole report took.
    pub seconds: f64,
    /// Whether this was the quick version.
    pub quick: bool,
}

/// Run everything, write `<out>/accuracy.md` and `<out>/img/accuracy-*.svg`, and return what was
/// measured. `progress` is told what is running.
pub fn generate(options: &ReportOptions, progress: &mut dyn FnMut(&str)) -> io::Result<Report> {
    let start = Instant::now();
    let img = options.out.join("img");
    std::fs::create_dir_all(&img)?;
    let mut sweeps = Vec::new();
    for case in closed_form::all().into_iter().chain(joint_forms::all()) {
        progress(&format!("sweep {}", case.name));
        sweeps.push(sweep::sweep_closed(&case, options.quick));
    }
    for case in reference::ReferenceCase::ALL {
        progress(&format!("sweep {} (with reference runs)", case.name()));
        sweeps.push(sweep::sweep_reference(case, options.quick));
    }
    // Other engines' points, if `benchmarks/vs-peers --accuracy` has written them.
    let peer_data = peers::load(&options.out.join(peers::CSV));
    for s in &sweeps {
        chart::chart_with_peers(
            s,
            &peer_data.for_case(s.name),
            &img.join(chart::chart_file(s.name)),
        )?;
    }
    let swept: Vec<&str> = sweeps.iter().map(|s| s.name).collect();
    let peer_charts = peers::extra_charts(&peer_data, &swept, &img)?;
    progress("stiff and extreme suite, both solvers");
    let suite = sweep::run_suite();
    let report = Report {
        sweeps,
        suite,
        seconds: start.elapsed().as_secs_f64(),
        quick: options.quick,
    };
    std::fs::write(
        options.out.join("accuracy.md"),
        markdown::markdown(&report) + &peers::section(&peer_data, &peer_charts),
    )?;
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::accuracy::sweep::{Curve, Point};
    use crate::measure::accuracy::{sequential, soft_step, Measurement};
    use crate::physics::Real;

    fn point(dt: Real, error: f64, diverged: bool) -> Point {
        Point {
            dt,
            measurement: Measurement {
                case: "test",
                error,
                unit: "m",
                error_meaning: "test error",
                diverged,
                steps: 10,
                details: vec![("x (m)", 1.0)],
            },
            ms_per_step: 0.01,
        }
    }

    #[test]
    fn the_chart_and_the_document_show_diverged_runs_and_exact_zeros() {
        let sweep = CaseSweep {
            name: "chart_test",
            title: "Chart test",
            setup: "none".into(),
            expected: "0".into(),
            unit: "m",
            error_meaning: "a | b",
            curves: vec![
                Curve {
                    label: "sequential, 10 it".into(),
                    settings: sequential(10),
                    points: vec![
                        point(1.0 / 30.0, f64::NAN, true),
                        point(1.0 / 60.0, 0.0, false),
                        point(1.0 / 120.0, 1e-3, false),
                    ],
                },
                Curve {
                    label: "soft step, 4 sub".into(),
                    settings: soft_step(4),
                    points: vec![point(1.0 / 60.0, 5.0, true)],
                },
            ],
        };
        let dir = std::env::temp_dir().join(format!("tiltbox-chart-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("chart.svg");
        chart::chart(&sweep, &path).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(
            svg.contains("diverged"),
            "the failure marks have a legend entry"
        );
        std::fs::remove_dir_all(&dir).unwrap();

        let report = Report {
            sweeps: vec![sweep],
            suite: SuiteResults {
                soft_step: vec![],
                sequential: vec![],
                soft_step_fixed: vec![],
            },
            seconds: 1.0,
            quick: true,
        };
        let md = markdown::markdown(&report);
        assert!(
            md.contains("diverged"),
            "diverged runs are listed in the tables"
        );
        assert!(md.contains("a \\| b"), "pipes in table cells are escaped");
    }
}
