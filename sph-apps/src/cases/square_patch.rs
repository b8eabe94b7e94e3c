//! Rotating square patch (SPH-EXA paper §4.6): a 2-D lattice copied along
//! z (periodic in z only), rigid rotation, stiff Tait EOS about each
//! particle's initial state, initial pressure from the incompressible
//! Poisson series.

use super::{Layout, Listing, field_set, initial_h, Case, InitialState, Physics, Scheme, Share};
use crate::AppError;
use sph_core::{Eos, HydroConfig};
use sph_tree::{Boundary, BoundingBox};
use std::f64::consts::PI;

/// The case (registered as `square-patch`).
#[derive(Debug, Clone, Copy)]
pub struct SquarePatch;

/// Side of the square and height of the slab (cm).
pub const L: f64 = 100.0;
/// Angular velocity (rad/s).
pub const OMEGA: f64 = 5.0;
/// Density (g/cm^3).
pub const RHO0: f64 = 1.0;
/// Reference sound speed (cm/s).
pub const C0: f64 = 3500.0;
/// Highest odd mode of the pressure series.
pub const MAX_MODE: u32 = 39;

/// Exact angular momentum of the continuous patch, `rho omega H L^4 / 6`.
pub fn angular_momentum_exact() -> f64 {
    RHO0 * OMEGA * L * L.powi(4) / 6.0
}

/// Initial pressure at `(x, y)` (origin at the centre of the square):
/// `P0 = rho sum_{m,n odd} -32 omega^2 / (m n pi^2 [(m pi/L)^2 + (n pi/L)^2])
///       sin(m pi x'/L) sin(n pi y'/L)`, `x' = x + L/2`.
pub fn initial_pressure(x: f64, y: f64) -> f64 {
    let (xs, ys) = (x + 0.5 * L, y + 0.5 * L);
    let mut p = 0.0;
    for m in (1..=MAX_MODE).step_by(2) {
        let km = f64::from(m) * PI / L;
        let sm = (km * xs).sin();
        for n in (1..=MAX_MODE).step_by(2) {
            let kn = f64::from(n) * PI / L;
            p += -32.0 * OMEGA * OMEGA / (f64::from(m * n) * PI * PI * (km * km + kn * kn))
                * sm
                * (kn * ys).sin();
        }
    }
    RHO0 * p
}

impl Case for SquarePatch {
    fn listing(&self) -> Listing {
        Listing {
            name: "square-patch",
            description: "Rotating square patch (stiff Tait EOS, free surface); checks angular momentum",
            side: 20,
            end_time: 0.05,
        }
    }

    /// The paper's scheme.
    fn default_scheme(&self) -> Scheme {
        Scheme::PAPER
    }

    /// The Tait EOS about each particle's initial state, sound speed
    /// [`C0`].
    fn physics(&self) -> Physics {
        Physics {
            eos: Eos::TaitReferenced { c0: C0 },
            softening: None,
        }
    }

    /// `side x side` particles per layer, `side` layers.
    fn initial_state(
        &self,
        side: usize,
        config: &HydroConfig,
        share: Share,
        _layout: &Layout,
    ) -> Result<InitialState, AppError> {
        let n = side * side * side;
        let dx = L / side as f64;
        let (mut p, mine) = share.particles(n, field_set(config));
        let h0 = initial_h(config.neighbors.ng0, L * L * L, n);
        let m = RHO0 * L * L * L / n as f64;
        let mut p_ref = vec![0.0; mine.len()];
        for (k, i) in mine.clone().enumerate() {
            let c = [i % side, i / side % side, i / (side * side)];
            let q = c.map(|k| -0.5 * L + (k as f64 + 0.5) * dx);
            (p.x[k], p.y[k], p.z[k]) = (q[0], q[1], q[2]);
            (p.vx[k], p.vy[k]) = (OMEGA * q[1], -OMEGA * q[0]);
            p.m[k] = m;
            p.h[k] = h0;
            p.u[k] = 1.0;
            p_ref[k] = initial_pressure(q[0], q[1]);
        }
        // Reference density 0 = calibrate from the first density evaluation.
        p.eos_ref = [vec![0.0; mine.len()], p_ref];
        let bbox = BoundingBox::new(
            [-0.5 * L; 3],
            [0.5 * L; 3],
            [Boundary::Open, Boundary::Open, Boundary::Periodic],
        )?;
        Ok(InitialState {
            total: n,
            particles: p,
            bbox,
            dt0: 1e-5,
        })
    }
}
