//! Contact, hit and sensor events on `…/events` from a real daemon over a real Zenoh socket:
//! the sensor example of docs/scenes.md (a ball falling through a gate onto a floor) reports
//! the ball entering and leaving the gate, hitting the floor and touching it, in that order, at
//! the frames docs/scenes.md states.
#![cfg(all(feature = "net", feature = "scene"))]

mod common;

use common::net::{daemon_config, open, subscribe};
use std::time::{Duration, Instant};
use tiltbox::protocol::*;
use tiltbox::scene::Scene;
use tiltbox::service::{SceneSource, Server, ServerOptions};

const PORT: u16 = 17590;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_sensor_example_reports_its_events_on_the_wire() {
    let text = common::scene::docs_example("## Example with a sensor and events");
    let scene = Scene::from_toml_str(&text).unwrap();
    let options = ServerOptions {
        source: Some(SceneSource::Given(Box::new(scene))),
        ..Default::default()
    };
    let s = open(PORT).await;
    let keys = Keys::for_world(DEFAULT_WORLD).unwrap();
    // Subscribed before the daemon starts, so the first frames' events are not missed.
    let (mut events, _sub) = subscribe::<Event>(&s, keys.events()).await;
    let server = Server::start(&daemon_config(PORT), options).await.unwrap();
    let (gate, ball) = (
        BodyRef {
            index: 1,
            generation: 0,
        },
        BodyRef {
            index: 2,
            generation: 0,
        },
    );
    let mut seen = Vec::new();
    let end = Instant::now() + Duration::from_secs(6);
    while seen.len() < 4 && Instant::now() < end {
        let Ok(Some(e)) = tokio::time::timeout(Duration::from_millis(500), events.recv()).await
        else {
            continue;
        };
        match e.kind {
            EventKind::Sensors {
                begin,
                end,
                dropped,
            } => {
                assert_eq!(dropped, 0);
                for (list, what) in [(begin, "enters"), (end, "leaves")] {
                    for p in list {
                        assert_eq!((p.a.id, p.b.id), (gate, ball));
                        seen.push((what, e.frame));
                    }
                }
            }
            EventKind::Hits { hits, .. } if seen.iter().all(|s| s.0 != "hits") => {
                assert_eq!(hits[0].pair.b.id, ball);
                assert!(hits[0].approach_speed > 11.0, "{:?}", hits[0]);
                seen.push(("hits", e.frame));
            }
            EventKind::Contacts { begin, .. } if !begin.is_empty() => {
                assert_eq!(begin[0].b.id, ball);
                seen.push(("touches", e.frame));
            }
            _ => {}
        }
    }
    // docs/scenes.md: enters in the 39th step, leaves in the 51st, lands in the 72nd (the hit
    // in that step, the contact judged touching at the start of the next or the one after).
    assert_eq!(
        &seen[..3],
        &[("enters", 39), ("leaves", 51), ("hits", 72)],
        "{seen:?}"
    );
    assert!(
        seen[3].0 == "touches" && (73..=74).contains(&seen[3].1),
        "{seen:?}"
    );
    server.shutdown().await.unwrap();
}
