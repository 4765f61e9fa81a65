//! The viewer: its pure drawing into ratatui's TestBackend, and `tiltbox-view --plain`
//! against an in-process daemon (real Zenoh over TCP loopback, port 17482, scouting off).
#![cfg(all(feature = "net", feature = "cli", feature = "tui"))]

mod common;

use common::net::{daemon_config, endpoint, next, open, serve, subscribe_snapshots};
use ratatui::backend::TestBackend;
use ratatui::layout::Size;
use ratatui::style::Color;
use ratatui::Terminal;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use tiltbox::client::view::plain::parse_line;
use tiltbox::client::view::render::{render, Status, Viewport};
use tiltbox::client::view::world::WorldView;
use tiltbox::protocol::*;

const WALL: Colour = Colour {
    r: 90,
    g: 90,
    b: 100,
};
const RED: Colour = Colour {
    r: 214,
    g: 69,
    b: 65,
};
const BLUE: Colour = Colour {
    r: 46,
    g: 134,
    b: 222,
};

fn body(
    index: u32,
    is_static: bool,
    colour: Colour,
    pos: (f32, f32),
    size: (f32, f32),
) -> BodyInfo {
    BodyInfo {
        id: BodyRef {
            index,
            generation: 0,
        },
        name: format!("b{index}"),
        shape: ShapeSpec::Rect {
            width: size.0,
            height: size.1,
        },
        is_static,
        colour,
        position: Vector::new(pos.0, pos.1),
        angle: 0.0,
        velocity: Vector::default(),
        angular_velocity: 0.0,
        mass: if is_static { 0.0 } else { 1.0 },
        friction: 0.5,
        restitution: 0.0,
    }
}

/// A box with inner corners (0, 0) and (20, 10), walls 1 m thick, and two bricks.
fn scene() -> SceneState {
    SceneState {
        world: "test".into(),
        scene: "Box".into(),
        frame: 10,
        time: 10.0 / 60.0,
        gravity: Vector::new(0.0, -9.81),
        bodies: vec![
            body(0, true, WALL, (10.0, -0.5), (22.0, 1.0)),
            body(1, true, WALL, (10.0, 10.5), (22.0, 1.0)),
            body(2, true, WALL, (-0.5, 5.0), (1.0, 10.0)),
            body(3, true, WALL, (20.5, 5.0), (1.0, 10.0)),
            body(4, false, RED, (4.0, 2.0), (2.0, 1.0)),
            body(5, false, BLUE, (16.0, 1.0), (1.0, 1.0)),
        ],
    }
}

fn rgb(c: Colour) -> Color {
    Color::Rgb(c.r, c.g, c.b)
}

fn draw(view: &WorldView, status: &Status, w: u16, h: u16) -> Terminal<TestBackend> {
    let mut t = Terminal::new(TestBackend::new(w, h)).unwrap();
    t.draw(|f| render(Some(view), status, f.area(), f.buffer_mut()))
        .unwrap();
    t
}

/// Cells (column, row) with foreground `c` and a braille glyph.
fn cells(t: &Terminal<TestBackend>, c: Colour) -> Vec<(u16, u16)> {
    let buf = t.backend().buffer();
    let mut out = Vec::new();
    for y in 0..buf.area.height {
        for x in 0..buf.area.width {
            let cell = &buf[(x, y)];
            let braille = cell
                .symbol()
                .chars()
                .next()
                .is_some_and(|ch| ('\u{2801}'..='\u{28ff}').contains(&ch));
            if cell.fg == rgb(c) && braille {
                out.push((x, y));
            }
        }
    }
    out
}

fn centroid(v: &[(u16, u16)]) -> (f32, f32) {
    let n = v.len() as f32;
    (
        v.iter().map(|c| c.0 as f32).sum::<f32>() / n,
        v.iter().map(|c| c.1 as f32).sum::<f32>() / n,
    )
}

/// Where world point (x, y) should land, interpolated between the cells the walls occupy:
/// the walls' outer edges are x = -1 and 21, y = -1 and 11.
fn expected_cell(walls: &[(u16, u16)], x: f32, y: f32) -> (f32, f32) {
    let c0 = walls.iter().map(|c| c.0).min().unwrap() as f32;
    let c1 = walls.iter().map(|c| c.0).max().unwrap() as f32 + 1.0;
    let r0 = walls.iter().map(|c| c.1).min().unwrap() as f32; // top (y = 11)
    let r1 = walls.iter().map(|c| c.1).max().unwrap() as f32 + 1.0; // bottom (y = -1)
    (
        c0 + (x + 1.0) / 22.0 * (c1 - c0) - 0.5,
        r0 + (11.0 - y) / 12.0 * (r1 - r0) - 0.5,
    )
}

#[test]
fn bricks_are_drawn_where_the_snapshot_puts_them_in_their_colours() {
    let mut view = WorldView::from_scene(scene());
    let status = Status {
        world: "test".into(),
        endpoint: "tcp/127.0.0.1:7447".into(),
        alive: true,
        rate_hz: 60.0,
        latency: Some(Duration::from_micros(250)),
        keys: tiltbox::client::view::control::KEY_HELP,
    };
    // the status line says what each key does (--control, and always in the demo)
    let line = tiltbox::client::view::render::status_text(Some(&view), &status);
    for what in [
        "roll",
        "lean",
        "landscape",
        "space brick",
        "R reset",
        "q quit",
    ] {
        assert!(line.contains(what), "{what}: {line}");
    }
    let t = draw(&view, &status, 72, 21);
    let walls = cells(&t, WALL);
    assert!(walls.len() > 100, "walls drawn: {}", walls.len());
    let red = cells(&t, RED);
    let blue = cells(&t, BLUE);
    assert!(!red.is_empty() && !blue.is_empty());
    for (cells, (x, y)) in [(&red, (4.0, 2.0)), (&blue, (16.0, 1.0))] {
        let (cx, cy) = centroid(cells);
        let (ex, ey) = expected_cell(&walls, x, y);
        assert!(
            (cx - ex).abs() <= 1.0 && (cy - ey).abs() <= 1.0,
            "drawn at ({cx}, {cy}), expected ({ex}, {ey})"
        );
    }
    // the red brick is 2 m x 1 m: about 6 cells wide: 22 m span ~65 columns
    let width = red.iter().map(|c| c.0).max().unwrap() - red.iter().map(|c| c.0).min().unwrap();
    assert!((4..=7).contains(&width), "red brick {width} cells wide");

    // a snapshot moves the red brick to the upper right and turns it upright; gravity right
    let s = Snapshot {
        frame: 11,
        time: 11.0 / 60.0,
        gravity: Vector::new(9.81, 0.0),
        keyframe: false,
        poses: vec![Pose {
            id: BodyRef {
                index: 4,
                generation: 0,
            },
            x: 14.0,
            y: 7.0,
            angle: std::f32::consts::FRAC_PI_2,
        }],
    };
    view.apply_snapshot(&s);
    let t = draw(&view, &status, 72, 21);
    let red = cells(&t, RED);
    let (cx, cy) = centroid(&red);
    let (ex, ey) = expected_cell(&walls, 14.0, 7.0);
    assert!(
        (cx - ex).abs() <= 1.0 && (cy - ey).abs() <= 1.0,
        "moved brick drawn at ({cx}, {cy}), expected ({ex}, {ey})"
    );
    // upright now: taller (in rows of 2 dots-per-... ) than wide in cells relative to before
    let width = red.iter().map(|c| c.0).max().unwrap() - red.iter().map(|c| c.0).min().unwrap();
    assert!(width <= 3, "upright brick {width} cells wide");
    let (ox, oy) = expected_cell(&walls, 4.0, 2.0);
    assert!(
        red.iter()
            .all(|c| (c.0 as f32 - ox).abs() > 3.0 || (c.1 as f32 - oy).abs() > 2.0),
        "nothing red left at the old place"
    );
    // the blue brick did not move
    assert!((centroid(&cells(&t, BLUE)).0 - expected_cell(&walls, 16.0, 1.0).0).abs() <= 1.0);
    // the status line: last row
    let buf = t.backend().buffer();
    let last: String = (0..buf.area.width)
        .map(|x| buf[(x, buf.area.height - 1)].symbol().to_string())
        .collect();
    for part in [
        "test",
        "frame 11",
        "6 bodies",
        "g → 9.81",
        "60 Hz",
        "latency 0.2 ms",
    ] {
        assert!(last.contains(part), "{part:?} in {last:?}");
    }
}

#[test]
fn waiting_for_server_is_shown_while_none_is_alive() {
    let status = Status {
        world: "test".into(),
        endpoint: "tcp/127.0.0.1:7447".into(),
        ..Status::default()
    };
    let mut t = Terminal::new(TestBackend::new(70, 10)).unwrap();
    t.draw(|f| render(None, &status, f.area(), f.buffer_mut()))
        .unwrap();
    let buf = t.backend().buffer();
    let text: String = (0..buf.area.height)
        .flat_map(|y| (0..buf.area.width).map(move |x| (x, y)))
        .map(|p| buf[p].symbol().to_string())
        .collect();
    assert!(text.contains("waiting for server"), "{text}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn plain_output_parses_back_to_the_poses_published() {
    let port = 17482;
    let server = serve(&daemon_config(port)).await;
    let keys = server.keys().clone();
    // our own record of what was published
    let session = open(port).await;
    let (mut snapshots, _sub) = subscribe_snapshots(&session, keys.poses()).await;
    next(&mut snapshots).await;
    // Keep the bricks moving while the viewer prints: left alone they sleep 2 s after the
    // daemon starts, and on a busy machine the viewer's 40 frames could all come after that,
    // leaving no poses to compare. Gravity turns a quarter turn a second.
    let tilting = {
        let (session, key) = (session.clone(), keys.gravity());
        tokio::spawn(async move {
            for i in 0u32.. {
                let a = 0.157 * i as f32;
                let g = SetGravity {
                    x: 9.81 * a.sin(),
                    y: -9.81 * a.cos(),
                };
                let _ = session.put(key.clone(), encode(&g).unwrap()).await;
                tokio::time::sleep(Duration::from_millis(100)).await;
            }
        })
    };

    let mut child = Command::new(env!("CARGO_BIN_EXE_tiltbox-view"))
        .args(["--plain", "--count", "40", "--connect"])
        .arg(endpoint(port))
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let lines = tokio::task::spawn_blocking(move || {
        BufReader::new(stdout)
            .lines()
            .map_while(Result::ok)
            .collect::<Vec<String>>()
    });
    let lines = tokio::time::timeout(Duration::from_secs(10), lines)
        .await
        .expect("40 lines within 10 s")
        .unwrap();
    tilting.abort();
    let status = child.wait().unwrap();
    assert!(status.success(), "{status}");
    assert_eq!(lines.len(), 40);

    let mut published: BTreeMap<u64, Snapshot> = BTreeMap::new();
    let end = Instant::now() + Duration::from_secs(5);
    let last_frame = parse_line(lines.last().unwrap()).unwrap().frame;
    while published.keys().next_back().is_none_or(|f| *f < last_frame) {
        assert!(
            Instant::now() < end,
            "our subscriber saw frame {last_frame}"
        );
        if let Ok(Some(s)) =
            tokio::time::timeout(Duration::from_millis(200), snapshots.recv()).await
        {
            published.insert(s.frame, s);
        }
    }
    let mut with_poses = 0;
    for line in &lines {
        assert!(
            line.bytes().all(|b| (0x20..0x7f).contains(&b)),
            "only printable ASCII: {line:?}"
        );
        let got = parse_line(line).unwrap();
        let Some(s) = published.get(&got.frame) else {
            continue; // published before our subscriber's window: nothing to compare
        };
        assert_eq!(got.time, s.time, "frame {}", got.frame);
        assert_eq!(got.poses, s.poses, "frame {}", got.frame);
        with_poses += usize::from(!got.poses.is_empty());
    }
    assert!(with_poses >= 5, "{with_poses} lines with poses compared");
    drop(_sub);
    let _ = session.close().await;
    server.shutdown().await.unwrap();
}

// ---- shapes: which braille dots each shape lights ----

const GREEN: Colour = Colour {
    r: 60,
    g: 180,
    b: 90,
};

/// A body of `shape` at `pos`, turned by `angle`.
fn shaped(index: u32, colour: Colour, pos: (f32, f32), angle: f32, shape: ShapeSpec) -> BodyInfo {
    let mut b = body(index, false, colour, pos, (1.0, 1.0));
    b.shape = shape;
    b.angle = angle;
    b
}

/// The walls and one green body of `shape` at `pos`, not turned.
fn walled_one(pos: (f32, f32), shape: ShapeSpec) -> WorldView {
    walled(vec![shaped(4, GREEN, pos, 0.0, shape)])
}

/// The walls of [`scene`] (inner corners (0, 0) and (20, 10)) and `bodies`.
fn walled(bodies: Vec<BodyInfo>) -> WorldView {
    let mut s = scene();
    s.bodies.truncate(4);
    s.bodies.extend(bodies);
    WorldView::from_scene(s)
}

/// A frame of `view` at 82 x 25 cells (164 x 96 dots, about 0.14 m a dot), read back dot by
/// dot.
struct Frame {
    t: Terminal<TestBackend>,
    x_bounds: [f64; 2],
    y_bounds: [f64; 2],
    dots: (usize, usize),
}

impl Frame {
    const W: u16 = 82;
    const H: u16 = 25;

    fn of(view: &WorldView) -> Frame {
        let status = Status {
            world: "test".into(),
            alive: true,
            ..Status::default()
        };
        let t = draw(view, &status, Frame::W, Frame::H);
        // the canvas is every row but the status line
        let vp = Viewport::fit(view.bounds().unwrap(), Size::new(Frame::W, Frame::H - 1));
        Frame {
            t,
            x_bounds: vp.x_bounds,
            y_bounds: vp.y_bounds,
            dots: (2 * Frame::W as usize, 4 * (Frame::H as usize - 1)),
        }
    }

    /// The colour of the cell holding the dot nearest world point (x, y) when that dot is lit
    /// (ratatui's mapping: a dot every `width / (dots - 1)` metres, from the top left).
    fn lit(&self, x: f32, y: f32) -> Option<Color> {
        let ([l, r], [b, t]) = (self.x_bounds, self.y_bounds);
        let gx = ((x as f64 - l) * (self.dots.0 - 1) as f64 / (r - l)).round() as usize;
        let gy = ((t - y as f64) * (self.dots.1 - 1) as f64 / (t - b)).round() as usize;
        assert!(
            gx < self.dots.0 && gy < self.dots.1,
            "({x}, {y}) on the canvas"
        );
        let cell = &self.t.backend().buffer()[((gx / 2) as u16, (gy / 4) as u16)];
        let ch = cell.symbol().chars().next().unwrap_or(' ');
        let bits = match ch {
            '\u{2800}'..='\u{28ff}' => ch as u32 - 0x2800,
            _ => 0,
        };
        // Unicode braille: dots 1-3 and 7 in the left column, 4-6 and 8 in the right
        const BIT: [[u32; 2]; 4] = [[0x01, 0x08], [0x02, 0x10], [0x04, 0x20], [0x40, 0x80]];
        (bits & BIT[gy % 4][gx % 2] != 0).then_some(cell.fg)
    }

    /// Lit dots in cells of colour `c`.
    fn count(&self, c: Colour) -> u32 {
        let buf = self.t.backend().buffer();
        (0..Frame::H - 1)
            .flat_map(|y| (0..Frame::W).map(move |x| (x, y)))
            .map(|p| &buf[p])
            .filter(|cell| cell.fg == rgb(c))
            .filter_map(|cell| cell.symbol().chars().next())
            .filter(|ch| ('\u{2800}'..='\u{28ff}').contains(ch))
            .map(|ch| (ch as u32 - 0x2800).count_ones())
            .sum()
    }
}

/// World point `centre + rotate(angle) (lx, ly)`.
fn at(centre: (f32, f32), angle: f32, lx: f32, ly: f32) -> (f32, f32) {
    let (s, c) = angle.sin_cos();
    (centre.0 + c * lx - s * ly, centre.1 + s * lx + c * ly)
}

fn turn(view: &mut WorldView, frame: u64, index: u32, pos: (f32, f32), angle: f32) {
    let s = Snapshot {
        frame,
        time: frame as f64 / 60.0,
        gravity: Vector::new(0.0, -9.81),
        keyframe: false,
        poses: vec![Pose {
            id: BodyRef {
                index,
                generation: 0,
            },
            x: pos.0,
            y: pos.1,
            angle,
        }],
    };
    assert_eq!(
        view.apply_snapshot(&s),
        tiltbox::client::view::world::Applied::Applied
    );
}

#[test]
fn a_circle_is_a_disc_where_a_square_of_its_width_fills_its_corners() {
    let (circle, square) = ((5.1, 5.2), (14.1, 5.2));
    let view = walled(vec![
        shaped(4, RED, circle, 0.0, ShapeSpec::Circle { radius: 1.5 }),
        shaped(
            5,
            BLUE,
            square,
            0.0,
            ShapeSpec::Rect {
                width: 3.0,
                height: 3.0,
            },
        ),
    ]);
    let f = Frame::of(&view);
    assert_eq!(f.lit(circle.0, circle.1), Some(rgb(RED)), "circle centre");
    assert_eq!(f.lit(square.0, square.1), Some(rgb(BLUE)), "square centre");
    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        // just inside the 3 m x 3 m bounding box's corners
        let (dx, dy) = (1.45 * sx, 1.45 * sy);
        assert_eq!(
            f.lit(square.0 + dx, square.1 + dy),
            Some(rgb(BLUE)),
            "square corner {sx},{sy}"
        );
        assert_eq!(
            f.lit(circle.0 + dx, circle.1 + dy),
            None,
            "circle's box corner {sx},{sy}"
        );
    }
    // the disc reaches its box's edges midway, but for the rotation mark along +x
    for (ex, ey) in [(-1.4, 0.0), (0.0, 1.4), (0.0, -1.4)] {
        assert_eq!(
            f.lit(circle.0 + ex, circle.1 + ey),
            Some(rgb(RED)),
            "circle rim ({ex}, {ey})"
        );
    }
    assert_eq!(f.lit(circle.0 + 1.4, circle.1), None, "the mark");
    // about pi/4 of the square's dots (the mark and the half-dot rims make it a little off)
    let ratio = f.count(RED) as f32 / f.count(BLUE) as f32;
    assert!((0.68..0.86).contains(&ratio), "disc / square dots {ratio}");
}

#[test]
fn a_circles_rotation_mark_turns_with_it() {
    // off the dot grid's half-way lines, so that "the nearest dot" is never a tie
    let c = (10.3, 5.2);
    let mut view = walled_one(c, ShapeSpec::Circle { radius: 2.0 });
    // local +x is marked: an unlit radius from a little out of the centre to the rim
    let marked = |f: &Frame, angle: f32| -> Vec<bool> {
        [0.0f32, 1.0, 2.0, 3.0]
            .iter()
            .map(|q| {
                let (x, y) = at(c, angle + q * std::f32::consts::FRAC_PI_2, 1.2, 0.0);
                f.lit(x, y).is_none()
            })
            .collect()
    };
    let f = Frame::of(&view);
    assert_eq!(f.lit(c.0, c.1), Some(rgb(GREEN)));
    // quarter turns from the body's x axis: only the first is the mark
    assert_eq!(marked(&f, 0.0), [true, false, false, false]);
    let before = f.count(GREEN);
    turn(&mut view, 11, 4, c, std::f32::consts::FRAC_PI_2);
    let f = Frame::of(&view);
    assert_eq!(marked(&f, 0.0), [false, true, false, false], "mark now up");
    assert_eq!(f.lit(c.0, c.1), Some(rgb(GREEN)));
    // rolled a little further and along: the mark follows the angle, not the axes
    let c = (12.1, 4.9);
    turn(&mut view, 12, 4, c, 2.4);
    let f = Frame::of(&view);
    let along = |f: &Frame, a: f32| {
        let (x, y) = at(c, a, 1.2, 0.0);
        f.lit(x, y)
    };
    assert_eq!(along(&f, 2.4), None, "mark at 2.4 rad");
    assert_eq!(along(&f, 2.4 + 0.6), Some(rgb(GREEN)));
    assert_eq!(along(&f, 2.4 - 0.6), Some(rgb(GREEN)));
    // the same disc otherwise: a mark is a few dots, whatever the angle
    let after = f.count(GREEN);
    assert!(before.abs_diff(after) <= 4, "{before} dots then {after}");
}

#[test]
fn a_capsule_is_a_stadium_along_its_axis() {
    let (flat, upright) = ((5.0, 5.0), (15.0, 5.0));
    let capsule = ShapeSpec::Capsule {
        length: 6.0,
        radius: 1.0,
    };
    let view = walled(vec![
        shaped(4, RED, flat, 0.0, capsule.clone()),
        shaped(5, BLUE, upright, std::f32::consts::FRAC_PI_2, capsule),
    ]);
    let f = Frame::of(&view);
    for (c, angle, colour) in [
        (flat, 0.0, RED),
        (upright, std::f32::consts::FRAC_PI_2, BLUE),
    ] {
        let p = |lx, ly| {
            let (x, y) = at(c, angle, lx, ly);
            f.lit(x, y)
        };
        for t in [-2.9, -2.0, -1.0, 0.0, 1.0, 2.0, 2.9] {
            assert_eq!(p(t, 0.0), Some(rgb(colour)), "axis at {t} ({angle} rad)");
        }
        // straight sides between the end discs' centres
        for (lx, ly) in [(-1.9, 0.95), (1.9, -0.95), (0.0, 0.95)] {
            assert_eq!(p(lx, ly), Some(rgb(colour)), "side ({lx}, {ly})");
        }
        // rounded ends: the bounding box's corners are empty
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            assert_eq!(p(2.95 * sx, 0.95 * sy), None, "box corner {sx},{sy}");
        }
        // nothing across the axis beyond the radius
        assert_eq!(p(0.0, 1.5), None);
    }
}

#[test]
fn a_triangle_fills_its_half_of_its_bounding_box() {
    // legs of 4.5 m; vertices centred on the centroid, counter-clockwise
    let c = (6.0, 5.0);
    let triangle = vec![
        Vector::new(-1.5, -1.5),
        Vector::new(3.0, -1.5),
        Vector::new(-1.5, 3.0),
    ];
    let mut view = walled_one(c, ShapeSpec::Polygon { vertices: triangle });
    let f = Frame::of(&view);
    let p = |f: &Frame, dx: f32, dy: f32| f.lit(c.0 + dx, c.1 + dy);
    for (dx, dy) in [
        (0.0, 0.0),
        (0.3, 0.3),
        (-0.3, 0.2),
        (-1.4, -1.4),
        (2.8, -1.4),
    ] {
        assert_eq!(p(&f, dx, dy), Some(rgb(GREEN)), "inside ({dx}, {dy})");
    }
    // the bounding box's corner opposite the right angle, and beyond the hypotenuse
    assert_eq!(p(&f, 2.9, 2.9), None);
    assert_eq!(p(&f, 1.2, 1.2), None);
    // half a box: about half the dots of the 4.5 m square it spans
    let dots = f.count(GREEN) as f32;
    let per_m = (Frame::W as f64 * 2.0 - 1.0) / (f.x_bounds[1] - f.x_bounds[0]);
    let half = 0.5 * (4.5 * per_m as f32).powi(2);
    assert!((0.85..1.3).contains(&(dots / half)), "{dots} dots, ~{half}");
    // turned half a turn: the right angle is now up and to the right
    turn(&mut view, 11, 4, c, std::f32::consts::PI);
    let f = Frame::of(&view);
    assert_eq!(p(&f, 1.4, 1.4), Some(rgb(GREEN)));
    assert_eq!(p(&f, 0.0, 0.0), Some(rgb(GREEN)));
    assert_eq!(p(&f, -1.2, -1.2), None);
    assert_eq!(p(&f, -1.4, -1.4), None);
}

/// A chain piece (a segment with no thickness) is a line of dots from `a` to `b`, turned with
/// its body, and nothing beside it.
#[test]
fn a_segment_is_a_line_from_a_to_b() {
    let c = (10.0, 5.0);
    let piece = ShapeSpec::Segment {
        a: Vector::new(-4.0, -1.0),
        b: Vector::new(4.0, 1.0),
        radius: 0.0,
        prev: Some(Vector::new(-6.0, -1.0)),
        next: None,
        one_sided: true,
    };
    let view = walled_one(c, piece);
    let f = Frame::of(&view);
    for t in [-1.0, -0.5, 0.0, 0.5, 1.0] {
        let (x, y) = (c.0 + 4.0 * t, c.1 + t);
        assert_eq!(f.lit(x, y), Some(rgb(GREEN)), "on the line at {t}");
    }
    // A metre to either side of the line, and past its ends: dark.
    for (dx, dy) in [(0.0, 1.0), (0.0, -1.0), (2.0, -0.5), (5.0, 1.25)] {
        assert_eq!(
            f.lit(c.0 + dx, c.1 + dy),
            None,
            "off the line at ({dx}, {dy})"
        );
    }
}
