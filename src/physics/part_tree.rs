//! A bounding-volume tree over the shapes of a body of many (a ground of hundreds of boxes), in
//! the body's own frame: a pair's touching shapes are found by querying it with the other
//! shape's box, in time that grows with the shapes found rather than with all of them.
//!
//! Built once, top down, when the body is made (its shapes never move within it): each node
//! splits its shapes at the median of their centres along its box's longer side.

use super::math::{Transform, Vec2};
use super::shape::Aabb;

/// Bodies with more shapes than this get a tree; fewer are tested one by one.
pub(crate) const TREE_FROM: usize = 8;

/// One node: a leaf holds a shape index, an inner node its two children.
#[derive(Clone, Copy, Debug)]
struct Node {
    aabb: Aabb,
    /// Leaf: the shape's index; inner: the first child (the second follows its subtree).
    index: u32,
    /// Inner: the second child's node index; leaf: [`LEAF`].
    second: u32,
}

const LEAF: u32 = u32::MAX;

/// The tree, its nodes in depth-first order.
#[derive(Clone, Debug, Default)]
pub(crate) struct PartTree {
    nodes: Vec<Node>,
}

impl PartTree {
    /// The tree over `boxes` (each shape's box in the body's frame, by shape index).
    pub fn new(boxes: &[Aabb]) -> PartTree {
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut tree = PartTree {
            nodes: Vec::with_capacity(2 * boxes.len()),
        };
        tree.build(boxes, &mut order);
        tree
    }

    /// Add the subtree over the shapes `order`, returning its root's index.
    fn build(&mut self, boxes: &[Aabb], order: &mut [u32]) -> u32 {
        let at = self.nodes.len() as u32;
        let aabb = union(order.iter().map(|&i| boxes[i as usize]));
        if let [only] = order {
            self.nodes.push(Node {
                aabb,
                index: *only,
                second: LEAF,
            });
            return at;
        }
        let size = aabb.max - aabb.min;
        let centre = |i: &u32| {
            let b = boxes[*i as usize];
            let c = b.min + b.max;
            if size.x >= size.y {
                c.x
            } else {
                c.y
            }
        };
        let half = order.len() / 2;
        order.select_nth_unstable_by(half, |a, b| centre(a).total_cmp(&centre(b)));
        self.nodes.push(Node {
            aabb,
            index: at + 1,
            second: 0,
        });
        let (low, high) = order.split_at_mut(half);
        self.build(boxes, low);
        let second = self.build(boxes, high);
        self.nodes[at as usize].second = second;
        at
    }

    /// Every shape whose box overlaps `query` (a box in the world) with the body at `body`,
    /// pushed onto `out` (in no particular order).
    pub fn query(&self, body: Transform, query: &Aabb, out: &mut Vec<u32>) {
        let local = into_frame(body, query);
        let mut stack = [0u32; 64];
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let node = self.nodes[stack[depth] as usize];
            if !node.aabb.overlaps(&local) {
                continue;
            }
            if node.second == LEAF {
                out.push(node.index);
            } else {
                stack[depth] = node.index;
                stack[depth + 1] = node.second;
                depth += 2;
            }
        }
    }
}

/// The box around `boxes`.
fn union(mut boxes: impl Iterator<Item = Aabb>) -> Aabb {
    let first = boxes.next().expect("at least one box");
    boxes.fold(first, |a, b| Aabb {
        min: a.min.min(b.min),
        max: a.max.max(b.max),
    })
}

/// A world box seen from the frame `xf`: the box around it turned into that frame
/// (its centre moved in, its half extents by |R^T|).
fn into_frame(xf: Transform, world: &Aabb) -> Aabb {
    let centre = xf.apply_inv(0.5 * (world.min + world.max));
    let h = 0.5 * (world.max - world.min);
    let (c, s) = (xf.q.c.abs(), xf.q.s.abs());
    let half = Vec2::new(c * h.x + s * h.y, s * h.x + c * h.y);
    Aabb {
        min: centre - half,
        max: centre + half,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::{vec2, Real, Rot};

    #[test]
    fn a_query_finds_exactly_the_overlapping_boxes_of_a_turned_body() {
        // 300 boxes scattered by a fixed sequence, a body turned 0.7 rad and moved, 200
        // queries: the tree's answer is the brute force's.
        let mut seed = 12345u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            (seed % 10_000) as Real / 10_000.0
        };
        let boxes: Vec<Aabb> = (0..300)
            .map(|_| {
                let c = vec2(40.0 * next() - 20.0, 40.0 * next() - 20.0);
                let h = vec2(0.1 + next(), 0.1 + next());
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect();
        let tree = PartTree::new(&boxes);
        let body = Transform {
            p: vec2(3.0, -2.0),
            q: Rot::from_angle(0.7),
        };
        let mut found = Vec::new();
        for _ in 0..200 {
            let c = vec2(50.0 * next() - 25.0, 50.0 * next() - 25.0);
            let q = Aabb {
                min: c,
                max: c + vec2(3.0 * next(), 3.0 * next()),
            };
            found.clear();
            tree.query(body, &q, &mut found);
            found.sort_unstable();
            let local = into_frame(body, &q);
            let brute: Vec<u32> = (0..boxes.len() as u32)
                .filter(|&i| boxes[i as usize].overlaps(&local))
                .collect();
            assert_eq!(found, brute);
        }
    }
}
