//! Kelvin-Helmholtz instability with smoothed interfaces (McNally, Lyra &
//! Passy 2012): in `[0, 1)^2` (x, y; a thin periodic slab in z) a band
//! `0.25 < y < 0.75` of rho = 2 moving at v_x = -0.5 between gas of
//! rho = 1 at v_x = +0.5, the density and velocity ramps exponential with
//! width 0.025, P = 2.5, gamma = 5/3, seeded by v_y = 0.01 sin(4 pi x).
//! The observable is the amplitude M(t) of the seeded mode (their
//! eqs. 6-8), written every step to `curve.csv`; their converged
//! reference reaches M(1.5) = 0.1479 (`docs/cases.md`).
//!
//! The particles sit on one cubic lattice with masses `rho(y) dx^3`, so the
//! smoothed profile is resolved without stretching the lattice.

use super::{Request, 
    field_set, initial_h, Case, Curve, InitialState, Listing, Scheme,
};
use crate::AppError;
use sph_core::Particles;
use sph_tree::{Boundary, BoundingBox};
use std::f64::consts::PI;

/// The case (registered as `kelvin-helmholtz`).
#[derive(Debug, Clone, Copy)]
pub struct KelvinHelmholtz;

/// Adiabatic index (that of the default gas, [`super::Physics::IDEAL_GAS`]).
pub const GAMMA: f64 = 5.0 / 3.0;
/// Pressure everywhere.
pub const PRESSURE: f64 = 2.5;
/// Width of the interface ramps.
pub const DELTA: f64 = 0.025;
/// Amplitude of the seed `v_y`.
pub const SEED: f64 = 0.01;
/// Lattice layers in z.
pub const LAYERS: usize = 8;

/// McNally et al.'s converged M(t) at t = 1.5 (their reference run).
pub const M_REFERENCE: &[(f64, f64)] = &[(1.5, 0.1479)];

/// The smoothed profile `f(y)` between `outer` (y near 0 and 1) and
/// `inner` (the band), McNally eq. 1-4.
pub fn profile(y: f64, outer: f64, inner: f64) -> f64 {
    let mid = 0.5 * (outer - inner);
    let y = y.rem_euclid(1.0);
    if y < 0.25 {
        outer - mid * ((y - 0.25) / DELTA).exp()
    } else if y < 0.5 {
        inner + mid * ((0.25 - y) / DELTA).exp()
    } else if y < 0.75 {
        inner + mid * ((y - 0.75) / DELTA).exp()
    } else {
        outer - mid * ((0.75 - y) / DELTA).exp()
    }
}

/// Density at height `y`.
pub fn density(y: f64) -> f64 {
    profile(y, 1.0, 2.0)
}

/// `v_x` at height `y`.
pub fn velocity_x(y: f64) -> f64 {
    profile(y, 0.5, -0.5)
}

/// Particle `i`'s terms of the mode amplitude: `[s_i, c_i, d_i]` times its
/// volume `m_i / rho_i` (McNally eqs. 6-8).
fn mode_terms(p: &Particles, i: usize, out: &mut [f64]) {
    let (x, y) = (p.x[i], p.y[i].rem_euclid(1.0));
    let off = if y < 0.5 { y - 0.25 } else { 1.0 - y - 0.25 };
    let d = (-4.0 * PI * off.abs()).exp();
    let volume = if p.rho[i] > 0.0 { p.m[i] / p.rho[i] } else { 0.0 };
    let (sin, cos) = (4.0 * PI * x).sin_cos();
    out[0] = p.vy[i] * sin * d * volume;
    out[1] = p.vy[i] * cos * d * volume;
    out[2] = d * volume;
}

/// `M = 2 sqrt((S/D)^2 + (C/D)^2)`.
fn mode_amplitude(sums: &[f64]) -> Vec<f64> {
    let (s, c, d) = (sums[0], sums[1], sums[2]);
    let m = if d > 0.0 {
        2.0 * ((s / d).powi(2) + (c / d).powi(2)).sqrt()
    } else {
        f64::NAN
    };
    vec![m]
}

impl Case for KelvinHelmholtz {
    /// `side` particles along x and y; 64 gives 32,768 particles.
    fn listing(&self) -> Listing {
        Listing {
            name: "kelvin-helmholtz",
            description: "Kelvin-Helmholtz instability (McNally et al. 2012), mode amplitude M(t) vs their M(1.5)",
            side: 64,
            end_time: 1.5,
        }
    }

    /// `gas` ([`Scheme::GAS`], issue 42's default for the ideal-gas
    /// cases), whose AV cleaning (after SPH-EXA's) leaves the layer's
    /// shear undamped. At 32^2 x 8 its M(1.5) is 0.0756 under block time
    /// steps against 0.0775 for `shear` ([`Scheme::SHEAR`], the case's
    /// scheme until 2026-12-07) and 0.0855 under global steps against 0.066
    /// (2026-12-07, evening: the larger conduction contrast and the
    /// strong-shock ceiling 0.3). At the case's default 64^2 x 8, block
    /// steps: 0.1053 against `shear`'s 0.1117 (0.1137 before those two
    /// changes; with the contrast of `u` alone, 0.1137 again: the pressure
    /// contrast damps the mode). Issue 42's "no lower than `shear`" is
    /// missed by 2.5% at 32^2 and 6% at 64^2 under block steps
    /// (`docs/schemes.md`, 2026-12-07, night).
    fn default_scheme(&self) -> Scheme {
        Scheme::GAS
    }

    /// A `side x side x 8` lattice.
    fn initial_state(&self, request: &Request<'_>) -> Result<InitialState, AppError> {
        let Request { side, config, share, .. } = *request;
        let dx = 1.0 / side as f64;
        let n = side * side * LAYERS;
        let h0 = initial_h(config.neighbors.ng0, dx * dx * dx, 1);
        let (mut p, mine) = share.particles(n, field_set(config));
        for (k, g) in mine.enumerate() {
            let c = [g % side, g / side % side, g / (side * side)];
            let [x, y, z] = c.map(|i| (i as f64 + 0.5) * dx);
            let rho = density(y);
            (p.x[k], p.y[k], p.z[k]) = (x, y, z);
            (p.vx[k], p.vy[k]) = (velocity_x(y), SEED * (4.0 * PI * x).sin());
            p.m[k] = rho * dx * dx * dx;
            p.h[k] = h0;
            p.u[k] = PRESSURE / ((GAMMA - 1.0) * rho);
        }
        Ok(InitialState {
            total: n,
            particles: p,
            bbox: BoundingBox::new(
                [0.0, 0.0, 0.0],
                [1.0, 1.0, LAYERS as f64 * dx],
                [Boundary::Periodic; 3],
            )?,
            dt0: 1e-4 * 64.0 * dx,
        })
    }

    fn curve(&self) -> Option<Curve> {
        Some(Curve {
            label: "mode amplitude M",
            columns: &["M"],
            sums: 3,
            terms: mode_terms,
            finish: mode_amplitude,
            reference: M_REFERENCE,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sph_core::HydroConfig;

    /// The profile's plateaus and the continuity of its pieces.
    #[test]
    fn profile_is_smooth_with_the_right_plateaus() {
        assert!((density(0.0) - 1.0).abs() < 1e-4);
        assert!((density(0.5) - 2.0).abs() < 1e-4);
        assert!((velocity_x(0.0) - 0.5).abs() < 1e-4);
        assert!((velocity_x(0.5) + 0.5).abs() < 1e-4);
        for y in [0.25, 0.5, 0.75] {
            let (a, b) = (density(y - 1e-12), density(y + 1e-12));
            assert!((a - b).abs() < 1e-9, "jump at {y}: {a} {b}");
        }
        assert!((density(0.25) - 1.5).abs() < 1e-12);
    }

    /// The seed alone gives M = SEED: S/D = SEED <sin^2> = SEED / 2.
    #[test]
    fn seeded_lattice_has_the_seed_amplitude() {
        let case = KelvinHelmholtz;
        let scene = case.setup(32, HydroConfig::default()).unwrap();
        let mut p = scene.particles;
        // Volumes from the set-up density (no solver here).
        for i in 0..p.len() {
            p.rho[i] = density(p.y[i]);
        }
        let curve = case.curve().unwrap();
        let mut sums = [0.0; 3];
        let mut t = [0.0; 3];
        for i in 0..p.len() {
            (curve.terms)(&p, i, &mut t);
            for k in 0..3 {
                sums[k] += t[k];
            }
        }
        let m = (curve.finish)(&sums)[0];
        assert!((m / SEED - 1.0).abs() < 1e-6, "M = {m}");
    }
}
