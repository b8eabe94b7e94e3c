//! The one pair-loop driver: every SPH pair stage (density, IAD, momentum
//! and energy, the viscosity switches, conduction) is a [`PairStage`] run
//! by [`PairLoop::run`].
//!
//! The driver owns everything that is the same in every stage: targets in
//! groups of [`LANES`] consecutive particles (compact in space along the
//! curve), one per vector lane; the union of their neighbour lists
//! ([`GroupUnion`]); the periodic fold, skipped for groups where it is the
//! identity; one bounds check per run of neighbours; the rayon split of
//! the groups over threads; the outputs cut into per-group chunks
//! ([`LaneOutputs`]); and the reduction of per-group figures
//! ([`Reduce`]). A stage supplies its per-pair arithmetic and its finish.
//!
//! Each neighbour `j` of a group's union is broadcast to all lanes and
//! interacts with every target of the group at once; a lane whose target
//! does not have `j` as neighbour adds an exact zero (the kernel vanishes
//! beyond its support, or the stage masks the pair with
//! [`neighbour_lanes`]). So lane `l` computes, operation for operation, the
//! sequential ascending-order sum a scalar loop over its own list computes:
//! results do not depend on the grouping, the number of threads or the
//! number of ranks, while the arithmetic runs as vector instructions.
//!
//! [`PairLoop::run_masked`] runs the same loop for a subset of the targets
//! (block time steps): groups without an active target are skipped, and
//! in the others the inactive targets' outputs are put back after the
//! stage's `finish`, so the active targets get `run`'s bits and no stage
//! needs to know about the mask.
//!
//! # Example: a stage of your own
//! The number of neighbours within `h` of each particle:
//!
//! ```
//! use sph_core::pair_loop::{Group, PairLoop, PairStage};
//! use sph_kernels::F64s;
//! use sph_tree::{compute_keys, Boundary, BoundingBox, CompactNeighborList, Curve};
//! use sph_tree::{apply_permutation, KeySorter, NeighborSearch, Octree};
//!
//! struct CloseCount<'a> {
//!     h: &'a [f64],
//! }
//!
//! impl PairStage for CloseCount<'_> {
//!     type Sums = (F64s, F64s); // (h^2 of the targets, count)
//!     type Out<'o> = [&'o mut [f64]; 1];
//!     type Stats = ();
//!     fn start(&self, g: &Group) -> Self::Sums {
//!         let h = g.load(self.h);
//!         (h * h, F64s::splat(0.0))
//!     }
//!     fn pair(&self, s: &mut Self::Sums, _j: usize, _d: [F64s; 3], r2: F64s) {
//!         s.1 += r2.lt(s.0).select(F64s::splat(1.0), F64s::splat(0.0));
//!     }
//!     fn finish(&self, _g: &Group, s: Self::Sums, [out]: &mut Self::Out<'_>) {
//!         s.1.store(out);
//!     }
//! }
//!
//! // A 6^3 lattice in a periodic unit box, sorted along the curve.
//! let n = 6;
//! let (mut x, mut y, mut z) = (vec![], vec![], vec![]);
//! for i in 0..n * n * n {
//!     x.push(((i % n) as f64 + 0.5) / n as f64);
//!     y.push(((i / n % n) as f64 + 0.5) / n as f64);
//!     z.push(((i / (n * n)) as f64 + 0.5) / n as f64);
//! }
//! let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
//! let mut keys = Vec::new();
//! compute_keys(&bbox, Curve::Hilbert, &x, &y, &z, &mut keys);
//! let mut perm = Vec::new();
//! KeySorter::new().sort(&keys, None, &mut perm);
//! for v in [&mut x, &mut y, &mut z] {
//!     *v = perm.iter().map(|&k| v[k as usize]).collect();
//! }
//! apply_permutation(&perm, &mut keys, &mut Vec::new());
//! let h = vec![1.01 / n as f64; x.len()];
//! let tree = Octree::build(&keys, &x, &y, &z, 8).unwrap();
//! let mut nl = CompactNeighborList::new();
//! NeighborSearch::default()
//!     .find_compact(&tree, &bbox, &x, &y, &z, &h, 0..x.len(), &mut nl)
//!     .unwrap();
//!
//! let mut count = vec![0.0; x.len()];
//! PairLoop::new(&bbox, 2.0, [&x, &y, &z], &h, &nl)
//!     .unwrap()
//!     .run(&CloseCount { h: &h }, [&mut count]);
//! // Each particle has its 6 face neighbours at one spacing (itself too, at 0).
//! assert!(count.iter().all(|&c| c == 7.0));
//! ```

use crate::geometry::Separation;
use crate::CoreError;
use rayon::prelude::*;
pub use sph_kernels::{F64s, LANES};
use sph_tree::{BoundingBox, CompactNeighborList};
use std::ops::Range;

// Grouped neighbour lists are built for this lane width.
const _: () = assert!(LANES == sph_tree::GROUP_LANES);

/// A group of up to [`LANES`] consecutive targets, one per lane; padding
/// lanes (when fewer than `LANES` targets remain) repeat the last target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Group {
    /// Local index of the first target.
    pub first: usize,
    /// Targets in the group (1 to [`LANES`]).
    pub valid: usize,
    /// Bit `l` set: the target of lane `l` is active, its outputs are kept
    /// ([`PairLoop::run_masked`]); every valid lane in [`PairLoop::run`].
    pub active: u32,
}

// The lane mask has a bit per lane.
const _: () = assert!(LANES <= 32);

impl Group {
    /// `values[first + l]` in lane `l` (padding lanes repeat the last).
    #[inline(always)]
    pub fn load(&self, values: &[f64]) -> F64s {
        F64s::load(values, self.first, self.valid)
    }

    /// Local indices of the group's targets.
    pub fn targets(&self) -> Range<usize> {
        self.first..self.first + self.valid
    }

    /// The mask with every valid lane active.
    pub fn all_lanes(valid: usize) -> u32 {
        (1u32 << valid) - 1
    }

    /// Whether every valid lane is active.
    pub fn all_active(&self) -> bool {
        self.active == Self::all_lanes(self.valid)
    }
}

/// One pair interaction on the shared driver: what a group of targets
/// starts from, what each neighbour adds, and what the sums become.
///
/// The driver calls, per group, [`start`](Self::start), then
/// [`pair`](Self::pair) for every partner `j` of the union of the group's
/// neighbour lists in ascending order (the target itself included, at
/// distance 0), then [`finish`](Self::finish) with the group's chunk of
/// the outputs; the groups' [`Stats`](Self::Stats) are reduced. A stage
/// computes every lane; in a masked run ([`PairLoop::run_masked`]) the
/// driver puts the inactive lanes' outputs back afterwards, so no stage
/// needs to know which lanes count (its `Stats` cover every lane of a
/// group with an active one).
pub trait PairStage: Sync {
    /// Per-group state: target values loaded by `start`, and the sums.
    type Sums;
    /// Per-target outputs (slices over the targets, cut into groups).
    type Out<'o>: LaneOutputs;
    /// A figure over all targets (e.g. a minimum for the time step).
    type Stats: Reduce;

    /// Loads the group's target values and zeroes its sums.
    fn start(&self, g: &Group) -> Self::Sums;

    /// Adds partner `j` at separation `d = x_i - x_j` (minimum image;
    /// one lane per target) and squared distance
    /// `r2 = d[0]^2 + d[1]^2 + d[2]^2`.
    fn pair(&self, sums: &mut Self::Sums, j: usize, d: [F64s; 3], r2: F64s);

    /// Turns the sums into the group's outputs (the first `g.valid`
    /// entries of each output slice) and its figure.
    fn finish(&self, g: &Group, sums: Self::Sums, out: &mut Self::Out<'_>) -> Self::Stats;
}

/// A figure reduced over groups in any order: `merge` must be associative
/// and commutative with `identity` as neutral element.
pub trait Reduce: Send + Sized {
    /// The neutral element.
    fn identity() -> Self;
    /// Combines two groups' figures.
    fn merge(self, other: Self) -> Self;
}

impl Reduce for () {
    fn identity() -> Self {}
    fn merge(self, _: Self) -> Self {}
}

/// Per-target output slices that can be cut at a target index, so the
/// driver hands each group its own chunk: `[&mut [f64]; N]` (N slices of
/// one length), `Option` of outputs (an output the caller did not ask for)
/// and pairs of outputs.
pub trait LaneOutputs: Send + Sized {
    /// Length of every slice (`None` for an absent output).
    fn entries(&self) -> Option<usize>;
    /// The first `mid` entries and the rest.
    fn split_at(self, mid: usize) -> (Self, Self);
    /// Appends the entries of the lanes `l < valid` whose bit in `mask`
    /// is clear to `keep`, slice by slice.
    fn save(&self, valid: usize, mask: u32, keep: &mut Vec<f64>);
    /// Writes back what [`save`](Self::save) took, in its order.
    fn restore(&mut self, valid: usize, mask: u32, keep: &mut std::slice::Iter<'_, f64>);
}

/// Whether lane `l` is clear in `mask` (an output to keep).
#[inline]
fn kept(mask: u32, l: usize) -> bool {
    mask & (1 << l) == 0
}

impl<const N: usize> LaneOutputs for [&mut [f64]; N] {
    fn entries(&self) -> Option<usize> {
        let n = self.first().map(|s| s.len())?;
        self.iter().all(|s| s.len() == n).then_some(n)
    }

    #[inline]
    fn split_at(self, mid: usize) -> (Self, Self) {
        let mut left: [&mut [f64]; N] = std::array::from_fn(|_| Default::default());
        let mut right: [&mut [f64]; N] = std::array::from_fn(|_| Default::default());
        for (k, s) in self.into_iter().enumerate() {
            (left[k], right[k]) = s.split_at_mut(mid);
        }
        (left, right)
    }

    fn save(&self, valid: usize, mask: u32, keep: &mut Vec<f64>) {
        for s in self {
            keep.extend((0..valid).filter(|&l| kept(mask, l)).map(|l| s[l]));
        }
    }

    fn restore(&mut self, valid: usize, mask: u32, keep: &mut std::slice::Iter<'_, f64>) {
        for s in self.iter_mut() {
            for l in (0..valid).filter(|&l| kept(mask, l)) {
                s[l] = *keep.next().expect("as many values as were saved");
            }
        }
    }
}

impl<A: LaneOutputs> LaneOutputs for Option<A> {
    fn entries(&self) -> Option<usize> {
        self.as_ref().and_then(A::entries)
    }

    #[inline]
    fn split_at(self, mid: usize) -> (Self, Self) {
        match self {
            Some(a) => {
                let (l, r) = a.split_at(mid);
                (Some(l), Some(r))
            }
            None => (None, None),
        }
    }

    fn save(&self, valid: usize, mask: u32, keep: &mut Vec<f64>) {
        if let Some(a) = self {
            a.save(valid, mask, keep);
        }
    }

    fn restore(&mut self, valid: usize, mask: u32, keep: &mut std::slice::Iter<'_, f64>) {
        if let Some(a) = self {
            a.restore(valid, mask, keep);
        }
    }
}

impl<A: LaneOutputs, B: LaneOutputs> LaneOutputs for (A, B) {
    fn entries(&self) -> Option<usize> {
        match (self.0.entries(), self.1.entries()) {
            (Some(a), Some(b)) if a != b => None,
            (a, b) => a.or(b),
        }
    }

    #[inline]
    fn split_at(self, mid: usize) -> (Self, Self) {
        let (a0, a1) = self.0.split_at(mid);
        let (b0, b1) = self.1.split_at(mid);
        ((a0, b0), (a1, b1))
    }

    fn save(&self, valid: usize, mask: u32, keep: &mut Vec<f64>) {
        self.0.save(valid, mask, keep);
        self.1.save(valid, mask, keep);
    }

    fn restore(&mut self, valid: usize, mask: u32, keep: &mut std::slice::Iter<'_, f64>) {
        self.0.restore(valid, mask, keep);
        self.1.restore(valid, mask, keep);
    }
}

/// The targets of a neighbour list with the geometry the pair stages
/// share: positions of every particle the lists reach, the box (periodic
/// folds) and the farthest a listed pair can be apart.
#[derive(Debug, Clone, Copy)]
pub struct PairLoop<'a> {
    sep: Separation,
    reach: f64,
    x: &'a [f64],
    y: &'a [f64],
    z: &'a [f64],
    nl: &'a CompactNeighborList,
}

impl<'a> PairLoop<'a> {
    /// The driver over the targets of `nl`, for a kernel of `support`
    /// (in units of h) and the positions and smoothing lengths of every
    /// particle the lists reach.
    ///
    /// # Errors
    /// [`CoreError::Invalid`] when the arrays differ in length or do not
    /// cover the targets.
    pub fn new(
        bbox: &BoundingBox,
        support: f64,
        [x, y, z]: [&'a [f64]; 3],
        h: &[f64],
        nl: &'a CompactNeighborList,
    ) -> Result<Self, CoreError> {
        let n = x.len();
        if y.len() != n || z.len() != n || h.len() != n {
            return Err(CoreError::Invalid(format!(
                "pair loop: x, y, z, h have {}, {}, {}, {} entries; all must be equal",
                n,
                y.len(),
                z.len(),
                h.len()
            )));
        }
        if nl.targets().end > n {
            return Err(CoreError::Invalid(format!(
                "pair loop: targets {:?} outside the {n} particles",
                nl.targets()
            )));
        }
        Ok(Self {
            sep: Separation::new(bbox),
            reach: max_reach(support, h),
            x,
            y,
            z,
            nl,
        })
    }

    /// The neighbour lists.
    pub fn list(&self) -> &'a CompactNeighborList {
        self.nl
    }

    /// Particles the lists may reach (targets and halos).
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Runs `stage` over every target; `out` holds one entry per target
    /// (slices over `nl.targets()`). Lists that serve some targets only
    /// ([`CompactNeighborList::active_targets`]) run as
    /// [`run_masked`](Self::run_masked) with their flags.
    ///
    /// # Panics
    /// If an output's length differs from the number of targets, or a
    /// neighbour index is beyond the particles (a list built for other
    /// arrays).
    pub fn run<S: PairStage>(&self, stage: &S, out: S::Out<'_>) -> S::Stats {
        self.run_where(stage, out, self.nl.active_targets())
    }

    /// As [`run`](Self::run) for the targets `t` with `active[t -
    /// targets.start]` (one flag per target): groups without an active
    /// target are skipped, and in the others the inactive targets'
    /// outputs are left as they were. The active targets' outputs are
    /// those of `run`, bit for bit. `Stats` cover every lane of the
    /// groups that ran.
    ///
    /// # Panics
    /// As [`run`](Self::run), and if `active` does not have one flag per
    /// target.
    pub fn run_masked<S: PairStage>(
        &self,
        stage: &S,
        out: S::Out<'_>,
        active: &[bool],
    ) -> S::Stats {
        assert_eq!(
            active.len(),
            self.nl.targets().len(),
            "pair loop: active flags vs targets"
        );
        self.run_where(stage, out, Some(active))
    }

    fn run_where<S: PairStage>(
        &self,
        stage: &S,
        out: S::Out<'_>,
        active: Option<&[bool]>,
    ) -> S::Stats {
        let targets = self.nl.targets();
        if let Some(len) = out.entries() {
            assert_eq!(len, targets.len(), "pair loop: outputs vs targets");
        }
        let chunk = Chunk {
            out,
            first: targets.start,
            len: targets.len(),
        };
        rayon::iter::split(chunk, Chunk::halve)
            .map_init(
                || (GroupUnion::default(), Vec::new()),
                |(union, keep), chunk| self.run_chunk(stage, union, keep, chunk, active),
            )
            .reduce(S::Stats::identity, S::Stats::merge)
    }

    /// The groups of one chunk, in order (`active`: one flag per target
    /// of the list, or all active).
    fn run_chunk<S: PairStage>(
        &self,
        stage: &S,
        union: &mut GroupUnion,
        keep: &mut Vec<f64>,
        mut chunk: Chunk<S::Out<'_>>,
        active: Option<&[bool]>,
    ) -> S::Stats {
        let (x, y, z) = (self.x, self.y, self.z);
        let n = x.len();
        let start = self.nl.targets().start;
        let mut stats = S::Stats::identity();
        while chunk.len > 0 {
            let valid = chunk.len.min(LANES);
            let (mut out, rest) = chunk.out.split_at(valid);
            let mask = match active {
                None => Group::all_lanes(valid),
                Some(a) => a[chunk.first - start..][..valid]
                    .iter()
                    .enumerate()
                    .fold(0, |m, (l, &on)| m | (u32::from(on) << l)),
            };
            let g = Group {
                first: chunk.first,
                valid,
                active: mask,
            };
            chunk = Chunk {
                out: rest,
                first: chunk.first + valid,
                len: chunk.len - valid,
            };
            if mask == 0 {
                continue;
            }
            let xi = [g.load(x), g.load(y), g.load(z)];
            let sep = self.sep.for_group(xi, self.reach);
            let mut sums = stage.start(&g);
            for run in union.build(self.nl, g.targets()) {
                assert!(run.end <= n, "neighbour {} of {n} particles", run.end - 1);
                for j in run.clone() {
                    let d = sep.between_lanes(xi, [x[j], y[j], z[j]]);
                    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    stage.pair(&mut sums, j, d, r2);
                }
            }
            if g.all_active() {
                stats = stats.merge(stage.finish(&g, sums, &mut out));
            } else {
                keep.clear();
                out.save(valid, mask, keep);
                stats = stats.merge(stage.finish(&g, sums, &mut out));
                out.restore(valid, mask, &mut keep.iter());
            }
        }
        stats
    }
}

/// Consecutive targets and their outputs, split in halves (at a multiple
/// of [`LANES`] from the first target, so groups stay aligned with the
/// grouped neighbour lists) as rayon's scheduler asks.
struct Chunk<O> {
    out: O,
    first: usize,
    len: usize,
}

impl<O: LaneOutputs> Chunk<O> {
    fn halve(self) -> (Self, Option<Self>) {
        let groups = self.len.div_ceil(LANES);
        if groups < 2 {
            return (self, None);
        }
        let mid = groups / 2 * LANES;
        let (a, b) = self.out.split_at(mid);
        (
            Chunk {
                out: a,
                first: self.first,
                len: mid,
            },
            Some(Chunk {
                out: b,
                first: self.first + mid,
                len: self.len - mid,
            }),
        )
    }
}

/// `support * max h`: the farthest any listed pair can be apart.
pub fn max_reach(support: f64, h: &[f64]) -> f64 {
    support * h.par_iter().copied().reduce(|| 0.0, f64::max)
}

/// Which lanes' targets have a partner at squared distance `r2` as
/// neighbour: the lists' criterion `r2 < reach_i` or `r2 < reach_j`
/// (squared support radii), and `r2 > 0`, which leaves out the target
/// itself (a pair at zero distance exerts no force either). Returns `r2`
/// with 1 in the other lanes (so every lane stays finite) and a weight of
/// 1 for neighbours, 0 for the rest.
#[inline(always)]
pub fn neighbour_lanes(r2: F64s, reach_i: F64s, reach_j: f64) -> (F64s, F64s) {
    let zero = F64s::splat(0.0);
    let one = F64s::splat(1.0);
    let near = r2.lt(reach_i) | r2.lt(F64s::splat(reach_j));
    let pair = near & r2.gt(zero);
    (pair.select(r2, one), pair.select(one, zero))
}

/// The union of the neighbour lists of a group of targets as ascending,
/// disjoint index ranges; the buffers are reused from group to group.
#[derive(Debug, Clone, Default)]
pub struct GroupUnion {
    union: Vec<Range<usize>>,
    next: Vec<Range<usize>>,
    runs: Vec<Range<usize>>,
}

impl GroupUnion {
    /// The union of the lists of `group` (targets of `nl`, starting at a
    /// multiple of [`LANES`] from the first target). Grouped lists
    /// ([`NeighborSearch::grouped`](sph_tree::NeighborSearch::grouped))
    /// hold it already; per-target lists are merged, each already a sorted
    /// run list, by a chain of linear merges.
    pub fn build(&mut self, nl: &CompactNeighborList, group: Range<usize>) -> &[Range<usize>] {
        self.union.clear();
        if nl.width() == LANES {
            self.union.extend(nl.runs(group.start));
            return &self.union;
        }
        for i in group {
            self.runs.clear();
            self.runs.extend(nl.runs(i));
            merge_runs(&self.union, &self.runs, &mut self.next);
            std::mem::swap(&mut self.union, &mut self.next);
        }
        &self.union
    }
}

/// `out` = the union of the ascending disjoint range lists `a` and `b`,
/// ascending, with overlapping or touching ranges joined.
fn merge_runs(a: &[Range<usize>], b: &[Range<usize>], out: &mut Vec<Range<usize>>) {
    out.clear();
    let (mut i, mut k) = (0, 0);
    while i < a.len() || k < b.len() {
        let r = if k == b.len() || (i < a.len() && a[i].start <= b[k].start) {
            i += 1;
            a[i - 1].clone()
        } else {
            k += 1;
            b[k - 1].clone()
        };
        match out.last_mut() {
            Some(last) if r.start <= last.end => last.end = last.end.max(r.end),
            _ => out.push(r),
        }
    }
}

/// `C v` for a symmetric 3x3 matrix `C = (xx, xy, xz, yy, yz, zz)` (the
/// inverse IAD matrix), one per lane.
#[inline(always)]
pub fn sym_mat_vec(c: &[F64s; 6], v: [F64s; 3]) -> [F64s; 3] {
    [
        c[0] * v[0] + c[1] * v[1] + c[2] * v[2],
        c[1] * v[0] + c[3] * v[1] + c[4] * v[2],
        c[2] * v[0] + c[4] * v[1] + c[5] * v[2],
    ]
}

/// How gradients are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Gradients {
    /// Integral approach to derivatives (exact for linear fields).
    #[default]
    Iad,
    /// Plain kernel gradients `grad W`.
    Kernel,
}

/// `--gradients` and the `gradients` key.
impl crate::Choice for Gradients {
    const ALL: &'static [Self] = &[Gradients::Iad, Gradients::Kernel];

    fn name(&self) -> &'static str {
        match self {
            Gradients::Iad => "iad",
            Gradients::Kernel => "kernel",
        }
    }

    fn help(&self) -> &'static str {
        match self {
            Gradients::Iad => "Integral approach to derivatives (exact for linear fields)",
            Gradients::Kernel => "Plain kernel gradients",
        }
    }
}

/// A computation with the gradient operator as a compile-time choice
/// (`IAD` true: the IAD matrices; false: plain kernel gradients), run by
/// [`with_gradients`]: the one place where the run-time choice becomes a
/// monomorphised pair loop.
pub trait WithGradients {
    /// What the computation returns.
    type Output;
    /// The computation for one operator.
    fn run<const IAD: bool>(self) -> Self::Output;
}

/// Runs `f` with the operator `g` as a compile-time parameter.
pub fn with_gradients<F: WithGradients>(g: Gradients, f: F) -> F::Output {
    match g {
        Gradients::Iad => f.run::<true>(),
        Gradients::Kernel => f.run::<false>(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merged_runs_are_the_set_union() {
        let a = vec![0..3, 5..6, 10..20];
        let b = vec![1..2, 3..5, 6..7, 8..9, 19..25];
        let mut out = Vec::new();
        merge_runs(&a, &b, &mut out);
        assert_eq!(out, vec![0..7, 8..9, 10..25]);
        merge_runs(&[], &b, &mut out);
        assert_eq!(out, vec![1..2, 3..5, 6..7, 8..9, 19..25]);
    }

    #[test]
    fn neighbour_mask() {
        let v = F64s::from_array(std::array::from_fn(|l| l as f64 + 1.0));
        let (r2, w) = neighbour_lanes(v - 1.0, F64s::splat(3.5), 0.0);
        // Lanes 1, 2, 3 (r2 = 1, 2, 3): lane 0 has r2 = 0 (itself).
        assert_eq!(w.sum(), 3.0);
        assert_eq!(r2.sum(), 1.0 + 1.0 + 2.0 + 3.0 + (LANES - 4) as f64);
    }

    #[test]
    fn outputs_split_into_aligned_chunks() {
        let (mut a, mut b) = (vec![0.0; 20], vec![0.0; 20]);
        let out: ([&mut [f64]; 2], Option<[&mut [f64]; 1]>) = ([&mut a, &mut b], None);
        assert_eq!(out.entries(), Some(20));
        let c = Chunk {
            out,
            first: 4,
            len: 20,
        };
        let (l, r) = c.halve();
        let r = r.unwrap();
        assert_eq!((l.first, l.len, r.first, r.len), (4, 8, 12, 12));
        assert_eq!((l.out.0[0].len(), r.out.0[1].len()), (8, 12));
    }
}
