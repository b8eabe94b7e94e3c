//! The test cases: initial conditions, the physics each needs, and its
//! reference solution.

use crate::reference::{FlowState, Noh, Sedov};
use sph_core::{HydroConfig, Particles};
use sph_tree::BoundingBox;

pub mod evrard;
pub mod noh;
pub mod sedov;
pub mod square_patch;

/// A case's name and one-line description, for `sphexa cases`.
#[derive(Debug, Clone, Copy)]
pub struct CaseInfo {
    /// Name on the command line.
    pub name: &'static str,
    /// One line for listings.
    pub description: &'static str,
    /// Default particles per side.
    pub default_side: usize,
    /// Default end time.
    pub default_end_time: f64,
    /// The scheme the case runs with unless told otherwise.
    pub scheme: Scheme,
    /// Self-gravity softening scale the case runs with (pairs softened
    /// within `softening * (h_i + h_j)`; cases with self-gravity).
    pub softening: f64,
}

pub use sph_core::Scheme;

/// Every case, in listing order.
pub const CASES: [CaseInfo; 4] = [sedov::INFO, noh::INFO, square_patch::INFO, evrard::INFO];

/// Looks a case up by name.
pub fn find(name: &str) -> Option<&'static CaseInfo> {
    CASES.iter().find(|c| c.name == name)
}

/// Reference energies of a case at one time.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct EnergyPoint {
    /// Time.
    pub t: f64,
    /// Kinetic energy.
    pub e_kin: f64,
    /// Internal (thermal) energy.
    pub e_int: f64,
    /// Gravitational energy.
    pub e_grav: f64,
}

/// A radially symmetric analytic solution to compare against.
#[derive(Debug, Clone)]
pub enum Reference {
    /// Sedov-Taylor blast wave centred at the origin.
    Sedov(Sedov),
    /// Noh implosion centred at the origin.
    Noh(Noh),
}

impl Reference {
    /// State at radius `r` and time `t`; `v` is the radial velocity.
    pub fn state(&self, r: f64, t: f64) -> FlowState {
        match self {
            Reference::Sedov(s) => s.state(r, t),
            Reference::Noh(n) => n.state(r, t),
        }
    }

    /// Shock radius at `t`.
    pub fn shock_radius(&self, t: f64) -> f64 {
        match self {
            Reference::Sedov(s) => s.shock_radius(t),
            Reference::Noh(n) => n.shock_radius(t),
        }
    }
}

/// Everything a run of a case starts from.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Case name.
    pub case: &'static str,
    /// Initial particles.
    pub particles: Particles,
    /// Simulation box.
    pub bbox: BoundingBox,
    /// The scheme the case needs.
    pub config: HydroConfig,
    /// First time step (the integrator's `dt_{-1}`).
    pub dt0: f64,
    /// Analytic solution, if any.
    pub reference: Option<Reference>,
    /// Reference energies over time, if any.
    pub energies: Option<&'static [EnergyPoint]>,
}

/// Particles of an `n^3` lattice of cell centres in the cube
/// `[lo, lo + len)^3`, in x-fastest order.
pub fn cube_lattice(n: usize, lo: f64, len: f64) -> impl Iterator<Item = [f64; 3]> {
    let dx = len / n as f64;
    (0..n * n * n).map(move |i| {
        let c = [i % n, i / n % n, i / (n * n)];
        c.map(|k| lo + (k as f64 + 0.5) * dx)
    })
}

/// Smoothing length giving `ng0` neighbours (within 2h) at number density
/// `n / volume`: `h = 1/2 (3/(4 pi) ng0 V / N)^(1/3)`.
pub fn initial_h(ng0: usize, volume: f64, n: usize) -> f64 {
    0.5 * (3.0 / (4.0 * std::f64::consts::PI) * ng0 as f64 * volume / n as f64).cbrt()
}
