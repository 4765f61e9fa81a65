//! `…/query` on a real daemon over a real Zenoh socket: rays, points and boxes find the Falling
//! Bricks where the daemon's own scene reply puts them, and bad requests are refused by name.
#![cfg(feature = "net")]

mod common;

use common::net::{daemon_config, open, serve};
use std::time::Duration;
use tiltbox::protocol::*;
use tiltbox::service::MAX_HITS;
use zenoh::Session;

const PORT: u16 = 17580;

async fn ask(s: &Session, keys: &Keys, q: &[u8]) -> QueryAnswer {
    for _ in 0..50 {
        let replies = s
            .get(keys.query())
            .payload(q.to_vec())
            .timeout(Duration::from_secs(2))
            .await
            .unwrap();
        if let Ok(reply) = replies.recv_async().await {
            let sample = reply.into_result().expect("a reply, not an error");
            return decode::<QueryAnswer>(&sample.payload().to_bytes()).unwrap();
        }
        tokio::time::sleep(Duration::from_millis(100)).await; // the daemon is not seen yet
    }
    panic!("no answer on {}", keys.query());
}

/// Whether `p` lies on the outline (within 1 mm) of rectangle body `b` as the scene reply
/// describes it.
fn on_outline(b: &BodyInfo, p: Vector) -> bool {
    let ShapeSpec::Rect { width, height } = b.shape else {
        panic!("{} is not a rectangle", b.name);
    };
    let (dx, dy) = (p.x - b.position.x, p.y - b.position.y);
    let (c, s) = (b.angle.cos(), b.angle.sin());
    let (lx, ly) = (c * dx + s * dy, -s * dx + c * dy);
    let out = (lx.abs() - width / 2.0).max(ly.abs() - height / 2.0);
    out.abs() < 1e-3
}

fn all() -> QueryFilterSpec {
    QueryFilterSpec::default()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rays_points_and_boxes_find_the_bricks_the_scene_reply_shows() {
    let server = serve(&daemon_config(PORT)).await;
    let keys = server.keys().clone();
    let s = open(PORT).await;
    // Let the bricks land and sleep, so the scene and the queries see the same World.
    tokio::time::sleep(Duration::from_secs(4)).await;
    let scene = tiltbox::client::view::query_scene(&s, keys.scene())
        .await
        .unwrap();
    let floor = scene.bodies.iter().find(|b| b.name == "floor").unwrap().id;
    let red = scene.bodies.iter().find(|b| b.name == "red brick").unwrap();

    // Straight down through the red brick's centre from under the ceiling: the first shape met
    // (the red brick, or a brick lying on it) has the hit point on its outline as the scene
    // reply describes it, with the normal facing up the ray.
    let (x, y) = (red.position.x, red.position.y);
    let down = WorldQuery::RayClosest {
        origin: Vector::new(x, 5.5),
        translation: Vector::new(0.0, -6.0),
        filter: all(),
    };
    let QueryAnswer::Hits { frame, hits } = ask(&s, &keys, &encode(&down).unwrap()).await else {
        panic!("not hits");
    };
    assert!(frame >= scene.frame);
    assert_eq!(hits.len(), 1);
    let first = hits[0];
    let met = scene.bodies.iter().find(|b| b.id == first.hit.id).unwrap();
    assert!(
        on_outline(met, first.point),
        "{first:?} is not on {}'s outline",
        met.name
    );
    assert!(first.point.y >= y && first.normal.y > 0.0, "{first:?}");
    let depth = 5.5 - first.point.y;
    assert!((first.fraction - depth / 6.0).abs() < 1e-4);

    // All hits, closest first: the first is the closest's, the red brick and then the floor
    // are among them; a limit of 1 keeps the closest.
    let through = |limit| WorldQuery::RayAll {
        origin: Vector::new(x, 5.5),
        translation: Vector::new(0.0, -6.0),
        filter: all(),
        limit,
    };
    let QueryAnswer::Hits { hits, .. } =
        ask(&s, &keys, &encode(&through(MAX_HITS + 5)).unwrap()).await
    else {
        panic!("not hits");
    };
    let ids: Vec<BodyRef> = hits.iter().map(|h| h.hit.id).collect();
    assert_eq!(hits[0], first);
    assert!(
        hits.windows(2).all(|w| w[0].fraction <= w[1].fraction),
        "{hits:?}"
    );
    let at = |id| ids.iter().position(|&i| i == id);
    assert!(at(red.id).unwrap() < at(floor).unwrap(), "{ids:?}");
    let QueryAnswer::Hits { hits, .. } = ask(&s, &keys, &encode(&through(1)).unwrap()).await else {
        panic!("not hits");
    };
    assert_eq!(hits, vec![first]);

    // The brick's centre holds the brick; a box around the whole box finds all ten bodies.
    let point = WorldQuery::Point {
        point: red.position,
        filter: all(),
    };
    let QueryAnswer::Shapes { shapes, .. } = ask(&s, &keys, &encode(&point).unwrap()).await else {
        panic!("not shapes");
    };
    assert_eq!(
        shapes,
        vec![ShapeHit {
            id: red.id,
            shape: 0
        }]
    );
    let everything = WorldQuery::Box {
        min: Vector::new(-5.0, -1.0),
        max: Vector::new(5.0, 7.0),
        filter: all(),
    };
    let QueryAnswer::Shapes { shapes, .. } = ask(&s, &keys, &encode(&everything).unwrap()).await
    else {
        panic!("not shapes");
    };
    assert_eq!(shapes.len(), scene.bodies.len());

    // Refusals name what was wrong and come back as answers.
    let nan = WorldQuery::Point {
        point: Vector::new(f32::NAN, 0.0),
        filter: all(),
    };
    let far = WorldQuery::RayClosest {
        origin: Vector::new(0.0, 0.0),
        translation: Vector::new(0.0, 1e6),
        filter: all(),
    };
    let backwards = WorldQuery::Box {
        min: Vector::new(1.0, 0.0),
        max: Vector::new(0.0, 1.0),
        filter: all(),
    };
    for (q, words) in [
        (encode(&nan).unwrap(), &["point.x", "NaN"][..]),
        (
            encode(&far).unwrap(),
            &["translation.y", "max_coordinate"][..],
        ),
        (encode(&backwards).unwrap(), &["min.x", "max.x"][..]),
        (vec![1, 9], &["WorldQuery"][..]),
    ] {
        let QueryAnswer::Refused { reason } = ask(&s, &keys, &q).await else {
            panic!("{q:02x?} was answered");
        };
        for w in words {
            assert!(reason.contains(w), "{reason:?} lacks {w:?}");
        }
    }
    drop(s);
    server.shutdown().await.unwrap();
}

/// `limits.max_queries_per_second` bounds the queries answered, all clients together: with 5
/// a second, a burst of 12 gets at most the bucket's 5 and what refills while they are
/// answered (a tick each, about 0.2 s: one more), and the rest are refused by name.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn queries_beyond_the_rate_limit_are_refused_by_name() {
    let mut config = daemon_config(PORT + 1);
    config.limits.max_queries_per_second = 5;
    let server = serve(&config).await;
    let keys = server.keys().clone();
    let s = open(PORT + 1).await;
    let q = encode(&WorldQuery::Point {
        point: Vector::new(0.0, 1.0),
        filter: all(),
    })
    .unwrap();
    let (mut answered, mut refused) = (0, 0);
    for _ in 0..12 {
        match ask(&s, &keys, &q).await {
            QueryAnswer::Refused { reason } => {
                assert!(
                    reason.contains("rate limit: limits.max_queries_per_second = 5"),
                    "{reason}"
                );
                refused += 1;
            }
            _ => answered += 1,
        }
    }
    assert!((5..=8).contains(&answered), "{answered} answered");
    assert_eq!(answered + refused, 12);
    server.shutdown().await.unwrap();
}
