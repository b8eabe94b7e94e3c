//! The Gresho-Chan vortex in a thin periodic slab: a rotating flow held
//! by its pressure gradient, so nothing should change; SPH's viscosity and
//! noise make it decay. Set-up of `docs/cases.md`: R1 = 0.2,
//! rho = 1, P0 = 5, gamma = 5/3, box `[-0.5, 0.5)^2` in x and y, 8 lattice
//! spacings in z, all periodic, to t = 1. The error is `L1(v_phi)` for
//! cylindrical radii up to 0.5.

use super::{Request, field_set, initial_h, Case, InitialState, Listing, Reference, Scheme};
use crate::reference::Gresho;
use crate::AppError;
use sph_tree::{Boundary, BoundingBox};

/// The case (registered as `gresho`).
#[derive(Debug, Clone, Copy)]
pub struct GreshoVortex;

/// Adiabatic index (that of the default gas, [`super::Physics::IDEAL_GAS`]).
pub const GAMMA: f64 = 5.0 / 3.0;
/// Lattice layers in z (2h is 2.9 spacings at ng0 = 100: under half of 8).
pub const LAYERS: usize = 8;

impl Case for GreshoVortex {
    /// `side` particles along x and y; 50 gives 20,000 particles.
    fn listing(&self) -> Listing {
        Listing {
            name: "gresho",
            description: "Gresho-Chan vortex in a thin periodic slab (stationary: the initial state is the answer)",
            side: 50,
            end_time: 1.0,
        }
    }

    /// `gas` ([`Scheme::GAS`]), issue 42's one default for the ideal-gas
    /// cases (the isobaric cube keeps its own until it meets its bound).
    fn default_scheme(&self) -> Scheme {
        Scheme::GAS
    }

    /// A `side x side x 8` lattice.
    fn initial_state(&self, request: &Request<'_>) -> Result<InitialState, AppError> {
        let Request { side, config, share, .. } = *request;
        let vortex = Gresho::standard(GAMMA)?;
        let layers = LAYERS.max(1);
        let dx = 1.0 / side as f64;
        let n = side * side * layers;
        let h0 = initial_h(config.neighbors.ng0, dx * dx * dx, 1);
        let (mut p, mine) = share.particles(n, field_set(config));
        for (k, g) in mine.enumerate() {
            let c = [g % side, g / side % side, g / (side * side)];
            let [x, y, z] = c.map(|i| (i as f64 + 0.5) * dx);
            let (x, y) = (x - 0.5, y - 0.5);
            let r = x.hypot(y);
            let s = vortex.state(r);
            (p.x[k], p.y[k], p.z[k]) = (x, y, z);
            if r > 0.0 {
                (p.vx[k], p.vy[k]) = (-s.v * y / r, s.v * x / r);
            }
            p.m[k] = vortex.density() * dx * dx * dx;
            p.h[k] = h0;
            p.u[k] = s.u;
        }
        Ok(InitialState {
            total: n,
            particles: p,
            bbox: BoundingBox::new(
                [-0.5, -0.5, 0.0],
                [0.5, 0.5, layers as f64 * dx],
                [Boundary::Periodic; 3],
            )?,
            dt0: 1e-4 * 50.0 * dx,
        })
    }

    fn reference(
        &self,
        _side: usize,
        _initial: &InitialState,
    ) -> Result<Option<Reference>, AppError> {
        Ok(Some(Reference::Vortex(Gresho::standard(GAMMA)?)))
    }
}
