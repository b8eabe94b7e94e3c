//! Lookup tables with linear interpolation (SPH-EXA's way to avoid `sin`/`pow`).

use std::fmt;

use crate::kernel::Kernel;
use crate::{F64s, KernelError};
use wide::f64x8;

/// Any [`Kernel`] sampled on `points` equally spaced nodes over `[0, support]`
/// and evaluated by linear interpolation of both the shape and its derivative.
///
/// The hot path ([`Kernel::shape_and_derivative`]) is a multiply, a float to
/// integer conversion, two adjacent loads and two interpolations: no
/// `sin`/`pow` and only a select for the support cut-off. With the default
/// 20,000 points the error is below ~1e-8 of `max |w|` and ~3e-8 of
/// `max |w'|` for every built-in kernel (sinc with `n` in `[1, 12]` except the
/// derivative for `1 < n < 2`, which has an infinite slope at `v = 2`).
///
/// The normalisation and support are copied from the source kernel.
#[derive(Clone)]
pub struct Tabulated {
    /// `[w(v_k), w'(v_k)]` interleaved so one interpolation touches one or two
    /// cache lines. The last node holds the left limit at the support radius.
    table: Box<[[f64; 2]]>,
    /// `(points - 1) / support`.
    inv_spacing: f64,
    /// Index of the last interval's left node, `points - 2`.
    last_interval: i32,
    support: f64,
    norm: f64,
}

impl Tabulated {
    /// SPH-EXA's table size.
    pub const DEFAULT_POINTS: usize = 20_000;
    /// Fewest points accepted (one interval).
    pub const MIN_POINTS: usize = 2;
    /// Most points accepted: node indices are `i32`, whose conversions from
    /// `f64` are single (vectorisable) instructions.
    pub const MAX_POINTS: usize = i32::MAX as usize;

    /// Tabulates `kernel` on `points` nodes over `[0, kernel.support()]`.
    ///
    /// # Errors
    /// [`KernelError::TooFewPoints`] if `points < MIN_POINTS`,
    /// [`KernelError::InvalidSupport`] if the support is not finite and positive,
    /// [`KernelError::NonFinite`] if the kernel returns NaN or infinity at a node.
    pub fn new<K: Kernel + ?Sized>(kernel: &K, points: usize) -> Result<Self, KernelError> {
        if points < Self::MIN_POINTS {
            return Err(KernelError::TooFewPoints {
                points,
                min: Self::MIN_POINTS,
            });
        }
        if points > Self::MAX_POINTS {
            return Err(KernelError::TooManyPoints {
                points,
                max: Self::MAX_POINTS,
            });
        }
        let support = kernel.support();
        if !(support.is_finite() && support > 0.0) {
            return Err(KernelError::InvalidSupport { support });
        }
        let spacing = support / (points - 1) as f64;
        let table = (0..points)
            .map(|k| {
                // At the support radius itself a kernel returns 0 by contract;
                // sample just inside so the last interval interpolates towards
                // the left limit (matters for S_1' or a truncated Gaussian).
                let v = if k + 1 == points {
                    support * (1.0 - f64::EPSILON)
                } else {
                    k as f64 * spacing
                };
                let (w, dw) = kernel.shape_and_derivative(v);
                if w.is_finite() && dw.is_finite() {
                    Ok([w, dw])
                } else {
                    Err(KernelError::NonFinite { v, w, dw })
                }
            })
            .collect::<Result<Box<[_]>, _>>()?;
        Ok(Self {
            table,
            inv_spacing: 1.0 / spacing,
            last_interval: (points - 2) as i32,
            support,
            norm: kernel.norm(),
        })
    }

    /// Number of nodes.
    pub fn points(&self) -> usize {
        self.table.len()
    }

    /// Node spacing in `v`.
    pub fn spacing(&self) -> f64 {
        self.support / f64::from(self.last_interval + 1)
    }
}

impl fmt::Debug for Tabulated {
    // The tables themselves are far too long to print.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Tabulated")
            .field("points", &self.points())
            .field("support", &self.support)
            .field("norm", &self.norm)
            .finish_non_exhaustive()
    }
}

impl Tabulated {
    /// The interval holding `v` and the position within it. The clamp to
    /// `[0, last_interval]` (NaN gives 0) keeps `i + 1` in bounds, so
    /// out-of-range input never panics.
    #[inline(always)]
    fn locate(&self, v: f64) -> (usize, f64) {
        let t = v * self.inv_spacing;
        let last = f64::from(self.last_interval);
        let c = if t > 0.0 { t } else { 0.0 };
        let c = if c < last { c } else { last };
        let i = c as i32;
        (i as usize, t - f64::from(i))
    }

    /// [`locate`](Self::locate) for a lane: interval indices (as integral
    /// `f64` in `[0, last_interval]`), positions within the intervals, and
    /// the mask of arguments inside the support.
    #[inline(always)]
    fn locate_lanes(&self, v: F64s) -> (f64x8, f64x8, f64x8) {
        let zero = f64x8::splat(0.0);
        let v = v.0;
        let t = v * f64x8::splat(self.inv_spacing);
        let last = f64x8::splat(f64::from(self.last_interval));
        let c = t.simd_gt(zero).select(t, zero);
        let c = c.simd_lt(last).select(c, last);
        let i = c.trunc();
        (i, t - i, v.simd_lt(f64x8::splat(self.support)))
    }

    /// Column `col` (0: w, 1: w') of the table at nodes `node` and
    /// `node + 1` per lane; `node` as from [`locate_lanes`](Self::locate_lanes).
    #[inline(always)]
    fn nodes(&self, node: f64x8, col: usize) -> (f64x8, f64x8) {
        #[cfg(all(target_arch = "x86_64", target_feature = "avx512f"))]
        {
            use std::arch::x86_64::{
                __m512d, _mm256_add_epi32, _mm512_cvttpd_epi32, _mm512_i32gather_pd,
            };
            let base = self.table.as_ptr().cast::<f64>();
            // SAFETY: AVX-512F is enabled at compile time (cfg above). Each
            // lane of `node` is an integer k in [0, last_interval], so the
            // flat offsets 2k + col and 2k + 2 + col (col <= 1) are at most
            // 2 last_interval + 3 = 2 points - 1: inside the table. Two
            // gathers replace sixteen scalar loads; criterion stages_1e5,
            // 1 thread, scalar loads -> gathers: IAD 95 -> 71 ms, momentum
            // 191 -> 162 ms, density 102 -> 99 ms.
            #[allow(unsafe_code)]
            unsafe {
                let k = _mm512_cvttpd_epi32(__m512d::from(node));
                let k2 = _mm256_add_epi32(k, k);
                let a = _mm512_i32gather_pd::<8>(k2, base.add(col));
                let b = _mm512_i32gather_pd::<8>(k2, base.add(col + 2));
                (f64x8::from(a), f64x8::from(b))
            }
        }
        #[cfg(not(all(target_arch = "x86_64", target_feature = "avx512f")))]
        {
            let mut a = [0.0; crate::LANES];
            let mut b = [0.0; crate::LANES];
            for (l, &k) in node.as_array().iter().enumerate() {
                let k = k as usize;
                (a[l], b[l]) = (self.table[k][col], self.table[k + 1][col]);
            }
            (f64x8::new(a), f64x8::new(b))
        }
    }
}

impl Kernel for Tabulated {
    #[inline]
    fn shape(&self, v: f64) -> f64 {
        self.shape_and_derivative(v).0
    }

    #[inline]
    fn shape_derivative(&self, v: f64) -> f64 {
        self.shape_and_derivative(v).1
    }

    #[inline]
    fn shape_and_derivative(&self, v: f64) -> (f64, f64) {
        let (i, f) = self.locate(v);
        let [w0, d0] = self.table[i];
        let [w1, d1] = self.table[i + 1];
        // Not `mul_add`: without an FMA target feature that is a libm call.
        let w = w0 + f * (w1 - w0);
        let dw = d0 + f * (d1 - d0);
        // Compiles to selects; `v < support` is false for NaN too.
        if v < self.support {
            (w, dw)
        } else {
            (0.0, 0.0)
        }
    }

    // The lane forms do the index arithmetic and the interpolation as
    // vector instructions (the loads too, as gathers, on AVX-512); each
    // lane is the scalar result bit for bit.
    #[inline(always)]
    fn shape_lanes(&self, v: F64s) -> F64s {
        let (node, frac, inside) = self.locate_lanes(v);
        let (w0, w1) = self.nodes(node, 0);
        F64s(inside.select(w0 + frac * (w1 - w0), f64x8::splat(0.0)))
    }

    #[inline(always)]
    fn shape_and_derivative_lanes(&self, v: F64s) -> (F64s, F64s) {
        let (node, frac, inside) = self.locate_lanes(v);
        let zero = f64x8::splat(0.0);
        let (w0, w1) = self.nodes(node, 0);
        let (d0, d1) = self.nodes(node, 1);
        (
            F64s(inside.select(w0 + frac * (w1 - w0), zero)),
            F64s(inside.select(d0 + frac * (d1 - d0), zero)),
        )
    }

    #[inline]
    fn support(&self) -> f64 {
        self.support
    }

    #[inline]
    fn norm(&self) -> f64 {
        self.norm
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CubicSpline, Sinc};

    #[test]
    fn nodes_are_reproduced_exactly() {
        let k = Sinc::new(6.0).unwrap();
        let t = Tabulated::new(&k, 101).unwrap();
        assert_eq!(t.points(), 101);
        assert!((t.spacing() - 0.02).abs() < 1e-16);
        for i in 0..100 {
            let v = i as f64 * t.spacing();
            let (a, b) = (t.shape_and_derivative(v), k.shape_and_derivative(v));
            assert!(
                (a.0 - b.0).abs() < 1e-15 && (a.1 - b.1).abs() < 1e-14,
                "v = {v}"
            );
        }
        assert_eq!(t.shape(0.0), 1.0);
    }

    #[test]
    fn outside_support_and_nan_give_zero() {
        let t = Tabulated::new(&CubicSpline, 64).unwrap();
        for v in [2.0, 2.5, 1e300, f64::INFINITY, f64::NAN] {
            assert_eq!(t.shape_and_derivative(v), (0.0, 0.0), "v = {v}");
        }
        assert_eq!(t.norm(), CubicSpline.norm());
        assert_eq!(t.support(), 2.0);
    }

    #[test]
    fn errors() {
        let err = Tabulated::new(&CubicSpline, 1).unwrap_err();
        assert_eq!(err, KernelError::TooFewPoints { points: 1, min: 2 });
        assert!(err.to_string().contains("at least 2") && err.to_string().contains("got 1"));

        #[derive(Debug)]
        struct Bad(f64);
        impl Kernel for Bad {
            fn shape(&self, v: f64) -> f64 {
                1.0 / (v - 1.0)
            }
            fn shape_derivative(&self, _: f64) -> f64 {
                0.0
            }
            fn support(&self) -> f64 {
                self.0
            }
            fn norm(&self) -> f64 {
                1.0
            }
        }
        assert!(matches!(
            Tabulated::new(&Bad(-1.0), 10),
            Err(KernelError::InvalidSupport { .. })
        ));
        // Node v = 1 hits the pole.
        let err = Tabulated::new(&Bad(2.0), 3).unwrap_err();
        assert!(
            matches!(err, KernelError::NonFinite { v, .. } if v == 1.0),
            "{err}"
        );
    }

    #[test]
    fn debug_is_short() {
        let t = Tabulated::new(&CubicSpline, Tabulated::DEFAULT_POINTS).unwrap();
        let s = format!("{t:?}");
        assert!(s.len() < 100 && s.contains("20000"), "{s}");
    }
}
