//! `profile.csv` and `profile.png`: the radial profile (already reduced
//! over the ranks, see [`crate::analysis::radial_profile`]) beside the
//! reference.

use super::CsvFile;
use crate::analysis::Bin;
use crate::AppError;
use std::path::Path;

/// Column names of `profile.csv`.
pub const HEADER: &str = "r,count,rho,p,v,rho_ref,p_ref,v_ref";

/// Writes `bins` to `path`, one line per bin.
pub fn write_csv(path: &Path, bins: &[Bin]) -> Result<(), AppError> {
    let mut f = CsvFile::create(path)?;
    f.line(HEADER)?;
    for b in bins {
        f.line_fmt(format_args!(
            "{:.6e},{},{:.8e},{:.8e},{:.8e},{:.8e},{:.8e},{:.8e}",
            b.r, b.count, b.rho, b.p, b.v, b.rho_ref, b.p_ref, b.v_ref
        ))?;
    }
    f.flush()
}

/// Writes `profile.csv` and `profile.png` (titled `title`) into `out`.
pub fn write(out: &Path, bins: &[Bin], title: &str) -> Result<(), AppError> {
    write_csv(&out.join("profile.csv"), bins)?;
    crate::plot::profile_png(&out.join("profile.png"), title, bins)
}
