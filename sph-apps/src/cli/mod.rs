//! The `sphexa` command line: the top-level parser and the dispatch to one
//! module per subcommand (`run`, `cases`, `bench`, `stress`, `glass`,
//! `spectrum`),
//! each of which parses its arguments and calls the library.

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::process::ExitCode;

/// `println!` that ends the process quietly (exit status 0) when stdout
/// is a closed pipe (`sphexa cases | head -1`), as Unix tools do, instead
/// of panicking.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout(), $($arg)*) {
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                std::process::exit(0);
            }
            panic!("writing to stdout: {e}");
        }
    }};
}

mod bench;
mod cases;
mod glass;
mod parse;
mod run;
mod spectrum;
mod stress;

// No doc comment on `Cli`: clap would take it as the about text, which is
// the crate's description (`about` below).
#[derive(Parser, Debug)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a test case and write its outputs (conserved.csv, timings.csv,
    /// profile.csv, summary.json, config.toml; snapshots/ and checkpoints/
    /// when asked for) into --out.
    Run(Box<run::args::RunArgs>),
    /// List the test cases with their default size, end time and scheme.
    Cases,
    /// Error against run time: run every combination of case, size,
    /// scheme, kernel and repeat as a fresh `sphexa run` process to the
    /// case's end time, and write bench.csv, bench.json (with the spread
    /// over repeats and the fitted convergence orders) and
    /// error_vs_time.png into --out.
    Bench(Box<bench::BenchArgs>),
    /// Runs built to break the solver (noisy lattices, Courant sweeps, a
    /// strong shock tube, extreme kernels and neighbour counts, a 100x
    /// spread of smoothing lengths, a long run at rest, extreme inputs):
    /// each pass or fail with its figures, in OUT/stress.json and a table.
    /// Exits non-zero when a scenario fails.
    Stress(stress::StressArgs),
    /// Glass initial conditions: relax SIDE^3 random particles in a
    /// periodic unit cube with the solver's kernel until the density
    /// scatter std(rho)/mean(rho) is below --tolerance, and write them
    /// (x, y, z in [0, 1), H5Part) to --out, by default into the glass
    /// cache that cases set up from glass read ($SPHEXA_GLASS_DIR, else
    /// $XDG_CACHE_HOME/sphexa/glass, else ~/.cache/sphexa/glass).
    Glass(glass::GlassArgs),
    /// The velocity power spectrum E(k) (with its solenoidal and
    /// compressive parts, deconvolved from the TSC deposit) and the PDF of
    /// ln(rho / mean rho) of one snapshot in a periodic cube, ours or an
    /// SPH-EXA H5Part dump: spectrum.csv and lnrho_pdf.csv, and a line with
    /// the total, the slope over k = 3..8 and the width of ln rho.
    Spectrum(spectrum::SpectrumArgs),
}

/// The `sphexa` binary: smoothed particle hydrodynamics (the SPH-EXA
/// scheme), multi-threaded, and over MPI when built with `--features mpi`
/// (`mpirun -n 4 sphexa run ...`). Parses the command line, runs the
/// subcommand, and prints its error (exit status 1) if it fails.
pub fn main() -> ExitCode {
    crate::memory::return_large_buffers_to_os();
    let matches = Cli::command().get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    let done = match cli.command {
        Command::Cases => {
            cases::list_cases();
            Ok(true)
        }
        Command::Stress(args) => stress::stress(args),
        Command::Glass(args) => glass::glass(args).map(|()| true),
        Command::Spectrum(args) => spectrum::spectrum(args).map(|()| true),
        Command::Bench(args) => bench::bench(*args).map(|()| true),
        Command::Run(args) => run::run(
            *args,
            matches.subcommand_matches("run").expect("run was parsed"),
        )
        .map(|()| true),
    };
    match done {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The global worker pool with `threads` threads (default: all cores).
fn start_threads(threads: Option<usize>) -> Result<(), crate::AppError> {
    if let Some(t) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .map_err(|e| crate::AppError::Usage(format!("cannot start {t} threads: {e}")))?;
    }
    Ok(())
}
