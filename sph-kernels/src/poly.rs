//! Kernel shapes as one polynomial over the whole support: no table, so the
//! lane forms are a handful of multiply-adds in registers instead of
//! gathers from memory.
//!
//! Gathers are what the lookup table costs in the pair loops: on the
//! AVX-512 machines we run on, the four gathers of one
//! [`Tabulated::shape_and_derivative_lanes`](crate::Tabulated) take about
//! as long as the rest of the density stage together. Smooth kernels are
//! reproduced by one polynomial of modest degree to better than the
//! table's own interpolation error, either in `v` or, for shapes even in
//! `v` (the sinc family), in `v^2`.

use std::fmt;

use crate::kernel::Kernel;
use crate::lanes::F32s;
use crate::{F64s, KernelError};

/// Most coefficients a fit may use (degree + 1).
pub(crate) const MAX_TERMS: usize = 32;
/// Points of the error check, equally spaced over `[0, support)`.
const CHECK_POINTS: usize = 4000;

/// The variable a [`Polynomial`] is a polynomial in, mapped onto
/// `t in [-1, 1]` over the support `[0, s]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FitVariable {
    /// `t = 2 v / s - 1`: any kernel that is a smooth function of `v`
    /// (the Wendland kernels are exact polynomials in `v`).
    Radius,
    /// `t = 2 v^2 / s^2 - 1`: shapes even in `v` (sinc), at about half the
    /// degree; `w'(0) = 0` holds exactly.
    Square,
}

/// A kernel shape approximated by one polynomial `P(t)` over its support
/// (Chebyshev interpolation, stored as monomial coefficients and evaluated
/// by Estrin's scheme), with the derivative `dw/dv = P'(t) dt/dv`; zero
/// from the support radius on.
///
/// [`Polynomial::fit`] picks the variable and the lowest degree whose
/// largest error over 4000 check points is within a given fraction of
/// `max |w|` (shape) and of `max |w'|` (derivative), or fails; the
/// normalisation and support are copied from the source kernel. Scalar and
/// lane forms run the same operations in the same order (multiply-adds
/// fused in both or in neither, as the build's target features allow), so
/// lane `l` equals the scalar result bit for bit.
///
/// ```
/// use sph_kernels::{F64s, Kernel, Polynomial, Sinc};
/// let sinc = Sinc::new(6.0)?;
/// let p = Polynomial::fit(&sinc, 1e-10)?;
/// assert!(p.degree() <= 20);
/// let (w, dw) = p.shape_and_derivative(0.7);
/// assert!((w - sinc.shape(0.7)).abs() < 1e-10);
/// assert!((dw - sinc.shape_derivative(0.7)).abs() < 1e-9);
/// assert_eq!(p.shape(2.0), 0.0);
/// // Lanes give the scalar bits.
/// let lanes = p.shape_lanes(F64s::splat(0.7));
/// assert_eq!(lanes.to_array()[3], w);
/// # Ok::<(), sph_kernels::KernelError>(())
/// ```
#[derive(Clone)]
pub struct Polynomial {
    /// Coefficients of `P(t)`, lowest first; `terms` are used.
    w: [f64; MAX_TERMS],
    /// Coefficients of `P'(t)` times the constant part of `dt/dv`
    /// (`2/s`, or `4/s^2` with a factor `v` applied at evaluation).
    dw: [f64; MAX_TERMS],
    terms: usize,
    variable: FitVariable,
    /// `2/s` or `2/s^2`: `t = scale v - 1` or `t = scale v^2 - 1`.
    scale: f64,
    support: f64,
    norm: f64,
}

impl Polynomial {
    /// The lowest-degree fit (either variable; the cheaper when both
    /// reach the tolerance) whose errors are at most `tolerance * max |w|`
    /// and `tolerance * max |w'|` over the support.
    ///
    /// # Errors
    /// [`KernelError::InvalidSupport`] for a support that is not finite and
    /// positive, [`KernelError::NonFinite`] when the kernel is not finite
    /// on its support, [`KernelError::NoPolynomialFit`] when no degree up
    /// to 31 reaches the tolerance (kernels with a kink, such as M4, or
    /// sinc with a non-integer exponent).
    pub fn fit<K: Kernel + ?Sized>(kernel: &K, tolerance: f64) -> Result<Self, KernelError> {
        let support = kernel.support();
        if !(support.is_finite() && support > 0.0) {
            return Err(KernelError::InvalidSupport { support });
        }
        let check = Check::sample(kernel)?;
        let mut best: Option<Self> = None;
        for variable in [FitVariable::Square, FitVariable::Radius] {
            // Only a fit cheaper than the best so far is worth trying.
            let most = best.as_ref().map_or(MAX_TERMS, |b| b.terms - 1);
            for terms in 2..=most {
                let p = Self::interpolate(kernel, variable, terms);
                if check.worst(&p) <= tolerance {
                    best = Some(p);
                    break;
                }
            }
        }
        best.ok_or(KernelError::NoPolynomialFit {
            tolerance,
            max_degree: MAX_TERMS - 1,
        })
    }

    /// Chebyshev interpolation of `kernel` at `terms` nodes of `variable`.
    pub(crate) fn interpolate<K: Kernel + ?Sized>(
        kernel: &K,
        variable: FitVariable,
        terms: usize,
    ) -> Self {
        let support = kernel.support();
        let scale = match variable {
            FitVariable::Radius => 2.0 / support,
            FitVariable::Square => 2.0 / (support * support),
        };
        let v_of = |t: f64| match variable {
            FitVariable::Radius => (t + 1.0) / scale,
            FitVariable::Square => ((t + 1.0) / scale).sqrt(),
        };
        let nf = terms as f64;
        let angle = |j: usize, k: usize| std::f64::consts::PI * k as f64 * (j as f64 + 0.5) / nf;
        let f: Vec<f64> = (0..terms)
            .map(|j| kernel.shape(v_of(angle(j, 1).cos())))
            .collect();
        // Chebyshev coefficients c_k, then the monomial form through the
        // recurrence T_{k+1} = 2 t T_k - T_{k-1}.
        let mut w = [0.0; MAX_TERMS];
        // T_{k-1} and T_k as monomial coefficients.
        let (mut t_prev, mut t_cur) = ([0.0; MAX_TERMS], [0.0; MAX_TERMS]);
        t_cur[0] = 1.0;
        for k in 0..terms {
            let mut c = (0..terms).map(|j| f[j] * angle(j, k).cos()).sum::<f64>() * 2.0 / nf;
            if k == 0 {
                c *= 0.5;
            }
            for (wi, ti) in w.iter_mut().zip(t_cur) {
                *wi += c * ti;
            }
            // T_1 = t, T_{k+1} = 2 t T_k - T_{k-1}.
            let (twice, minus) = if k == 0 { (1.0, 0.0) } else { (2.0, 1.0) };
            let mut t_next = [0.0; MAX_TERMS];
            for i in 0..MAX_TERMS {
                let shifted = if i > 0 { twice * t_cur[i - 1] } else { 0.0 };
                t_next[i] = shifted - minus * t_prev[i];
            }
            (t_prev, t_cur) = (t_cur, t_next);
        }
        let mut dw = [0.0; MAX_TERMS];
        let chain = match variable {
            FitVariable::Radius => scale,
            FitVariable::Square => 2.0 * scale,
        };
        for k in 1..terms {
            dw[k - 1] = k as f64 * w[k] * chain;
        }
        Self {
            w,
            dw,
            terms,
            variable,
            scale,
            support,
            norm: kernel.norm(),
        }
    }

    /// The coefficients of `P(t)` and of the derivative form, the number
    /// of terms of `P` and the scale of `t` (for the single-precision copy
    /// of a fit in `v^2`).
    pub(crate) fn coefficients(&self) -> (&[f64; MAX_TERMS], &[f64; MAX_TERMS], usize, f64) {
        (&self.w, &self.dw, self.terms, self.scale)
    }

    /// Degree of the shape polynomial.
    pub fn degree(&self) -> usize {
        self.terms - 1
    }

    /// The variable the polynomial is in.
    pub fn variable(&self) -> FitVariable {
        self.variable
    }

    /// `t` for `v`.
    #[inline(always)]
    fn t(&self, v: f64) -> f64 {
        match self.variable {
            FitVariable::Radius => self.scale * v - 1.0,
            FitVariable::Square => self.t_sq(v * v),
        }
    }

    #[inline(always)]
    fn t_lanes(&self, v: F64s) -> F64s {
        match self.variable {
            FitVariable::Radius => v * self.scale - 1.0,
            FitVariable::Square => self.t_sq_lanes(v * v),
        }
    }

    /// `t` for `v^2` (a fit in `v^2` only).
    #[inline(always)]
    fn t_sq(&self, v2: f64) -> f64 {
        self.scale * v2 - 1.0
    }

    #[inline(always)]
    fn t_sq_lanes(&self, v2: F64s) -> F64s {
        v2 * self.scale - 1.0
    }

    /// `value` where `v^2` is inside the support, else 0.
    #[inline(always)]
    fn inside_sq(&self, v2: F64s, value: F64s) -> F64s {
        v2.lt(F64s::splat(self.support * self.support))
            .select(value, F64s::splat(0.0))
    }
}

impl fmt::Debug for Polynomial {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Polynomial")
            .field("variable", &self.variable)
            .field("degree", &self.degree())
            .field("support", &self.support)
            .field("norm", &self.norm)
            .finish_non_exhaustive()
    }
}

/// Scalars and lanes, for the one polynomial evaluation both share (so
/// lane `l` is the scalar result bit for bit), in `f64` or `f32`.
pub(crate) trait PolyValue: Copy {
    /// The coefficients' type (the scalar of the same precision).
    type Coef: Copy;
    fn splat(c: Self::Coef) -> Self;
    fn mul(self, b: Self) -> Self;
    /// `self b + c`: fused where the build targets FMA (in both forms),
    /// else a multiply and an add.
    fn mul_add(self, b: Self, c: Self) -> Self;
}

/// `PolyValue` for a scalar or lane type whose `*` is element-wise and
/// whose inherent `mul_add` fuses: its coefficient type and how a
/// coefficient fills it; the multiply-add is
/// [`fused_mul_add`](crate::lanes::fused_mul_add)'s.
macro_rules! poly_value {
    ($t:ty, $coef:ty, $splat:expr) => {
        impl PolyValue for $t {
            type Coef = $coef;

            #[inline(always)]
            fn splat(c: $coef) -> Self {
                $splat(c)
            }

            #[inline(always)]
            fn mul(self, b: Self) -> Self {
                self * b
            }

            #[inline(always)]
            fn mul_add(self, b: Self, c: Self) -> Self {
                crate::lanes::fused_mul_add!(self, b, c)
            }
        }
    };
}

poly_value!(f64, f64, |c| c);
poly_value!(F64s, f64, F64s::splat);
poly_value!(f32, f32, |c| c);
poly_value!(F32s, f32, F32s::splat);

/// `sum c[k] t^k` over the first `terms` coefficients. The pair loops
/// are latency-bound (a pair's chain from `r^2` to the sums is longer
/// than the out-of-order window can hide, on AVX2 above all), so the
/// polynomial is evaluated by Estrin's scheme, whose depth grows as
/// `log2(terms)`: fully unrolled for the term counts of the sinc base of
/// the default kernel's power form (8 and 7), by two Horner chains in
/// `t^2` for other counts.
#[inline(always)]
pub(crate) fn poly<V: PolyValue>(c: &[V::Coef; MAX_TERMS], terms: usize, t: V) -> V {
    match terms {
        // The power form's sinc base and its derivative (each arm is
        // inlined into every kernel call of every pair loop: few arms).
        8 => estrin::<V, 8>(c, t),
        7 => estrin::<V, 7>(c, t),
        _ => horner(c, terms, t),
    }
}

/// Estrin's scheme for `N` terms: pairs `c[2i] + c[2i+1] t`, then pairs of
/// those with `t^2`, with `t^4`, ... (depth `ceil(log2 N)` multiply-adds
/// instead of `N - 1`).
#[inline(always)]
fn estrin<V: PolyValue, const N: usize>(c: &[V::Coef; MAX_TERMS], t: V) -> V {
    let mut v: [V; N] = std::array::from_fn(|k| V::splat(c[k]));
    let (mut n, mut x) = (N, t);
    while n > 1 {
        let half = n.div_ceil(2);
        for i in 0..half {
            v[i] = if 2 * i + 1 < n {
                v[2 * i + 1].mul_add(x, v[2 * i])
            } else {
                v[2 * i]
            };
        }
        n = half;
        if n > 1 {
            x = x.mul(x);
        }
    }
    v[0]
}

/// `sum c[k] t^k` by Horner's rule in `t^2` for the even and odd halves
/// as two independent chains, then `even + t odd`.
#[inline(always)]
fn horner<V: PolyValue>(c: &[V::Coef; MAX_TERMS], terms: usize, t: V) -> V {
    let top = terms - 1;
    if top == 0 {
        return V::splat(c[0]);
    }
    let t2 = t.mul(t);
    // Highest even and odd indices.
    let (mut e, mut o) = if top.is_multiple_of(2) {
        (top, top - 1)
    } else {
        (top - 1, top)
    };
    let (mut even, mut odd) = (V::splat(c[e]), V::splat(c[o]));
    while e >= 2 {
        e -= 2;
        even = even.mul_add(t2, V::splat(c[e]));
    }
    while o >= 2 {
        o -= 2;
        odd = odd.mul_add(t2, V::splat(c[o]));
    }
    odd.mul_add(t, even)
}

impl Kernel for Polynomial {
    #[inline]
    fn shape(&self, v: f64) -> f64 {
        let w = poly(&self.w, self.terms, self.t(v));
        // `v < support` is false for NaN too.
        if v < self.support {
            w
        } else {
            0.0
        }
    }

    #[inline]
    fn shape_derivative(&self, v: f64) -> f64 {
        self.shape_and_derivative(v).1
    }

    #[inline]
    fn shape_and_derivative(&self, v: f64) -> (f64, f64) {
        let t = self.t(v);
        let w = poly(&self.w, self.terms, t);
        let mut dw = poly(&self.dw, self.terms - 1, t);
        if self.variable == FitVariable::Square {
            dw *= v;
        }
        if v < self.support {
            (w, dw)
        } else {
            (0.0, 0.0)
        }
    }

    #[inline(always)]
    fn shape_lanes(&self, v: F64s) -> F64s {
        let w = poly(&self.w, self.terms, self.t_lanes(v));
        v.lt(F64s::splat(self.support)).select(w, F64s::splat(0.0))
    }

    #[inline(always)]
    fn shape_and_derivative_lanes(&self, v: F64s) -> (F64s, F64s) {
        let t = self.t_lanes(v);
        let w = poly(&self.w, self.terms, t);
        let mut dw = poly(&self.dw, self.terms - 1, t);
        if self.variable == FitVariable::Square {
            dw *= v;
        }
        let inside = v.lt(F64s::splat(self.support));
        let zero = F64s::splat(0.0);
        (inside.select(w, zero), inside.select(dw, zero))
    }

    #[inline]
    fn derivative_over_v_sq(&self, v2: f64) -> f64 {
        match self.variable {
            // w' = v P'(t) (chain factor in dw), so w' / v = P'(t).
            FitVariable::Square => {
                let dw = poly(&self.dw, self.terms - 1, self.t_sq(v2));
                if v2 < self.support * self.support {
                    dw
                } else {
                    0.0
                }
            }
            FitVariable::Radius => {
                let v = v2.sqrt();
                self.shape_derivative(v) / v
            }
        }
    }

    #[inline(always)]
    fn derivative_over_v_sq_lanes(&self, v2: F64s) -> F64s {
        match self.variable {
            FitVariable::Square => {
                let dw = poly(&self.dw, self.terms - 1, self.t_sq_lanes(v2));
                self.inside_sq(v2, dw)
            }
            FitVariable::Radius => {
                let v = v2.sqrt();
                self.shape_and_derivative_lanes(v).1 / v
            }
        }
    }

    #[inline]
    fn shape_sq(&self, v2: f64) -> f64 {
        match self.variable {
            FitVariable::Square => {
                let w = poly(&self.w, self.terms, self.t_sq(v2));
                if v2 < self.support * self.support {
                    w
                } else {
                    0.0
                }
            }
            FitVariable::Radius => self.shape(v2.sqrt()),
        }
    }

    #[inline]
    fn shape_and_v_derivative_sq(&self, v2: f64) -> (f64, f64) {
        match self.variable {
            FitVariable::Square => {
                let t = self.t_sq(v2);
                let w = poly(&self.w, self.terms, t);
                let vdw = poly(&self.dw, self.terms - 1, t) * v2;
                if v2 < self.support * self.support {
                    (w, vdw)
                } else {
                    (0.0, 0.0)
                }
            }
            FitVariable::Radius => {
                let v = v2.sqrt();
                let (w, dw) = self.shape_and_derivative(v);
                (w, v * dw)
            }
        }
    }

    #[inline(always)]
    fn shape_sq_lanes(&self, v2: F64s) -> F64s {
        match self.variable {
            FitVariable::Square => {
                let w = poly(&self.w, self.terms, self.t_sq_lanes(v2));
                self.inside_sq(v2, w)
            }
            FitVariable::Radius => self.shape_lanes(v2.sqrt()),
        }
    }

    #[inline(always)]
    fn shape_and_v_derivative_sq_lanes(&self, v2: F64s) -> (F64s, F64s) {
        match self.variable {
            // w' = v P'(t) dw-coefficients, so v w' = v^2 (...): no root.
            FitVariable::Square => {
                let t = self.t_sq_lanes(v2);
                let w = poly(&self.w, self.terms, t);
                let vdw = poly(&self.dw, self.terms - 1, t) * v2;
                (self.inside_sq(v2, w), self.inside_sq(v2, vdw))
            }
            FitVariable::Radius => {
                let v = v2.sqrt();
                let (w, dw) = self.shape_and_derivative_lanes(v);
                (w, v * dw)
            }
        }
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

/// The exact kernel on the check points, and the scales errors are
/// measured against.
pub(crate) struct Check {
    v: Vec<f64>,
    w: Vec<f64>,
    dw: Vec<f64>,
    max_w: f64,
    max_dw: f64,
}

impl Check {
    pub(crate) fn sample<K: Kernel + ?Sized>(kernel: &K) -> Result<Self, KernelError> {
        let s = kernel.support();
        let v: Vec<f64> = (0..CHECK_POINTS)
            .map(|i| s * i as f64 / CHECK_POINTS as f64)
            .collect();
        let (mut w, mut dw) = (Vec::with_capacity(v.len()), Vec::with_capacity(v.len()));
        for &vi in &v {
            let (a, b) = kernel.shape_and_derivative(vi);
            if !(a.is_finite() && b.is_finite()) {
                return Err(KernelError::NonFinite { v: vi, w: a, dw: b });
            }
            w.push(a);
            dw.push(b);
        }
        let max_abs = |x: &[f64]| x.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        let (max_w, max_dw) = (max_abs(&w), max_abs(&dw));
        Ok(Self {
            v,
            w,
            dw,
            max_w,
            max_dw,
        })
    }

    /// The larger of the shape and derivative errors of `p`, relative to
    /// their scales.
    pub(crate) fn worst<P: Kernel + ?Sized>(&self, p: &P) -> f64 {
        let mut worst = 0.0f64;
        for ((&v, &w), &dw) in self.v.iter().zip(&self.w).zip(&self.dw) {
            let (a, b) = p.shape_and_derivative(v);
            let e = ((a - w).abs() / self.max_w)
                .max((b - dw).abs() / self.max_dw.max(f64::MIN_POSITIVE));
            // NaN counts as failure.
            worst = if e.is_nan() {
                f64::INFINITY
            } else {
                worst.max(e)
            };
        }
        worst
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CubicSpline, Sinc, WendlandC2, WendlandC6};

    #[test]
    fn built_in_kernels_fit_or_fail_as_expected() {
        let sinc6 = Polynomial::fit(&Sinc::new(6.0).unwrap(), 1e-10).unwrap();
        assert_eq!(sinc6.variable(), FitVariable::Square);
        // Wendland kernels are polynomials in v: reproduced at their degree.
        let c2 = Polynomial::fit(&WendlandC2, 1e-10).unwrap();
        assert_eq!((c2.variable(), c2.degree()), (FitVariable::Radius, 5));
        let c6 = Polynomial::fit(&WendlandC6, 1e-10).unwrap();
        assert_eq!((c6.variable(), c6.degree()), (FitVariable::Radius, 11));
        // M4 has a kink in w'' at v = 1: no single polynomial.
        assert!(matches!(
            Polynomial::fit(&CubicSpline, 1e-10),
            Err(KernelError::NoPolynomialFit { .. })
        ));
    }

    #[test]
    fn derivative_vanishes_at_the_centre_for_even_fits() {
        let p = Polynomial::fit(&Sinc::new(6.0).unwrap(), 1e-10).unwrap();
        assert_eq!(p.shape_derivative(0.0), 0.0);
    }
}
