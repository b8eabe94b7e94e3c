//! Evrard collapse: a cold gas sphere with `rho ~ 1/r` (G = M = R = 1)
//! falls in under its own gravity, bounces and settles; compared with the
//! energies of a 1-D Lagrangian reference.

use super::{Request, Listing, cube_lattice, field_set, initial_h, Case, EnergyPoint, InitialState, Physics, Scheme};
use crate::glass;
use crate::AppError;
use sph_core::Eos;
use sph_tree::{Boundary, BoundingBox};

/// Particles per side of the glass block tiled to fill the cube the
/// sphere is cut from (the run's `side` when that is smaller, but at least
/// [`glass::MIN_SIDE`]).
pub const GLASS_SIDE: usize = 15;

/// The case (registered as `evrard`).
#[derive(Debug, Clone, Copy)]
pub struct EvrardCollapse;

/// [`Scheme::GAS`], issue 42's one scheme for the ideal-gas cases, with
/// pairs softened within `(h_i + h_j) / 4` (the case's [`physics`]). Past
/// the bounce the shocked core keeps a velocity dispersion (on a lattice
/// at 30^3, t = 1.0, with conductivity 1: 30 times the kinetic energy
/// the 1-D reference has inside r = 0.2, radial and tangential alike);
/// conduction of its pressure noise turns it into heat, which is why
/// `gas` weights its conduction by the larger of each pair's contrasts
/// of pressure and of `u` (with the contrast of `u` alone, E_kin at
/// t = 2.0 is 13.1% below the reference at 14k particles, E_int 6.9%
/// below at 65k). The case's own scheme before,
/// [`Scheme::EVRARD`] (kernel gradients, no grad-h,
/// switches up to 0.5, conductivity 3), stays selectable with
/// `--scheme evrard` (`docs/schemes.md`, 2026-12-07, evening).
///
/// [`physics`]: Case::physics
pub const SCHEME: Scheme = Scheme::GAS;

/// Courant factor: 1.5 times the default 0.2. With `gas` the total energy
/// through the bounce (t <= 1.5, 14,175 particles) drifts by 1.06e-2 at
/// 0.5 (the `evrard` scheme's old factor), 2.9e-3 at 0.3 and 8.5e-4 at
/// 0.2, while the energies at t = 0.8, 1.0 and 2.0 move by at most 0.7
/// points of percent from 0.5 to 0.3 and 0.2 points from 0.3 to 0.2;
/// 0.3 costs 0.70 of 0.2's particle updates (9.8 M against 14.0 M to
/// t = 2). The signal velocity `c_i + c_j - 3 min(w_ij, 0)` of the
/// paper's viscosity form is about twice SPH-EXA's where the sound speed
/// dominates, so 0.3 is a step of `0.15 h / c` (`docs/schemes.md`,
/// 2026-12-07, evening).
pub const COURANT: f64 = 0.3;

/// Adiabatic index.
pub const GAMMA: f64 = 5.0 / 3.0;
/// Initial specific internal energy.
pub const U0: f64 = 0.05;

/// Energies of the 1-D Lagrangian reference (`docs/cases.md`, +-2%):
/// (t, E_kin, E_int, E_grav).
pub const ENERGIES: [EnergyPoint; 4] = [
    EnergyPoint {
        t: 0.8,
        e_kin: 0.4119,
        e_int: 0.4662,
        e_grav: -1.4948,
    },
    EnergyPoint {
        t: 1.0,
        e_kin: 0.2723,
        e_int: 1.5765,
        e_grav: -2.4654,
    },
    EnergyPoint {
        t: 2.0,
        e_kin: 0.2292,
        e_int: 0.7351,
        e_grav: -1.5810,
    },
    EnergyPoint {
        t: 3.0,
        e_kin: 0.2046,
        e_int: 0.7725,
        e_grav: -1.5937,
    },
];

impl Case for EvrardCollapse {
    fn listing(&self) -> Listing {
        Listing {
            name: "evrard",
            description: "Evrard collapse of a self-gravitating gas sphere vs reference energies",
            side: 30,
            end_time: 2.0,
        }
    }

    fn default_scheme(&self) -> Scheme {
        SCHEME
    }

    /// An ideal gas with [`GAMMA`], self-gravity softened within
    /// `(h_i + h_j) / 4`, Courant factor [`COURANT`].
    fn physics(&self) -> Physics {
        Physics {
            eos: Eos::IdealGas { gamma: GAMMA },
            softening: Some(0.25),
            courant: Some(COURANT),
            stirring: None,
        }
    }

    /// The unit sphere cut from the cube `[-1, 1]^3` filled at spacing
    /// `2 / side` with a glass ([`GLASS_SIDE`]^3 block, tiled; a cubic
    /// lattice with [`Layout::Lattice`](super::Layout::Lattice)), stretched radially
    /// (`r -> (r / R)^(3/2)`, with `R` the radius of the ball the points'
    /// cells fill) so that the enclosed mass goes as `r^2`, i.e.
    /// `rho = 1 / (2 pi r)`; equal masses `1/N`, at rest, `u = 0.05`; h from
    /// the local density. Past the bounce a lattice leaves more velocity
    /// dispersion in the shocked core than a glass (E_kin at t = 1.0, 30^3,
    /// alpha 0.5 and conductivity 1: +18.4% of the reference on the
    /// lattice, +13.3% on the glass).
    fn initial_state(&self, request: &Request<'_>) -> Result<InitialState, AppError> {
        let Request { side, config, share, layout } = *request;
        let cell = 2.0 / side as f64;
        let inside = |q: &[f64; 3]| q[0] * q[0] + q[1] * q[1] + q[2] * q[2] < 1.0;
        let pts: Vec<[f64; 3]> = match layout.glass(side.clamp(glass::MIN_SIDE, GLASS_SIDE), config)? {
            Some(g) => g
                .fill([-1.0; 3], [1.0; 3], cell)
                .into_iter()
                .filter(inside)
                .collect(),
            None => cube_lattice(side, -1.0, 2.0).filter(inside).collect(),
        };
        let n = pts.len();
        let (mut p, mine) = share.particles(n, field_set(config));
        let m = 1.0 / n as f64;
        // The n points cut at r < 1 fill the ball whose volume is n cells,
        // a little over 1 (1.0045 for the 30^3 lattice); mapping that
        // radius to 1 gives the enclosed mass r^2 up to the surface (mapping
        // 1 to 1 leaves the sphere 0.9% less bound than -2/3).
        let filled_radius = (3.0 * n as f64 / (4.0 * std::f64::consts::PI)).cbrt() * cell;
        for (i, q) in pts[mine].iter().enumerate() {
            let r = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            let s = (r / filled_radius).sqrt() / filled_radius; // r_new / r
            let r_new = r * s;
            (p.x[i], p.y[i], p.z[i]) = (q[0] * s, q[1] * s, q[2] * s);
            // Number density N rho / M = N / (2 pi r): a uniform set of that
            // density in the unit volume has 2 pi r / N per particle.
            let volume_per = 2.0 * std::f64::consts::PI * r_new.max(0.5 / side as f64) / n as f64;
            p.h[i] = initial_h(config.neighbors.ng0, volume_per, 1);
            p.m[i] = m;
            p.u[i] = U0;
        }
        Ok(InitialState {
            total: n,
            particles: p,
            bbox: BoundingBox::cube(-1.0, 1.0, Boundary::Open)?,
            dt0: 1e-4,
        })
    }

    fn energies(&self) -> Option<&'static [EnergyPoint]> {
        Some(&ENERGIES)
    }
}
