//! Communication layer of sph-exa-rs: the [`Communicator`] trait and its
//! implementations, plus [`ExactSum`], a reproducible `f64` sum that gives
//! the same bits for any number of threads and ranks.
//!
//! Implementations of [`Communicator`]:
//! * [`SerialComm`]: one rank, always available;
//! * `MpiComm` (cargo feature `mpi`, built on rsmpi): one rank per MPI
//!   process;
//! * [`ThreadComm`]: several ranks inside one process, one thread each,
//!   started by [`run_ranks`]; no MPI needed, meant for testing multi-rank
//!   code in a plain `cargo test`.
//!
//! Physics code is written once against `C: Communicator`; a serial run uses
//! [`SerialComm`], an MPI run `MpiComm`, and nothing else differs.
//! [`launch::mpirun`] builds the `mpirun` command that tests use to start
//! MPI jobs (no `mpi` feature needed).
//!
//! ```
//! use sph_comm::{Communicator, ExactSum, ReduceOp, SerialComm};
//!
//! fn global_kinetic_energy<C: Communicator>(comm: &C, m: &[f64], v2: &[f64]) -> f64 {
//!     let mut e = ExactSum::new();
//!     for (m, v2) in m.iter().zip(v2) {
//!         e.add(0.5 * m * v2);
//!     }
//!     e.all_reduce(comm); // identical bits on 1, 2, 4, ... ranks
//!     e.value()
//! }
//!
//! let comm = SerialComm::new();
//! assert_eq!((comm.rank(), comm.size()), (0, 1));
//! assert_eq!(global_kinetic_energy(&comm, &[1.0, 2.0], &[4.0, 1.0]), 3.0);
//!
//! // Global minimum time step.
//! assert_eq!(comm.all_reduce_scalar(0.25f64, ReduceOp::Min), 0.25);
//!
//! // Sparse exchange: send to a few peers, receive from whoever sends.
//! let got = comm.sparse_exchange(&[(0, vec![1.0f64, 2.0]), (0, vec![])]).unwrap();
//! assert_eq!(got, vec![(0, vec![1.0, 2.0]), (0, vec![])]);
//!
//! // All-to-all with variable counts: counts[r] elements go to rank r.
//! let g = comm.all_to_all_v(&[7u64, 8, 9], &[3]).unwrap();
//! assert_eq!(g.data, vec![7, 8, 9]);
//! assert_eq!(g.counts, vec![3]);
//!
//! // The same code on four in-process ranks.
//! let energies = sph_comm::run_ranks(4, |comm| {
//!     let r = comm.rank() as f64;
//!     global_kinetic_energy(&comm, &[1.0], &[r])
//! });
//! assert_eq!(energies, vec![3.0; 4]);
//! ```
//!
//! # Sparse exchange protocol (MPI)
//! `MpiComm::sparse_exchange` uses the NBX algorithm (Hoefler, Siebert and
//! Lumsdaine 2010): synchronous non-blocking sends (`MPI_Issend`), a loop of
//! `MPI_Improbe` + `MPI_Mrecv` for whatever arrives, and a non-blocking
//! barrier (`MPI_Ibarrier`) entered once all of this rank's sends have been
//! matched; when the barrier completes every message has been received. It
//! costs no collective of size `O(P)` (unlike a count all-to-all first) and
//! one message per actual peer, which is what the halo exchange needs.

#![deny(missing_docs)]

mod communicator;
mod error;
mod exact_sum;
pub mod launch;
#[cfg(feature = "mpi")]
mod mpi_comm;
mod plain;
mod serial;
mod thread_comm;

pub use communicator::{Communicator, Gathered, Received};
pub use error::CommError;
pub use exact_sum::{exact_sum, ExactSum, LIMBS};
#[cfg(feature = "mpi")]
pub use mpi_comm::{MpiComm, ThreadLevel};
pub use plain::{Plain, ReduceOp, Reducible};
pub use serial::SerialComm;
pub use thread_comm::{run_ranks, ThreadComm};
