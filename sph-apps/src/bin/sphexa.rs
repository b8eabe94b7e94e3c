//! `sphexa`: run the SPH-EXA test cases from the command line.

use clap::{Args, Parser, Subcommand, ValueEnum};
use sph_apps::cases::{self, CASES};
use sph_apps::simulation::{Progress, Stop};
use sph_apps::{AppError, Simulation};
use sph_comm::Communicator;
use sph_core::{Gradients, HydroConfig, Scheme};
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
    /// List the test cases.
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

#[derive(Args, Debug)]
struct RunArgs {
    /// Test case (see `sphexa cases`).
    case: String,
    /// Particles per side of the initial lattice (default: the case's).
    #[arg(short = 'n', long = "side")]
    side: Option<usize>,
    /// Number of steps to run.
    #[arg(long, conflicts_with = "end_time")]
    steps: Option<u64>,
    /// Simulated time to reach (default: the case's).
    #[arg(long = "end-time")]
    end_time: Option<f64>,
    /// Output folder (default: out/CASE).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Kernel: `sinc`, `sinc:N` (N >= 1, default 6), `m4`, `wendland-c2`, `wendland-c4`, `wendland-c6`.
    #[arg(long, default_value = "sinc:6")]
    kernel: String,
    /// Target neighbour count, self included.
    #[arg(long, default_value_t = 100)]
    ng0: usize,
    /// Largest accepted neighbour count before h is iterated.
    #[arg(long, default_value_t = 150)]
    ngmax: usize,
    /// Scheme preset to start from (default: the case's own): `paper`
    /// (the seed paper's eqs. 1-5: IAD, grad-h, alpha = 1), `noh`, `evrard`
    /// (see `sphexa cases`); the options below override it one by one.
    #[arg(long, value_name = "NAME")]
    scheme: Option<String>,
    /// Gradient operator (default: the scheme's; iad for `paper`).
    #[arg(long, value_enum)]
    gradients: Option<GradientArg>,
    /// Space-filling curve for sorting particles.
    #[arg(long, value_enum, default_value = "hilbert")]
    curve: CurveArg,
    /// Artificial viscosity strength alpha, the maximum with switches
    /// (default: the case's; 1 for all but evrard, 0.5).
    #[arg(long)]
    alpha: Option<f64>,
    /// Courant factor.
    #[arg(long, default_value_t = 0.2)]
    courant: f64,
    /// The grad-h correction Omega (default: the case's; on for all but
    /// evrard).
    #[arg(long, value_name = "on|off")]
    grad_h: Option<Switch>,
    /// Leave out the grad-h correction (Omega = 1): `--grad-h off`.
    #[arg(long, conflicts_with = "grad_h")]
    no_grad_h: bool,
    /// Time-dependent viscosity switches: each particle's alpha rises to
    /// --alpha in shocks and decays to 0.05 elsewhere (SPH-EXA's "ve"
    /// switches). Default: the case's; on for evrard only.
    #[arg(long, value_name = "on|off")]
    av_switches: Option<Switch>,
    /// Artificial conductivity of internal energy alpha_u (0 = off, the
    /// paper's scheme; ~1 smooths wall heating at shocks and walls).
    /// Default: the scheme's (off in every preset).
    #[arg(long)]
    conductivity: Option<f64>,
    /// Self-gravity: opening angle theta of the tree (cases with gravity).
    #[arg(long, default_value_t = 0.5)]
    theta: f64,
    /// Self-gravity: pairs are softened within SOFTENING * (h_i + h_j)
    /// (1 = SPH-EXA's choice; default: the case's, 0.25 for evrard).
    #[arg(long)]
    softening: Option<f64>,
    /// Also write the final state of every particle (particles.csv, sorted
    /// by id, exact decimal round-trip of every value).
    #[arg(long)]
    write_particles: bool,
    /// No progress output.
    #[arg(short, long)]
    quiet: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Cases => {
            println!(
                "{:<14} {:>6} {:>9}  description",
                "case", "side", "end time"
            );
            for c in CASES {
                println!(
                    "{:<14} {:>6} {:>9}  {}",
                    c.name, c.default_side, c.default_end_time, c.description
                );
            }
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

fn run(a: RunArgs) -> Result<(), AppError> {
    let info = cases::find(&a.case).ok_or_else(|| {
        let names: Vec<&str> = CASES.iter().map(|c| c.name).collect();
        AppError::Usage(format!(
            "unknown case '{}'; available: {}",
            a.case,
            names.join(", ")
        ))
    })?;
    let side = a.side.unwrap_or(info.default_side);
    if side < 4 {
        return Err(AppError::Usage(format!(
            "--side {side} is too small: at least 4 particles per side are needed"
        )));
    }
    if side > 1000 {
        return Err(AppError::Usage(format!(
            "--side {side} is too large (at most 1000)"
        )));
    }
    if let Some(t) = a.end_time {
        if !(t > 0.0 && t.is_finite()) {
            return Err(AppError::Usage(format!(
                "--end-time {t} must be a positive number"
            )));
        }
    }
    if a.steps == Some(0) {
        return Err(AppError::Usage("--steps must be at least 1".into()));
    }
    if a.ng0 < 8 || a.ng0 > a.ngmax {
        return Err(AppError::Usage(format!(
            "--ng0 {} must be at least 8 and at most --ngmax {}",
            a.ng0, a.ngmax
        )));
    }
    if !(a.courant > 0.0 && a.courant <= 1.0) {
        return Err(AppError::Usage(format!(
            "--courant {} must be in (0, 1]",
            a.courant
        )));
    }
    if let Some(t) = a.threads {
        if t == 0 {
            return Err(AppError::Usage("--threads must be at least 1".into()));
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .map_err(|e| AppError::Usage(format!("cannot start {t} threads: {e}")))?;
    }
    let kernel_choice: KernelChoice = a.kernel.parse()?;
    let kernel: Tabulated = kernel_choice.tabulate(Tabulated::DEFAULT_POINTS)?;

    let mut config = HydroConfig {
        curve: match a.curve {
            CurveArg::Hilbert => Curve::Hilbert,
            CurveArg::Morton => Curve::Morton,
        },
        ..HydroConfig::default()
    };
    config.neighbors.ng0 = a.ng0;
    config.neighbors.ngmax = a.ngmax;
    config.timestep.k_courant = a.courant;
    if !(a.theta > 0.0 && a.theta.is_finite()) {
        return Err(AppError::Usage(format!(
            "--theta {} must be positive",
            a.theta
        )));
    }
    // The case's scheme (or a named preset), then what the command line
    // overrides.
    let mut scheme = match &a.scheme {
        Some(name) => Scheme::preset(name)?,
        None => info.scheme,
    };
    if let Some(c) = a.conductivity {
        if !(c >= 0.0 && c.is_finite()) {
            return Err(AppError::Usage(format!(
                "--conductivity {c} must be a finite number >= 0 (0 = off)"
            )));
        }
        scheme.conductivity = (c > 0.0).then_some(c);
    }
    if let Some(g) = a.gradients {
        scheme.gradients = match g {
            GradientArg::Iad => Gradients::Iad,
            GradientArg::Kernel => Gradients::Kernel,
        };
    }
    if let Some(alpha) = a.alpha {
        if !(alpha >= 0.0 && alpha.is_finite()) {
            return Err(AppError::Usage(format!("--alpha {alpha} must be >= 0")));
        }
        scheme.set_alpha(alpha);
    }
    if let Some(g) = a.grad_h {
        scheme.grad_h = g == Switch::On;
    }
    if a.no_grad_h {
        scheme.grad_h = false;
    }
    if let Some(s) = a.av_switches {
        scheme.set_switches(s == Switch::On);
    }
    let softening = a.softening.unwrap_or(info.softening);
    if !(softening >= 0.0 && softening.is_finite()) {
        return Err(AppError::Usage(format!(
            "--softening {softening} must be >= 0"
        )));
    }
    scheme.validate()?;
    config.scheme = scheme;
    // Cases without self-gravity drop these parameters.
    config.gravity = Some(sph_gravity::GravityParams {
        theta: a.theta,
        softening,
        ..Default::default()
    });

    let scene = match info.name {
        "sedov" => cases::sedov::setup(side, config)?,
        "noh" => cases::noh::setup(side, config)?,
        "square-patch" => cases::square_patch::setup(side, config)?,
        "evrard" => cases::evrard::setup(side, config)?,
        other => return Err(AppError::Usage(format!("case {other} has no set-up"))),
    };
    let stop = match (a.steps, a.end_time) {
        (Some(s), _) => Stop::Steps(s),
        (None, Some(t)) => Stop::Time(t),
        (None, None) => Stop::Time(info.default_end_time),
    };
    let out = a
        .out
        .unwrap_or_else(|| PathBuf::from("out").join(info.name));
    #[cfg(feature = "mpi")]
    let comm = sph_comm::MpiComm::init()?;
    #[cfg(not(feature = "mpi"))]
    let comm = sph_comm::SerialComm::new();
    let (rank, ranks) = (comm.rank(), comm.size());
    let root = rank == 0;
    let n = scene.particles.len();
    if !a.quiet && root {
        eprintln!(
            "sphexa: {} with {n} particles, kernel {kernel_choice}, {ranks} rank(s) x {} threads, output in {}",
            info.name,
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
