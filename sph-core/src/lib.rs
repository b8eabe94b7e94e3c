//! The SPH-EXA hydrodynamics on structure-of-arrays particle data.
//!
//! Each stage is a function over particle slices and neighbour lists (no
//! hidden state, no communication), parallel over particles with rayon and
//! summing neighbours in ascending index order so that results do not
//! depend on the number of threads:
//!
//! | stage | module |
//! | --- | --- |
//! | neighbours + h iteration | [`neighbors`] |
//! | density, grad-h Omega | [`density`] |
//! | equation of state | [`eos`] |
//! | IAD matrices | [`iad`] |
//! | momentum and energy, AV | [`momentum`] |
//! | time step | [`timestep`] |
//! | integer time line and bins of block time steps | [`timeline`] |
//! | Press / Adams-Bashforth integrator, h update | [`integrate`] |
//! | conserved quantities | [`conserved`] |
//! | turbulence driving (not yet used by the solver) | [`stirring`] |
//!
//! [`Hydro`] chains them into one time step with reusable buffers.
//!
//! ```
//! use sph_core::{FieldSet, Hydro, HydroConfig, Particles};
//! use sph_kernels::{Sinc, Tabulated};
//! use sph_tree::{Boundary, BoundingBox};
//!
//! // A 12^3 lattice of gas at rest in a periodic unit box, hot in the middle.
//! let n = 12;
//! let mut p = Particles::new(n * n * n, FieldSet::default());
//! for i in 0..p.len() {
//!     let c = [i % n, i / n % n, i / (n * n)].map(|k| (k as f64 + 0.5) / n as f64 - 0.5);
//!     (p.x[i], p.y[i], p.z[i]) = (c[0], c[1], c[2]);
//!     p.m[i] = 1.0 / p.len() as f64;
//!     p.h[i] = 1.5 / n as f64;
//!     p.u[i] = 1.0 + (-(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / 0.01).exp();
//! }
//! let mut bbox = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
//! let kernel = Tabulated::new(&Sinc::new(6.0).unwrap(), Tabulated::DEFAULT_POINTS).unwrap();
//! let mut config = HydroConfig::default();
//! config.neighbors.ng0 = 50;
//! let mut hydro = Hydro::new(kernel, config, 0.0, 1e-4).unwrap();
//! hydro.prepare(&mut p);
//! let first = hydro.step(&mut p, &mut bbox).unwrap();
//! let mut last = first;
//! for _ in 0..4 {
//!     last = hydro.step(&mut p, &mut bbox).unwrap();
//! }
//! // Total energy is conserved to integrator accuracy.
//! let (e0, e1) = (first.conserved.e_tot(), last.conserved.e_tot());
//! assert!(((e1 - e0) / e0).abs() < 1e-6);
//! assert!(hydro.time() > first.dt);
//! ```

pub mod av_switch;
mod choice;
pub mod conduction;
pub mod conserved;
pub mod density;
pub mod eos;
mod error;
pub mod fields;
mod flow;
pub mod geometry;
pub mod hydro;
pub mod iad;
pub mod integrate;
pub mod momentum;
pub mod neighbors;
pub mod pair_loop;
mod particles;
pub mod scheme;
pub mod stirring;
pub mod timeline;
pub mod timestep;

pub use av_switch::{AvSwitchParams, SwitchForm};
pub use choice::Choice;
pub use conserved::Conserved;
pub use eos::Eos;
pub use error::CoreError;
pub use hydro::{
    BlockRun, DomainStepStats, Hydro, HydroConfig, RunState, StageTimes, StepReport, BIN_OFFSETS,
    STAGES,
};
pub use integrate::HUpdate;
pub use neighbors::NeighborParams;
pub use pair_loop::Gradients;
pub use particles::{FieldSet, Particles};
pub use scheme::{AvForm, Scheme, Viscosity, Volume, PRESETS};
pub use timestep::{TimeSteps, TimestepParams};
