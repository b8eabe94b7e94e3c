//! `sphexa glass`: relax a block of glass ([`crate::glass`]), report, and
//! write it.

use super::parse::{parse_kernel, parse_positive, parse_side, parse_steps, parse_threads};
use super::start_threads;
use crate::glass::{default_cache_dir, relax, write, GlassSpec};
use crate::AppError;
use clap::Args;
use sph_kernels::KernelChoice;
use std::path::PathBuf;

/// The options of `sphexa glass`.
#[derive(Args, Debug)]
pub(crate) struct GlassArgs {
    /// Particles per side of the block, 6 to 200.
    #[arg(long, value_name = "N", default_value_t = 16, value_parser = parse_side)]
    side: usize,
    /// Kernel (as `sphexa run --kernel`).
    #[arg(long, value_name = "NAME", default_value = "sinc:6", value_parser = parse_kernel)]
    kernel: KernelChoice,
    /// Target neighbour count (as `sphexa run --ng0`).
    #[arg(long, value_name = "N", default_value_t = 100)]
    ng0: usize,
    /// Most neighbours (as `sphexa run --ngmax`).
    #[arg(long, value_name = "N", default_value_t = 150)]
    ngmax: usize,
    /// Stop when std(rho)/mean(rho) is below this.
    #[arg(long, value_name = "X", default_value_t = crate::glass::TOLERANCE,
          allow_negative_numbers = true, value_parser = parse_positive)]
    tolerance: f64,
    /// Most relaxation steps.
    #[arg(long, value_name = "N", default_value_t = crate::glass::MAX_STEPS,
          allow_negative_numbers = true, value_parser = parse_steps)]
    steps: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_threads)]
    threads: Option<usize>,
    /// Output file (default: the cache's file for this side, kernel and
    /// neighbour counts and relaxation version, e.g.
    /// glass_16_sinc6_ng100_150_v1.h5).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// No line per 10 steps.
    #[arg(short, long)]
    quiet: bool,
}

/// `sphexa glass`: relax a block, report, write it.
pub(crate) fn glass(a: GlassArgs) -> Result<(), AppError> {
    start_threads(a.threads)?;
    let spec = GlassSpec {
        side: a.side,
        kernel: a.kernel,
        ng0: a.ng0,
        ngmax: a.ngmax,
    };
    let path = a
        .out
        .clone()
        .unwrap_or_else(|| default_cache_dir().join(spec.file_name()));
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| {
            AppError::Usage(format!(
                "--out {}: cannot create its folder ({e})",
                path.display()
            ))
        })?;
    }
    let start = std::time::Instant::now();
    let g = relax(&spec, a.steps, a.tolerance, |s| {
        if !a.quiet && s.step % 10 == 0 {
            eprintln!(
                "step {:>5}: largest move {:.3e} spacings ({:.1} s)",
                s.step,
                s.max_shift,
                start.elapsed().as_secs_f64()
            );
        }
    })?;
    write(&g, &path)?;
    let r = g.report;
    say!(
        "{} particles, {} steps, {:.1} s: density scatter {:.4} -> {:.4}, closest pair {:.3} -> {:.3} spacings{}",
        g.pos.len(),
        r.steps,
        start.elapsed().as_secs_f64(),
        r.rho_scatter_start,
        r.rho_scatter,
        r.min_pair_start,
        r.min_pair,
        if r.rho_scatter > a.tolerance { " (tolerance not reached: raise --steps)" } else { "" }
    );
    say!("wrote {}", path.display());
    Ok(())
}
