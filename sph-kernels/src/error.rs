//! The one error type of the crate.

use std::num::ParseFloatError;

/// Everything that can go wrong when building or choosing a kernel.
#[derive(thiserror::Error, Debug, Clone, PartialEq)]
pub enum KernelError {
    /// The sinc exponent `n` is not a finite number in the allowed range.
    #[error(
        "sinc exponent n = {n} is out of range: a finite n with {min} <= n <= {max} is required"
    )]
    SincExponent {
        /// The rejected exponent.
        n: f64,
        /// Smallest allowed exponent ([`crate::Sinc::MIN_EXPONENT`]).
        min: f64,
        /// Largest allowed exponent ([`crate::Sinc::MAX_EXPONENT`]).
        max: f64,
    },

    /// A lookup table was asked for with too few points.
    #[error("a kernel table needs at least {min} points, got {points}")]
    TooFewPoints {
        /// The requested number of points.
        points: usize,
        /// The minimum ([`crate::Tabulated::MIN_POINTS`]).
        min: usize,
    },

    /// A lookup table was asked for with more points than it can index.
    #[error("a kernel table holds at most {max} points, got {points}")]
    TooManyPoints {
        /// The requested number of points.
        points: usize,
        /// The maximum ([`crate::Tabulated::MAX_POINTS`]).
        max: usize,
    },

    /// A kernel reported a support radius that is not finite and positive.
    #[error("kernel support radius must be finite and > 0, got {support}")]
    InvalidSupport {
        /// The rejected support radius (in units of h).
        support: f64,
    },

    /// A kernel returned a non-finite shape or derivative while being tabulated.
    #[error("kernel shape or derivative is not finite at v = {v} (w = {w}, dw/dv = {dw})")]
    NonFinite {
        /// Where the kernel was evaluated.
        v: f64,
        /// The shape value returned there.
        w: f64,
        /// The derivative returned there.
        dw: f64,
    },

    /// No polynomial up to the largest degree reproduces the kernel to the
    /// asked accuracy ([`crate::Polynomial::fit`]).
    #[error("no polynomial of degree <= {max_degree} reproduces the kernel to {tolerance:e} of its scale")]
    NoPolynomialFit {
        /// The relative accuracy asked for.
        tolerance: f64,
        /// The largest degree tried.
        max_degree: usize,
    },

    /// A kernel name that [`crate::KernelChoice`] does not know.
    #[error("unknown kernel \"{name}\"; allowed: {allowed}")]
    UnknownKernel {
        /// The name as given.
        name: String,
        /// The accepted names, comma separated.
        allowed: String,
    },

    /// The number after `sinc:` could not be parsed.
    #[error(
        "bad sinc exponent \"{text}\" in \"{input}\" (expected e.g. sinc:6 or sinc:5.5): {source}"
    )]
    BadSincNumber {
        /// The text after `sinc:`.
        text: String,
        /// The whole kernel specification.
        input: String,
        /// Why the number did not parse.
        source: ParseFloatError,
    },
}
