//! Collision filters: which bodies' shapes may touch (Box2D's `b2Filter`).

use serde::{Deserialize, Serialize};

/// A shape's collision filter. Two shapes collide when they share a nonzero `group` that is
/// positive (never when it is negative), and otherwise when each one's `category` is in the
/// other's `mask`. The default (category 1, mask all, group 0) collides with everything.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(default)]
pub struct Filter {
    /// The categories this shape is in, one bit each (usually one bit).
    pub category: u64,
    /// The categories it collides with.
    pub mask: u64,
    /// Shapes of the same nonzero group always collide (positive) or never (negative),
    /// whatever their categories; 0: no group.
    pub group: i32,
}

impl Filter {
    /// Collides with everything: category 1, mask all, no group.
    pub const DEFAULT: Filter = Filter {
        category: 1,
        mask: u64::MAX,
        group: 0,
    };

    /// Whether shapes with filters `self` and `other` collide.
    #[inline]
    pub fn should_collide(&self, other: &Filter) -> bool {
        if self.group == other.group && self.group != 0 {
            return self.group > 0;
        }
        self.category & other.mask != 0 && other.category & self.mask != 0
    }
}

impl Default for Filter {
    fn default() -> Self {
        Filter::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn filters_collide_as_box2d_says() {
        let d = Filter::DEFAULT;
        assert!(d.should_collide(&d));
        let player = Filter {
            category: 0b10,
            mask: !0b10,
            group: 0,
        };
        // Players pass through players, hit everything else both ways.
        assert!(!player.should_collide(&player));
        assert!(player.should_collide(&d) && d.should_collide(&player));
        // A mask that leaves the other's category out refuses, whichever side asks.
        let ghost = Filter {
            mask: 0,
            ..Filter::DEFAULT
        };
        assert!(!ghost.should_collide(&d) && !d.should_collide(&ghost));
        // A shared negative group never collides, a shared positive one always does,
        // whatever the categories; different groups fall back to the categories.
        let ragdoll = Filter {
            group: -1,
            ..Filter::DEFAULT
        };
        assert!(!ragdoll.should_collide(&ragdoll));
        let team = Filter { group: 3, ..ghost };
        assert!(team.should_collide(&team));
        let other_team = Filter { group: 4, ..ghost };
        assert!(!team.should_collide(&other_team));
        assert!(ragdoll.should_collide(&d));
    }
}
