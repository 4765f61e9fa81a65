//! Other engines on the report's charts: Box2D v3 and rapier2d points read from a CSV written by
//! `benchmarks/vs-peers --accuracy` (`docs/data/peers.csv`). The engine crate never links the
//! peers; it only reads their numbers.
//!
//! Self-contained on purpose: [`load`] reads the file (absent file = no peers), [`draw`] adds a
//! case's peer points to a chart the report already draws, [`extra_charts`] draws the cases the
//! report does not sweep for tiltbox (the jittered stack, mass ratios) from the CSV alone, and
//! [`section`] is the markdown that says where the points come from.

use super::chart::legend;
use plotters::coord::{combinators::LogCoord, Shift};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::io;
use std::path::Path;

/// Where the report looks for the peers' points, relative to its output directory.
pub const CSV: &str = "data/peers.csv";

/// One row of the CSV.
#[derive(Clone, Debug, PartialEq)]
pub struct PeerPoint {
    /// e.g. `Box2D v3 (SSE2)`, `rapier2d`, `tiltbox`.
    pub engine: String,
    /// A report case name, e.g. `pyramid_20`.
    pub case: String,
    /// Step (s).
    pub dt: f64,
    /// The case's error (NaN: diverged).
    pub error: f64,
    /// CPU ms per simulated second.
    pub ms_per_sim_second: f64,
}

/// The CSV's contents: its `#` header lines (how it was obtained) and its points.
#[derive(Clone, Debug, Default)]
pub struct Peers {
    /// The comment lines, without the leading `# `.
    pub provenance: Vec<String>,
    /// Every point.
    pub points: Vec<PeerPoint>,
}

/// Read `path`; a missing or unreadable file gives no peers (the report draws tiltbox alone).
pub fn load(path: &Path) -> Peers {
    std::fs::read_to_string(path)
        .map(|text| parse(&text))
        .unwrap_or_default()
}

/// Parse the CSV text (`engine,case,dt,error,cpu_ms_per_simulated_s`, `#` comments, a header).
pub fn parse(text: &str) -> Peers {
    let mut peers = Peers::default();
    for line in text.lines().map(str::trim).filter(|l| !l.is_empty()) {
        if let Some(c) = line.strip_prefix('#') {
            peers.provenance.push(c.trim().to_string());
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let num = |i: usize| f.get(i).and_then(|x| x.parse::<f64>().ok());
        if let (5, Some(dt), Some(ms)) = (f.len(), num(2), num(4)) {
            peers.points.push(PeerPoint {
                engine: f[0].to_string(),
                case: f[1].to_string(),
                dt,
                error: num(3).unwrap_or(f64::NAN),
                ms_per_sim_second: ms,
            });
        }
    }
    peers
}

impl Peers {
    /// The peers' points of `case` (tiltbox's own rows excluded: the report has its own).
    pub fn for_case(&self, case: &str) -> Vec<&PeerPoint> {
        self.points
            .iter()
            .filter(|p| p.case == case && !is_tiltbox(&p.engine))
            .collect()
    }

    /// Cases in the CSV in first-seen order.
    fn cases(&self) -> Vec<&str> {
        let mut v: Vec<&str> = Vec::new();
        for p in &self.points {
            if !v.contains(&p.case.as_str()) {
                v.push(&p.case);
            }
        }
        v
    }
}

fn is_tiltbox(engine: &str) -> bool {
    engine.starts_with("tiltbox")
}

/// Marker and colour per engine: Box2D black triangles, rapier2d olive squares, tiltbox (in the
/// CSV-only charts) the report's soft-step-4 brown circles.
fn style(engine: &str) -> (RGBColor, u8) {
    if engine.starts_with("Box2D") {
        (RGBColor(0, 0, 0), 0)
    } else if engine.starts_with("rapier") {
        (RGBColor(128, 128, 0), 1)
    } else {
        (RGBColor(140, 86, 75), 2)
    }
}

/// Smallest error drawn (errors of 0 are drawn here).
const FLOOR: f64 = 1e-9;

type LogChart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

/// Draw `points` (one series per engine, a thin line through markers) on `chart` with a legend
/// entry each. Diverged points (NaN error) are not drawn; their count goes in the legend.
pub fn draw<'a, 'b: 'a>(chart: &mut LogChart<'a, 'b>, points: &[&PeerPoint]) -> io::Result<()> {
    let err = |e: plotters::drawing::DrawingAreaErrorKind<_>| io::Error::other(format!("{e:?}"));
    let mut engines: Vec<&str> = Vec::new();
    for p in points {
        if !engines.contains(&p.engine.as_str()) {
            engines.push(&p.engine);
        }
    }
    for engine in engines {
        let (color, marker) = style(engine);
        let mut xy: Vec<(f64, f64, f64)> = points
            .iter()
            .filter(|p| p.engine == engine)
            .map(|p| (p.dt, p.ms_per_sim_second.max(1e-6), p.error))
            .collect();
        xy.sort_by(|a, b| b.0.total_cmp(&a.0));
        let diverged = xy.iter().filter(|p| !p.2.is_finite()).count();
        let good: Vec<(f64, f64)> = xy
            .iter()
            .filter(|p| p.2.is_finite())
            .map(|p| (p.1, p.2.max(FLOOR)))
            .collect();
        let name = if is_tiltbox(engine) {
            "tiltbox, default settings"
        } else {
            engine
        };
        let label = if diverged > 0 {
            format!("{name} ({diverged} diverged, not drawn)")
        } else {
            name.to_string()
        };
        chart
            .draw_series(LineSeries::new(good.clone(), color.stroke_width(1)))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| EmptyElement::at((x + 9, y)) + marker_shape(marker, color));
        chart
            .draw_series(
                good.iter()
                    .map(|&(x, y)| EmptyElement::at((x, y)) + marker_shape(marker, color)),
            )
            .map_err(err)?;
    }
    Ok(())
}

fn marker_shape<DB: DrawingBackend>(
    marker: u8,
    color: RGBColor,
) -> DynElement<'static, DB, (i32, i32)> {
    match marker {
        0 => TriangleMarker::new((0, 0), 6, color.filled()).into_dyn(),
        1 => Rectangle::new([(-4, -4), (4, 4)], color.filled()).into_dyn(),
        _ => Circle::new((0, 0), 4, color.stroke_width(2)).into_dyn(),
    }
}

/// (x, error) ranges covering `points` (finite, positive errors only), for the chart's axes.
pub fn extent(points: &[&PeerPoint]) -> Option<((f64, f64), (f64, f64))> {
    let xs = points.iter().map(|p| p.ms_per_sim_second.max(1e-6));
    let es = points
        .iter()
        .filter(|p| p.error.is_finite())
        .map(|p| p.error.max(FLOOR));
    let fold = |it: &mut dyn Iterator<Item = f64>| {
        it.fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)))
    };
    let (x, e) = (fold(&mut xs.into_iter()), fold(&mut es.into_iter()));
    (x.0.is_finite() && e.0.is_finite()).then_some((x, e))
}

/// Titles of the CSV-only cases.
fn title(case: &str) -> String {
    match case {
        "stack_20" => "Jittered 20-stack, top drift".into(),
        "mass_ratio_100" => "Mass ratio 100:1, deepest overlap".into(),
        "mass_ratio_1000" => "Mass ratio 1000:1, deepest overlap".into(),
        c => c.to_string(),
    }
}

/// File name of a CSV-only case's chart.
pub fn extra_chart_file(case: &str) -> String {
    format!("accuracy-peers-{}.svg", case.replace('_', "-"))
}

/// Charts of the cases in the CSV that the report has no sweep of (`swept` lists the report's
/// own), every engine of the CSV including tiltbox's defaults; returns the cases drawn.
pub fn extra_charts(peers: &Peers, swept: &[&str], img: &Path) -> io::Result<Vec<String>> {
    let mut drawn = Vec::new();
    for case in peers.cases() {
        if swept.contains(&case) {
            continue;
        }
        let points: Vec<&PeerPoint> = peers.points.iter().filter(|p| p.case == case).collect();
        let Some(((xmin, xmax), (emin, emax))) = extent(&points) else {
            continue;
        };
        let path = img.join(extra_chart_file(case));
        let root = SVGBackend::new(&path, (760, 500)).into_drawing_area();
        draw_extra(&root, &title(case), &points, (xmin, xmax), (emin, emax))
            .map_err(|e| io::Error::other(format!("chart: {e:?}")))?;
        root.present()
            .map_err(|e| io::Error::other(format!("chart: {e:?}")))?;
        drawn.push(case.to_string());
    }
    Ok(drawn)
}

fn draw_extra(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    title: &str,
    points: &[&PeerPoint],
    (xmin, xmax): (f64, f64),
    (emin, emax): (f64, f64),
) -> io::Result<()> {
    let err = |e: plotters::drawing::DrawingAreaErrorKind<_>| io::Error::other(format!("{e:?}"));
    root.fill(&WHITE).map_err(err)?;
    let widen = ((10.0 * xmin / xmax).max(1.0)).sqrt();
    let (xlo, xhi) = (xmin / 1.5 / widen, xmax * 1.5 * widen);
    let (ylo, yhi) = (emin / 3.0, (emax * 3.0).max(emin * 30.0));
    let mut chart = ChartBuilder::on(root)
        .caption(format!("{title}: error vs run time"), ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((xlo..xhi).log_scale(), (ylo..yhi).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("CPU ms per simulated second (vs-peers run)")
        .y_desc("error (m)")
        .x_labels(8)
        .y_labels(8)
        .light_line_style(RGBColor(238, 238, 238))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()
        .map_err(err)?;
    draw(&mut chart, points)?;
    legend(&mut chart, SeriesLabelPosition::UpperRight)
}

/// The markdown section: where the points come from, the CSV-only charts, and every point.
pub fn section(peers: &Peers, extra: &[String]) -> String {
    let mut m = String::new();
    if peers.points.is_empty() {
        return m;
    }
    let _ = writeln!(m, "## Other engines: Box2D v3 and rapier2d\n");
    let _ = writeln!(
        m,
        "The pyramid and resting-stack charts above also carry Box2D v3 (black triangles) and \
         rapier2d (olive squares), one point per dt of the same sweep. Their points are not \
         computed by this report (the engine crate does not depend on other engines): they are \
         read from `docs/{CSV}`, written by `benchmarks/vs-peers --accuracy`, which builds every \
         case from the same body definitions in each engine, runs it with 4 substeps (rapier: 4 \
         solver iterations), sleep off, at every dt of the sweep, and measures the error as this \
         report does; the pyramid's reference run is the SAME engine at dt = 1/960 s with 16 \
         substeps (rapier: 16 iterations), as tiltbox's is its own. Their run times come from \
         that tool's run (fat LTO, single thread, whole run including building), not from this \
         one, so compare x positions across engines as rough; the table below also has \
         tiltbox's defaults measured in the same run as the peers, for a same-run comparison. \
         The jittered 20-stack and the mass ratios are not swept here for tiltbox, so they get \
         charts of their own from the CSV alone (tiltbox: `Settings::default()`)."
    );
    let _ = writeln!(m, "\nHow the file was obtained (its header):\n");
    for line in &peers.provenance {
        let _ = writeln!(m, "> {line}");
    }
    let _ = writeln!(m);
    for case in extra {
        let _ = writeln!(m, "![{}](img/{})\n", title(case), extra_chart_file(case));
    }
    let _ = writeln!(
        m,
        "| engine | case | dt | error (m) | CPU ms per simulated s |\n| --- | --- | --- | ---: | ---: |"
    );
    for p in &peers.points {
        let _ = writeln!(
            m,
            "| {} | {} | 1/{:.0} | {} | {:.2} |",
            p.engine,
            p.case,
            1.0 / p.dt,
            if p.error.is_finite() {
                format!("{:.3e}", p.error)
            } else {
                "diverged".into()
            },
            p.ms_per_sim_second
        );
    }
    let _ = writeln!(m);
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_comments_header_rows_and_diverged_points() {
        let text =
            "# made by vs-peers\n# on a machine\nengine,case,dt,error,cpu_ms_per_simulated_s\n\
                    Box2D v3 (SSE2),pyramid_20,0.016666668,1.5e-2,20.5\n\
                    rapier2d,pyramid_20,0.033333335,NaN,9.0\n\
                    tiltbox,stack_20,0.016666668,2e-2,1.0\n";
        let p = parse(text);
        assert_eq!(p.provenance, vec!["made by vs-peers", "on a machine"]);
        assert_eq!(p.points.len(), 3);
        assert!(p.points[1].error.is_nan());
        let pyramid = p.for_case("pyramid_20");
        assert_eq!(pyramid.len(), 2);
        assert!(
            p.for_case("stack_20").is_empty(),
            "tiltbox rows are the report's own"
        );
        assert!(load(Path::new("/nonexistent/peers.csv")).points.is_empty());
    }

    #[test]
    fn extra_charts_draw_cases_the_report_does_not_sweep() {
        let text = "engine,case,dt,error,cpu_ms_per_simulated_s\n\
                    Box2D v3 (SSE2),mass_ratio_100,0.016666668,1e-2,0.5\n\
                    rapier2d,mass_ratio_100,0.016666668,0,0.6\n\
                    tiltbox,mass_ratio_100,0.008333334,3e-3,1.2\n\
                    rapier2d,pyramid_20,0.016666668,1e-2,20\n";
        let dir = std::env::temp_dir().join(format!("tiltbox-peers-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let drawn = extra_charts(&parse(text), &["pyramid_20"], &dir).unwrap();
        assert_eq!(drawn, vec!["mass_ratio_100".to_string()]);
        let svg = std::fs::read_to_string(dir.join(extra_chart_file("mass_ratio_100"))).unwrap();
        assert!(svg.contains("rapier2d") && svg.contains("Box2D v3 (SSE2)"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
