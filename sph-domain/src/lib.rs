//! Distributed particle domain in the style of cornerstone (SPH-EXA's
//! domain library): a replicated global octree whose leaf counts are summed
//! with one all-reduce, contiguous SFC key ranges per rank balanced by
//! count, migration of particles to their owners, halo discovery (periodic
//! aware) and point-to-point halo exchange of any set of fields.
//!
//! After [`Domain::sync`] a rank's arrays hold its halos and owned particles
//! in ascending (key, id) order, the same relative order as on one rank, so
//! neighbour sums run in the same order whatever the number of ranks.
//!
//! ```
//! use sph_comm::SerialComm;
//! use sph_domain::{Domain, DomainConfig, ParticleFields};
//! use sph_tree::{Boundary, BoundingBox};
//! use std::ops::Range;
//!
//! /// The smallest container: positions, h and an id.
//! #[derive(Default)]
//! struct Cloud { id: Vec<u64>, x: Vec<f64>, y: Vec<f64>, z: Vec<f64>, h: Vec<f64> }
//!
//! impl ParticleFields for Cloud {
//!     fn len(&self) -> usize { self.id.len() }
//!     fn ids(&self) -> &[u64] { &self.id }
//!     fn positions(&self) -> [&[f64]; 3] { [&self.x, &self.y, &self.z] }
//!     fn smoothing_lengths(&self) -> &[f64] { &self.h }
//!     fn packed_words(&self) -> usize { 5 }
//!     fn pack(&self, i: usize, out: &mut Vec<u64>) {
//!         out.extend([self.id[i], self.x[i].to_bits(), self.y[i].to_bits(),
//!                     self.z[i].to_bits(), self.h[i].to_bits()]);
//!     }
//!     fn push_packed(&mut self, w: &[u64]) {
//!         self.id.push(w[0]);
//!         self.x.push(f64::from_bits(w[1]));
//!         self.y.push(f64::from_bits(w[2]));
//!         self.z.push(f64::from_bits(w[3]));
//!         self.h.push(f64::from_bits(w[4]));
//!     }
//!     fn keep(&mut self, r: Range<usize>) {
//!         self.id = self.id[r.clone()].to_vec();
//!         for v in [&mut self.x, &mut self.y, &mut self.z, &mut self.h] {
//!             *v = v[r.clone()].to_vec();
//!         }
//!     }
//!     fn reorder(&mut self, perm: &[u32], _scratch: &mut Vec<u64>) {
//!         self.id = perm.iter().map(|&p| self.id[p as usize]).collect();
//!         for v in [&mut self.x, &mut self.y, &mut self.z, &mut self.h] {
//!             *v = perm.iter().map(|&p| v[p as usize]).collect();
//!         }
//!     }
//! }
//!
//! let mut cloud = Cloud::default();
//! for i in 0..1000u64 {
//!     let f = |k: u64| ((i * k) % 1000) as f64 / 1000.0;
//!     cloud.push_packed(&[i, f(7).to_bits(), f(13).to_bits(), f(31).to_bits(), 0.05f64.to_bits()]);
//! }
//! let mut bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
//! let mut domain = Domain::new(SerialComm::new(), DomainConfig::default()).unwrap();
//! let owned = domain.sync(&mut cloud, &mut bbox).unwrap();
//! assert_eq!(owned, 0..1000); // one rank: everything owned, no halos
//! assert!(domain.keys().windows(2).all(|w| w[0] <= w[1]));
//! ```

mod domain;
mod error;
mod fields;
pub mod global_tree;
pub mod halo;

pub use domain::{Domain, DomainConfig, SyncStats};
pub use error::DomainError;
pub use fields::ParticleFields;
pub use global_tree::{Assignment, GlobalTree, KEY_END};
