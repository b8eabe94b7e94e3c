//! Velocity power spectra and the ln-density PDF of particle data
//! (docs/turbulence.md §6): analysis only, pure functions on slices.
//!
//! - [`SpectrumGrid`]: triangular-shaped-cloud (TSC, 27 cells) deposit of
//!   `m` and `m v` on an `N_g^3` periodic grid, in fixed point, so that any
//!   order or grouping of the particles (threads, ranks) gives the same
//!   integers. A caller on many ranks finds the global [`Extremes`] and
//!   particle count, builds one [`DepositScale`], deposits its own
//!   particles and sums [`SpectrumGrid::integers_mut`] over the ranks.
//! - [`velocity_spectrum`]: the shell spectrum `E(k)` of the mass-weighted
//!   velocity `u = j / rho_bar`, optionally divided by the TSC window, with
//!   its solenoidal and compressive parts; [`slope`] fits `ln E` against
//!   `ln k`; [`write_spectrum_csv`] writes it.
//! - [`LnRhoPdf`]: exact mass sums in bins of `s = ln(rho / rho_bar)`, with
//!   the mass-weighted mean and width of `s`.
//!
//! Wavenumbers are integers in units of `2 pi / L`.
//!
//! ```
//! use sph_apps::spectrum::{velocity_spectrum, DepositScale, Extremes, SpectrumGrid};
//!
//! // 8^3 particles on the nodes of an 8^3 grid in the unit box, moving
//! // with u_y = sin(2 pi x): one solenoidal mode at k = 1.
//! let n = 8;
//! let (mut x, mut y, mut z, mut vy) = (vec![], vec![], vec![], vec![]);
//! for i in 0..n * n * n {
//!     let p = [i / (n * n), i / n % n, i % n].map(|j| j as f64 / n as f64);
//!     x.push(p[0]);
//!     y.push(p[1]);
//!     z.push(p[2]);
//!     vy.push((2.0 * std::f64::consts::PI * p[0]).sin());
//! }
//! let m = vec![1.0 / (n * n * n) as f64; n * n * n];
//! let zero = vec![0.0; n * n * n];
//! let extremes = Extremes::local(&m, &zero, &vy, &zero)?; // all-reduce (max) on many ranks
//! let scale = DepositScale::new(extremes, m.len() as u64)?;
//! let mut grid = SpectrumGrid::new(n, [0.0; 3], 1.0, scale)?;
//! grid.deposit(&x, &y, &z, &m, &zero, &vy, &zero)?;
//! let s = velocity_spectrum(&grid, true)?;
//! // <u_y^2> / 2 = 1/4, all of it at k = 1 and solenoidal; the 0.3%
//! // left is the window's alias sum at k = 1 of 8.
//! assert!((s.e[1] / 0.25 - 1.0).abs() < 5e-3 && s.e_comp[1] < 1e-25);
//! # Ok::<(), sph_apps::spectrum::SpectrumError>(())
//! ```

mod fft;
mod grid;
mod pdf;
mod power;
#[cfg(test)]
mod tests;

pub use grid::{DepositScale, Extremes, SpectrumGrid, FRACTION_BITS, MIN_FRACTION_BITS};
pub use pdf::{write_pdf_csv, LnRhoPdf, PDF_BINS, S_MAX, S_MIN};
pub use power::{slope, velocity_spectrum, write_spectrum_csv, Spectrum};

/// The default grid for `particles` particles: their cube root of cells
/// per side, rounded to an even number, at least 8.
pub fn default_grid(particles: usize) -> usize {
    let side = (particles as f64).cbrt().round() as usize;
    side.next_multiple_of(2).max(8)
}

/// Writes the CSV that `body` produces to `path` (made in memory first,
/// so a failed write names the file).
pub(crate) fn write_csv(
    path: &std::path::Path,
    body: impl FnOnce(&mut Vec<u8>) -> std::io::Result<()>,
) -> Result<(), crate::AppError> {
    let mut bytes = Vec::new();
    body(&mut bytes).map_err(|e| crate::AppError::io(path, e))?;
    std::fs::write(path, bytes).map_err(|e| crate::AppError::io(path, e))
}

/// Why a spectrum or PDF could not be computed; each names the bad value.
#[derive(thiserror::Error, Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SpectrumError {
    /// The grid size is outside the supported range.
    #[error("spectrum grid of {n}^3 cells: N_g must be in {min}..={max}")]
    GridSize {
        /// The rejected number of cells per side.
        n: usize,
        /// Smallest allowed.
        min: usize,
        /// Largest allowed.
        max: usize,
    },
    /// The box is not a finite cube of positive side.
    #[error("spectrum box with min ({}, {}, {}) and side {length}: min must be finite and the side finite and > 0", min[0], min[1], min[2])]
    BadBox {
        /// Lower corner.
        min: [f64; 3],
        /// Side.
        length: f64,
    },
    /// Per-particle slices of different lengths.
    #[error("{what} has {len} values but {expected} particles were given")]
    Length {
        /// The slice.
        what: &'static str,
        /// Its length.
        len: usize,
        /// The length of the first slice.
        expected: usize,
    },
    /// A particle value that is not allowed (non-finite, negative mass or
    /// density).
    #[error("{what} of particle {index} is {value}: {why}")]
    BadValue {
        /// The quantity.
        what: &'static str,
        /// The particle's position in the slices.
        index: usize,
        /// The value.
        value: f64,
        /// What is required.
        why: &'static str,
    },
    /// A particle term is larger than the scale's maximum (the scale was
    /// built from other data).
    #[error("|{what}| = {value} of particle {index} exceeds the scale's maximum {max}")]
    AboveScale {
        /// The quantity.
        what: &'static str,
        /// The particle's position in the slices.
        index: usize,
        /// The value.
        value: f64,
        /// The maximum the scale was built for.
        max: f64,
    },
    /// A maximum handed to [`DepositScale::new`] is not finite and >= 0.
    #[error("deposit scale: the maximum {what} {value} is not finite and >= 0")]
    BadExtreme {
        /// The quantity.
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// More particles than the fixed-point headroom allows.
    #[error("{particles} particles: more than the {max} whose fixed-point deposits fit in i64 at {bits} fraction bits")]
    TooManyParticles {
        /// The particle count.
        particles: u64,
        /// The largest count allowed at `bits`.
        max: u64,
        /// The fraction bits at which the count was checked.
        bits: u32,
    },
    /// Two grids that cannot be added (different cells, box or scale).
    #[error("grids differ: {0}")]
    Mismatch(&'static str),
    /// The grid holds no mass, so it has no mean density.
    #[error("the grid holds no mass (total {mass}): no mean density to divide the momentum by")]
    NoMass {
        /// The total mass deposited.
        mass: f64,
    },
    /// A slope range that the spectrum cannot fit.
    #[error("slope over k = {k_lo}..={k_hi}: {why}")]
    SlopeRange {
        /// First shell.
        k_lo: usize,
        /// Last shell.
        k_hi: usize,
        /// Why not.
        why: String,
    },
    /// The mean density of the PDF is not finite and > 0.
    #[error("mean density rho_bar = {rho_bar}: it must be finite and > 0")]
    MeanDensity {
        /// The value.
        rho_bar: f64,
    },
}
