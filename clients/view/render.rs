//! The viewer's drawing, a pure function: (world view, status, area) to ratatui cells. Tests
//! render it into ratatui's `TestBackend`.
//!
//! Bodies are filled shapes on a braille canvas (2 x 4 dots per cell), in each body's colour:
//! rotated rectangles, discs with a rotation mark (a radius line of unlit dots along the
//! body's local x axis, so rolling shows), capsules (stadiums) and polygons. Each shape is
//! painted dot by dot over its bounding box (clipped to the canvas), a dot lit when its centre
//! passes the shape's point-in-shape test grown by half a dot, so thin bodies still show.
//! Static bodies are painted first and dynamic ones over them (a cell has one colour: the
//! last body painted in it). The view fits the walls (the static bodies; every body if there
//! are none) into the area with equal scale on both axes: a braille dot is about as wide as it
//! is tall, so the same metres per dot horizontally and vertically keep the shapes square. The
//! last row is the status line.

use super::world::{capsule_half_core, ViewBody, WorldView};
use crate::protocol::{BodyRef, ShapeSpec, Vector};
use ratatui::buffer::Buffer;
use ratatui::layout::{Rect, Size};
use ratatui::style::{Color, Modifier, Style};
use ratatui::symbols::Marker;
use ratatui::text::Line;
use ratatui::widgets::canvas::{Canvas, Line as Segment, Painter, Shape};
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
    /// What the keys do, last on the line (`q quits` when empty).
    pub keys: &'static str,
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

/// How a shape is tested, in the body's frame (x along the body's angle, metres).
#[derive(Debug)]
enum Fill {
    /// Half extents of a rectangle.
    Rect { hx: f64, hy: f64 },
    /// A disc, with its rotation mark: a radius line of unlit dots along local +x, from a
    /// little out of the centre through the rim, when the radius is at least two dots.
    Circle { r: f64 },
    /// A capsule: its core segment runs from `(-half, 0)` to `(half, 0)`.
    Capsule { half: f64, r: f64 },
    /// A convex polygon as half-planes `n . p <= c` (`n` the unit outward normal of an edge).
    Convex { planes: Vec<(f64, f64, f64)> },
    /// A segment from `a` to `b` grown by `r` (a piece of a chain, or a lone one).
    Segment {
        a: (f64, f64),
        b: (f64, f64),
        r: f64,
    },
    /// Any other polygon (not convex, winding round more than once, no area, under three
    /// vertices): even-odd inside, or within the tolerance of an edge.
    General { vertices: Vec<(f64, f64)> },
    /// Several shapes, each with its place in the body's frame: `(x, y, cos, sin)` of its
    /// offset and angle.
    Compound {
        parts: Vec<((f64, f64, f64, f64), Fill)>,
    },
}

impl Fill {
    /// The test for a wire shape (a convex polygon of either winding gets half-planes).
    fn of(shape: &ShapeSpec) -> Fill {
        match shape {
            ShapeSpec::Rect { width, height } => Fill::Rect {
                hx: *width as f64 * 0.5,
                hy: *height as f64 * 0.5,
            },
            ShapeSpec::Circle { radius } => Fill::Circle { r: *radius as f64 },
            ShapeSpec::Capsule { length, radius } => Fill::Capsule {
                half: capsule_half_core(*length, *radius) as f64,
                r: *radius as f64,
            },
            ShapeSpec::Polygon { vertices } => {
                let v: Vec<(f64, f64)> =
                    vertices.iter().map(|p| (p.x as f64, p.y as f64)).collect();
                match convex_planes(&v) {
                    Some(planes) => Fill::Convex { planes },
                    None => Fill::General { vertices: v },
                }
            }
            ShapeSpec::Segment { a, b, radius, .. } => Fill::Segment {
                a: (a.x as f64, a.y as f64),
                b: (b.x as f64, b.y as f64),
                r: *radius as f64,
            },
            ShapeSpec::Compound { parts } => Fill::Compound {
                parts: parts
                    .iter()
                    .map(|p| {
                        let (s, c) = (p.angle as f64).sin_cos();
                        let place = (p.offset.x as f64, p.offset.y as f64, c, s);
                        (place, Fill::of(&p.shape))
                    })
                    .collect(),
            },
        }
    }

    /// Whether the point `(x, y)` (body frame) is painted, the shape grown by `tol` (half a
    /// dot, so that thin bodies still show as a line of dots); `dot` is the dot pitch (m).
    fn contains(&self, x: f64, y: f64, tol: f64, dot: f64) -> bool {
        match self {
            Fill::Rect { hx, hy } => x.abs() <= hx + tol && y.abs() <= hy + tol,
            Fill::Circle { r } => {
                let rr = r + tol;
                if x * x + y * y > rr * rr {
                    return false;
                }
                // the mark, a dot wide (two where the axis runs half-way between two rows of
                // dots: never none); too small a disc would be all mark
                let mark = *r >= 2.0 * dot && x > (0.35 * r).max(dot) && y.abs() <= 0.55 * dot;
                !mark
            }
            Fill::Capsule { half, r } => {
                let ex = (x.abs() - half).max(0.0);
                let rr = r + tol;
                ex * ex + y * y <= rr * rr
            }
            Fill::Convex { planes } => planes.iter().all(|(nx, ny, c)| nx * x + ny * y <= c + tol),
            Fill::Segment { a, b, r } => {
                // Distance from the point to the segment, against the radius grown by tol.
                let (ex, ey) = (b.0 - a.0, b.1 - a.1);
                let len2 = (ex * ex + ey * ey).max(f64::MIN_POSITIVE);
                let t = (((x - a.0) * ex + (y - a.1) * ey) / len2).clamp(0.0, 1.0);
                let (dx, dy) = (x - a.0 - t * ex, y - a.1 - t * ey);
                // Half a dot's diagonal: the nearest dot to any point of a slanted line lies
                // within it, so a bare line shows unbroken.
                let rr = r + tol * std::f64::consts::SQRT_2;
                dx * dx + dy * dy <= rr * rr
            }
            Fill::General { vertices } => {
                point_in_polygon(vertices, x, y) || near_outline(vertices, x, y, tol)
            }
            Fill::Compound { parts } => parts.iter().any(|&((ox, oy, c, s), ref fill)| {
                let (dx, dy) = (x - ox, y - oy);
                fill.contains(c * dx + s * dy, -s * dx + c * dy, tol, dot)
            }),
        }
    }
}

/// The half-planes of a convex polygon with either winding (`None` when it has fewer than three
/// vertices, no area, is not convex or winds round more than once). Zero-length edges are
/// skipped.
fn convex_planes(v: &[(f64, f64)]) -> Option<Vec<(f64, f64, f64)>> {
    let n = v.len();
    if n < 3 {
        return None;
    }
    let edge = |i: usize| {
        let (a, b) = (v[i], v[(i + 1) % n]);
        (b.0 - a.0, b.1 - a.1)
    };
    let area2: f64 = (0..n)
        .map(|i| v[i].0 * v[(i + 1) % n].1 - v[(i + 1) % n].0 * v[i].1)
        .sum();
    let scale = (0..n)
        .map(|i| edge(i).0.hypot(edge(i).1))
        .fold(0.0, f64::max);
    if area2.is_nan() || area2.abs() <= 1e-9 * scale * scale {
        return None; // no area
    }
    let sign = area2.signum();
    let mut planes = Vec::with_capacity(n);
    let mut turning = 0.0;
    for (i, &(vx, vy)) in v.iter().enumerate() {
        let (ex, ey) = edge(i);
        let (fx, fy) = edge((i + 1) % n);
        let cross = ex * fy - ey * fx;
        if sign * cross < -1e-9 * scale * scale {
            return None; // a reflex vertex
        }
        turning += (sign * cross).atan2(ex * fx + ey * fy);
        let len = ex.hypot(ey);
        if len <= 1e-12 * scale {
            continue;
        }
        // outward normal: right of the edge for counter-clockwise, left for clockwise
        let (nx, ny) = (sign * ey / len, -sign * ex / len);
        planes.push((nx, ny, nx * vx + ny * vy));
    }
    // once round: a star turns the same way at every vertex but twice round
    (turning < 2.5 * std::f64::consts::PI).then_some(planes)
}

/// Even-odd rule (crossing number).
fn point_in_polygon(v: &[(f64, f64)], x: f64, y: f64) -> bool {
    let n = v.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (v[i], v[(i + 1) % n]);
        if (a.1 > y) != (b.1 > y) && x < a.0 + (y - a.1) / (b.1 - a.1) * (b.0 - a.0) {
            inside = !inside;
        }
    }
    inside
}

/// Whether `(x, y)` is within `tol` of an edge (or of the only vertex).
fn near_outline(v: &[(f64, f64)], x: f64, y: f64, tol: f64) -> bool {
    let n = v.len();
    (0..n).any(|i| {
        let (a, b) = (v[i], v[(i + 1) % n]);
        let (ex, ey) = (b.0 - a.0, b.1 - a.1);
        let (px, py) = (x - a.0, y - a.1);
        let len2 = ex * ex + ey * ey;
        let t = if len2 > 0.0 {
            ((px * ex + py * ey) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (dx, dy) = (px - t * ex, py - t * ey);
        dx * dx + dy * dy <= tol * tol
    })
}

/// One body's filled shape, painted dot by dot: every dot of its bounding box (grown by half a
/// dot, clipped to the canvas) whose centre passes the shape's point-in-shape test.
struct FilledShape {
    fill: Fill,
    /// World bounding box `(min_x, min_y, max_x, max_y)`, metres.
    aabb: (f64, f64, f64, f64),
    centre: (f64, f64),
    angle: f64,
    colour: Color,
}

impl FilledShape {
    /// `None` when the body has nothing to draw (no vertices, numbers not finite).
    fn of(b: &ViewBody) -> Option<FilledShape> {
        let (x0, y0, x1, y1) = b.aabb()?;
        let c = b.info.colour;
        let centre = (b.x as f64, b.y as f64);
        let angle = b.angle as f64;
        if !(centre.0.is_finite() && centre.1.is_finite() && angle.is_finite()) {
            return None;
        }
        Some(FilledShape {
            fill: Fill::of(&b.info.shape),
            aabb: (x0 as f64, y0 as f64, x1 as f64, y1 as f64),
            centre,
            angle,
            colour: Color::Rgb(c.r, c.g, c.b),
        })
    }
}

impl Shape for FilledShape {
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
        let dot = dx.max(dy);
        // half a dot of tolerance: thin bodies still show as a line of dots
        let tol = 0.5 * dot;
        let (x0, y0, x1, y1) = self.aabb;
        let (x0, y0, x1, y1) = (x0 - tol, y0 - tol, x1 + tol, y1 + tol);
        if x1 < l || x0 > r || y1 < b || y0 > t {
            return; // off the canvas
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
        for gy in gy0..=gy1 {
            let wy = t - gy as f64 * dy - self.centre.1;
            for gx in gx0..=gx1 {
                let wx = l + gx as f64 * dx - self.centre.0;
                let (lx, ly) = (c * wx + s * wy, -s * wx + c * wy);
                if self.fill.contains(lx, ly, tol, dot) {
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
    let keys = if status.keys.is_empty() {
        "q quits"
    } else {
        status.keys
    };
    if !status.alive {
        return format!(
            " {world} │ waiting for server at {} │ {keys}",
            status.endpoint
        );
    }
    let Some(v) = view else {
        return format!(" {world} │ joining (asking …/scene) │ {keys}");
    };
    let g = v.gravity;
    let latency = match status.latency {
        Some(d) => format!("{:.1} ms", d.as_secs_f64() * 1e3),
        None => "-".into(),
    };
    // most useful first: a narrow terminal cuts the end
    format!(
        " {world} │ frame {} │ {} bodies │ g {} {:.2} │ {:.0} Hz │ latency {latency} │ {} │ {keys}",
        v.frame,
        v.bodies.len(),
        gravity_arrow(g),
        g.x.hypot(g.y),
        status.rate_hz,
        v.scene,
    )
}

/// The world point (m) at the middle of terminal cell (`column`, `row`) of a screen of `area`
/// drawn by [`render`] (the canvas above the status line). None off the canvas or before the
/// scene is known.
pub fn cell_to_world(view: &WorldView, area: Rect, column: u16, row: u16) -> Option<(f32, f32)> {
    let canvas = Rect {
        height: area.height.checked_sub(1)?,
        ..area
    };
    let inside = column >= canvas.x && column < canvas.x + canvas.width;
    if !inside || row < canvas.y || row >= canvas.y + canvas.height {
        return None;
    }
    let vp = Viewport::fit(view.bounds()?, canvas.as_size());
    let fx = ((column - canvas.x) as f64 + 0.5) / canvas.width as f64;
    let fy = ((row - canvas.y) as f64 + 0.5) / canvas.height as f64;
    let x = vp.x_bounds[0] + fx * (vp.x_bounds[1] - vp.x_bounds[0]);
    let y = vp.y_bounds[1] - fy * (vp.y_bounds[1] - vp.y_bounds[0]);
    Some((x as f32, y as f32))
}

/// The dynamic body of `view` under world point (`x`, `y`), within `slop` metres, if any (the
/// last drawn, so the one on top).
pub fn body_at(view: &WorldView, (x, y): (f32, f32), slop: f32) -> Option<BodyRef> {
    let mut found = None;
    for b in view.bodies.values().filter(|b| !b.info.is_static) {
        let (s, c) = (-(b.angle as f64)).sin_cos();
        let (dx, dy) = ((x - b.x) as f64, (y - b.y) as f64);
        let (lx, ly) = (c * dx - s * dy, s * dx + c * dy);
        if Fill::of(&b.info.shape).contains(lx, ly, slop as f64, slop as f64) {
            found = Some(b.info.id);
        }
    }
    found
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
    let shapes: Vec<(bool, FilledShape)> = view
        .bodies
        .values()
        .filter_map(|b| Some((b.info.is_static, FilledShape::of(b)?)))
        .collect();
    // Joints: a white line from anchor to anchor, over the bodies (a hinge is a dot).
    let joints: Vec<Segment> = view
        .joints
        .values()
        .filter_map(|j| view.joint_anchors(j))
        .map(|((ax, ay), (bx, by))| Segment {
            x1: ax as f64,
            y1: ay as f64,
            x2: bx as f64,
            y2: by as f64,
            color: Color::White,
        })
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
            for j in &joints {
                ctx.draw(j);
            }
        })
        .render(canvas_area, buf);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn poly(v: &[(f32, f32)]) -> Fill {
        Fill::of(&ShapeSpec::Polygon {
            vertices: v.iter().map(|&(x, y)| Vector::new(x, y)).collect(),
        })
    }

    /// A 10 m x 5 m box (two static floors, an L-shaped compound on the left, a rod hanging from
    /// the world at (5, 4.5) to a disc at (5, 2)) rendered into 40 x 13 cells: the joint's line
    /// is white cells between its anchors, and the L's second shape, 2.5 m above its first, is
    /// painted in the L's colour.
    #[test]
    fn joints_are_white_lines_and_every_shape_of_a_compound_is_painted() {
        use crate::protocol::{
            BodyInfo, BodyRef, Colour, JointEnd, JointInfo, JointKindSpec, JointRef, JointSpec,
            PartShape, SceneState,
        };
        let id = |index| BodyRef {
            index,
            generation: 0,
        };
        let rect = |w, h| ShapeSpec::Rect {
            width: w,
            height: h,
        };
        let mut l = BodyInfo::wall(
            id(2),
            ShapeSpec::Compound {
                parts: vec![
                    PartShape {
                        shape: rect(1.0, 0.5),
                        offset: Vector::new(0.0, 0.0),
                        angle: 0.0,
                    },
                    PartShape {
                        shape: rect(1.0, 1.0),
                        offset: Vector::new(0.0, 2.5),
                        angle: 0.0,
                    },
                ],
            },
            Vector::new(1.5, 1.0),
        );
        l.colour = Colour::new(0, 200, 0);
        let mut disc = BodyInfo::wall(
            id(3),
            ShapeSpec::Circle { radius: 0.3 },
            Vector::new(5.0, 2.0),
        );
        (disc.is_static, disc.colour) = (false, Colour::new(200, 0, 0));
        let mut view = WorldView::from_scene(SceneState {
            world: "w".into(),
            scene: "s".into(),
            frame: 1,
            time: 0.0,
            gravity: Vector::new(0.0, -9.81),
            bodies: vec![
                BodyInfo::wall(id(0), rect(10.0, 0.5), Vector::new(5.0, 0.0)),
                BodyInfo::wall(id(1), rect(10.0, 0.5), Vector::new(5.0, 5.0)),
                l,
                disc,
            ],
        });
        view.add_joints(&[JointInfo {
            id: JointRef {
                index: 0,
                generation: 0,
            },
            joint: JointSpec {
                a: JointEnd::World,
                b: JointEnd::Live(id(3)),
                anchor_a: Vector::new(5.0, 4.5),
                anchor_b: Vector::new(0.0, 0.0),
                kind: JointKindSpec::Distance {
                    length: Some(2.5),
                    spring: None,
                    limit: None,
                },
                collide_connected: false,
                break_force: None,
                break_torque: None,
            },
        }]);
        let status = Status {
            world: "w".into(),
            endpoint: String::new(),
            alive: true,
            rate_hz: 60.0,
            latency: None,
            keys: "",
        };
        let area = Rect::new(0, 0, 40, 13);
        let mut buf = Buffer::empty(area);
        render(Some(&view), &status, area, &mut buf);
        let vp = Viewport::fit(view.bounds().unwrap(), Rect::new(0, 0, 40, 12).as_size());
        let cell = |x: f64, y: f64| {
            let col = (x - vp.x_bounds[0]) / (vp.x_bounds[1] - vp.x_bounds[0]) * 40.0;
            let row = (vp.y_bounds[1] - y) / (vp.y_bounds[1] - vp.y_bounds[0]) * 12.0;
            buf[(col as u16, row as u16)].fg
        };
        // the rod, half-way between its anchors (the disc is 0.3 m, below 3.5 m)
        assert_eq!(cell(5.0, 3.5), Color::White, "the joint's line");
        assert_eq!(
            cell(1.5, 3.5),
            Color::Rgb(0, 200, 0),
            "the L's second shape"
        );
        assert_ne!(
            cell(1.5, 2.1),
            Color::Rgb(0, 200, 0),
            "between the L's shapes"
        );
    }

    #[test]
    fn point_in_shape_tests_match_the_geometry() {
        let (tol, dot) = (0.0, 0.1);
        let rect = Fill::of(&ShapeSpec::Rect {
            width: 2.0,
            height: 1.0,
        });
        assert!(rect.contains(0.99, 0.49, tol, dot));
        assert!(!rect.contains(1.01, 0.0, tol, dot) && !rect.contains(0.0, 0.51, tol, dot));
        // the tolerance grows every shape by that much
        assert!(rect.contains(1.04, 0.0, 0.05, dot));

        let disc = Fill::of(&ShapeSpec::Circle { radius: 1.0 });
        assert!(disc.contains(0.0, 0.0, tol, dot) && disc.contains(0.0, -0.99, tol, dot));
        assert!(disc.contains(-0.7, 0.7, tol, dot));
        assert!(!disc.contains(0.72, 0.72, tol, dot), "bounding-box corner");
        // the mark: along +x, beyond the centre; not along -x or y
        assert!(!disc.contains(0.6, 0.0, tol, dot) && !disc.contains(0.99, 0.04, tol, dot));
        assert!(disc.contains(0.05, 0.0, tol, dot) && disc.contains(0.6, 0.1, tol, dot));
        assert!(disc.contains(-0.6, 0.0, tol, dot) && disc.contains(0.0, 0.6, tol, dot));
        // a disc under two dots across has no mark
        let small = Fill::of(&ShapeSpec::Circle { radius: 0.15 });
        assert!(small.contains(0.12, 0.0, tol, dot));

        let capsule = Fill::of(&ShapeSpec::Capsule {
            length: 4.0,
            radius: 0.5,
        });
        assert!(capsule.contains(1.99, 0.0, tol, dot) && capsule.contains(-1.5, 0.49, tol, dot));
        assert!(capsule.contains(1.5 + 0.35, 0.35, tol, dot));
        assert!(
            !capsule.contains(1.9, 0.45, tol, dot),
            "rounded end, not a box"
        );
        assert!(!capsule.contains(2.01, 0.0, tol, dot) && !capsule.contains(0.0, 0.51, tol, dot));
    }

    #[test]
    fn polygons_of_either_winding_and_non_convex_ones_are_filled() {
        let (tol, dot) = (0.0, 0.1);
        let ccw = [(-1.0, -1.0), (2.0, -1.0), (-1.0, 2.0)];
        let mut cw = ccw;
        cw.reverse();
        for (name, f) in [("ccw", poly(&ccw)), ("cw", poly(&cw))] {
            assert!(matches!(f, Fill::Convex { .. }), "{name}");
            assert!(f.contains(0.0, 0.0, tol, dot), "{name} centroid");
            assert!(f.contains(-0.95, -0.95, tol, dot), "{name} right angle");
            assert!(!f.contains(1.0, 1.0, tol, dot), "{name} far corner");
            assert!(!f.contains(-1.05, 0.0, tol, dot), "{name} left of it");
        }
        // an L (not convex): the notch is empty, both arms are filled
        let l = poly(&[
            (0.0, 0.0),
            (2.0, 0.0),
            (2.0, 1.0),
            (1.0, 1.0),
            (1.0, 2.0),
            (0.0, 2.0),
        ]);
        assert!(matches!(l, Fill::General { .. }));
        assert!(l.contains(1.5, 0.5, tol, dot) && l.contains(0.5, 1.5, tol, dot));
        assert!(!l.contains(1.5, 1.5, tol, dot));
        // a pentagram turns left at every vertex but is no convex polygon: its points are
        // filled (even-odd leaves the inner pentagon empty)
        let star: Vec<(f32, f32)> = (0..5)
            .map(|k| {
                let a = std::f32::consts::FRAC_PI_2 + k as f32 * 4.0 * std::f32::consts::PI / 5.0;
                (a.cos(), a.sin())
            })
            .collect();
        let star = poly(&star);
        assert!(matches!(star, Fill::General { .. }));
        assert!(star.contains(0.0, 0.9, tol, dot) && !star.contains(0.0, 0.0, tol, dot));
        // no area: drawn as its outline within the tolerance
        let flat = poly(&[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)]);
        assert!(flat.contains(1.5, 0.02, 0.05, dot) && !flat.contains(1.5, 0.2, 0.05, dot));
        assert!(!poly(&[]).contains(0.0, 0.0, 0.05, dot));
    }
}
