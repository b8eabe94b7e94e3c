//! Neighbour lists stored as runs of consecutive indices.
//!
//! Particles sorted along a Hilbert curve have neighbours that come in runs
//! of consecutive indices, so a list is stored as `(start, length)` pairs,
//! LEB128-encoded relative to the previous run: about 0.6-1 byte per
//! neighbour instead of 4 for plain `u32` CSR, and stages iterate over
//! index ranges without decoding every element. Lists stay in the
//! per-chunk buffers they are written to (no concatenation copy).

use std::ops::Range;

/// Run-length-encoded neighbour lists of a contiguous range of targets.
/// Built by [`NeighborSearch::find_compact`](crate::NeighborSearch::find_compact),
/// or for flagged groups of targets only by
/// [`NeighborSearch::find_compact_groups`](crate::NeighborSearch::find_compact_groups)
/// (the others then have empty lists).
#[derive(Debug, Clone, Default)]
pub struct CompactNeighborList {
    pub(crate) targets: Range<usize>,
    // Targets per list: 1, or GROUP_LANES for grouped lists (0 reads as 1).
    pub(crate) width: usize,
    // First list of each chunk, ascending.
    pub(crate) chunk_first: Vec<usize>,
    // Encoded runs of each chunk (buffers kept between searches).
    pub(crate) chunks: Vec<Vec<u8>>,
    // Byte offset of each list within its chunk.
    pub(crate) start: Vec<u32>,
    // One-sided neighbour counts (within support * h_i).
    pub(crate) counts: Vec<u32>,
    pub(crate) n_chunks: usize,
    // Largest h per tree node (symmetric searches).
    pub(crate) node_hmax_scratch: Vec<f64>,
    // One flag per target when the lists serve some targets only (block
    // time steps); empty when they serve every target.
    pub(crate) active: Vec<bool>,
}

impl CompactNeighborList {
    /// An empty list.
    pub fn new() -> Self {
        Self::default()
    }

    /// The target particles the lists belong to.
    pub fn targets(&self) -> Range<usize> {
        self.targets.clone()
    }

    /// The targets the lists serve, one flag per target of
    /// [`targets`](Self::targets), or `None` when they serve every target
    /// (after [`find_compact`](crate::NeighborSearch::find_compact)). Pair
    /// loops over the lists compute the flagged targets only.
    pub fn active_targets(&self) -> Option<&[bool]> {
        (!self.active.is_empty()).then_some(self.active.as_slice())
    }

    /// The targets the lists serve, ascending: all of
    /// [`targets`](Self::targets), or the flagged ones
    /// ([`active_targets`](Self::active_targets)).
    pub fn served_targets(&self) -> impl Iterator<Item = usize> + '_ {
        let start = self.targets.start;
        self.targets
            .clone()
            .filter(move |&i| self.active.is_empty() || self.active[i - start])
    }

    /// Marks the lists as serving the flagged targets only (one flag per
    /// target; lists of
    /// [`find_compact_groups`](crate::NeighborSearch::find_compact_groups)
    /// with every flagged target in a flagged group), until the next
    /// search.
    ///
    /// # Panics
    /// If `flags` does not hold one flag per target.
    pub fn set_active_targets(&mut self, flags: &[bool]) {
        assert_eq!(flags.len(), self.targets.len(), "one flag per target");
        self.active.clear();
        self.active.extend_from_slice(flags);
    }

    /// Targets sharing one list: 1, or [`GROUP_LANES`](crate::GROUP_LANES)
    /// for lists built with [`NeighborSearch::grouped`](crate::NeighborSearch::grouped).
    #[inline]
    pub fn width(&self) -> usize {
        self.width.max(1)
    }

    /// Neighbour count of target `i` within `support * h_i`, self included.
    #[inline]
    pub fn count(&self, i: usize) -> usize {
        self.counts[i - self.targets.start] as usize
    }

    /// The neighbours of target `i` as ascending runs of consecutive
    /// indices. For grouped lists ([`width`](Self::width) > 1) these are the
    /// neighbours of any target of `i`'s group: a superset of `i`'s own,
    /// the same for every target of the group.
    #[inline]
    pub fn runs(&self, i: usize) -> Runs<'_> {
        let w = self.width();
        let k = (i - self.targets.start) / w;
        let c = self.chunk_first[..self.n_chunks].partition_point(|&f| f <= k) - 1;
        let buf = &self.chunks[c];
        let a = self.start[k] as usize;
        let last_in_chunk = if c + 1 < self.n_chunks {
            self.chunk_first[c + 1] == k + 1
        } else {
            k + 1 == self.start.len()
        };
        let b = if last_in_chunk {
            buf.len()
        } else {
            self.start[k + 1] as usize
        };
        Runs {
            bytes: &buf[a..b],
            prev_end: self.targets.start + k * w,
        }
    }

    /// The neighbours of target `i`, ascending.
    #[inline]
    pub fn neighbors(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.runs(i).flatten()
    }

    /// Number of listed neighbours of `i` (at least [`count`](Self::count)
    /// for symmetric searches; the group's for grouped lists).
    pub fn listed(&self, i: usize) -> usize {
        self.runs(i).map(|r| r.len()).sum()
    }

    /// Bytes held (capacity of every buffer), for memory reports.
    pub fn bytes(&self) -> usize {
        self.chunks.iter().map(|c| c.capacity()).sum::<usize>()
            + self.start.capacity() * 4
            + self.counts.capacity() * 4
            + self.chunk_first.capacity() * 8
            + self.node_hmax_scratch.capacity() * 8
            + self.active.capacity()
    }
}

/// Iterator over the runs of one list.
#[derive(Debug, Clone)]
pub struct Runs<'a> {
    bytes: &'a [u8],
    prev_end: usize,
}

impl Iterator for Runs<'_> {
    type Item = Range<usize>;

    #[inline]
    fn next(&mut self) -> Option<Range<usize>> {
        if self.bytes.is_empty() {
            return None;
        }
        let offset = unzigzag(read_varint(&mut self.bytes));
        let len = read_varint(&mut self.bytes) as usize + 1;
        let a = (self.prev_end as i64 + offset) as usize;
        self.prev_end = a + len;
        Some(a..a + len)
    }
}

#[inline]
fn read_varint(bytes: &mut &[u8]) -> u64 {
    let mut v = 0u64;
    let mut shift = 0;
    loop {
        let b = bytes[0];
        *bytes = &bytes[1..];
        v |= u64::from(b & 0x7f) << shift;
        if b < 0x80 {
            return v;
        }
        shift += 7;
    }
}

#[inline]
fn write_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

#[inline]
fn zigzag(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

#[inline]
fn unzigzag(v: u64) -> i64 {
    ((v >> 1) as i64) ^ -((v & 1) as i64)
}

/// Appends the ascending list `nb` of particle `i` to `out` as runs.
pub(crate) fn encode(out: &mut Vec<u8>, i: usize, nb: &[u32]) {
    let mut prev_end = i as i64;
    let mut k = 0;
    while k < nb.len() {
        let a = nb[k] as i64;
        let mut e = k + 1;
        while e < nb.len() && nb[e] == nb[e - 1] + 1 {
            e += 1;
        }
        write_varint(out, zigzag(a - prev_end));
        write_varint(out, (e - k - 1) as u64);
        prev_end = a + (e - k) as i64;
        k = e;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varint_and_zigzag_round_trip() {
        for v in [0i64, 1, -1, 63, -64, 64, 1 << 20, -(1 << 33), i64::MAX / 2] {
            let mut b = Vec::new();
            write_varint(&mut b, zigzag(v));
            let mut s = &b[..];
            assert_eq!(unzigzag(read_varint(&mut s)), v);
            assert!(s.is_empty());
        }
    }
}
