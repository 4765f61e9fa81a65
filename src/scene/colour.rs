//! Body colours: one type for scene files, the wire, journals and checkpoints.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;
use std::str::FromStr;

/// An sRGB colour, 8 bits per channel, used by viewers to draw a body (no effect on physics).
///
/// Its serde form depends on the format. Human-readable formats (scene files in TOML, JSON)
/// write and read `"#rrggbb"` (six hex digits, either case), as [`fmt::Display`] and
/// [`FromStr`] do. Binary formats (postcard: the wire protocol, journals, checkpoints) write the
/// three channels as three bytes, red first (`docs/protocol.md`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Colour {
    /// Red, 0-255.
    pub r: u8,
    /// Green, 0-255.
    pub g: u8,
    /// Blue, 0-255.
    pub b: u8,
}

impl Colour {
    /// The neutral grey `#808080` given to bodies whose scene entry has no colour.
    pub const GREY: Colour = Colour::new(0x80, 0x80, 0x80);

    /// A colour from its red, green and blue channels (0-255 each).
    pub const fn new(r: u8, g: u8, b: u8) -> Colour {
        Colour { r, g, b }
    }
}

impl Default for Colour {
    /// [`Colour::GREY`].
    fn default() -> Self {
        Colour::GREY
    }
}

impl fmt::Display for Colour {
    /// `#rrggbb`, lower-case hex.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{:02x}{:02x}{:02x}", self.r, self.g, self.b)
    }
}

/// A colour string that is not `"#rrggbb"`; holds the string as given.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("colour {0:?} is not \"#rrggbb\" (a '#' and six hex digits)")]
pub struct ParseColourError(
    /// The string as given.
    pub String,
);

impl FromStr for Colour {
    type Err = ParseColourError;

    /// Parse `"#rrggbb"` (six hex digits, either case).
    fn from_str(s: &str) -> Result<Colour, ParseColourError> {
        let bad = || ParseColourError(s.to_owned());
        let hex = s.strip_prefix('#').ok_or_else(bad)?;
        if hex.len() != 6 || !hex.bytes().all(|c| c.is_ascii_hexdigit()) {
            return Err(bad());
        }
        let channel = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).map_err(|_| bad());
        Ok(Colour::new(channel(0)?, channel(2)?, channel(4)?))
    }
}

/// The binary form: three bytes, red, green, blue.
#[derive(Serialize, Deserialize)]
#[serde(rename = "Colour")]
struct Channels {
    r: u8,
    g: u8,
    b: u8,
}

impl Serialize for Colour {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        if serializer.is_human_readable() {
            serializer.collect_str(self)
        } else {
            let Colour { r, g, b } = *self;
            Channels { r, g, b }.serialize(serializer)
        }
    }
}

impl<'de> Deserialize<'de> for Colour {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Colour, D::Error> {
        if deserializer.is_human_readable() {
            let s = String::deserialize(deserializer)?;
            s.parse().map_err(serde::de::Error::custom)
        } else {
            let Channels { r, g, b } = Channels::deserialize(deserializer)?;
            Ok(Colour::new(r, g, b))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_through_its_string_form() {
        let c: Colour = "#D64541".parse().unwrap();
        assert_eq!(c, Colour::new(0xd6, 0x45, 0x41));
        assert_eq!(c.to_string(), "#d64541");
        assert_eq!(Colour::GREY.to_string(), "#808080");
    }

    #[cfg(feature = "net")] // postcard comes with the wire protocol
    #[test]
    fn binary_formats_carry_three_bytes_and_text_formats_the_hex_string() {
        let c = Colour::new(0xd6, 0x45, 0x41);
        let bytes = postcard::to_allocvec(&c).unwrap();
        assert_eq!(bytes, [0xd6, 0x45, 0x41]);
        assert_eq!(postcard::from_bytes::<Colour>(&bytes).unwrap(), c);
        #[derive(Serialize, Deserialize)]
        struct Entry {
            colour: Colour,
        }
        let text = toml::to_string(&Entry { colour: c }).unwrap();
        assert_eq!(text.trim(), "colour = \"#d64541\"");
        assert_eq!(toml::from_str::<Entry>(&text).unwrap().colour, c);
    }

    #[test]
    fn refuses_anything_else() {
        for s in [
            "", "#", "d64541", "#d6454", "#d645411", "#g64541", "#+1+2+3", "#ééé",
        ] {
            let e = s.parse::<Colour>().unwrap_err();
            assert_eq!(e.0, s);
        }
    }
}
