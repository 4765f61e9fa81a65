//! Fewer half-empty bundles in small solves: a contact changes colour into a bundle with a
//! free lane wherever that changes no body's order of constraints.
//!
//! Each colour's list of bundles ends in a bundle with free lanes, and a small solve is mostly
//! such bundles: Falling Bricks' 8 contacts take 4 bundles of 4 lanes, because its ground
//! contacts keep to the top colours (solved last, `graph.rs`). Every bundle costs a full
//! bundle's work in every pass. A Gauss-Seidel solve's result depends only on the order in
//! which each body's constraints are applied, and a bundle's lanes do not mix, so a contact may
//! move from colour `from` to colour `to` when neither of its bodies has a constraint in any
//! colour between them (`to` included, `from` excluded): every body then sees its constraints
//! in the same order as before, and the solve gives the same numbers to the bit. Moving one
//! contact out of a list whose last bundle holds only it, into a list whose last bundle has a
//! free lane, saves a bundle.
//!
//! Joints take colours too and are not seen here: a solve with joints does not move contacts.

use super::graph::{COLOURS, OVERFLOW};

/// Solves of up to this many contacts look for moves (a scan over the solve's contacts per
/// candidate, against at most one bundle saved per list: large solves gain nothing from it).
pub(crate) const GAPS_FILLED_UP_TO: usize = 32;

/// A body that is not a node of the graph (static or kinematic, or the fixed dummy).
pub(crate) const NOT_A_NODE: u32 = u32::MAX;

/// One contact of a small solve as the move needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Entry {
    /// The colour it is solved in (changed by [`fill_gaps`]); [`OVERFLOW`] stays put.
    pub colour: u8,
    /// Its bundle kind's list within a colour.
    pub kind: u8,
    /// Its bodies' slots, [`NOT_A_NODE`] for a body no constraint is ordered on.
    pub nodes: [u32; 2],
}

/// Move contacts of `entries` (packed `width` lanes a bundle, a power of two, in lists of
/// `kinds` kinds per colour) between colours where that saves a bundle and changes no body's
/// order of constraints (see the module's comment). Returns how many bundles it saved.
pub(crate) fn fill_gaps(entries: &mut [Entry], width: usize, kinds: usize) -> usize {
    debug_assert!(width.is_power_of_two() && kinds <= 4 && entries.len() <= u8::MAX as usize);
    let part = width - 1;
    let mut counts = [0u8; COLOURS * 4];
    let list = |colour: usize, kind: u8| colour * kinds + kind as usize;
    for e in entries.iter().filter(|e| e.colour < OVERFLOW) {
        counts[list(e.colour as usize, e.kind)] += 1;
    }
    // Per kind, a bit for each colour whose last bundle has a free lane.
    // (From the contacts, not from every list: a few contacts against 96 lists.)
    let mut open = [0u64; 4];
    for e in entries.iter().filter(|e| e.colour < OVERFLOW) {
        if counts[list(e.colour as usize, e.kind)] as usize & part != 0 {
            open[e.kind as usize] |= 1 << e.colour;
        }
    }
    let mut saved = 0;
    for x in 0..entries.len() {
        let Entry { colour, kind, .. } = entries[x];
        if colour >= OVERFLOW || counts[list(colour as usize, kind)] as usize & part != 1 {
            continue;
        }
        let reach = reachable(colours_on_bodies(entries, x), colour as u32);
        let Some(to) = nearest(open[kind as usize] & reach, colour as u32) else {
            continue;
        };
        for (c, change) in [(colour as usize, -1), (to as usize, 1)] {
            let n = &mut counts[list(c, kind)];
            *n = n.wrapping_add_signed(change);
            let bit = 1u64 << c;
            open[kind as usize] = if *n as usize & part != 0 {
                open[kind as usize] | bit
            } else {
                open[kind as usize] & !bit
            };
        }
        entries[x].colour = to as u8;
        saved += 1;
    }
    saved
}

/// The colours a contact of colour `from` may move to, one bit each: those between `from` and
/// the nearest colour `taken` on either side (by another constraint on one of its bodies).
fn reachable(taken: u64, from: u32) -> u64 {
    let below = taken & ((1 << from) - 1);
    let low = 64 - below.leading_zeros();
    let above = taken & !((2 << from) - 1);
    let high = if above == 0 {
        COLOURS as u32
    } else {
        above.trailing_zeros()
    };
    let up_to_high = (1u64 << high) - 1;
    let from_low = !((1u64 << low) - 1);
    up_to_high & from_low & !(1 << from)
}

/// The colour of `candidates` nearest below `from`, else nearest above.
fn nearest(candidates: u64, from: u32) -> Option<u32> {
    let below = candidates & ((1 << from) - 1);
    if below != 0 {
        return Some(63 - below.leading_zeros());
    }
    let above = candidates & !((2 << from) - 1);
    (above != 0).then(|| above.trailing_zeros())
}

/// The colours of every other contact of `entries` that shares a node with contact `x`, one
/// bit each (the overflow's left out: it is solved before every colour).
fn colours_on_bodies(entries: &[Entry], x: usize) -> u64 {
    let nodes = entries[x].nodes;
    let shares = |e: &Entry| {
        e.nodes
            .iter()
            .any(|&n| n != NOT_A_NODE && nodes.contains(&n))
    };
    entries
        .iter()
        .enumerate()
        .filter(|&(y, e)| y != x && e.colour < OVERFLOW && shares(e))
        .fold(0, |taken, (_, e)| taken | 1u64 << e.colour)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(colour: u8, nodes: [u32; 2]) -> Entry {
        Entry {
            colour,
            kind: 0,
            nodes,
        }
    }

    const G: u32 = NOT_A_NODE;

    /// Falling Bricks' solve as the graph colours it: ground contacts in colour 31, two in
    /// colour 0 and one in colour 1 (body 9 has three constraints). Four bundles of four
    /// lanes; three suffice (body 9's three constraints need three), and a ground contact
    /// whose brick has no constraint in colours 1-30 can join colour 1.
    #[test]
    fn falling_bricks_needs_three_bundles_not_four() {
        let mut entries = [
            entry(31, [G, 4]),
            entry(31, [G, 5]),
            entry(31, [G, 7]),
            entry(31, [G, 8]),
            entry(31, [G, 9]),
            entry(0, [4, 7]),
            entry(1, [5, 9]),
            entry(0, [6, 9]),
        ];
        assert_eq!(fill_gaps(&mut entries, 4, 3), 1);
        let bundles = |c: u8| entries.iter().filter(|e| e.colour == c).count().div_ceil(4);
        assert_eq!(bundles(0) + bundles(1) + bundles(31), 3);
        // The moved contact shares no node with colour 1's: the colour stays valid.
        let moved = entries
            .iter()
            .position(|e| e.colour == 1 && e.nodes[0] == G);
        let moved = moved.expect("a ground contact joined colour 1");
        assert!(!entries[moved].nodes.contains(&5) && !entries[moved].nodes.contains(&9));
    }

    /// A contact does not cross a colour in which one of its bodies has a constraint: body 2's
    /// order (colour 5 before colour 9) would change.
    #[test]
    fn a_move_never_reorders_a_body() {
        let mut entries = [
            entry(9, [G, 2]),
            entry(9, [G, 3]),
            entry(9, [G, 4]),
            entry(9, [G, 6]),
            entry(9, [G, 8]),
            entry(5, [2, 7]),
        ];
        // Another ground contact goes down to colour 5; body 2's may not.
        let before = entries;
        assert_eq!(fill_gaps(&mut entries, 4, 3), 1);
        let moved: Vec<usize> = (0..6).filter(|&i| entries[i] != before[i]).collect();
        assert_eq!(moved.len(), 1);
        assert_ne!(
            entries[moved[0]].nodes,
            [G, 2],
            "body 2 would see colour 9 before 5"
        );
        assert_eq!(entries[moved[0]].colour, 5);
    }

    /// Between the nearest taken colours on either side, never itself; the nearest below
    /// first.
    #[test]
    fn reach_stops_at_the_nearest_taken_colours() {
        let bits = |cs: &[u32]| cs.iter().fold(0u64, |m, &c| m | 1 << c);
        assert_eq!(reachable(bits(&[3, 10]), 7), bits(&[4, 5, 6, 8, 9]));
        assert_eq!(reachable(0, 31), bits(&(0..31).collect::<Vec<_>>()));
        assert_eq!(reachable(bits(&[30]), 31), 0);
        assert_eq!(reachable(bits(&[0]), 0), bits(&(1..32).collect::<Vec<_>>()));
        assert_eq!(nearest(bits(&[2, 5, 9]), 7), Some(5));
        assert_eq!(nearest(bits(&[9, 12]), 7), Some(9));
        assert_eq!(nearest(bits(&[7]), 7), None);
    }

    /// No free lane anywhere, or a lone bundle of its own kind only: nothing moves.
    #[test]
    fn nothing_moves_without_a_bundle_to_save() {
        let mut full = [
            entry(31, [G, 1]),
            entry(31, [G, 2]),
            entry(31, [G, 3]),
            entry(31, [G, 4]),
            entry(0, [5, 6]),
        ];
        assert_eq!(fill_gaps(&mut full, 4, 3), 0);
        let mut other_kind = [entry(31, [G, 1]), entry(0, [5, 6])];
        other_kind[1].kind = 1;
        assert_eq!(fill_gaps(&mut other_kind, 4, 3), 0);
        let mut overflow = [entry(OVERFLOW, [1, 2]), entry(3, [5, 6])];
        assert_eq!(fill_gaps(&mut overflow, 4, 3), 0);
    }
}
