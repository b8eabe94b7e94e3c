//! Errors of the tree crate.

/// What can go wrong when building boxes, trees or neighbour lists.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TreeError {
    /// A box with `lo >= hi` (or non-finite bounds) along an axis.
    #[error("invalid bounding box along axis {axis}: lo = {lo}, hi = {hi} (need finite lo < hi)")]
    InvalidBox {
        /// The axis (0 = x, 1 = y, 2 = z).
        axis: usize,
        /// Lower bound given.
        lo: f64,
        /// Upper bound given.
        hi: f64,
    },
    /// Coordinate slices of different lengths.
    #[error("coordinate arrays differ in length: x has {x}, y has {y}, z has {z}{extra}")]
    LengthMismatch {
        /// Length of x.
        x: usize,
        /// Length of y.
        y: usize,
        /// Length of z.
        z: usize,
        /// Description of any other mismatching array.
        extra: String,
    },
    /// More particles than 32-bit neighbour indices can address.
    #[error("{0} particles exceed the 2^32 - 1 limit of the u32 neighbour indices")]
    TooManyParticles(usize),
    /// A bucket size of zero.
    #[error("bucket size must be at least 1, got {0}")]
    InvalidBucketSize(usize),
    /// A non-finite coordinate or smoothing length.
    #[error("particle {index} has a non-finite {what}: {value}")]
    NonFinite {
        /// Local index of the particle.
        index: usize,
        /// Which quantity (`"x"`, `"h"`, ...).
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A search radius that would see a periodic image of itself twice.
    #[error(
        "search radius {radius} of particle {index} exceeds half the periodic box length \
         {half_length} along axis {axis}; minimum-image search needs radius <= L/2"
    )]
    RadiusTooLarge {
        /// Local index of the particle.
        index: usize,
        /// Its search radius.
        radius: f64,
        /// The periodic axis.
        axis: usize,
        /// Half the box length along that axis.
        half_length: f64,
    },
}
