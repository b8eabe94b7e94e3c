//! The runs of a bench: every combination of case, size, scheme, kernel,
//! time-step mode, rank count and repeat as a fresh `sphexa run` process (so the peak RSS
//! each reports is its own), read back as [`Row`]s from its
//! `summary.json`.

use super::Row;
use crate::AppError;
use sph_core::timestep::TimeSteps;
use sph_core::{Choice, PRESETS};
use sph_kernels::KernelChoice;
use std::path::{Path, PathBuf};

/// What a bench runs: the product of these lists, each run in its own
/// folder under `out/runs`.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// Test cases.
    pub cases: Vec<String>,
    /// Particles per side.
    pub sizes: Vec<usize>,
    /// Scheme presets; `case` is each case's own scheme.
    pub schemes: Vec<String>,
    /// Kernels.
    pub kernels: Vec<KernelChoice>,
    /// Time-step modes (global, block, kdk).
    pub time_steps: Vec<TimeSteps>,
    /// MPI rank counts (a run on more than one is started by `launcher`).
    pub ranks: Vec<usize>,
    /// Runs of each combination, at least 1.
    pub repeat: u64,
    /// Worker threads per rank of each run (default: all cores).
    pub threads: Option<usize>,
    /// Simulated time of every run (default: each case's end time).
    pub end_time: Option<f64>,
    /// The MPI launcher as words (given `-n R` and the run's command line).
    pub launcher: String,
    /// The bench's output folder.
    pub out: PathBuf,
    /// No line per run.
    pub quiet: bool,
}

impl Sweep {
    /// Checks the scheme names and, for runs on more than one rank, the
    /// build and the launcher, before anything runs.
    ///
    /// # Errors
    /// An unknown scheme, ranks without MPI, or an empty launcher.
    pub fn check(&self) -> Result<(), AppError> {
        for name in &self.schemes {
            if name != "case" {
                crate::cases::Scheme::preset(name).map_err(|_| {
                    let names: Vec<&str> = PRESETS.iter().map(|p| p.0).collect();
                    AppError::Usage(format!(
                        "--schemes: unknown scheme '{name}'; allowed: case (each case's own), {}",
                        names.join(", ")
                    ))
                })?;
            }
        }
        if let Some(&r) = self.ranks.iter().find(|&&r| r > 1) {
            if !cfg!(feature = "mpi") {
                return Err(AppError::Usage(format!(
                    "--ranks {r}: this sphexa was built without MPI; build it with \
                     `cargo build --release -p sph-apps --features mpi` for runs on more than one rank"
                )));
            }
            if self.launcher.split_whitespace().next().is_none() {
                return Err(AppError::Usage(
                    "--mpirun '': give the MPI launcher, e.g. mpirun or srun".into(),
                ));
            }
        }
        Ok(())
    }

    /// Every combination, in order (case, size, scheme, kernel, time
    /// steps, ranks, repeat).
    fn combinations(&self) -> Vec<Combination<'_>> {
        let mut v = Vec::new();
        for case in &self.cases {
            for &side in &self.sizes {
                for scheme in &self.schemes {
                    for kernel in &self.kernels {
                        for &time_steps in &self.time_steps {
                            for &ranks in &self.ranks {
                                v.extend((0..self.repeat).map(|repeat| Combination {
                                    case,
                                    side,
                                    scheme,
                                    kernel,
                                    time_steps,
                                    ranks,
                                    repeat,
                                }));
                            }
                        }
                    }
                }
            }
        }
        v
    }

    /// Runs every combination with the `sphexa` binary `exe`, in order
    /// (case, size, scheme, kernel, time steps, ranks, repeat), appending
    /// each run's row to `rows`.
    ///
    /// # Errors
    /// A run that cannot start or fails (with its error output), or a
    /// summary that cannot be read.
    pub fn run(&self, exe: &Path, rows: &mut Vec<Row>) -> Result<(), AppError> {
        let launcher: Vec<&str> = self.launcher.split_whitespace().collect();
        let all = self.combinations();
        let total = all.len();
        for (k, c) in all.into_iter().enumerate() {
            let Combination {
                case,
                side,
                scheme,
                kernel,
                time_steps,
                ranks,
                repeat,
            } = c;
            let kernel_text = kernel.to_string();
            let mode = Choice::name(&time_steps);
            // Global runs keep the folder names they had before the mode
            // was a dimension.
            let mode_dir = if time_steps == TimeSteps::Global {
                String::new()
            } else {
                format!("_{mode}")
            };
            let dir = self.out.join("runs").join(format!(
                "{case}_{scheme}_{}{mode_dir}_{side}_r{ranks}_{repeat}",
                kernel_text.replace(':', "")
            ));
            let mut cmd = if ranks > 1 {
                let mut c = std::process::Command::new(launcher[0]);
                c.args(&launcher[1..]);
                c.arg("-n").arg(ranks.to_string()).arg(exe);
                c
            } else {
                std::process::Command::new(exe)
            };
            cmd.args(["run", case, "-n", &side.to_string(), "-q"])
                .args(["--kernel", &kernel_text])
                .args(["--time-steps", mode])
                .arg("--out")
                .arg(&dir);
            if scheme != "case" {
                cmd.args(["--scheme", scheme]);
            }
            if let Some(t) = self.threads {
                cmd.args(["--threads", &t.to_string()]);
            }
            if let Some(t) = self.end_time {
                cmd.args(["--end-time", &t.to_string()]);
            }
            let what = format!(
                "{case} --scheme {scheme} --kernel {kernel_text} --time-steps {mode} -n {side} on {ranks} rank(s), repeat {repeat}"
            );
            let row = run_one(&mut cmd, &what, &dir, scheme, side, repeat)?;
            if !self.quiet {
                eprintln!(
                    "[{}/{total}] {what}: {} particles, {} steps, {} updates, {:.2} s, L1 rho {:.4e} P {:.4e} |v| {:.4e}, peak RSS {:.0} MB",
                    k + 1,
                    row.n,
                    row.steps,
                    row.particle_updates,
                    row.wall_s,
                    row.l1_rho,
                    row.l1_p,
                    row.l1_v,
                    row.peak_rss_bytes as f64 / 1e6
                );
            }
            rows.push(row);
        }
        Ok(())
    }
}

/// One run of a sweep.
struct Combination<'a> {
    case: &'a str,
    side: usize,
    scheme: &'a str,
    kernel: &'a KernelChoice,
    time_steps: TimeSteps,
    ranks: usize,
    repeat: u64,
}

/// Runs `cmd` (the run `what`, writing into `dir`) and reads its row.
fn run_one(
    cmd: &mut std::process::Command,
    what: &str,
    dir: &Path,
    scheme: &str,
    side: usize,
    repeat: u64,
) -> Result<Row, AppError> {
    let o = cmd
        .output()
        .map_err(|e| AppError::Usage(format!("{what}: could not start: {e}")))?;
    if !o.status.success() {
        let err = String::from_utf8_lossy(&o.stderr);
        return Err(AppError::Usage(format!(
            "{what} failed ({}): {}",
            o.status,
            err.trim()
        )));
    }
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| AppError::io(&path, e))?;
    let json: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| AppError::Usage(format!("{}: {e}", path.display())))?;
    Row::from_summary(&json, scheme, side as u64, repeat, &path)
}
