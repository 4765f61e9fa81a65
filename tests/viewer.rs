//! The viewer: its pure drawing into ratatui's TestBackend, and `tiltbox-view --plain`
//! against an in-process daemon (real Zenoh over TCP loopback, port 17482, scouting off).
#![cfg(all(feature = "net", feature = "cli", feature = "tui"))]

use ratatui::backend::TestBackend;
use ratatui::style::Color;
use ratatui::Terminal;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use tiltbox::client::plain::parse_line;
use tiltbox::client::render::{render, Status};
use tiltbox::client::world::WorldView;
use tiltbox::protocol::*;
use tiltbox::service::{Server, ServerConfig, ServerOptions};

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
    };
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
    let mut cfg = ServerConfig::default();
    cfg.zenoh.listen = vec![format!("tcp/127.0.0.1:{port}")];
    let server = Server::start(&cfg, ServerOptions::default()).await.unwrap();
    let keys = server.keys().clone();
    // our own record of what was published
    let session = tiltbox::client::session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    let (tx, rx) = std::sync::mpsc::channel::<Snapshot>();
    let _sub = session
        .declare_subscriber(keys.poses())
        .callback(move |s| {
            if let Ok(s) = decode::<Snapshot>(&s.payload().to_bytes()) {
                let _ = tx.send(s);
            }
        })
        .await
        .unwrap();
    rx.recv_timeout(Duration::from_secs(5))
        .expect("a first snapshot");

    let mut child = Command::new(env!("CARGO_BIN_EXE_tiltbox-view"))
        .args(["--plain", "--count", "40", "--connect"])
        .arg(format!("tcp/127.0.0.1:{port}"))
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
        if let Ok(s) = rx.recv_timeout(Duration::from_millis(200)) {
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
