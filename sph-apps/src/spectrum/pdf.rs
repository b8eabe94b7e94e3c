//! The mass-weighted PDF of `s = ln(rho / rho_bar)`, in exact sums.

use super::grid::check_lengths;
use super::SpectrumError;
use sph_comm::ExactSum;
use std::io;

/// Bins of the PDF over `[S_MIN, S_MAX)`.
pub const PDF_BINS: usize = 200;
/// Lower edge of the first bin.
pub const S_MIN: f64 = -2.0;
/// Upper edge of the last bin.
pub const S_MAX: f64 = 2.0;

/// Bins per unit of `s` (exact: 200 / 4).
const BINS_PER_UNIT: f64 = PDF_BINS as f64 / (S_MAX - S_MIN);

/// Sums after the bins: the mass below `S_MIN` and at or above `S_MAX`,
/// then `sum m`, `sum m s`, `sum m s^2` over all particles.
const BELOW: usize = PDF_BINS;
const ABOVE: usize = PDF_BINS + 1;
const MASS: usize = PDF_BINS + 2;
const MOMENT1: usize = PDF_BINS + 3;
const MOMENT2: usize = PDF_BINS + 4;
const SUMS: usize = PDF_BINS + 5;

/// Mass in [`PDF_BINS`] bins of `s = ln(rho / rho_bar)` over
/// `[S_MIN, S_MAX)`, with the mass-weighted mean and width of `s` over
/// all particles (those outside the bins included). Every sum is an
/// [`ExactSum`], so the order of the particles and the ranks do not
/// matter.
#[derive(Debug, Clone)]
pub struct LnRhoPdf {
    sums: Vec<ExactSum>,
}

impl Default for LnRhoPdf {
    fn default() -> Self {
        Self::new()
    }
}

impl LnRhoPdf {
    /// An empty PDF.
    pub fn new() -> Self {
        LnRhoPdf {
            sums: vec![ExactSum::new(); SUMS],
        }
    }

    /// Adds particles of masses `m` and densities `rho` (finite, > 0;
    /// masses finite, >= 0) against the mean density `rho_bar` (total mass
    /// over the box's volume). On an error nothing is added.
    pub fn add(&mut self, m: &[f64], rho: &[f64], rho_bar: f64) -> Result<(), SpectrumError> {
        check_lengths(m.len(), &[("rho", rho)])?;
        if !(rho_bar.is_finite() && rho_bar > 0.0) {
            return Err(SpectrumError::MeanDensity { rho_bar });
        }
        for (i, (&mi, &ri)) in m.iter().zip(rho).enumerate() {
            if !(mi.is_finite() && mi >= 0.0) {
                return Err(bad("m", i, mi, "masses must be finite and >= 0"));
            }
            if !(ri.is_finite() && ri > 0.0) {
                return Err(bad("rho", i, ri, "densities must be finite and > 0"));
            }
        }
        for (&mi, &ri) in m.iter().zip(rho) {
            let s = (ri / rho_bar).ln();
            let bin = if s < S_MIN {
                BELOW
            } else if s >= S_MAX {
                ABOVE
            } else {
                // The product can round up to PDF_BINS just below S_MAX.
                (((s - S_MIN) * BINS_PER_UNIT) as usize).min(PDF_BINS - 1)
            };
            self.sums[bin].add(mi);
            self.sums[MASS].add(mi);
            self.sums[MOMENT1].add(mi * s);
            self.sums[MOMENT2].add(mi * s * s);
        }
        Ok(())
    }

    /// Adds another PDF's sums (exact).
    pub fn merge(&mut self, other: &LnRhoPdf) {
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            a.merge(b);
        }
    }

    /// The sums, for `ExactSum::all_reduce_many` over ranks.
    pub fn sums_mut(&mut self) -> &mut [ExactSum] {
        &mut self.sums
    }

    /// The centre of bin `i`.
    pub fn centre(i: usize) -> f64 {
        S_MIN + (i as f64 + 0.5) / BINS_PER_UNIT
    }

    /// The mass in each bin.
    pub fn mass(&self) -> Vec<f64> {
        self.sums[..PDF_BINS].iter().map(ExactSum::value).collect()
    }

    /// The mass below `S_MIN` and at or above `S_MAX`.
    pub fn outside(&self) -> (f64, f64) {
        (self.sums[BELOW].value(), self.sums[ABOVE].value())
    }

    /// The total mass added.
    pub fn total_mass(&self) -> f64 {
        self.sums[MASS].value()
    }

    /// The mass fraction per unit `s` in each bin (the bins integrate to
    /// the fraction inside `[S_MIN, S_MAX)`); zeros for an empty PDF.
    pub fn pdf(&self) -> Vec<f64> {
        let total = self.total_mass();
        self.mass()
            .into_iter()
            .map(|m| {
                if total > 0.0 {
                    m * BINS_PER_UNIT / total
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// The mass-weighted mean of `s` (NaN for an empty PDF).
    pub fn mean(&self) -> f64 {
        self.sums[MOMENT1].value() / self.total_mass()
    }

    /// The mass-weighted standard deviation of `s`, `sigma_ln_rho` (NaN
    /// for an empty PDF).
    pub fn width(&self) -> f64 {
        let mean = self.mean();
        (self.sums[MOMENT2].value() / self.total_mass() - mean * mean)
            .max(0.0)
            .sqrt()
    }
}

fn bad(what: &'static str, index: usize, value: f64, why: &'static str) -> SpectrumError {
    SpectrumError::BadValue {
        what,
        index,
        value,
        why,
    }
}

/// Writes `s,pdf,mass`, one bin per line (shortest round-trip decimals).
pub fn write_pdf_csv(w: &mut impl io::Write, pdf: &LnRhoPdf) -> io::Result<()> {
    writeln!(w, "s,pdf,mass")?;
    for (i, (p, m)) in pdf.pdf().into_iter().zip(pdf.mass()).enumerate() {
        writeln!(w, "{},{p},{m}", LnRhoPdf::centre(i))?;
    }
    Ok(())
}
