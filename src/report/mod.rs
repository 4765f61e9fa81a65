//! The accuracy report: sweeps every [`crate::accuracy`] case over step sizes and solver
//! configurations, times each run, draws error-against-run-time charts (SVG, plotters) and
//! writes `accuracy.md` with the stiff and extreme suite's pass/fail table for both solvers.
//!
//! Entry point: [`generate`]. Everything is single-threaded so timings are not disturbed.

use crate::accuracy::{
    closed_form, config_label, extreme, fmt_num, scenes, sequential, soft_step, Measurement,
    Verdict,
};
use crate::physics::{Real, Settings, SolverKind};
use plotters::prelude::*;

pub mod peers;
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};
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

/// One run of the sweep.
#[derive(Clone, Debug)]
pub struct Point {
    /// Step (s).
    pub dt: Real,
    /// What the run measured.
    pub measurement: Measurement,
    /// Minimum over the timed runs of wall-clock time per step (ms).
    pub ms_per_step: f64,
}

impl Point {
    /// Run time per simulated second (ms): ms per step / dt.
    pub fn ms_per_sim_second(&self) -> f64 {
        self.ms_per_step / self.dt as f64
    }
}

/// The runs of one solver configuration over the step sizes.
#[derive(Clone, Debug)]
pub struct Curve {
    /// e.g. `soft step, 4 sub`.
    pub label: String,
    /// The configuration.
    pub settings: Settings,
    /// One point per step size, largest step first.
    pub points: Vec<Point>,
}

/// Everything measured for one case.
#[derive(Clone, Debug)]
pub struct CaseSweep {
    /// Machine name (chart file name).
    pub name: &'static str,
    /// Human title.
    pub title: &'static str,
    /// Set-up, in words.
    pub setup: String,
    /// Expected answer, in words.
    pub expected: String,
    /// Unit of the error.
    pub unit: &'static str,
    /// What the error is.
    pub error_meaning: &'static str,
    /// One curve per solver configuration.
    pub curves: Vec<Curve>,
}

/// Step sizes swept (s).
pub fn step_sizes(quick: bool) -> Vec<Real> {
    let hz: &[Real] = if quick {
        &[30.0, 120.0, 480.0]
    } else {
        &[30.0, 60.0, 120.0, 240.0, 480.0, 960.0]
    };
    hz.iter().map(|f| 1.0 / f).collect()
}

/// Solver configurations swept: sequential 4/10/30 iterations, soft step 1/2/4/8 substeps.
pub fn configurations(quick: bool) -> Vec<Settings> {
    if quick {
        vec![sequential(10), soft_step(1), soft_step(4)]
    } else {
        vec![
            sequential(4),
            sequential(10),
            sequential(30),
            soft_step(1),
            soft_step(2),
            soft_step(4),
            soft_step(8),
        ]
    }
}

/// Run `f` once as a warm-up (its result is kept), then time it again until `repeats` timed
/// runs are done or 2 s have been spent; returns the result and the minimum time (ms).
fn timed(repeats: usize, mut f: impl FnMut() -> Measurement) -> (Measurement, f64) {
    let t = Instant::now();
    let m = f();
    let mut best = t.elapsed().as_secs_f64();
    let budget = Instant::now();
    for i in 0..repeats {
        if i > 0 && budget.elapsed().as_secs_f64() > 2.0 {
            break;
        }
        let t = Instant::now();
        let _ = std::hint::black_box(f());
        best = best.min(t.elapsed().as_secs_f64());
    }
    (m, best * 1e3)
}

fn repeats(quick: bool) -> usize {
    if quick {
        1
    } else {
        5
    }
}

/// Sweep one closed-form case over every configuration and step size.
pub fn sweep_closed(case: &closed_form::ClosedFormCase, quick: bool) -> CaseSweep {
    let mut curves = Vec::new();
    let mut first: Option<Measurement> = None;
    for settings in configurations(quick) {
        let points = step_sizes(quick)
            .into_iter()
            .map(|dt| {
                let (m, ms) = timed(repeats(quick), || (case.run)(&settings, dt));
                let ms_per_step = ms / m.steps.max(1) as f64;
                Point {
                    dt,
                    measurement: m,
                    ms_per_step,
                }
            })
            .collect::<Vec<_>>();
        if first.is_none() {
            first = points.first().map(|p| p.measurement.clone());
        }
        curves.push(Curve {
            label: config_label(&settings),
            settings,
            points,
        });
    }
    let first = first.expect("at least one run");
    CaseSweep {
        name: case.name,
        title: case.title,
        setup: case.setup.to_string(),
        expected: case.expected.to_string(),
        unit: first.unit,
        error_meaning: first.error_meaning,
        curves,
    }
}

/// Sweep one scene: a reference run per solver, then every configuration and step size.
pub fn sweep_scene(scene: scenes::Scene, quick: bool) -> CaseSweep {
    let refs = [
        (
            SolverKind::Sequential,
            scenes::reference_run(scene, &Settings::sequential()),
        ),
        (
            SolverKind::SoftStep,
            scenes::reference_run(scene, &Settings::soft_step()),
        ),
    ];
    let mut curves = Vec::new();
    let mut meaning = "";
    for settings in configurations(quick) {
        let reference = &refs
            .iter()
            .find(|(k, _)| *k == settings.solver)
            .expect("a reference per solver")
            .1;
        let points = step_sizes(quick)
            .into_iter()
            .map(|dt| {
                let (m, ms) = timed(repeats(quick), || {
                    scenes::compare(&scenes::run(scene, &settings, dt), reference)
                });
                meaning = m.error_meaning;
                let ms_per_step = ms / m.steps.max(1) as f64;
                Point {
                    dt,
                    measurement: m,
                    ms_per_step,
                }
            })
            .collect();
        curves.push(Curve {
            label: config_label(&settings),
            settings,
            points,
        });
    }
    let (rs, rdt) = scenes::reference(&Settings::sequential());
    let (fs, _) = scenes::reference(&Settings::soft_step());
    CaseSweep {
        name: scene.name(),
        title: scene.title(),
        setup: scene.setup().to_string(),
        expected: format!(
            "no closed form: compared with the same solver at dt = 1/{:.0} s with {} iterations (sequential) or {} substeps (soft step), positions sampled at t = {} s",
            1.0 / rdt,
            rs.iterations,
            fs.substeps,
            scene
                .sample_times()
                .iter()
                .map(|t| format!("{t}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        unit: "m",
        error_meaning: meaning,
        curves,
    }
}

const PALETTE: [RGBColor; 7] = [
    RGBColor(31, 119, 180),  // sequential 4
    RGBColor(44, 160, 44),   // sequential 10
    RGBColor(23, 190, 207),  // sequential 30
    RGBColor(255, 127, 14),  // soft 1
    RGBColor(148, 103, 189), // soft 2
    RGBColor(140, 86, 75),   // soft 4
    RGBColor(227, 119, 194), // soft 8
];

fn color_for(label: &str, index: usize) -> RGBColor {
    let known = [
        "sequential, 4 it",
        "sequential, 10 it",
        "sequential, 30 it",
        "soft step, 1 sub",
        "soft step, 2 sub",
        "soft step, 4 sub",
        "soft step, 8 sub",
    ];
    let i = known
        .iter()
        .position(|k| *k == label)
        .unwrap_or(index % PALETTE.len());
    PALETTE[i]
}

/// Smallest error drawn on a log axis; exact (zero) errors are drawn here.
const ERROR_FLOOR: f64 = 1e-9;

fn plot_err<E: std::fmt::Debug>(e: E) -> io::Error {
    io::Error::other(format!("chart: {e:?}"))
}

/// Draw `sweep` as error against run time per simulated second, log-log, to `path`.
pub fn chart(sweep: &CaseSweep, path: &Path) -> io::Result<()> {
    chart_with_peers(sweep, &[], path)
}

/// [`chart`] with other engines' points of the same case beside tiltbox's curves ([`peers`]).
pub fn chart_with_peers(
    sweep: &CaseSweep,
    peer_points: &[&peers::PeerPoint],
    path: &Path,
) -> io::Result<()> {
    let ok = |p: &Point| !p.measurement.diverged && p.measurement.error.is_finite();
    let all: Vec<&Point> = sweep.curves.iter().flat_map(|c| &c.points).collect();
    let peer_extent = peers::extent(peer_points);
    let xs: Vec<f64> = all
        .iter()
        .map(|p| p.ms_per_sim_second().max(1e-6))
        .chain(peer_extent.iter().flat_map(|(x, _)| [x.0, x.1]))
        .collect();
    let (xmin, xmax) = xs
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    let errs: Vec<f64> = all
        .iter()
        .filter(|p| ok(p))
        .map(|p| p.measurement.error.max(ERROR_FLOOR))
        .chain(peer_extent.iter().flat_map(|(_, e)| [e.0, e.1]))
        .collect();
    let (emin, emax) = if errs.is_empty() {
        (1e-3, 1.0)
    } else {
        errs.iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &e| (a.min(e), b.max(e)))
    };
    let (ylo, yhi) = (emin / 3.0, (emax * 3.0).max(emin * 30.0));
    // At least a decade on x, so the log axis gets labels.
    let widen = ((10.0 * xmin / xmax).max(1.0)).sqrt();
    let (xlo, xhi) = (xmin / 1.5 / widen, xmax * 1.5 * widen);

    let root = SVGBackend::new(path, (760, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(plot_err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{}: error vs run time", sweep.title),
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((xlo..xhi).log_scale(), (ylo..yhi).log_scale())
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc("CPU ms per simulated second (min of repeated runs)")
        .y_desc(format!("error ({})", sweep.unit))
        .x_labels(8)
        .y_labels(8)
        .light_line_style(RGBColor(238, 238, 238))
        .x_label_formatter(&|x| axis_num(*x))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()
        .map_err(plot_err)?;

    let mut any_failed = false;
    for (i, curve) in sweep.curves.iter().enumerate() {
        let color = color_for(&curve.label, i);
        let good: Vec<(f64, f64)> = curve
            .points
            .iter()
            .filter(|p| ok(p))
            .map(|p| {
                (
                    p.ms_per_sim_second().max(1e-6),
                    p.measurement.error.max(ERROR_FLOOR),
                )
            })
            .collect();
        chart
            .draw_series(LineSeries::new(good.clone(), color.stroke_width(2)))
            .map_err(plot_err)?
            .label(curve.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        chart
            .draw_series(
                good.iter()
                    .map(|&(x, y)| Circle::new((x, y), 3, color.filled())),
            )
            .map_err(plot_err)?;
        let failed: Vec<f64> = curve
            .points
            .iter()
            .filter(|p| !ok(p))
            .map(|p| p.ms_per_sim_second().max(1e-6))
            .collect();
        if !failed.is_empty() {
            any_failed = true;
            chart
                .draw_series(
                    failed
                        .iter()
                        .map(|&x| Cross::new((x, yhi / 1.15), 6, RED.stroke_width(3))),
                )
                .map_err(plot_err)?;
        }
    }
    peers::draw(&mut chart, peer_points)?;
    if any_failed {
        chart
            .draw_series(std::iter::once(Cross::new(
                (xlo, ylo),
                0,
                RED.stroke_width(3),
            )))
            .map_err(plot_err)?
            .label("diverged (drawn at the top edge)")
            .legend(|(x, y)| Cross::new((x + 9, y), 5, RED.stroke_width(3)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(plot_err)?;
    root.present().map_err(plot_err)?;
    Ok(())
}

/// The stiff and extreme suite for both solvers at their defaults.
#[derive(Clone, Debug)]
pub struct SuiteResults {
    /// `Settings::soft_step()`.
    pub soft_step: Vec<Verdict>,
    /// `Settings::sequential()`.
    pub sequential: Vec<Verdict>,
    /// The soft step with 8 substeps and 4 relax passes: what the mass-ratio cases need.
    pub soft_step_stiff: Vec<Verdict>,
}

/// The named stiffer soft-step configuration of the third column: `Settings::soft_step_stiff`
/// (8 substeps, 4 relax passes, 120 Hz contacts, load-aware stiffening).
pub fn stiff_soft_step() -> Settings {
    Settings::soft_step_stiff()
}

/// Run the suite for both solvers (with the report-only pyramid of base 100).
pub fn run_suite() -> SuiteResults {
    SuiteResults {
        soft_step: extreme::suite(&Settings::soft_step(), true),
        sequential: extreme::suite(&Settings::sequential(), true),
        soft_step_stiff: extreme::suite(&stiff_soft_step(), true),
    }
}

/// Everything the report contains.
#[derive(Clone, Debug)]
pub struct Report {
    /// Closed-form cases then the two scenes.
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
    for case in closed_form::all() {
        progress(&format!("sweep {}", case.name));
        sweeps.push(sweep_closed(&case, options.quick));
    }
    for scene in scenes::Scene::ALL {
        progress(&format!("sweep {} (with reference runs)", scene.name()));
        sweeps.push(sweep_scene(scene, options.quick));
    }
    // Other engines' points, if `benchmarks/vs-peers --accuracy` has written them.
    let peer_data = peers::load(&options.out.join(peers::CSV));
    for s in &sweeps {
        chart_with_peers(
            s,
            &peer_data.for_case(s.name),
            &img.join(chart_file(s.name)),
        )?;
    }
    let swept: Vec<&str> = sweeps.iter().map(|s| s.name).collect();
    let peer_charts = peers::extra_charts(&peer_data, &swept, &img)?;
    progress("stiff and extreme suite, both solvers");
    let suite = run_suite();
    let report = Report {
        sweeps,
        suite,
        seconds: start.elapsed().as_secs_f64(),
        quick: options.quick,
    };
    std::fs::write(
        options.out.join("accuracy.md"),
        markdown(&report) + &peers::section(&peer_data, &peer_charts),
    )?;
    Ok(report)
}

/// File name of a case's chart.
pub fn chart_file(name: &str) -> String {
    format!("accuracy-{}.svg", name.replace('_', "-"))
}

fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    format!(
        "{cpu}, {cores} logical cores available, {} / {}, {} build, {} scalars",
        std::env::consts::OS,
        std::env::consts::ARCH,
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        },
        std::any::type_name::<Real>()
    )
}

fn hz(dt: Real) -> String {
    format!("1/{:.0}", 1.0 / dt as f64)
}

fn verdict_cell(v: &Verdict) -> String {
    let status = if v.report_only {
        "report"
    } else if v.passed {
        "**pass**"
    } else {
        "**FAIL**"
    };
    let nums: Vec<String> = v
        .measured
        .iter()
        .map(|(n, x)| format!("{n}: {}", fmt_num(*x)))
        .collect();
    format!("{status}<br>{}", nums.join("<br>"))
}

/// The document.
pub fn markdown(r: &Report) -> String {
    let mut md = String::new();
    let m = &mut md;
    let _ = writeln!(m, "# Accuracy and stability\n");
    let _ = writeln!(
        m,
        "Generated by `cargo run --release -- report{}` (source: `src/accuracy/`, `src/report/`); \
         do not edit by hand. The whole run took {:.0} s.\n",
        if r.quick { " --quick" } else { "" },
        r.seconds
    );
    let _ = writeln!(
        m,
        "**Machine caveat.** Times are wall-clock on one machine: {}. They include the runner's \
         per-step checks (finiteness, penetration), are single-threaded, and compare configurations \
         with each other on that machine only; they are not a benchmark of other hardware.\n",
        machine()
    );

    // Stiff and extreme table.
    let _ = writeln!(m, "## Stiff and extreme cases\n");
    let _ = writeln!(
        m,
        "Each case runs at 60 Hz (except `huge_dt`) with the solver's defaults: \
         `Settings::soft_step()` ({} substeps, {} Hz contacts, damping ratio {}, push-out {} m/s, \
         fixed springs, slop {} m) and `Settings::sequential()` (10 iterations, \
         Baumgarte 0.2, slop 10 mm); the last column is `Settings::soft_step_stiff()`: 8 substeps, 4 relax passes, \
         120 Hz contacts and load-aware stiffening. Sleeping is turned off (a sleeping stack cannot drift) except \
         in `pyramid_sleeps`. The criterion column is the soft step's text; limits written in slops \
         use each solver's own slop. The CI versions are `tests/stability.rs` (soft step; see its \
         header for the cases it asserts in another configuration).\n",
        Settings::soft_step().substeps,
        Settings::soft_step().contact_hertz,
        Settings::soft_step().contact_damping_ratio,
        Settings::soft_step().max_push_out_speed,
        Settings::soft_step().linear_slop,
    );
    let soft_pass = r
        .suite
        .soft_step
        .iter()
        .filter(|v| !v.report_only && v.passed)
        .count();
    let seq_pass = r
        .suite
        .sequential
        .iter()
        .filter(|v| !v.report_only && v.passed)
        .count();
    let stiff_pass = r
        .suite
        .soft_step_stiff
        .iter()
        .filter(|v| !v.report_only && v.passed)
        .count();
    let total = r.suite.soft_step.iter().filter(|v| !v.report_only).count();
    let _ = writeln!(
        m,
        "Passed: soft step {soft_pass} of {total}, sequential {seq_pass} of {total}, `soft_step_stiff` {stiff_pass} of {total}.\n"
    );
    let _ = writeln!(
        m,
        "| case | criterion | soft step | sequential | `soft_step_stiff` (8 sub, 4 relax, 120 Hz, load-aware) |"
    );
    let _ = writeln!(m, "| --- | --- | --- | --- | --- |");
    for ((a, b), c) in r
        .suite
        .soft_step
        .iter()
        .zip(&r.suite.sequential)
        .zip(&r.suite.soft_step_stiff)
    {
        let _ = writeln!(
            m,
            "| `{}` | {} | {} | {} | {} |",
            a.case,
            md_cell(&a.criterion),
            verdict_cell(a),
            verdict_cell(b),
            verdict_cell(c)
        );
    }
    let notes: Vec<String> = r
        .suite
        .soft_step
        .iter()
        .chain(&r.suite.sequential)
        .filter(|v| !v.note.is_empty())
        .map(|v| format!("- `{}`: {}", v.case, v.note))
        .collect();
    let mut seen = std::collections::BTreeSet::new();
    if !notes.is_empty() {
        let _ = writeln!(m, "\nNotes:\n");
        for n in notes {
            if seen.insert(n.clone()) {
                let _ = writeln!(m, "{n}");
            }
        }
    }
    let spacing = extreme::real_spacing(10_000.0);
    let _ = writeln!(
        m,
        "\n**Large coordinates.** Positions are `{}`: the spacing between representable values is \
         {:.3e} m at 10 km and {:.3e} m at 1e7 m, so positions and contact geometry far from the \
         origin are quantised at that scale, and a body moving less than half the spacing per \
         step does not move at all (Box2D recommends f32 worlds under ~12 km). \
         Build with `--features f64` for double precision (spacing ~2e-12 m at 10 km).\n",
        std::any::type_name::<Real>(),
        spacing,
        extreme::real_spacing(1.0e7)
    );

    // Headline table at 60 Hz.
    let _ = writeln!(m, "## Error at 60 Hz with the defaults\n");
    let _ = writeln!(
        m,
        "dt = 1/60 s; `sequential, 10 it` and `soft step, 4 sub` are the two solvers' defaults. \
         Errors are absolute, in the unit shown; `diverged` marks a run that went non-finite or blew up.\n"
    );
    let _ = writeln!(
        m,
        "| case | error measured | unit | sequential, 10 it | µs/step | soft step, 4 sub | µs/step |"
    );
    let _ = writeln!(m, "| --- | --- | --- | --- | --- | --- | --- |");
    for s in &r.sweeps {
        let cell = |label: &str| -> (String, String) {
            s.curves
                .iter()
                .find(|c| c.label == label)
                .and_then(|c| c.points.iter().find(|p| (p.dt - 1.0 / 60.0).abs() < 1e-6))
                .map(|p| (err_cell(&p.measurement), us(p.ms_per_step)))
                .unwrap_or_else(|| ("-".into(), "-".into()))
        };
        let (a, at) = cell("sequential, 10 it");
        let (b, bt) = cell("soft step, 4 sub");
        let _ = writeln!(
            m,
            "| {} | {} | {} | {a} | {at} | {b} | {bt} |",
            s.title,
            md_cell(s.error_meaning),
            s.unit
        );
    }

    // How measured.
    let _ = writeln!(m, "\n## How the numbers are measured\n");
    let _ = writeln!(
        m,
        "- **Sweep.** Every case runs for every step dt in {{{}}} s and every solver configuration \
         ({}). One chart per case, one curve per configuration, one point per dt (left to right: \
         larger to smaller dt).",
        step_sizes(r.quick)
            .iter()
            .map(|&d| hz(d))
            .collect::<Vec<_>>()
            .join(", "),
        configurations(r.quick)
            .iter()
            .map(config_label)
            .collect::<Vec<_>>()
            .join("; ")
    );
    let _ = writeln!(
        m,
        "- **Time.** Each run is done once as a warm-up, then repeated {} and the minimum \
         wall-clock time (`std::time::Instant`) is kept (fewer repeats once a point has used 2 s). \
         µs/step = that time / steps. The charts' x axis is ms per *simulated second* \
         (time per step / dt), so that a smaller dt pays for its extra steps; the tables give µs per step.",
        if r.quick {
            "1 time".to_string()
        } else {
            format!("{} times", repeats(r.quick))
        }
    );
    let _ = writeln!(
        m,
        "- **Error.** Closed-form cases: absolute difference from the continuous-time answer at \
         the end of the run (see each section). Scenes without a closed form (Falling Bricks, \
         pyramid of base 20): RMS over bodies and sample times of the distance between the run's \
         positions and a reference run of the same solver at dt = 1/960 s (= 1/60 / 16) with 100 \
         iterations or 16 substeps; the largest penetration seen at any step and the energy drift \
         (E_end - E_start) / E_start (E = kinetic + potential above the floor) are in the tables."
    );
    let _ = writeln!(
        m,
        "- **Failures.** A run that goes non-finite, leaves its arena or hits the speed cap is \
         drawn as a red cross at the top edge of its chart at its run time, and listed as \
         `diverged` in the tables; it is never dropped. Errors of exactly 0 are drawn at {ERROR_FLOOR:.0e}."
    );
    let _ = writeln!(
        m,
        "- **Soft contacts have a floor.** The soft step's contacts are springs (60 Hz, stiffened \
         with load): a resting contact sinks until its spring carries the load, so resting cases \
         (resting stack, pyramid) level off at an error set by the stiffness, not by dt. Against \
         its own reference (16 substeps, hence stiffer springs) the soft step therefore converges \
         to a floor, while the sequential solver's rigid contacts keep converging."
    );
    let _ = writeln!(
        m,
        "- **Sleep.** Every run has sleeping off, so a body that comes to rest keeps being \
         simulated and timed (as in Box2D's benchmarks)."
    );
    let _ = writeln!(
        m,
        "- **Chaos.** Falling Bricks is chaotic: once bricks collide, tiny differences grow, so its \
         RMS error measures how far a configuration lands from the reference, not a convergence order.\n"
    );

    // Per-case sections.
    let _ = writeln!(m, "## Error against run time, case by case\n");
    for s in &r.sweeps {
        let _ = writeln!(m, "### {}\n", s.title);
        let _ = writeln!(
            m,
            "Set-up: {}. Expected: {}. Error: {} ({}).\n",
            s.setup, s.expected, s.error_meaning, s.unit
        );
        let _ = writeln!(m, "![{}](img/{})\n", s.title, chart_file(s.name));
        let dts = step_sizes(r.quick);
        let _ = write!(m, "| configuration |");
        for &d in &dts {
            let _ = write!(m, " dt {} |", hz(d));
        }
        let _ = writeln!(m);
        let _ = write!(m, "| --- |");
        for _ in &dts {
            let _ = write!(m, " --- |");
        }
        let _ = writeln!(m);
        for c in &s.curves {
            let _ = write!(m, "| {} |", c.label);
            for p in &c.points {
                let _ = write!(
                    m,
                    " {} ({} µs) |",
                    err_cell(&p.measurement),
                    us(p.ms_per_step)
                );
            }
            let _ = writeln!(m);
        }
        // Details for the two defaults at 60 Hz.
        for label in ["sequential, 10 it", "soft step, 4 sub"] {
            if let Some(p) = s
                .curves
                .iter()
                .find(|c| c.label == label)
                .and_then(|c| c.points.iter().find(|p| (p.dt - 1.0 / 60.0).abs() < 1e-6))
            {
                let d: Vec<String> = p
                    .measurement
                    .details
                    .iter()
                    .map(|(n, x)| format!("{n} {}", fmt_num(*x)))
                    .collect();
                let _ = writeln!(m, "\n{label} at 1/60: {}.", d.join("; "));
            }
        }
        let _ = writeln!(m);
    }
    md
}

/// A tick label: as few digits as the magnitude needs (0.002, 0.05, 3, 200).
fn axis_num(x: f64) -> String {
    if x >= 1.0 || x <= 0.0 {
        format!("{x:.0}")
    } else {
        let decimals = (-x.log10().floor()) as usize;
        format!("{x:.decimals$}")
    }
}

/// Markdown table cell text: pipes escaped.
fn md_cell(text: &str) -> String {
    text.replace('|', "\\|")
}

/// Microseconds per step, from milliseconds.
fn us(ms: f64) -> String {
    fmt_num(ms * 1e3)
}

fn err_cell(m: &Measurement) -> String {
    if m.diverged {
        "diverged".into()
    } else {
        fmt_num(m.error)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn charts_draw_diverged_runs_and_exact_zeros_without_failing() {
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
        chart(&sweep, &path).unwrap();
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
                soft_step_stiff: vec![],
            },
            seconds: 1.0,
            quick: true,
        };
        let md = markdown(&report);
        assert!(
            md.contains("diverged"),
            "diverged runs are listed in the tables"
        );
        assert!(md.contains("a \\| b"), "pipes in table cells are escaped");
    }
}
