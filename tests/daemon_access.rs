//! Access control with Zenoh's own user/password authentication and ACL, using the shipped
//! `config/zenoh/acl-daemon.json5`, `acl-client.json5` and `users.txt` (port and paths
//! adjusted): a viewer may watch but its spawn never reaches the World; an operator's does;
//! a wrong password does not get in at all.
#![cfg(feature = "net")]

mod common;

use common::net::{query_scene, subscribe, subscribe_snapshots, WAIT};
use common::{repo_path, temp_dir};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use tiltbox::protocol::*;
use tiltbox::service::{Server, ServerConfig};

const PORT: u16 = 17540;

fn daemon_config(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(repo_path("config/zenoh/acl-daemon.json5")).unwrap();
    let users = repo_path("config/zenoh/users.txt");
    let text = text
        .replace("tcp/127.0.0.1:7447", &format!("tcp/127.0.0.1:{PORT}"))
        .replace("config/zenoh/users.txt", users.to_str().unwrap());
    let path = dir.join("acl-daemon.json5");
    std::fs::write(&path, text).unwrap();
    path
}

fn client_config(user: &str, password: &str) -> zenoh::Config {
    let text = std::fs::read_to_string(repo_path("config/zenoh/acl-client.json5")).unwrap();
    let text = text
        .replace("tcp/127.0.0.1:7447", &format!("tcp/127.0.0.1:{PORT}"))
        .replace("\"viewer\"", &format!("\"{user}\""))
        .replace("\"change-me-viewer\"", &format!("\"{password}\""));
    zenoh::Config::from_json5(&text).unwrap()
}

fn spawn(name: &str) -> Vec<u8> {
    encode(&Spawn {
        bodies: vec![SpawnBody {
            name: Some(name.into()),
            shape: ShapeSpec::Rect {
                width: 0.5,
                height: 0.5,
            },
            position: Vector::new(0.0, 8.0),
            angle: 0.0,
            velocity: Vector::default(),
            angular_velocity: 0.0,
            density: 1.0,
            friction: 0.5,
            restitution: 0.0,
            colour: Colour::default(),
        }],
    })
    .unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_viewer_watches_but_its_spawn_never_reaches_the_world() {
    let dir = temp_dir("acl");
    let mut config = ServerConfig::default();
    config.zenoh.config_file = Some(daemon_config(&dir));
    let server = Server::start(&config, Default::default()).await.unwrap();
    let keys = server.keys().clone();

    // A wrong password does not get a session at all.
    let bad = tokio::time::timeout(WAIT, zenoh::open(client_config("viewer", "guess"))).await;
    assert!(
        matches!(bad, Ok(Err(_))),
        "a wrong password was let in (or hung)"
    );

    // The viewer may watch: snapshots and events arrive.
    let viewer = zenoh::open(client_config("viewer", "change-me-viewer"))
        .await
        .unwrap();
    let (mut poses, _p) = subscribe_snapshots(&viewer, keys.poses()).await;
    let (mut viewer_events, _e) = subscribe::<Event>(&viewer, keys.events()).await;
    let first = tokio::time::timeout(WAIT, poses.recv())
        .await
        .expect("the viewer receives snapshots")
        .unwrap()
        .frame;

    // The operator.
    let operator = zenoh::open(client_config("operator", "change-me-operator"))
        .await
        .unwrap();

    // The viewer tries to spawn and reset, again and again.
    for _ in 0..10 {
        viewer.put(keys.spawn(), spawn("intruder")).await.unwrap();
        viewer
            .put(keys.reset(), encode(&Reset).unwrap())
            .await
            .unwrap();
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    // The operator's spawn goes through (retry until the daemon has announced itself to it).
    let mut seen = Vec::new();
    let end = Instant::now() + WAIT;
    'outer: loop {
        assert!(Instant::now() < end, "the operator's spawn never arrived");
        operator.put(keys.spawn(), spawn("allowed")).await.unwrap();
        let until = Instant::now() + Duration::from_millis(200);
        while let Ok(Some(e)) =
            tokio::time::timeout(until - Instant::now(), viewer_events.recv()).await
        {
            seen.push(e.clone());
            if let EventKind::Added { bodies } = &e.kind {
                if bodies.iter().any(|b| b.name == "allowed") {
                    break 'outer;
                }
            }
            if until <= Instant::now() {
                break;
            }
        }
    }
    // Give anything of the viewer's that might still be in flight 30 more frames.
    let end = Instant::now() + WAIT;
    let mut last = first;
    while last < first + 60 {
        assert!(Instant::now() < end);
        if let Ok(Some(s)) = tokio::time::timeout(WAIT, poses.recv()).await {
            last = s.frame;
        }
    }
    // The operator may query the scene: "allowed" is there, "intruder" is not, and there was
    // no reset and not even a rejection for the viewer's commands.
    let scene = query_scene(&operator, &keys).await;
    assert!(scene.bodies.iter().any(|b| b.name == "allowed"));
    assert!(!scene.bodies.iter().any(|b| b.name == "intruder"));
    while let Ok(e) = viewer_events.try_recv() {
        seen.push(e);
    }
    for e in seen {
        assert!(
            !matches!(e.kind, EventKind::Reset { .. } | EventKind::Rejected { .. }),
            "{e:?}"
        );
        if let EventKind::Added { bodies } = &e.kind {
            assert!(bodies.iter().all(|b| b.name != "intruder"));
        }
    }
    for s in [viewer, operator] {
        s.close().await.unwrap();
    }
    server.shutdown().await.unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}
