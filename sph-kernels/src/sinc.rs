//! The sinc kernel family `S_n(v) = [sin(pi v/2) / (pi v/2)]^n` (Cabezón et al. 2008).

use std::f64::consts::FRAC_PI_2;

use crate::kernel::{normalisation, Kernel};
use crate::KernelError;

/// The sinc kernel `S_n(v) = [sin(x)/x]^n`, `x = pi v / 2`, support `2h`,
/// evaluated exactly (with `sin` and `powi`/`powf`) for any real `n >= 1`.
///
/// The normalisation `K_n` is computed numerically at construction;
/// `n = 6` (the SPH-EXA default) gives `K_6 ≈ 0.790450`. For the hot loop
/// wrap it in a [`crate::Tabulated`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sinc {
    n: f64,
    /// Raises `S_1` to the power `n - 1` (`S_n = S_{n-1} S_1`).
    pow_n_minus_1: Power,
    norm: f64,
}

/// Integer exponents use `powi` (several times faster than `powf`).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Power {
    Int(i32),
    Real(f64),
}

impl Power {
    #[inline]
    fn apply(self, x: f64) -> f64 {
        match self {
            Power::Int(k) => x.powi(k),
            Power::Real(p) => x.powf(p),
        }
    }
}

impl Sinc {
    /// Smallest allowed exponent: below 1, `S_n` is not differentiable at `v = 2`.
    pub const MIN_EXPONENT: f64 = 1.0;
    /// Largest allowed exponent: far beyond practical use (3..12); keeps the
    /// kernel wide enough for the numeric normalisation to stay accurate.
    pub const MAX_EXPONENT: f64 = 1000.0;
    /// The SPH-EXA default exponent.
    pub const DEFAULT_EXPONENT: f64 = 6.0;

    /// Sinc kernel with exponent `n`.
    ///
    /// # Errors
    /// [`KernelError::SincExponent`] unless `n` is finite and in
    /// [`MIN_EXPONENT`](Self::MIN_EXPONENT), [`MAX_EXPONENT`](Self::MAX_EXPONENT).
    pub fn new(n: f64) -> Result<Self, KernelError> {
        Self::check_exponent(n)?;
        let pow_n_minus_1 = if n.fract() == 0.0 {
            Power::Int(n as i32 - 1)
        } else {
            Power::Real(n - 1.0)
        };
        let mut sinc = Self {
            n,
            pow_n_minus_1,
            norm: f64::NAN,
        };
        sinc.norm = normalisation(|v| sinc.shape(v), 2.0);
        Ok(sinc)
    }

    /// Range check shared with [`crate::KernelChoice`]'s parser.
    pub(crate) fn check_exponent(n: f64) -> Result<(), KernelError> {
        // `contains` is false for NaN.
        if (Self::MIN_EXPONENT..=Self::MAX_EXPONENT).contains(&n) {
            Ok(())
        } else {
            Err(KernelError::SincExponent {
                n,
                min: Self::MIN_EXPONENT,
                max: Self::MAX_EXPONENT,
            })
        }
    }

    /// The exponent `n`.
    pub fn exponent(&self) -> f64 {
        self.n
    }
}

impl Default for Sinc {
    /// `S_6`, the SPH-EXA default.
    fn default() -> Self {
        Self::new(Self::DEFAULT_EXPONENT).expect("the default exponent is valid")
    }
}

/// Below this `x`, Taylor series replace `sin(x)/x` (0/0 at x = 0) and
/// `(x cos x - sin x)/x^2` (cancellation); truncation error there is < 1e-16.
const SERIES_X: f64 = 0.25;

/// `S_1 = sin(x)/x` and `dS_1/dx`.
#[inline]
fn sinc1_and_derivative(x: f64) -> (f64, f64) {
    if x < SERIES_X {
        let y = x * x;
        // sin(x)/x = sum (-1)^k x^2k / (2k+1)!
        let s = 1.0
            + y * (-1.0 / 6.0
                + y * (1.0 / 120.0
                    + y * (-1.0 / 5040.0 + y * (1.0 / 362_880.0 + y * (-1.0 / 39_916_800.0)))));
        // d/dx = sum (-1)^k 2k x^(2k-1) / (2k+1)!
        let ds = x
            * (-1.0 / 3.0
                + y * (1.0 / 30.0
                    + y * (-1.0 / 840.0
                        + y * (1.0 / 45_360.0 + y * (-1.0 / 3_991_680.0 + y / 518_918_400.0)))));
        (s, ds)
    } else {
        let (sin, cos) = x.sin_cos();
        let s = sin / x;
        (s, (cos - s) / x)
    }
}

impl Kernel for Sinc {
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
        // Written so that NaN also lands in the zero branch.
        if v >= 2.0 || v.is_nan() {
            return (0.0, 0.0);
        }
        let x = FRAC_PI_2 * v;
        let (s1, ds1_dx) = sinc1_and_derivative(x);
        // sin(x) may round to a tiny negative value next to x = pi; powf of a
        // negative base would be NaN.
        let s1 = s1.max(0.0);
        let s_n_minus_1 = self.pow_n_minus_1.apply(s1);
        // dS_n/dv = n S_{n-1} dS_1/dv, dS_1/dv = pi/2 dS_1/dx.
        (s_n_minus_1 * s1, self.n * s_n_minus_1 * FRAC_PI_2 * ds1_dx)
    }

    #[inline]
    fn norm(&self) -> f64 {
        self.norm
    }

    /// `S_n = S_1^n` for integer `n >= 2`.
    fn power_of(&self) -> Option<(Box<dyn Kernel>, u32)> {
        if self.n.fract() != 0.0 || self.n < 2.0 {
            return None;
        }
        // Built only for integer exponents (its norm costs an integral).
        let base = Sinc::new(1.0).ok()?;
        Some((Box::new(base), self.n as u32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn series_and_closed_form_agree_at_the_switch() {
        let below = sinc1_and_derivative(SERIES_X * (1.0 - 1e-15));
        let above = sinc1_and_derivative(SERIES_X);
        assert!((below.0 - above.0).abs() < 1e-15, "{below:?} {above:?}");
        assert!((below.1 - above.1).abs() < 1e-14, "{below:?} {above:?}");
    }

    #[test]
    fn value_at_origin_is_exactly_one() {
        for n in [1.0, 3.0, 5.5, 6.0, 12.0] {
            let k = Sinc::new(n).unwrap();
            assert_eq!(k.shape(0.0), 1.0);
            assert_eq!(k.shape_derivative(0.0), 0.0);
        }
    }

    #[test]
    fn integer_and_real_paths_agree() {
        let int = Sinc::new(6.0).unwrap();
        let real = Sinc {
            pow_n_minus_1: Power::Real(5.0),
            ..int
        };
        for i in 0..=200 {
            let v = i as f64 * 0.01;
            let (a, b) = (int.shape_and_derivative(v), real.shape_and_derivative(v));
            assert!(
                (a.0 - b.0).abs() < 1e-15 && (a.1 - b.1).abs() < 1e-14,
                "v = {v}"
            );
        }
    }

    #[test]
    fn k6_reference_value() {
        let k = Sinc::new(6.0).unwrap();
        assert!((k.norm() - 0.790450).abs() < 1e-5, "{}", k.norm());
        assert_eq!(Sinc::default(), k);
    }

    #[test]
    fn exponent_range_is_enforced() {
        for n in [0.999, 0.0, -3.0, 1000.5, f64::NAN, f64::INFINITY] {
            let err = Sinc::new(n).unwrap_err();
            assert!(matches!(err, KernelError::SincExponent { .. }), "{err}");
        }
        let msg = Sinc::new(0.5).unwrap_err().to_string();
        assert!(msg.contains("0.5") && msg.contains("1 <= n"), "{msg}");
        assert!(Sinc::new(1.0).is_ok() && Sinc::new(1000.0).is_ok());
    }

    #[test]
    fn n_equal_one_has_a_derivative_jump_at_the_edge() {
        // S_1'(2-) = -1/2, and zero beyond by contract.
        let k = Sinc::new(1.0).unwrap();
        let below = k.shape_derivative(2.0 - 1e-12);
        assert!((below + 0.5).abs() < 1e-9, "{below}");
        assert_eq!(k.shape_derivative(2.0), 0.0);
    }
}
