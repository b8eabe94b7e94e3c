//! `sphexa spectrum`: the velocity power spectrum and the ln-density PDF
//! of one snapshot, ours or another code's H5Part dump (SPH-EXA's), so
//! that both codes of a side-by-side are measured by one program
//! ([`crate::spectrum`]).

use super::parse::{parse_count, parse_interval};
use crate::checkpoint::split_spec;
use crate::output::spectra::{measure, periodic_cube, SpectrumInput};
use crate::spectrum::{default_grid, slope, write_csv, write_pdf_csv, write_spectrum_csv};
use crate::AppError;
use clap::Args;
use sph_comm::SerialComm;
use sph_tree::{Boundary, BoundingBox};
use std::path::{Path, PathBuf};

/// The options of `sphexa spectrum`.
#[derive(Args, Debug)]
pub(crate) struct SpectrumArgs {
    /// Snapshot `FILE[:K]` (step group K, default the last): ours or an
    /// H5Part dump of SPH-EXA with x, y, z, vx, vy, vz, m and rho, in a
    /// periodic cube (its `box` attribute, or --box).
    file: String,
    /// Grid cells per side, 8 to 512 (default: the particles' cube root,
    /// rounded to an even number): shells k up to half of it.
    #[arg(long, value_name = "N", value_parser = parse_count)]
    grid: Option<usize>,
    /// The cube `LO:HI` on every axis, for files without a `box` attribute.
    #[arg(long = "box", value_name = "LO:HI", allow_hyphen_values = true, value_parser = parse_interval)]
    cube: Option<(f64, f64)>,
    /// Leave the spectrum convolved with the deposit's window (TSC), not
    /// divided by it.
    #[arg(long)]
    raw: bool,
    /// Folder for spectrum.csv (k, E, E_sol, E_comp, cells) and
    /// lnrho_pdf.csv (s = ln(rho / mean rho), pdf, mass); default: the
    /// snapshot's folder, the files named after it.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

/// The fields a spectrum reads.
const FIELDS: [&str; 8] = ["x", "y", "z", "vx", "vy", "vz", "m", "rho"];

/// `sphexa spectrum`: read, deposit, transform, write, report.
pub(crate) fn spectrum(a: SpectrumArgs) -> Result<(), AppError> {
    let (path, k) = split_spec(&a.file)?;
    let count = sph_io::foreign::step_count(&path)
        .map_err(|e| AppError::Usage(format!("{}: {e}", path.display())))?;
    let index = k.map_or(count.saturating_sub(1), |k| k as usize);
    let step = sph_io::foreign::read_foreign_rows(&path, index, &FIELDS, &[], 0..u64::MAX)?;
    let field = |n: &str| step.field(n).expect("a required field was read");
    let in_file = |e: String| AppError::Usage(format!("{}: {e}", path.display()));
    let cube = match (a.cube, step.bbox) {
        (Some((lo, hi)), _) => BoundingBox::cube(lo, hi, Boundary::Periodic)
            .map_err(|e| in_file(format!("--box {lo}:{hi}: {e}")))?,
        (None, Some(b)) => {
            let periodic = [Boundary::Periodic; 3];
            let cube = BoundingBox::new([b[0], b[2], b[4]], [b[1], b[3], b[5]], periodic)
                .map_err(|e| in_file(format!("its box {b:?}: {e}")))?;
            periodic_cube(&cube)
                .map_err(|e| in_file(format!("{e}; give --box LO:HI to use one")))?;
            cube
        }
        (None, None) => {
            return Err(in_file(format!(
                "Step#{index} has no box attribute; give the periodic cube with --box LO:HI"
            )))
        }
    };
    let n = step.total as usize;
    let grid_n = a.grid.unwrap_or_else(|| default_grid(n));
    let named = |e: AppError| match e {
        AppError::Usage(m) => in_file(m),
        e => e,
    };
    let input = SpectrumInput {
        x: field("x"),
        y: field("y"),
        z: field("z"),
        m: field("m"),
        vx: field("vx"),
        vy: field("vy"),
        vz: field("vz"),
        rho: field("rho"),
    };
    let (s, pdf) = measure(&input, &cube, n, grid_n, !a.raw, &SerialComm).map_err(named)?;
    let s = s.expect("one rank: rank 0 holds the spectrum");

    let (dir, stem) = output_names(&path, index, a.out.as_deref());
    std::fs::create_dir_all(&dir).map_err(|e| AppError::io(&dir, e))?;
    let spectrum_file = dir.join(format!("{stem}spectrum.csv"));
    write_csv(&spectrum_file, |w| write_spectrum_csv(w, &s))?;
    let pdf_file = dir.join(format!("{stem}lnrho_pdf.csv"));
    write_csv(&pdf_file, |w| write_pdf_csv(w, &pdf))?;
    let k_hi = 8.min(grid_n / 2);
    let fit =
        slope(&s, 3.min(k_hi - 1), k_hi).map_or_else(|e| format!("({e})"), |v| format!("{v:.3}"));
    say!(
        "{}, Step#{index}{}: {n} particles on {grid_n}^3 cells; E total {:.6e} (<|u|^2>/2 {:.6e}), slope of ln E over k = 3..{k_hi} {fit}; ln rho: mean {:.4e}, width {:.4e}",
        path.display(),
        step.time.map_or(String::new(), |t| format!(" (t = {t})")),
        s.total(),
        s.grid_energy,
        pdf.mean(),
        pdf.width()
    );
    say!(
        "wrote {} and {}",
        spectrum_file.display(),
        pdf_file.display()
    );
    Ok(())
}

/// The output folder and file-name prefix: `--out DIR` and no prefix, or
/// the snapshot's folder and `NAME_K_` (its stem and step).
fn output_names(path: &Path, index: usize, out: Option<&Path>) -> (PathBuf, String) {
    match out {
        Some(d) => (d.to_path_buf(), String::new()),
        None => {
            let dir = path.parent().map_or_else(PathBuf::new, Path::to_path_buf);
            let stem = path
                .file_stem()
                .map_or("snapshot".into(), |s| s.to_string_lossy());
            (dir, format!("{stem}_{index}_"))
        }
    }
}
