//! Analytic reference solutions the test cases are measured against.
//!
//! - [`Sedov`]: the Sedov-Taylor point blast (Kamm & Timmes 2007, standard case).
//! - [`Noh`]: the Noh implosion (exact, piecewise closed form).
//! - [`Riemann`]: the exact Riemann problem (shock tubes such as Sod's).
//! - [`Gresho`]: the Gresho-Chan vortex (stationary).
//!
//! Each returns a [`FlowState`] at a radius (a position along the tube) and a time; the constructors validate their
//! parameters and report a [`ReferenceError`] naming the bad value.

mod gresho;
mod noh;
mod quadrature;
mod riemann;
mod sedov;

pub use gresho::Gresho;
pub use noh::Noh;
pub use riemann::{GasState, Riemann, Waves};
pub use sedov::Sedov;

/// The fluid state of a reference solution at one radius and time.
///
/// All quantities are in the units of the parameters the solution was built with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlowState {
    /// Mass density.
    pub rho: f64,
    /// Pressure.
    pub p: f64,
    /// Signed radial velocity: positive outwards, negative towards the centre.
    pub v: f64,
    /// Specific internal energy, `p / ((gamma - 1) rho)` where the gas is shocked.
    pub u: f64,
}

impl FlowState {
    /// The state reported for NaN input.
    pub const NAN: FlowState = FlowState {
        rho: f64::NAN,
        p: f64::NAN,
        v: f64::NAN,
        u: f64::NAN,
    };
}

/// Why a reference solution could not be built.
#[derive(thiserror::Error, Debug, Clone, PartialEq)]
pub enum ReferenceError {
    /// The adiabatic index is not a finite number above 1.
    #[error("adiabatic index gamma = {gamma} is not allowed: it must be finite and > 1")]
    InvalidGamma {
        /// The rejected adiabatic index.
        gamma: f64,
    },

    /// The adiabatic index is valid but the standard Sedov family has no regular solution there.
    #[error("gamma = {gamma} is not supported in geometry j = {geometry}: {reason}")]
    UnsupportedGamma {
        /// The rejected adiabatic index.
        gamma: f64,
        /// The geometry it was rejected for (1 planar, 2 cylindrical, 3 spherical).
        geometry: u32,
        /// What is allowed instead.
        reason: &'static str,
    },

    /// The blast energy is not finite and positive.
    #[error("blast energy E = {energy} is not allowed: it must be finite and > 0")]
    InvalidEnergy {
        /// The rejected energy.
        energy: f64,
    },

    /// The ambient density is not finite and positive.
    #[error("ambient density rho0 = {rho0} is not allowed: it must be finite and > 0")]
    InvalidDensity {
        /// The rejected density.
        rho0: f64,
    },

    /// The geometry index is not 1, 2 or 3.
    #[error(
        "geometry j = {geometry} is not allowed: use 1 (planar), 2 (cylindrical) or 3 (spherical)"
    )]
    InvalidGeometry {
        /// The rejected geometry index.
        geometry: u32,
    },

    /// The inflow speed is not finite and positive.
    #[error("inflow speed v0 = {v0} is not allowed: it must be finite and > 0")]
    InvalidSpeed {
        /// The rejected speed.
        v0: f64,
    },

    /// A pressure that is not finite and positive.
    #[error("pressure P = {p} is not allowed: it must be finite and > 0")]
    InvalidPressure {
        /// The rejected pressure.
        p: f64,
    },

    /// A radius that is not finite and positive.
    #[error("radius r = {r} is not allowed: it must be finite and > 0")]
    InvalidRadius {
        /// The rejected radius.
        r: f64,
    },

    /// A velocity that is not finite.
    #[error("velocity v = {v} is not allowed: it must be finite")]
    InvalidVelocity {
        /// The rejected velocity.
        v: f64,
    },

    /// The two states of a Riemann problem move apart fast enough to open
    /// a vacuum between them, which this solver does not model.
    #[error("the two states separate faster than 2/(gamma-1) (c_L + c_R): a vacuum forms; use states closer in velocity")]
    Vacuum,
}

/// Rejects an adiabatic index that is not a finite number above 1.
fn check_gamma(gamma: f64) -> Result<(), ReferenceError> {
    if gamma.is_finite() && gamma > 1.0 {
        Ok(())
    } else {
        Err(ReferenceError::InvalidGamma { gamma })
    }
}

/// Rejects a density that is not finite and positive.
fn check_density(rho0: f64) -> Result<(), ReferenceError> {
    if rho0.is_finite() && rho0 > 0.0 {
        Ok(())
    } else {
        Err(ReferenceError::InvalidDensity { rho0 })
    }
}
