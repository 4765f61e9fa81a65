//! Length prefixes checked before the elements are read: a polygon's vertex count above
//! [`MAX_VERTICES`] is refused as soon as it is read, with the real limit, instead of
//! reading on until the payload runs out (which would report it as truncated).
//!
//! postcard turns a deserializer's own error into a bare `SerdeDeCustom` with no text, so
//! the count refused (and the index of the spawn body being read) is left in a thread-local
//! for [`super::decode`] to pick up.

use super::build::{PartShape, PartSpec, MAX_PARTS};
use super::messages::{SpawnBody, Vector};
use crate::physics::convex::MAX_VERTICES;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use std::cell::Cell;

thread_local! {
    /// The index in `Spawn.bodies` of the body being read, while a spawn is decoded.
    static BODY_INDEX: Cell<Option<usize>> = const { Cell::new(None) };
    /// (body index, vertex count) of the polygon the current decode refused.
    static REFUSED: Cell<Option<(Option<usize>, usize)>> = const { Cell::new(None) };
    /// Set while a compound's parts are read, so a compound inside one is refused at once
    /// (nesting is never read deeper than that).
    static IN_COMPOUND: Cell<bool> = const { Cell::new(false) };
    /// What was wrong with a list of parts the current decode refused.
    static REFUSED_PARTS: Cell<Option<&'static str>> = const { Cell::new(None) };
}

/// Forget what an earlier decode on this thread left (call before decoding).
pub(super) fn reset() {
    BODY_INDEX.with(|c| c.set(None));
    REFUSED.with(|c| c.set(None));
    IN_COMPOUND.with(|c| c.set(false));
    REFUSED_PARTS.with(|c| c.set(None));
}

/// Why the last decode on this thread refused a list of parts, if it did.
pub(super) fn take_refused_parts() -> Option<&'static str> {
    REFUSED_PARTS.with(Cell::take)
}

/// Refuse a list of parts: note why for [`take_refused_parts`].
fn refuse_parts<E: de::Error>(why: &'static str) -> E {
    REFUSED_PARTS.with(|c| c.set(Some(why)));
    E::custom(why)
}

/// Read up to [`MAX_PARTS`] elements, refusing a longer list by its claimed length before
/// reading any.
fn bounded_parts<'de, T: Deserialize<'de>, A: SeqAccess<'de>>(
    mut seq: A,
) -> Result<Vec<T>, A::Error> {
    if seq.size_hint().is_some_and(|n| n > MAX_PARTS) {
        return Err(refuse_parts("a body holds more than 16 parts (MAX_PARTS)"));
    }
    let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0));
    while let Some(p) = seq.next_element()? {
        if out.len() == MAX_PARTS {
            return Err(refuse_parts("a body holds more than 16 parts (MAX_PARTS)"));
        }
        out.push(p);
    }
    Ok(out)
}

/// Deserialize `BuildBody.parts`: at most [`MAX_PARTS`].
pub(super) fn parts<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<PartSpec>, D::Error> {
    struct Parts;
    impl<'de> Visitor<'de> for Parts {
        type Value = Vec<PartSpec>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "1 to {MAX_PARTS} parts")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Vec<PartSpec>, A::Error> {
            bounded_parts(seq)
        }
    }
    d.deserialize_seq(Parts)
}

/// Deserialize a compound's parts: at most [`MAX_PARTS`], none of them a compound (refused
/// as soon as one starts, so a payload cannot nest compounds to exhaust the stack).
pub(super) fn compound_parts<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<PartShape>, D::Error> {
    struct Parts;
    impl<'de> Visitor<'de> for Parts {
        type Value = Vec<PartShape>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "2 to {MAX_PARTS} parts")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Vec<PartShape>, A::Error> {
            bounded_parts(seq)
        }
    }
    if IN_COMPOUND.with(|c| c.replace(true)) {
        return Err(refuse_parts(
            "a compound's part is itself a compound (parts do not nest)",
        ));
    }
    let parts = d.deserialize_seq(Parts);
    IN_COMPOUND.with(|c| c.set(false));
    parts
}

/// The polygon the last decode on this thread refused, if any: the spawn body's index (when
/// it was in a spawn) and its vertex count.
pub(super) fn take_refused() -> Option<(Option<usize>, usize)> {
    REFUSED.with(Cell::take)
}

/// Deserialize `Spawn.bodies`, noting which body is being read for [`take_refused`].
pub(super) fn spawn_bodies<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<SpawnBody>, D::Error> {
    struct Bodies;
    impl<'de> Visitor<'de> for Bodies {
        type Value = Vec<SpawnBody>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a list of bodies")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<SpawnBody>, A::Error> {
            // A claimed length is not trusted for the allocation.
            let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(64));
            loop {
                BODY_INDEX.with(|c| c.set(Some(out.len())));
                match seq.next_element()? {
                    Some(b) => out.push(b),
                    None => break,
                }
            }
            BODY_INDEX.with(|c| c.set(None));
            Ok(out)
        }
    }
    d.deserialize_seq(Bodies)
}

/// Deserialize a polygon's vertices, refusing more than [`MAX_VERTICES`] before reading any.
///
/// A binary format (postcard) is read as its bytes are laid out - the count (a varint), then
/// the vertices - so the count is known even when it claims more than the payload holds
/// (postcard's own sequence access hides such a count). A human-readable format (TOML, for
/// `simulate --timeline`) is read as a list.
pub(super) fn vertices<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Vector>, D::Error> {
    struct Prefixed;
    impl<'de> Visitor<'de> for Prefixed {
        type Value = Vec<Vector>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "a count, then 3 to {MAX_VERTICES} vertices")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<Vector>, A::Error> {
            let missing = || de::Error::custom("the vertex count is missing");
            let n: u64 = seq.next_element()?.ok_or_else(missing)?;
            let n = usize::try_from(n).unwrap_or(usize::MAX);
            if n > MAX_VERTICES {
                let body = BODY_INDEX.with(Cell::get);
                REFUSED.with(|c| c.set(Some((body, n))));
                return Err(de::Error::custom(format!(
                    "shape.vertices must hold 3 to {MAX_VERTICES} points, got {n}"
                )));
            }
            let mut out = Vec::with_capacity(n);
            for i in 0..n {
                out.push(
                    seq.next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?,
                );
            }
            Ok(out)
        }
    }
    struct Listed;
    impl<'de> Visitor<'de> for Listed {
        type Value = Vec<Vector>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "3 to {MAX_VERTICES} vertices")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<Vector>, A::Error> {
            let mut out = Vec::with_capacity(MAX_VERTICES);
            while let Some(v) = seq.next_element()? {
                if out.len() == MAX_VERTICES {
                    return Err(de::Error::custom(format!(
                        "shape.vertices must hold 3 to {MAX_VERTICES} points, got more"
                    )));
                }
                out.push(v);
            }
            Ok(out)
        }
    }
    if d.is_human_readable() {
        d.deserialize_seq(Listed)
    } else {
        // The count and up to MAX_VERTICES vertices, read one by one.
        d.deserialize_tuple(MAX_VERTICES + 1, Prefixed)
    }
}

#[cfg(test)]
mod tests {
    use crate::protocol::*;

    /// A spawn of `n` bodies, the last a triangle whose vertex count is then rewritten as the
    /// varint `count`, with the payload left as short as it was.
    fn spawn_claiming(n: usize, count: u16) -> Vec<u8> {
        let ball = SpawnBody::at(ShapeSpec::Circle { radius: 0.5 }, Vector::new(0.0, 1.0));
        let x0 = 123.25_f32;
        let tri = ShapeSpec::Polygon {
            vertices: vec![
                Vector::new(x0, 0.0),
                Vector::new(1.0, 0.0),
                Vector::new(0.0, 1.0),
            ],
        };
        let mut bodies = vec![ball; n - 1];
        bodies.push(SpawnBody::at(tri, Vector::new(0.0, 1.0)));
        let bytes = encode(&Spawn { bodies }).unwrap();
        // The count is the byte just before the first vertex's x.
        let at = bytes
            .windows(4)
            .position(|w| w == x0.to_le_bytes())
            .unwrap()
            - 1;
        assert_eq!(bytes[at], 3);
        let mut out = bytes[..at].to_vec();
        out.extend_from_slice(&[(count as u8 & 0x7f) | 0x80, (count >> 7) as u8]);
        out.extend_from_slice(&bytes[at + 1..]);
        out
    }

    #[test]
    fn a_vertex_count_beyond_the_payload_is_refused_with_the_limit_not_as_truncated() {
        let e = decode::<Spawn>(&spawn_claiming(1, 1000)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "bodies[0]: shape.vertices must hold 3 to 8 points, got 1000"
        );
        let e = decode::<Spawn>(&spawn_claiming(3, 9)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "bodies[2]: shape.vertices must hold 3 to 8 points, got 9"
        );
        // A refusal is not remembered by the next decode on the thread.
        let ok = encode(&Spawn {
            bodies: vec![SpawnBody::at(
                ShapeSpec::Circle { radius: 0.5 },
                Vector::new(0.0, 1.0),
            )],
        })
        .unwrap();
        assert!(decode::<Spawn>(&ok).is_ok());
        let mut cut = ok.clone();
        cut.pop();
        assert!(matches!(
            decode::<Spawn>(&cut),
            Err(DecodeError::Truncated { .. })
        ));
    }
}
