//! Errors of the gravity crate.

use sph_comm::CommError;
use sph_tree::TreeError;

/// What can go wrong when evaluating self-gravity.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GravityError {
    /// An input slice whose length differs from the number of particles
    /// (the length of `x`).
    #[error("slice {what} has {len} elements, expected {expected} (the length of x)")]
    LengthMismatch {
        /// Which slice (`"y"`, `"m"`, `"h"`, ...).
        what: &'static str,
        /// Its length.
        len: usize,
        /// The number of particles.
        expected: usize,
    },
    /// An opening angle that is not a finite positive number.
    #[error("opening angle theta must be finite and > 0, got {0}")]
    InvalidTheta(f64),
    /// A gravitational constant that is not finite.
    #[error("gravitational constant G must be finite, got {0}")]
    InvalidG(f64),
    /// A target group size of zero.
    #[error("group size must be at least 1, got {0}")]
    InvalidGroupSize(usize),
    /// A box with a periodic axis: periodic gravity needs Ewald summation,
    /// which is not implemented.
    #[error(
        "the box is periodic along axis {axis}; tree gravity supports open boundaries only \
         (periodic self-gravity needs Ewald summation)"
    )]
    PeriodicBox {
        /// The first periodic axis (0 = x, 1 = y, 2 = z).
        axis: usize,
    },
    /// A non-finite coordinate, mass or smoothing length.
    #[error("particle {index} has a non-finite {what}: {value}")]
    NonFinite {
        /// Index of the particle in the caller's order.
        index: usize,
        /// Which quantity (`"x"`, `"m"`, `"h"`, ...).
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A negative smoothing (softening) length.
    #[error("particle {index} has a negative smoothing length h = {value}")]
    NegativeSoftening {
        /// Index of the particle.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A tree built over a different number of particles than given.
    #[error("the octree was built over {tree} particles, but {particles} were given")]
    TreeMismatch {
        /// Particles in the tree.
        tree: usize,
        /// Particles given to the evaluation.
        particles: usize,
    },
    /// Target flags ([`Targets`](crate::Targets)) for another number of
    /// particles than given.
    #[error("{flags} target flags were given for {particles} particles")]
    TargetMismatch {
        /// Flags given.
        flags: usize,
        /// Particles given to the evaluation.
        particles: usize,
    },
    /// A drift bound that is negative or not finite.
    #[error("drift bound {0} must be a finite number >= 0")]
    InvalidDrift(f64),
    /// A softening scale that is negative or not finite.
    #[error("softening scale {0} must be a finite number >= 0")]
    InvalidSoftening(f64),
    /// Key ranges that do not describe a decomposition over the ranks:
    /// `bounds` key-range bounds for `ranks` ranks (`ranks + 1` needed).
    #[error("invalid decomposition: {bounds} key-range bounds for {ranks} ranks (need size + 1)")]
    InvalidDecomposition {
        /// The number of key-range bounds given.
        bounds: usize,
        /// The number of ranks.
        ranks: usize,
    },
    /// Communication between ranks failed.
    #[error(transparent)]
    Communication(#[from] CommError),
    /// An error of the tree crate (key computation or tree build).
    #[error(transparent)]
    Tree(#[from] TreeError),
}
