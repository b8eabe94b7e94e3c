//! SPH smoothing kernels for 3-D simulations, after the SPH-EXA mini-app.
//!
//! Every kernel is written as a dimensionless shape `w(v)` of `v = r/h` with
//! compact support `2h` and a normalisation constant `K`:
//!
//! ```text
//! W(r, h) = K / h^3 * w(r / h),      w(v) = 0 for v >= 2,
//! ∫ W d^3r = 1,   dW/dr = K/h^4 w'(v),   dW/dh = -K/h^4 (3 w(v) + v w'(v)).
//! ```
//!
//! Built-in kernels (all implementing [`Kernel`]):
//!
//! * [`Sinc`]: the sinc family `S_n(v) = [sin(pi v/2)/(pi v/2)]^n` for any
//!   real `n >= 1`; `n = 6` is the SPH-EXA default. `K_n` is computed
//!   numerically at construction.
//! * [`CubicSpline`]: the M4 B-spline, `K = 1/pi`.
//! * [`WendlandC2`], [`WendlandC4`], [`WendlandC6`]: Wendland functions of
//!   `q = v/2`.
//! * [`Tabulated`]: any kernel (built-in or your own) sampled on a table of
//!   [`Tabulated::DEFAULT_POINTS`] nodes and evaluated by linear interpolation,
//!   as SPH-EXA does in its hot loops (no `sin`/`pow` per pair).
//!
//! [`KernelChoice`] names the built-ins for command lines (`sinc:6`, `m4`,
//! `wendland-c4`, ...), and [`normalisation`] computes `K` for any shape.
//!
//! # Example
//!
//! ```
//! use sph_kernels::{normalisation, Kernel, KernelChoice, Sinc, Tabulated};
//!
//! // (1) The default sinc kernel, exactly and through a lookup table.
//! let exact = Sinc::new(6.0)?;
//! let table = Tabulated::new(&exact, Tabulated::DEFAULT_POINTS)?;
//! assert!((exact.norm() - 0.790450).abs() < 1e-5);
//! let (w, dw) = table.shape_and_derivative(0.7);
//! assert!((w - exact.shape(0.7)).abs() < 1e-8);
//! assert!((dw - exact.shape_derivative(0.7)).abs() < 1e-7);
//! // Dimensional values for a pair at distance r with smoothing length h.
//! let (r, h) = (0.012, 0.01);
//! assert!((table.w(r, h) - exact.w(r, h)).abs() < 1e-6 * exact.w(0.0, h));
//! assert_eq!(exact.w(2.0 * h, h), 0.0);
//! // The same, chosen by name.
//! let from_cli: KernelChoice = "sinc:6".parse()?;
//! assert_eq!(from_cli.tabulate(Tabulated::DEFAULT_POINTS)?.norm(), exact.norm());
//!
//! // (2) Your own kernel: a Gaussian truncated at v = 2.
//! #[derive(Debug, Clone, Copy)]
//! struct TruncatedGaussian {
//!     norm: f64,
//! }
//!
//! impl TruncatedGaussian {
//!     fn new() -> Self {
//!         Self { norm: normalisation(|v| (-v * v).exp(), 2.0) }
//!     }
//! }
//!
//! impl Kernel for TruncatedGaussian {
//!     fn shape(&self, v: f64) -> f64 {
//!         if v < 2.0 { (-v * v).exp() } else { 0.0 }
//!     }
//!     fn shape_derivative(&self, v: f64) -> f64 {
//!         if v < 2.0 { -2.0 * v * (-v * v).exp() } else { 0.0 }
//!     }
//!     fn norm(&self) -> f64 {
//!         self.norm
//!     }
//! }
//!
//! let gauss = TruncatedGaussian::new();
//! let gauss_table = Tabulated::new(&gauss, Tabulated::DEFAULT_POINTS)?;
//! assert!((gauss_table.shape(1.3) - gauss.shape(1.3)).abs() < 1e-8);
//! assert_eq!(gauss_table.norm(), gauss.norm());
//! # Ok::<(), sph_kernels::KernelError>(())
//! ```

mod choice;
mod error;
mod fast;
mod gauss;
mod kernel;
pub mod lanes;
mod poly;
mod power;
mod sinc;
mod single;
mod spline;
mod table;
mod wendland;

pub use choice::KernelChoice;
pub use error::KernelError;
pub use fast::FastKernel;
pub use kernel::{normalisation, Kernel, LANES};
pub use lanes::{F64s, Lane, Mask};
pub use poly::{FitVariable, Polynomial};
pub use power::PowerPolynomial;
pub use sinc::Sinc;
pub use single::SinglePower;
pub use spline::CubicSpline;
pub use table::Tabulated;
pub use wendland::{WendlandC2, WendlandC4, WendlandC6};
