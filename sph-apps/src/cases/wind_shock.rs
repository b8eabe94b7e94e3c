//! Wind-shock (cloud crushing): a cold dense cloud (radius 0.025, rho 10)
//! at rest in a hot supersonic wind (rho 1, u 1.5, v_x 2.7, Mach 2.1) in
//! the periodic box `1 x 0.25 x 0.25`, in pressure equilibrium, gamma 5/3
//! (`docs/cases.md`). The wind shocks on the cloud and strips
//! it; the observable is the surviving cloud fraction against t / tau_KH
//! (tau_KH = 0.0937): the mass with rho >= 0.64 rho_cloud and
//! u <= 0.9 u_wind (temperature at most 0.9 of the wind's) over the
//! nominal cloud mass, in `curve.csv` every step. The test of the case
//! is robustness (no NaN, no negative u) to 2 tau_KH.
//!
//! Both gases are equal-mass particles, the cloud's spacing 10^(-1/3) of
//! the wind's, cut from one periodic glass block ([`crate::glass`],
//! `side/4` particles per side, relaxed with the run's kernel and
//! neighbour counts: at the wind's spacing it spans the box's width once,
//! so the wind has no seam across the periodic faces) or, with
//! [`Layout::Lattice`](super::Layout::Lattice), from cubic lattices.

use super::{Request, field_set, initial_h, Case, Curve, InitialState, Listing, Scheme};
use crate::AppError;
use sph_core::Particles;
use sph_tree::{Boundary, BoundingBox};

/// The case (registered as `wind-shock`).
#[derive(Debug, Clone, Copy)]
pub struct WindShock;

/// Adiabatic index (that of the default gas, [`super::Physics::IDEAL_GAS`]).
pub const GAMMA: f64 = 5.0 / 3.0;
/// Cloud radius.
pub const RADIUS: f64 = 0.025;
/// Cloud density.
pub const RHO_CLOUD: f64 = 10.0;
/// Wind density.
pub const RHO_WIND: f64 = 1.0;
/// Wind specific internal energy.
pub const U_WIND: f64 = 1.5;
/// Wind speed along x.
pub const V_WIND: f64 = 2.7;
/// Kelvin-Helmholtz time of the cloud (`docs/cases.md`).
pub const TAU_KH: f64 = 0.0937;
/// Box size (x, y, z).
pub const BOX: [f64; 3] = [1.0, 0.25, 0.25];
/// Cloud centre.
pub const CENTRE: [f64; 3] = [0.125, 0.125, 0.125];

/// Particle `i`'s surviving-cloud mass.
fn survival_terms(p: &Particles, i: usize, out: &mut [f64]) {
    let cold = p.u[i] <= 0.9 * U_WIND;
    let dense = p.rho[i] >= 0.64 * RHO_CLOUD;
    out[0] = if cold && dense { p.m[i] } else { 0.0 };
}

/// The surviving mass over the nominal cloud mass `rho_c 4/3 pi R^3` (the
/// lattice cut to the sphere holds a few percent more or less).
fn survival_fraction(sums: &[f64]) -> Vec<f64> {
    let cloud = RHO_CLOUD * 4.0 / 3.0 * std::f64::consts::PI * RADIUS.powi(3);
    vec![sums[0] / cloud]
}

impl Case for WindShock {
    /// `side` wind particles per unit length (the box is `side x side/4 x
    /// side/4`; `side` a multiple of 4): 64 gives 16,539 particles from
    /// glass, 16,536 from lattices.
    fn listing(&self) -> Listing {
        Listing {
            name: "wind-shock",
            description: "Dense cloud in a supersonic wind (cloud crushing): surviving fraction vs t/tau_KH",
            side: 64,
            end_time: 2.0 * TAU_KH,
        }
    }

    /// `gas` ([`Scheme::GAS`]), issue 42's one default for the ideal-gas
    /// cases (the isobaric cube keeps its own until it meets its bound).
    fn default_scheme(&self) -> Scheme {
        Scheme::GAS
    }

    fn initial_state(&self, request: &Request<'_>) -> Result<InitialState, AppError> {
        let Request { side, config, share, layout } = *request;
        if !side.is_multiple_of(4) {
            return Err(AppError::Usage(format!(
                "case wind-shock: {side} particles per unit length; it must be a multiple of 4 (the box is 1 x 0.25 x 0.25)"
            )));
        }
        // The kernel's support (2h, in spacings of the wind) must stay
        // inside half the 0.25-wide box, with 10% to spare for h to grow.
        let support = 2.0 * initial_h(config.neighbors.ng0, 1.0, 1);
        let least = ((8.0 * 1.1 * support).ceil() as usize).next_multiple_of(4);
        if side < least {
            return Err(AppError::Usage(format!(
                "case wind-shock: {side} particles per unit length puts {} across the 0.25-wide box, \
                 too few for ng0 = {}; give -n {least} or more (or a smaller --ng0)",
                side / 4,
                config.neighbors.ng0
            )));
        }
        let d = 1.0 / side as f64;
        let dc = d * (RHO_WIND / RHO_CLOUD).cbrt();
        let dist = |q: [f64; 3]| {
            ((q[0] - CENTRE[0]).powi(2) + (q[1] - CENTRE[1]).powi(2) + (q[2] - CENTRE[2]).powi(2))
                .sqrt()
        };
        let lattice = |spacing: f64, lo: [f64; 3], counts: [usize; 3]| {
            (0..counts[0] * counts[1] * counts[2]).map(move |g| {
                let c = [g % counts[0], g / counts[0] % counts[1], g / (counts[0] * counts[1])];
                std::array::from_fn::<f64, 3, _>(|k| lo[k] + (c[k] as f64 + 0.5) * spacing)
            })
        };
        let k = (2.0 * RADIUS / dc).ceil() as usize + 1;
        let lo = CENTRE.map(|c| c - 0.5 * k as f64 * dc);
        let (wind, cloud): (Vec<[f64; 3]>, Vec<[f64; 3]>) = match layout.glass(side / 4, config)? {
            None => (
                lattice(d, [0.0; 3], [side, side / 4, side / 4]).collect(),
                lattice(dc, lo, [k; 3]).collect(),
            ),
            Some(g) => {
                let hi = lo.map(|c| c + k as f64 * dc);
                (g.fill([0.0; 3], BOX, d), g.fill(lo, hi, dc))
            }
        };
        let mut pts: Vec<([f64; 3], bool)> = wind
            .into_iter()
            .filter(|&q| dist(q) >= RADIUS)
            .map(|q| (q, false))
            .collect();
        pts.extend(
            cloud
                .into_iter()
                .filter(|&q| dist(q) < RADIUS)
                .map(|q| (q, true)),
        );
        let n = pts.len();
        let m = RHO_WIND * d * d * d;
        let h_wind = initial_h(config.neighbors.ng0, d * d * d, 1);
        let pressure = (GAMMA - 1.0) * RHO_WIND * U_WIND;
        let (mut p, mine) = share.particles(n, field_set(config));
        for (k, &(q, cloud)) in pts[mine].iter().enumerate() {
            (p.x[k], p.y[k], p.z[k]) = (q[0], q[1], q[2]);
            p.m[k] = m;
            if cloud {
                p.h[k] = h_wind * dc / d;
                p.u[k] = pressure / ((GAMMA - 1.0) * RHO_CLOUD);
            } else {
                p.h[k] = h_wind;
                p.u[k] = U_WIND;
                p.vx[k] = V_WIND;
            }
        }
        Ok(InitialState {
            total: n,
            particles: p,
            bbox: BoundingBox::new([0.0; 3], BOX, [Boundary::Periodic; 3])?,
            dt0: 1e-5 * 64.0 * d,
        })
    }

    fn curve(&self) -> Option<Curve> {
        Some(Curve {
            label: "surviving cloud fraction",
            columns: &["surviving_fraction"],
            sums: 1,
            terms: survival_terms,
            finish: survival_fraction,
            reference: &[],
        })
    }
}
