//! One page's WebSocket: Zenoh samples down, checked commands up.
//!
//! Per page: subscribers on `…/poses`, `…/events` and `…/stats` whose callbacks only
//! `try_send` tagged frames into a bounded queue (a full queue drops snapshots, which the next
//! keyframe repairs, and turns a lost event into a fresh `…/scene` reply), a liveliness watch
//! on `…/server` that sends the scene whenever a daemon appears, and the page's frames, each
//! rate-limited, decoded and checked before it is put.

use super::wire::{self, RateLimit, Tag};
use super::{Counters, Ctx};
use crate::client::session::watch_server;
use crate::protocol::{decode, CommandKey, Drag, Keys};
use axum::extract::ws::{Message, WebSocket};
use futures_util::{SinkExt, StreamExt};
use serde_json::json;
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::mpsc;
use zenoh::liveliness::LivelinessToken;
use zenoh::qos::CongestionControl;

/// What the Zenoh side hands the socket task.
enum Down {
    /// A tagged frame to send as is.
    Frame(Vec<u8>),
    /// The daemon appeared (or an event was lost): send the scene again.
    Resync,
    /// The daemon's token went away.
    Gone,
}

/// Frames queued per page before snapshots are dropped: about 4 s at 60 Hz.
const QUEUE: usize = 256;

pub(super) async fn run(socket: WebSocket, ctx: Arc<Ctx>, keys: Keys) {
    let c = &ctx.counters;
    Counters::add(&c.pages, 1);
    Counters::add(&c.pages_total, 1);
    if let Err(e) = serve(socket, &ctx, &keys).await {
        tracing::debug!("page on {}: {e}", keys.prefix());
    }
    c.pages.fetch_sub(1, Ordering::Relaxed);
}

fn world_of(keys: &Keys) -> &str {
    keys.prefix()
        .strip_prefix("tiltbox/")
        .unwrap_or(keys.prefix())
}

async fn serve(socket: WebSocket, ctx: &Ctx, keys: &Keys) -> Result<(), String> {
    let (mut sink, mut stream) = socket.split();
    let (tx, mut rx) = mpsc::channel::<Down>(QUEUE);
    let lost_event = Arc::new(AtomicBool::new(false));
    let s = &ctx.session;
    let counters = ctx.counters.clone();

    let subscribe = |key: String, tag: Tag| {
        let tx = tx.clone();
        let lost = lost_event.clone();
        let counters = counters.clone();
        async move {
            s.declare_subscriber(key)
                .callback(move |sample| {
                    let f = wire::frame(tag, &sample.payload().to_bytes());
                    if tx.try_send(Down::Frame(f)).is_err() {
                        Counters::add(&counters.dropped, 1);
                        if tag == Tag::Events {
                            lost.store(true, Ordering::Relaxed);
                        }
                    }
                })
                .await
                .map_err(|e| format!("subscriber: {e}"))
        }
    };
    let _poses = subscribe(keys.poses(), Tag::Poses).await?;
    let _events = subscribe(keys.events(), Tag::Events).await?;
    let _stats = subscribe(keys.stats(), Tag::Stats).await?;
    let wtx = tx.clone();
    let _server = watch_server(s, keys, move |up| {
        let _ = wtx.try_send(if up { Down::Resync } else { Down::Gone });
    })
    .await
    .map_err(|e| e.to_string())?;
    drop(tx);

    let mut worlds = ctx.worlds.clone();
    let hello = json!({
        "type": "hello",
        "world": world_of(keys),
        "prefix": keys.prefix(),
        "worlds": *worlds.borrow_and_update(),
        "pick": !ctx.opts.fixed_prefix,
        "allow": ctx.opts.allow.names(),
        "rate": ctx.opts.rate,
    });
    send_text(&mut sink, &hello).await?;

    let mut commands = RateLimit::new(ctx.opts.rate);
    // A liveliness token per hand this page holds with: when the page goes (this function
    // returns, however), the tokens go and the daemon lets its hands go at once.
    let mut hands = HashMap::new();
    loop {
        tokio::select! {
            down = rx.recv() => {
                let Some(down) = down else { break };
                match down {
                    Down::Frame(f) => send_frame(&mut sink, &ctx.counters, f).await?,
                    Down::Resync => resync(&mut sink, ctx, keys).await?,
                    Down::Gone => send_text(&mut sink, &json!({"type": "server", "alive": false})).await?,
                }
                if lost_event.swap(false, Ordering::Relaxed) {
                    resync(&mut sink, ctx, keys).await?;
                }
            }
            changed = worlds.changed() => {
                if changed.is_ok() {
                    let list = worlds.borrow_and_update().clone();
                    send_text(&mut sink, &json!({"type": "worlds", "worlds": list})).await?;
                }
            }
            msg = stream.next() => {
                let msg = match msg {
                    None | Some(Ok(Message::Close(_))) => break,
                    Some(Err(e)) => return Err(format!("websocket: {e}")),
                    Some(Ok(m)) => m,
                };
                match msg {
                    Message::Binary(b) => {
                        let verdict = if commands.take(Instant::now()) {
                            wire::check_upstream(&b, &ctx.opts.allow)
                        } else {
                            Err(wire::Refusal::RateLimited(commands.rate()))
                        };
                        match verdict {
                            Ok(checked) => {
                                if checked.key == CommandKey::Drag {
                                    track_hand(ctx, keys, &checked.payload, &mut hands).await;
                                }
                                put(ctx, keys, checked).await?;
                                Counters::add(&ctx.counters.commands, 1);
                            }
                            Err(r) => {
                                Counters::add(&ctx.counters.refused, 1);
                                tracing::debug!("page on {}: refused: {r}", keys.prefix());
                                send_text(&mut sink, &json!({"type": "error", "reason": r.to_string()})).await?;
                            }
                        }
                    }
                    Message::Text(t) => {
                        let v: Option<serde_json::Value> = serde_json::from_str(t.as_str()).ok();
                        match v.as_ref().and_then(|v| Some((v.get("type")?.as_str()?, v))) {
                            Some(("ping", v)) => {
                                send_text(&mut sink, &json!({"type": "pong", "t": v.get("t")})).await?;
                            }
                            Some(("scene", _)) => resync(&mut sink, ctx, keys).await?,
                            _ => {
                                Counters::add(&ctx.counters.refused, 1);
                                send_text(&mut sink, &json!({"type": "error",
                                    "reason": "text frames carry only {\"type\":\"ping\"} or {\"type\":\"scene\"}; commands are binary frames"})).await?;
                            }
                        }
                    }
                    Message::Ping(_) | Message::Pong(_) | Message::Close(_) => {}
                }
            }
        }
    }
    Ok(())
}

/// Most hand tokens kept for one page: beyond it, those of hands already let go are dropped.
const MAX_HAND_TOKENS: usize = 16;

/// Keep a `…/hand/<hand>` token for each hand a page grabs with (and whether it was let go).
/// A release does not drop its token at once: the token's end travels apart from the
/// release, and arriving first it would make the release a refusal ("holds no body").
async fn track_hand(
    ctx: &Ctx,
    keys: &Keys,
    payload: &[u8],
    hands: &mut HashMap<u64, (LivelinessToken, bool)>,
) {
    match decode::<Drag>(payload) {
        Ok(Drag::Grab { hand, .. }) => {
            if let Some(h) = hands.get_mut(&hand) {
                h.1 = false;
                return;
            }
            if hands.len() >= MAX_HAND_TOKENS {
                hands.retain(|_, (_, released)| !*released);
            }
            match ctx
                .session
                .liveliness()
                .declare_token(keys.hand(hand))
                .await
            {
                Ok(token) => {
                    hands.insert(hand, (token, false));
                }
                // The daemon's 3 s time-out still lets the hand go.
                Err(e) => tracing::debug!("hand token: {e}"),
            }
        }
        Ok(Drag::Release { hand }) => {
            if let Some(h) = hands.get_mut(&hand) {
                h.1 = true;
            }
        }
        _ => {}
    }
}

async fn put(ctx: &Ctx, keys: &Keys, c: wire::Checked) -> Result<(), String> {
    // Tilt and gravity are superseded by the next reading; the rest must not be lost.
    let cc = match c.key {
        CommandKey::Tilt | CommandKey::Gravity => CongestionControl::Drop,
        _ => CongestionControl::Block,
    };
    ctx.session
        .put(keys.command(c.key), c.payload)
        .congestion_control(cc)
        .await
        .map_err(|e| format!("put on {}: {e}", keys.command(c.key)))
}

async fn resync<S>(sink: &mut S, ctx: &Ctx, keys: &Keys) -> Result<(), String>
where
    S: SinkExt<Message> + Unpin,
    S::Error: std::fmt::Display,
{
    let Ok(replies) = ctx
        .session
        .get(format!("{}?joints", keys.scene()))
        .timeout(Duration::from_secs(2))
        .await
    else {
        return Ok(());
    };
    while let Ok(reply) = replies.recv_async().await {
        if let Ok(sample) = reply.into_result() {
            let f = wire::frame(Tag::SceneWithJoints, &sample.payload().to_bytes());
            send_frame(sink, &ctx.counters, f).await?;
            return send_text(sink, &json!({"type": "server", "alive": true})).await;
        }
    }
    Ok(())
}

async fn send_frame<S>(sink: &mut S, counters: &Counters, f: Vec<u8>) -> Result<(), String>
where
    S: SinkExt<Message> + Unpin,
    S::Error: std::fmt::Display,
{
    Counters::add(&counters.frames_out, 1);
    Counters::add(&counters.bytes_out, f.len() as u64);
    sink.send(Message::Binary(f.into()))
        .await
        .map_err(|e| e.to_string())
}

async fn send_text<S>(sink: &mut S, v: &serde_json::Value) -> Result<(), String>
where
    S: SinkExt<Message> + Unpin,
    S::Error: std::fmt::Display,
{
    sink.send(Message::Text(v.to_string().into()))
        .await
        .map_err(|e| e.to_string())
}
