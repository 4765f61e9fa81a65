//! The WebSocket wire between `tiltbox-web` and its page.
//!
//! Every binary frame is one **tag byte** naming a key, then the payload of that key exactly
//! as `docs/protocol.md` documents it (the version byte and the postcard message). Text
//! frames carry the gateway's own small JSON notes (hello, worlds, errors, pings), never
//! protocol messages.
//!
//! Frames from a page are decoded with the protocol's own decoders, re-encoded, and only then
//! put on Zenoh; anything else is refused with a reason and changes nothing.

use crate::protocol::{
    self, Build, CommandKey, DecodeError, Drag, Remove, RemoveJoints, Reset, SetGravity,
    SetVelocity, Spawn, Tilt,
};
use std::fmt;

/// The tag byte of a frame: which key its payload belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Tag {
    /// `…/poses` (gateway → page): a `Snapshot`.
    Poses = 1,
    /// `…/events` (gateway → page): an `Event`.
    Events = 2,
    /// `…/stats` (gateway → page): a `Stats`.
    Stats = 3,
    /// `…/scene` reply (gateway → page): a `SceneState`.
    Scene = 4,
    /// `…/gravity` (page → gateway): a `SetGravity`.
    Gravity = 5,
    /// `…/tilt` (page → gateway): a `Tilt`.
    Tilt = 6,
    /// `…/spawn` (page → gateway): a `Spawn`.
    Spawn = 7,
    /// `…/remove` (page → gateway): a `Remove`.
    Remove = 8,
    /// `…/reset` (page → gateway): a `Reset`.
    Reset = 9,
    /// `…/velocity` (page → gateway): a `SetVelocity` (drive a kinematic body).
    Velocity = 10,
    /// `…/drag` (page → gateway): a `Drag` (grab, move, release a body).
    Drag = 11,
    /// `…/build` (page → gateway): a `Build` (bodies of several shapes, joints).
    Build = 12,
    /// `…/remove_joints` (page → gateway): a `RemoveJoints`.
    RemoveJoints = 13,
    /// `…/scene?joints` reply (gateway → page): a `SceneWithJoints`, sent where tag 4 was
    /// before (2026-11-26).
    SceneWithJoints = 14,
}

impl Tag {
    /// The tag of a byte, if it is one.
    pub fn from_byte(b: u8) -> Option<Tag> {
        Some(match b {
            1 => Tag::Poses,
            2 => Tag::Events,
            3 => Tag::Stats,
            4 => Tag::Scene,
            5 => Tag::Gravity,
            6 => Tag::Tilt,
            7 => Tag::Spawn,
            8 => Tag::Remove,
            9 => Tag::Reset,
            10 => Tag::Velocity,
            11 => Tag::Drag,
            12 => Tag::Build,
            13 => Tag::RemoveJoints,
            14 => Tag::SceneWithJoints,
            _ => return None,
        })
    }

    /// The command key a page may send this tag to, or None for the downstream tags.
    pub fn command(self) -> Option<CommandKey> {
        Some(match self {
            Tag::Gravity => CommandKey::Gravity,
            Tag::Tilt => CommandKey::Tilt,
            Tag::Spawn => CommandKey::Spawn,
            Tag::Remove => CommandKey::Remove,
            Tag::Reset => CommandKey::Reset,
            Tag::Velocity => CommandKey::Velocity,
            Tag::Drag => CommandKey::Drag,
            Tag::Build => CommandKey::Build,
            Tag::RemoveJoints => CommandKey::RemoveJoints,
            _ => return None,
        })
    }
}

/// A downstream frame: `tag` then `payload`.
pub fn frame(tag: Tag, payload: &[u8]) -> Vec<u8> {
    let mut v = Vec::with_capacity(payload.len() + 1);
    v.push(tag as u8);
    v.extend_from_slice(payload);
    v
}

/// Which commands pages may send (`--allow`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Allow([bool; CommandKey::ALL.len()]);

impl Allow {
    /// Nothing allowed: a watch-only page.
    pub const NONE: Allow = Allow([false; CommandKey::ALL.len()]);

    /// The default: tilt and spawn.
    pub fn default_set() -> Allow {
        Allow::NONE
            .with(CommandKey::Tilt)
            .with(CommandKey::Spawn)
            .with(CommandKey::Drag)
    }

    /// This set plus `key`.
    pub fn with(mut self, key: CommandKey) -> Allow {
        self.0[key.index()] = true;
        self
    }

    /// Whether pages may send `key`.
    pub fn allows(&self, key: CommandKey) -> bool {
        self.0[key.index()]
    }

    /// The allowed keys' names, in [`CommandKey::ALL`] order.
    pub fn names(&self) -> Vec<&'static str> {
        CommandKey::ALL
            .iter()
            .filter(|k| self.allows(**k))
            .map(|k| k.suffix())
            .collect()
    }

    /// Parse `tilt,spawn,reset` (`none` or an empty string: nothing).
    pub fn parse(s: &str) -> Result<Allow, String> {
        let mut a = Allow::NONE;
        for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            if part == "none" {
                continue;
            }
            let key = CommandKey::ALL
                .into_iter()
                .find(|k| k.suffix() == part)
                .ok_or_else(|| {
                    format!(
                        "--allow {s:?}: unknown command {part:?} (one of gravity, tilt, spawn, remove, reset, velocity, none)"
                    )
                })?;
            a = a.with(key);
        }
        Ok(a)
    }
}

impl fmt::Display for Allow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.names();
        if n.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&n.join(","))
        }
    }
}

/// Why a frame from a page was refused. Nothing was put on Zenoh.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Refusal {
    /// A binary frame with no bytes.
    #[error("empty frame: expected a tag byte and a payload")]
    Empty,
    /// The first byte is no tag.
    #[error("unknown tag {0:#04x}")]
    UnknownTag(u8),
    /// A tag the gateway only sends.
    #[error("tag {0:#04x} ({1}) is sent by the gateway, not accepted from a page")]
    Downstream(u8, &'static str),
    /// A command this gateway's `--allow` leaves out.
    #[error("{0} is not allowed by this gateway (--allow {1})")]
    NotAllowed(CommandKey, String),
    /// The payload does not decode as the tag's message.
    #[error("{key}: {source}")]
    Decode {
        /// The key.
        key: CommandKey,
        /// The protocol's decode error.
        source: DecodeError,
    },
    /// The per-connection rate limit.
    #[error("rate limit: more than {0} commands per second from this page")]
    RateLimited(u32),
}

/// A command from a page, decoded, checked and re-encoded: ready to put on `key`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Checked {
    /// The key it goes to.
    pub key: CommandKey,
    /// The payload: the version byte and the postcard message, as re-encoded by this build.
    pub payload: Vec<u8>,
}

fn recode<M: protocol::Message>(key: CommandKey, bytes: &[u8]) -> Result<Checked, Refusal> {
    let msg: M = protocol::decode(bytes).map_err(|source| Refusal::Decode { key, source })?;
    let payload = protocol::encode(&msg).map_err(|e| Refusal::Decode {
        key,
        source: DecodeError::Malformed {
            message: e.message,
            what: "cannot be encoded again",
        },
    })?;
    Ok(Checked { key, payload })
}

/// Decode and check one binary frame from a page.
pub fn check_upstream(bytes: &[u8], allow: &Allow) -> Result<Checked, Refusal> {
    let (&tag_byte, payload) = bytes.split_first().ok_or(Refusal::Empty)?;
    let tag = Tag::from_byte(tag_byte).ok_or(Refusal::UnknownTag(tag_byte))?;
    let key = tag.command().ok_or_else(|| {
        let name = match tag {
            Tag::Poses => "poses",
            Tag::Events => "events",
            Tag::Stats => "stats",
            _ => "scene",
        };
        Refusal::Downstream(tag_byte, name)
    })?;
    if !allow.allows(key) {
        return Err(Refusal::NotAllowed(key, allow.to_string()));
    }
    match key {
        CommandKey::Gravity => recode::<SetGravity>(key, payload),
        CommandKey::Tilt => recode::<Tilt>(key, payload),
        CommandKey::Spawn => recode::<Spawn>(key, payload),
        CommandKey::Remove => recode::<Remove>(key, payload),
        CommandKey::Reset => recode::<Reset>(key, payload),
        CommandKey::Velocity => recode::<SetVelocity>(key, payload),
        CommandKey::Drag => recode::<Drag>(key, payload),
        CommandKey::Build => recode::<Build>(key, payload),
        CommandKey::RemoveJoints => recode::<RemoveJoints>(key, payload),
    }
}

pub use crate::protocol::RateLimit;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{encode, Orientation};
    use std::time::{Duration, Instant};

    #[test]
    fn allowed_commands_are_decoded_and_re_encoded() {
        let allow = Allow::default_set();
        let tilt = encode(&Tilt::Orientation(Orientation::LandscapeLeft)).unwrap();
        let c = check_upstream(&frame(Tag::Tilt, &tilt), &allow).unwrap();
        assert_eq!(c.key, CommandKey::Tilt);
        assert_eq!(c.payload, tilt);
        assert_eq!(
            check_upstream(&frame(Tag::Reset, &[1]), &allow),
            Err(Refusal::NotAllowed(
                CommandKey::Reset,
                "tilt,spawn,drag".to_string()
            ))
        );
        let all = Allow::parse("gravity, tilt,spawn,remove,reset").unwrap();
        assert!(check_upstream(&frame(Tag::Reset, &[1]), &all).is_ok());
        assert_eq!(Allow::parse("none").unwrap(), Allow::NONE);
        assert!(Allow::parse("tilt,fly").unwrap_err().contains("\"fly\""));
    }

    #[test]
    fn garbage_is_refused_with_a_reason() {
        let all = Allow::parse("gravity,tilt,spawn,remove,reset").unwrap();
        assert_eq!(check_upstream(&[], &all), Err(Refusal::Empty));
        assert_eq!(
            check_upstream(&[0xee], &all),
            Err(Refusal::UnknownTag(0xee))
        );
        assert!(matches!(
            check_upstream(&[1, 1, 0], &all),
            Err(Refusal::Downstream(1, "poses"))
        ));
        for bad in [
            &[6u8][..],
            &[6, 1, 9],
            &[6, 2, 0, 0],
            &[7, 1, 0xff, 0xff, 0xff],
            &[9, 1, 0],
        ] {
            let e = check_upstream(bad, &all).unwrap_err();
            assert!(matches!(e, Refusal::Decode { .. }), "{bad:?}: {e}");
        }
        let e = check_upstream(&[6, 1, 9], &all).unwrap_err().to_string();
        assert!(e.starts_with("tilt: unknown variant in Tilt"), "{e}");
    }

    #[test]
    fn the_rate_limit_refills_over_time() {
        let t0 = Instant::now();
        let mut r = RateLimit::new(10);
        assert!((0..10).all(|_| r.take(t0)));
        assert!(!r.take(t0));
        assert!(r.take(t0 + Duration::from_millis(110)));
        assert!(!r.take(t0 + Duration::from_millis(110)));
        assert!(!RateLimit::new(0).take(t0));
    }
}
