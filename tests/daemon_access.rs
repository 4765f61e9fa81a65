//! Access control with Zenoh's own user/password authentication and ACL, using the shipped
//! `config/zenoh/acl-daemon.json5`, `acl-client.json5` and `users.txt` (port and paths
//! adjusted): a viewer may watch but its spawn never reaches the World; an operator's does;
//! a wrong password does not get in at all.
#![cfg(feature = "net")]

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use tiltbox::protocol::*;
use tiltbox::service::{Server, ServerConfig};

const WAIT: Duration = Duration::from_secs(5);
const PORT: u16 = 17540;

fn manifest(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn daemon_config(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(manifest("config/zenoh/acl-daemon.json5")).unwrap();
    let users = manifest("config/zenoh/users.txt");
    let text = text
        .replace("tcp/127.0.0.1:7447", &format!("tcp/127.0.0.1:{PORT}"))
        .replace("config/zenoh/users.txt", users.to_str().unwrap());
    let path = dir.join("acl-daemon.json5");
    std::fs::write(&path, text).unwrap();
    path
}

fn client_config(user: &str, password: &str) -> zenoh::Config {
    let text = std::fs::read_to_string(manifest("config/zenoh/acl-client.json5")).unwrap();
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
    let dir = std::env::temp_dir().join(format!("tiltbox-acl-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
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
    let (ptx, mut poses) = tokio::sync::mpsc::unbounded_channel();
    let _p = viewer
        .declare_subscriber(keys.poses())
        .callback(move |s| {
            if let Ok(snap) = decode::<Snapshot>(&s.payload().to_bytes()) {
                let _ = ptx.send(snap.frame);
            }
        })
        .await
        .unwrap();
    let (vtx, mut viewer_events) = tokio::sync::mpsc::unbounded_channel();
    let _e = viewer
        .declare_subscriber(keys.events())
        .callback(move |s| {
            if let Ok(e) = decode::<Event>(&s.payload().to_bytes()) {
                let _ = vtx.send(e);
            }
        })
        .await
        .unwrap();
    let first = tokio::time::timeout(WAIT, poses.recv())
        .await
        .expect("the viewer receives snapshots")
        .unwrap();

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
        if let Ok(Some(f)) = tokio::time::timeout(WAIT, poses.recv()).await {
            last = f;
        }
    }
    // The operator may query the scene: "allowed" is there, "intruder" is not, and there was
    // no reset and not even a rejection for the viewer's commands.
    let replies = operator.get(keys.scene()).await.unwrap();
    let reply = tokio::time::timeout(WAIT, replies.recv_async())
        .await
        .expect("scene reply")
        .unwrap();
    let scene: SceneState = decode(&reply.into_result().unwrap().payload().to_bytes()).unwrap();
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
