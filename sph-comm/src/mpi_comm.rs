//! The MPI communicator (cargo feature `mpi`).

use std::sync::{Mutex, MutexGuard};
use std::thread::{self, ThreadId};

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::datatype::{Partition, PartitionMut};
use mpi::environment::Universe;
use mpi::point_to_point::{Destination, Message, Source, Status};
use mpi::request::{Request, Scope};
use mpi::topology::{Communicator as _, SimpleCommunicator};
use mpi::traits::Equivalence;
use mpi::{Count, Tag, Threading};

use crate::communicator::{check_counts, check_dests};
use crate::{CommError, Communicator, Gathered, Plain, Received, ReduceOp, Reducible};

/// The thread support level MPI was initialised with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThreadLevel {
    /// Only the thread that called [`MpiComm::init`] may call MPI; `MpiComm`
    /// panics when called from any other thread.
    Funneled,
    /// Any thread may call MPI, one at a time (`MpiComm` serialises its calls
    /// with a mutex).
    Serialized,
    /// Any thread, concurrently (still serialised by `MpiComm`).
    Multiple,
}

/// The communicator handle, only touched with the mutex held.
struct Inner {
    comm: SimpleCommunicator,
    /// Number of sparse exchanges so far; selects one of two tags.
    exchanges: u64,
}

// SAFETY: an MPI communicator handle is a process-wide identifier that is
// valid on every thread; rsmpi marks it !Send only because it wraps a raw
// pointer. `Inner` is only reached through `MpiComm::inner`, a mutex, so MPI
// is never called concurrently, and MPI was initialised with at least
// MPI_THREAD_SERIALIZED, or with MPI_THREAD_FUNNELED, in which case
// `MpiComm::lock` refuses every thread but the initialising one.
#[allow(unsafe_code)] // the workspace denies unsafe code; this is its one exception
unsafe impl Send for Inner {}

/// A [`Communicator`] over `MPI_COMM_WORLD` (a private duplicate of it, so
/// that its messages never match those of other libraries).
///
/// Create it once, at the start of `main`, with [`MpiComm::init`]; it owns the
/// MPI environment and finalises MPI when dropped, so drop it (on the same
/// thread) at the end of the run. Rayon worker threads may hold `&MpiComm`
/// but must not call it.
///
/// ```no_run
/// use sph_comm::{Communicator, MpiComm};
/// let comm = MpiComm::init().expect("MPI initialisation");
/// println!("rank {} of {}", comm.rank(), comm.size());
/// ```
pub struct MpiComm {
    // Field order matters: the duplicated communicator is freed before the
    // universe finalises MPI.
    inner: Mutex<Inner>,
    rank: usize,
    size: usize,
    level: ThreadLevel,
    init_thread: ThreadId,
    _universe: Universe,
}

impl std::fmt::Debug for MpiComm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MpiComm")
            .field("rank", &self.rank)
            .field("size", &self.size)
            .field("level", &self.level)
            .finish_non_exhaustive()
    }
}

/// The two tags that consecutive sparse exchanges alternate between. A rank
/// can be at most one exchange ahead of another (the Ibarrier of exchange k
/// completes only after every rank entered it), so two tags keep messages of
/// consecutive exchanges apart.
const EXCHANGE_TAGS: [Tag; 2] = [17, 18];

/// Largest element count of one MPI call.
const MAX_COUNT: usize = i32::MAX as usize;

fn to_count(len: usize) -> Result<Count, CommError> {
    Count::try_from(len).map_err(|_| CommError::TooLarge {
        len,
        max: MAX_COUNT,
    })
}

fn system_op(op: ReduceOp) -> SystemOperation {
    match op {
        ReduceOp::Sum => SystemOperation::sum(),
        ReduceOp::Min => SystemOperation::min(),
        ReduceOp::Max => SystemOperation::max(),
    }
}

/// Exclusive prefix sum of the counts (displacements).
fn displacements(counts: &[Count]) -> Result<Vec<Count>, CommError> {
    let mut displs = Vec::with_capacity(counts.len());
    let mut acc: usize = 0;
    for &c in counts {
        displs.push(to_count(acc)?);
        acc += c as usize;
    }
    to_count(acc)?;
    Ok(displs)
}

impl MpiComm {
    /// Initialises MPI (asking for `MPI_THREAD_SERIALIZED`) and returns the
    /// world communicator. Call it once per process.
    ///
    /// # Errors
    /// [`CommError::AlreadyInitialized`] on a second call (or if something
    /// else initialised MPI), [`CommError::ThreadLevel`] if the library only
    /// supports `MPI_THREAD_SINGLE`.
    pub fn init() -> Result<MpiComm, CommError> {
        let (universe, provided) = mpi::initialize_with_threading(Threading::Serialized)
            .ok_or(CommError::AlreadyInitialized)?;
        let level = match provided {
            Threading::Single => {
                return Err(CommError::ThreadLevel {
                    provided: format!("{provided:?}"),
                })
            }
            Threading::Funneled => ThreadLevel::Funneled,
            Threading::Serialized => ThreadLevel::Serialized,
            Threading::Multiple => ThreadLevel::Multiple,
        };
        let comm = universe.world().duplicate();
        let rank = comm.rank() as usize;
        let size = comm.size() as usize;
        Ok(MpiComm {
            inner: Mutex::new(Inner { comm, exchanges: 0 }),
            rank,
            size,
            level,
            init_thread: thread::current().id(),
            _universe: universe,
        })
    }

    /// The thread support level that MPI provided.
    pub fn thread_level(&self) -> ThreadLevel {
        self.level
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        if self.level == ThreadLevel::Funneled {
            assert_eq!(
                thread::current().id(),
                self.init_thread,
                "MPI provides only MPI_THREAD_FUNNELED: call MpiComm from the thread that initialised it"
            );
        }
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Aborts the whole MPI job after an error that the ranks cannot agree on.
fn abort(comm: &SimpleCommunicator, what: &str, e: &CommError) -> ! {
    eprintln!("sph-comm: {what}: {e}; aborting all ranks");
    comm.abort(1)
}

/// Receives a matched message as a vector of `T`, checking its size.
fn receive_matched<T: Plain>(msg: Message, status: Status) -> Result<(usize, Vec<T>), CommError> {
    let source_rank = status.source_rank() as usize;
    let count = status.count(T::equivalent_datatype());
    if count >= 0 {
        let mut buf = vec![T::default(); count as usize];
        msg.matched_receive_into(&mut buf[..]);
        Ok((source_rank, buf))
    } else {
        // MPI_UNDEFINED: not a whole number of T. Drain it as bytes.
        let bytes = status.count(u8::equivalent_datatype()).max(0) as usize;
        let mut buf = vec![0u8; bytes];
        msg.matched_receive_into(&mut buf[..]);
        Err(CommError::MessageSize {
            source_rank,
            bytes,
            elem_size: std::mem::size_of::<T>(),
        })
    }
}

/// Tests the pending sends, keeping those not yet complete.
fn test_sends<'a, T, S: Scope<'a>>(pending: Vec<Request<'a, [T], S>>) -> Vec<Request<'a, [T], S>> {
    pending.into_iter().filter_map(|r| r.test().err()).collect()
}

impl Communicator for MpiComm {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn barrier(&self) {
        self.lock().comm.barrier();
    }

    /// One rank per process; any thread may call it unless MPI gave only
    /// `MPI_THREAD_FUNNELED`.
    fn may_drive_from_pool(&self) -> bool {
        self.level != ThreadLevel::Funneled
    }

    fn all_reduce<T: Reducible>(&self, buf: &mut [T], op: ReduceOp) {
        if buf.is_empty() {
            return;
        }
        assert!(
            buf.len() <= MAX_COUNT,
            "all_reduce of more than i32::MAX elements"
        );
        let send = buf.to_vec();
        self.lock()
            .comm
            .all_reduce_into(&send[..], buf, system_op(op));
    }

    /// NBX: `MPI_Issend` to every destination, then alternately drain
    /// arrived messages (`MPI_Improbe`/`MPI_Mrecv`) and test progress: once all
    /// own sends are matched, enter an `MPI_Ibarrier`; when the barrier
    /// completes, every rank's sends were matched, so nothing more can arrive.
    /// Messages to self are copied locally.
    fn sparse_exchange<T: Plain, S: AsRef<[T]>>(
        &self,
        sends: &[(usize, S)],
    ) -> Result<Received<T>, CommError> {
        check_dests(self.size, sends)?;
        for (_, s) in sends {
            to_count(s.as_ref().len())?;
        }
        let mut inner = self.lock();
        let tag = EXCHANGE_TAGS[(inner.exchanges % 2) as usize];
        inner.exchanges += 1;
        let comm = &inner.comm;
        let me = self.rank;

        let mut received: Vec<(usize, Vec<T>)> = sends
            .iter()
            .filter(|(d, _)| *d == me)
            .map(|(_, s)| (me, s.as_ref().to_vec()))
            .collect();
        let mut first_error = None;

        mpi::request::scope(|scope| {
            let mut pending: Vec<Request<'_, [T], _>> = sends
                .iter()
                .filter(|(d, _)| *d != me)
                .map(|(d, s)| {
                    comm.process_at_rank(*d as i32)
                        .immediate_synchronous_send_with_tag(scope, s.as_ref(), tag)
                })
                .collect();
            let mut barrier: Option<Request<'static, ()>> = None;
            loop {
                while let Some((msg, status)) =
                    comm.any_process().immediate_matched_probe_with_tag(tag)
                {
                    match receive_matched::<T>(msg, status) {
                        Ok(m) => received.push(m),
                        Err(e) => {
                            first_error.get_or_insert(e);
                        }
                    }
                }
                match barrier.take() {
                    None => {
                        pending = test_sends(pending);
                        if pending.is_empty() {
                            barrier = Some(comm.immediate_barrier());
                        }
                    }
                    Some(b) => match b.test() {
                        Ok(_) => break,
                        Err(b) => barrier = Some(b),
                    },
                }
            }
        });
        drop(inner);
        if let Some(e) = first_error {
            return Err(e);
        }
        // Stable: messages of one source keep their (non-overtaking) order.
        received.sort_by_key(|(src, _)| *src);
        Ok(received)
    }

    fn all_to_all_v<T: Plain>(
        &self,
        send: &[T],
        send_counts: &[usize],
    ) -> Result<Gathered<T>, CommError> {
        check_counts(self.size, send.len(), send_counts)?;
        let scounts = send_counts
            .iter()
            .map(|&c| to_count(c))
            .collect::<Result<Vec<_>, _>>()?;
        let sdispls = displacements(&scounts)?;
        let inner = self.lock();
        let mut rcounts = vec![0 as Count; self.size];
        inner.comm.all_to_all_into(&scounts[..], &mut rcounts[..]);
        // Every rank checked its own sends; the receive total can still
        // overflow. Then the ranks disagree on whether to go on, so abort.
        let rdispls = match displacements(&rcounts) {
            Ok(d) => d,
            Err(e) => abort(&inner.comm, "all_to_all_v", &e),
        };
        let total: usize = rcounts.iter().map(|&c| c as usize).sum();
        let mut recv = vec![T::default(); total];
        {
            let sbuf = Partition::new(send, &scounts[..], &sdispls[..]);
            let mut rbuf = PartitionMut::new(&mut recv[..], &rcounts[..], &rdispls[..]);
            inner.comm.all_to_all_varcount_into(&sbuf, &mut rbuf);
        }
        Ok(Gathered {
            data: recv,
            counts: rcounts.iter().map(|&c| c as usize).collect(),
        })
    }

    fn all_gather_v<T: Plain>(&self, send: &[T]) -> Result<Gathered<T>, CommError> {
        let n = to_count(send.len())?;
        let inner = self.lock();
        let mut rcounts = vec![0 as Count; self.size];
        inner.comm.all_gather_into(&n, &mut rcounts[..]);
        let rdispls = match displacements(&rcounts) {
            Ok(d) => d,
            Err(e) => abort(&inner.comm, "all_gather_v", &e),
        };
        let total: usize = rcounts.iter().map(|&c| c as usize).sum();
        let mut recv = vec![T::default(); total];
        {
            let mut rbuf = PartitionMut::new(&mut recv[..], &rcounts[..], &rdispls[..]);
            inner.comm.all_gather_varcount_into(send, &mut rbuf);
        }
        Ok(Gathered {
            data: recv,
            counts: rcounts.iter().map(|&c| c as usize).collect(),
        })
    }
}
