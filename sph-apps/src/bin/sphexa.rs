//! `sphexa`: run the SPH-EXA test cases from the command line.

use clap::builder::{PossibleValue, PossibleValuesParser};
use clap::{Args, Parser, Subcommand, ValueEnum};
use sph_apps::cases::{self, Scheme, SchemeOverrides};
use sph_apps::simulation::{Progress, Stop};
use sph_apps::{AppError, Simulation};
use sph_comm::Communicator;
use sph_core::PRESETS;
use sph_core::{Gradients, HydroConfig};
use sph_kernels::{KernelChoice, Tabulated};
use sph_tree::Curve;
use std::path::PathBuf;
use std::process::ExitCode;

/// Smoothed Particle Hydrodynamics (the SPH-EXA scheme), multi-threaded, and
/// over MPI when built with `--features mpi` (`mpirun -n 4 sphexa run ...`).
#[derive(Parser, Debug)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a test case and write its outputs (conserved.csv, timings.csv,
    /// profile.csv, summary.json) into --out.
    Run(Box<RunArgs>),
    /// List the test cases with their default size, end time and scheme.
    Cases,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum GradientArg {
    /// Integral approach to derivatives (exact for linear fields).
    Iad,
    /// Plain kernel gradients.
    Kernel,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq)]
enum Switch {
    /// Enabled.
    On,
    /// Disabled.
    Off,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum CurveArg {
    /// Hilbert curve.
    Hilbert,
    /// Morton (Z-order) curve.
    Morton,
}

/// Most worker threads per rank.
const MAX_THREADS: i64 = 1 << 16;

/// Smallest and largest particles per side.
const SIDE_RANGE: (usize, usize) = (4, 1000);

#[derive(Args, Debug)]
struct RunArgs {
    /// Test case (`sphexa cases` lists each with its defaults).
    #[arg(value_parser = case_names())]
    case: String,
    /// Particles per side of the initial lattice, 4 to 1000 (default: the
    /// case's, see `sphexa cases`).
    #[arg(short = 'n', long = "side", value_name = "N", allow_negative_numbers = true,
          value_parser = parse_side)]
    side: Option<usize>,
    /// Number of steps to run, at least 1 (default: run to the end time).
    #[arg(long, conflicts_with = "end_time", allow_negative_numbers = true,
          value_parser = parse_steps)]
    steps: Option<u64>,
    /// Simulated time to reach, a positive number (default: the case's, see
    /// `sphexa cases`).
    #[arg(long = "end-time", value_name = "T", allow_negative_numbers = true,
          value_parser = parse_positive)]
    end_time: Option<f64>,
    /// Output folder, created if needed (default: out/CASE).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Worker threads per rank, at least 1 (default: all cores).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_threads)]
    threads: Option<usize>,
    /// Kernel: `sinc` (= sinc:6), `sinc:N` (1 <= N <= 1000), `m4`, `wendland-c2`,
    /// `wendland-c4`, `wendland-c6`.
    #[arg(long, default_value = "sinc:6", value_parser = parse_kernel)]
    kernel: KernelChoice,
    /// Target neighbour count, self included: 8 to --ngmax.
    #[arg(long, default_value_t = 100, allow_negative_numbers = true,
          value_parser = parse_count)]
    ng0: usize,
    /// Largest accepted neighbour count before h is iterated: --ng0 or more.
    #[arg(long, default_value_t = 150, allow_negative_numbers = true,
          value_parser = parse_count)]
    ngmax: usize,
    /// Scheme preset to start from instead of the case's own: `paper`
    /// (the seed paper's eqs. 1-5: IAD, grad-h, constant alpha = 1), `noh`
    /// (kernel gradients, grad-h, switches up to alpha 0.7), `evrard`
    /// (kernel gradients, no grad-h, switches up to alpha 0.5). The options
    /// below override it one by one.
    #[arg(long, value_name = "NAME")]
    scheme: Option<String>,
    /// Gradient operator (default: the case's, see `sphexa cases`).
    #[arg(long, value_enum)]
    gradients: Option<GradientArg>,
    /// Space-filling curve for sorting particles.
    #[arg(long, value_enum, default_value = "hilbert")]
    curve: CurveArg,
    /// Artificial viscosity strength alpha, the maximum with switches; a
    /// number >= 0 (default: the case's, see `sphexa cases`).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_non_negative)]
    alpha: Option<f64>,
    /// Courant factor, in (0, 1].
    #[arg(long, default_value_t = 0.2, allow_negative_numbers = true,
          value_parser = parse_courant)]
    courant: f64,
    /// The grad-h correction Omega (default: the case's, see `sphexa cases`).
    #[arg(long, value_enum)]
    grad_h: Option<Switch>,
    /// Leave out the grad-h correction (Omega = 1): `--grad-h off`.
    #[arg(long, conflicts_with = "grad_h")]
    no_grad_h: bool,
    /// Time-dependent viscosity switches: each particle's alpha rises to
    /// --alpha in shocks and decays to 0.05 elsewhere (SPH-EXA's "ve"
    /// switches). Default: the case's, see `sphexa cases`.
    #[arg(long, value_enum)]
    av_switches: Option<Switch>,
    /// Artificial conductivity of internal energy alpha_u, a number >= 0
    /// (0 = off; ~1 smooths wall heating at shocks and walls). Default: the
    /// scheme's (off in every preset).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_non_negative)]
    conductivity: Option<f64>,
    /// Self-gravity: opening angle theta of the tree, a positive number
    /// (cases with gravity only).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true,
          value_parser = parse_positive)]
    theta: f64,
    /// Self-gravity: pairs are softened within SOFTENING * (h_i + h_j), a
    /// number >= 0 (1 = SPH-EXA's choice; default: the case's, see
    /// `sphexa cases`; cases with gravity only).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_non_negative)]
    softening: Option<f64>,
    /// Also write the final state of every particle (particles.csv, sorted
    /// by id, exact decimal round-trip of every value).
    #[arg(long)]
    write_particles: bool,
    /// No progress output.
    #[arg(short, long)]
    quiet: bool,
}

/// The registered cases as the allowed values of the case argument (with
/// their descriptions in `sphexa run --help`).
fn case_names() -> PossibleValuesParser {
    PossibleValuesParser::new(
        cases::registry()
            .iter()
            .map(|c| PossibleValue::new(c.name()).help(c.description())),
    )
}

fn parse_side(s: &str) -> Result<usize, String> {
    let (lo, hi) = SIDE_RANGE;
    match s.trim().parse::<i64>() {
        Ok(n) if (lo as i64..=hi as i64).contains(&n) => Ok(n as usize),
        _ => Err(format!(
            "particles per side must be a whole number from {lo} to {hi}"
        )),
    }
}

fn parse_steps(s: &str) -> Result<u64, String> {
    match s.trim().parse::<i64>() {
        Ok(n) if n >= 1 => Ok(n as u64),
        _ => Err("the number of steps must be a whole number, at least 1".into()),
    }
}

fn parse_threads(s: &str) -> Result<usize, String> {
    match s.trim().parse::<i64>() {
        Ok(n) if (1..=MAX_THREADS).contains(&n) => Ok(n as usize),
        _ => Err(format!(
            "the thread count must be a whole number, at least 1 (at most {MAX_THREADS})"
        )),
    }
}

fn parse_count(s: &str) -> Result<usize, String> {
    match s.trim().parse::<i64>() {
        Ok(n) if n >= 1 => Ok(n as usize),
        _ => Err("a neighbour count must be a whole number, at least 1".into()),
    }
}

/// A finite number within `ok`, or `allowed` as the error.
fn parse_number(s: &str, ok: impl Fn(f64) -> bool, allowed: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && ok(x) => Ok(x),
        _ => Err(allowed.into()),
    }
}

fn parse_positive(s: &str) -> Result<f64, String> {
    parse_number(s, |x| x > 0.0, "a positive finite number is required")
}

fn parse_non_negative(s: &str) -> Result<f64, String> {
    parse_number(s, |x| x >= 0.0, "a finite number >= 0 is required")
}

fn parse_courant(s: &str) -> Result<f64, String> {
    parse_number(
        s,
        |x| x > 0.0 && x <= 1.0,
        "the Courant factor must be a number in (0, 1]",
    )
}

fn parse_kernel(s: &str) -> Result<KernelChoice, String> {
    s.parse()
        .map_err(|e: sph_kernels::KernelError| e.to_string())
}

fn main() -> ExitCode {
    sph_apps::memory::return_large_buffers_to_os();
    let cli = Cli::parse();
    match cli.command {
        Command::Cases => {
            list_cases();
            ExitCode::SUCCESS
        }
        Command::Run(args) => match run(*args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        },
    }
}

/// `sphexa cases`: one line per case, then its default scheme as the
/// options that would select it.
fn list_cases() {
    println!(
        "{:<14} {:>6} {:>9}  description",
        "case", "side", "end time"
    );
    for c in cases::registry() {
        println!(
            "{:<14} {:>6} {:>9}  {}",
            c.name(),
            c.default_side(),
            c.default_end_time(),
            c.description()
        );
        println!(
            "{:<14} scheme: {}",
            "",
            scheme_options(&c.default_scheme(), c.physics().softening)
        );
    }
    println!("\nscheme presets (sphexa run CASE --scheme NAME):");
    for (name, scheme, what) in PRESETS {
        println!("{name:<14} {what}");
        println!("{:<14} {}", "", scheme_options(&scheme, None));
    }
}

/// A scheme (and the case's softening) written as the `sphexa run`
/// options that select it.
fn scheme_options(s: &Scheme, softening: Option<f64>) -> String {
    let on = |b: bool| if b { "on" } else { "off" };
    let gradients = match s.gradients {
        Gradients::Iad => "iad",
        Gradients::Kernel => "kernel",
    };
    let mut text = format!(
        "--gradients {gradients} --grad-h {} --alpha {} --av-switches {}",
        on(s.grad_h),
        s.alpha(),
        on(s.switches().is_some())
    );
    if let Some(c) = s.conductivity {
        text += &format!(" --conductivity {c}");
    }
    if let Some(soft) = softening {
        text += &format!(" --softening {soft} (self-gravity)");
    }
    text
}

/// What the command line changes in the case's scheme.
fn scheme_overrides(a: &RunArgs) -> Result<SchemeOverrides, AppError> {
    let preset = match &a.scheme {
        Some(name) => Some(Scheme::preset(name).map_err(|_| {
            let names: Vec<String> = PRESETS
                .iter()
                .map(|(n, _, what)| format!("{n} ({what})"))
                .collect();
            AppError::Usage(format!(
                "--scheme {name}: unknown scheme; presets: {}",
                names.join("; ")
            ))
        })?),
        None => None,
    };
    Ok(SchemeOverrides {
        preset,
        gradients: a.gradients.map(|g| match g {
            GradientArg::Iad => Gradients::Iad,
            GradientArg::Kernel => Gradients::Kernel,
        }),
        grad_h: if a.no_grad_h {
            Some(false)
        } else {
            a.grad_h.map(|g| g == Switch::On)
        },
        alpha: a.alpha,
        av_switches: a.av_switches.map(|s| s == Switch::On),
        conductivity: a.conductivity,
        softening: a.softening,
    })
}

fn run(a: RunArgs) -> Result<(), AppError> {
    let case = cases::lookup(&a.case)?;
    let side = a.side.unwrap_or(case.default_side());
    if a.ng0 < 8 || a.ng0 > a.ngmax {
        return Err(AppError::Usage(format!(
            "--ng0 {} must be at least 8 and at most --ngmax {}",
            a.ng0, a.ngmax
        )));
    }
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(case.name()));
    // Before any work: a folder that cannot be made is a usage error.
    std::fs::create_dir_all(&out).map_err(|e| {
        AppError::Usage(format!(
            "--out {}: cannot create this folder ({e}); give a folder that can be created and written",
            out.display()
        ))
    })?;
    if let Some(t) = a.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .map_err(|e| AppError::Usage(format!("cannot start {t} threads: {e}")))?;
    }
    let kernel_choice = a.kernel;
    let kernel: Tabulated = kernel_choice.tabulate(Tabulated::DEFAULT_POINTS)?;

    let mut config = HydroConfig {
        curve: match a.curve {
            CurveArg::Hilbert => Curve::Hilbert,
            CurveArg::Morton => Curve::Morton,
        },
        // Kept only by cases with self-gravity.
        gravity: Some(sph_gravity::GravityParams {
            theta: a.theta,
            ..Default::default()
        }),
        ..HydroConfig::default()
    };
    config.neighbors.ng0 = a.ng0;
    config.neighbors.ngmax = a.ngmax;
    config.timestep.k_courant = a.courant;
    let stop = match (a.steps, a.end_time) {
        (Some(s), _) => Stop::Steps(s),
        (None, Some(t)) => Stop::Time(t),
        (None, None) => Stop::Time(case.default_end_time()),
    };
    #[cfg(feature = "mpi")]
    let comm = sph_comm::MpiComm::init()?;
    #[cfg(not(feature = "mpi"))]
    let comm = sph_comm::SerialComm::new();
    let (rank, ranks) = (comm.rank(), comm.size());
    let root = rank == 0;
    // The case applies its own scheme with what the command line
    // overrides; each rank builds only its share of the particles.
    let share = cases::Share { rank, ranks };
    let scene = case.setup_share(side, config, &scheme_overrides(&a)?, share)?;
    scene.config.scheme.validate()?;
    let n = scene.total;
    if !a.quiet && root {
        eprintln!(
            "sphexa: {} with {n} particles, kernel {kernel_choice}, {ranks} rank(s) x {} threads, output in {}",
            case.name(),
            rayon::current_num_threads(),
            out.display()
        );
    }
    let progress = if a.quiet {
        Progress::Quiet
    } else {
        Progress::Auto
    };
    let result = Simulation::with_comm(scene, kernel, kernel_choice.to_string(), comm).and_then(
        |mut sim| {
            sim.set_write_particles(a.write_particles);
            sim.run(stop, &out, progress)
        },
    );
    let s = match result {
        Ok(s) => s,
        Err(e) if ranks > 1 => {
            // The other ranks may wait in a collective: leave without
            // finalising MPI, so that mpirun ends the job with this message.
            eprintln!("error on rank {rank} of {ranks}: {e}");
            std::process::exit(1);
        }
        Err(e) => return Err(e),
    };
    if !root {
        return Ok(());
    }
    println!(
        "{}: {} particles, {} steps to t = {:.4}, {:.1} s wall, {:.3e} particle-steps/s, peak RSS {:.0} MB",
        s.case,
        s.particles,
        s.steps,
        s.t_end,
        s.wall_s,
        s.particle_steps_per_s,
        s.peak_rss_bytes as f64 / 1e6
    );
    if let Some(l1) = s.l1 {
        println!("L1: rho {:.4e}  p {:.4e}  |v| {:.4e}", l1.rho, l1.p, l1.v);
    }
    if let (Some(r), Some(rr)) = (s.shock_radius, s.shock_radius_ref) {
        println!(
            "shock radius {r:.4} (reference {rr:.4}), peak density {:.3}",
            s.peak_density
        );
    }
    println!(
        "energy drift {:.3e}, momentum drift {:.3e}, angular momentum drift {:.3e}",
        s.energy_rel_drift, s.momentum_rel_drift, s.angular_momentum_rel_drift
    );
    if ranks > 1 {
        let d = s.domain;
        println!(
            "domain: {ranks} ranks, {}..{} particles per rank, halo ratio {:.3} (max {:.3}), {:.3e} bytes sent/step, sync {:.3e} s/step, communication {:.3e} s/step",
            d.owned_min, d.owned_max, d.halo_ratio_mean, d.halo_ratio_max,
            d.bytes_sent_per_step, d.sync_seconds_per_step, d.comm_seconds_per_step
        );
    }
    Ok(())
}
