//! The replicated global octree: leaves as contiguous SFC key ranges with
//! their global particle counts, refined and coarsened towards a bucket size
//! (cornerstone style: the tree is a sorted array of leaf start keys).

use sph_tree::{BoundingBox, Curve, CELLS_PER_AXIS, MAX_LEVEL};

/// One past the largest key (keys hold 3 x 21 = 63 bits).
pub const KEY_END: u64 = 1 << (3 * MAX_LEVEL);

/// Leaves of an octree over the whole key space, each an aligned key range
/// `[starts[i], starts[i + 1])` of `8^(21 - level)` keys.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GlobalTree {
    starts: Vec<u64>,
}

impl GlobalTree {
    /// The uniform tree of all `8^level` cells of one level.
    pub fn uniform(level: u32) -> Self {
        let level = level.min(MAX_LEVEL);
        let size = 1u64 << (3 * (MAX_LEVEL - level));
        let mut starts: Vec<u64> = (0..(1u64 << (3 * level))).map(|i| i * size).collect();
        starts.push(KEY_END);
        Self { starts }
    }

    /// Number of leaves.
    pub fn num_leaves(&self) -> usize {
        self.starts.len() - 1
    }

    /// Leaf start keys followed by [`KEY_END`].
    pub fn starts(&self) -> &[u64] {
        &self.starts
    }

    /// Level of leaf `i` (0 = the whole box).
    pub fn level(&self, i: usize) -> u32 {
        let size = self.starts[i + 1] - self.starts[i];
        MAX_LEVEL - size.trailing_zeros() / 3
    }

    /// Particles per leaf of a key-sorted array.
    pub fn count(&self, sorted_keys: &[u64], counts: &mut Vec<u64>) {
        counts.clear();
        let mut lo = 0;
        for i in 0..self.num_leaves() {
            let end = self.starts[i + 1];
            let hi = lo + sorted_keys[lo..].partition_point(|&k| k < end);
            counts.push((hi - lo) as u64);
            lo = hi;
        }
    }

    /// Splits leaves holding more than `bucket` particles into their eight
    /// children and merges complete sibling groups holding at most `bucket`
    /// together. One level per call, as cornerstone does each step: the tree
    /// follows the particles over a few steps.
    pub fn rebalance(&mut self, counts: &[u64], bucket: u64) {
        assert_eq!(counts.len(), self.num_leaves(), "one count per leaf");
        let n = self.num_leaves();
        let mut out = Vec::with_capacity(self.starts.len());
        let mut i = 0;
        while i < n {
            let start = self.starts[i];
            let size = self.starts[i + 1] - start;
            let level = self.level(i);
            let parent_size = size << 3;
            let first_child = level > 0 && start.is_multiple_of(parent_size);
            if first_child
                && i + 8 <= n
                && self.starts[i + 8] == start + parent_size
                && counts[i..i + 8].iter().sum::<u64>() <= bucket
            {
                // Eight leaves spanning exactly the parent are its children.
                out.push(start);
                i += 8;
                continue;
            }
            if counts[i] > bucket && level < MAX_LEVEL {
                let child = size >> 3;
                out.extend((0..8).map(|c| start + c * child));
            } else {
                out.push(start);
            }
            i += 1;
        }
        out.push(KEY_END);
        self.starts = out;
    }

    /// Geometric box of leaf `i` in `bbox` for `curve` keys.
    pub fn cell_box(&self, i: usize, bbox: &BoundingBox, curve: Curve) -> ([f64; 3], [f64; 3]) {
        let side = 1u32 << (MAX_LEVEL - self.level(i));
        let (a, b, c) = curve.decode(self.starts[i]);
        let corner = [a & !(side - 1), b & !(side - 1), c & !(side - 1)];
        let (lo, len) = (bbox.lo(), bbox.lengths());
        let scale = f64::from(CELLS_PER_AXIS);
        let mut blo = [0.0; 3];
        let mut bhi = [0.0; 3];
        for k in 0..3 {
            blo[k] = lo[k] + f64::from(corner[k]) / scale * len[k];
            bhi[k] = lo[k] + f64::from(corner[k] + side) / scale * len[k];
        }
        (blo, bhi)
    }
}

/// Contiguous leaf ranges per rank, balanced by particle count.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Assignment {
    /// First leaf of each rank, then the number of leaves.
    pub leaf_start: Vec<usize>,
    /// First key of each rank, then [`KEY_END`].
    pub key_start: Vec<u64>,
}

impl Assignment {
    /// Splits the leaves among `ranks` so that each rank's count is as close
    /// as possible to `total / ranks` (the cut falls at the leaf boundary
    /// nearest the ideal prefix count).
    pub fn balanced(tree: &GlobalTree, counts: &[u64], ranks: usize) -> Self {
        assert!(ranks > 0, "at least one rank");
        let n = tree.num_leaves();
        let total: u64 = counts.iter().sum();
        let mut prefix = Vec::with_capacity(n + 1);
        prefix.push(0u64);
        for &c in counts {
            prefix.push(prefix.last().unwrap() + c);
        }
        let mut leaf_start = vec![0usize; ranks + 1];
        leaf_start[ranks] = n;
        for r in 1..ranks {
            let ideal = (u128::from(total) * r as u128 / ranks as u128) as u64;
            // First boundary with prefix >= ideal, or the one before if nearer.
            let mut b = prefix.partition_point(|&p| p < ideal);
            if b > 0 && ideal - prefix[b - 1] < prefix.get(b).map_or(u64::MAX, |&p| p - ideal) {
                b -= 1;
            }
            leaf_start[r] = b.clamp(leaf_start[r - 1], n);
        }
        let key_start = leaf_start.iter().map(|&l| tree.starts()[l]).collect();
        Self {
            leaf_start,
            key_start,
        }
    }

    /// Number of ranks.
    pub fn ranks(&self) -> usize {
        self.leaf_start.len() - 1
    }

    /// The rank owning `key`.
    pub fn owner(&self, key: u64) -> usize {
        self.key_start.partition_point(|&k| k <= key) - 1
    }

    /// The rank owning leaf `leaf`.
    pub fn leaf_owner(&self, leaf: usize) -> usize {
        self.leaf_start.partition_point(|&l| l <= leaf) - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_levels_and_counts() {
        let t = GlobalTree::uniform(2);
        assert_eq!(t.num_leaves(), 64);
        assert!((0..64).all(|i| t.level(i) == 2));
        let keys: Vec<u64> = (0..1000u64).map(|i| i * (KEY_END / 1000)).collect();
        let mut counts = Vec::new();
        t.count(&keys, &mut counts);
        assert_eq!(counts.iter().sum::<u64>(), 1000);
    }

    #[test]
    fn rebalance_splits_and_merges() {
        let mut t = GlobalTree::uniform(1);
        let mut counts = vec![0; 8];
        counts[3] = 100;
        t.rebalance(&counts, 10);
        // Leaf 3 split into 8; the others cannot merge (only 7 left of 8).
        assert_eq!(t.num_leaves(), 15);
        let zero = vec![0; 15];
        t.rebalance(&zero, 10);
        // The 8 children of old leaf 3 merge back; the root cannot form
        // because they were not all leaves of the same level before.
        assert_eq!(t.num_leaves(), 8);
        t.rebalance(&[0; 8], 10);
        assert_eq!(t.num_leaves(), 1);
        assert_eq!(t.level(0), 0);
    }

    #[test]
    fn assignment_balances() {
        let t = GlobalTree::uniform(2);
        let counts = vec![10u64; 64];
        let a = Assignment::balanced(&t, &counts, 4);
        assert_eq!(a.leaf_start, vec![0, 16, 32, 48, 64]);
        assert_eq!(a.owner(0), 0);
        assert_eq!(a.owner(KEY_END - 1), 3);
        assert_eq!(a.leaf_owner(47), 2);
    }
}
