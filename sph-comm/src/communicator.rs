//! The [`Communicator`] trait.

use crate::{CommError, Plain, ReduceOp, Reducible};

/// Messages received by [`Communicator::sparse_exchange`]: `(source rank, data)`
/// in ascending source-rank order.
pub type Received<T> = Vec<(usize, Vec<T>)>;

/// Data and per-source counts returned by [`Communicator::all_to_all_v`] and
/// [`Communicator::all_gather_v`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Gathered<T> {
    /// The received elements, grouped by source rank in ascending order.
    pub data: Vec<T>,
    /// `counts[r]` elements of `data` came from rank `r` (length: the size).
    pub counts: Vec<usize>,
}

impl<T> Gathered<T> {
    /// The elements that came from rank `r`.
    ///
    /// # Panics
    /// If `r` is not below the communicator size.
    pub fn from_rank(&self, r: usize) -> &[T] {
        let start: usize = self.counts[..r].iter().sum();
        &self.data[start..start + self.counts[r]]
    }
}

/// What every piece of the solver needs from the parallel environment.
///
/// Implemented by [`crate::SerialComm`] (one rank, always available),
/// [`crate::ThreadComm`] (several ranks as threads of one process, for tests)
/// and, with the cargo feature `mpi`, by `MpiComm`. The trait requires `Send + Sync` so
/// that code running rayon loops can hold a reference to it; the methods
/// themselves must only be called from one thread at a time (the thread that
/// drives the time step), never from inside a rayon loop.
///
/// All methods except [`rank`](Self::rank) and [`size`](Self::size) are
/// collective: every rank must call them in the same order.
pub trait Communicator: Send + Sync {
    /// This process's rank, in `0..size()`.
    fn rank(&self) -> usize;

    /// Number of ranks.
    fn size(&self) -> usize;

    /// Waits until every rank has called `barrier`.
    fn barrier(&self);

    /// Whether this rank may be driven from a worker of the process's
    /// rayon pool rather than only from the thread that made it: where the
    /// rank is alone in its process and any thread may call it. A loop of
    /// many short parallel stages runs faster there (a stage started from
    /// outside the pool wakes a worker and sleeps until the stage ends).
    /// Ranks that share one pool must not: a rank blocked in a collective
    /// would hold a worker that its partners may need. `false` unless an
    /// implementation knows better.
    fn may_drive_from_pool(&self) -> bool {
        false
    }

    /// Replaces `buf[i]`, on every rank, by the reduction over all ranks of
    /// their `buf[i]`. All ranks must pass slices of the same length.
    ///
    /// A floating-point [`ReduceOp::Sum`] is rounded in an order that depends
    /// on the rank count; use [`crate::ExactSum`] for reproducible sums.
    fn all_reduce<T: Reducible>(&self, buf: &mut [T], op: ReduceOp);

    /// The reduction of one value over all ranks.
    fn all_reduce_scalar<T: Reducible>(&self, value: T, op: ReduceOp) -> T {
        let mut buf = [value];
        self.all_reduce(&mut buf, op);
        buf[0]
    }

    /// Sparse point-to-point exchange: this rank sends each `(dest, data)` of
    /// `sends` to rank `dest` (itself included, empty messages allowed) and
    /// receives every message that any rank sends to it, without knowing
    /// beforehand who sends.
    ///
    /// The result lists `(source, data)` in ascending source rank; several
    /// messages from one source keep the order in which that source listed
    /// them. The result is therefore deterministic.
    ///
    /// # Errors
    /// [`CommError::InvalidRank`] if a destination is not below `size()`
    /// (checked before anything is sent), [`CommError::TooLarge`] for a
    /// message over `i32::MAX` elements, [`CommError::MessageSize`] if a peer
    /// sent another element type.
    fn sparse_exchange<T: Plain, S: AsRef<[T]>>(
        &self,
        sends: &[(usize, S)],
    ) -> Result<Received<T>, CommError>;

    /// All-to-all with variable counts: the first `send_counts[0]` elements of
    /// `send` go to rank 0, the next `send_counts[1]` to rank 1, and so on.
    /// Returns what every rank sent to this one, grouped by source rank.
    ///
    /// # Errors
    /// [`CommError::CountsLength`] if `send_counts.len() != size()`,
    /// [`CommError::CountsSum`] if the counts do not add up to `send.len()`,
    /// [`CommError::TooLarge`] beyond MPI's `int` counts.
    fn all_to_all_v<T: Plain>(
        &self,
        send: &[T],
        send_counts: &[usize],
    ) -> Result<Gathered<T>, CommError>;

    /// Gathers every rank's `send` (lengths may differ) on every rank, in
    /// rank order.
    ///
    /// # Errors
    /// [`CommError::TooLarge`] beyond MPI's `int` counts.
    fn all_gather_v<T: Plain>(&self, send: &[T]) -> Result<Gathered<T>, CommError>;

    /// Gathers one value per rank, in rank order.
    fn all_gather_scalar<T: Plain>(&self, value: T) -> Vec<T> {
        self.all_gather_v(&[value])
            .expect("one element per rank always fits")
            .data
    }
}

/// Checks an all-to-all-v argument list.
pub(crate) fn check_counts(
    size: usize,
    data_len: usize,
    counts: &[usize],
) -> Result<(), CommError> {
    if counts.len() != size {
        return Err(CommError::CountsLength {
            expected: size,
            got: counts.len(),
        });
    }
    let counts_sum: usize = counts.iter().sum();
    if counts_sum != data_len {
        return Err(CommError::CountsSum {
            counts_sum,
            data_len,
        });
    }
    Ok(())
}

/// Checks that every destination is a valid rank.
pub(crate) fn check_dests<S>(size: usize, sends: &[(usize, S)]) -> Result<(), CommError> {
    match sends.iter().find(|(d, _)| *d >= size) {
        Some(&(rank, _)) => Err(CommError::InvalidRank { rank, size }),
        None => Ok(()),
    }
}

/// A shared reference to a communicator is a communicator, so code can store
/// `&C` where it expects `C: Communicator`.
impl<C: Communicator> Communicator for &C {
    fn rank(&self) -> usize {
        (**self).rank()
    }

    fn size(&self) -> usize {
        (**self).size()
    }

    fn barrier(&self) {
        (**self).barrier()
    }

    fn all_reduce<T: Reducible>(&self, buf: &mut [T], op: ReduceOp) {
        (**self).all_reduce(buf, op)
    }

    fn sparse_exchange<T: Plain, S: AsRef<[T]>>(
        &self,
        sends: &[(usize, S)],
    ) -> Result<Received<T>, CommError> {
        (**self).sparse_exchange(sends)
    }

    fn all_to_all_v<T: Plain>(
        &self,
        send: &[T],
        send_counts: &[usize],
    ) -> Result<Gathered<T>, CommError> {
        (**self).all_to_all_v(send, send_counts)
    }

    fn all_gather_v<T: Plain>(&self, send: &[T]) -> Result<Gathered<T>, CommError> {
        (**self).all_gather_v(send)
    }
}
