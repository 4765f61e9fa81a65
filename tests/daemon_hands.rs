//! A hand whose client goes away is let go at once: the client keeps a `…/hand/<hand>`
//! liveliness token while it holds a brick, and when its session closes the daemon releases the
//! brick at the next tick, not after the 3 s silence time-out. Real daemon, real sockets.
#![cfg(feature = "net")]

mod common;

use common::net::{daemon_config, open, serve};
use std::time::{Duration, Instant};
use tiltbox::client::view::query_scene;
use tiltbox::protocol::*;
use zenoh::Session;

const PORT: u16 = 17620;

async fn red(s: &Session, keys: &Keys) -> BodyInfo {
    let scene = query_scene(s, keys.scene()).await.unwrap();
    scene
        .bodies
        .into_iter()
        .find(|b| b.name == "red brick")
        .unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_hand_is_let_go_as_soon_as_its_client_leaves() {
    let server = serve(&daemon_config(PORT)).await;
    let keys = server.keys().clone();
    let watcher = open(PORT).await;
    let hand_client = open(PORT).await;
    tokio::time::sleep(Duration::from_secs(2)).await; // the bricks land
    let brick = red(&watcher, &keys).await;
    let _token = hand_client
        .liveliness()
        .declare_token(keys.hand(42))
        .await
        .unwrap();
    let grab = Drag::Grab {
        hand: 42,
        id: brick.id,
        point: brick.position,
    };
    hand_client
        .put(keys.drag(), encode(&grab).unwrap())
        .await
        .unwrap();
    // Hold it up at (0, 4.5) for a second, moving the target now and then.
    let up = Drag::Move {
        hand: 42,
        target: Vector::new(0.0, 4.5),
    };
    for _ in 0..10 {
        hand_client
            .put(keys.drag(), encode(&up).unwrap())
            .await
            .unwrap();
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let held = red(&watcher, &keys).await.position;
    assert!(held.y > 4.0, "the brick is held up: {held:?}");
    hand_client.close().await.unwrap();
    let gone = Instant::now();
    // Let go, it falls 1 m in 0.45 s; held until the 3 s time-out, it would not.
    loop {
        let y = red(&watcher, &keys).await.position.y;
        if y < 3.5 {
            break;
        }
        assert!(
            gone.elapsed() < Duration::from_millis(1500),
            "still held {:?} after the client left (y = {y})",
            gone.elapsed()
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    println!(
        "let go and fallen 1 m {:?} after the client left",
        gone.elapsed()
    );
    server.shutdown().await.unwrap();
}
