//! Sedov-Taylor point blast in a periodic box, set up as the C++ SPH-EXA
//! does: regular lattice in `[-0.5, 0.5]^3`, rho = 1, gamma = 5/3, E = 1
//! deposited as a Gaussian of width 0.1, first dt = 1e-6.

use super::{cube_lattice, initial_h, CaseInfo, Reference, Scene};
use crate::reference::Sedov;
use crate::AppError;
use sph_core::{Eos, FieldSet, HydroConfig, Particles};
use sph_tree::{Boundary, BoundingBox};

/// Listing entry.
pub const INFO: CaseInfo = CaseInfo {
    name: "sedov",
    description: "Sedov-Taylor blast wave in a periodic box vs the similarity solution",
    default_side: 30,
    scheme: super::Scheme::PAPER,
    softening: 1.0,
    default_end_time: 0.05,
};

/// Gaussian width of the initial energy deposit.
pub const WIDTH: f64 = 0.1;
/// Blast energy.
pub const ENERGY: f64 = 1.0;
/// Ambient specific internal energy.
pub const U0: f64 = 1e-8;
/// Adiabatic index.
pub const GAMMA: f64 = 5.0 / 3.0;

/// Builds the scene with `side^3` particles.
pub fn setup(side: usize, mut config: HydroConfig) -> Result<Scene, AppError> {
    let n = side * side * side;
    let mut p = Particles::new(
        n,
        FieldSet {
            iad: config.scheme.gradients == sph_core::Gradients::Iad,
            grad_h: config.scheme.grad_h,
            gravity: false,
        },
    );
    let h0 = initial_h(config.neighbors.ng0, 1.0, n);
    let norm = ENERGY / (std::f64::consts::PI.powf(1.5) * WIDTH.powi(3));
    for (i, q) in cube_lattice(side, -0.5, 1.0).enumerate() {
        (p.x[i], p.y[i], p.z[i]) = (q[0], q[1], q[2]);
        let r2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
        p.m[i] = 1.0 / n as f64;
        p.h[i] = h0;
        p.u[i] = norm * (-r2 / (WIDTH * WIDTH)).exp() + U0;
    }
    config.eos = Eos::IdealGas { gamma: GAMMA };
    // Pure hydrodynamics: no self-gravity whatever the caller passed.
    config.gravity = None;
    let reference = Sedov::spherical(GAMMA, ENERGY, 1.0)?.with_ambient(0.0, U0);
    Ok(Scene {
        case: INFO.name,
        particles: p,
        bbox: BoundingBox::cube(-0.5, 0.5, Boundary::Periodic)?,
        config,
        dt0: 1e-6,
        reference: Some(Reference::Sedov(reference)),
        energies: None,
    })
}
