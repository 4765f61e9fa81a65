//! Key expressions: every key the daemon uses, built in one place from the prefix.

use std::fmt;

/// The default world name.
pub const DEFAULT_WORLD: &str = "bricks";

/// Declares the command keys from one table, in wire order: each [`CommandKey`] variant with
/// the last segment of its key, which is also the name of the [`Keys`] method that builds it.
/// [`CommandKey::ALL`], [`CommandKey::suffix`] and those methods all come from the table.
macro_rules! command_keys {
    ($($(#[$doc:meta])* $variant:ident => $suffix:ident,)*) => {
        /// Which command key a message arrived on (the keys clients write to).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum CommandKey {
            $($(#[$doc])* $variant,)*
        }

        impl CommandKey {
            /// Every command key, in a fixed order (its index is [`CommandKey::index`]).
            pub const ALL: [CommandKey; [$(CommandKey::$variant),*].len()] =
                [$(CommandKey::$variant),*];

            /// The last segment of the key, e.g. `spawn`.
            pub fn suffix(self) -> &'static str {
                match self {
                    $(CommandKey::$variant => stringify!($suffix),)*
                }
            }
        }

        impl Keys {
            $(
                #[doc = concat!("`…/", stringify!($suffix), "`")]
                pub fn $suffix(&self) -> String {
                    self.command(CommandKey::$variant)
                }
            )*
        }
    };
}

command_keys! {
    /// `…/gravity`
    Gravity => gravity,
    /// `…/tilt`
    Tilt => tilt,
    /// `…/spawn`
    Spawn => spawn,
    /// `…/remove`
    Remove => remove,
    /// `…/reset`
    Reset => reset,
    /// `…/velocity` (a kinematic body's velocity)
    Velocity => velocity,
    /// `…/drag` (grab, move and release bodies)
    Drag => drag,
    /// `…/build` (bodies of several shapes, and joints)
    Build => build,
    /// `…/remove_joints`
    RemoveJoints => remove_joints,
}

impl CommandKey {
    /// Position in [`CommandKey::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

impl fmt::Display for CommandKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.suffix())
    }
}

/// The key space of one world: `<prefix>/poses`, `<prefix>/spawn`, ...
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Keys {
    prefix: String,
}

/// Why a prefix cannot be used as a key-expression prefix.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("key prefix {prefix:?} is not usable: {reason}")]
pub struct KeyError {
    /// The prefix as given.
    pub prefix: String,
    /// What is wrong with it.
    pub reason: &'static str,
}

impl Keys {
    /// The default prefix for `world`: `tiltbox/<world>`.
    pub fn default_prefix(world: &str) -> String {
        format!("tiltbox/{world}")
    }

    /// The keys under `prefix` (e.g. `tiltbox/bricks`). The prefix must be a plain key
    /// (non-empty chunks separated by `/`, no wildcards `*`, no `$`, `?`, `#`, no leading or
    /// trailing `/`), so that every key built from it is a valid, non-wild key expression.
    pub fn new(prefix: &str) -> Result<Keys, KeyError> {
        let bad = |reason| {
            Err(KeyError {
                prefix: prefix.to_owned(),
                reason,
            })
        };
        if prefix.is_empty() {
            return bad("it is empty");
        }
        if prefix.split('/').any(str::is_empty) {
            return bad("it has an empty chunk (leading, trailing or double '/')");
        }
        if prefix.contains(['*', '$', '?', '#']) {
            return bad("it contains one of * $ ? # (wildcards and reserved characters)");
        }
        if prefix.chars().any(|c| c.is_whitespace() || c.is_control()) {
            return bad("it contains whitespace or control characters");
        }
        Ok(Keys {
            prefix: prefix.to_owned(),
        })
    }

    /// The keys of world `world` under the default prefix.
    pub fn for_world(world: &str) -> Result<Keys, KeyError> {
        Keys::new(&Keys::default_prefix(world))
    }

    /// The prefix, e.g. `tiltbox/bricks`.
    pub fn prefix(&self) -> &str {
        &self.prefix
    }

    fn key(&self, suffix: &str) -> String {
        format!("{}/{suffix}", self.prefix)
    }

    /// `…/poses`: a [`super::Snapshot`] after every step.
    pub fn poses(&self) -> String {
        self.key("poses")
    }
    /// `…/events`: [`super::Event`]s.
    pub fn events(&self) -> String {
        self.key("events")
    }
    /// `…/stats`: [`super::Stats`] once a second.
    pub fn stats(&self) -> String {
        self.key("stats")
    }
    /// `…/scene`: the queryable answering [`super::SceneState`].
    pub fn scene(&self) -> String {
        self.key("scene")
    }
    /// `…/query`: the queryable answering [`super::WorldQuery`]s.
    pub fn query(&self) -> String {
        self.key("query")
    }
    /// `…/server`: the daemon's liveliness token.
    pub fn server(&self) -> String {
        self.key("server")
    }
    /// `…/hand/<hand>`: the liveliness token a client keeps while its hand `hand` may hold a
    /// body; when it goes (the client left), the daemon lets the hand go.
    pub fn hand(&self, hand: u64) -> String {
        self.key(&format!("hand/{hand}"))
    }
    /// `…/hand/*`: every hand's token (what the daemon watches).
    pub fn hands(&self) -> String {
        self.key("hand/*")
    }
    /// The hand a `…/hand/<hand>` key names, if it is one of this world's.
    pub fn hand_of(&self, key: &str) -> Option<u64> {
        key.strip_prefix(self.prefix.as_str())?
            .strip_prefix("/hand/")?
            .parse()
            .ok()
    }
    /// The key a command is written to.
    pub fn command(&self, key: CommandKey) -> String {
        self.key(key.suffix())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_built_from_the_prefix() {
        let k = Keys::for_world(DEFAULT_WORLD).unwrap();
        assert_eq!(k.poses(), "tiltbox/bricks/poses");
        assert_eq!(k.command(CommandKey::Spawn), "tiltbox/bricks/spawn");
        assert_eq!(k.server(), "tiltbox/bricks/server");
        for (i, c) in CommandKey::ALL.iter().enumerate() {
            assert_eq!(c.index(), i);
        }
    }

    #[test]
    fn bad_prefixes_are_refused() {
        for p in ["", "/a", "a/", "a//b", "a/*", "a/**/b", "a b", "a$b"] {
            assert!(Keys::new(p).is_err(), "{p:?}");
        }
        assert!(Keys::new("lab/tiltbox/w1").is_ok());
    }
}
