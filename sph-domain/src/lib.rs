//! Distributed particle domain in the style of cornerstone (SPH-EXA's
//! domain library): a replicated global octree whose leaf counts are summed
//! with one all-reduce, contiguous SFC key ranges per rank balanced by
//! count, migration of particles to their owners, halo discovery (periodic
//! aware) and point-to-point halo exchange of any set of fields: of every
//! halo ([`Domain::exchange`]), of the halos of a subset chosen by the owner
//! ([`Domain::exchange_where`], for block time steps' active particles),
//! and back from the halos to their owners by minimum
//! ([`Domain::exchange_reverse_min`]).
//!
//! After [`Domain::sync`] a rank's arrays hold its halos and owned particles
//! in ascending (key, id) order, the same relative order as on one rank, so
//! neighbour sums run in the same order whatever the number of ranks.
//!
//! ```
//! use sph_comm::SerialComm;
//! use sph_domain::{Domain, DomainConfig, Points};
//! use sph_tree::{Boundary, BoundingBox};
//!
//! let mut cloud = Points::default();
//! for i in 0..1000u64 {
//!     let f = |k: u64| ((i * k) % 1000) as f64 / 1000.0;
//!     cloud.push(i, [f(7), f(13), f(31)], 0.05);
//! }
//! let mut bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
//! let mut domain = Domain::new(SerialComm::new(), DomainConfig::default()).unwrap();
//! let owned = domain.sync(&mut cloud, &mut bbox).unwrap();
//! assert_eq!(owned, 0..1000); // one rank: everything owned, no halos
//! assert!(domain.keys().windows(2).all(|w| w[0] <= w[1]));
//! ```
//!
//! With several ranks (here in-process threads; `MpiComm` works the same),
//! each rank owns a contiguous key range and holds the halos it needs:
//!
//! ```
//! use sph_comm::{run_ranks, Communicator};
//! use sph_domain::{Domain, DomainConfig, Points};
//! use sph_tree::{Boundary, BoundingBox};
//!
//! let owned = run_ranks(2, |comm| {
//!     let mut cloud = Points::default();
//!     for i in (comm.rank() as u64..1000).step_by(2) {
//!         let f = |k: u64| ((i * k) % 1000) as f64 / 1000.0;
//!         cloud.push(i, [f(7), f(13), f(31)], 0.05);
//!     }
//!     let mut bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
//!     let mut domain = Domain::new(&comm, DomainConfig::default()).unwrap();
//!     domain.sync(&mut cloud, &mut bbox).unwrap().len()
//! });
//! assert_eq!(owned.iter().sum::<usize>(), 1000);
//! ```

mod domain;
mod error;
mod fields;
pub mod global_tree;
pub mod halo;
mod points;

pub use domain::{Domain, DomainConfig, SyncStats};
pub use error::DomainError;
pub use fields::{halo_placement, halo_slot, ParticleFields};
pub use global_tree::{Assignment, GlobalTree, KEY_END};
pub use points::Points;
