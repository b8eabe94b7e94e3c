//! Kernels that are an integer power of a smooth base, `w = b^n` (the sinc
//! family: `S_n = S_1^n`), evaluated as a polynomial fit of the base raised
//! to the power.
//!
//! The base is far smoother than its power: the lowest-degree fit of
//! `S_1(v) = sin(pi v / 2) / (pi v / 2)` in `v^2` whose sixth power is
//! within [`FastKernel::TOLERANCE`](crate::FastKernel::TOLERANCE) of `S_6`
//! has 8 terms, where a direct fit of `S_6` needs 17, so the pair loops
//! evaluate 8 + 7 terms and a few products instead of 17 + 16 terms.

use crate::kernel::Kernel;
use crate::poly::{Check, MAX_TERMS};
use crate::{F64s, FitVariable, KernelError, Polynomial};
use std::ops::Mul;

/// `w = P(v^2)^n`: a polynomial fit `P` of the base in `v^2`, raised to
/// the integer power `n` by repeated squaring. Scalar and lane forms do the
/// same operations, so lane `l` is the scalar result bit for bit.
///
/// ```
/// use sph_kernels::{FastKernel, Kernel, Sinc};
/// let exact = Sinc::new(6.0)?;
/// let FastKernel::Power(p) = FastKernel::new(&exact)? else { panic!() };
/// assert_eq!(p.power(), 6);
/// // Within the fit's tolerance of the kernel's scale (max |w| = 1).
/// assert!((p.shape(0.7) - exact.shape(0.7)).abs() < FastKernel::TOLERANCE);
/// # Ok::<(), sph_kernels::KernelError>(())
/// ```
#[derive(Debug, Clone)]
pub struct PowerPolynomial {
    base: Polynomial,
    n: u32,
    norm: f64,
}

impl PowerPolynomial {
    /// The power form of `kernel`, whose shape is `base^n`: the
    /// lowest-degree Chebyshev fit of the base in `v^2` whose power is
    /// within `tolerance` of `kernel` as [`Polynomial::fit`] checks its fits
    /// (shape and derivative, relative to their scales). The base's own
    /// error may be larger: the power's derivative `n b^(n-1) b'` damps the
    /// base's error where `b` is small, near the edge of the support.
    ///
    /// # Errors
    /// [`KernelError::InvalidSupport`] for a base whose support is not
    /// finite and positive, [`KernelError::NonFinite`] when `kernel` is not
    /// finite on its support, [`KernelError::NoPolynomialFit`] when `n < 2`
    /// or no degree up to 31 reaches the tolerance.
    pub fn fit<K: Kernel + ?Sized, B: Kernel + ?Sized>(
        kernel: &K,
        base: &B,
        n: u32,
        tolerance: f64,
    ) -> Result<Self, KernelError> {
        let support = base.support();
        if !(support.is_finite() && support > 0.0) {
            return Err(KernelError::InvalidSupport { support });
        }
        let check = Check::sample(kernel)?;
        let norm = kernel.norm();
        if n >= 2 {
            for terms in 2..=MAX_TERMS {
                let p = Self {
                    base: Polynomial::interpolate(base, FitVariable::Square, terms),
                    n,
                    norm,
                };
                if check.worst(&p) <= tolerance {
                    return Ok(p);
                }
            }
        }
        Err(KernelError::NoPolynomialFit {
            tolerance,
            max_degree: MAX_TERMS - 1,
        })
    }

    /// The exponent `n`.
    pub fn power(&self) -> u32 {
        self.n
    }

    /// The fit of the base.
    pub fn base(&self) -> &Polynomial {
        &self.base
    }

    /// `b^n`, as `b^(n-1) b` in every form (so the shape alone and the
    /// shape with its derivative are the same bits).
    #[inline(always)]
    fn pow_n<V: Copy + Mul<Output = V> + Mul<f64, Output = V>>(&self, b: V) -> V {
        self.raise(b).0
    }

    /// `(b^n, n b^(n-1))` from `b`.
    #[inline(always)]
    fn raise<V: Copy + Mul<Output = V> + Mul<f64, Output = V>>(&self, b: V) -> (V, V) {
        let below = power_below(b, self.n);
        (below * b, below * f64::from(self.n))
    }
}

/// `b^(n-1)` for `n >= 2`, the factor both `b^n` and `d(b^n)/db` share
/// (in every precision and form, so they stay the same bits).
#[inline(always)]
pub(crate) fn power_below<V: Copy + Mul<Output = V>>(b: V, n: u32) -> V {
    match n {
        // The default kernel's power, unrolled at compile time.
        6 => pow(b, 5),
        n => pow(b, n - 1),
    }
}

/// `b^e` for `e >= 1` by repeated squaring (the same products in scalar
/// and lane forms).
#[inline(always)]
fn pow<V: Copy + Mul<Output = V>>(b: V, e: u32) -> V {
    debug_assert!(e >= 1);
    let (mut sq, mut e) = (b, e);
    while e & 1 == 0 {
        sq = sq * sq;
        e >>= 1;
    }
    let mut acc = sq;
    e >>= 1;
    while e != 0 {
        sq = sq * sq;
        if e & 1 == 1 {
            acc = acc * sq;
        }
        e >>= 1;
    }
    acc
}

impl Kernel for PowerPolynomial {
    #[inline]
    fn shape(&self, v: f64) -> f64 {
        self.pow_n(self.base.shape(v))
    }

    #[inline]
    fn shape_derivative(&self, v: f64) -> f64 {
        self.shape_and_derivative(v).1
    }

    #[inline]
    fn shape_and_derivative(&self, v: f64) -> (f64, f64) {
        let (b, db) = self.base.shape_and_derivative(v);
        let (w, dw_db) = self.raise(b);
        (w, dw_db * db)
    }

    #[inline(always)]
    fn shape_lanes(&self, v: F64s) -> F64s {
        self.pow_n(self.base.shape_lanes(v))
    }

    #[inline(always)]
    fn shape_and_derivative_lanes(&self, v: F64s) -> (F64s, F64s) {
        let (b, db) = self.base.shape_and_derivative_lanes(v);
        let (w, dw_db) = self.raise(b);
        (w, dw_db * db)
    }

    #[inline]
    fn shape_sq(&self, v2: f64) -> f64 {
        self.pow_n(self.base.shape_sq(v2))
    }

    #[inline]
    fn shape_and_v_derivative_sq(&self, v2: f64) -> (f64, f64) {
        let (b, vdb) = self.base.shape_and_v_derivative_sq(v2);
        let (w, dw_db) = self.raise(b);
        (w, dw_db * vdb)
    }

    #[inline]
    fn derivative_over_v_sq(&self, v2: f64) -> f64 {
        let b = self.base.shape_sq(v2);
        self.raise(b).1 * self.base.derivative_over_v_sq(v2)
    }

    #[inline(always)]
    fn shape_sq_lanes(&self, v2: F64s) -> F64s {
        self.pow_n(self.base.shape_sq_lanes(v2))
    }

    #[inline(always)]
    fn shape_and_v_derivative_sq_lanes(&self, v2: F64s) -> (F64s, F64s) {
        let (b, vdb) = self.base.shape_and_v_derivative_sq_lanes(v2);
        let (w, dw_db) = self.raise(b);
        (w, dw_db * vdb)
    }

    #[inline(always)]
    fn derivative_over_v_sq_lanes(&self, v2: F64s) -> F64s {
        let b = self.base.shape_sq_lanes(v2);
        self.raise(b).1 * self.base.derivative_over_v_sq_lanes(v2)
    }

    #[inline]
    fn support(&self) -> f64 {
        self.base.support()
    }

    #[inline]
    fn norm(&self) -> f64 {
        self.norm
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Sinc;

    #[test]
    fn powers_by_squaring_are_exact_for_small_integers() {
        for e in 1..=12u32 {
            assert_eq!(pow(2.0f64, e), 2.0f64.powi(e as i32), "2^{e}");
        }
    }

    #[test]
    fn sinc_six_as_a_power_of_sinc_one() {
        let exact = Sinc::new(6.0).unwrap();
        let p = PowerPolynomial::fit(&exact, &Sinc::new(1.0).unwrap(), 6, 1e-11).unwrap();
        assert!(p.base().degree() <= 9, "{}", p.base().degree());
        for i in 0..=400 {
            let v = 2.0 * f64::from(i) / 400.0;
            let (w, dw) = exact.shape_and_derivative(v);
            let (pw, pdw) = p.shape_and_derivative(v);
            assert!((pw - w).abs() < 1e-12, "v = {v}: {pw} vs {w}");
            assert!((pdw - dw).abs() < 1e-11, "v = {v}: {pdw} vs {dw}");
        }
        assert_eq!(p.shape(2.0), 0.0);
        assert_eq!(p.norm(), exact.norm());
    }
}
