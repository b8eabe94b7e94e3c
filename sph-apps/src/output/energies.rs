//! The energies of a run over time: their comparison with a case's
//! reference table (in `summary.json`) and `energies.png`.

use crate::cases::EnergyPoint;
use crate::AppError;
use plotters::style::RGBColor;
use sph_core::Conserved;
use std::path::Path;

/// The run's energies at a reference time, beside the reference values.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct EnergyCheck {
    /// Time.
    pub t: f64,
    /// Kinetic energy of the run.
    pub e_kin: f64,
    /// Internal energy of the run.
    pub e_int: f64,
    /// Gravitational energy of the run.
    pub e_grav: f64,
    /// Reference kinetic energy.
    pub e_kin_ref: f64,
    /// Reference internal energy.
    pub e_int_ref: f64,
    /// Reference gravitational energy.
    pub e_grav_ref: f64,
}

/// `[t, E_kin, E_int, E_grav]` of every step (a few numbers per step, the
/// same on every rank).
#[derive(Debug, Clone, Default)]
pub struct EnergyTrack {
    samples: Vec<[f64; 4]>,
}

impl EnergyTrack {
    /// No samples yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the energies `c` at time `t` (times increasing).
    pub fn push(&mut self, t: f64, c: &Conserved) {
        self.samples.push([t, c.e_kin, c.e_int, c.e_grav]);
    }

    /// `[E_kin, E_int, E_grav]` at `t`, linear between the samples,
    /// constant beyond them.
    ///
    /// # Panics
    /// Without samples.
    pub fn at(&self, t: f64) -> [f64; 3] {
        let s = &self.samples;
        let k = s.partition_point(|s| s[0] < t);
        if k == 0 {
            return [s[0][1], s[0][2], s[0][3]];
        }
        if k == s.len() {
            let s = s[k - 1];
            return [s[1], s[2], s[3]];
        }
        let (a, b) = (s[k - 1], s[k]);
        let w = if b[0] > a[0] {
            (t - a[0]) / (b[0] - a[0])
        } else {
            1.0
        };
        std::array::from_fn(|j| a[j + 1] + w * (b[j + 1] - a[j + 1]))
    }

    /// The run's energies beside the reference values at the reference
    /// times up to `t_end`.
    pub fn checks(&self, reference: &[EnergyPoint], t_end: f64) -> Vec<EnergyCheck> {
        reference
            .iter()
            .filter(|e| e.t <= t_end * (1.0 + 1e-12))
            .map(|e| {
                let at = self.at(e.t);
                EnergyCheck {
                    t: e.t,
                    e_kin: at[0],
                    e_int: at[1],
                    e_grav: at[2],
                    e_kin_ref: e.e_kin,
                    e_int_ref: e.e_int,
                    e_grav_ref: e.e_grav,
                }
            })
            .collect()
    }

    /// `energies.png`: the energies against time with the reference values
    /// as markers.
    pub fn plot(
        &self,
        path: &Path,
        title: &str,
        reference: &[EnergyPoint],
    ) -> Result<(), AppError> {
        let pick = |f: fn(&[f64; 4]) -> f64| -> Vec<(f64, f64)> {
            self.samples.iter().map(|s| (s[0], f(s))).collect()
        };
        let kin = pick(|s| s[1]);
        let int = pick(|s| s[2]);
        let grav = pick(|s| s[3]);
        let tot = pick(|s| s[1] + s[2] + s[3]);
        let colours = [
            RGBColor(214, 39, 40),
            RGBColor(31, 119, 180),
            RGBColor(44, 160, 44),
            RGBColor(0, 0, 0),
        ];
        let rk: Vec<(f64, f64)> = reference.iter().map(|e| (e.t, e.e_kin)).collect();
        let ri: Vec<(f64, f64)> = reference.iter().map(|e| (e.t, e.e_int)).collect();
        let rg: Vec<(f64, f64)> = reference.iter().map(|e| (e.t, e.e_grav)).collect();
        crate::plot::energy_png(
            path,
            title,
            &[
                ("E_kin", colours[0], &kin),
                ("E_int", colours[1], &int),
                ("E_grav", colours[2], &grav),
                ("E_tot", colours[3], &tot),
            ],
            &[
                ("E_kin ref", colours[0], &rk),
                ("E_int ref", colours[1], &ri),
                ("E_grav ref", colours[2], &rg),
            ],
        )
    }
}
