//! The [`Kernel`] trait, its derived quantities, and numeric normalisation.

use std::f64::consts::PI;
use std::sync::Arc;

use crate::gauss::GaussLegendre;
use crate::F64s;

/// How many arguments the lane methods ([`Kernel::shape_lanes`],
/// [`Kernel::shape_and_derivative_lanes`]) take at once: neighbour loops
/// work in chunks of this many pairs so the arithmetic vectorises.
pub const LANES: usize = 8;
// The lane forms of the tables use `wide::f64x8`.
const _: () = assert!(LANES == 8);

/// A spherically symmetric SPH smoothing kernel in 3-D.
///
/// Implementors give the dimensionless shape `w(v)`, `v = r/h`, its derivative,
/// the support radius (in units of `h`) and the normalisation `K`, so that
/// `W(r, h) = K / h^3 * w(r/h)` integrates to 1 over 3-D space. The provided
/// methods [`w`](Kernel::w), [`dw_dr`](Kernel::dw_dr) and [`dw_dh`](Kernel::dw_dh)
/// turn that into the dimensional quantities an SPH solver needs.
///
/// The trait is object safe, so solvers can hold a `Box<dyn Kernel>`.
pub trait Kernel: Send + Sync {
    /// Dimensionless shape `w(v)`, `v = r/h >= 0`; zero for `v >= support()`.
    fn shape(&self, v: f64) -> f64;

    /// Derivative `dw/dv`; zero for `v >= support()`.
    fn shape_derivative(&self, v: f64) -> f64;

    /// `(w(v), dw/dv)` at once. The default calls the two methods above;
    /// kernels that share work between them (sinc, tables) override it.
    #[inline]
    fn shape_and_derivative(&self, v: f64) -> (f64, f64) {
        (self.shape(v), self.shape_derivative(v))
    }

    /// `w(v)` for a lane of [`LANES`] arguments. The default calls
    /// [`shape`](Kernel::shape) per lane; tables override it with vector
    /// instructions. Lane `l` equals `shape(v[l])` bit for bit.
    #[inline]
    fn shape_lanes(&self, v: F64s) -> F64s {
        F64s::from_array(v.to_array().map(|x| self.shape(x)))
    }

    /// `(w(v), w'(v))` for a lane of [`LANES`] arguments; lane `l` equals
    /// `shape_and_derivative(v[l])` bit for bit.
    #[inline]
    fn shape_and_derivative_lanes(&self, v: F64s) -> (F64s, F64s) {
        let v = v.to_array();
        let mut w = [0.0; LANES];
        let mut dw = [0.0; LANES];
        for l in 0..LANES {
            (w[l], dw[l]) = self.shape_and_derivative(v[l]);
        }
        (F64s::from_array(w), F64s::from_array(dw))
    }

    /// `w(v)` from the squared argument `v2 = v^2` (what a pair loop
    /// has before any square root). The default takes the root; a
    /// polynomial in `v^2` ([`Polynomial`](crate::Polynomial)) evaluates
    /// without it. Lane forms: [`shape_sq_lanes`](Kernel::shape_sq_lanes).
    ///
    /// ```
    /// use sph_kernels::{FastKernel, Kernel, Sinc};
    /// let k = FastKernel::new(&Sinc::new(6.0)?)?;
    /// // A pair at r = 0.007 with h = 0.01: v^2 = r^2 / h^2, no root taken.
    /// let (r2, h) = (0.007f64 * 0.007, 0.01);
    /// let (v2, v) = (r2 / (h * h), r2.sqrt() / h);
    /// assert!((k.shape_sq(v2) - k.shape(v)).abs() < 1e-13);
    /// let (w, vdw) = k.shape_and_v_derivative_sq(v2);
    /// assert!((w - k.shape(v)).abs() < 1e-13);
    /// assert!((vdw - v * k.shape_derivative(v)).abs() < 1e-13);
    /// assert!((k.derivative_over_v_sq(v2) * v - k.shape_derivative(v)).abs() < 1e-13);
    /// # Ok::<(), sph_kernels::KernelError>(())
    /// ```
    #[inline]
    fn shape_sq(&self, v2: f64) -> f64 {
        self.shape(v2.sqrt())
    }

    /// `(w(v), v w'(v))` from the squared argument `v2 = v^2` (the
    /// h-derivative of a kernel sum needs `3 w + v w'`); the default takes
    /// the root.
    #[inline]
    fn shape_and_v_derivative_sq(&self, v2: f64) -> (f64, f64) {
        let v = v2.sqrt();
        let (w, dw) = self.shape_and_derivative(v);
        (w, v * dw)
    }

    /// `w'(v) / v` from the squared argument `v2 = v^2` (`v > 0`): a
    /// kernel gradient is `K/h^5 (w'(v) / v) (x_i - x_j)`. The default
    /// takes the root and divides (not finite at `v = 0`, where callers
    /// mask the pair); a polynomial in `v^2` needs neither.
    #[inline]
    fn derivative_over_v_sq(&self, v2: f64) -> f64 {
        let v = v2.sqrt();
        self.shape_derivative(v) / v
    }

    /// [`shape_sq`](Kernel::shape_sq) for a lane of squared arguments;
    /// lane `l` equals `shape_sq(v2[l])` bit for bit.
    #[inline]
    fn shape_sq_lanes(&self, v2: F64s) -> F64s {
        self.shape_lanes(v2.sqrt())
    }

    /// [`shape_and_v_derivative_sq`](Kernel::shape_and_v_derivative_sq)
    /// for a lane of squared arguments; lane `l` equals its scalar form
    /// bit for bit.
    #[inline]
    fn shape_and_v_derivative_sq_lanes(&self, v2: F64s) -> (F64s, F64s) {
        let v = v2.sqrt();
        let (w, dw) = self.shape_and_derivative_lanes(v);
        (w, v * dw)
    }

    /// [`derivative_over_v_sq`](Kernel::derivative_over_v_sq) for a lane
    /// of squared arguments; lane `l` equals its scalar form bit for bit.
    #[inline]
    fn derivative_over_v_sq_lanes(&self, v2: F64s) -> F64s {
        let v = v2.sqrt();
        self.shape_and_derivative_lanes(v).1 / v
    }

    /// Support radius in units of `h` (2.0 for every built-in kernel).
    #[inline]
    fn support(&self) -> f64 {
        2.0
    }

    /// `Some((b, n))` when the shape is `b(v)^n` for a smooth kernel `b`
    /// (same support) and an integer `n >= 2`, as sinc's `S_n = S_1^n`:
    /// [`FastKernel`](crate::FastKernel) then fits `b`, which takes far
    /// fewer terms than its power. `None` by default.
    fn power_of(&self) -> Option<(Box<dyn Kernel>, u32)> {
        None
    }

    /// Normalisation `K`: `W(r, h) = K/h^3 w(r/h)` integrates to 1 in 3-D.
    /// For a custom kernel, [`normalisation`] computes it.
    fn norm(&self) -> f64;

    /// The kernel `W(r, h) = K/h^3 w(r/h)`.
    #[inline]
    fn w(&self, r: f64, h: f64) -> f64 {
        let inv_h = 1.0 / h;
        self.norm() * inv_h * inv_h * inv_h * self.shape(r * inv_h)
    }

    /// Radial derivative `dW/dr = K/h^4 w'(r/h)`; the gradient is
    /// `∇_i W = dW/dr * x_ij / r`.
    #[inline]
    fn dw_dr(&self, r: f64, h: f64) -> f64 {
        let inv_h = 1.0 / h;
        let inv_h2 = inv_h * inv_h;
        self.norm() * inv_h2 * inv_h2 * self.shape_derivative(r * inv_h)
    }

    /// Derivative with respect to the smoothing length (grad-h terms):
    /// `dW/dh = -K/h^4 (3 w(v) + v w'(v))`.
    #[inline]
    fn dw_dh(&self, r: f64, h: f64) -> f64 {
        let inv_h = 1.0 / h;
        let inv_h2 = inv_h * inv_h;
        let v = r * inv_h;
        let (w, dw) = self.shape_and_derivative(v);
        -self.norm() * inv_h2 * inv_h2 * (3.0 * w + v * dw)
    }
}

// Forwarding impls so `&K`, `Box<dyn Kernel>` and `Arc<dyn Kernel>` are kernels
// too (e.g. to tabulate a boxed kernel, or share one across threads).
macro_rules! forward_kernel {
    ($($ptr:ty),*) => {$(
        impl<K: Kernel + ?Sized> Kernel for $ptr {
            #[inline]
            fn shape(&self, v: f64) -> f64 {
                (**self).shape(v)
            }
            #[inline]
            fn shape_derivative(&self, v: f64) -> f64 {
                (**self).shape_derivative(v)
            }
            #[inline]
            fn shape_and_derivative(&self, v: f64) -> (f64, f64) {
                (**self).shape_and_derivative(v)
            }
            #[inline]
            fn shape_lanes(&self, v: F64s) -> F64s {
                (**self).shape_lanes(v)
            }
            #[inline]
            fn shape_and_derivative_lanes(&self, v: F64s) -> (F64s, F64s) {
                (**self).shape_and_derivative_lanes(v)
            }
            #[inline]
            fn derivative_over_v_sq(&self, v2: f64) -> f64 {
                (**self).derivative_over_v_sq(v2)
            }
            #[inline]
            fn derivative_over_v_sq_lanes(&self, v2: F64s) -> F64s {
                (**self).derivative_over_v_sq_lanes(v2)
            }
            #[inline]
            fn shape_sq(&self, v2: f64) -> f64 {
                (**self).shape_sq(v2)
            }
            #[inline]
            fn shape_and_v_derivative_sq(&self, v2: f64) -> (f64, f64) {
                (**self).shape_and_v_derivative_sq(v2)
            }
            #[inline]
            fn shape_sq_lanes(&self, v2: F64s) -> F64s {
                (**self).shape_sq_lanes(v2)
            }
            #[inline]
            fn shape_and_v_derivative_sq_lanes(&self, v2: F64s) -> (F64s, F64s) {
                (**self).shape_and_v_derivative_sq_lanes(v2)
            }
            #[inline]
            fn support(&self) -> f64 {
                (**self).support()
            }
            fn power_of(&self) -> Option<(Box<dyn Kernel>, u32)> {
                (**self).power_of()
            }
            #[inline]
            fn norm(&self) -> f64 {
                (**self).norm()
            }
        }
    )*};
}
forward_kernel!(&K, Box<K>, Arc<K>);

/// Panel count per unit length in the first quadrature pass.
const START_PANELS_PER_UNIT: usize = 16;
/// Refinement stops here even if not converged (only for pathological shapes).
const MAX_PANELS_PER_UNIT: usize = 1 << 14;
/// Relative change between successive refinements that counts as converged.
const TOLERANCE: f64 = 1e-14;

/// Normalisation `K = 1 / (4 pi ∫_0^s w(v) v^2 dv)` of a 3-D kernel shape with
/// support `s` (in units of `h`).
///
/// Composite 20-point Gauss-Legendre quadrature with panel boundaries at every
/// integer `v` (so piecewise-polynomial kernels with pieces joining at `v = 1`,
/// such as M4, are integrated exactly), refined by doubling the panel count
/// until two passes agree to 1e-14; results are accurate to ~1e-14. The shape
/// is only evaluated inside `(0, s)`.
///
/// Returns a non-finite or negative value if `w` integrates to zero or less.
///
/// # Panics
/// If `support` is not finite and positive.
pub fn normalisation(shape: impl Fn(f64) -> f64, support: f64) -> f64 {
    assert!(
        support.is_finite() && support > 0.0,
        "normalisation: support must be finite and > 0, got {support}"
    );
    let rule = GaussLegendre::<20>::new();
    let integrand = |v: f64| shape(v) * v * v;

    // Pieces [0, 1], [1, 2], ..., [floor(s), s]: kinks of piecewise kernels sit
    // on integers, so no Gauss panel straddles one.
    let mut breaks = vec![0.0];
    breaks.extend((1..).map(|k| k as f64).take_while(|&k| k < support));
    breaks.push(support);

    let integrate = |per_unit: usize| -> f64 {
        breaks
            .windows(2)
            .map(|piece| {
                let (a, b) = (piece[0], piece[1]);
                let panels = (((b - a) * per_unit as f64).ceil() as usize).max(1);
                let width = (b - a) / panels as f64;
                (0..panels)
                    .map(|p| {
                        let lo = a + p as f64 * width;
                        let hi = if p + 1 == panels { b } else { lo + width };
                        rule.integrate(&integrand, lo, hi)
                    })
                    .sum::<f64>()
            })
            .sum()
    };

    let mut per_unit = START_PANELS_PER_UNIT;
    let mut coarse = integrate(per_unit);
    let integral = loop {
        per_unit *= 2;
        let fine = integrate(per_unit);
        if (fine - coarse).abs() <= TOLERANCE * fine.abs() || per_unit >= MAX_PANELS_PER_UNIT {
            break fine;
        }
        coarse = fine;
    };
    1.0 / (4.0 * PI * integral)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_sphere_normalisation() {
        // w = 1 on [0, s): K = 3 / (4 pi s^3).
        for s in [0.5, 1.0, 2.0, 2.5, 3.0] {
            let k = normalisation(|_| 1.0, s);
            let want = 3.0 / (4.0 * PI * s * s * s);
            assert!((k / want - 1.0).abs() < 1e-14, "s = {s}: {k} vs {want}");
        }
    }

    #[test]
    fn gaussian_normalisation_matches_erf_free_closed_form() {
        // ∫_0^∞ exp(-v^2) v^2 dv = sqrt(pi)/4; truncating at 8 loses < 1e-26.
        let k = normalisation(|v| (-v * v).exp(), 8.0);
        let want = 1.0 / (PI * PI.sqrt());
        assert!((k / want - 1.0).abs() < 1e-14, "{k} vs {want}");
    }

    #[test]
    #[should_panic(expected = "support must be finite")]
    fn bad_support_panics() {
        normalisation(|_| 1.0, f64::NAN);
    }

    #[derive(Debug)]
    struct Step;
    impl Kernel for Step {
        fn shape(&self, v: f64) -> f64 {
            if v < 2.0 {
                1.0
            } else {
                0.0
            }
        }
        fn shape_derivative(&self, _v: f64) -> f64 {
            0.0
        }
        fn norm(&self) -> f64 {
            3.0 / (32.0 * PI)
        }
    }

    #[test]
    fn dimensional_helpers_scale_with_h() {
        let k = Step;
        let h = 0.25;
        assert!((k.w(0.1, h) - k.norm() / (h * h * h)).abs() < 1e-12);
        assert_eq!(k.w(0.5, h), 0.0);
        assert!((k.dw_dh(0.1, h) + 3.0 * k.norm() / h.powi(4)).abs() < 1e-9);
        // Forwarding impls.
        let boxed: Box<dyn Kernel> = Box::new(Step);
        assert_eq!(boxed.w(0.1, h), k.w(0.1, h));
        fn support_of(k: impl Kernel) -> f64 {
            k.support()
        }
        assert_eq!(support_of(&k), 2.0);
        assert_eq!(Arc::new(Step).norm(), k.norm());
    }
}
