//! `sphexa bench`: the options of a bench; the runs ([`crate::bench::Sweep`])
//! and the report ([`crate::bench::Report`]) are the library's.

use super::parse::{
    case_names, choice, parse_kernel, parse_positive, parse_side, parse_steps, parse_threads,
};
use crate::bench::{read_csv, Report, Sweep};
use crate::AppError;
use clap::Args;
use sph_core::timestep::TimeSteps;
use sph_kernels::KernelChoice;
use std::path::PathBuf;

/// The options of `sphexa bench`.
#[derive(Args, Debug)]
pub(crate) struct BenchArgs {
    /// Test cases (each needs a reference solution for its L1 errors).
    #[arg(required_unless_present = "from", value_parser = case_names())]
    cases: Vec<String>,
    /// Particles per side, comma-separated (e.g. 20,30,40), each 4 to 1000.
    #[arg(long, value_name = "N1,N2,...", required_unless_present = "from",
          value_delimiter = ',', value_parser = parse_side)]
    sizes: Vec<usize>,
    /// Run nothing: read the rows of an earlier bench.csv and write the
    /// report (JSON, CSV, plot) again, e.g. with another --reference.
    #[arg(long, value_name = "BENCH_CSV", conflicts_with_all = ["cases", "sizes"])]
    from: Option<PathBuf>,
    /// Scheme presets, comma-separated (`sphexa cases` lists them); `case`
    /// is each case's own scheme.
    #[arg(
        long,
        value_name = "S1,S2,...",
        default_value = "case",
        value_delimiter = ','
    )]
    schemes: Vec<String>,
    /// Kernels, comma-separated (as `sphexa run --kernel`).
    #[arg(long, value_name = "K1,K2,...", default_value = "sinc:6", value_delimiter = ',',
          value_parser = parse_kernel)]
    kernels: Vec<KernelChoice>,
    /// Time-step modes, comma-separated (as `sphexa run --time-steps`):
    /// `global,block` runs every combination both ways; bench.csv has the
    /// mode and the particle updates of each run.
    #[arg(long, value_name = "M1,M2,...", default_value = "global", value_delimiter = ',',
          value_parser = choice::<TimeSteps>())]
    time_steps: Vec<TimeSteps>,
    /// Worker threads per rank of each run (default: all cores).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_threads)]
    threads: Option<usize>,
    /// MPI ranks, comma-separated: a run on R > 1 ranks is started as
    /// `mpirun -n R sphexa run ...` (needs a `--features mpi` build).
    #[arg(long, value_name = "R1,R2,...", default_value = "1", value_delimiter = ',',
          value_parser = parse_threads)]
    ranks: Vec<usize>,
    /// The MPI launcher for runs on R > 1 ranks, as words (it is given
    /// `-n R` and the run's command line), e.g. "srun" or
    /// "mpirun --oversubscribe".
    #[arg(long, value_name = "CMD", default_value = "mpirun")]
    mpirun: String,
    /// Runs of each combination (their spread, min and median, is in
    /// bench.json), at least 1.
    #[arg(long, value_name = "R", default_value_t = 1, allow_negative_numbers = true,
          value_parser = parse_steps)]
    repeat: u64,
    /// Simulated time of every run (default: each case's end time).
    #[arg(long = "end-time", value_name = "T", allow_negative_numbers = true,
          value_parser = parse_positive)]
    end_time: Option<f64>,
    /// Output folder (default out/bench); each run's own outputs go to
    /// runs/ inside it.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Another code's points to draw over the plot: a CSV with bench.csv's
    /// columns (at least N, wall_s and l1_rho / l1_p / l1_v; case, scheme
    /// and kernel name its series).
    #[arg(long, value_name = "FILE")]
    reference: Option<PathBuf>,
    /// No line per run.
    #[arg(short, long)]
    quiet: bool,
}

/// `sphexa bench`: every combination as a child process, then the report.
pub(crate) fn bench(a: BenchArgs) -> Result<(), AppError> {
    let sweep = Sweep {
        cases: a.cases,
        sizes: a.sizes,
        schemes: a.schemes,
        kernels: a.kernels,
        time_steps: a.time_steps,
        ranks: a.ranks,
        repeat: a.repeat,
        threads: a.threads,
        end_time: a.end_time,
        launcher: a.mpirun,
        out: a.out.unwrap_or_else(|| PathBuf::from("out/bench")),
        quiet: a.quiet,
    };
    sweep.check()?;
    let reference = match &a.reference {
        Some(path) => Some((path.clone(), read_csv(path)?)),
        None => None,
    };
    let exe = std::env::current_exe()
        .map_err(|e| AppError::Usage(format!("cannot find the sphexa binary to run: {e}")))?;
    let mut rows = match &a.from {
        Some(path) => read_csv(path)?,
        None => Vec::new(),
    };
    sweep.run(&exe, &mut rows)?;
    let report = Report::new(rows, reference);
    let out = &sweep.out;
    report.write(out, &report.title())?;
    say!("{}", report.table());
    say!(
        "wrote {}, {}, {}",
        out.join("bench.csv").display(),
        out.join("bench.json").display(),
        out.join("error_vs_time.png").display()
    );
    Ok(())
}
