//! An in-process communicator whose ranks are threads ([`ThreadComm`],
//! started by [`run_ranks`]).
//!
//! # Design
//! Every collective call is one round of a shared "deposit and collect"
//! step: each rank puts its contribution (the buffer to reduce, its list of
//! outgoing messages, ...) into its slot of a shared table under a mutex;
//! the last rank to arrive publishes the complete table as round
//! `generation` and wakes the others (a condition variable). Every rank then
//! reads what concerns it from the published table, in rank order, so all
//! results are deterministic. Published tables alternate between two
//! buffers: a rank can be at most one round ahead of another (round `g + 1`
//! completes only after every rank has left round `g`), so the table of
//! round `g` stays readable until every rank has read it.
//!
//! Contributions are type-erased (`Box<dyn Any>`); every rank checks that all
//! ranks made the same call (collective, element type, reduction and length)
//! and panics otherwise, since MPI would deadlock or corrupt data there.
//!
//! A panicking rank marks the shared state as poisoned; ranks waiting in a
//! collective, or entering one later, panic as well, and [`run_ranks`]
//! re-raises the first panic. A rank that returns from its closure while
//! others wait in a collective that it will never join makes them panic
//! too, so a mismatched number of collective calls fails instead of hanging.

use std::any::{type_name, Any};
use std::fmt;
use std::mem::size_of;
use std::panic::{self, AssertUnwindSafe};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::thread;

use crate::communicator::{check_counts, check_dests};
use crate::{CommError, Communicator, Gathered, Plain, Received, ReduceOp, Reducible};

/// Largest element count of one call (MPI's `int` counts), enforced so that
/// code tested with [`ThreadComm`] also runs with `MpiComm`.
const MAX_COUNT: usize = i32::MAX as usize;

fn check_len(len: usize) -> Result<(), CommError> {
    if len > MAX_COUNT {
        Err(CommError::TooLarge {
            len,
            max: MAX_COUNT,
        })
    } else {
        Ok(())
    }
}

/// Which collective a rank entered; all ranks of a round must agree.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Collective {
    Barrier,
    AllReduce {
        op: ReduceOp,
        len: usize,
        elem: &'static str,
    },
    SparseExchange,
    AllToAllV {
        elem: &'static str,
    },
    AllGatherV {
        elem: &'static str,
    },
}

/// What one rank deposits in a round.
struct Contribution {
    what: Collective,
    data: Box<dyn Any + Send + Sync>,
}

impl Contribution {
    fn get<D: 'static>(&self) -> &D {
        self.data
            .downcast_ref::<D>()
            .expect("contributions of one round have the same type")
    }
}

/// One message of a sparse exchange (`data` is a `Vec<T>` of the sender's
/// element type).
struct Message {
    dest: usize,
    bytes: usize,
    data: Box<dyn Any + Send + Sync>,
}

/// The state shared by the ranks, behind [`Shared::state`].
struct State {
    /// Number of completed rounds.
    generation: u64,
    /// Contributions to the current round, by rank.
    pending: Vec<Option<Contribution>>,
    /// Number of `Some` in `pending`.
    arrived: usize,
    /// Published tables of the last two rounds, indexed by `round % 2`.
    done: [Option<Arc<Vec<Contribution>>>; 2],
    /// The first rank that panicked.
    panicked: Option<usize>,
    /// Ranks whose closure has returned.
    returned: Vec<bool>,
}

struct Shared {
    size: usize,
    state: Mutex<State>,
    turn: Condvar,
}

impl Shared {
    fn new(size: usize) -> Self {
        Shared {
            size,
            state: Mutex::new(State {
                generation: 0,
                pending: (0..size).map(|_| None).collect(),
                arrived: 0,
                done: [None, None],
                panicked: None,
                returned: vec![false; size],
            }),
            turn: Condvar::new(),
        }
    }

    /// Locks the state. Ranks never panic with the lock held, but a
    /// poisoned mutex is harmless here anyway: poisoning is tracked in
    /// [`State::panicked`].
    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Records that `rank` left its closure (by panicking or returning) and
    /// wakes the waiting ranks so that they notice.
    fn finish(&self, rank: usize, panicked: bool) {
        let mut st = self.lock();
        if panicked {
            st.panicked.get_or_insert(rank);
        } else {
            st.returned[rank] = true;
        }
        drop(st);
        self.turn.notify_all();
    }
}

/// One rank of an in-process communicator: every rank is an OS thread started
/// by [`run_ranks`], and the ranks talk through shared memory.
///
/// It implements [`Communicator`] with the semantics documented there, so
/// multi-rank code (domain decomposition, halo exchange, distributed
/// gravity) can be tested with 2, 4 or more ranks in a plain `cargo test`,
/// without MPI:
///
/// * [`all_reduce`](Communicator::all_reduce) combines the ranks' buffers in
///   rank order (`((b0 op b1) op b2) ...`), so a floating-point sum is
///   deterministic and every rank gets the same bits. Integer sums wrap.
///   `Min`/`Max` of a NaN are unspecified, as with MPI.
/// * [`sparse_exchange`](Communicator::sparse_exchange),
///   [`all_to_all_v`](Communicator::all_to_all_v) and
///   [`all_gather_v`](Communicator::all_gather_v) return exactly what
///   `MpiComm` returns, with the same argument errors (checked before the
///   rank enters the collective) and the same `i32::MAX` element limit.
///   A message of another element type is reported as
///   [`CommError::MessageSize`] whatever its length (MPI only notices when
///   its byte length is not a multiple of the element size).
///
/// Misuse that would hang or corrupt an MPI run panics instead: ranks
/// entering different collectives (or the same one with different element
/// types, reduction operations or `all_reduce` lengths), a rank returning
/// while others wait for it, one handle used from two threads at once. A
/// panic on any rank releases the others (they panic too) and
/// [`run_ranks`] re-raises it.
///
/// Like every communicator, a handle may be shared with rayon loops (it is
/// `Send + Sync`) but its methods must be called by one thread at a time,
/// never from inside a rayon loop. The ranks share rayon's global pool.
///
/// ```
/// use sph_comm::{run_ranks, Communicator, ReduceOp};
/// let sums = run_ranks(2, |comm| comm.all_reduce_scalar(comm.rank(), ReduceOp::Sum));
/// assert_eq!(sums, vec![1, 1]);
/// ```
pub struct ThreadComm {
    rank: usize,
    shared: Arc<Shared>,
}

impl fmt::Debug for ThreadComm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ThreadComm")
            .field("rank", &self.rank)
            .field("size", &self.shared.size)
            .finish_non_exhaustive()
    }
}

/// Runs `f` on `size` ranks, each an OS thread with its own [`ThreadComm`]
/// (rank `r` of `size`), and returns the ranks' results in rank order.
///
/// The threads are scoped, so `f` may borrow from the caller; they are named
/// `rank 0`, `rank 1`, ... If a rank panics, the ranks that wait for it in a
/// collective (or call one later) panic too instead of hanging, and
/// `run_ranks` resumes the first panic once every thread has finished.
///
/// # Panics
/// If `size` is 0, if a thread cannot be spawned, or if a rank panicked.
///
/// ```
/// use sph_comm::{run_ranks, Communicator, ReduceOp};
/// let out = run_ranks(2, |comm| {
///     let total = comm.all_reduce_scalar(comm.rank() as u64, ReduceOp::Sum);
///     (comm.rank(), total)
/// });
/// assert_eq!(out, vec![(0, 1), (1, 1)]);
/// ```
pub fn run_ranks<R, F>(size: usize, f: F) -> Vec<R>
where
    R: Send,
    F: Fn(ThreadComm) -> R + Sync,
{
    assert!(size > 0, "run_ranks needs at least one rank");
    let shared = Arc::new(Shared::new(size));
    let mut results: Vec<thread::Result<R>> = thread::scope(|s| {
        let mut handles = Vec::with_capacity(size);
        for rank in 0..size {
            let comm = ThreadComm {
                rank,
                shared: Arc::clone(&shared),
            };
            let (f, shared) = (&f, &shared);
            let spawned = thread::Builder::new()
                .name(format!("rank {rank}"))
                .spawn_scoped(s, move || {
                    let r = panic::catch_unwind(AssertUnwindSafe(|| f(comm)));
                    shared.finish(rank, r.is_err());
                    r
                });
            match spawned {
                Ok(h) => handles.push(h),
                Err(e) => {
                    // Release the ranks already started before the scope
                    // joins them.
                    shared.finish(rank, true);
                    panic!("run_ranks: cannot spawn the thread of rank {rank}: {e}");
                }
            }
        }
        handles
            .into_iter()
            .map(|h| h.join().and_then(|r| r))
            .collect()
    });
    if results.iter().any(Result::is_err) {
        let origin = shared.lock().panicked;
        let r = origin
            .filter(|&r| results[r].is_err())
            .or_else(|| results.iter().position(Result::is_err))
            .expect("some rank failed");
        if let Err(payload) = results.swap_remove(r) {
            panic::resume_unwind(payload);
        }
        unreachable!("rank {r} failed");
    }
    results.into_iter().flatten().collect()
}

impl ThreadComm {
    /// Deposits this rank's contribution to the next round and returns the
    /// table of all ranks' contributions once every rank has deposited.
    fn round(&self, what: Collective, data: Box<dyn Any + Send + Sync>) -> Arc<Vec<Contribution>> {
        let me = self.rank;
        let sh = &*self.shared;
        let mut st = sh.lock();
        if let Some(r) = st.panicked {
            drop(st);
            panic!("rank {me}: rank {r} panicked; not entering {what:?}");
        }
        if st.pending[me].is_some() {
            drop(st);
            panic!("the ThreadComm of rank {me} was called from two threads at once");
        }
        let gen = st.generation;
        st.pending[me] = Some(Contribution { what, data });
        st.arrived += 1;
        if st.arrived == sh.size {
            let table: Vec<Contribution> = st
                .pending
                .iter_mut()
                .map(|c| c.take().expect("every rank has deposited"))
                .collect();
            st.arrived = 0;
            st.done[(gen % 2) as usize] = Some(Arc::new(table));
            st.generation += 1;
            sh.turn.notify_all();
        } else {
            while st.generation == gen {
                if let Some(r) = st.panicked {
                    drop(st);
                    panic!("rank {me}: rank {r} panicked while this rank waits in {what:?}");
                }
                if let Some(r) = st.returned.iter().position(|&x| x) {
                    drop(st);
                    panic!(
                        "rank {me} waits in {what:?} but rank {r} has returned from its closure \
                         (all ranks must make the same collective calls)"
                    );
                }
                st = sh.turn.wait(st).unwrap_or_else(PoisonError::into_inner);
            }
        }
        let table = Arc::clone(
            st.done[(gen % 2) as usize]
                .as_ref()
                .expect("a completed round is published"),
        );
        drop(st);
        if let Some((r, c)) = table.iter().enumerate().find(|(_, c)| c.what != what) {
            panic!(
                "collective mismatch: rank {me} called {what:?} while rank {r} called {:?}",
                c.what
            );
        }
        table
    }
}

impl Communicator for ThreadComm {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.shared.size
    }

    fn barrier(&self) {
        self.round(Collective::Barrier, Box::new(()));
    }

    /// Combines the buffers in rank order; see [`ThreadComm`].
    fn all_reduce<T: Reducible>(&self, buf: &mut [T], op: ReduceOp) {
        // Like MpiComm: an empty reduction does not communicate.
        if buf.is_empty() {
            return;
        }
        assert!(
            buf.len() <= MAX_COUNT,
            "all_reduce of more than i32::MAX elements"
        );
        let what = Collective::AllReduce {
            op,
            len: buf.len(),
            elem: type_name::<T>(),
        };
        let table = self.round(what, Box::new(buf.to_vec()));
        let mut parts = table.iter().map(Contribution::get::<Vec<T>>);
        buf.copy_from_slice(parts.next().expect("at least one rank"));
        for part in parts {
            for (a, &b) in buf.iter_mut().zip(part) {
                *a = T::combine(*a, b, op);
            }
        }
    }

    fn sparse_exchange<T: Plain, S: AsRef<[T]>>(
        &self,
        sends: &[(usize, S)],
    ) -> Result<Received<T>, CommError> {
        check_dests(self.size(), sends)?;
        for (_, s) in sends {
            check_len(s.as_ref().len())?;
        }
        let outgoing: Vec<Message> = sends
            .iter()
            .map(|(dest, s)| {
                let s = s.as_ref();
                Message {
                    dest: *dest,
                    bytes: std::mem::size_of_val(s),
                    data: Box::new(s.to_vec()),
                }
            })
            .collect();
        let table = self.round(Collective::SparseExchange, Box::new(outgoing));
        let mut received = Vec::new();
        let mut first_error = None;
        for (source_rank, c) in table.iter().enumerate() {
            for m in c.get::<Vec<Message>>() {
                if m.dest != self.rank {
                    continue;
                }
                match m.data.downcast_ref::<Vec<T>>() {
                    Some(v) => received.push((source_rank, v.clone())),
                    None => {
                        first_error.get_or_insert(CommError::MessageSize {
                            source_rank,
                            bytes: m.bytes,
                            elem_size: size_of::<T>(),
                        });
                    }
                }
            }
        }
        match first_error {
            Some(e) => Err(e),
            None => Ok(received),
        }
    }

    fn all_to_all_v<T: Plain>(
        &self,
        send: &[T],
        send_counts: &[usize],
    ) -> Result<Gathered<T>, CommError> {
        check_counts(self.size(), send.len(), send_counts)?;
        for &c in send_counts {
            check_len(c)?;
        }
        check_len(send.len())?;
        // Offsets of the blocks for each destination (length size + 1).
        let offsets: Vec<usize> = std::iter::once(0)
            .chain(send_counts.iter().scan(0, |acc, &c| {
                *acc += c;
                Some(*acc)
            }))
            .collect();
        let what = Collective::AllToAllV {
            elem: type_name::<T>(),
        };
        let table = self.round(what, Box::new((send.to_vec(), offsets)));
        let me = self.rank;
        let blocks: Vec<&[T]> = table
            .iter()
            .map(|c| {
                let (data, offsets) = c.get::<(Vec<T>, Vec<usize>)>();
                &data[offsets[me]..offsets[me + 1]]
            })
            .collect();
        let counts: Vec<usize> = blocks.iter().map(|b| b.len()).collect();
        // MpiComm aborts the job here; the panic releases the other ranks.
        let total: usize = counts.iter().sum();
        assert!(
            total <= MAX_COUNT,
            "all_to_all_v: rank {me} would receive {total} elements, more than i32::MAX"
        );
        Ok(Gathered {
            data: blocks.concat(),
            counts,
        })
    }

    fn all_gather_v<T: Plain>(&self, send: &[T]) -> Result<Gathered<T>, CommError> {
        check_len(send.len())?;
        let what = Collective::AllGatherV {
            elem: type_name::<T>(),
        };
        let table = self.round(what, Box::new(send.to_vec()));
        let blocks: Vec<&[T]> = table.iter().map(|c| c.get::<Vec<T>>().as_slice()).collect();
        let counts: Vec<usize> = blocks.iter().map(|b| b.len()).collect();
        let total: usize = counts.iter().sum();
        assert!(
            total <= MAX_COUNT,
            "all_gather_v: {total} elements in all, more than i32::MAX"
        );
        Ok(Gathered {
            data: blocks.concat(),
            counts,
        })
    }
}
