//! Spectra during a run (`--spectra-every-time DT`): at each multiple of
//! DT the velocity power spectrum and the ln-density PDF of all ranks'
//! particles ([`crate::spectrum`]), written by rank 0 as
//! `spectra/spectrum_STEP.csv` and `spectra/lnrho_STEP.csv`.
//!
//! Collective and rank-independent: the deposit is in fixed point and the
//! PDF in exact sums, each reduced over the ranks; rank 0 transforms.

use super::observer::{Observed, StepObserver, StepView};
use super::snapshot::Schedule;
use crate::spectrum::{
    default_grid, velocity_spectrum, write_csv, write_pdf_csv, write_spectrum_csv, DepositScale,
    Extremes, LnRhoPdf, Spectrum, SpectrumError, SpectrumGrid,
};
use crate::AppError;
use sph_comm::{Communicator, ExactSum, ReduceOp};
use sph_tree::BoundingBox;
use std::path::PathBuf;

/// The spectra of a run, on their schedule.
#[derive(Debug)]
pub struct SpectraObserver {
    schedule: Schedule,
    /// Rank 0's folder (`None` elsewhere).
    dir: Option<PathBuf>,
    /// Rank 0's spectra so far, `(t, (k, E))` up to the Nyquist shell,
    /// for `spectrum.png`.
    lines: Vec<crate::plot::SpectrumLine>,
}

impl SpectraObserver {
    /// Spectra at every multiple of `every_time` after `t0` (a resumed run
    /// does not repeat its first part's), into `dir` (rank 0's; `None`
    /// elsewhere).
    pub fn new(every_time: f64, t0: f64, dir: Option<PathBuf>) -> Self {
        Self {
            schedule: Schedule::new(None, Some(every_time), Vec::new(), t0),
            dir,
            lines: Vec::new(),
        }
    }
}

/// The values a spectrum reads, one per particle of this rank's share.
#[derive(Debug, Clone, Copy)]
pub struct SpectrumInput<'a> {
    /// Positions.
    pub x: &'a [f64],
    /// Positions.
    pub y: &'a [f64],
    /// Positions.
    pub z: &'a [f64],
    /// Masses.
    pub m: &'a [f64],
    /// Velocities.
    pub vx: &'a [f64],
    /// Velocities.
    pub vy: &'a [f64],
    /// Velocities.
    pub vz: &'a [f64],
    /// Densities.
    pub rho: &'a [f64],
}

/// The spectrum (rank 0 only: `None` elsewhere) and the PDF of every
/// rank's `input` particles, on a grid of `n_grid` cells per side over the
/// periodic cube `bbox`, divided by the deposit's window where
/// `deconvolve`. Collective: a run's spectra and `sphexa spectrum` (one
/// rank) both measure here.
///
/// # Errors
/// A box that is not a periodic cube, or particle values the spectrum
/// refuses (non-finite, negative mass or density).
pub fn measure<C: Communicator>(
    input: &SpectrumInput<'_>,
    bbox: &BoundingBox,
    total: usize,
    n_grid: usize,
    deconvolve: bool,
    comm: &C,
) -> Result<(Option<Spectrum>, LnRhoPdf), AppError> {
    let (lo, length) = periodic_cube(bbox).map_err(AppError::Usage)?;
    let SpectrumInput {
        x,
        y,
        z,
        m,
        vx,
        vy,
        vz,
        rho,
    } = *input;
    let failed = |e: SpectrumError| AppError::Usage(format!("spectra: {e}"));
    let local = agree(Extremes::local(m, vx, vy, vz), comm)?;
    let mut ext = [local.mass, local.momentum];
    comm.all_reduce(&mut ext, ReduceOp::Max);
    let extremes = Extremes {
        mass: ext[0],
        momentum: ext[1],
    };
    let scale = DepositScale::new(extremes, total as u64).map_err(failed)?;
    let mut grid = SpectrumGrid::new(n_grid, lo, length, scale).map_err(failed)?;
    let deposited = grid.deposit(x, y, z, m, vx, vy, vz);
    agree(deposited, comm)?;
    comm.all_reduce(grid.integers_mut(), ReduceOp::Sum);
    let rho_bar = grid.total_mass() / length.powi(3);
    let mut pdf = LnRhoPdf::new();
    agree(pdf.add(m, rho, rho_bar), comm)?;
    ExactSum::all_reduce_many(pdf.sums_mut(), comm);
    let spectrum = if comm.rank() == 0 {
        Some(velocity_spectrum(&grid, deconvolve).map_err(failed)?)
    } else {
        None
    };
    Ok((spectrum, pdf))
}

/// The corner and side of `bbox` if it is a periodic cube (sides equal
/// to 1e-12), else what it is instead.
///
/// # Errors
/// The box, when it is not a periodic cube.
pub fn periodic_cube(bbox: &BoundingBox) -> Result<([f64; 3], f64), String> {
    let (lo, hi) = (bbox.lo(), bbox.hi());
    let length = hi[0] - lo[0];
    let cube = (0..3).all(|d| {
        bbox.is_periodic(d)
            && (lo[d] - lo[0]).abs() <= 1e-12 * length
            && (hi[d] - lo[d] - length).abs() <= 1e-12 * length
    });
    if cube {
        Ok((lo, length))
    } else {
        Err(format!(
            "spectra need a periodic cube; the box is {lo:?} to {hi:?} (periodic: {:?})",
            [0, 1, 2].map(|d| bbox.is_periodic(d))
        ))
    }
}

/// `local` if every rank's part succeeded, else an error on every rank
/// (this rank's own, or one saying another rank's failed): all ranks then
/// leave the collective together. Collective.
fn agree<T, C: Communicator>(local: Result<T, SpectrumError>, comm: &C) -> Result<T, AppError> {
    let failed = comm.all_reduce_scalar(u64::from(local.is_err()), ReduceOp::Max) > 0;
    match local {
        Err(e) => Err(AppError::Usage(format!("spectra: {e}"))),
        Ok(_) if failed => Err(AppError::Usage(
            "spectra: another rank's particles were refused".into(),
        )),
        Ok(v) => Ok(v),
    }
}

impl<C: Communicator> StepObserver<C> for SpectraObserver {
    fn step(&mut self, view: &StepView<'_, C>) -> Result<Observed, AppError> {
        let state = view.state;
        let time_due = self.schedule.time_due(state.t);
        if !self.schedule.due(state.step, state.t) {
            return Ok(Observed::Recorded);
        }
        // Block time steps: the state at the requested time, as a
        // snapshot due then holds it.
        let at = view.output_time(time_due);
        let p = view.particles;
        let x = view.owned_at("x", &p.x, at)?;
        let y = view.owned_at("y", &p.y, at)?;
        let z = view.owned_at("z", &p.z, at)?;
        let vx = view.owned_at("vx", &p.vx, at)?;
        let vy = view.owned_at("vy", &p.vy, at)?;
        let vz = view.owned_at("vz", &p.vz, at)?;
        let rho = view.owned_at("rho", &p.rho, at)?;
        let input = SpectrumInput {
            x: &x,
            y: &y,
            z: &z,
            m: &p.m[view.owned.clone()],
            vx: &vx,
            vy: &vy,
            vz: &vz,
            rho: &rho,
        };
        let (spectrum, pdf) = measure(
            &input,
            view.bbox,
            view.total,
            default_grid(view.total),
            true,
            view.comm,
        )?;
        if let (Some(dir), Some(s)) = (&self.dir, spectrum) {
            std::fs::create_dir_all(dir).map_err(|e| AppError::io(dir, e))?;
            let step = state.step;
            write_csv(&dir.join(format!("spectrum_{step:08}.csv")), |w| {
                write_spectrum_csv(w, &s)
            })?;
            write_csv(&dir.join(format!("lnrho_{step:08}.csv")), |w| {
                write_pdf_csv(w, &pdf)
            })?;
            // Complete shells only: up to the grid's Nyquist wavenumber.
            let nyquist = (default_grid(view.total) / 2) as f64;
            let points = (s.k.iter().copied().zip(s.e.iter().copied()))
                .filter(|p| p.0 <= nyquist)
                .collect();
            self.lines.push((state.t, points));
        }
        Ok(Observed::Recorded)
    }

    /// Rank 0 draws `spectra/spectrum.png` from the spectra of this part
    /// of the run.
    fn finish(&mut self) -> Result<(), AppError> {
        match &self.dir {
            Some(dir) if !self.lines.is_empty() => crate::plot::spectra_png(
                &dir.join("spectrum.png"),
                "velocity power spectrum (mass-weighted, TSC deconvolved)",
                &self.lines,
            ),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::periodic_cube;
    use sph_tree::{Boundary, BoundingBox};

    #[test]
    fn only_a_periodic_cube_is_one() {
        let p = [Boundary::Periodic; 3];
        let cube = BoundingBox::new([-0.5; 3], [0.5; 3], p).unwrap();
        assert_eq!(periodic_cube(&cube), Ok(([-0.5; 3], 1.0)));
        let slab = BoundingBox::new([-0.5; 3], [0.5, 0.5, 0.1], p).unwrap();
        assert!(periodic_cube(&slab).unwrap_err().contains("periodic cube"));
        let mut open = p;
        open[2] = Boundary::Open;
        let half_open = BoundingBox::new([-0.5; 3], [0.5; 3], open).unwrap();
        assert!(periodic_cube(&half_open).is_err());
    }
}
