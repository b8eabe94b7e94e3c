//! `conserved.csv`: the conserved quantities and neighbour counts of every
//! step, in full precision; under block time steps, of every
//! synchronisation point (the sub-steps where every particle is active, so
//! that every sum is of fresh values).

use super::observer::{Observed, StepObserver, StepView};
use super::CsvFile;
use crate::AppError;
use sph_core::StepReport;
use std::path::Path;

/// Column names of `conserved.csv`.
pub const HEADER: &str =
    "step,t,dt,E_kin,E_int,E_grav,E_tot,px,py,pz,Lx,Ly,Lz,nc_min,nc_max,nc_mean";

/// The last column of a driven run: the work done by the stirring up to
/// `t` (`E_tot - W_ext` is what the scheme conserves).
pub const WORK_COLUMN: &str = "W_ext";

/// The open `conserved.csv` (rank 0 only).
#[derive(Debug)]
pub struct ConservedCsv {
    file: CsvFile,
    /// Whether the run is driven (the [`WORK_COLUMN`] is written).
    work: bool,
}

impl ConservedCsv {
    /// The header of a run that is `driven` or not.
    pub fn header(driven: bool) -> String {
        if driven {
            format!("{HEADER},{WORK_COLUMN}")
        } else {
            HEADER.to_owned()
        }
    }

    /// Creates the file and writes the header (with the work column when
    /// the run is `driven`).
    pub fn create(path: &Path, driven: bool) -> Result<Self, AppError> {
        let mut file = CsvFile::create(path)?;
        file.line(&Self::header(driven))?;
        Ok(Self { file, work: driven })
    }

    /// Continues the file of a run resumed after step `last_step`: keeps
    /// its header and its lines of steps up to `last_step` (those of a run
    /// that went further before it stopped are dropped), or starts a new
    /// file with the header when there is none.
    pub fn resume(path: &Path, last_step: u64, driven: bool) -> Result<Self, AppError> {
        let old = match std::fs::read_to_string(path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
            Err(e) => return Err(AppError::io(path, e)),
        };
        let mut s = Self::create(path, driven)?;
        let header = Self::header(driven);
        let columns = header.split(',').count();
        for line in old.lines().filter(|l| *l != header) {
            let step = line.split(',').next().and_then(|s| s.parse::<u64>().ok());
            // Only complete lines (as many columns as the header) of
            // earlier steps.
            if step.is_some_and(|s| s <= last_step) && line.split(',').count() == columns {
                s.file.line(line)?;
            }
        }
        Ok(s)
    }

    /// One line for the step `r` of a run with `total` particles (energies,
    /// momentum and angular momentum in `{:.17e}`; the mean neighbour count
    /// per particle).
    pub fn step(&mut self, r: &StepReport, total: usize) -> Result<(), AppError> {
        let c = &r.conserved;
        let work = if self.work {
            format!(",{:.17e}", r.external_work)
        } else {
            String::new()
        };
        self.file.line_fmt(format_args!(
            "{},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{},{},{:.6}{work}",
            r.step, r.t, r.dt, c.e_kin, c.e_int, c.e_grav, c.e_tot(),
            c.momentum[0], c.momentum[1], c.momentum[2],
            c.angular_momentum[0], c.angular_momentum[1], c.angular_momentum[2],
            r.neighbors.min_count, r.neighbors.max_count,
            r.neighbors.total as f64 / total.max(1) as f64
        ))
    }

    /// Writes out what is buffered (at the end of the loop).
    pub fn flush(&mut self) -> Result<(), AppError> {
        self.file.flush()
    }
}

impl<C> StepObserver<C> for ConservedCsv {
    fn step(&mut self, view: &StepView<'_, C>) -> Result<Observed, AppError> {
        if view.report.all_active {
            ConservedCsv::step(self, view.report, view.total)?;
        }
        Ok(Observed::Recorded)
    }

    fn flush(&mut self) -> Result<(), AppError> {
        ConservedCsv::flush(self)
    }
}
