//! The form a solver evaluates a kernel in: a polynomial where one is
//! faithful, else the lookup table.

use std::fmt;

use crate::kernel::Kernel;
use crate::{F64s, KernelError, Polynomial, PowerPolynomial, SinglePower, Tabulated};

/// A kernel prepared for the pair loops: [`PowerPolynomial`] for a power
/// of a smooth base ([`Kernel::power_of`]: the sinc family with integer
/// exponent), else [`Polynomial`] when one reproduces the kernel to
/// [`FastKernel::TOLERANCE`] of its scale (the Wendland kernels), else the
/// [`Tabulated`] lookup table (M4, whose second derivative jumps at
/// `v = 1`). The polynomial is both more accurate than the table (whose
/// interpolation error is ~1e-8) and, without gathers from memory,
/// faster: criterion `stages_1e5` on an AVX-512 machine, 2 threads,
/// table -> polynomial: density + grad-h 39 -> 19 ms, IAD 23 -> 18.5 ms,
/// momentum-energy 64 -> 42 ms.
///
/// ```
/// use sph_kernels::{CubicSpline, FastKernel, Kernel, Sinc};
/// let sinc = FastKernel::new(&Sinc::new(6.0)?)?;
/// assert!(matches!(sinc, FastKernel::Power(_)));
/// assert!((sinc.shape(0.5) - Sinc::new(6.0)?.shape(0.5)).abs() < 1e-9);
/// let m4 = FastKernel::new(&CubicSpline)?;
/// assert!(matches!(m4, FastKernel::Table(_)));
/// # Ok::<(), sph_kernels::KernelError>(())
/// ```
// The coefficients stay inline (no indirection in the pair loops); a run
// holds one of these.
#[allow(clippy::large_enum_variant)]
#[derive(Clone)]
pub enum FastKernel {
    /// An integer power of one polynomial over the support.
    Power(PowerPolynomial),
    /// The same power form evaluated in `f32` ([`FastKernel::single`]).
    Single(SinglePower),
    /// One polynomial over the support.
    Polynomial(Polynomial),
    /// Linear interpolation in a table of [`Tabulated::DEFAULT_POINTS`].
    Table(Tabulated),
}

impl FastKernel {
    /// Largest error of a polynomial form, relative to `max |w|` for the
    /// shape and to `max |w'|` for the derivative: ten times below the
    /// table's.
    pub const TOLERANCE: f64 = 1e-9;

    /// The polynomial form of `kernel` if one reaches
    /// [`TOLERANCE`](Self::TOLERANCE), else its table.
    ///
    /// # Errors
    /// As [`Tabulated::new`] (a support that is not finite and positive, a
    /// kernel that is not finite on its support).
    pub fn new<K: Kernel + ?Sized>(kernel: &K) -> Result<Self, KernelError> {
        if let Some((base, n)) = kernel.power_of() {
            if let Ok(p) = PowerPolynomial::fit(kernel, &*base, n, Self::TOLERANCE) {
                return Ok(Self::Power(p));
            }
        }
        match Polynomial::fit(kernel, Self::TOLERANCE) {
            Ok(p) => Ok(Self::Polynomial(p)),
            Err(KernelError::NoPolynomialFit { .. }) => Ok(Self::Table(Tabulated::new(
                kernel,
                Tabulated::DEFAULT_POINTS,
            )?)),
            Err(e) => Err(e),
        }
    }

    /// As [`new`](Self::new), but a power form evaluated in `f32`
    /// ([`SinglePower`], within [`SinglePower::TOLERANCE`] of the kernel);
    /// the pair loops' sums stay in `f64`. Faster in the pair loops
    /// (Sedov 50^3, 1 rank x 2 threads, AVX2: momentum -8 to -16%, 80^3
    /// -5 to -7%; Sedov L1 unchanged to 5 digits), but not the solver's
    /// default: its rounding seeds a mode that grows from round-off in the
    /// isobaric cube (kinetic energy e-folding every ~30 steps; the `f64`
    /// run's seed is 1e9 times smaller and stays below it to t = 1, the
    /// `f32` run's reaches it by t = 0.8: v_rms / c 0.0085 -> 0.0105 at 32
    /// thin particles per side).
    ///
    /// ```
    /// use sph_kernels::{FastKernel, Kernel, Sinc, SinglePower};
    /// let k = FastKernel::single(&Sinc::new(6.0)?)?;
    /// assert!(matches!(k, FastKernel::Single(_)));
    /// assert!((k.shape(0.5) - Sinc::new(6.0)?.shape(0.5)).abs() < SinglePower::TOLERANCE);
    /// # Ok::<(), sph_kernels::KernelError>(())
    /// ```
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn single<K: Kernel + ?Sized>(kernel: &K) -> Result<Self, KernelError> {
        Ok(match Self::new(kernel)? {
            Self::Power(p) => Self::Single(SinglePower::new(&p)),
            other => other,
        })
    }

    /// How the kernel is evaluated, for run reports: `power 6 of a
    /// polynomial of degree 7 in v^2`, `polynomial of degree d in v^2` or
    /// `table of 20000 points`.
    pub fn describe(&self) -> String {
        match self {
            Self::Power(p) => format!(
                "power {} of a polynomial of degree {} in v^2",
                p.power(),
                p.base().degree()
            ),
            Self::Single(p) => format!(
                "power {} of a polynomial of degree {} in v^2, in f32",
                p.power(),
                p.degree()
            ),
            Self::Polynomial(p) => format!(
                "polynomial of degree {} in {}",
                p.degree(),
                match p.variable() {
                    crate::FitVariable::Radius => "v",
                    crate::FitVariable::Square => "v^2",
                }
            ),
            Self::Table(t) => format!("table of {} points", t.points()),
        }
    }
}

impl fmt::Debug for FastKernel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Power(p) => p.fmt(f),
            Self::Single(p) => p.fmt(f),
            Self::Polynomial(p) => p.fmt(f),
            Self::Table(t) => t.fmt(f),
        }
    }
}

/// Forwards a method to the form in use.
macro_rules! either {
    ($self:ident, $k:ident => $e:expr) => {
        match $self {
            FastKernel::Power($k) => $e,
            FastKernel::Single($k) => $e,
            FastKernel::Polynomial($k) => $e,
            FastKernel::Table($k) => $e,
        }
    };
}

impl Kernel for FastKernel {
    #[inline]
    fn shape(&self, v: f64) -> f64 {
        either!(self, k => k.shape(v))
    }

    #[inline]
    fn shape_derivative(&self, v: f64) -> f64 {
        either!(self, k => k.shape_derivative(v))
    }

    #[inline]
    fn shape_and_derivative(&self, v: f64) -> (f64, f64) {
        either!(self, k => k.shape_and_derivative(v))
    }

    #[inline(always)]
    fn shape_lanes(&self, v: F64s) -> F64s {
        either!(self, k => k.shape_lanes(v))
    }

    #[inline(always)]
    fn shape_and_derivative_lanes(&self, v: F64s) -> (F64s, F64s) {
        either!(self, k => k.shape_and_derivative_lanes(v))
    }

    #[inline]
    fn derivative_over_v_sq(&self, v2: f64) -> f64 {
        either!(self, k => k.derivative_over_v_sq(v2))
    }

    #[inline(always)]
    fn derivative_over_v_sq_lanes(&self, v2: F64s) -> F64s {
        either!(self, k => k.derivative_over_v_sq_lanes(v2))
    }

    #[inline]
    fn shape_sq(&self, v2: f64) -> f64 {
        either!(self, k => k.shape_sq(v2))
    }

    #[inline]
    fn shape_and_v_derivative_sq(&self, v2: f64) -> (f64, f64) {
        either!(self, k => k.shape_and_v_derivative_sq(v2))
    }

    #[inline(always)]
    fn shape_sq_lanes(&self, v2: F64s) -> F64s {
        either!(self, k => k.shape_sq_lanes(v2))
    }

    #[inline(always)]
    fn shape_and_v_derivative_sq_lanes(&self, v2: F64s) -> (F64s, F64s) {
        either!(self, k => k.shape_and_v_derivative_sq_lanes(v2))
    }

    #[inline]
    fn support(&self) -> f64 {
        either!(self, k => k.support())
    }

    #[inline]
    fn norm(&self) -> f64 {
        either!(self, k => k.norm())
    }
}
