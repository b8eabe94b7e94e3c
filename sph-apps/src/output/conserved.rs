//! `conserved.csv`: the conserved quantities and neighbour counts of every
//! step, in full precision.

use super::observer::{Observed, StepObserver, StepView};
use super::CsvFile;
use crate::AppError;
use sph_core::StepReport;
use std::path::Path;

/// Column names of `conserved.csv`.
pub const HEADER: &str =
    "step,t,dt,E_kin,E_int,E_grav,E_tot,px,py,pz,Lx,Ly,Lz,nc_min,nc_max,nc_mean";

/// The open `conserved.csv` (rank 0 only).
#[derive(Debug)]
pub struct ConservedCsv(CsvFile);

impl ConservedCsv {
    /// Creates the file and writes the header.
    pub fn create(path: &Path) -> Result<Self, AppError> {
        let mut f = CsvFile::create(path)?;
        f.line(HEADER)?;
        Ok(Self(f))
    }

    /// Continues the file of a run resumed after step `last_step`: keeps
    /// its header and its lines of steps up to `last_step` (those of a run
    /// that went further before it stopped are dropped), or starts a new
    /// file with the header when there is none.
    pub fn resume(path: &Path, last_step: u64) -> Result<Self, AppError> {
        let old = match std::fs::read_to_string(path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
            Err(e) => return Err(AppError::io(path, e)),
        };
        let mut f = CsvFile::create(path)?;
        f.line(HEADER)?;
        for line in old.lines().filter(|l| *l != HEADER) {
            let step = line.split(',').next().and_then(|s| s.parse::<u64>().ok());
            // Only complete lines (16 columns) of earlier steps.
            if step.is_some_and(|s| s <= last_step) && line.split(',').count() == 16 {
                f.line(line)?;
            }
        }
        Ok(Self(f))
    }

    /// One line for the step `r` of a run with `total` particles (energies,
    /// momentum and angular momentum in `{:.17e}`; the mean neighbour count
    /// per particle).
    pub fn step(&mut self, r: &StepReport, total: usize) -> Result<(), AppError> {
        let c = &r.conserved;
        self.0.line_fmt(format_args!(
            "{},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{},{},{:.6}",
            r.step, r.t, r.dt, c.e_kin, c.e_int, c.e_grav, c.e_tot(),
            c.momentum[0], c.momentum[1], c.momentum[2],
            c.angular_momentum[0], c.angular_momentum[1], c.angular_momentum[2],
            r.neighbors.min_count, r.neighbors.max_count,
            r.neighbors.total as f64 / total.max(1) as f64
        ))
    }

    /// Writes out what is buffered (at the end of the loop).
    pub fn flush(&mut self) -> Result<(), AppError> {
        self.0.flush()
    }
}

impl<C> StepObserver<C> for ConservedCsv {
    fn step(&mut self, view: &StepView<'_, C>) -> Result<Observed, AppError> {
        ConservedCsv::step(self, view.report, view.total)?;
        Ok(Observed::Recorded)
    }

    fn flush(&mut self) -> Result<(), AppError> {
        ConservedCsv::flush(self)
    }
}
