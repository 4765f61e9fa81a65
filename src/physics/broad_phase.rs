//! Broad phase: which pairs of bodies might touch this step.
//!
//! Sort and sweep along x: bodies are kept in an order sorted by the left edge of their
//! bounding box. The order barely changes between steps, so insertion sort restores it in
//! close to linear time; the sweep then only tests boxes whose x intervals overlap.
//! Static-static pairs are never examined.

use super::shape::Aabb;

/// What the broad phase needs to know about one body slot.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Proxy {
    /// Bounding box, already grown by the body's contact margin (m).
    pub aabb: Aabb,
    /// Immovable bodies never pair with each other.
    pub is_static: bool,
}

/// A candidate pair as a sortable key: lower slot index in the high 32 bits.
#[inline]
pub(crate) fn pair_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (lo as u64) << 32 | hi as u64
}

/// The two slot indices of a pair key, lower first.
#[inline]
pub(crate) fn pair_of(key: u64) -> (u32, u32) {
    ((key >> 32) as u32, key as u32)
}

/// Sort-and-sweep broad phase with a persistent order.
#[derive(Debug, Default, Clone)]
pub(crate) struct SweepAndPrune {
    /// Slot indices of live bodies, sorted by `aabb.min.x` as of the last query.
    order: Vec<u32>,
}

impl SweepAndPrune {
    /// A body slot came alive.
    pub fn insert(&mut self, index: u32) {
        self.order.push(index);
    }

    /// A body slot was freed.
    pub fn remove(&mut self, index: u32) {
        self.order.retain(|&i| i != index);
    }

    /// Forget every body.
    pub fn clear(&mut self) {
        self.order.clear();
    }

    /// Fill `out` with the keys of all pairs whose boxes overlap, sorted ascending.
    /// `proxies` is indexed by slot; only slots in the order are read.
    pub fn find_pairs(&mut self, proxies: &[Proxy], out: &mut Vec<u64>) {
        out.clear();
        // Insertion sort: nearly sorted input from last step makes this close to O(n).
        let order = &mut self.order;
        for i in 1..order.len() {
            let item = order[i];
            let x = proxies[item as usize].aabb.min.x;
            let mut j = i;
            while j > 0 && proxies[order[j - 1] as usize].aabb.min.x > x {
                order[j] = order[j - 1];
                j -= 1;
            }
            order[j] = item;
        }
        for (i, &a) in order.iter().enumerate() {
            let pa = &proxies[a as usize];
            for &b in &order[i + 1..] {
                let pb = &proxies[b as usize];
                if pb.aabb.min.x > pa.aabb.max.x {
                    break;
                }
                if pa.is_static && pb.is_static {
                    continue;
                }
                if pa.aabb.min.y <= pb.aabb.max.y && pb.aabb.min.y <= pa.aabb.max.y {
                    out.push(pair_key(a, b));
                }
            }
        }
        out.sort_unstable();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::vec2;

    fn proxy(x0: f32, y0: f32, x1: f32, y1: f32, is_static: bool) -> Proxy {
        Proxy {
            aabb: Aabb {
                min: vec2(x0 as _, y0 as _),
                max: vec2(x1 as _, y1 as _),
            },
            is_static,
        }
    }

    #[test]
    fn finds_exactly_the_overlapping_non_static_pairs() {
        let proxies = [
            proxy(0.0, 0.0, 1.0, 1.0, false),    // 0 overlaps 1
            proxy(0.5, 0.5, 1.5, 1.5, false),    // 1
            proxy(0.2, 5.0, 0.8, 6.0, false),    // 2: same x range as 0, far in y
            proxy(-10.0, -1.0, 10.0, 0.1, true), // 3: ground under 0 and 1
            proxy(-10.0, -1.0, 10.0, 0.1, true), // 4: static on static: never a pair
        ];
        let mut sap = SweepAndPrune::default();
        for i in 0..5 {
            sap.insert(i);
        }
        let mut out = Vec::new();
        sap.find_pairs(&proxies, &mut out);
        let pairs: Vec<_> = out.iter().map(|&k| pair_of(k)).collect();
        assert_eq!(pairs, vec![(0, 1), (0, 3), (0, 4), (1, 3), (1, 4)]);
    }
}
