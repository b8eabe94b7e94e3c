//! Neighbour sums over groups of targets, one target per vector lane.
//!
//! [`LANES`] consecutive targets (compact in space along the curve) share
//! the union of their neighbour lists ([`GroupUnion`]). Each neighbour `j`
//! of the union is broadcast to all lanes and interacts with every target
//! of the group at once; a lane whose target does not have `j` as
//! neighbour adds an exact zero. So lane `l` computes, operation for
//! operation, the sequential ascending-order sum a scalar loop over its own
//! list computes: results stay independent of the grouping, the number of
//! threads and the number of ranks, while the arithmetic runs as vector
//! instructions with no gathers of neighbour data (the scalar loops were
//! bound by per-pair latency and loads). The price is the pairs of the
//! union outside a target's support: about half the lane work for 100
//! neighbours and groups of 8.
//!
//! [`F64s`] is the lane type, on `wide::f64x8` (explicit SIMD, safe API;
//! AVX-512, AVX or SSE2 as the build's target features allow):
//! element-wise IEEE operations, no reassociation and no fused
//! multiply-add, so each lane is bit for bit what the scalar expression
//! gives.

pub use sph_kernels::LANES;
// Grouped neighbour lists are built for this lane width.
const _: () = assert!(LANES == sph_tree::GROUP_LANES);
use sph_tree::CompactNeighborList;
use std::ops::{Add, AddAssign, Div, Mul, Neg, Range, Sub, SubAssign};
use wide::f64x8;

/// One value per lane, as an array.
pub type Lane = [f64; LANES];

/// A lane of `f64` with element-wise arithmetic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct F64s(f64x8);

impl F64s {
    /// Every lane `v`.
    #[inline(always)]
    pub fn splat(v: f64) -> Self {
        Self(f64x8::splat(v))
    }

    /// From an array of lanes.
    #[inline(always)]
    pub fn from_array(a: Lane) -> Self {
        Self(f64x8::new(a))
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn to_array(self) -> Lane {
        self.0.to_array()
    }

    /// `values[first + l]` for the lanes of a group of `valid` targets
    /// starting at `first`; padding lanes repeat the last target.
    #[inline(always)]
    pub fn load(values: &[f64], first: usize, valid: usize) -> Self {
        let v = &values[first..first + valid];
        let mut r = [v[valid - 1]; LANES];
        r[..valid].copy_from_slice(v);
        Self::from_array(r)
    }

    /// Writes the first `out.len()` lanes.
    #[inline(always)]
    pub fn store(self, out: &mut [f64]) {
        out.copy_from_slice(&self.to_array()[..out.len()]);
    }

    /// The smallest lane.
    #[inline(always)]
    pub fn min_lane(self) -> f64 {
        self.to_array().into_iter().fold(f64::INFINITY, f64::min)
    }

    /// The largest lane.
    #[inline(always)]
    pub fn max_lane(self) -> f64 {
        self.to_array()
            .into_iter()
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Absolute value per lane.
    #[inline(always)]
    pub fn abs(self) -> Self {
        Self(self.0.abs())
    }

    /// Square root per lane.
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        Self(self.0.sqrt())
    }

    /// The smaller of `self` and `o` per lane (`o` where either is NaN).
    #[inline(always)]
    pub fn min(self, o: Self) -> Self {
        Self(self.0.simd_lt(o.0).select(self.0, o.0))
    }

    /// The larger of `self` and `o` per lane (`o` where either is NaN).
    #[inline(always)]
    pub fn max(self, o: Self) -> Self {
        Self(self.0.simd_gt(o.0).select(self.0, o.0))
    }

    /// `self - length` where `self > half`, `self + length` where
    /// `self < -half`, else `self` (the minimum image; `half` infinite on
    /// open axes).
    #[inline(always)]
    pub fn fold(self, half: f64, length: f64) -> Self {
        let l = f64x8::splat(length);
        let above = self.0.simd_gt(f64x8::splat(half));
        let below = self.0.simd_lt(f64x8::splat(-half));
        Self(above.select(self.0 - l, below.select(self.0 + l, self.0)))
    }

    /// `a` where `m > 0`, else `b`.
    #[inline(always)]
    pub fn select_positive(m: Self, a: Self, b: Self) -> Self {
        Self(m.0.simd_gt(f64x8::splat(0.0)).select(a.0, b.0))
    }

    /// `a` where `self < 0`, else 0.
    #[inline(always)]
    pub fn where_negative(self, a: Self) -> Self {
        let zero = f64x8::splat(0.0);
        Self(self.0.simd_lt(zero).select(a.0, zero))
    }

    /// The lanes' sum in a fixed pairwise order.
    #[inline(always)]
    pub fn sum(self) -> f64 {
        let mut s = self.to_array();
        let mut w = LANES;
        while w > 1 {
            w /= 2;
            for l in 0..w {
                s[l] += s[l + w];
            }
        }
        s[0]
    }
}

macro_rules! lane_op {
    ($tr:ident, $f:ident, $tra:ident, $fa:ident, $op:tt) => {
        impl $tr for F64s {
            type Output = F64s;
            #[inline(always)]
            fn $f(self, o: F64s) -> F64s {
                F64s(self.0 $op o.0)
            }
        }
        impl $tr<f64> for F64s {
            type Output = F64s;
            #[inline(always)]
            fn $f(self, o: f64) -> F64s {
                F64s(self.0 $op f64x8::splat(o))
            }
        }
        impl $tr<F64s> for f64 {
            type Output = F64s;
            #[inline(always)]
            fn $f(self, o: F64s) -> F64s {
                F64s(f64x8::splat(self) $op o.0)
            }
        }
        impl $tra for F64s {
            #[inline(always)]
            fn $fa(&mut self, o: F64s) {
                *self = *self $op o;
            }
        }
    };
}
lane_op!(Add, add, AddAssign, add_assign, +);
lane_op!(Sub, sub, SubAssign, sub_assign, -);
lane_op!(Mul, mul, MulAssign, mul_assign, *);
lane_op!(Div, div, DivAssign, div_assign, /);
use std::ops::{DivAssign, MulAssign};

impl Neg for F64s {
    type Output = F64s;
    #[inline(always)]
    fn neg(self) -> F64s {
        F64s(-self.0)
    }
}

/// Which lanes' targets have a partner at squared distance `r2` as
/// neighbour: the lists' criterion `r2 < reach_i` or `r2 < reach_j`
/// (squared support radii), and `r2 > 0`, which leaves out the target
/// itself (a pair at zero distance exerts no force either). Returns `r2`
/// with 1 in the other lanes (so every lane stays finite) and a weight of
/// 1 for neighbours, 0 for the rest.
#[inline(always)]
pub fn neighbour_lanes(r2: F64s, reach_i: F64s, reach_j: f64) -> (F64s, F64s) {
    let zero = f64x8::splat(0.0);
    let one = f64x8::splat(1.0);
    let near = r2.0.simd_lt(reach_i.0) | r2.0.simd_lt(f64x8::splat(reach_j));
    let pair = near & r2.0.simd_gt(zero);
    (F64s(pair.select(r2.0, one)), F64s(pair.select(one, zero)))
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
    fn lane_arithmetic_sum_and_neighbour_mask() {
        let a: Lane = std::array::from_fn(|l| l as f64 + 1.0);
        let v = F64s::from_array(a);
        assert_eq!(v.sum(), (LANES * (LANES + 1) / 2) as f64);
        assert_eq!((v * 2.0 - v).to_array(), a);
        assert_eq!(v.max(F64s::splat(3.0)).to_array()[0], 3.0);
        assert_eq!(v.min(F64s::splat(3.0)).to_array()[LANES - 1], 3.0);
        let (r2, w) = neighbour_lanes(v - 1.0, F64s::splat(3.5), 0.0);
        // Lanes 1, 2, 3 (r2 = 1, 2, 3): lane 0 has r2 = 0 (itself).
        assert_eq!(w.sum(), 3.0);
        assert_eq!(r2.sum(), 1.0 + 1.0 + 2.0 + 3.0 + (LANES - 4) as f64);
    }
}
