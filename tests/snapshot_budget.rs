//! The byte budget of quantized snapshots (issue 14), on shipped scenes settling under
//! gravity, without a network: bytes are deterministic (the engine is), time is not measured.
//!
//! - a keyframe costs at most 8 bytes a body (beyond its 21 to 23-byte header);
//! - a delta costs at most 6 bytes per moving body on average, a moving body being one the
//!   delta must carry: off its pose of the latest keyframe (deltas are against the keyframe,
//!   for loss tolerance, so a body that moved and stopped is carried until the next
//!   keyframe). The cost per body whose pose changed since the previous frame is printed too;
//! - a pile at rest costs nothing per body: its deltas are the header and nothing else.
#![cfg(feature = "net")]

mod common;

use std::collections::BTreeMap;
use tiltbox::protocol::{decode_frame, encode_frame, BodyRef, SnapshotDecoder, SnapshotFrame};
use tiltbox::service::{SceneSource, ServerConfig, Simulation};

#[derive(Debug, Default)]
struct Bytes {
    keyframes: usize,
    keyframe_bytes: usize,
    keyframe_bodies: usize,
    deltas: usize,
    delta_bytes: usize,
    /// Bodies listed in deltas (off their keyframe pose).
    listed: usize,
    /// Bodies whose decoded pose changed since the previous frame.
    moving: usize,
    /// Bytes of keyframes and deltas beyond their header (frame, time, gravity, ...).
    keyframe_entry_bytes: usize,
    delta_entry_bytes: usize,
    /// Payload size of each delta that carries no pose.
    quiet_delta_bytes: Vec<usize>,
}

/// The size of `f`'s header: the frame encoded without its poses and gone bodies.
fn header_len(f: &SnapshotFrame) -> usize {
    let empty = SnapshotFrame {
        poses: Vec::new(),
        gone: Vec::new(),
        ..f.clone()
    };
    let mut out = Vec::new();
    encode_frame(&empty, &mut out);
    out.len()
}

fn measure(scene: &str, frames: u64) -> Bytes {
    let source = SceneSource::File(common::scene::scene_path(scene));
    let mut sim = Simulation::new(&ServerConfig::default(), source).unwrap();
    let mut out = Vec::new();
    let mut decoder = SnapshotDecoder::new();
    let mut last: BTreeMap<BodyRef, (f32, f32, f32)> = BTreeMap::new();
    let mut b = Bytes::default();
    for _ in 0..frames {
        sim.step().unwrap();
        let f = sim.snapshot_into(&mut out).clone();
        assert_eq!(decode_frame(&out).unwrap(), f);
        let s = decoder.decode(&out).unwrap().expect("every frame decodes");
        let changed = s
            .poses
            .iter()
            .filter(|p| last.get(&p.id) != Some(&(p.x, p.y, p.angle)))
            .count();
        for p in &s.poses {
            last.insert(p.id, (p.x, p.y, p.angle));
        }
        let entries = out.len() - header_len(&f);
        if f.is_keyframe() {
            b.keyframe_entry_bytes += entries;
            b.keyframes += 1;
            b.keyframe_bytes += out.len();
            b.keyframe_bodies += f.poses.len();
        } else {
            b.deltas += 1;
            b.delta_entry_bytes += entries;
            b.delta_bytes += out.len();
            b.listed += f.poses.len();
            b.moving += changed;
            if f.poses.is_empty() {
                b.quiet_delta_bytes.push(out.len());
            }
        }
    }
    b
}

/// Bytes a body that moved since the previous frame, in deltas, headers left out.
fn per_moved(b: &Bytes) -> f64 {
    b.delta_entry_bytes as f64 / b.moving.max(1) as f64
}

/// Keyframe bytes a body and delta bytes a listed body, headers left out.
fn report(scene: &str, b: &Bytes) -> (f64, f64) {
    let per_key = b.keyframe_entry_bytes as f64 / b.keyframe_bodies as f64;
    let per_moving = per_moved(b);
    let per_listed = b.delta_entry_bytes as f64 / b.listed.max(1) as f64;
    println!(
        "{scene}: keyframes {per_key:.2} B/body ({:.2} with the header, {} keyframes); \
         deltas {per_listed:.2} B per body carried ({per_moving:.2} per body that moved since \
         the previous frame; {:.1} carried, {:.1} moved and {:.1} B a delta on average, header \
         included; {} deltas, {} at rest)",
        b.keyframe_bytes as f64 / b.keyframe_bodies as f64,
        b.keyframes,
        b.listed as f64 / b.deltas as f64,
        b.moving as f64 / b.deltas as f64,
        b.delta_bytes as f64 / b.deltas as f64,
        b.deltas,
        b.quiet_delta_bytes.len()
    );
    (per_key, per_listed)
}

#[test]
fn a_settling_mixed_pile_fits_the_byte_budget() {
    // Shapes: 20 circles, capsules, polygons and bricks falling into a box, 10 s.
    let b = measure("shapes.toml", 600);
    let (per_key, per_moving) = report("shapes", &b);
    assert!(per_key <= 8.0, "{per_key} bytes a body in keyframes");
    assert!(
        per_moving <= 6.0,
        "{per_moving} bytes per moving body in deltas"
    );
    assert!(b.listed > 1000, "the pile moved: {b:?}");
}

#[test]
fn a_settling_pyramid_fits_the_byte_budget_and_rest_costs_nothing() {
    // 210 boxes settling, then asleep: 20 s.
    let b = measure("pyramid.toml", 1200);
    let (per_key, per_moving) = report("pyramid", &b);
    assert!(per_key <= 8.0, "{per_key} bytes a body in keyframes");
    let whole = b.keyframe_bytes as f64 / b.keyframe_bodies as f64;
    assert!(
        whole <= 8.0,
        "{whole} bytes a body in keyframes, header included"
    );
    assert!(
        per_moving <= 6.0,
        "{per_moving} bytes per moving body in deltas"
    );
    // at rest a delta is its header: version, frame (2 bytes past 127), time, gravity,
    // reference, grid, no pose, no body gone
    assert!(!b.quiet_delta_bytes.is_empty(), "the pyramid came to rest");
    assert!(b
        .quiet_delta_bytes
        .iter()
        .all(|&n| n <= 1 + 2 + 8 + 8 + 1 + 1 + 1 + 1));
}

/// docs/protocol.md's "What it costs" and the README state these runs' figures, to the
/// hundredth.
#[test]
fn the_byte_figures_the_docs_state_are_the_measured_ones() {
    let shapes = measure("shapes.toml", 600);
    let (key, carried) = report("shapes", &shapes);
    let pyramid = measure("pyramid.toml", 1200);
    let (pkey, pcarried) = report("pyramid", &pyramid);
    let protocol = common::read_repo_file("docs/protocol.md").replace('\n', " ");
    let stated = [
        format!("takes {key:.2} bytes a body in keyframes and {carried:.2} bytes per body a delta carries"),
        format!("({:.2} per body whose pose changed", per_moved(&shapes)),
        format!("the 210-box `pyramid.toml` (20 s) {pkey:.2} and {pcarried:.2}."),
    ];
    for s in &stated {
        assert!(protocol.contains(s), "docs/protocol.md does not say {s:?}");
    }
    let readme = common::read_repo_file("README.md").replace('\n', " ");
    let s = format!("{key:.2} bytes a body in keyframes and {carried:.2} per body a delta carries");
    assert!(readme.contains(&s), "README.md does not say {s:?}");
}
