//! `sphexa`: run the SPH-EXA test cases from the command line.

use clap::builder::{PossibleValue, PossibleValuesParser};
use clap::parser::ValueSource;
use clap::{
    ArgAction, ArgMatches, Args, CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum,
};
use sph_apps::cases::{self, FirstStep, Physics, Scheme, SchemeOverrides};
use sph_apps::checkpoint;
use sph_apps::config::{self, OptionKey};
use sph_apps::output::snapshot::{self as snapfile, Schedule};
use sph_apps::simulation::{CheckpointEvery, Outputs, Progress, Stop};
use sph_apps::watch::{Bounds, Watch, GRAVITY_MOMENTUM_BOUND};
use sph_apps::{AppError, Simulation};
use sph_comm::Communicator;
use sph_core::PRESETS;
use sph_core::{AvForm, Choice, Gradients, HydroConfig, Volume};
use sph_kernels::{FastKernel, KernelChoice};
use sph_tree::Curve;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Smoothed Particle Hydrodynamics (the SPH-EXA scheme), multi-threaded, and
/// over MPI when built with `--features mpi` (`mpirun -n 4 sphexa run ...`).
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
    Run(Box<RunArgs>),
    /// List the test cases with their default size, end time and scheme.
    Cases,
    /// Error against run time: run every combination of case, size,
    /// scheme, kernel and repeat as a fresh `sphexa run` process to the
    /// case's end time, and write bench.csv, bench.json (with the spread
    /// over repeats and the fitted convergence orders) and
    /// error_vs_time.png into --out.
    Bench(Box<BenchArgs>),
    /// Runs built to break the solver (noisy lattices, Courant sweeps, a
    /// strong shock tube, extreme kernels and neighbour counts, a 100x
    /// spread of smoothing lengths, a long run at rest, extreme inputs):
    /// each pass or fail with its figures, in OUT/stress.json and a table.
    /// Exits non-zero when a scenario fails.
    Stress(StressArgs),
    /// Glass initial conditions: relax SIDE^3 random particles in a
    /// periodic unit cube with the solver's kernel until the density
    /// scatter std(rho)/mean(rho) is below --tolerance, and write them
    /// (x, y, z in [0, 1), H5Part) to --out, by default into the glass
    /// cache that cases set up from glass read ($SPHEXA_GLASS_DIR, else
    /// $XDG_CACHE_HOME/sphexa/glass, else ~/.cache/sphexa/glass).
    Glass(GlassArgs),
}

#[derive(Args, Debug)]
struct GlassArgs {
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
    #[arg(long, value_name = "X", default_value_t = sph_apps::glass::TOLERANCE,
          allow_negative_numbers = true, value_parser = parse_positive)]
    tolerance: f64,
    /// Most relaxation steps.
    #[arg(long, value_name = "N", default_value_t = sph_apps::glass::MAX_STEPS,
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

#[derive(Args, Debug)]
struct StressArgs {
    /// The short suite (CI: under 5 minutes on 2 cores).
    #[arg(long)]
    quick: bool,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_threads)]
    threads: Option<usize>,
    /// Output folder (default out/stress): stress.json and each run's files.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

#[derive(Args, Debug)]
struct BenchArgs {
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

#[derive(ValueEnum, Clone, Copy, Debug)]
enum GradientArg {
    /// Integral approach to derivatives (exact for linear fields).
    Iad,
    /// Plain kernel gradients.
    Kernel,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq)]
enum VolumeArg {
    /// m / rho: the seed paper's.
    Mass,
    /// SPH-EXA's generalised volume elements, X = m / rho0 (needs IAD).
    Ve,
    /// Pressure-energy volumes, X = m u: a pressure that stays smooth
    /// across contact discontinuities (needs u > 0).
    PressureEnergy,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq)]
enum AvFormArg {
    /// The seed paper's: Pi_ij = -alpha_ij/2 (c_i + c_j - 3 w_ij) w_ij, and
    /// the Courant signal velocity c_i + c_j - 3 min(w_ij, 0).
    Paper,
    /// SPH-EXA's `ve`: Pi_ij = -(alpha_ij/2 (c_i + c_j) - 2 w_ij) w_ij (its
    /// beta = 2 term not scaled by alpha), and the Courant signal velocity
    /// (c_i + c_j)/2 - 2 w_ij.
    SphExa,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq)]
enum FirstStepArg {
    /// At most 1.1 times the case's first dt, growing by 1.1 per step
    /// until a time-step criterion takes over (SPH-EXA's start).
    Ramp,
    /// The time-step criteria's step at once (Courant, density change,
    /// acceleration, falling internal energy).
    Criteria,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq)]
enum SmoothingArg {
    /// Follows the neighbour count every step.
    Adaptive,
    /// Stays as set up.
    Fixed,
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

/// The default of --max-momentum-drift.
const DEFAULT_MOMENTUM_BOUND: f64 = 1e-10;

/// Most worker threads per rank.
const MAX_THREADS: i64 = 1 << 16;

/// Smallest and largest particles per side.
const SIDE_RANGE: (usize, usize) = (4, 1000);

#[derive(Args, Debug)]
struct RunArgs {
    /// Test case (`sphexa cases` lists each with its defaults). Required
    /// unless --config or --restart names it.
    #[arg(value_parser = case_names())]
    case: Option<String>,
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
    /// Cubic lattices even where the case starts from glass (sod,
    /// wind-shock). Glass
    /// blocks are relaxed with the run's kernel and neighbour counts on
    /// first use and cached in $SPHEXA_GLASS_DIR, else
    /// $XDG_CACHE_HOME/sphexa/glass, else ~/.cache/sphexa/glass (see
    /// `sphexa glass`).
    #[arg(long)]
    lattice: bool,
    /// Target neighbour count, self included: 8 to --ngmax.
    #[arg(long, default_value_t = 100, allow_negative_numbers = true,
          value_parser = parse_count)]
    ng0: usize,
    /// Largest accepted neighbour count before h is iterated: --ng0 or more.
    #[arg(long, default_value_t = 150, allow_negative_numbers = true,
          value_parser = parse_count)]
    ngmax: usize,
    /// Scheme preset to start from instead of the case's own: `paper`
    /// (the seed paper's eqs. 1-5: IAD, grad-h, constant alpha = 1), `std`
    /// (SPH-EXA's std: as paper without grad-h), `ve` (SPH-EXA's default:
    /// volume elements, grad-h, IAD, its switches), `ve-ac` (ve without
    /// grad-h, with conductivity 1), `best` (ve-ac with the paper's
    /// viscosity and switches up to alpha 0.5: the lowest Sedov error per
    /// second), `shear` (the paper's with switches and
    /// AV cleaning), `contact` (pressure-energy volumes,
    /// kernel gradients, grad-h, alpha = 1), `noh` (kernel gradients, grad-h,
    /// switches up to alpha 0.7), `evrard` (kernel gradients, no grad-h,
    /// switches up to alpha 0.5, conductivity 3); `sphexa cases` lists them. The options
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
    /// Courant factor, in (0, 1] (default: the case's, see `sphexa cases`:
    /// 0.2, evrard 0.5).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_courant)]
    courant: Option<f64>,
    /// The first time step (default: ramp). `criteria` skips the ramp
    /// from the case's first dt: Sedov (dt0 = 1e-6, as SPH-EXA) then
    /// starts at the Courant step of its hot centre, with about 60 steps
    /// fewer to t = 0.05.
    #[arg(long, value_enum)]
    first_step: Option<FirstStepArg>,
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
    /// scheme's (1 in `ve-ac`, 3 in `evrard`, off in the other presets).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_non_negative)]
    conductivity: Option<f64>,
    /// Artificial stress epsilon against the tensile instability (Monaghan
    /// 2000): a repulsion between particles under negative pressure that
    /// close in below the lattice spacing; a number >= 0 (0 = off; 0.2 is
    /// Monaghan's value). Default: the case's (square-patch: 0.2; off
    /// elsewhere).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_non_negative)]
    artificial_stress: Option<f64>,
    /// Smoothing lengths: `adaptive` follows the neighbour count every
    /// step; `fixed` keeps each particle's h as set up (weakly compressible
    /// flows with a free surface). Default: the case's (square-patch:
    /// fixed; adaptive elsewhere).
    #[arg(long, value_enum)]
    smoothing_length: Option<SmoothingArg>,
    /// Particle volumes (default: the case's, see `sphexa cases`).
    #[arg(long, value_enum)]
    volume: Option<VolumeArg>,
    /// AV cleaning after SPH-EXA's: the viscosity of an approaching pair acts
    /// on the velocity jump left after a limited linear reconstruction from
    /// both sides, so shear layers and smooth flows keep their kinetic
    /// energy while shocks keep their full viscosity. Default: the case's (kelvin-helmholtz:
    /// see `sphexa cases`).
    #[arg(long, value_enum)]
    av_cleaning: Option<Switch>,
    /// Form of the artificial viscosity and of the Courant signal velocity
    /// that goes with it (default: the scheme's: `sph-exa` in `ve` and
    /// `ve-ac`, `paper` in the other presets).
    #[arg(long, value_enum)]
    av_form: Option<AvFormArg>,
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
    /// Every rank but 0 also writes its own stage timings
    /// (timings.rankR.csv, the columns of timings.csv, which is rank 0's):
    /// where a multi-rank run waits. A pair stage slower on one rank is
    /// imbalance; the others' `halos` and `conserved` columns hold their
    /// wait for it.
    #[arg(long)]
    rank_timings: bool,
    /// No progress output.
    #[arg(short, long)]
    quiet: bool,
    /// Stop with an error at the first conserved quantity past its bound
    /// (--max-energy-drift, --max-momentum-drift, total mass exact, every
    /// particle mass > 0), naming the quantity, the step and the particle
    /// to blame. Without it the run warns once per quantity and records
    /// the step in summary.json.
    #[arg(long)]
    strict: bool,
    /// Bound of the relative total-energy drift |E - E0| / |E0| checked
    /// after every step, a number >= 0.
    #[arg(long, value_name = "X", default_value_t = 1e-2, allow_negative_numbers = true,
          value_parser = parse_non_negative)]
    max_energy_drift: f64,
    /// Bound of the momentum drift |p - p0| relative to the momentum scale
    /// (the largest sqrt(2 M (E_kin + |E_int|)) so far: M times the rms of
    /// speed and thermal speed), a number >= 0. Left at its default 1e-10,
    /// runs with self-gravity use 1e-4 (the tree's forces conserve momentum
    /// only to its accuracy).
    #[arg(long, value_name = "X", default_value_t = DEFAULT_MOMENTUM_BOUND, allow_negative_numbers = true,
          value_parser = parse_non_negative)]
    max_momentum_drift: f64,
    /// Fields of the snapshots, comma-separated (default:
    /// x,y,z,vx,vy,vz,h,m,u,rho,p,id). Snapshots are written when a
    /// --snapshot-every-steps, --snapshot-every-time or --snapshot-at
    /// schedule is given, as OUT/snapshots/snapshot_SSSSSSSS.h5 (HDF5,
    /// H5Part layout: h5py, ParaView and SPH-EXA's scripts read them).
    /// Fields: see the full help (--help).
    #[arg(long, value_name = "LIST", value_parser = parse_field_list,
          long_help = snapshot_fields_help())]
    snapshot_fields: Option<FieldList>,
    /// Write a snapshot after every N-th step (N >= 1).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_steps)]
    snapshot_every_steps: Option<u64>,
    /// Write a snapshot after the first step reaching each multiple of T
    /// (simulated time, positive). Steps are never shortened for outputs.
    #[arg(long, value_name = "T", allow_negative_numbers = true, value_parser = parse_positive)]
    snapshot_every_time: Option<f64>,
    /// Write a snapshot after the first step reaching each of these times
    /// (comma-separated, each >= 0).
    #[arg(long, value_name = "T1,T2,...", allow_negative_numbers = true, value_parser = parse_times)]
    snapshot_at: Option<Times>,
    /// Write checkpoints (every field a restart needs, full precision) as
    /// OUT/checkpoints/checkpoint_SSSSSSSS.h5: `N` after every N-th step;
    /// `time:T` after the first step reaching each multiple of simulated
    /// time T; `wall:DURATION` every DURATION of wall-clock time (`90s`,
    /// `10m`, `2h`, `1d`; a plain number is seconds); `auto` every
    /// sqrt(2 C M) of wall-clock time (Young/Daly), with C the measured time
    /// of the last checkpoint (the first is written after step 1) and M
    /// from --mtbf.
    #[arg(long, value_name = "SPEC", value_parser = parse_checkpoint_every)]
    checkpoint_every: Option<CheckpointSpec>,
    /// Mean time between failures of the machine, for `--checkpoint-every
    /// auto`: a DURATION (`6h`, `30m`, `2d`, or seconds).
    #[arg(long, value_name = "DURATION", value_parser = parse_duration)]
    mtbf: Option<f64>,
    /// Checkpoints of this run to keep: older ones are deleted once a newer
    /// one is complete (0 keeps all).
    #[arg(long, value_name = "K", default_value_t = 2, allow_negative_numbers = true,
          value_parser = parse_keep)]
    checkpoint_keep: usize,
    /// Continue the run of checkpoint FILE (its step STEP, default the
    /// last step group): the checkpoint's configuration applies, options
    /// given here override it (a changed physics option makes the
    /// continuation differ from the run that wrote it). --steps and
    /// --end-time count from the run's start, not from the checkpoint.
    /// conserved.csv in --out keeps its lines up to the checkpoint;
    /// timings.csv and summary.json cover the continued part.
    #[arg(long, value_name = "FILE[:STEP]", conflicts_with = "init")]
    restart: Option<String>,
    /// Start the case from the particles of snapshot FILE (Step#K, default
    /// the last): ours, or an H5Part file of SPH-EXA (group Step#K with 1-D
    /// datasets x, y, z, h, m, u and optionally vx, vy, vz, id, any float
    /// or integer type; the box from attribute `box` if present). Time
    /// starts at 0; the case supplies the scheme and the reference.
    #[arg(long, value_name = "FILE[:K]")]
    init: Option<String>,
    /// Read options from a TOML file: one key per option, named as the
    /// option without its dashes (`side = 20`, `end-time = 0.05`,
    /// `av-switches = "on"`, `snapshot-at = [0.01, 0.02]`, `case =
    /// "sedov"`); options on the command line override it. Every run writes
    /// its resolved configuration as OUT/config.toml, which repeats it.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
}

/// A `--checkpoint-every` value.
#[derive(Debug, Clone, Copy, PartialEq)]
enum CheckpointSpec {
    Steps(u64),
    Time(f64),
    Wall(f64),
    Auto,
}

impl std::fmt::Display for CheckpointSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CheckpointSpec::Steps(n) => write!(f, "{n}"),
            CheckpointSpec::Time(t) => write!(f, "time:{t}"),
            CheckpointSpec::Wall(s) => write!(f, "wall:{s}s"),
            CheckpointSpec::Auto => f.write_str("auto"),
        }
    }
}

fn parse_checkpoint_every(s: &str) -> Result<CheckpointSpec, String> {
    let s = s.trim();
    let allowed = "allowed: N (steps, at least 1), time:T (positive simulated time), wall:DURATION (e.g. 90s, 10m, 2h), auto (with --mtbf)";
    if s == "auto" {
        return Ok(CheckpointSpec::Auto);
    }
    if let Some(t) = s.strip_prefix("time:") {
        return parse_positive(t)
            .map(CheckpointSpec::Time)
            .map_err(|_| format!("'{t}' is not a positive time; {allowed}"));
    }
    if let Some(d) = s.strip_prefix("wall:") {
        return parse_duration(d).map(CheckpointSpec::Wall);
    }
    parse_steps(s)
        .map(CheckpointSpec::Steps)
        .map_err(|_| allowed.to_owned())
}

/// A duration: a positive number with an optional unit s, m, h or d.
fn parse_duration(s: &str) -> Result<f64, String> {
    let s = s.trim();
    let (num, scale) = match s.char_indices().last() {
        Some((i, 's')) => (&s[..i], 1.0),
        Some((i, 'm')) => (&s[..i], 60.0),
        Some((i, 'h')) => (&s[..i], 3600.0),
        Some((i, 'd')) => (&s[..i], 86400.0),
        _ => (s, 1.0),
    };
    match num.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x * scale),
        _ => Err("a duration is a positive number with an optional unit s, m, h or d (e.g. 90s, 10m, 6h, 2d)".into()),
    }
}

/// A `--snapshot-fields` list.
#[derive(Debug, Clone, PartialEq)]
struct FieldList(Vec<String>);

/// The long help of `--snapshot-fields`, its field list from the field
/// table.
fn snapshot_fields_help() -> String {
    format!(
        "Fields of the snapshots, comma-separated (default: {}). Snapshots are written when a \
         --snapshot-every-steps, --snapshot-every-time or --snapshot-at schedule is given, as \
         OUT/snapshots/snapshot_SSSSSSSS.h5 (HDF5, H5Part layout: h5py, ParaView and SPH-EXA's \
         scripts read them). Fields: {}; and, where the scheme has them: {}.",
        snapfile::DEFAULT_FIELDS.join(","),
        snapfile::base_fields().join(","),
        snapfile::optional_fields().join(",")
    )
}

fn parse_field_list(s: &str) -> Result<FieldList, String> {
    snapfile::parse_fields(s).map(FieldList)
}

/// A `--snapshot-at` list.
#[derive(Debug, Clone, PartialEq)]
struct Times(Vec<f64>);

fn parse_times(s: &str) -> Result<Times, String> {
    s.split(',')
        .map(|t| {
            parse_number(t, |x| x >= 0.0, "").map_err(|_| {
                format!(
                    "'{}' is not a time >= 0; give times separated by commas",
                    t.trim()
                )
            })
        })
        .collect::<Result<Vec<f64>, String>>()
        .map(Times)
}

fn parse_keep(s: &str) -> Result<usize, String> {
    match s.trim().parse::<i64>() {
        Ok(n) if n >= 0 => Ok(n as usize),
        _ => Err(
            "the number of checkpoints to keep must be a whole number >= 0 (0 keeps all)".into(),
        ),
    }
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
    let matches = Cli::command().get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    match cli.command {
        Command::Cases => {
            list_cases();
            ExitCode::SUCCESS
        }
        Command::Stress(args) => match stress(args) {
            Ok(true) => ExitCode::SUCCESS,
            Ok(false) => ExitCode::FAILURE,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        },
        Command::Glass(args) => match glass(args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        },
        Command::Bench(args) => match bench(*args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        },
        Command::Run(args) => match layered(
            *args,
            matches.subcommand_matches("run").expect("run was parsed"),
        )
        .and_then(run)
        {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        },
    }
}

/// The global worker pool with `threads` threads (default: all cores).
fn start_threads(threads: Option<usize>) -> Result<(), AppError> {
    if let Some(t) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .map_err(|e| AppError::Usage(format!("cannot start {t} threads: {e}")))?;
    }
    Ok(())
}

/// `sphexa glass`: relax a block, report, write it.
fn glass(a: GlassArgs) -> Result<(), AppError> {
    use sph_apps::glass::{default_cache_dir, relax, write, GlassSpec};
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

/// `sphexa stress`: the suite, its table, and whether every scenario passed.
fn stress(a: StressArgs) -> Result<bool, AppError> {
    start_threads(a.threads)?;
    let out = a.out.unwrap_or_else(|| PathBuf::from("out/stress"));
    let outcomes = sph_apps::stress::run_suite(&sph_apps::stress::Options {
        quick: a.quick,
        out: out.clone(),
        verbose: true,
    })?;
    print!("{}", sph_apps::stress::table(&outcomes));
    let failed = outcomes.iter().filter(|o| !o.pass).count();
    say!(
        "{} of {} passed; {}",
        outcomes.len() - failed,
        outcomes.len(),
        out.join("stress.json").display()
    );
    Ok(failed == 0)
}

/// `sphexa bench`: every combination as a child process, then the report.
fn bench(a: BenchArgs) -> Result<(), AppError> {
    use sph_apps::bench::{read_csv, Report, Row};
    for name in &a.schemes {
        if name != "case" {
            Scheme::preset(name).map_err(|_| {
                let names: Vec<&str> = PRESETS.iter().map(|p| p.0).collect();
                AppError::Usage(format!(
                    "--schemes: unknown scheme '{name}'; allowed: case (each case's own), {}",
                    names.join(", ")
                ))
            })?;
        }
    }
    let launcher: Vec<&str> = a.mpirun.split_whitespace().collect();
    if let Some(&r) = a.ranks.iter().find(|&&r| r > 1) {
        if !cfg!(feature = "mpi") {
            return Err(AppError::Usage(format!(
                "--ranks {r}: this sphexa was built without MPI; build it with \
                 `cargo build --release -p sph-apps --features mpi` for runs on more than one rank"
            )));
        }
        if launcher.is_empty() {
            return Err(AppError::Usage(
                "--mpirun '': give the MPI launcher, e.g. mpirun or srun".into(),
            ));
        }
    }
    let reference = match &a.reference {
        Some(path) => Some((path.clone(), read_csv(path)?)),
        None => None,
    };
    let out = a.out.clone().unwrap_or_else(|| PathBuf::from("out/bench"));
    let exe = std::env::current_exe()
        .map_err(|e| AppError::Usage(format!("cannot find the sphexa binary to run: {e}")))?;
    let total = a.cases.len()
        * a.sizes.len()
        * a.schemes.len()
        * a.kernels.len()
        * a.ranks.len()
        * a.repeat as usize;
    let mut rows = match &a.from {
        Some(path) => read_csv(path)?,
        None => Vec::new(),
    };
    let mut k = 0;
    for case in &a.cases {
        for &side in &a.sizes {
            for scheme in &a.schemes {
                for kernel in &a.kernels {
                    for &ranks in &a.ranks {
                        for repeat in 0..a.repeat {
                            k += 1;
                            let kernel_text = kernel.to_string();
                            let dir = out.join("runs").join(format!(
                                "{case}_{scheme}_{}_{side}_r{ranks}_{repeat}",
                                kernel_text.replace(':', "")
                            ));
                            let mut cmd = if ranks > 1 {
                                let mut c = std::process::Command::new(launcher[0]);
                                c.args(&launcher[1..]);
                                c.arg("-n").arg(ranks.to_string()).arg(&exe);
                                c
                            } else {
                                std::process::Command::new(&exe)
                            };
                            cmd.args(["run", case, "-n", &side.to_string(), "-q"])
                                .args(["--kernel", &kernel_text])
                                .arg("--out")
                                .arg(&dir);
                            if scheme != "case" {
                                cmd.args(["--scheme", scheme]);
                            }
                            if let Some(t) = a.threads {
                                cmd.args(["--threads", &t.to_string()]);
                            }
                            if let Some(t) = a.end_time {
                                cmd.args(["--end-time", &t.to_string()]);
                            }
                            let what = format!(
                                "{case} --scheme {scheme} --kernel {kernel_text} -n {side} on {ranks} rank(s), repeat {repeat}"
                            );
                            let o = cmd.output().map_err(|e| {
                                AppError::Usage(format!("{what}: could not start: {e}"))
                            })?;
                            if !o.status.success() {
                                let err = String::from_utf8_lossy(&o.stderr);
                                return Err(AppError::Usage(format!(
                                    "{what} failed ({}): {}",
                                    o.status,
                                    err.trim()
                                )));
                            }
                            let path = dir.join("summary.json");
                            let text = std::fs::read_to_string(&path)
                                .map_err(|e| AppError::io(&path, e))?;
                            let json: serde_json::Value = serde_json::from_str(&text)
                                .map_err(|e| AppError::Usage(format!("{}: {e}", path.display())))?;
                            let row = Row::from_summary(&json, scheme, side as u64, repeat, &path)?;
                            if !a.quiet {
                                eprintln!(
                                    "[{k}/{total}] {what}: {} particles, {} steps, {:.2} s, L1 rho {:.4e} P {:.4e} |v| {:.4e}, peak RSS {:.0} MB",
                                    row.n, row.steps, row.wall_s, row.l1_rho, row.l1_p, row.l1_v,
                                    row.peak_rss_bytes as f64 / 1e6
                                );
                            }
                            rows.push(row);
                        }
                    }
                }
            }
        }
    }
    let mut names: Vec<String> = rows.iter().map(|r| r.case.clone()).collect();
    names.dedup();
    let report = Report::new(rows, reference);
    let title = format!("L1 against wall time: {}", names.join(", "));
    report.write(&out, &title)?;
    say!(
        "{:<28} {:>9} {:>6} {:>10} {:>10} {:>10} {:>10} {:>9}",
        "series",
        "N",
        "steps",
        "wall_s",
        "L1 rho",
        "L1 P",
        "L1 |v|",
        "RSS MB"
    );
    for sp in &report.spread {
        let r = report
            .runs
            .iter()
            .find(|r| r.series() == sp.series && r.n == sp.n)
            .expect("a spread has runs");
        say!(
            "{:<28} {:>9} {:>6} {:>10.3} {:>10.4e} {:>10.4e} {:>10.4e} {:>9.0}",
            sp.series,
            sp.n,
            r.steps,
            sp.wall_s_median,
            r.l1_rho,
            r.l1_p,
            r.l1_v,
            sp.peak_rss_bytes_median as f64 / 1e6
        );
    }
    for o in &report.orders {
        say!(
            "order {:<28} {:<7} {:.3} (sizes {:?})",
            o.series,
            o.field,
            o.order,
            o.sizes
        );
    }
    say!(
        "wrote {}, {}, {}",
        out.join("bench.csv").display(),
        out.join("bench.json").display(),
        out.join("error_vs_time.png").display()
    );
    Ok(())
}

/// `sphexa cases`: one line per case, then its default scheme as the
/// options that would select it.
fn list_cases() {
    say!(
        "{:<14} {:>6} {:>9}  description",
        "case",
        "side",
        "end time"
    );
    for c in cases::registry() {
        say!(
            "{:<14} {:>6} {:>9}  {}",
            c.name(),
            c.default_side(),
            c.default_end_time(),
            c.description()
        );
        say!(
            "{:<14} scheme: {}",
            "",
            scheme_options(&c.default_scheme(), c.physics())
        );
    }
    say!("\nscheme presets (sphexa run CASE --scheme NAME):");
    for (name, scheme, what) in PRESETS {
        say!("{name:<14} {what}");
        say!("{:<14} {}", "", scheme_options(&scheme, Physics::IDEAL_GAS));
    }
}

/// A scheme (and the case's softening and Courant factor) written as the
/// `sphexa run` options that select it.
fn scheme_options(s: &Scheme, physics: Physics) -> String {
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
    if let Some(e) = s.artificial_stress {
        text += &format!(" --artificial-stress {e}");
    }
    if s.fixed_h {
        text += " --smoothing-length fixed";
    }
    if s.volume != Volume::Mass {
        text += &format!(" --volume {}", s.volume.name());
    }
    if s.av_cleaning {
        text += " --av-cleaning on";
    }
    if s.av_form != AvForm::Paper {
        text += &format!(" --av-form {}", s.av_form.name());
    }
    if let Some(soft) = physics.softening {
        text += &format!(" --softening {soft} (self-gravity)");
    }
    if let Some(k) = physics.courant {
        text += &format!(" --courant {k}");
    }
    text
}

/// The `--first-step` value of `f`.
fn first_step_name(f: FirstStep) -> &'static str {
    match f {
        FirstStep::Ramp => "ramp",
        FirstStep::Criteria => "criteria",
    }
}

/// Checks the scheme the run will use (the case's with the command line's
/// overrides) before the solver sees it, in the options' terms.
fn check_scheme(s: &Scheme, a: &RunArgs, case: &str) -> Result<(), AppError> {
    if let Some(sw) = s.switches() {
        if s.alpha() < sw.alpha_min || s.alpha().is_nan() {
            let origin = match (a.alpha, a.av_switches, &a.scheme) {
                (Some(_), Some(_), _) => "--av-switches on",
                (Some(_), None, Some(_)) => "the scheme given by --scheme",
                (Some(_), None, None) => "the scheme of case '{case}'",
                _ => "the scheme",
            }
            .replace("{case}", case);
            return Err(AppError::Usage(format!(
                "--alpha {}: with viscosity switches on ({origin}), --alpha is the largest viscosity and must be at least the switches' floor {}; give --alpha >= {}, or --av-switches off for one constant alpha (any value >= 0)",
                s.alpha(),
                sw.alpha_min,
                sw.alpha_min
            )));
        }
    }
    s.validate()
        .map_err(|e| AppError::Usage(format!("scheme options: {e}")))
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
        artificial_stress: a.artificial_stress,
        fixed_h: a.smoothing_length.map(|s| s == SmoothingArg::Fixed),
        volume: a.volume.map(|v| match v {
            VolumeArg::Mass => Volume::Mass,
            VolumeArg::Ve => Volume::Generalised,
            VolumeArg::PressureEnergy => Volume::PressureEnergy,
        }),
        av_cleaning: a.av_cleaning.map(|s| s == Switch::On),
        av_form: a.av_form.map(|f| match f {
            AvFormArg::Paper => AvForm::Paper,
            AvFormArg::SphExa => AvForm::SphExa,
        }),
        softening: a.softening,
        courant: a.courant,
        first_step: a.first_step.map(|f| match f {
            FirstStepArg::Ramp => FirstStep::Ramp,
            FirstStepArg::Criteria => FirstStep::Criteria,
        }),
    })
}

/// `sphexa run` options alone (to parse a configuration's options).
#[derive(Parser, Debug)]
#[command(name = "sphexa run", no_binary_name = true)]
struct RunOnly {
    #[command(flatten)]
    args: RunArgs,
}

/// Every option of `sphexa run`, with its configuration key (the long
/// option without dashes; `case` for the case).
fn option_keys() -> Vec<OptionKey> {
    RunOnly::command()
        .get_arguments()
        .filter(|a| !matches!(a.get_id().as_str(), "help" | "version"))
        .map(|a| OptionKey {
            key: a
                .get_long()
                .map(str::to_owned)
                .unwrap_or_else(|| a.get_id().to_string()),
            id: a.get_id().to_string(),
            flag: matches!(a.get_action(), ArgAction::SetTrue),
            positional: a.is_positional(),
        })
        .collect()
}

/// Options that exclude each other: a layer's key is dropped when a
/// higher layer sets its partner.
const EXCLUSIVE: &[[&str; 2]] = &[
    ["steps", "end-time"],
    ["grad-h", "no-grad-h"],
    ["restart", "init"],
];

/// The first line of a command-line error, without clap's `error: `.
fn first_line(e: &clap::Error) -> String {
    let msg = e.render().to_string();
    msg.lines()
        .next()
        .unwrap_or("")
        .trim_start_matches("error: ")
        .to_owned()
}

/// Reads a configuration table from TOML `text` of `source`, refusing
/// unknown keys (named, with the allowed keys) and values the option's own
/// parser refuses.
fn config_table(text: &str, source: &str, keys: &[OptionKey]) -> Result<toml::Table, AppError> {
    config::table(text, source, keys, |tokens| {
        RunOnly::try_parse_from(tokens)
            .map(drop)
            .map_err(|e| first_line(&e))
    })
}

/// The run's options: the command line over the configuration file
/// (`--config`) over the checkpoint's configuration (`--restart`).
fn layered(cli: RunArgs, m: &ArgMatches) -> Result<RunArgs, AppError> {
    if cli.config.is_none() && cli.restart.is_none() {
        return Ok(cli);
    }
    let keys = option_keys();
    let mut taken: Vec<String> = keys
        .iter()
        .filter(|k| m.value_source(&k.id) == Some(ValueSource::CommandLine))
        .map(|k| k.key.clone())
        .collect();
    let mut layers: Vec<(String, toml::Table)> = Vec::new();
    if let Some(path) = &cli.config {
        let source = path.display().to_string();
        let text = config::read(path)?;
        layers.push((source.clone(), config_table(&text, &source, &keys)?));
    }
    let restart = cli.restart.clone().or_else(|| {
        layers
            .first()
            .and_then(|(_, t)| t.get("restart"))
            .and_then(|v| v.as_str().map(str::to_owned))
    });
    if let Some(spec) = restart {
        let (path, step) = checkpoint::split_spec(&spec)?;
        let k = checkpoint::group_of_step(&path, step)?;
        let meta = sph_io::SnapshotReader::read_step(
            &sph_io::H5Part,
            &path,
            k,
            &sph_io::Selection::Names(Vec::new()),
        )?;
        let source = format!("{} (the checkpoint's configuration)", path.display());
        if let Some(sph_io::Attr::Str(text)) = meta.attr("config") {
            let mut table = config_table(text, &source, &keys)?;
            for key in ["restart", "init", "config"] {
                table.remove(key);
            }
            layers.push((source, table));
        }
    }
    let mut tokens: Vec<OsString> = Vec::new();
    for (source, table) in &layers {
        let mut mine = Vec::new();
        for (name, value) in table {
            let partner_taken = EXCLUSIVE.iter().any(|pair| {
                pair.contains(&name.as_str()) && pair.iter().any(|p| taken.iter().any(|t| t == p))
            });
            if taken.contains(name) || partner_taken {
                continue;
            }
            let k = keys.iter().find(|k| &k.key == name).expect("checked key");
            tokens.extend(
                config::tokens(k, value, source)?
                    .into_iter()
                    .map(OsString::from),
            );
            mine.push(name.clone());
        }
        taken.extend(mine);
    }
    // The command line's own tokens, after `run`.
    let argv: Vec<OsString> = std::env::args_os().collect();
    if let Some(at) = argv.iter().position(|a| a == "run") {
        tokens.extend(argv[at + 1..].iter().cloned());
    }
    RunOnly::try_parse_from(&tokens)
        .map(|r| r.args)
        .map_err(|e| AppError::Usage(first_line(&e)))
}

/// The fully resolved configuration of a run: every option with the value
/// it ran with (scheme options as the case and the overrides made them), so
/// `sphexa run --config OUT/config.toml` repeats the run.
fn resolved_config(
    a: &RunArgs,
    case: &str,
    side: usize,
    stop: Stop,
    out: &Path,
    config: &HydroConfig,
) -> toml::Table {
    use toml::Value;
    let mut t = toml::Table::new();
    let mut set = |k: &str, v: Value| {
        t.insert(k.to_owned(), v);
    };
    let on = |b: bool| Value::String(if b { "on" } else { "off" }.into());
    set("case", Value::String(case.into()));
    set("side", Value::Integer(side as i64));
    match stop {
        Stop::Steps(n) => set("steps", Value::Integer(n as i64)),
        Stop::Time(te) => set("end-time", Value::Float(te)),
    }
    set("out", Value::String(out.display().to_string()));
    if let Some(n) = a.threads {
        set("threads", Value::Integer(n as i64));
    }
    set("kernel", Value::String(a.kernel.to_string()));
    if a.lattice {
        set("lattice", Value::Boolean(true));
    }
    set("ng0", Value::Integer(a.ng0 as i64));
    set("ngmax", Value::Integer(a.ngmax as i64));
    if let Some(s) = &a.scheme {
        set("scheme", Value::String(s.clone()));
    }
    let s = &config.scheme;
    set(
        "gradients",
        Value::String(match s.gradients {
            Gradients::Iad => "iad".into(),
            Gradients::Kernel => "kernel".into(),
        }),
    );
    set(
        "curve",
        Value::String(match a.curve {
            CurveArg::Hilbert => "hilbert".into(),
            CurveArg::Morton => "morton".into(),
        }),
    );
    set("alpha", Value::Float(s.alpha()));
    set("courant", Value::Float(config.timestep.k_courant));
    set(
        "first-step",
        Value::String(first_step_name(config.timestep.first_step).into()),
    );
    set("grad-h", on(s.grad_h));
    set("av-switches", on(s.switches().is_some()));
    set("conductivity", Value::Float(s.conductivity.unwrap_or(0.0)));
    set(
        "artificial-stress",
        Value::Float(s.artificial_stress.unwrap_or(0.0)),
    );
    set(
        "smoothing-length",
        Value::String(if s.fixed_h { "fixed" } else { "adaptive" }.into()),
    );
    set("volume", Value::String(s.volume.name().into()));
    set("av-cleaning", on(s.av_cleaning));
    set("av-form", Value::String(s.av_form.name().into()));
    set("theta", Value::Float(a.theta));
    if let Some(g) = config.gravity {
        set("softening", Value::Float(g.softening));
    }
    set("write-particles", Value::Boolean(a.write_particles));
    set("quiet", Value::Boolean(a.quiet));
    // The watch's options only when set: plain runs keep their config.toml.
    if a.strict {
        set("strict", Value::Boolean(true));
    }
    if a.rank_timings {
        set("rank-timings", Value::Boolean(true));
    }
    if a.max_energy_drift != 1e-2 {
        set("max-energy-drift", Value::Float(a.max_energy_drift));
    }
    if a.max_momentum_drift != DEFAULT_MOMENTUM_BOUND {
        set("max-momentum-drift", Value::Float(a.max_momentum_drift));
    }
    if let Some(f) = &a.snapshot_fields {
        set("snapshot-fields", Value::String(f.0.join(",")));
    }
    if let Some(n) = a.snapshot_every_steps {
        set("snapshot-every-steps", Value::Integer(n as i64));
    }
    if let Some(x) = a.snapshot_every_time {
        set("snapshot-every-time", Value::Float(x));
    }
    if let Some(at) = &a.snapshot_at {
        set(
            "snapshot-at",
            Value::Array(at.0.iter().map(|&x| Value::Float(x)).collect()),
        );
    }
    if let Some(c) = a.checkpoint_every {
        set("checkpoint-every", Value::String(c.to_string()));
    }
    if let Some(m) = a.mtbf {
        set("mtbf", Value::String(format!("{m}s")));
    }
    set("checkpoint-keep", Value::Integer(a.checkpoint_keep as i64));
    if let Some(r) = &a.restart {
        set("restart", Value::String(r.clone()));
    }
    if let Some(i) = &a.init {
        set("init", Value::String(i.clone()));
    }
    t
}

/// The particles of snapshot `spec` (`FILE[:K]`, ours or SPH-EXA's) as
/// this rank's share of the initial conditions of a run with `fields`;
/// the total and, if the file has one, its box (with `boundary` kinds
/// unless the file records them).
fn init_particles<C: Communicator>(
    comm: &C,
    spec: &str,
    fields: sph_core::FieldSet,
    boundary: [sph_tree::Boundary; 3],
) -> Result<(sph_core::Particles, usize, Option<sph_tree::BoundingBox>), AppError> {
    use sph_io::foreign;
    let (path, k) = checkpoint::split_spec(spec)?;
    let count = foreign::step_count(&path)?;
    let index = match k {
        Some(k) => k as usize,
        None => count.saturating_sub(1),
    };
    let required = ["x", "y", "z", "h", "m", "u"];
    let optional = ["vx", "vy", "vz", "id"];
    let head = foreign::read_foreign_rows(&path, index, &required, &[], 0..0)?;
    let total = head.total;
    let (r, size) = (comm.rank() as u64, comm.size() as u64);
    let rows = total * r / size..total * (r + 1) / size;
    // Our own files: read through the checksummed reader.
    let ours = sph_io::SnapshotReader::read_step(
        &sph_io::H5Part,
        &path,
        index,
        &sph_io::Selection::Names(Vec::new()),
    )
    .is_ok();
    let mut values: Vec<(String, Vec<f64>)> = Vec::new();
    let mut ids: Option<Vec<u64>> = None;
    let mut periodic = None;
    if ours {
        let present: Vec<&str> = required
            .iter()
            .chain(&optional)
            .copied()
            .filter(|n| head.datasets.iter().any(|d| d == n))
            .collect();
        let (snap, _) =
            snapfile::read_share(comm, &path, index, &sph_io::Selection::names(&present))?;
        periodic = Some(snap.bbox.periodic);
        for f in snap.fields {
            match f.data {
                sph_io::FieldData::F64(v) => values.push((f.name, v)),
                sph_io::FieldData::U64(v) if f.name == "id" => ids = Some(v),
                sph_io::FieldData::U64(v) => {
                    values.push((f.name, v.into_iter().map(|x| x as f64).collect()))
                }
            }
        }
        for n in required {
            if !values.iter().any(|(m, _)| m == n) {
                return Err(AppError::Usage(format!(
                    "--init {}: Step#{index} has no field '{n}'; initial conditions need {}",
                    path.display(),
                    required.join(", ")
                )));
            }
        }
    } else {
        let st = foreign::read_foreign_rows(&path, index, &required, &optional, rows.clone())?;
        for (name, v) in st.fields {
            if name == "id" {
                ids = Some(v.iter().map(|&x| x as u64).collect());
            } else {
                values.push((name, v));
            }
        }
    }
    let n = (rows.end - rows.start) as usize;
    let mut p = sph_core::Particles::new(n, fields);
    p.id = ids.unwrap_or_else(|| rows.clone().collect());
    for (name, v) in values {
        // Only the initial state's fields: the rest start from the case.
        if !required.contains(&name.as_str()) && !optional.contains(&name.as_str()) {
            continue;
        }
        if let Some(dst) = sph_core::fields::find(&name).and_then(|f| f.f64_mut(&mut p)) {
            dst.copy_from_slice(&v);
        }
    }
    let bbox = match head.bbox {
        Some(b) => {
            let kinds = match periodic {
                Some(per) => per.map(|q| {
                    if q {
                        sph_tree::Boundary::Periodic
                    } else {
                        sph_tree::Boundary::Open
                    }
                }),
                None => boundary,
            };
            Some(sph_tree::BoundingBox::new(
                [b[0], b[2], b[4]],
                [b[1], b[3], b[5]],
                kinds,
            )?)
        }
        None => None,
    };
    let total = usize::try_from(total)
        .map_err(|_| AppError::Usage(format!("--init {}: {total} particles", path.display())))?;
    Ok((p, total, bbox))
}

/// The snapshot and checkpoint outputs the options ask for; `config` is
/// the resolved configuration (stored in every file), `t0` the start time.
fn outputs(a: &RunArgs, config: String, t0: f64) -> Result<Outputs, AppError> {
    let schedule = Schedule::new(
        a.snapshot_every_steps,
        a.snapshot_every_time,
        a.snapshot_at.clone().map(|t| t.0).unwrap_or_default(),
        t0,
    );
    if a.snapshot_fields.is_some() && !schedule.is_active() {
        return Err(AppError::Usage(
            "--snapshot-fields needs a schedule: --snapshot-every-steps N, --snapshot-every-time T or --snapshot-at T1,T2,...".into(),
        ));
    }
    let snapshots = schedule.is_active().then(|| {
        let fields = a.snapshot_fields.clone().map(|f| f.0).unwrap_or_else(|| {
            snapfile::DEFAULT_FIELDS
                .iter()
                .map(|s| (*s).to_owned())
                .collect()
        });
        (fields, schedule)
    });
    let every = match (a.checkpoint_every, a.mtbf) {
        (None, None) => None,
        (None, Some(_)) => {
            return Err(AppError::Usage("--mtbf is used by --checkpoint-every auto; give both".into()))
        }
        (Some(CheckpointSpec::Auto), None) => {
            return Err(AppError::Usage(
                "--checkpoint-every auto needs --mtbf DURATION (the machine's mean time between failures, e.g. 6h)".into(),
            ))
        }
        (Some(CheckpointSpec::Auto), Some(m)) => Some(CheckpointEvery::Auto { mtbf_s: m }),
        (Some(_), Some(_)) => {
            return Err(AppError::Usage("--mtbf applies only to --checkpoint-every auto".into()))
        }
        (Some(CheckpointSpec::Steps(n)), None) => Some(CheckpointEvery::Steps(n)),
        (Some(CheckpointSpec::Time(t)), None) => Some(CheckpointEvery::Time(t)),
        (Some(CheckpointSpec::Wall(w)), None) => Some(CheckpointEvery::Wall(w)),
    };
    Ok(Outputs {
        snapshots,
        checkpoints: every.map(|e| (e, a.checkpoint_keep)),
        attrs: vec![("config".into(), sph_io::Attr::Str(config))],
    })
}

/// The rank count an MPI launcher announces to the processes it starts
/// (Open MPI; MPICH and others through PMI), if any.
#[cfg(not(feature = "mpi"))]
fn launched_ranks() -> Option<usize> {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"]
        .iter()
        .find_map(|k| std::env::var(k).ok()?.trim().parse().ok())
}

fn run(a: RunArgs) -> Result<(), AppError> {
    let Some(case_name) = a.case.clone() else {
        return Err(AppError::Usage(format!(
            "no case given: name one ({}), or give --config FILE or --restart FILE",
            cases::names().join(", ")
        )));
    };
    let case = cases::lookup(&case_name)?;
    let side = a.side.unwrap_or(case.default_side());
    if a.ng0 < 8 || a.ng0 > a.ngmax {
        return Err(AppError::Usage(format!(
            "--ng0 {} must be at least 8 and at most --ngmax {}",
            a.ng0, a.ngmax
        )));
    }
    // Output options are checked before any folder is made.
    outputs(&a, String::new(), f64::NEG_INFINITY)?;
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
    start_threads(a.threads)?;
    let kernel_choice = a.kernel;
    let kernel: FastKernel = kernel_choice.fast()?;

    let mut config = HydroConfig::default();
    config.curve = match a.curve {
        CurveArg::Hilbert => Curve::Hilbert,
        CurveArg::Morton => Curve::Morton,
    };
    // Kept only by cases with self-gravity.
    config.gravity = Some(sph_gravity::GravityParams {
        theta: a.theta,
        ..Default::default()
    });
    config.neighbors.ng0 = a.ng0;
    config.neighbors.ngmax = a.ngmax;
    let stop = match (a.steps, a.end_time) {
        (Some(s), _) => Stop::Steps(s),
        (None, Some(t)) => Stop::Time(t),
        (None, None) => Stop::Time(case.default_end_time()),
    };
    #[cfg(not(feature = "mpi"))]
    if let Some(n) = launched_ranks().filter(|&n| n > 1) {
        return Err(AppError::Usage(format!(
            "started as one of {n} MPI ranks, but this sphexa was built without MPI: every rank \
             would run the whole problem into the same files; build it with \
             `cargo build --release -p sph-apps --features mpi`, or run it without mpirun"
        )));
    }
    #[cfg(feature = "mpi")]
    let comm = sph_comm::MpiComm::init()?;
    #[cfg(not(feature = "mpi"))]
    let comm = sph_comm::SerialComm::new();
    let (rank, ranks) = (comm.rank(), comm.size());
    let root = rank == 0;
    // The case applies its own scheme with what the command line
    // overrides; each rank builds only its share of the particles.
    let share = cases::Share { rank, ranks };
    let overrides = scheme_overrides(&a)?;
    check_scheme(&overrides.over(case.default_scheme()), &a, case.name())?;
    let layout = if a.lattice {
        cases::Layout::Lattice
    } else {
        cases::Layout::Glass {
            kernel: a.kernel,
            dir: sph_apps::glass::default_cache_dir(),
        }
    };
    let mut scene = case.setup_share(side, config, &overrides, share, &layout)?;
    scene.config.scheme.validate()?;
    // A checkpoint, or a snapshot as initial conditions, replaces the
    // case's particles (each rank reads only its share).
    let loaded = match &a.restart {
        Some(spec) => Some(checkpoint::load(&comm, spec)?),
        None => None,
    };
    if let Some(l) = &loaded {
        if l.case.as_deref().is_some_and(|c| c != case.name()) {
            return Err(AppError::Usage(format!(
                "--restart {}: the checkpoint is of case '{}', not '{}'",
                l.path.display(),
                l.case.as_deref().unwrap_or(""),
                case.name()
            )));
        }
        scene.particles = checkpoint::particles(&l.rows, scene.config.fields(), &l.path)?;
        scene.total = l.total;
        scene.bbox = l.bbox;
    } else if let Some(spec) = &a.init {
        let (p, total, bbox) =
            init_particles(&comm, spec, scene.config.fields(), scene.bbox.boundary())?;
        scene.particles = p;
        scene.total = total;
        if let Some(b) = bbox {
            scene.bbox = b;
        }
    }
    let resolved = resolved_config(&a, case.name(), side, stop, &out, &scene.config);
    let config_text = toml::to_string(&resolved).expect("a TOML table serialises");
    if root {
        let path = out.join("config.toml");
        std::fs::write(&path, &config_text).map_err(|e| AppError::io(&path, e))?;
    }
    let outputs = outputs(
        &a,
        config_text,
        loaded.as_ref().map_or(f64::NEG_INFINITY, |l| l.state.t),
    )?;
    let gravity = scene.config.gravity.is_some();
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
    let sim = match &loaded {
        Some(l) => Simulation::resume(scene, kernel, kernel_choice.to_string(), comm, l.state),
        None => Simulation::with_comm(scene, kernel, kernel_choice.to_string(), comm),
    };
    let result = sim.and_then(|mut sim| {
        sim.set_write_particles(a.write_particles);
        sim.set_rank_timings(a.rank_timings);
        sim.set_after_step(Some(sph_apps::memory::return_free_heap_to_os));
        // Self-gravity's default momentum bound is the tree's accuracy.
        let momentum = if a.max_momentum_drift == DEFAULT_MOMENTUM_BOUND && gravity {
            GRAVITY_MOMENTUM_BOUND
        } else {
            a.max_momentum_drift
        };
        sim.set_watch(Some(Watch::new(
            Bounds {
                energy: a.max_energy_drift,
                momentum,
            },
            a.strict,
        )));
        sim.set_outputs(outputs)?;
        sim.run(stop, &out, progress)
    });
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
    say!(
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
        say!("L1: rho {:.4e}  p {:.4e}  |v| {:.4e}", l1.rho, l1.p, l1.v);
    }
    if let (Some(r), Some(rr)) = (s.shock_radius, s.shock_radius_ref) {
        say!(
            "shock radius {r:.4} (reference {rr:.4}), peak density {:.3}",
            s.peak_density
        );
    }
    say!(
        "energy drift {:.3e}, momentum drift {:.3e}, angular momentum drift {:.3e}",
        s.energy_rel_drift,
        s.momentum_rel_drift,
        s.angular_momentum_rel_drift
    );
    if ranks > 1 {
        let d = s.domain;
        say!(
            "domain: {ranks} ranks, {}..{} particles per rank, halo ratio {:.3} (max {:.3}), {:.3e} bytes sent/step, sync {:.3e} s/step, communication {:.3e} s/step",
            d.owned_min, d.owned_max, d.halo_ratio_mean, d.halo_ratio_max,
            d.bytes_sent_per_step, d.sync_seconds_per_step, d.comm_seconds_per_step
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The resolved configuration of a Sedov run, as `sphexa run` writes
    /// it: every key of the defaults.
    fn resolved() -> String {
        let a = RunOnly::try_parse_from([
            "sedov",
            "--checkpoint-every",
            "3",
            "--snapshot-at",
            "0.1,0.2",
        ])
        .expect("options")
        .args;
        let config = HydroConfig::default();
        let t = resolved_config(&a, "sedov", 8, Stop::Steps(5), Path::new("out"), &config);
        toml::to_string(&t).expect("TOML")
    }

    /// What `--config hostile.toml` holding `text` gives: a table, or an
    /// error that names the file; the table's tokens parse or are refused,
    /// never a panic.
    fn configure(text: &str) -> Result<(), String> {
        let keys = option_keys();
        let table = config_table(text, "hostile.toml", &keys).map_err(|e| e.to_string())?;
        let mut tokens = Vec::new();
        for (name, value) in &table {
            let k = keys.iter().find(|k| &k.key == name).expect("checked key");
            tokens.extend(config::tokens(k, value, "hostile.toml").map_err(|e| e.to_string())?);
        }
        RunOnly::try_parse_from(&tokens)
            .map(drop)
            .map_err(|e| format!("hostile.toml: {}", first_line(&e)))
    }

    #[test]
    fn the_resolved_configuration_reads_back() {
        let text = resolved();
        assert!(
            text.contains("case = \"sedov\"") && text.contains("checkpoint-every"),
            "{text}"
        );
        configure(&text).expect("valid");
        let e = configure("side = 0\n").unwrap_err();
        assert!(
            e.contains("hostile.toml") && e.contains("'side'") && e.contains("4 to 1000"),
            "{e}"
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        /// A changed byte or a cut in a run's configuration, checked by the
        /// driver's own option parsers: an error naming the file, or read.
        #[test]
        fn a_damaged_configuration_is_refused_by_name_or_read(
            pos in any::<prop::sample::Index>(),
            mask in 1u8..=255,
            keep in any::<prop::sample::Index>(),
        ) {
            let text = resolved();
            let mut bytes = text.as_bytes().to_vec();
            let i = pos.index(bytes.len());
            bytes[i] ^= mask;
            // Not UTF-8: config::read refuses it before any parsing.
            if let Ok(flipped) = String::from_utf8(bytes) {
                if let Err(e) = configure(&flipped) {
                    prop_assert!(e.contains("hostile.toml"), "{}", e);
                }
            }
            let n = keep.index(text.len() + 1);
            if let Err(e) = configure(&text[..n]) {
                prop_assert!(e.contains("hostile.toml"), "{}", e);
            }
        }

        /// Random text of TOML's characters and option-like words.
        #[test]
        fn random_configurations_are_refused_by_name_or_read(
            text in "(side|steps|end-time|kernel|alpha|snapshot-at|checkpoint-every|quiet|case|[a-z-]{1,8})( ?= ?)([0-9.e+-]{0,8}|\"[a-z0-9:.,-]{0,10}\"|true|false|\\[[0-9., ]{0,12}\\]|\\{\\})\n{0,2}",
            junk in "[a-z0-9 =\"'\\[\\]{}.,#\n_+:-]{0,128}",
        ) {
            for t in [text.as_str(), junk.as_str()] {
                if let Err(e) = configure(t) {
                    prop_assert!(e.contains("hostile.toml"), "{}", e);
                }
            }
        }
    }
}
