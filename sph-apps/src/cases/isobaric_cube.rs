//! The isobaric cube: a cube of dense gas (rho = 8) inside thin gas
//! (rho = 1), both at P = 2.5, at rest, in a periodic box: the exact
//! solution is the initial state. SPH's smoothed density across the
//! contact makes a pressure blip there that pushes the interface; a scheme
//! that handles contacts keeps the cube still and square. Set-up of
//! `docs/cases.md`: box `[-0.5, 0.5)^3`, inner cube
//! `[-0.25, 0.25)^3`, gamma = 5/3, to t = 1 (two sound crossings of the box
//! in the thin gas, c = 2.04).
//!
//! Both gases are cubic lattices of equal-mass particles, the dense one
//! with half the spacing. The reference's coordinate is the distance in
//! the max norm, `max(|x|, |y|, |z|)`, so the profile shows the interface
//! at 0.25 as a step.

use super::{Request, 
    field_set, initial_h, Case, InitialState, Listing, Reference, Scheme, Stationary,
};
use crate::AppError;
use sph_tree::{Boundary, BoundingBox};

/// The case (registered as `isobaric-cube`).
#[derive(Debug, Clone, Copy)]
pub struct IsobaricCube;

/// Adiabatic index (that of the default gas, [`super::Physics::IDEAL_GAS`]).
pub const GAMMA: f64 = 5.0 / 3.0;
/// Density inside the cube.
pub const RHO_IN: f64 = 8.0;
/// Density outside.
pub const RHO_OUT: f64 = 1.0;
/// Pressure everywhere.
pub const PRESSURE: f64 = 2.5;
/// Half the side of the inner cube.
pub const HALF: f64 = 0.25;

impl Case for IsobaricCube {
    /// `side` is the number of thin-gas particles per box side (even);
    /// the dense cube holds `side^3` particles: 20 gives 15,000 in all.
    fn listing(&self) -> Listing {
        Listing {
            name: "isobaric-cube",
            description: "Dense cube in pressure equilibrium with thin gas (stationary: the initial state is the answer)",
            side: 20,
            end_time: 1.0,
        }
    }

    /// Pressure-energy volumes ([`Scheme::CONTACT`]): the cube's contact
    /// keeps one smoothed pressure. Not yet `gas` ([`Scheme::GAS`], the
    /// default of the other ideal-gas cases): its time-mean v_rms / c is
    /// 0.067 at 16 and 0.044 at 32 per side, against 0.022 and 0.017. The
    /// cube needs pressure-energy volumes, kernel gradients and a constant
    /// alpha = 1 together: Sedov and Kelvin-Helmholtz fail with the three,
    /// Noh and Gresho with kernel gradients alone (`docs/schemes.md`,
    /// 2026-12-08).
    fn default_scheme(&self) -> Scheme {
        Scheme::CONTACT
    }

    /// The thin lattice (spacing `1/side`) without the cells of the inner
    /// cube, then the dense lattice (spacing `1/(2 side)`) filling it.
    fn initial_state(&self, request: &Request<'_>) -> Result<InitialState, AppError> {
        let Request { side, config, share, .. } = *request;
        if !side.is_multiple_of(2) {
            return Err(AppError::Usage(format!(
                "case isobaric-cube: {side} particles per side; it must be even (the cube is half the box)"
            )));
        }
        let d = 1.0 / side as f64;
        let inside = |q: [f64; 3]| q.iter().all(|c| c.abs() < HALF);
        let thin: Vec<[f64; 3]> = super::cube_lattice(side, -0.5, 1.0)
            .filter(|&q| !inside(q))
            .collect();
        let n = thin.len() + side * side * side;
        let m = RHO_OUT * d * d * d;
        let h_thin = initial_h(config.neighbors.ng0, d * d * d, 1);
        let u = |rho: f64| PRESSURE / ((GAMMA - 1.0) * rho);
        let (mut p, mine) = share.particles(n, field_set(config));
        let mut dense = super::cube_lattice(side, -HALF, 2.0 * HALF).skip(
            mine.start.saturating_sub(thin.len()),
        );
        for (k, g) in mine.enumerate() {
            let (q, h, rho) = if g < thin.len() {
                (thin[g], h_thin, RHO_OUT)
            } else {
                let q = dense.next().expect("dense lattice holds side^3 points");
                (q, 0.5 * h_thin, RHO_IN)
            };
            (p.x[k], p.y[k], p.z[k]) = (q[0], q[1], q[2]);
            p.m[k] = m;
            p.h[k] = h;
            p.u[k] = u(rho);
        }
        Ok(InitialState {
            total: n,
            particles: p,
            bbox: BoundingBox::cube(-0.5, 0.5, Boundary::Periodic)?,
            dt0: 1e-4 * 20.0 * d,
        })
    }

    fn reference(
        &self,
        _side: usize,
        _initial: &InitialState,
    ) -> Result<Option<Reference>, AppError> {
        Ok(Some(Reference::Stationary(Stationary {
            inner: [RHO_IN, PRESSURE],
            outer: [RHO_OUT, PRESSURE],
            half: HALF,
            gamma: GAMMA,
        })))
    }
}
