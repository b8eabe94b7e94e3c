//! The writers of a run's outputs, one concept per module. The run loop in
//! [`crate::simulation`] feeds them; none of them gathers particles on one
//! rank.
//!
//! | file | module | written by |
//! | --- | --- | --- |
//! | `conserved.csv` | [`conserved`] | rank 0, one line per step |
//! | `timings.csv` | [`timings`] | rank 0, one line per step and the means |
//! | `timings.rankR.csv` | [`timings`] | rank R > 0 its own, with `--rank-timings` |
//! | `profile.csv`, `profile.png` | [`profile`] | rank 0, from the reduced profile |
//! | `energies.png` | [`energies`] | rank 0, from the per-step energies |
//! | `curve.csv`, `curve.png` | [`curve`] | rank 0, a case's tracked observable each step (reduced over the ranks) |
//! | `particles.csv` | [`particles`] | rank 0, streamed from every rank in bounded chunks |
//! | `summary.json` | [`summary`] | rank 0, last |
//! | (every step) | [`observer`] | the writers above that write per step, the watch and the progress report, as [`observer::StepObserver`]s |
//! | `snapshots/snapshot_SSSSSSSS.h5`, `checkpoints/checkpoint_SSSSSSSS.h5` | [`snapshot`], [`crate::checkpoint`] | every rank its own rows, into one file |

pub mod conserved;
mod csv;
pub mod curve;
pub mod energies;
pub mod files;
pub mod observer;
pub mod particles;
pub mod profile;
pub mod progress;
pub mod snapshot;
pub mod spectra;
pub mod summary;
pub mod timings;
pub mod totals;

pub use csv::CsvFile;
