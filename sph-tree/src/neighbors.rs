//! Fixed-radius neighbour search: for every target particle `i`, all `j`
//! with `|x_i - x_j| < support * h_i` (minimum image on periodic axes),
//! self included, in ascending index order, stored as CSR.

use crate::octree::Octree;
use crate::{BoundingBox, TreeError};
use rayon::prelude::*;
use std::ops::Range;

/// Particles per parallel work item: big enough to amortise scheduling,
/// small enough to balance clustered sets over threads.
const PARTICLES_PER_CHUNK: usize = 2048;

/// Search settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeighborSearch {
    /// Search radius in units of `h` (2 for every built-in SPH kernel).
    pub support: f64,
    /// Most neighbours stored per particle; beyond it a list is cut and the
    /// particle is reported in [`NeighborStats`] (never silently).
    pub cap: usize,
}

impl Default for NeighborSearch {
    fn default() -> Self {
        Self {
            support: 2.0,
            cap: u32::MAX as usize,
        }
    }
}

/// What a search found, for checking and for the smoothing-length iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NeighborStats {
    /// Smallest neighbour count (self included) over the targets.
    pub min_count: usize,
    /// Largest neighbour count over the targets (before any cut).
    pub max_count: usize,
    /// Sum of the counts.
    pub total: usize,
    /// Number of targets whose list was cut at the cap.
    pub over_cap: usize,
    /// The first target (lowest index) whose list was cut, if any.
    pub first_over_cap: Option<usize>,
}

/// Neighbour lists in compressed-sparse-row form for a contiguous range of
/// target particles: the neighbours of target `i` are
/// `indices[offsets[k]..offsets[k + 1]]` with `k = i - targets.start`.
#[derive(Debug, Clone, Default)]
pub struct NeighborList {
    targets: Range<usize>,
    offsets: Vec<usize>,
    indices: Vec<u32>,
    counts: Vec<u32>,
    // Per-chunk buffers, kept between searches so rebuilding allocates nothing.
    chunk_indices: Vec<Vec<u32>>,
}

impl NeighborList {
    /// An empty list.
    pub fn new() -> Self {
        Self::default()
    }

    /// The target particles the lists belong to.
    pub fn targets(&self) -> Range<usize> {
        self.targets.clone()
    }

    /// Neighbours of target particle `i` (a global index in `targets()`),
    /// ascending.
    #[inline]
    pub fn neighbors(&self, i: usize) -> &[u32] {
        let k = i - self.targets.start;
        &self.indices[self.offsets[k]..self.offsets[k + 1]]
    }

    /// True neighbour count of target `i`, even if its list was cut.
    #[inline]
    pub fn count(&self, i: usize) -> usize {
        self.counts[i - self.targets.start] as usize
    }

    /// CSR offsets (length = targets + 1).
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// CSR neighbour indices.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// Bytes held by the lists (offsets, indices, counts).
    pub fn bytes(&self) -> usize {
        self.offsets.len() * std::mem::size_of::<usize>()
            + self.indices.len() * 4
            + self.counts.len() * 4
    }
}

impl NeighborSearch {
    /// Builds the neighbour lists of the particles in `targets` against all
    /// particles of the tree. `x, y, z, h` are in tree (sorted) order.
    pub fn find(
        &self,
        tree: &Octree,
        bbox: &BoundingBox,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        h: &[f64],
        targets: Range<usize>,
        list: &mut NeighborList,
    ) -> Result<NeighborStats, TreeError> {
        self.validate(tree, bbox, x, y, z, h, &targets)?;
        let chunks = target_chunks(tree, &targets);
        let nt = targets.len();
        list.targets = targets.clone();
        list.counts.clear();
        list.counts.resize(nt, 0);
        list.offsets.clear();
        list.offsets.resize(nt + 1, 0);
        if list.chunk_indices.len() < chunks.len() {
            list.chunk_indices.resize_with(chunks.len(), Vec::new);
        }
        let cap = self.cap;
        // Pass 1, parallel over chunks: each chunk writes its own buffer and
        // its slice of the counts/offsets.
        {
            let mut counts_rest: &mut [u32] = &mut list.counts;
            let mut sizes_rest: &mut [usize] = &mut list.offsets[1..];
            let mut work = Vec::with_capacity(chunks.len());
            let bufs = list.chunk_indices.iter_mut();
            for (range, buf) in chunks.iter().zip(bufs) {
                let (c, cr) = std::mem::take(&mut counts_rest).split_at_mut(range.len());
                let (s, sr) = std::mem::take(&mut sizes_rest).split_at_mut(range.len());
                counts_rest = cr;
                sizes_rest = sr;
                work.push((range.clone(), buf, c, s));
            }
            work.into_par_iter().for_each(|(range, buf, counts, sizes)| {
                buf.clear();
                for (k, i) in range.enumerate() {
                    let before = buf.len();
                    let r = self.support * h[i];
                    let mut n = 0usize;
                    for_each_neighbor(tree, bbox, x, y, z, i, r, |j| {
                        if n < cap {
                            buf.push(j as u32);
                        }
                        n += 1;
                    });
                    counts[k] = n.min(u32::MAX as usize) as u32;
                    sizes[k] = buf.len() - before;
                }
            });
        }
        // Prefix sum of the list sizes, then one parallel copy per chunk.
        for k in 0..nt {
            list.offsets[k + 1] += list.offsets[k];
        }
        let total = list.offsets[nt];
        list.indices.clear();
        list.indices.resize(total, 0);
        {
            let mut rest: &mut [u32] = &mut list.indices;
            let mut work = Vec::with_capacity(chunks.len());
            for buf in list.chunk_indices.iter().take(chunks.len()) {
                let (d, r) = std::mem::take(&mut rest).split_at_mut(buf.len());
                rest = r;
                work.push((d, buf));
            }
            work.into_par_iter().for_each(|(d, b)| d.copy_from_slice(b));
        }
        Ok(stats(&list.counts, cap, targets.start))
    }

    /// Counts neighbours without storing them (for the smoothing-length
    /// iteration): `counts[k]` for target `targets.start + k`.
    pub fn count(
        &self,
        tree: &Octree,
        bbox: &BoundingBox,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        h: &[f64],
        targets: Range<usize>,
        counts: &mut Vec<u32>,
    ) -> Result<NeighborStats, TreeError> {
        self.validate(tree, bbox, x, y, z, h, &targets)?;
        counts.clear();
        counts.resize(targets.len(), 0);
        let start = targets.start;
        counts
            .par_chunks_mut(PARTICLES_PER_CHUNK)
            .enumerate()
            .for_each(|(c, out)| {
                for (k, o) in out.iter_mut().enumerate() {
                    let i = start + c * PARTICLES_PER_CHUNK + k;
                    let mut n = 0u32;
                    for_each_neighbor(tree, bbox, x, y, z, i, self.support * h[i], |_| n += 1);
                    *o = n;
                }
            });
        Ok(stats(counts, self.cap, start))
    }

    fn validate(
        &self,
        tree: &Octree,
        bbox: &BoundingBox,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        h: &[f64],
        targets: &Range<usize>,
    ) -> Result<(), TreeError> {
        crate::check_lengths(x, y, z, Some(("h", h.len())))?;
        assert_eq!(
            tree.num_particles(),
            x.len(),
            "tree was built over a different particle set"
        );
        assert!(targets.end <= x.len(), "target range beyond the particles");
        let lengths = bbox.lengths();
        for i in targets.clone() {
            let r = self.support * h[i];
            if !r.is_finite() || r < 0.0 {
                return Err(TreeError::NonFinite {
                    index: i,
                    what: "h",
                    value: h[i],
                });
            }
            for axis in 0..3 {
                if bbox.is_periodic(axis) && r > 0.5 * lengths[axis] {
                    return Err(TreeError::RadiusTooLarge {
                        index: i,
                        radius: r,
                        axis,
                        half_length: 0.5 * lengths[axis],
                    });
                }
            }
        }
        Ok(())
    }
}

/// Calls `f(j)` for every particle `j` with `|x_i - x_j| < r`, in ascending
/// `j` (self included when `r > 0`).
#[inline]
pub fn for_each_neighbor(
    tree: &Octree,
    bbox: &BoundingBox,
    x: &[f64],
    y: &[f64],
    z: &[f64],
    i: usize,
    r: f64,
    mut f: impl FnMut(usize),
) {
    let p = [x[i], y[i], z[i]];
    let r2 = r * r;
    let periodic = (0..3).any(|a| bbox.is_periodic(a));
    tree.traverse(
        |node| {
            let (lo, hi) = tree.node_box(node);
            bbox.distance2_to_box(p, lo, hi) < r2
        },
        |leaf| {
            let range = tree.particles(leaf);
            if periodic {
                for j in range {
                    if bbox.distance2(p, [x[j], y[j], z[j]]) < r2 {
                        f(j);
                    }
                }
            } else {
                for j in range {
                    let (dx, dy, dz) = (p[0] - x[j], p[1] - y[j], p[2] - z[j]);
                    if dx * dx + dy * dy + dz * dz < r2 {
                        f(j);
                    }
                }
            }
        },
    );
}

/// Splits the targets into contiguous chunks for the parallel loop.
fn target_chunks(_tree: &Octree, targets: &Range<usize>) -> Vec<Range<usize>> {
    let mut out = Vec::with_capacity(targets.len() / PARTICLES_PER_CHUNK + 1);
    let mut a = targets.start;
    while a < targets.end {
        let b = (a + PARTICLES_PER_CHUNK).min(targets.end);
        out.push(a..b);
        a = b;
    }
    out
}

fn stats(counts: &[u32], cap: usize, start: usize) -> NeighborStats {
    let mut s = NeighborStats {
        min_count: usize::MAX,
        ..Default::default()
    };
    for (k, &c) in counts.iter().enumerate() {
        let c = c as usize;
        s.min_count = s.min_count.min(c);
        s.max_count = s.max_count.max(c);
        s.total += c;
        if c > cap {
            s.over_cap += 1;
            if s.first_over_cap.is_none() {
                s.first_over_cap = Some(start + k);
            }
        }
    }
    if counts.is_empty() {
        s.min_count = 0;
    }
    s
}
