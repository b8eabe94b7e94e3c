//! The error type of this crate.

use thiserror::Error;

/// Everything that can go wrong in a communication call.
///
/// Collective calls check their arguments locally before communicating, so a
/// rank that returns one of the argument errors has not entered the
/// collective; the caller should treat these as programming errors and stop
/// the run (the other ranks would otherwise wait forever).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum CommError {
    /// A destination rank outside `0..size`.
    #[error("rank {rank} is out of range for a communicator of size {size}")]
    InvalidRank {
        /// The offending rank.
        rank: usize,
        /// The communicator size.
        size: usize,
    },
    /// A per-rank count array whose length is not the communicator size.
    #[error("expected {expected} per-rank counts (the communicator size), got {got}")]
    CountsLength {
        /// The communicator size.
        expected: usize,
        /// The length that was passed.
        got: usize,
    },
    /// Per-rank counts that do not add up to the length of the data buffer.
    #[error(
        "per-rank counts add up to {counts_sum} but the send buffer holds {data_len} elements"
    )]
    CountsSum {
        /// Sum of the counts that were passed.
        counts_sum: usize,
        /// Length of the data buffer.
        data_len: usize,
    },
    /// A message or buffer longer than MPI's `int` counts can describe.
    #[error("{len} elements do not fit in an MPI count (at most {max})")]
    TooLarge {
        /// The requested length.
        len: usize,
        /// The largest supported length.
        max: usize,
    },
    /// A received message whose byte length is not a multiple of the element
    /// size (the sender used another element type).
    #[error("received {bytes} bytes from rank {source_rank}, not a multiple of the element size {elem_size}")]
    MessageSize {
        /// Rank that sent the message.
        source_rank: usize,
        /// Length of the message in bytes.
        bytes: usize,
        /// Size of the expected element type in bytes.
        elem_size: usize,
    },
    /// MPI was already initialised (by this crate or someone else).
    #[error("MPI is already initialised; call MpiComm::init once per process")]
    AlreadyInitialized,
    /// The MPI library does not provide the thread support this crate needs.
    #[error("MPI provides thread level {provided}, at least Funneled is needed")]
    ThreadLevel {
        /// The level the library provided.
        provided: String,
    },
}
