//! Noh implosion: a sphere of radius 0.5 cut from a lattice, uniform
//! density, falling inwards at unit speed, open boundaries.

use super::{Request, Listing, cube_lattice, field_set, initial_h, Case, InitialState, Reference, Scheme};
use crate::reference::Noh;
use crate::AppError;
use sph_tree::{Boundary, BoundingBox};

/// The case (registered as `noh`).
#[derive(Debug, Clone, Copy)]
pub struct NohImplosion;

/// Noh's scheme: `gas`, issue 42's one default for the ideal-gas cases
/// ([`Scheme::GAS`]): its viscosity switches stop at alpha = 0.3 in shocks
/// into cold gas. With the paper's constant alpha = 1 the viscosity also
/// heats the converging inflow and the mean post-shock density (0.3 to 0.8
/// shock radii) stays near 21 rho0 against 64 rho0. The `noh` preset
/// ([`Scheme::NOH`], kernel gradients, switches up to 0.7), this case's
/// scheme before `gas`, gives 58 rho0 at 14328 particles (30^3 cut), 66
/// rho0 at 26745 (37^3 cut) and 62 rho0 at 33552 (40^3 cut).
pub const SCHEME: Scheme = Scheme::GAS;

/// Adiabatic index (that of the default gas, [`super::Physics::IDEAL_GAS`]).
pub const GAMMA: f64 = 5.0 / 3.0;
/// Radius of the sphere.
pub const RADIUS: f64 = 0.5;
/// Initial specific internal energy (cold, but positive).
pub const U0: f64 = 1e-6;

impl Case for NohImplosion {
    /// The default lattice, 37^3 cut to the sphere, holds 26745 particles:
    /// as many as a 30^3 cube.
    fn listing(&self) -> Listing {
        Listing {
            name: "noh",
            description: "Noh implosion of a cold sphere vs the exact solution (64x compression)",
            side: 37,
            end_time: 0.3,
        }
    }

    fn default_scheme(&self) -> Scheme {
        SCHEME
    }


    /// A `side^3` lattice of the cube `[-0.5, 0.5]^3` cut to the sphere,
    /// unit total mass, unit inward speed.
    fn initial_state(&self, request: &Request<'_>) -> Result<InitialState, AppError> {
        let Request { side, config, share, .. } = *request;
        let pts = sphere(side);
        let n = pts.len();
        let m = 1.0 / n as f64;
        let h0 = initial_h(config.neighbors.ng0, 1.0, side * side * side);
        let (mut p, mine) = share.particles(n, field_set(config));
        for (k, q) in pts[mine].iter().enumerate() {
            let r = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            (p.x[k], p.y[k], p.z[k]) = (q[0], q[1], q[2]);
            if r > 0.0 {
                (p.vx[k], p.vy[k], p.vz[k]) = (-q[0] / r, -q[1] / r, -q[2] / r);
            }
            p.m[k] = m;
            p.h[k] = h0;
            p.u[k] = U0;
        }
        Ok(InitialState {
            total: n,
            particles: p,
            bbox: BoundingBox::cube(-0.5, 0.5, Boundary::Open)?,
            dt0: 1e-4,
        })
    }

    /// The exact solution for the particle set's actual density: the
    /// particle mass over the lattice cell volume.
    fn reference(
        &self,
        side: usize,
        initial: &InitialState,
    ) -> Result<Option<Reference>, AppError> {
        let m = 1.0 / initial.total as f64;
        let rho0 = m * (side * side * side) as f64;
        let noh = Noh::new(GAMMA, rho0, 1.0)?.with_ambient_u(U0);
        Ok(Some(Reference::Noh(noh)))
    }
}

/// The cell centres of a `side^3` lattice of `[-0.5, 0.5]^3` inside the
/// sphere of [`RADIUS`].
fn sphere(side: usize) -> Vec<[f64; 3]> {
    cube_lattice(side, -0.5, 1.0)
        .filter(|q| (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt() < RADIUS)
        .collect()
}
