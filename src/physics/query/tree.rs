//! A dynamic bounding-volume tree over the bodies, for queries (after Box2D's
//! `b2DynamicTree`): each leaf holds a body's box grown by a margin, so a body that moves a
//! little keeps its leaf; one that leaves its box is taken out and put back where the box
//! grows its new siblings least. A query descends only into boxes it touches, so its cost grows
//! with what it finds, and a ray's closest hit so far shortens the ray for the rest.
//!
//! The tree is built the first time the World is queried and brought up to date at the next
//! query after a step: a world that is never queried pays nothing for it.

use crate::physics::math::{Real, Vec2};
use crate::physics::shape::Aabb;

/// No node.
const NONE: u32 = u32::MAX;

/// One node: a leaf holds a body's slot; an inner node its two children.
#[derive(Clone, Copy, Debug)]
struct Node {
    aabb: Aabb,
    parent: u32,
    /// Inner: the children; leaf: `[NONE, slot]`.
    children: [u32; 2],
}

impl Node {
    fn is_leaf(&self) -> bool {
        self.children[0] == NONE
    }
}

/// The tree: nodes in a slot array with a free list.
#[derive(Clone, Debug, Default)]
pub(crate) struct Tree {
    nodes: Vec<Node>,
    free: Vec<u32>,
    root: Option<u32>,
}

fn union(a: &Aabb, b: &Aabb) -> Aabb {
    Aabb {
        min: a.min.min(b.min),
        max: a.max.max(b.max),
    }
}

/// Half the perimeter (m): the cost of a box, as Box2D's surface-area heuristic reckons it.
fn cost(a: &Aabb) -> Real {
    let e = a.max - a.min;
    e.x + e.y
}

impl Tree {
    /// A tree over `items` (slot, box), built top down: each node splits its boxes at the
    /// median of their centres along its longer side. Returns each item's leaf, in order.
    pub fn build(items: &[(u32, Aabb)]) -> (Tree, Vec<u32>) {
        let mut tree = Tree::default();
        let mut leaves = Vec::new();
        tree.rebuild(items, &mut Vec::new(), &mut leaves);
        (tree, leaves)
    }

    /// Build the tree afresh over `items` as [`Tree::build`] does, in its own storage (and
    /// `order`'s, scratch), so that a tree rebuilt every step allocates only as it grows;
    /// each item's leaf into `leaves`.
    pub fn rebuild(&mut self, items: &[(u32, Aabb)], order: &mut Vec<u32>, leaves: &mut Vec<u32>) {
        self.nodes.clear();
        self.nodes.reserve(2 * items.len());
        self.free.clear();
        self.root = None;
        leaves.clear();
        leaves.resize(items.len(), NONE);
        order.clear();
        order.extend(0..items.len() as u32);
        if !items.is_empty() {
            self.root = Some(self.build_node(items, order, leaves, NONE));
        }
    }

    fn build_node(
        &mut self,
        items: &[(u32, Aabb)],
        order: &mut [u32],
        leaves: &mut [u32],
        parent: u32,
    ) -> u32 {
        if let [only] = order {
            let (slot, aabb) = items[*only as usize];
            let leaf = self.allocate(Node {
                aabb,
                parent,
                children: [NONE, slot],
            });
            leaves[*only as usize] = leaf;
            return leaf;
        }
        let boxes = order.iter().map(|&i| items[i as usize].1);
        let aabb = boxes.reduce(|a, b| union(&a, &b)).expect("two or more");
        let axis = usize::from(aabb.max.y - aabb.min.y > aabb.max.x - aabb.min.x);
        let centre = |i: &u32| {
            let b = items[*i as usize].1;
            b.min[axis] + b.max[axis]
        };
        let mid = order.len() / 2;
        order.select_nth_unstable_by(mid, |a, b| centre(a).total_cmp(&centre(b)));
        let node = self.allocate(Node {
            aabb,
            parent,
            children: [NONE, NONE],
        });
        let (low, high) = order.split_at_mut(mid);
        let first = self.build_node(items, low, leaves, node);
        let second = self.build_node(items, high, leaves, node);
        self.nodes[node as usize].children = [first, second];
        node
    }

    /// The box a leaf holds.
    pub fn leaf_box(&self, leaf: u32) -> Aabb {
        self.nodes[leaf as usize].aabb
    }

    fn allocate(&mut self, node: Node) -> u32 {
        match self.free.pop() {
            Some(i) => {
                self.nodes[i as usize] = node;
                i
            }
            None => {
                self.nodes.push(node);
                self.nodes.len() as u32 - 1
            }
        }
    }

    /// Put `slot`'s box in; the new leaf.
    pub fn insert(&mut self, slot: u32, aabb: Aabb) -> u32 {
        let leaf = self.allocate(Node {
            aabb,
            parent: NONE,
            children: [NONE, slot],
        });
        let Some(root) = self.root else {
            self.root = Some(leaf);
            return leaf;
        };
        let sibling = self.best_sibling(root, &aabb);
        let old_parent = self.nodes[sibling as usize].parent;
        let parent = self.allocate(Node {
            aabb: union(&aabb, &self.nodes[sibling as usize].aabb),
            parent: old_parent,
            children: [sibling, leaf],
        });
        self.nodes[sibling as usize].parent = parent;
        self.nodes[leaf as usize].parent = parent;
        if old_parent == NONE {
            self.root = Some(parent);
        } else {
            let p = &mut self.nodes[old_parent as usize];
            let side = usize::from(p.children[1] == sibling);
            p.children[side] = parent;
        }
        self.refit(old_parent);
        leaf
    }

    /// Descend from `node` toward the child whose box grows least by taking `aabb` in, and stop
    /// where pairing with the node itself costs less than going further.
    fn best_sibling(&self, mut node: u32, aabb: &Aabb) -> u32 {
        loop {
            let n = &self.nodes[node as usize];
            if n.is_leaf() {
                return node;
            }
            let combined = cost(&union(&n.aabb, aabb));
            let here = 2.0 * combined;
            let inherited = 2.0 * (combined - cost(&n.aabb));
            let child_cost = |c: u32| {
                let b = &self.nodes[c as usize];
                let grown = cost(&union(&b.aabb, aabb));
                let own = if b.is_leaf() { 0.0 } else { cost(&b.aabb) };
                grown - own + inherited
            };
            let (c0, c1) = (n.children[0], n.children[1]);
            let (k0, k1) = (child_cost(c0), child_cost(c1));
            if here < k0.min(k1) {
                return node;
            }
            node = if k0 <= k1 { c0 } else { c1 };
        }
    }

    /// Recompute the boxes from `node` up to the root.
    fn refit(&mut self, mut node: u32) {
        while node != NONE {
            let [a, b] = self.nodes[node as usize].children;
            let aabb = union(&self.nodes[a as usize].aabb, &self.nodes[b as usize].aabb);
            self.nodes[node as usize].aabb = aabb;
            node = self.nodes[node as usize].parent;
        }
    }

    /// Take a leaf out; its sibling takes its parent's place.
    pub fn remove(&mut self, leaf: u32) {
        let parent = self.nodes[leaf as usize].parent;
        self.free.push(leaf);
        if parent == NONE {
            self.root = None;
            return;
        }
        let p = self.nodes[parent as usize];
        let sibling = p.children[usize::from(p.children[0] == leaf)];
        self.free.push(parent);
        self.nodes[sibling as usize].parent = p.parent;
        if p.parent == NONE {
            self.root = Some(sibling);
        } else {
            let g = &mut self.nodes[p.parent as usize];
            let side = usize::from(g.children[1] == parent);
            g.children[side] = sibling;
            self.refit(p.parent);
        }
    }

    /// Every slot whose box overlaps `aabb`, to `visit`, until it returns false.
    pub fn query(&self, aabb: &Aabb, mut visit: impl FnMut(u32) -> bool) {
        let mut stack = Stack::new(self.root);
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i as usize];
            if !n.aabb.overlaps(aabb) {
                continue;
            }
            if n.is_leaf() {
                if !visit(n.children[1]) {
                    return;
                }
            } else {
                stack.extend(n.children);
            }
        }
    }

    /// Every slot whose box the ray `origin + t d`, t in [0, max], may cross, to `visit`,
    /// which answers the new largest t (smaller to shorten the ray, 0 to stop).
    pub fn ray(
        &self,
        origin: Vec2,
        d: Vec2,
        mut max: Real,
        mut visit: impl FnMut(u32, Real) -> Real,
    ) {
        let mut stack = Stack::new(self.root);
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i as usize];
            if !ray_meets_box(origin, d, max, &n.aabb) {
                continue;
            }
            if n.is_leaf() {
                max = visit(n.children[1], max);
                if max <= 0.0 {
                    return;
                }
            } else {
                stack.extend(n.children);
            }
        }
    }
}

/// The nodes still to visit: 64 inline (a tree as deep as that holds far more bodies than a
/// World can), the rest on the heap, so a query allocates nothing.
struct Stack {
    inline: [u32; 64],
    len: usize,
    spill: Vec<u32>,
}

impl Stack {
    fn new(root: Option<u32>) -> Stack {
        let mut s = Stack {
            inline: [NONE; 64],
            len: 0,
            spill: Vec::new(),
        };
        if let Some(r) = root {
            s.extend([r]);
        }
        s
    }

    fn extend(&mut self, nodes: impl IntoIterator<Item = u32>) {
        for n in nodes {
            if self.len < self.inline.len() {
                self.inline[self.len] = n;
                self.len += 1;
            } else {
                self.spill.push(n);
            }
        }
    }

    fn pop(&mut self) -> Option<u32> {
        if let Some(n) = self.spill.pop() {
            return Some(n);
        }
        self.len = self.len.checked_sub(1)?;
        Some(self.inline[self.len])
    }
}

/// Whether `origin + t d`, t in [0, max], meets the box (the slab test).
fn ray_meets_box(origin: Vec2, d: Vec2, max: Real, b: &Aabb) -> bool {
    let (mut lo, mut hi) = (0.0 as Real, max);
    for axis in 0..2 {
        let (o, v, min, mx) = (origin[axis], d[axis], b.min[axis], b.max[axis]);
        if v == 0.0 {
            if o < min || o > mx {
                return false;
            }
            continue;
        }
        let (t0, t1) = ((min - o) / v, (mx - o) / v);
        lo = lo.max(t0.min(t1));
        hi = hi.min(t0.max(t1));
        if lo > hi {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::vec2;

    fn boxed(x: Real, y: Real) -> Aabb {
        Aabb {
            min: vec2(x, y),
            max: vec2(x + 1.0, y + 1.0),
        }
    }

    /// The slots `tree` reports for box `q`, sorted.
    fn found_in(tree: &Tree, q: &Aabb) -> Vec<u32> {
        let mut found = Vec::new();
        tree.query(q, |s| {
            found.push(s);
            true
        });
        found.sort_unstable();
        found
    }

    /// A tree built top down answers as one built leaf by leaf.
    #[test]
    fn a_tree_built_at_once_finds_every_box() {
        let items: Vec<(u32, Aabb)> = (0..100u32)
            .map(|i| (i, boxed((i % 10) as Real * 2.0, (i / 10) as Real * 2.0)))
            .collect();
        let (tree, leaves) = Tree::build(&items);
        assert!(leaves.iter().all(|&l| l != NONE));
        let q = Aabb {
            min: vec2(4.5, 4.5),
            max: vec2(6.5, 6.5),
        };
        let found = found_in(&tree, &q);
        // Boxes at x, y in {4, 6} (each 1 m square) meet [4.5, 6.5]^2.
        assert_eq!(found, vec![22, 23, 32, 33]);
    }

    /// A tree rebuilt in place over other boxes (after inserts and removals left it a free
    /// list) finds exactly those boxes, as a fresh one does.
    #[test]
    fn a_rebuilt_tree_forgets_its_old_boxes() {
        let old: Vec<(u32, Aabb)> = (0..50u32).map(|i| (i, boxed(i as Real, 0.0))).collect();
        let (mut tree, _) = Tree::build(&old);
        let extra = tree.insert(99, boxed(3.0, 3.0));
        tree.remove(extra);
        let new: Vec<(u32, Aabb)> = (0..20u32)
            .map(|i| (100 + i, boxed(0.0, 2.0 * i as Real)))
            .collect();
        let (mut order, mut leaves) = (Vec::new(), Vec::new());
        tree.rebuild(&new, &mut order, &mut leaves);
        assert_eq!(leaves.len(), 20);
        let q = Aabb {
            min: vec2(-1.0, -1.0),
            max: vec2(60.0, 6.5),
        };
        let found = found_in(&tree, &q);
        // The new boxes at y = 0, 2, 4 and 6 meet y <= 6.5; none of the old ones is left.
        assert_eq!(found, vec![100, 101, 102, 103]);
        tree.rebuild(&[], &mut order, &mut leaves);
        let mut any = false;
        tree.query(&q, |_| {
            any = true;
            true
        });
        assert!(!any, "an empty rebuild leaves no box");
    }

    /// Every slot the tree reports for a box, against a test of every box.
    #[test]
    fn queries_find_what_testing_every_box_finds_through_inserts_and_removals() {
        let mut tree = Tree::default();
        let mut leaves = Vec::new();
        let mut seed = 7u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as Real / (1u32 << 24) as Real * 40.0
        };
        for slot in 0..300 {
            let b = boxed(next(), next());
            leaves.push(Some((tree.insert(slot, b), b)));
        }
        for slot in (0..300).step_by(3) {
            let (leaf, _) = leaves[slot].take().unwrap();
            tree.remove(leaf);
        }
        for _ in 0..50 {
            let q = Aabb {
                min: vec2(next(), next()),
                max: vec2(next(), next()) + vec2(40.0, 40.0),
            };
            let found = found_in(&tree, &q);
            let expected: Vec<u32> = (0..300u32)
                .filter(|&s| leaves[s as usize].is_some_and(|(_, b)| b.overlaps(&q)))
                .collect();
            assert_eq!(found, expected);
        }
        let mut crossed = Vec::new();
        tree.ray(vec2(-1.0, 20.5), vec2(50.0, 0.0), 1.0, |s, max| {
            crossed.push(s);
            max
        });
        crossed.sort_unstable();
        let expected: Vec<u32> = (0..300u32)
            .filter(|&s| {
                leaves[s as usize].is_some_and(|(_, b)| b.min.y <= 20.5 && 20.5 <= b.max.y)
            })
            .collect();
        assert_eq!(crossed, expected);
    }
}
