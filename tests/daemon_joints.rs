//! Joints on a real daemon over a real Zenoh socket: a daemon serving the rope scene lists its
//! links' joints in the `…/scene?joints` reply (a plain `…/scene` reply stays a bare
//! `SceneState`), and a joint removed over `…/remove_joints` is gone from the next reply.
#![cfg(feature = "net")]

mod common;

use common::net::{daemon_config, open, serve, subscribe};
use std::time::Duration;
use tiltbox::client::view::{query_scene, query_scene_with_joints};
use tiltbox::protocol::*;

const PORT: u16 = 17610;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_scene_reply_with_joints_lists_the_ropes_links_and_follows_removals() {
    let mut config = daemon_config(PORT);
    config.scene = Some(common::repo_path("config/scenes/rope.toml"));
    let server = serve(&config).await;
    let keys = server.keys().clone();
    let s = open(PORT).await;
    let (mut events, _sub) = subscribe::<Event>(&s, keys.events()).await;
    let mut full = None;
    for _ in 0..50 {
        if let Ok(r) = query_scene_with_joints(&s, keys.scene()).await {
            full = Some(r);
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await; // the daemon is not seen yet
    }
    let full = full.expect("a reply to …/scene?joints");
    // The rope scene: 12 links hinged end to end from the ceiling, and a weight at the end.
    assert!(full.joints.len() >= 12, "{} joints", full.joints.len());
    let names: std::collections::HashMap<BodyRef, &str> = full
        .scene
        .bodies
        .iter()
        .map(|b| (b.id, b.name.as_str()))
        .collect();
    for j in &full.joints {
        for end in [j.joint.a, j.joint.b] {
            match end {
                JointEnd::Live(id) => assert!(names.contains_key(&id), "{id} is not in the scene"),
                JointEnd::World => {}
                JointEnd::New(_) => panic!("a live joint names a new body"),
            }
        }
    }
    let plain = query_scene(&s, keys.scene()).await.unwrap();
    assert_eq!(plain.bodies.len(), full.scene.bodies.len());

    let gone = full.joints[0].id;
    s.put(
        keys.remove_joints(),
        encode(&RemoveJoints { ids: vec![gone] }).unwrap(),
    )
    .await
    .unwrap();
    let removed = loop {
        let e = tokio::time::timeout(Duration::from_secs(5), events.recv())
            .await
            .expect("a JointsRemoved event")
            .unwrap();
        if let EventKind::JointsRemoved { ids } = e.kind {
            break ids;
        }
    };
    assert_eq!(removed, vec![gone]);
    let after = query_scene_with_joints(&s, keys.scene()).await.unwrap();
    assert_eq!(after.joints.len(), full.joints.len() - 1);
    assert!(after.joints.iter().all(|j| j.id != gone));
    server.shutdown().await.unwrap();
}
