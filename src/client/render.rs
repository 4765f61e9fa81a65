//! The viewer's drawing, a pure function: (world view, status, area) to ratatui cells. Tests
//! render it into ratatui's `TestBackend`.
//!
//! Bodies are filled rotated rectangles on a braille canvas (2 x 4 dots per cell), in each
//! body's colour, static ones first and dynamic ones over them (a cell has one colour: the
//! last body painted in it). The view fits the walls (the
//! static bodies; every body if there are none) into the area with equal scale on both axes:
//! a braille dot is about as wide as it is tall, so the same metres per dot horizontally and
//! vertically keep the shapes square. The last row is the status line.

use super::world::{ViewBody, WorldView};
use crate::protocol::Vector;
use ratatui::buffer::Buffer;
use ratatui::layout::{Rect, Size};
use ratatui::style::{Color, Modifier, Style};
use ratatui::symbols::Marker;
use ratatui::text::Line;
use ratatui::widgets::canvas::{Canvas, Painter, Shape};
use ratatui::widgets::{Paragraph, Widget};
use std::time::Duration;

/// What the status line says besides the world itself.
#[derive(Clone, Debug, Default)]
pub struct Status {
    /// World name (shown even before the scene reply).
    pub world: String,
    /// Where the daemon is expected (shown while waiting).
    pub endpoint: String,
    /// Whether a daemon's liveliness token is visible.
    pub alive: bool,
    /// Snapshots received per second, over the last second.
    pub rate_hz: f64,
    /// Latency of the latest snapshot, when it could be measured.
    pub latency: Option<Duration>,
}

/// The world-to-canvas mapping for an area: the canvas bounds, in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewport {
    /// Left and right edges (m).
    pub x_bounds: [f64; 2],
    /// Bottom and top edges (m).
    pub y_bounds: [f64; 2],
}

impl Viewport {
    /// Fit `(min_x, min_y, max_x, max_y)`, with a small margin, into a canvas of `cells`
    /// braille cells, with equal metres per dot on both axes, centred.
    pub fn fit(bounds: (f32, f32, f32, f32), cells: Size) -> Viewport {
        let (x0, y0, x1, y1) = bounds;
        let (x0, y0, x1, y1) = (x0 as f64, y0 as f64, x1 as f64, y1 as f64);
        let margin = 0.02 * (x1 - x0).max(y1 - y0).max(1e-3);
        let (bw, bh) = (x1 - x0 + 2.0 * margin, y1 - y0 + 2.0 * margin);
        let dots_x = (2.0 * cells.width.max(1) as f64 - 1.0).max(1.0);
        let dots_y = (4.0 * cells.height.max(1) as f64 - 1.0).max(1.0);
        let per_dot = (bw / dots_x).max(bh / dots_y);
        let (cx, cy) = ((x0 + x1) * 0.5, (y0 + y1) * 0.5);
        let (hw, hh) = (per_dot * dots_x * 0.5, per_dot * dots_y * 0.5);
        Viewport {
            x_bounds: [cx - hw, cx + hw],
            y_bounds: [cy - hh, cy + hh],
        }
    }
}

/// A filled rotated rectangle, painted dot by dot.
struct FilledRect {
    corners: [(f32, f32); 4],
    centre: (f64, f64),
    angle: f64,
    half: (f64, f64),
    colour: Color,
}

impl FilledRect {
    fn of(b: &ViewBody) -> FilledRect {
        let (width, height) = match &b.info.shape {
            crate::protocol::ShapeSpec::Rect { width, height } => (*width, *height),
            _ => (0.1, 0.1), // TEMPORARY until the viewer learns the other shapes
        };
        let c = b.info.colour;
        FilledRect {
            corners: b.corners(),
            centre: (b.x as f64, b.y as f64),
            angle: b.angle as f64,
            half: (width as f64 * 0.5, height as f64 * 0.5),
            colour: Color::Rgb(c.r, c.g, c.b),
        }
    }
}

impl Shape for FilledRect {
    fn draw(&self, painter: &mut Painter) {
        let ([l, r], [b, t]) = {
            let (x, y) = painter.bounds();
            (*x, *y)
        };
        // the grid's last dot, from the bottom-right corner of the bounds
        let Some((gx_max, gy_max)) = painter.get_point(r, b) else {
            return;
        };
        if gx_max == 0 || gy_max == 0 {
            return;
        }
        let (dx, dy) = ((r - l) / gx_max as f64, (t - b) / gy_max as f64);
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (x, y) in self.corners {
            let (x, y) = (x as f64, y as f64);
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
        if !(x0.is_finite() && x1.is_finite() && y0.is_finite() && y1.is_finite()) {
            return;
        }
        let clamp = |v: f64, max: usize| v.clamp(0.0, max as f64) as usize;
        let (gx0, gx1) = (
            clamp(((x0 - l) / dx).floor(), gx_max),
            clamp(((x1 - l) / dx).ceil(), gx_max),
        );
        let (gy0, gy1) = (
            clamp(((t - y1) / dy).floor(), gy_max),
            clamp(((t - y0) / dy).ceil(), gy_max),
        );
        let (s, c) = self.angle.sin_cos();
        // half a dot of tolerance: thin bodies still show as a line of dots
        let (hx, hy) = (self.half.0 + dx * 0.5, self.half.1 + dy * 0.5);
        for gy in gy0..=gy1 {
            let wy = t - gy as f64 * dy - self.centre.1;
            for gx in gx0..=gx1 {
                let wx = l + gx as f64 * dx - self.centre.0;
                let (lx, ly) = (c * wx + s * wy, -s * wx + c * wy);
                if lx.abs() <= hx && ly.abs() <= hy {
                    painter.paint(gx, gy, self.colour);
                }
            }
        }
    }
}

/// An arrow for the direction of `g` (8 directions), or `·` when it is (almost) zero.
pub fn gravity_arrow(g: Vector) -> char {
    if g.x.hypot(g.y) < 1e-3 {
        return '·';
    }
    let octant = (g.y.atan2(g.x) / std::f32::consts::FRAC_PI_4).round() as i32;
    ['→', '↗', '↑', '↖', '←', '↙', '↓', '↘'][octant.rem_euclid(8) as usize]
}

/// The status line's text.
pub fn status_text(view: Option<&WorldView>, status: &Status) -> String {
    let world = view.map_or(status.world.as_str(), |v| v.world.as_str());
    if !status.alive {
        return format!(
            " {world} │ waiting for server at {} │ q quits",
            status.endpoint
        );
    }
    let Some(v) = view else {
        return format!(" {world} │ joining (asking …/scene) │ q quits");
    };
    let g = v.gravity;
    let latency = match status.latency {
        Some(d) => format!("{:.1} ms", d.as_secs_f64() * 1e3),
        None => "-".into(),
    };
    // most useful first: a narrow terminal cuts the end
    format!(
        " {world} │ frame {} │ {} bodies │ g {} {:.2} │ {:.0} Hz │ latency {latency} │ {} │ q quits",
        v.frame,
        v.bodies.len(),
        gravity_arrow(g),
        g.x.hypot(g.y),
        status.rate_hz,
        v.scene,
    )
}

/// Draw the view (or a waiting message) and the status line into `area` of `buf`.
pub fn render(view: Option<&WorldView>, status: &Status, area: Rect, buf: &mut Buffer) {
    if area.height == 0 || area.width == 0 {
        return;
    }
    let canvas_area = Rect {
        height: area.height - 1,
        ..area
    };
    let status_area = Rect {
        y: area.y + area.height - 1,
        height: 1,
        ..area
    };
    Paragraph::new(Line::from(status_text(view, status)))
        .style(Style::default().add_modifier(Modifier::REVERSED))
        .render(status_area, buf);
    if canvas_area.height == 0 {
        return;
    }
    let message = if !status.alive {
        Some(format!(
            "waiting for server (world {}, {})",
            status.world, status.endpoint
        ))
    } else if view.is_none() {
        Some("joining…".to_owned())
    } else {
        None
    };
    if let Some(m) = message {
        let y = canvas_area.y + canvas_area.height / 2;
        let w = (m.chars().count() as u16).min(canvas_area.width);
        let x = canvas_area.x + (canvas_area.width - w) / 2;
        Paragraph::new(m).render(Rect::new(x, y, w, 1), buf);
        return;
    }
    let Some(view) = view else { return };
    let Some(bounds) = view.bounds() else { return };
    let vp = Viewport::fit(bounds, canvas_area.as_size());
    let shapes: Vec<(bool, FilledRect)> = view
        .bodies
        .values()
        .map(|b| (b.info.is_static, FilledRect::of(b)))
        .collect();
    Canvas::default()
        .marker(Marker::Braille)
        .x_bounds(vp.x_bounds)
        .y_bounds(vp.y_bounds)
        .paint(|ctx| {
            // one layer, static bodies first: a cell shared by a wall and a brick keeps the
            // dots of both and takes the brick's colour
            for (_, s) in shapes.iter().filter(|(st, _)| *st) {
                ctx.draw(s);
            }
            for (_, s) in shapes.iter().filter(|(st, _)| !*st) {
                ctx.draw(s);
            }
        })
        .render(canvas_area, buf);
}
