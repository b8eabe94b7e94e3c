//! The SPH-EXA test cases, their analytic references, the [`Simulation`]
//! that runs them, and the `sphexa` command-line driver.
//!
//! ```no_run
//! use sph_apps::{cases, Simulation, simulation::{Progress, Stop}};
//! use sph_core::HydroConfig;
//! use sph_kernels::KernelChoice;
//!
//! // The case applies its own scheme; `HydroConfig` carries the rest.
//! let scene = cases::lookup("sedov")?.setup(20, HydroConfig::default())?;
//! let kernel = KernelChoice::default().fast()?;
//! let mut sim = Simulation::new(scene, kernel, "sinc:6".into())?;
//! let summary = sim.run(Stop::Time(0.01), std::path::Path::new("out/sedov"), Progress::Quiet)?;
//! println!("L1(rho) = {:?}", summary.l1);
//! # Ok::<(), sph_apps::AppError>(())
//! ```
//!
//! The reference solutions are usable on their own:
//!
//! ```
//! let sedov = sph_apps::reference::Sedov::spherical(5.0 / 3.0, 1.0, 1.0).unwrap();
//! assert!((sedov.shock_radius(0.05) - 0.3475).abs() < 1e-3);
//! ```

pub mod analysis;
pub mod bench;
pub mod cases;
pub mod checkpoint;
pub mod cli;
pub mod config;
pub mod glass;
pub mod init;
pub mod memory;
pub mod output;
pub mod plot;
pub mod reference;
pub mod rng;
pub mod simulation;
pub mod spectrum;
pub mod stress;
pub mod watch;

pub use simulation::{Simulation, Summary};

use std::path::Path;

/// Why a run could not start or had to stop.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AppError {
    /// Bad user input.
    #[error("{0}")]
    Usage(String),
    /// A file could not be written or read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The physics stopped (numerical failure).
    #[error(transparent)]
    Core(#[from] sph_core::CoreError),
    /// A box or tree problem.
    #[error(transparent)]
    Tree(#[from] sph_tree::TreeError),
    /// A bad kernel choice.
    #[error(transparent)]
    Kernel(#[from] sph_kernels::KernelError),
    /// Communication between ranks failed.
    #[error(transparent)]
    Comm(#[from] sph_comm::CommError),
    /// A bad reference-solution parameter.
    #[error(transparent)]
    Reference(#[from] reference::ReferenceError),
    /// A velocity spectrum or density PDF could not be computed.
    #[error(transparent)]
    Spectrum(#[from] spectrum::SpectrumError),
    /// A snapshot or checkpoint file could not be written or read.
    #[error(transparent)]
    Snapshot(#[from] sph_io::IoError),
    /// A numerical failure of the solver, with the position of the
    /// particle it names.
    #[error("{source}; the particle is at ({:.6e}, {:.6e}, {:.6e})", position[0], position[1], position[2])]
    Located {
        /// The failure (names the step and the particle id).
        source: sph_core::CoreError,
        /// The particle's position when it failed.
        position: [f64; 3],
    },
    /// A conserved quantity went non-finite.
    #[error("step {step}: the conserved sums are not finite; first particle with a non-finite value: {}", particle.as_ref().map_or("none found".to_string(), |b| b.to_string()))]
    NonFinite {
        /// Step.
        step: u64,
        /// The particle of smallest id holding a non-finite value.
        particle: Option<watch::Blame>,
    },
    /// A bad value in the initial particles.
    #[error("initial state: {0}")]
    Input(watch::Blame),
    /// A strict run crossed a bound ([`watch::Watch`]).
    #[error("{0} (--strict)")]
    Watch(Box<watch::Violation>),
}

impl AppError {
    /// An I/O error on `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        AppError::Io {
            path: path.display().to_string(),
            source,
        }
    }
}

/// The folder of the unit tests' files: under the target directory, next
/// to the test binary (unit tests have no `CARGO_TARGET_TMPDIR`), never in
/// the user's folders or `/tmp`.
#[cfg(test)]
fn unit_test_root() -> std::path::PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    // target/<profile>/deps/<binary>
    exe.parent()
        .and_then(Path::parent)
        .expect("the test binary is in target/<profile>/deps")
        .join("sph-apps-unit-tests")
}

/// A fresh, empty folder `NAME` for a unit test's files (see
/// [`unit_test_root`]).
#[cfg(test)]
pub(crate) fn test_dir(name: &str) -> std::path::PathBuf {
    let dir = unit_test_root().join(name);
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).expect("test folder");
    dir
}

/// The glass cache of the unit tests (see [`unit_test_root`]): kept
/// between runs, so a glass is relaxed once.
#[cfg(test)]
pub(crate) fn test_glass_dir() -> std::path::PathBuf {
    unit_test_root().join("glass-cache")
}
