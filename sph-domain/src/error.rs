//! Errors of the domain crate.

use sph_comm::CommError;
use sph_tree::TreeError;

/// What can go wrong while decomposing or exchanging.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DomainError {
    /// A global bucket size of zero.
    #[error("global bucket size must be at least 1, got {0}")]
    InvalidBucket(u64),
    /// A smoothing-length margin that is not a finite number `>= 1`.
    #[error("smoothing-length margin {0} must be a finite number >= 1")]
    InvalidHMargin(f64),
    /// No rank holds any particle.
    #[error("the domain is empty: no rank holds a particle")]
    Empty,
    /// A particle with a non-finite coordinate or smoothing length.
    #[error("particle {id} has a non-finite {what}: {value}")]
    NonFinite {
        /// Particle id.
        id: u64,
        /// Which quantity.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// A particle outside the box the caller promised holds them all.
    #[error("particle {id} lies at {value} on axis {axis}, outside the box [{lo}, {hi}]")]
    OutsideBox {
        /// Particle id.
        id: u64,
        /// The axis.
        axis: usize,
        /// Its coordinate.
        value: f64,
        /// Box bounds on that axis.
        lo: f64,
        /// Box bounds on that axis.
        hi: f64,
    },
    /// A halo message from a rank that is no peer of the last sync.
    #[error("halo message from rank {0}, which is not a peer of the last sync")]
    UnexpectedPeer(usize),
    /// A halo message of the wrong length.
    #[error("halo message from rank {peer} holds {got} values, expected {expected}")]
    Mismatch {
        /// Sending rank.
        peer: usize,
        /// Values expected.
        expected: usize,
        /// Values received.
        got: usize,
    },
    /// A subset halo message naming a halo the sender does not send to
    /// this rank (see [`Domain::exchange_where`](crate::Domain::exchange_where)).
    #[error("halo message from rank {peer} names halo {index}, but that rank sends {halos}")]
    HaloIndex {
        /// Sending rank.
        peer: usize,
        /// The index received (position in the sender's halo list).
        index: u64,
        /// Number of halos the peer sends to this rank.
        halos: usize,
    },
    /// Communication failed.
    #[error(transparent)]
    Comm(#[from] CommError),
    /// A box could not be built.
    #[error(transparent)]
    Tree(#[from] TreeError),
}
