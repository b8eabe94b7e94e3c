//! The shell spectrum of the mass-weighted velocity and its slope.

use super::fft::Fft3;
use super::{SpectrumError, SpectrumGrid};
use rustfft::num_complex::Complex64;
use rustfft::FftDirection;
use std::f64::consts::PI;
use std::io;

/// Kinetic energy per unit mass by wavenumber shell.
///
/// Shell `k` holds the modes `n` (integers, wavevector `2 pi n / L`) with
/// `k - 1/2 <= |n| < k + 1/2`, for `k = 0` (the mean flow) up to the
/// corners of the grid, `round(sqrt(3) N_g / 2)`; shells beyond `N_g / 2`
/// are incomplete. `E(k) = 1/2 sum |u^(n)|^2` over the shell with
/// `u^ = FFT(u) / N_g^3`.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrum {
    /// Shell wavenumbers `0, 1, ..., k_max` (units of `2 pi / L`).
    pub k: Vec<f64>,
    /// `E(k)`.
    pub e: Vec<f64>,
    /// The solenoidal part of `E(k)`: `u^` less its projection on `n / |n|`.
    pub e_sol: Vec<f64>,
    /// The compressive part of `E(k)`: the projection on `n / |n|`. The
    /// mean flow (`k = 0`) is neither, so `e_sol[0] = e_comp[0] = 0`.
    pub e_comp: Vec<f64>,
    /// Modes in each shell.
    pub cells: Vec<u64>,
    /// `<|u|^2> / 2` over the grid cells, in real space: equals the sum of
    /// `e` (Parseval) unless the spectrum is deconvolved.
    pub grid_energy: f64,
    /// Whether each mode was divided by the TSC window.
    pub deconvolved: bool,
}

impl Spectrum {
    /// The sum of `E(k)` over all shells, corners included.
    pub fn total(&self) -> f64 {
        self.e.iter().sum()
    }
}

/// The spectrum of the mass-weighted velocity `u = j / rho_bar` of a
/// deposited grid: momentum density over the mean density, linear in the
/// particles, so the TSC window is a factor of each mode and `deconvolve`
/// divides it out, `W(n) = prod_i sinc^3(pi n_i / N_g)` (no zero for
/// `|n_i| <= N_g / 2`); what it leaves is the alias sum of the window.
///
/// Frequencies follow the FFT convention: index `N_g / 2` is `-N_g / 2`,
/// which decides the direction `n / |n|` of those Nyquist modes in the
/// solenoidal/compressive split (shells `k >= N_g / 2` only).
pub fn velocity_spectrum(grid: &SpectrumGrid, deconvolve: bool) -> Result<Spectrum, SpectrumError> {
    let n = grid.n();
    let n3 = n * n * n;
    let mass: i128 = grid.field(0).iter().map(|&v| i128::from(v)).sum();
    if mass <= 0 {
        return Err(SpectrumError::NoMass {
            mass: grid.total_mass(),
        });
    }
    let scale = grid.scale();
    // u = (P / s_p) / h^3 / ((M / s_m) / L^3) = P N^3 s_m / (s_p M).
    let to_u = scale.mass_scale() / scale.momentum_scale() * n3 as f64 / mass as f64;
    let mut u: Vec<Vec<Complex64>> = (1..4)
        .map(|f| {
            grid.field(f)
                .iter()
                .map(|&p| Complex64::new(p as f64 * to_u, 0.0))
                .collect()
        })
        .collect();
    let grid_energy = u.iter().flatten().map(|c| c.re * c.re).sum::<f64>() / (2 * n3) as f64;
    let mut fft = Fft3::new(n, FftDirection::Forward);
    for c in &mut u {
        fft.process(c);
    }

    let freq: Vec<i64> = (0..n).map(|i| frequency(i, n)).collect();
    let window: Vec<f64> = freq
        .iter()
        .map(|&f| {
            if deconvolve {
                sinc(PI * f as f64 / n as f64).powi(3)
            } else {
                1.0
            }
        })
        .collect();
    let half = (n / 2) as i64;
    let shells = shell(3 * half * half) + 1;
    let mut s = Spectrum {
        k: (0..shells).map(|k| k as f64).collect(),
        e: vec![0.0; shells],
        e_sol: vec![0.0; shells],
        e_comp: vec![0.0; shells],
        cells: vec![0; shells],
        grid_energy,
        deconvolved: deconvolve,
    };
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let c = (i * n + j) * n + k;
                let nv = [freq[i], freq[j], freq[k]];
                let n2 = nv.iter().map(|v| v * v).sum::<i64>();
                let b = shell(n2);
                // u^ = FFT(u) / N^3, over the window if deconvolved.
                let norm = 1.0 / (n3 as f64 * window[i] * window[j] * window[k]);
                let a = [u[0][c] * norm, u[1][c] * norm, u[2][c] * norm];
                s.e[b] += 0.5 * a.iter().map(|v| v.norm_sqr()).sum::<f64>();
                s.cells[b] += 1;
                if n2 > 0 {
                    let len = (n2 as f64).sqrt();
                    let nh = nv.map(|v| v as f64 / len);
                    let along: Complex64 = (0..3).map(|d| a[d] * nh[d]).sum();
                    s.e_comp[b] += 0.5 * along.norm_sqr();
                    // The remainder directly, not |u^|^2 - |along|^2, which
                    // would cancel for compressive modes.
                    s.e_sol[b] += 0.5
                        * (0..3)
                            .map(|d| (a[d] - along * nh[d]).norm_sqr())
                            .sum::<f64>();
                }
            }
        }
    }
    Ok(s)
}

/// The least-squares slope of `ln E` against `ln k` over the shells
/// `k_lo..=k_hi` (`1 <= k_lo < k_hi`, each with `E > 0`).
pub fn slope(spectrum: &Spectrum, k_lo: usize, k_hi: usize) -> Result<f64, SpectrumError> {
    let fail = |why: String| SpectrumError::SlopeRange { k_lo, k_hi, why };
    if k_lo < 1 || k_hi <= k_lo {
        return Err(fail("needs 1 <= k_lo < k_hi".into()));
    }
    if k_hi >= spectrum.e.len() {
        return Err(fail(format!(
            "the spectrum ends at k = {}",
            spectrum.e.len() - 1
        )));
    }
    let mut pts = Vec::with_capacity(k_hi - k_lo + 1);
    for k in k_lo..=k_hi {
        let e = spectrum.e[k];
        if !(e.is_finite() && e > 0.0) {
            return Err(fail(format!("E({k}) = {e} has no logarithm")));
        }
        pts.push((spectrum.k[k].ln(), e.ln()));
    }
    let m = pts.len() as f64;
    let (mx, my) = pts
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / m, b + y / m));
    let (sxy, sxx) = pts.iter().fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    Ok(sxy / sxx)
}

/// Writes `k,E,E_sol,E_comp,cells`, one shell per line (shortest
/// round-trip decimals).
pub fn write_spectrum_csv(w: &mut impl io::Write, s: &Spectrum) -> io::Result<()> {
    writeln!(w, "k,E,E_sol,E_comp,cells")?;
    for i in 0..s.k.len() {
        writeln!(
            w,
            "{},{},{},{},{}",
            s.k[i], s.e[i], s.e_sol[i], s.e_comp[i], s.cells[i]
        )?;
    }
    Ok(())
}

/// The signed frequency of FFT index `i` of `n` (index `n / 2` is `-n / 2`).
pub(crate) fn frequency(i: usize, n: usize) -> i64 {
    if i < n.div_ceil(2) {
        i as i64
    } else {
        i as i64 - n as i64
    }
}

/// The shell of a mode with `|n|^2 = n2`: `round(|n|)` (never a tie, as
/// `(k + 1/2)^2` is not an integer).
fn shell(n2: i64) -> usize {
    ((n2 as f64).sqrt() + 0.5) as usize
}

/// `sin x / x`, 1 at 0.
pub(crate) fn sinc(x: f64) -> f64 {
    if x == 0.0 {
        1.0
    } else {
        x.sin() / x
    }
}
