//! The lane type of the SIMD pair loops: [`F64s`], [`LANES`] `f64` values
//! with element-wise IEEE arithmetic (on `wide::f64x8`: AVX-512, AVX or
//! SSE2 as the build's target features allow). No reassociation, and
//! multiply-adds are fused only where asked for ([`F64s::mul_add`], whose
//! scalar twin is [`mul_add`]), so each lane is bit for bit what the
//! scalar expression gives; kernels take and return lanes
//! ([`Kernel::shape_lanes`](crate::Kernel::shape_lanes)) so pair loops
//! never round-trip through arrays.
//!
//! ```
//! use sph_kernels::{F64s, LANES};
//! let v = F64s::from_array(std::array::from_fn(|l| l as f64));
//! let w = (v * 2.0 + 1.0).sqrt();
//! assert_eq!(w.to_array()[4], 3.0);
//! assert_eq!(v.sum(), (LANES * (LANES - 1) / 2) as f64);
//! ```

use crate::LANES;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};
use wide::{f32x8, f64x8};

/// [`LANES`] `f32` values, the lanes of the single-precision kernel forms
/// ([`SinglePower`](crate::SinglePower)): one AVX register where `F64s`
/// takes two.
pub(crate) type F32s = f32x8;

/// `$a * $b + $c` through the type's inherent fused `mul_add` where the
/// build targets FMA, else a multiply and an add (never the slow software
/// fusion of `f64::mul_add` without the instruction): the one place that
/// choice is made, for `f64`, `f32` and their lanes.
macro_rules! fused_mul_add {
    ($a:expr, $b:expr, $c:expr) => {
        if cfg!(target_feature = "fma") {
            $a.mul_add($b, $c)
        } else {
            $a * $b + $c
        }
    };
}
pub(crate) use fused_mul_add;

/// `a b + c` as [`F64s::mul_add`] computes it in each lane: fused where
/// the build targets FMA, else a multiply and an add.
#[inline(always)]
pub fn mul_add(a: f64, b: f64, c: f64) -> f64 {
    fused_mul_add!(a, b, c)
}

/// One value per lane, as an array.
pub type Lane = [f64; LANES];

/// A lane of `f64` with element-wise arithmetic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct F64s(pub(crate) f64x8);

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

    /// Each lane rounded to the nearest `f32`.
    #[inline(always)]
    pub(crate) fn to_f32s(self) -> F32s {
        let a = self.to_array();
        F32s::new(std::array::from_fn(|l| a[l] as f32))
    }

    /// Each `f32` lane widened (exactly).
    #[inline(always)]
    pub(crate) fn from_f32s(v: F32s) -> Self {
        let a = v.to_array();
        Self::from_array(std::array::from_fn(|l| f64::from(a[l])))
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

    /// `self b + c` per lane: one rounding where the build targets FMA,
    /// else a multiply and an add, as the scalar [`mul_add`] does (so a
    /// scalar reference written with [`mul_add`] matches lane for lane).
    ///
    /// ```
    /// use sph_kernels::F64s;
    /// let (a, b, c) = (0.1, 0.7, -0.07);
    /// let lanes = F64s::splat(a).mul_add(F64s::splat(b), F64s::splat(c));
    /// assert_eq!(lanes.to_array()[0].to_bits(), sph_kernels::lanes::mul_add(a, b, c).to_bits());
    /// ```
    #[inline(always)]
    pub fn mul_add(self, b: Self, c: Self) -> Self {
        Self(fused_mul_add!(self.0, b.0, c.0))
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

    /// Lanes where `self < o` (false where either is NaN).
    #[inline(always)]
    pub fn lt(self, o: Self) -> Mask {
        Mask(self.0.simd_lt(o.0))
    }

    /// Lanes where `self > o` (false where either is NaN).
    #[inline(always)]
    pub fn gt(self, o: Self) -> Mask {
        Mask(self.0.simd_gt(o.0))
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

/// A lane mask: the result of a lane comparison ([`F64s::lt`],
/// [`F64s::gt`]), combined with `|` and `&`, used by [`Mask::select`].
#[derive(Debug, Clone, Copy)]
pub struct Mask(f64x8);

impl Mask {
    /// `a` in the lanes where the mask is set, else `b`.
    #[inline(always)]
    pub fn select(self, a: F64s, b: F64s) -> F64s {
        F64s(self.0.select(a.0, b.0))
    }

    /// Whether every lane is set.
    ///
    /// ```
    /// use sph_kernels::F64s;
    /// let v = F64s::splat(1.0);
    /// assert!(v.gt(F64s::splat(0.0)).all());
    /// assert!(!(v.lt(F64s::splat(0.0)) | v.gt(F64s::splat(2.0))).all());
    /// ```
    #[inline(always)]
    pub fn all(self) -> bool {
        self.0.all()
    }

    /// The set lanes as bits: bit `l` for lane `l`.
    ///
    /// ```
    /// use sph_kernels::F64s;
    /// let v = F64s::from_array(std::array::from_fn(|l| l as f64));
    /// assert_eq!(v.lt(F64s::splat(2.0)).bits(), 0b11);
    /// ```
    #[inline(always)]
    pub fn bits(self) -> u32 {
        self.0.to_bitmask()
    }
}

impl std::ops::BitOr for Mask {
    type Output = Mask;
    #[inline(always)]
    fn bitor(self, o: Mask) -> Mask {
        Mask(self.0 | o.0)
    }
}

impl std::ops::BitAnd for Mask {
    type Output = Mask;
    #[inline(always)]
    fn bitand(self, o: Mask) -> Mask {
        Mask(self.0 & o.0)
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

impl Neg for F64s {
    type Output = F64s;
    #[inline(always)]
    fn neg(self) -> F64s {
        F64s(-self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lane_arithmetic_and_sum() {
        let a: Lane = std::array::from_fn(|l| l as f64 + 1.0);
        let v = F64s::from_array(a);
        assert_eq!(v.sum(), (LANES * (LANES + 1) / 2) as f64);
        assert_eq!((v * 2.0 - v).to_array(), a);
        assert_eq!(v.max(F64s::splat(3.0)).to_array()[0], 3.0);
        assert_eq!(v.min(F64s::splat(3.0)).to_array()[LANES - 1], 3.0);
        assert_eq!(v.min_lane(), 1.0);
        assert_eq!(v.max_lane(), LANES as f64);
        assert_eq!(F64s::load(&a, 6, 2).to_array()[7], a[7]);
        assert_eq!(F64s::load(&a, 6, 1).to_array()[7], a[6]);
    }
}
