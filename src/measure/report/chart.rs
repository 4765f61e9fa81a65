//! The report's charts: error against run time per simulated second, log-log, one curve per
//! solver configuration, drawn to SVG with plotters. Runs that diverged are drawn as red
//! crosses at the top edge, never dropped.

use super::peers;
use crate::measure::accuracy::sweep::{CaseSweep, Point};
use plotters::prelude::*;
use std::io;
use std::path::Path;

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
pub const ERROR_FLOOR: f64 = 1e-9;

/// A plotters error as an I/O error, `chart: ` and what plotters said.
pub(super) fn plot_err<E: std::fmt::Debug>(e: E) -> io::Error {
    io::Error::other(format!("chart: {e:?}"))
}

/// Draw `chart`'s legend at `position` in the report's style: white, framed, 13 px text.
pub(super) fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> io::Result<()> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(plot_err)
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
    legend(&mut chart, SeriesLabelPosition::LowerLeft)?;
    root.present().map_err(plot_err)?;
    Ok(())
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

/// File name of a case's chart.
pub fn chart_file(name: &str) -> String {
    format!("accuracy-{}.svg", name.replace('_', "-"))
}
