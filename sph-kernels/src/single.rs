//! The power form of a kernel ([`PowerPolynomial`]) evaluated in `f32`:
//! half the vector registers per lane group, for pair loops whose sums
//! stay in `f64`.
//!
//! The kernel's values enter every pair term as a factor, so a relative
//! error of ~1e-7 in them moves a particle's sums by as much, far below
//! the scheme's own error, while their evaluation (the base polynomial and
//! its power) runs on one 256-bit register per 8 lanes instead of two. The
//! distance `v^2` arrives in `f64`, is rounded to `f32` once, and the
//! support test stays in `f64`, so a pair is inside the support exactly
//! where the neighbour search put it.

use crate::kernel::Kernel;
use crate::lanes::F32s;
use crate::poly::{poly, PolyValue, MAX_TERMS};
use crate::power::power_below;
use crate::{F64s, PowerPolynomial};
use std::ops::Mul;

/// `w = P(v^2)^n` as [`PowerPolynomial`], with `P` and its derivative
/// evaluated in `f32` from the same fit's coefficients (rounded once).
/// Scalar and lane forms do the same `f32` operations, so lane `l` is the
/// scalar result bit for bit. Its error against the exact kernel is within
/// [`SinglePower::TOLERANCE`] of the scales (`max |w|`, `max |w'|`).
///
/// ```
/// use sph_kernels::{FastKernel, Kernel, Sinc, SinglePower};
/// let exact = Sinc::new(6.0)?;
/// let FastKernel::Power(p) = FastKernel::new(&exact)? else { panic!() };
/// let single = SinglePower::new(&p);
/// assert!((single.shape(0.7) - exact.shape(0.7)).abs() < SinglePower::TOLERANCE);
/// assert_eq!(single.shape(2.0), 0.0);
/// # Ok::<(), sph_kernels::KernelError>(())
/// ```
#[derive(Debug, Clone)]
pub struct SinglePower {
    /// Coefficients of `P(t)`, lowest first; `terms` are used.
    w: [f32; MAX_TERMS],
    /// Coefficients of `dP/dt` times `2 scale` (so `w'(v) = v P'`).
    dw: [f32; MAX_TERMS],
    terms: usize,
    /// `t = scale v^2 - 1`.
    scale: f32,
    n: u32,
    support: f64,
    norm: f64,
}

impl SinglePower {
    /// Largest error of the shape (relative to `max |w|`) and of its
    /// derivative (relative to `max |w'|`) against the exact kernel: the
    /// `f64` fit's 1e-9 plus the `f32` rounding of a handful of operations.
    pub const TOLERANCE: f64 = 1e-6;

    /// The `f32` copy of `p` (whose base is always a fit in `v^2`).
    pub fn new(p: &PowerPolynomial) -> Self {
        let (w, dw, terms, scale) = p.base().coefficients();
        Self {
            w: std::array::from_fn(|k| w[k] as f32),
            dw: std::array::from_fn(|k| dw[k] as f32),
            terms,
            scale: scale as f32,
            n: p.power(),
            support: p.support(),
            norm: p.norm(),
        }
    }

    /// The exponent `n`.
    pub fn power(&self) -> u32 {
        self.n
    }

    /// Degree of the base polynomial.
    pub fn degree(&self) -> usize {
        self.terms - 1
    }

    /// `(w, w'/v)` at `v^2` (in `f32`, inside or not).
    #[inline(always)]
    fn raw<V>(&self, v2: V) -> (V, V)
    where
        V: PolyValue<Coef = f32> + Mul<Output = V> + Mul<f32, Output = V>,
    {
        let t = v2.mul_add(V::splat(self.scale), V::splat(-1.0));
        let b = poly(&self.w, self.terms, t);
        let db = poly(&self.dw, self.terms - 1, t);
        let below = power_below(b, self.n);
        (below * b, below * db * (self.n as f32))
    }

    #[inline(always)]
    fn inside(&self, v2: f64) -> bool {
        // False for NaN too.
        v2 < self.support * self.support
    }

    /// `value` (widened) where `v^2` is inside the support, else 0.
    #[inline(always)]
    fn inside_lanes(&self, v2: F64s, value: F32s) -> F64s {
        self.inside_wide(v2, F64s::from_f32s(value))
    }

    #[inline(always)]
    fn inside_wide(&self, v2: F64s, value: F64s) -> F64s {
        v2.lt(F64s::splat(self.support * self.support))
            .select(value, F64s::splat(0.0))
    }
}

impl Kernel for SinglePower {
    #[inline]
    fn shape(&self, v: f64) -> f64 {
        self.shape_sq(v * v)
    }

    #[inline]
    fn shape_derivative(&self, v: f64) -> f64 {
        self.shape_and_derivative(v).1
    }

    #[inline]
    fn shape_and_derivative(&self, v: f64) -> (f64, f64) {
        let v2 = v * v;
        if !self.inside(v2) {
            return (0.0, 0.0);
        }
        let (w, dw_v) = self.raw(v2 as f32);
        (f64::from(w), f64::from(dw_v) * v)
    }

    #[inline(always)]
    fn shape_lanes(&self, v: F64s) -> F64s {
        self.shape_sq_lanes(v * v)
    }

    #[inline(always)]
    fn shape_and_derivative_lanes(&self, v: F64s) -> (F64s, F64s) {
        let v2 = v * v;
        let (w, dw_v) = self.raw(v2.to_f32s());
        let dw = F64s::from_f32s(dw_v) * v;
        (self.inside_lanes(v2, w), self.inside_wide(v2, dw))
    }

    #[inline]
    fn derivative_over_v_sq(&self, v2: f64) -> f64 {
        if self.inside(v2) {
            f64::from(self.raw(v2 as f32).1)
        } else {
            0.0
        }
    }

    #[inline(always)]
    fn derivative_over_v_sq_lanes(&self, v2: F64s) -> F64s {
        self.inside_lanes(v2, self.raw(v2.to_f32s()).1)
    }

    #[inline]
    fn shape_sq(&self, v2: f64) -> f64 {
        if self.inside(v2) {
            // The derivative's polynomial is dead code here, compiled away.
            f64::from(self.raw(v2 as f32).0)
        } else {
            0.0
        }
    }

    #[inline]
    fn shape_and_v_derivative_sq(&self, v2: f64) -> (f64, f64) {
        if !self.inside(v2) {
            return (0.0, 0.0);
        }
        let (w, dw_v) = self.raw(v2 as f32);
        // v w' = v^2 (w'/v), the product in f64 as the root form's v (w'/v).
        (f64::from(w), f64::from(dw_v) * v2)
    }

    #[inline(always)]
    fn shape_sq_lanes(&self, v2: F64s) -> F64s {
        self.inside_lanes(v2, self.raw(v2.to_f32s()).0)
    }

    #[inline(always)]
    fn shape_and_v_derivative_sq_lanes(&self, v2: F64s) -> (F64s, F64s) {
        let (w, dw_v) = self.raw(v2.to_f32s());
        let vdw = F64s::from_f32s(dw_v) * v2;
        (self.inside_lanes(v2, w), self.inside_wide(v2, vdw))
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
    use crate::{FastKernel, Sinc, LANES};
    use proptest::prelude::*;

    fn single(n: f64) -> (Sinc, SinglePower) {
        let exact = Sinc::new(n).unwrap();
        let FastKernel::Power(p) = FastKernel::new(&exact).unwrap() else {
            panic!("sinc:{n} has a power form")
        };
        (exact, SinglePower::new(&p))
    }

    #[test]
    fn within_tolerance_of_the_exact_kernel() {
        for n in [3.0, 4.0, 5.0, 6.0, 8.0] {
            let (exact, s) = single(n);
            let (mut w_max, mut dw_max) = (0.0f64, 0.0f64);
            for i in 0..=2000 {
                let v = 2.0 * f64::from(i) / 2000.0;
                let (w, dw) = exact.shape_and_derivative(v);
                w_max = w_max.max(w.abs());
                dw_max = dw_max.max(dw.abs());
            }
            let (mut ew, mut edw) = (0.0f64, 0.0f64);
            for i in 0..=2000 {
                let v = 2.0 * f64::from(i) / 2000.0;
                let (w, dw) = exact.shape_and_derivative(v);
                let (sw, sdw) = s.shape_and_derivative(v);
                ew = ew.max((sw - w).abs() / w_max);
                edw = edw.max((sdw - dw).abs() / dw_max);
            }
            assert!(ew < SinglePower::TOLERANCE, "sinc:{n} shape {ew:e}");
            assert!(edw < SinglePower::TOLERANCE, "sinc:{n} derivative {edw:e}");
            // Not the f64 form in disguise: f32 rounding shows.
            assert!(ew > 1e-10, "sinc:{n} shape error {ew:e} is f64-like");
        }
    }

    #[test]
    fn zero_outside_and_finite_at_the_centre() {
        let (_, s) = single(6.0);
        assert_eq!(s.shape(2.0), 0.0);
        assert_eq!(s.shape_sq(4.0), 0.0);
        assert_eq!(s.shape_sq(f64::NAN), 0.0);
        assert_eq!(s.derivative_over_v_sq(5.0), 0.0);
        assert!((s.shape(0.0) - 1.0).abs() < 1e-6);
        assert_eq!(s.shape_derivative(0.0), 0.0);
    }

    proptest! {
        /// Lane `l` is the scalar form's result bit for bit, in every form.
        #[test]
        fn lanes_are_the_scalar_bits(v in proptest::array::uniform8(0.0f64..2.2)) {
            let (_, s) = single(6.0);
            let lanes = F64s::from_array(v);
            let v2 = lanes * lanes;
            let w = s.shape_lanes(lanes).to_array();
            let (w2, dw) = s.shape_and_derivative_lanes(lanes);
            let sq = s.shape_sq_lanes(v2).to_array();
            let (sw, svdw) = s.shape_and_v_derivative_sq_lanes(v2);
            let dov = s.derivative_over_v_sq_lanes(v2).to_array();
            for l in 0..LANES {
                let x = v[l];
                prop_assert_eq!(w[l].to_bits(), s.shape(x).to_bits());
                let (a, b) = s.shape_and_derivative(x);
                prop_assert_eq!(w2.to_array()[l].to_bits(), a.to_bits());
                prop_assert_eq!(dw.to_array()[l].to_bits(), b.to_bits());
                let x2 = x * x;
                prop_assert_eq!(sq[l].to_bits(), s.shape_sq(x2).to_bits());
                let (c, d) = s.shape_and_v_derivative_sq(x2);
                prop_assert_eq!(sw.to_array()[l].to_bits(), c.to_bits());
                prop_assert_eq!(svdw.to_array()[l].to_bits(), d.to_bits());
                prop_assert_eq!(dov[l].to_bits(), s.derivative_over_v_sq(x2).to_bits());
                // The shape alone is the shape of the pair form.
                prop_assert_eq!(sq[l].to_bits(), c.to_bits());
            }
        }
    }
}
