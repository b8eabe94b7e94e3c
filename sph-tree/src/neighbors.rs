//! Fixed-radius neighbour search: for every target particle `i`, all `j`
//! with `|x_i - x_j| < support * h_i` (minimum image on periodic axes),
//! self included, in ascending index order, stored as CSR.

use crate::compact::CompactNeighborList;
use crate::octree::{NodeId, Octree};
use crate::{BoundingBox, TreeError};
use rayon::prelude::*;
use std::ops::Range;
use wide::f64x8;

/// Particles per parallel work item: big enough to amortise scheduling,
/// small enough to balance clustered sets over threads.
const PARTICLES_PER_CHUNK: usize = 2048;
/// Consecutive particles searched together (one tree walk per group).
const GROUP_SIZE: usize = 64;
/// Nodes holding at most this many particles are scanned whole instead of
/// opened further.
const CANDIDATE_SIZE: usize = 32;
/// Targets per list of a grouped search ([`NeighborSearch::grouped`]): one
/// per SIMD lane of `f64x8`.
pub const GROUP_LANES: usize = 8;
const _: () = assert!(
    GROUP_SIZE.is_multiple_of(GROUP_LANES) && PARTICLES_PER_CHUNK.is_multiple_of(GROUP_SIZE)
);

/// Search settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeighborSearch {
    /// Search radius in units of `h` (2 for every built-in SPH kernel).
    pub support: f64,
    /// Most neighbours stored per particle; beyond it a list is cut and the
    /// particle is reported in [`NeighborStats`] (never silently).
    pub cap: usize,
    /// List `j` for `i` when `|x_i - x_j| < support * max(h_i, h_j)`, so
    /// every interacting pair appears in both lists (what pairwise
    /// antisymmetric forces need). Counts stay one-sided (`< support * h_i`).
    pub symmetric: bool,
    /// [`find_compact`](Self::find_compact) only: one list per
    /// [`GROUP_LANES`] consecutive targets (counted from the first target),
    /// the union of theirs, for loops that take a group of targets per
    /// vector (one lane each). Counts stay per target. The group's lanes are
    /// tested against each candidate at once, so grouped searches are also
    /// faster (3x at 100 neighbours), and the lists take about a third of the
    /// memory.
    pub grouped: bool,
}

impl Default for NeighborSearch {
    fn default() -> Self {
        Self {
            support: 2.0,
            cap: u32::MAX as usize,
            symmetric: false,
            grouped: false,
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
    // Largest h per tree node (symmetric searches).
    node_hmax: Vec<f64>,
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

    /// Neighbour count of target `i` within `support * h_i` (self
    /// included), even if its list was cut.
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
        self.validate(tree, bbox, x, y, z, h, &targets, None)?;
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
        if self.symmetric {
            node_hmax(tree, h, &mut list.node_hmax);
        }
        let ctx = self.context(tree, bbox, [x, y, z, h], Some(&list.node_hmax));
        let cap = self.cap;
        let cut: (usize, Option<usize>);
        // Pass 1, parallel over chunks: each chunk writes its own buffer and
        // its slice of the counts and list sizes.
        {
            let lens = || chunks.iter().map(|c| c.particles.len());
            let counts = split_by(&mut list.counts, lens());
            let sizes = split_by(&mut list.offsets[1..], lens());
            let work: Vec<_> = chunks
                .iter()
                .zip(list.chunk_indices.iter_mut())
                .zip(counts.into_iter().zip(sizes))
                .map(|((chunk, buf), (c, s))| (chunk, buf, c, s))
                .collect();
            cut = work
                .into_par_iter()
                .map(|(chunk, buf, counts, sizes)| {
                    buf.clear();
                    let mut sink = ListSink {
                        buf,
                        counts,
                        sizes,
                        cap,
                        base: chunk.particles.start,
                        over_cap: 0,
                        first_over_cap: None,
                    };
                    ctx.run_chunk(chunk, &mut sink);
                    (sink.over_cap, sink.first_over_cap)
                })
                .reduce(
                    || (0, None),
                    |a, b| {
                        let first = match (a.1, b.1) {
                            (Some(x), Some(y)) => Some(x.min(y)),
                            (x, y) => x.or(y),
                        };
                        (a.0 + b.0, first)
                    },
                );
        }
        // Prefix sum of the list sizes, then one parallel copy per chunk.
        for k in 0..nt {
            list.offsets[k + 1] += list.offsets[k];
        }
        let total = list.offsets[nt];
        list.indices.clear();
        list.indices.resize(total, 0);
        {
            let bufs = &list.chunk_indices[..chunks.len()];
            let dests = split_by(&mut list.indices, bufs.iter().map(|b| b.len()));
            dests
                .into_par_iter()
                .zip(bufs.par_iter())
                .for_each(|(d, b)| d.copy_from_slice(b));
        }
        let mut st = stats(&list.counts, usize::MAX, targets.start);
        (st.over_cap, st.first_over_cap) = cut;
        Ok(st)
    }

    /// Like [`find`](Self::find), but stores the lists run-length encoded
    /// ([`CompactNeighborList`]): a fraction of the memory of CSR. The cap
    /// does not apply (lists are never cut).
    pub fn find_compact(
        &self,
        tree: &Octree,
        bbox: &BoundingBox,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        h: &[f64],
        targets: Range<usize>,
        list: &mut CompactNeighborList,
    ) -> Result<NeighborStats, TreeError> {
        self.compact(tree, bbox, [x, y, z, h], targets, None, list)
    }

    /// Like [`find_compact`](Self::find_compact), for the flagged groups of
    /// targets only: `group_active[g]` says whether the targets
    /// `targets.start + g * GROUP_LANES ..` (at most [`GROUP_LANES`] of
    /// them, the last group possibly shorter) get their lists, so
    /// `group_active.len()` is `targets.len().div_ceil(GROUP_LANES)`. The
    /// groups are those of [`grouped`](Self::grouped) lists, whether the
    /// search is grouped or not.
    ///
    /// A flagged group's lists and counts are bit for bit those
    /// [`find_compact`](Self::find_compact) gives it (same entries, same
    /// order), whatever the other flags and the thread count. An unflagged
    /// group's lists are empty and its counts 0, so the list is indexed as
    /// after a full search. The stats cover the flagged targets only.
    ///
    /// The cost follows the flagged groups: unflagged ones are only marked
    /// empty, and a tree walk serves 64 consecutive targets, walked only if
    /// one of their groups is flagged. Symmetric searches still take one
    /// O(N) pass over the tree for each node's largest `h`. `h` is checked
    /// for the flagged targets only.
    ///
    /// # Panics
    ///
    /// If `group_active` does not hold one flag per group, or for the
    /// reasons [`find`](Self::find) panics.
    ///
    /// ```
    /// use sph_tree::{Boundary, BoundingBox, CompactNeighborList, NeighborSearch, Octree,
    ///                GROUP_LANES};
    ///
    /// // A 10^3 lattice in a periodic unit cube, x varying fastest.
    /// let n = 10;
    /// let (mut x, mut y, mut z) = (Vec::new(), Vec::new(), Vec::new());
    /// for i in 0..n * n * n {
    ///     x.push(((i % n) as f64 + 0.5) / n as f64);
    ///     y.push(((i / n % n) as f64 + 0.5) / n as f64);
    ///     z.push(((i / (n * n)) as f64 + 0.5) / n as f64);
    /// }
    /// let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
    /// // One leaf over the whole set: the tree needs sorted keys only.
    /// let keys = vec![0u64; x.len()];
    /// let tree = Octree::build(&keys, &x, &y, &z, x.len()).unwrap();
    /// let h = vec![0.075; x.len()];
    /// let search = NeighborSearch { grouped: true, ..Default::default() };
    ///
    /// // Lists for groups 0 and 5 only (targets 0..8 and 40..48).
    /// let groups = x.len().div_ceil(GROUP_LANES);
    /// let mut active = vec![false; groups];
    /// active[0] = true;
    /// active[5] = true;
    /// let mut some = CompactNeighborList::new();
    /// let st = search
    ///     .find_compact_groups(&tree, &bbox, &x, &y, &z, &h, 0..x.len(), &active, &mut some)
    ///     .unwrap();
    /// assert_eq!(st.min_count, 19); // over the 16 flagged targets
    ///
    /// let mut all = CompactNeighborList::new();
    /// search.find_compact(&tree, &bbox, &x, &y, &z, &h, 0..x.len(), &mut all).unwrap();
    /// for i in 0..x.len() {
    ///     if active[i / GROUP_LANES] {
    ///         assert!(some.runs(i).eq(all.runs(i)));
    ///         assert_eq!(some.count(i), all.count(i));
    ///     } else {
    ///         assert_eq!((some.runs(i).count(), some.count(i)), (0, 0));
    ///     }
    /// }
    /// ```
    pub fn find_compact_groups(
        &self,
        tree: &Octree,
        bbox: &BoundingBox,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        h: &[f64],
        targets: Range<usize>,
        group_active: &[bool],
        list: &mut CompactNeighborList,
    ) -> Result<NeighborStats, TreeError> {
        assert_eq!(
            group_active.len(),
            targets.len().div_ceil(GROUP_LANES),
            "one activity flag per group of {GROUP_LANES} targets"
        );
        self.compact(tree, bbox, [x, y, z, h], targets, Some(group_active), list)
    }

    /// [`find_compact`](Self::find_compact) (`active = None`) and
    /// [`find_compact_groups`](Self::find_compact_groups).
    fn compact(
        &self,
        tree: &Octree,
        bbox: &BoundingBox,
        [x, y, z, h]: [&[f64]; 4],
        targets: Range<usize>,
        active: Option<&[bool]>,
        list: &mut CompactNeighborList,
    ) -> Result<NeighborStats, TreeError> {
        self.validate(tree, bbox, x, y, z, h, &targets, active)?;
        let chunks = match active {
            None => target_chunks(tree, &targets),
            Some(a) => active_chunks(&targets, a),
        };
        let nt = targets.len();
        let width = if self.grouped { GROUP_LANES } else { 1 };
        list.targets = targets.clone();
        list.width = width;
        list.active.clear();
        list.counts.clear();
        list.counts.resize(nt, 0);
        list.start.clear();
        list.start.resize(nt.div_ceil(width), 0);
        list.chunk_first.clear();
        list.chunk_first.extend(
            chunks
                .iter()
                .map(|c| (c.particles.start - targets.start) / width),
        );
        if list.chunks.len() < chunks.len() {
            list.chunks.resize_with(chunks.len(), Vec::new);
        }
        list.n_chunks = chunks.len();
        if self.symmetric {
            node_hmax(tree, h, &mut list.node_hmax_scratch);
        }
        let mut ctx = self.context(tree, bbox, [x, y, z, h], Some(&list.node_hmax_scratch));
        ctx.grouped = self.grouped;
        ctx.active = active;
        ctx.first_target = targets.start;
        let lens = || chunks.iter().map(|c| c.particles.len());
        let counts = split_by(&mut list.counts, lens());
        let starts = split_by(
            &mut list.start,
            chunks.iter().map(|c| c.particles.len().div_ceil(width)),
        );
        let work: Vec<_> = chunks
            .iter()
            .zip(list.chunks.iter_mut())
            .zip(counts.into_iter().zip(starts))
            .map(|((chunk, buf), (c, s))| (chunk, buf, c, s))
            .collect();
        work.into_par_iter()
            .for_each(|(chunk, buf, counts, start)| {
                buf.clear();
                let mut sink = CompactSink {
                    buf,
                    counts,
                    start,
                    base: chunk.particles.start,
                    width,
                };
                ctx.run_chunk(chunk, &mut sink);
                sink.buf.shrink_to(sink.buf.len() + sink.buf.len() / 8);
            });
        Ok(match active {
            None => stats(&list.counts, usize::MAX, targets.start),
            Some(a) => {
                let mut st = Accumulated::default();
                for (g, _) in a.iter().enumerate().filter(|(_, &on)| on) {
                    let k = g * GROUP_LANES;
                    st.add(&list.counts[k..(k + GROUP_LANES).min(nt)]);
                }
                st.finish()
            }
        })
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
        self.validate(tree, bbox, x, y, z, h, &targets, None)?;
        counts.clear();
        counts.resize(targets.len(), 0);
        let chunks = target_chunks(tree, &targets);
        let ctx = self.context(tree, bbox, [x, y, z, h], None);
        let parts = split_by(counts, chunks.iter().map(|c| c.particles.len()));
        let work: Vec<_> = chunks.iter().zip(parts).collect();
        work.into_par_iter().for_each(|(chunk, counts)| {
            let mut sink = CountSink {
                counts,
                base: chunk.particles.start,
            };
            ctx.run_chunk(chunk, &mut sink);
        });
        Ok(stats(counts, self.cap, targets.start))
    }

    /// What a chunk search reads; `hmax` is the per-node largest h,
    /// used only by symmetric searches.
    fn context<'a>(
        &self,
        tree: &'a Octree,
        bbox: &'a BoundingBox,
        [x, y, z, h]: [&'a [f64]; 4],
        hmax: Option<&'a [f64]>,
    ) -> Context<'a> {
        Context {
            tree,
            bbox,
            x,
            y,
            z,
            h,
            support: self.support,
            node_hmax: if self.symmetric { hmax } else { None },
            grouped: false,
            active: None,
            first_target: 0,
        }
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
        active: Option<&[bool]>,
    ) -> Result<(), TreeError> {
        crate::check_lengths(x, y, z, Some(("h", h.len())))?;
        assert_eq!(
            tree.num_particles(),
            x.len(),
            "tree was built over a different particle set"
        );
        assert!(targets.end <= x.len(), "target range beyond the particles");
        let lengths = bbox.lengths();
        let checked = targets
            .clone()
            .filter(|i| active.is_none_or(|a| a[(i - targets.start) / GROUP_LANES]));
        for i in checked {
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

/// Receives the neighbours of consecutive target particles.
trait Sink {
    /// Whether the sink needs the indices (else only their number).
    const STORE: bool;
    /// Particle `i` has `count` neighbours within its own radius and
    /// `neighbors.len()` listed ones (symmetric searches list more); when
    /// `STORE` the list is complete and ascending (else it is empty).
    fn particle(&mut self, i: usize, neighbors: &[u32], count: usize);
    /// Targets `first..first + counts.len()` (one group) have the union
    /// `neighbors` (ascending) and the given counts. Only compact lists
    /// are grouped.
    fn group(&mut self, first: usize, neighbors: &[u32], counts: &[u32]) {
        let _ = (first, neighbors, counts);
        unreachable!("only compact lists are grouped");
    }
    /// Targets `targets` (whole groups of `GROUP_LANES` counted from the
    /// first target, or the short last one) are not searched: empty lists,
    /// counts 0. Only compact lists skip targets.
    fn skip(&mut self, targets: Range<usize>) {
        let _ = targets;
        unreachable!("only compact lists skip targets");
    }
}

struct ListSink<'a> {
    buf: &'a mut Vec<u32>,
    counts: &'a mut [u32],
    sizes: &'a mut [usize],
    cap: usize,
    base: usize,
    over_cap: usize,
    first_over_cap: Option<usize>,
}

impl Sink for ListSink<'_> {
    const STORE: bool = true;
    #[inline]
    fn particle(&mut self, i: usize, neighbors: &[u32], n: usize) {
        let k = i - self.base;
        let listed = neighbors.len();
        self.buf
            .extend_from_slice(&neighbors[..listed.min(self.cap)]);
        self.counts[k] = n.min(u32::MAX as usize) as u32;
        self.sizes[k] = listed.min(self.cap);
        if listed > self.cap {
            self.over_cap += 1;
            self.first_over_cap.get_or_insert(i);
        }
    }
}

struct CompactSink<'a> {
    buf: &'a mut Vec<u8>,
    counts: &'a mut [u32],
    start: &'a mut [u32],
    base: usize,
    width: usize,
}

impl Sink for CompactSink<'_> {
    const STORE: bool = true;
    #[inline]
    fn particle(&mut self, i: usize, neighbors: &[u32], n: usize) {
        let k = i - self.base;
        self.start[k] = self.buf.len() as u32;
        self.counts[k] = n.min(u32::MAX as usize) as u32;
        crate::compact::encode(self.buf, i, neighbors);
    }

    #[inline]
    fn group(&mut self, first: usize, neighbors: &[u32], counts: &[u32]) {
        let k = first - self.base;
        self.start[k / self.width] = self.buf.len() as u32;
        self.counts[k..k + counts.len()].copy_from_slice(counts);
        crate::compact::encode(self.buf, first, neighbors);
    }

    #[inline]
    fn skip(&mut self, targets: Range<usize>) {
        let k = targets.start - self.base;
        let end = self.buf.len() as u32;
        self.start[k / self.width..(k + targets.len()).div_ceil(self.width)].fill(end);
        self.counts[k..k + targets.len()].fill(0);
    }
}

struct CountSink<'a> {
    counts: &'a mut [u32],
    base: usize,
}

impl Sink for CountSink<'_> {
    const STORE: bool = false;
    #[inline]
    fn particle(&mut self, i: usize, _neighbors: &[u32], n: usize) {
        self.counts[i - self.base] = n.min(u32::MAX as usize) as u32;
    }
}

/// A leaf that may hold neighbours of a group, with the periodic shift that
/// brings it next to the group (`exact_shift = false`: the shift is not
/// guaranteed right for every pair, so pairs use the minimum image).
struct Candidate {
    particles: Range<usize>,
    lo: [f64; 3],
    hi: [f64; 3],
    shift: [f64; 3],
    exact_shift: bool,
    /// Largest search radius of the node's particles (symmetric mode).
    r_node: f64,
}

/// A run of consecutive leaves searched by one parallel task.
struct Chunk {
    particles: Range<usize>,
}

struct Context<'a> {
    tree: &'a Octree,
    bbox: &'a BoundingBox,
    x: &'a [f64],
    y: &'a [f64],
    z: &'a [f64],
    h: &'a [f64],
    support: f64,
    node_hmax: Option<&'a [f64]>,
    /// One list per GROUP_LANES targets (compact lists only).
    grouped: bool,
    /// Flags of the groups of GROUP_LANES targets counted from
    /// `first_target` that are searched (compact lists only; `None`: all).
    active: Option<&'a [bool]>,
    first_target: usize,
}

impl Context<'_> {
    /// Whether the group of `GROUP_LANES` targets starting at `first` is
    /// searched.
    #[inline]
    fn is_active(&self, first: usize) -> bool {
        self.active
            .is_none_or(|a| a[(first - self.first_target) / GROUP_LANES])
    }

    /// Searches the chunk in groups of `GROUP_SIZE` consecutive particles
    /// (compact in space, thanks to the curve): one tree walk per group finds
    /// the candidate nodes, then each particle of the group scans only those.
    fn run_chunk(&self, chunk: &Chunk, sink: &mut impl Sink) {
        let mut cands: Vec<Candidate> = Vec::with_capacity(256);
        let mut scratch: Vec<u32> = Vec::new();
        let mut a = chunk.particles.start;
        while a < chunk.particles.end {
            let b = (a + GROUP_SIZE).min(chunk.particles.end);
            if (a..b).step_by(GROUP_LANES).any(|g| self.is_active(g)) {
                self.search_group(a..b, &mut cands, &mut scratch, sink);
            } else {
                sink.skip(a..b);
            }
            a = b;
        }
    }

    fn search_group<S: Sink>(
        &self,
        group: Range<usize>,
        cands: &mut Vec<Candidate>,
        scratch: &mut Vec<u32>,
        sink: &mut S,
    ) {
        let (x, y, z) = (self.x, self.y, self.z);
        let bbox = self.bbox;
        let lengths = bbox.lengths();
        let periodic = [
            bbox.is_periodic(0),
            bbox.is_periodic(1),
            bbox.is_periodic(2),
        ];
        let support = self.support;
        // Group box and largest search radius, over every target of the
        // group, flagged or not: the candidates (and their shifts) are then
        // the full search's, so flagged targets get its lists bit for bit.
        let mut glo = [f64::INFINITY; 3];
        let mut ghi = [f64::NEG_INFINITY; 3];
        let mut rgroup: f64 = 0.0;
        for i in group.clone() {
            let p = [x[i], y[i], z[i]];
            for d in 0..3 {
                glo[d] = glo[d].min(p[d]);
                ghi[d] = ghi[d].max(p[d]);
            }
            rgroup = rgroup.max(support * self.h[i]);
        }
        let gc = [
            0.5 * (glo[0] + ghi[0]),
            0.5 * (glo[1] + ghi[1]),
            0.5 * (glo[2] + ghi[2]),
        ];
        let gh = [
            0.5 * (ghi[0] - glo[0]),
            0.5 * (ghi[1] - glo[1]),
            0.5 * (ghi[2] - glo[2]),
        ];
        // Search radius against a node: the group's, or in symmetric mode
        // the larger of it and the node's own particles' radii.
        let node_r = |node: NodeId| -> f64 {
            match self.node_hmax {
                Some(hm) => rgroup.max(support * hm[node as usize]),
                None => rgroup,
            }
        };
        // Squared gap between the group box and a node box (nearest
        // periodic image), the shift putting the node there, and whether
        // that single shift is right for every pair within `r`.
        let gaps = |lo: [f64; 3], hi: [f64; 3], r: f64| -> (f64, [f64; 3], bool) {
            let mut d2 = 0.0;
            let mut shift = [0.0; 3];
            let mut exact = true;
            for d in 0..3 {
                let nc = 0.5 * (lo[d] + hi[d]);
                let nh = 0.5 * (hi[d] - lo[d]);
                let mut dc = nc - gc[d];
                if periodic[d] {
                    let s = -lengths[d] * (dc / lengths[d]).round();
                    dc += s;
                    shift[d] = s;
                    exact &= r + 2.0 * (gh[d] + nh) <= 0.5 * lengths[d];
                }
                let gap = dc.abs() - gh[d] - nh;
                if gap > 0.0 {
                    d2 += gap * gap;
                }
            }
            (d2, shift, exact)
        };
        cands.clear();
        let tree = self.tree;
        tree.traverse(
            |node| {
                let (lo, hi) = tree.node_box(node);
                let r = node_r(node);
                let (d2, shift, exact_shift) = gaps(lo, hi, r);
                if d2 >= r * r {
                    return false;
                }
                let particles = tree.particles(node);
                if particles.len() > CANDIDATE_SIZE && !tree.is_leaf(node) {
                    return true; // descend
                }
                cands.push(Candidate {
                    particles,
                    lo: [lo[0] + shift[0], lo[1] + shift[1], lo[2] + shift[2]],
                    hi: [hi[0] + shift[0], hi[1] + shift[1], hi[2] + shift[2]],
                    shift,
                    exact_shift,
                    r_node: self.node_hmax.map_or(0.0, |hm| support * hm[node as usize]),
                });
                false
            },
            |_| {},
        );
        // Room for every candidate particle, so the scan below can write
        // each index unconditionally and advance only on a hit (no branch).
        let most: usize = cands.iter().map(|c| c.particles.len()).sum();
        if S::STORE && scratch.len() < most {
            scratch.resize(most, 0);
        }
        // Search groups start on a multiple of GROUP_LANES from the first
        // target, so activity flags cover whole sub-groups.
        let mut a = group.start;
        while a < group.end {
            let b = (a + GROUP_LANES).min(group.end);
            if !self.is_active(a) {
                sink.skip(a..b);
            } else if self.grouped {
                self.scan_lanes(a..b, cands, scratch, sink);
            } else {
                for i in a..b {
                    self.scan_target(i, cands, scratch, sink);
                }
            }
            a = b;
        }
    }

    /// The neighbours of target `i` among the candidates of its search
    /// group.
    #[inline]
    fn scan_target<S: Sink>(
        &self,
        i: usize,
        cands: &[Candidate],
        scratch: &mut [u32],
        sink: &mut S,
    ) {
        let (x, y, z) = (self.x, self.y, self.z);
        let bbox = self.bbox;
        let support = self.support;
        let symmetric = self.node_hmax.is_some();
        let p = [x[i], y[i], z[i]];
        let r = support * self.h[i];
        let r2 = r * r;
        let mut len = 0usize;
        let mut own = 0usize;
        for c in cands.iter() {
            // Point-to-box distance against the (shifted) leaf box.
            let mut d2 = 0.0;
            for d in 0..3 {
                let g = (c.lo[d] - p[d]).max(p[d] - c.hi[d]);
                if g > 0.0 {
                    d2 += g * g;
                }
            }
            let reach = r.max(c.r_node);
            if c.exact_shift && d2 >= reach * reach {
                continue;
            }
            let q = if c.exact_shift {
                [p[0] - c.shift[0], p[1] - c.shift[1], p[2] - c.shift[2]]
            } else {
                p
            };
            for j in c.particles.clone() {
                let dd = if c.exact_shift {
                    let (dx, dy, dz) = (q[0] - x[j], q[1] - y[j], q[2] - z[j]);
                    dx * dx + dy * dy + dz * dz
                } else {
                    bbox.distance2(p, [x[j], y[j], z[j]])
                };
                let inside = dd < r2;
                let listed = if symmetric {
                    let rj = support * self.h[j];
                    inside | (dd < rj * rj)
                } else {
                    inside
                };
                if S::STORE {
                    scratch[len] = j as u32;
                }
                len += usize::from(listed);
                own += usize::from(inside);
            }
        }
        sink.particle(i, &scratch[..if S::STORE { len } else { 0 }], own);
    }

    /// The grouped form of the per-target scan of [`search_group`](Self::search_group):
    /// the targets of `sub` (at most `GROUP_LANES`) take one lane each and
    /// test every candidate particle at once, with the per-target scan's
    /// arithmetic and decisions lane by lane (so the union and the counts
    /// are exactly those of per-target searches).
    fn scan_lanes<S: Sink>(
        &self,
        sub: Range<usize>,
        cands: &[Candidate],
        scratch: &mut [u32],
        sink: &mut S,
    ) {
        let (x, y, z) = (self.x, self.y, self.z);
        let valid = sub.len();
        let load = |a: &[f64]| {
            let mut r = [a[sub.end - 1]; GROUP_LANES];
            r[..valid].copy_from_slice(&a[sub.clone()]);
            f64x8::new(r)
        };
        let splat = f64x8::splat;
        let zero = splat(0.0);
        let p = [load(x), load(y), load(z)];
        let r = splat(self.support) * load(self.h);
        let r2 = r * r;
        let bbox = self.bbox;
        let lengths = bbox.lengths();
        // Minimum-image fold as BoundingBox::min_image (infinite half
        // length on open axes: never folds).
        let half: [f64; 3] = std::array::from_fn(|d| {
            if bbox.is_periodic(d) {
                0.5 * lengths[d]
            } else {
                f64::INFINITY
            }
        });
        let fold = |d: f64x8, k: usize| {
            let l = splat(lengths[k]);
            let above = d.simd_gt(splat(half[k]));
            let below = d.simd_lt(splat(-half[k]));
            above.select(d - l, below.select(d + l, d))
        };
        let symmetric = self.node_hmax.is_some();
        let mut count = zero;
        let mut len = 0usize;
        for c in cands {
            // Point-to-box distance per lane against the (shifted) leaf box.
            let mut d2 = zero;
            for d in 0..3 {
                let a = splat(c.lo[d]) - p[d];
                let b = p[d] - splat(c.hi[d]);
                let g = a.simd_gt(b).select(a, b);
                d2 += g.simd_gt(zero).select(g * g, zero);
            }
            let rn = splat(c.r_node);
            let reach = r.simd_gt(rn).select(r, rn);
            // Lanes the per-target scan would skip for this candidate.
            let active = if c.exact_shift {
                d2.simd_lt(reach * reach)
            } else {
                zero.simd_eq(zero)
            };
            if c.exact_shift && !active.any() {
                continue;
            }
            let q = if c.exact_shift {
                [0, 1, 2].map(|d| p[d] - splat(c.shift[d]))
            } else {
                p
            };
            for j in c.particles.clone() {
                let (dx, dy, dz) = if c.exact_shift {
                    (q[0] - splat(x[j]), q[1] - splat(y[j]), q[2] - splat(z[j]))
                } else {
                    (
                        fold(p[0] - splat(x[j]), 0),
                        fold(p[1] - splat(y[j]), 1),
                        fold(p[2] - splat(z[j]), 2),
                    )
                };
                let dd = dx * dx + dy * dy + dz * dz;
                let inside = dd.simd_lt(r2) & active;
                let listed = if symmetric {
                    let rj = self.support * self.h[j];
                    inside | (dd.simd_lt(splat(rj * rj)) & active)
                } else {
                    inside
                };
                count += inside.select(splat(1.0), zero);
                scratch[len] = j as u32;
                len += usize::from(listed.any());
            }
        }
        let mut counts = [0u32; GROUP_LANES];
        for (c, &v) in counts.iter_mut().zip(count.as_array()) {
            *c = v as u32;
        }
        sink.group(sub.start, &scratch[..len], &counts[..valid]);
    }
}

/// Splits the targets into runs of `PARTICLES_PER_CHUNK` consecutive
/// particles, one parallel task each (a multiple of the search groups and
/// list groups, counted from the first target).
fn target_chunks(_tree: &Octree, targets: &Range<usize>) -> Vec<Chunk> {
    (targets.start..targets.end)
        .step_by(PARTICLES_PER_CHUNK)
        .map(|a| Chunk {
            particles: a..(a + PARTICLES_PER_CHUNK).min(targets.end),
        })
        .collect()
}

/// Splits the targets for a search of the flagged groups: runs of search
/// groups (`GROUP_SIZE` targets counted from the first target, so the same
/// as a full search's) holding about `PARTICLES_PER_CHUNK` flagged targets,
/// at most `SKIP_SPAN` targets long. Depends on the flags only (never on
/// the thread count).
fn active_chunks(targets: &Range<usize>, active: &[bool]) -> Vec<Chunk> {
    const SKIP_SPAN: usize = 16 * PARTICLES_PER_CHUNK;
    let mut chunks = Vec::new();
    let (mut a, mut flagged) = (targets.start, 0);
    let mut g = 0; // first group of the next search group
    for s in (targets.start..targets.end).step_by(GROUP_SIZE) {
        let e = (s + GROUP_SIZE).min(targets.end);
        let g_end = (e - targets.start).div_ceil(GROUP_LANES);
        flagged += active[g..g_end].iter().filter(|&&f| f).count() * GROUP_LANES;
        g = g_end;
        if flagged >= PARTICLES_PER_CHUNK || e - a >= SKIP_SPAN || e == targets.end {
            chunks.push(Chunk { particles: a..e });
            (a, flagged) = (e, 0);
        }
    }
    chunks
}

/// Count statistics accumulated over pieces of the counts.
#[derive(Default)]
struct Accumulated {
    min: Option<u32>,
    max: u32,
    total: usize,
}

impl Accumulated {
    fn add(&mut self, counts: &[u32]) {
        for &c in counts {
            self.min = Some(self.min.map_or(c, |m| m.min(c)));
            self.max = self.max.max(c);
            self.total += c as usize;
        }
    }

    fn finish(self) -> NeighborStats {
        NeighborStats {
            min_count: self.min.unwrap_or(0) as usize,
            max_count: self.max as usize,
            total: self.total,
            over_cap: 0,
            first_over_cap: None,
        }
    }
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

/// Largest h over each node's particles, bottom-up.
fn node_hmax(tree: &Octree, h: &[f64], out: &mut Vec<f64>) {
    out.clear();
    out.resize(tree.num_nodes(), 0.0);
    for l in (0..tree.num_levels()).rev() {
        for node in tree.level_nodes(l) {
            let m = if tree.is_leaf(node) {
                h[tree.particles(node)]
                    .iter()
                    .fold(0.0, |a: f64, &b| a.max(b))
            } else {
                tree.children(node)
                    .fold(0.0, |a: f64, c| a.max(out[c as usize]))
            };
            out[node as usize] = m;
        }
    }
}

/// Cuts `data` into consecutive pieces of the given lengths (one per
/// parallel chunk).
fn split_by<T>(mut data: &mut [T], lens: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut out = Vec::new();
    for len in lens {
        let (a, rest) = std::mem::take(&mut data).split_at_mut(len);
        out.push(a);
        data = rest;
    }
    out
}
