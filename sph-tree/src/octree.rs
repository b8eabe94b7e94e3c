//! A flat octree built from particles sorted by SFC key.
//!
//! Nodes are stored level by level (breadth first), so the children of a
//! node are contiguous and, like the particles, in key order. Every node
//! knows its particle range in the sorted arrays and its tight bounding box.
//! No pointers: everything is an index into flat vectors, which are reused
//! (not reallocated) when the tree is rebuilt each step.

use crate::sfc::MAX_LEVEL;
use crate::TreeError;
use rayon::prelude::*;
use std::ops::Range;

/// Index of a node; the root is node 0.
pub type NodeId = u32;

/// Deepest pending-node count of a depth-first traversal: 7 siblings wait
/// per level below the current one, plus the node itself.
pub(crate) const STACK_DEPTH: usize = 8 * (MAX_LEVEL as usize + 1);

/// The octree. Build it with [`Octree::build`] (or rebuild an existing one
/// with [`Octree::rebuild`], which keeps its buffers).
#[derive(Debug, Clone, Default)]
pub struct Octree {
    bucket: usize,
    // Per node, in breadth-first order.
    first: Vec<u32>,
    count: Vec<u32>,
    key: Vec<u64>,
    level: Vec<u8>,
    child_start: Vec<u32>,
    n_children: Vec<u8>,
    box_lo: Vec<[f64; 3]>,
    box_hi: Vec<[f64; 3]>,
    // Node index where each level starts (length = levels + 1).
    level_start: Vec<usize>,
    // Leaf node ids in key order.
    leaves: Vec<NodeId>,
    // Scratch: child boundaries per node of the level being split.
    splits: Vec<[u32; 9]>,
}

impl Octree {
    /// Builds the tree over particles whose `keys` are sorted ascending,
    /// with coordinates `x, y, z` in the same order. Leaves hold at most
    /// `bucket` particles (except cells at the finest level holding more
    /// coincident keys, which cannot be split).
    pub fn build(
        keys: &[u64],
        x: &[f64],
        y: &[f64],
        z: &[f64],
        bucket: usize,
    ) -> Result<Self, TreeError> {
        let mut t = Self::default();
        t.rebuild(keys, x, y, z, bucket)?;
        Ok(t)
    }

    /// Rebuilds in place, reusing every buffer.
    pub fn rebuild(
        &mut self,
        keys: &[u64],
        x: &[f64],
        y: &[f64],
        z: &[f64],
        bucket: usize,
    ) -> Result<(), TreeError> {
        crate::check_lengths(x, y, z, Some(("keys", keys.len())))?;
        if bucket == 0 {
            return Err(TreeError::InvalidBucketSize(bucket));
        }
        if keys.len() > u32::MAX as usize {
            return Err(TreeError::TooManyParticles(keys.len()));
        }
        debug_assert!(keys.windows(2).all(|w| w[0] <= w[1]), "keys not sorted");
        self.bucket = bucket;
        for v in [&mut self.first, &mut self.count, &mut self.child_start] {
            v.clear();
        }
        self.key.clear();
        self.level.clear();
        self.n_children.clear();
        self.level_start.clear();
        self.leaves.clear();

        self.push_node(0, keys.len() as u32, 0, 0);
        self.level_start.push(0);
        self.level_start.push(1);
        for lvl in 0..MAX_LEVEL as usize {
            let range = self.level_start[lvl]..self.level_start[lvl + 1];
            if range.is_empty() {
                break;
            }
            self.split_level(range, lvl as u32, keys);
            let end = self.first.len();
            self.level_start.push(end);
        }
        // The loop may stop at MAX_LEVEL with a non-empty last level, or
        // push one empty level: drop trailing empty levels.
        while self.level_start.len() > 2
            && self.level_start[self.level_start.len() - 1]
                == self.level_start[self.level_start.len() - 2]
        {
            self.level_start.pop();
        }
        self.compute_boxes(x, y, z);
        self.collect_leaves();
        Ok(())
    }

    /// Recomputes every node's tight box from moved positions `x, y, z`
    /// (in the tree's particle order), keeping the topology: the particle
    /// order, each node's particle range, children, levels and keys stay
    /// those of the last build. O(N), parallel within each level, no
    /// allocation once the tree is built.
    ///
    /// Searches over a refitted tree are exact: they find every pair within
    /// the search radius of the current positions, since each node's box is
    /// again the tight box of its particles (on periodic axes too: a
    /// particle wrapped to the other side of the box only makes its nodes'
    /// boxes larger). What no longer holds is the space-filling-curve
    /// order: [`key`](Self::key) is the cell of the build, no longer the
    /// cell of the particles' new positions, and the boxes grow and overlap
    /// as particles drift apart, so searches slow down until the next
    /// rebuild. The boxes equal those of a fresh [`build`](Self::build) with
    /// the old keys and the new positions.
    ///
    /// ```
    /// use sph_tree::Octree;
    /// let keys: Vec<u64> = (0..100u64).map(|i| i << 40).collect();
    /// let mut x: Vec<f64> = (0..100).map(|i| i as f64).collect();
    /// let mut t = Octree::build(&keys, &x, &x, &x, 8).unwrap();
    /// assert_eq!(t.node_box(0), ([0.0; 3], [99.0; 3]));
    /// let leaves = t.leaves().to_vec();
    /// x[99] = 150.0; // particle 99 drifts away
    /// t.refit(&x, &x, &x).unwrap();
    /// assert_eq!(t.node_box(0), ([0.0; 3], [150.0; 3]));
    /// assert_eq!(t.leaves(), &leaves[..]); // same topology
    /// let last = *leaves.last().unwrap();
    /// assert_eq!(t.node_box(last).1, [150.0; 3]);
    /// ```
    pub fn refit(&mut self, x: &[f64], y: &[f64], z: &[f64]) -> Result<(), TreeError> {
        crate::check_lengths(x, y, z, Some(("the tree", self.num_particles())))?;
        if !self.first.is_empty() {
            self.compute_boxes(x, y, z);
        }
        Ok(())
    }

    fn push_node(&mut self, first: u32, count: u32, key: u64, level: u8) {
        self.first.push(first);
        self.count.push(count);
        self.key.push(key);
        self.level.push(level);
        self.child_start.push(0);
        self.n_children.push(0);
    }

    /// Splits every over-full node of one level into its non-empty octants.
    fn split_level(&mut self, range: Range<usize>, lvl: u32, keys: &[u64]) {
        let bucket = self.bucket;
        let shift = 3 * (MAX_LEVEL - lvl - 1);
        self.splits.clear();
        self.splits.resize(range.len(), [0; 9]);
        let first = &self.first[range.clone()];
        let count = &self.count[range.clone()];
        let nkey = &self.key[range.clone()];
        self.splits.par_iter_mut().enumerate().for_each(|(k, s)| {
            let (a, n) = (first[k] as usize, count[k] as usize);
            if n <= bucket || lvl >= MAX_LEVEL {
                s[0] = u32::MAX; // leaf marker
                return;
            }
            let slice = &keys[a..a + n];
            s[0] = a as u32;
            for d in 1..8u64 {
                let bound = nkey[k] | (d << shift);
                s[d as usize] = (a + slice.partition_point(|&kk| kk < bound)) as u32;
            }
            s[8] = (a + n) as u32;
        });
        for k in 0..range.len() {
            let s = self.splits[k];
            if s[0] == u32::MAX {
                continue;
            }
            let node = range.start + k;
            let start = self.first.len() as u32;
            let mut nc = 0u8;
            for d in 0..8 {
                let c = s[d + 1] - s[d];
                if c > 0 {
                    let key = self.key[node] | ((d as u64) << shift);
                    self.push_node(s[d], c, key, (lvl + 1) as u8);
                    nc += 1;
                }
            }
            self.child_start[node] = start;
            self.n_children[node] = nc;
        }
    }

    /// Tight boxes, bottom-up one level at a time (parallel within a level).
    fn compute_boxes(&mut self, x: &[f64], y: &[f64], z: &[f64]) {
        let n = self.first.len();
        self.box_lo.clear();
        self.box_hi.clear();
        self.box_lo.resize(n, [f64::INFINITY; 3]);
        self.box_hi.resize(n, [f64::NEG_INFINITY; 3]);
        for lvl in (0..self.level_start.len() - 1).rev() {
            let (a, b) = (self.level_start[lvl], self.level_start[lvl + 1]);
            let (lo_head, lo_tail) = self.box_lo.split_at_mut(b);
            let (hi_head, hi_tail) = self.box_hi.split_at_mut(b);
            let (first, count) = (&self.first, &self.count);
            let (cs, nc) = (&self.child_start, &self.n_children);
            lo_head[a..b]
                .par_iter_mut()
                .zip(hi_head[a..b].par_iter_mut())
                .enumerate()
                .for_each(|(k, (lo, hi))| {
                    let node = a + k;
                    if nc[node] == 0 {
                        let r = first[node] as usize..(first[node] + count[node]) as usize;
                        for i in r {
                            let p = [x[i], y[i], z[i]];
                            for d in 0..3 {
                                lo[d] = lo[d].min(p[d]);
                                hi[d] = hi[d].max(p[d]);
                            }
                        }
                    } else {
                        let c0 = cs[node] as usize - b;
                        for c in c0..c0 + nc[node] as usize {
                            for d in 0..3 {
                                lo[d] = lo[d].min(lo_tail[c][d]);
                                hi[d] = hi[d].max(hi_tail[c][d]);
                            }
                        }
                    }
                });
        }
    }

    fn collect_leaves(&mut self) {
        let mut leaves = std::mem::take(&mut self.leaves);
        self.traverse(|_| true, |leaf| leaves.push(leaf));
        self.leaves = leaves;
    }

    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.first.len()
    }

    /// Number of particles the tree was built over.
    pub fn num_particles(&self) -> usize {
        self.count.first().map_or(0, |&c| c as usize)
    }

    /// Maximum particles per leaf the tree was built with.
    pub fn bucket(&self) -> usize {
        self.bucket
    }

    /// Number of levels below the root that hold nodes, plus one.
    pub fn num_levels(&self) -> usize {
        self.level_start.len() - 1
    }

    /// Node ids of level `l` (0 = root).
    pub fn level_nodes(&self, l: usize) -> Range<NodeId> {
        self.level_start[l] as NodeId..self.level_start[l + 1] as NodeId
    }

    /// Leaves in key order: their particle ranges tile `0..num_particles()`.
    pub fn leaves(&self) -> &[NodeId] {
        &self.leaves
    }

    /// Whether a node has no children.
    #[inline]
    pub fn is_leaf(&self, node: NodeId) -> bool {
        self.n_children[node as usize] == 0
    }

    /// Children of a node, in key order (empty for a leaf).
    #[inline]
    pub fn children(&self, node: NodeId) -> Range<NodeId> {
        let s = self.child_start[node as usize];
        s..s + u32::from(self.n_children[node as usize])
    }

    /// Range of the node's particles in the sorted arrays.
    #[inline]
    pub fn particles(&self, node: NodeId) -> Range<usize> {
        let f = self.first[node as usize] as usize;
        f..f + self.count[node as usize] as usize
    }

    /// Level of a node (root = 0).
    #[inline]
    pub fn level(&self, node: NodeId) -> u32 {
        u32::from(self.level[node as usize])
    }

    /// Smallest key of the node's cell; the cell spans
    /// `key .. key + 8^(21 - level)`.
    #[inline]
    pub fn key(&self, node: NodeId) -> u64 {
        self.key[node as usize]
    }

    /// Tight bounding box `(lo, hi)` of the node's particles.
    #[inline]
    pub fn node_box(&self, node: NodeId) -> ([f64; 3], [f64; 3]) {
        (self.box_lo[node as usize], self.box_hi[node as usize])
    }

    /// Depth-first traversal in key order. `open(node)` decides whether to
    /// look inside a node (return `false` to skip it and its subtree, for
    /// example because it is far away or was accepted as a whole); an opened
    /// leaf is handed to `on_leaf`. Leaves arrive in ascending key order, so
    /// the particles they hold arrive in ascending index order.
    ///
    /// ```
    /// use sph_tree::Octree;
    /// let keys: Vec<u64> = (0..100u64).map(|i| i << 40).collect();
    /// let x: Vec<f64> = (0..100).map(|i| i as f64).collect();
    /// let t = Octree::build(&keys, &x, &x, &x, 8).unwrap();
    /// let mut n = 0;
    /// t.traverse(|_| true, |leaf| n += t.particles(leaf).len());
    /// assert_eq!(n, 100);
    /// ```
    #[inline]
    pub fn traverse(&self, mut open: impl FnMut(NodeId) -> bool, mut on_leaf: impl FnMut(NodeId)) {
        if self.first.is_empty() || self.count[0] == 0 {
            return;
        }
        let mut stack = [0 as NodeId; STACK_DEPTH];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = stack[top];
            if !open(node) {
                continue;
            }
            let nc = self.n_children[node as usize] as u32;
            if nc == 0 {
                on_leaf(node);
            } else {
                let s = self.child_start[node as usize];
                // Push in reverse so the first child pops first.
                for c in (s..s + nc).rev() {
                    stack[top] = c;
                    top += 1;
                }
            }
        }
    }
}
