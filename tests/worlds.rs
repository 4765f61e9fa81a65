//! Many worlds joined by a Zenoh router: a router-mode session (what zenohd runs), one daemon
//! in client mode serving two worlds from one session, a second daemon in client mode serving a
//! third, and a viewer that lists the live worlds through liveliness, follows one, and sees a
//! world go away when its daemon stops.
#![cfg(feature = "net")]

mod common;

use common::net::{query_scene, WAIT};
use std::collections::BTreeSet;
use std::time::{Duration, Instant};
use tiltbox::protocol::*;
use tiltbox::service::{shutdown_worlds, start_worlds, world_configs, Server, ServerConfig};
use zenoh::sample::SampleKind;

const ROUTER: u16 = 17550;

fn client_mode() -> ServerConfig {
    let mut c = ServerConfig::default();
    c.zenoh.mode = "client".into();
    c.zenoh.listen = vec![];
    c.zenoh.connect = vec![format!("tcp/127.0.0.1:{ROUTER}")];
    c
}

fn world_of(key: &str) -> Option<String> {
    // tiltbox/<world>/server
    let rest = key.strip_prefix("tiltbox/")?;
    rest.strip_suffix("/server").map(str::to_owned)
}

async fn live_worlds(viewer: &zenoh::Session) -> BTreeSet<String> {
    let replies = viewer.liveliness().get("tiltbox/*/server").await.unwrap();
    let mut out = BTreeSet::new();
    while let Ok(Ok(reply)) = tokio::time::timeout(WAIT, replies.recv_async()).await {
        if let Ok(sample) = reply.into_result() {
            out.extend(world_of(sample.key_expr().as_str()));
        }
    }
    out
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_viewer_lists_and_follows_worlds_behind_a_router() {
    // The router (zenohd's role).
    let mut rc = zenoh::Config::default();
    rc.insert_json5("mode", "\"router\"").unwrap();
    rc.insert_json5("listen/endpoints", &format!("[\"tcp/127.0.0.1:{ROUTER}\"]"))
        .unwrap();
    rc.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    let router = zenoh::open(rc).await.unwrap();

    // Daemon 1: worlds "bricks" and "tower" on one session.
    let mut c1 = client_mode();
    c1.worlds = vec!["tower".into()];
    assert_eq!(world_configs(&c1).len(), 2);
    let daemon1 = start_worlds(&c1, Default::default()).await.unwrap();
    assert_eq!(daemon1.len(), 2);
    // Daemon 2: world "pit".
    let mut c2 = client_mode();
    c2.world = "pit".into();
    let daemon2 = Server::start(&c2, Default::default()).await.unwrap();

    // The viewer: a client of the router, like the daemons.
    let mut vc = zenoh::Config::default();
    vc.insert_json5("mode", "\"client\"").unwrap();
    vc.insert_json5(
        "connect/endpoints",
        &format!("[\"tcp/127.0.0.1:{ROUTER}\"]"),
    )
    .unwrap();
    vc.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    let viewer = zenoh::open(vc).await.unwrap();
    let (ltx, mut changes) = tokio::sync::mpsc::unbounded_channel();
    let _live = viewer
        .liveliness()
        .declare_subscriber("tiltbox/*/server")
        .callback(move |s| {
            let _ = ltx.send((s.kind(), s.key_expr().as_str().to_owned()));
        })
        .await
        .unwrap();

    let want: BTreeSet<String> = ["bricks", "pit", "tower"].map(String::from).into();
    let end = Instant::now() + WAIT;
    loop {
        let got = live_worlds(&viewer).await;
        if got == want {
            break;
        }
        assert!(Instant::now() < end, "live worlds {got:?}, want {want:?}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }

    // Follow one world: its scene and its snapshots, and nothing of the others.
    let keys = Keys::for_world("tower").unwrap();
    let (ptx, mut poses) = tokio::sync::mpsc::unbounded_channel();
    let _p = viewer
        .declare_subscriber(keys.poses())
        .callback(move |s| {
            let _ = ptx.send((
                s.key_expr().as_str().to_owned(),
                s.payload().to_bytes().to_vec(),
            ));
        })
        .await
        .unwrap();
    let (key, payload) = tokio::time::timeout(WAIT, poses.recv())
        .await
        .expect("snapshots of the followed world")
        .unwrap();
    assert_eq!(key, "tiltbox/tower/poses");
    assert!(decode_frame(&payload).is_ok());
    let scene = query_scene(&viewer, &keys).await;
    assert_eq!(scene.world, "tower");

    // A command to one world changes that world only.
    let g = SetGravity { x: 7.0, y: 0.0 };
    let end = Instant::now() + WAIT;
    loop {
        viewer
            .put(keys.gravity(), encode(&g).unwrap())
            .await
            .unwrap();
        let (_, payload) = tokio::time::timeout(WAIT, poses.recv())
            .await
            .unwrap()
            .unwrap();
        if decode_frame(&payload).unwrap().gravity.x == 7.0 {
            break;
        }
        assert!(Instant::now() < end, "gravity never changed");
    }
    let other = Keys::for_world("bricks").unwrap();
    let replies = viewer.get(other.scene()).await.unwrap();
    let reply = tokio::time::timeout(WAIT, replies.recv_async())
        .await
        .unwrap()
        .unwrap();
    let bricks: SceneState = decode(&reply.into_result().unwrap().payload().to_bytes()).unwrap();
    assert_eq!(bricks.world, "bricks");
    assert_ne!(bricks.gravity.x, 7.0);

    // Daemon 2 stops: the viewer sees "pit" leave.
    daemon2.shutdown().await.unwrap();
    let end = Instant::now() + WAIT;
    loop {
        let left = end.saturating_duration_since(Instant::now());
        match tokio::time::timeout(left, changes.recv()).await {
            Ok(Some((SampleKind::Delete, key))) if world_of(&key).as_deref() == Some("pit") => {
                break
            }
            Ok(Some(_)) => {}
            _ => panic!("no liveliness Delete for pit"),
        }
    }
    let want: BTreeSet<String> = ["bricks", "tower"].map(String::from).into();
    assert_eq!(live_worlds(&viewer).await, want);

    shutdown_worlds(daemon1).await.unwrap();
    viewer.close().await.unwrap();
    router.close().await.unwrap();
}
