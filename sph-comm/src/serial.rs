//! The one-rank communicator.

use crate::communicator::{check_counts, check_dests};
use crate::{CommError, Communicator, Gathered, Plain, Received, ReduceOp, Reducible};

/// A communicator with exactly one rank (rank 0). Reductions are the
/// identity, and messages sent to rank 0 come back to the sender.
///
/// ```
/// use sph_comm::{Communicator, SerialComm};
/// let comm = SerialComm::new();
/// let got = comm.sparse_exchange(&[(0, vec![1u64, 2])]).unwrap();
/// assert_eq!(got, vec![(0, vec![1, 2])]);
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SerialComm;

impl SerialComm {
    /// The serial communicator.
    pub const fn new() -> Self {
        SerialComm
    }
}

impl Communicator for SerialComm {
    fn rank(&self) -> usize {
        0
    }

    fn size(&self) -> usize {
        1
    }

    fn barrier(&self) {}

    fn may_drive_from_pool(&self) -> bool {
        true
    }

    fn all_reduce<T: Reducible>(&self, _buf: &mut [T], _op: ReduceOp) {}

    fn sparse_exchange<T: Plain, S: AsRef<[T]>>(
        &self,
        sends: &[(usize, S)],
    ) -> Result<Received<T>, CommError> {
        check_dests(1, sends)?;
        Ok(sends
            .iter()
            .map(|(_, s)| (0, s.as_ref().to_vec()))
            .collect())
    }

    fn all_to_all_v<T: Plain>(
        &self,
        send: &[T],
        send_counts: &[usize],
    ) -> Result<Gathered<T>, CommError> {
        check_counts(1, send.len(), send_counts)?;
        Ok(Gathered {
            data: send.to_vec(),
            counts: vec![send.len()],
        })
    }

    fn all_gather_v<T: Plain>(&self, send: &[T]) -> Result<Gathered<T>, CommError> {
        Ok(Gathered {
            data: send.to_vec(),
            counts: vec![send.len()],
        })
    }
}
