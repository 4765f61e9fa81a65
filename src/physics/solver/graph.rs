//! The constraint graph: a colour for every constraint, kept from step to step, such that no
//! two constraints of one colour share a dynamic body (Box2D v3's `constraint_graph.c`).
//!
//! Within a colour the constraints are independent, so the soft step packs each colour's
//! contacts into bundles and solves them in the lanes of one SIMD value. A constraint gets its
//! colour when it begins (a contact's or a joint's first step, or its island waking) and gives
//! it back when it ends (the pair parts, a body or joint is removed, its island falls asleep);
//! in between it keeps it, so the colouring costs nothing per step. Contacts begin and end in
//! key order, joints in slot order, so the colours, and the solve order they set, are the same
//! on every run and after a checkpoint is restored (colours are part of the solver's history).
//!
//! Only dynamic bodies (awake or asleep) are nodes of the graph: nothing writes to a static or
//! kinematic body, so any number of constraints of one colour may share one. A sleeping body
//! counts as dynamic, so a colour stays valid when it wakes. Constraints between two dynamic
//! bodies take the lowest free colour among the first [`DYNAMIC_COLOURS`]; constraints with one
//! fixed body take the highest free colour, from the top down. Colours are solved in
//! ascending order and a Gauss-Seidel solve favours what it solves last, so contacts with the
//! ground win over contacts between bodies, which keeps a pile from being pushed through it
//! (Box2D's reason). A constraint that finds no free colour goes to the overflow, solved one
//! by one and first (lowest priority) by the same kernel at width one; it stays there until
//! it ends.
//!
//! Joints take colours from the same graph, by the same rules, when either body is awake
//! (a joint to the world is a constraint with one fixed body), and give them back when their
//! island sleeps or they are removed; each colour's joints are solved just before its
//! contacts. A tier of adaptive stiffness solves the subset of the colours' constraints that
//! are its own (islands of different tiers share no dynamic body, so any subset of a valid
//! colouring is one).

/// How many colours the graph has (one bit each in a body's mask).
pub(crate) const COLOURS: usize = 32;

/// Colours `0..DYNAMIC_COLOURS` are for constraints between two dynamic bodies; the rest are
/// left to constraints with a fixed body, which take colours from the top down.
pub(crate) const DYNAMIC_COLOURS: usize = COLOURS - 4;

/// The colour of a constraint the graph could not place: solved by the overflow path.
pub(crate) const OVERFLOW: u8 = COLOURS as u8;

/// The colour of a constraint that is not in the graph (a sleeping contact).
pub(crate) const UNCOLOURED: u8 = u8::MAX;

/// Per dynamic body, which colours its constraints use.
#[derive(Clone, Debug)]
pub(crate) struct ConstraintGraph {
    /// Bit c of `masks[i]` is set while a constraint of colour c joins body slot i.
    masks: Vec<u32>,
    /// Colours in use, up to [`COLOURS`] (tests lower it to send constraints to the overflow).
    colours: usize,
}

impl Default for ConstraintGraph {
    fn default() -> Self {
        ConstraintGraph {
            masks: Vec::new(),
            colours: COLOURS,
        }
    }
}

impl ConstraintGraph {
    /// A colour for a new constraint between body slots `a` and `b`, of which those marked
    /// `dynamic` are nodes of the graph (at least one is); [`OVERFLOW`] when none is free.
    pub fn add(&mut self, [a, b]: [u32; 2], dynamic: [bool; 2]) -> u8 {
        let top = a.max(b) as usize;
        if self.masks.len() <= top {
            self.masks.resize(top + 1, 0);
        }
        let colour = match dynamic {
            [true, true] => {
                let used = self.masks[a as usize] | self.masks[b as usize];
                (0..DYNAMIC_COLOURS.min(self.colours)).find(|&c| used & 1 << c == 0)
            }
            [true, false] | [false, true] => {
                let node = if dynamic[0] { a } else { b };
                let used = self.masks[node as usize];
                (1..self.colours).rev().find(|&c| used & 1 << c == 0)
            }
            [false, false] => None,
        };
        let Some(colour) = colour else {
            return OVERFLOW;
        };
        for (i, node) in [a, b].into_iter().zip(dynamic) {
            if node {
                self.masks[i as usize] |= 1 << colour;
            }
        }
        colour as u8
    }

    /// Give back the colour of a constraint between slots `a` and `b` that ends. A fixed
    /// body's mask never has the bit, so clearing it there changes nothing.
    pub fn remove(&mut self, colour: u8, [a, b]: [u32; 2]) {
        if colour >= OVERFLOW {
            return;
        }
        for i in [a, b] {
            if let Some(mask) = self.masks.get_mut(i as usize) {
                *mask &= !(1 << colour);
            }
        }
    }

    /// Put back a constraint of `colour` between `a` and `b` (those marked `dynamic` being
    /// nodes), as a checkpoint has it: false, changing nothing, when the colour is taken on
    /// either body or out of range.
    pub fn restore(&mut self, colour: u8, [a, b]: [u32; 2], dynamic: [bool; 2]) -> bool {
        if colour == OVERFLOW {
            return true;
        }
        if colour as usize >= self.colours {
            return false;
        }
        let top = a.max(b) as usize;
        if self.masks.len() <= top {
            self.masks.resize(top + 1, 0);
        }
        let bit = 1u32 << colour;
        let taken = [a, b]
            .into_iter()
            .zip(dynamic)
            .any(|(i, node)| node && self.masks[i as usize] & bit != 0);
        if taken {
            return false;
        }
        for (i, node) in [a, b].into_iter().zip(dynamic) {
            if node {
                self.masks[i as usize] |= bit;
            }
        }
        true
    }

    /// No constraint at all.
    pub fn clear(&mut self) {
        self.masks.clear();
    }

    /// Body slot `i`'s mask (tests check it against the contacts).
    #[cfg(test)]
    pub fn mask(&self, i: u32) -> u32 {
        self.masks.get(i as usize).copied().unwrap_or(0)
    }

    /// Use only the first `colours` colours (0: every new constraint overflows).
    #[cfg(test)]
    pub fn limit_colours(&mut self, colours: usize) {
        self.colours = colours.min(COLOURS);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three bodies in a row (0-1-2) and a ground (3): the two dynamic pairs share body 1, so
    /// they take colours 0 and 1; the ground contacts take the top colours, one per body but
    /// the same colour for bodies that share nothing; a colour given back is taken again.
    #[test]
    fn colours_are_lowest_free_for_pairs_and_highest_free_against_fixed_bodies() {
        let mut g = ConstraintGraph::default();
        assert_eq!(g.add([0, 1], [true, true]), 0);
        assert_eq!(g.add([1, 2], [true, true]), 1);
        let top = (COLOURS - 1) as u8;
        assert_eq!(g.add([0, 3], [true, false]), top);
        assert_eq!(g.add([2, 3], [true, false]), top);
        assert_eq!(g.add([1, 3], [true, false]), top);
        // a second fixed body under body 1: the next colour down
        assert_eq!(g.add([1, 4], [true, false]), top - 1);
        g.remove(0, [0, 1]);
        assert_eq!(g.add([0, 2], [true, true]), 0);
    }

    /// A body with a constraint in every dynamic colour sends the next one to the overflow;
    /// a graph limited to no colours overflows everything.
    #[test]
    fn a_crowded_body_overflows() {
        let mut g = ConstraintGraph::default();
        for other in 1..=DYNAMIC_COLOURS as u32 {
            assert!(g.add([0, other], [true, true]) < OVERFLOW);
        }
        assert_eq!(g.add([0, 100], [true, true]), OVERFLOW);
        // a fixed body still finds one of the colours kept for it
        assert!(g.add([0, 101], [true, false]) >= DYNAMIC_COLOURS as u8);
        let mut none = ConstraintGraph::default();
        none.limit_colours(0);
        assert_eq!(none.add([0, 1], [true, true]), OVERFLOW);
        assert_eq!(none.add([0, 2], [true, false]), OVERFLOW);
    }

    /// Restoring checks the colour is free on both dynamic bodies.
    #[test]
    fn restore_refuses_a_colour_already_taken() {
        let mut g = ConstraintGraph::default();
        assert!(g.restore(3, [0, 1], [true, true]));
        assert!(!g.restore(3, [1, 2], [true, true]));
        assert!(g.restore(3, [2, 9], [true, false]));
        assert!(g.restore(OVERFLOW, [0, 1], [true, true]));
        assert!(!g.restore(40, [5, 6], [true, true]));
    }
}
