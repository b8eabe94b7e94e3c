//! The options of `sphexa run` (each documented as its `--help` line) and
//! the value types of its options that are not `sph-core`'s (those take
//! their values from [`sph_core::Choice`]).

use super::scheme_args::{SchemeArgs, HEADING};
use crate::cases::scene::SceneGravity;
use crate::cli::parse::{
    case_names, choice, parse_checkpoint_every, parse_count, parse_courant, parse_duration,
    parse_eos, parse_field_list, parse_keep, parse_kernel, parse_limiter_factor,
    parse_non_negative, parse_on_off, parse_positive, parse_side, parse_steps, parse_stir,
    parse_threads, parse_times, snapshot_fields_help, CheckpointSpec, FieldList, StirArg, Times,
};
use crate::cli::parse::{parse_boundary, parse_box, parse_gravity, BoundaryArg, BoxArg};
use clap::{Args, Parser, ValueEnum};
use sph_core::timestep::{FirstStep, TimeSteps};
use sph_core::Eos;
use sph_kernels::KernelChoice;
use std::path::PathBuf;

/// `--curve`: the space-filling curve.
#[derive(ValueEnum, Clone, Copy, Debug)]
pub(crate) enum CurveArg {
    /// Hilbert curve.
    Hilbert,
    /// Morton (Z-order) curve.
    Morton,
}

/// `--snapshot-format`: the layout of the snapshots.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq)]
pub(crate) enum FormatArg {
    /// Ours: H5Part (the --snapshot-fields asked for, with checksums)
    H5part,
    /// SWIFT's snapshot layout (PartType0: coordinates in [0, BoxSize), velocities, masses, SWIFT's smoothing lengths, internal energies, ids, densities, pressures), which SWIFT, swiftsimio and `sphexa run --init` read
    Swift,
}

/// The default of --max-momentum-drift.
pub(crate) const DEFAULT_MOMENTUM_BOUND: f64 = 1e-10;

/// The options of `sphexa run`; their long names are also the keys of
/// `--config` files and of the resolved `config.toml`.
#[derive(Args, Debug)]
pub(crate) struct RunArgs {
    /// Test case (`sphexa cases` lists each with its defaults). Required
    /// unless --config or --restart names it, or --init FILE gives a scene
    /// of your own.
    #[arg(value_parser = case_names())]
    pub(crate) case: Option<String>,
    /// Particles per side of the initial lattice, 4 to 1000 (default: the
    /// case's, see `sphexa cases`).
    #[arg(short = 'n', long = "side", value_name = "N", allow_negative_numbers = true,
          value_parser = parse_side)]
    pub(crate) side: Option<usize>,
    /// Number of steps to run, at least 1 (default: run to the end time).
    #[arg(long, conflicts_with = "end_time", allow_negative_numbers = true,
          value_parser = parse_steps)]
    pub(crate) steps: Option<u64>,
    /// Simulated time to reach, a positive number (default: the case's, see
    /// `sphexa cases`).
    #[arg(long = "end-time", value_name = "T", allow_negative_numbers = true,
          value_parser = parse_positive)]
    pub(crate) end_time: Option<f64>,
    /// Output folder, created if needed (default: out/CASE).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// Worker threads per rank, at least 1 (default: all cores).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_threads)]
    pub(crate) threads: Option<usize>,
    /// Kernel: `sinc` (= sinc:6), `sinc:N` (1 <= N <= 1000), `m4`, `wendland-c2`,
    /// `wendland-c4`, `wendland-c6`.
    #[arg(long, default_value = "sinc:6", value_parser = parse_kernel)]
    pub(crate) kernel: KernelChoice,
    /// Cubic lattices even where the case starts from glass (sod,
    /// wind-shock). Glass
    /// blocks are relaxed with the run's kernel and neighbour counts on
    /// first use and cached in $SPHEXA_GLASS_DIR, else
    /// $XDG_CACHE_HOME/sphexa/glass, else ~/.cache/sphexa/glass (see
    /// `sphexa glass`).
    #[arg(long)]
    pub(crate) lattice: bool,
    /// Target neighbour count, self included: 8 to --ngmax.
    #[arg(long, default_value_t = 100, allow_negative_numbers = true,
          value_parser = parse_count)]
    pub(crate) ng0: usize,
    /// Largest accepted neighbour count before h is iterated: --ng0 or more.
    #[arg(long, default_value_t = 150, allow_negative_numbers = true,
          value_parser = parse_count)]
    pub(crate) ngmax: usize,
    /// Scheme preset to start from instead of the case's own: `gas` (the
    /// ideal-gas cases' default: `best` with AV cleaning, switches from
    /// alpha 0.3 at strong shocks to 2 at weak ones, conductivity 2
    /// weighted by each pair's larger contrast of u or pressure), `paper`
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
    #[arg(long, value_name = "NAME", help_heading = HEADING)]
    pub(crate) scheme: Option<String>,
    /// The scheme options, each over the case's scheme or the preset
    /// (their flags come from `sph_apps::cases::SCHEME_OPTIONS`).
    #[command(flatten)]
    pub(crate) scheme_options: SchemeArgs,
    /// Space-filling curve for sorting particles.
    #[arg(long, value_enum, default_value = "hilbert")]
    pub(crate) curve: CurveArg,
    /// Courant factor, in (0, 1] (default: the case's, see `sphexa cases`:
    /// 0.2, evrard 0.3).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_courant)]
    pub(crate) courant: Option<f64>,
    /// The first time step (default: ramp). `criteria` skips the ramp
    /// from the case's first dt: Sedov (dt0 = 1e-6, as SPH-EXA) then
    /// starts at the Courant step of its hot centre, with about 60 steps
    /// fewer to t = 0.05.
    #[arg(long, value_parser = choice::<FirstStep>())]
    pub(crate) first_step: Option<FirstStep>,
    /// How particles share time steps (default: the case's, `block`;
    /// `global` where the run stirs (its particles all need about the
    /// same step), for a restart of a global run's checkpoint, and for a
    /// scene of your own stopped by `--steps` alone). `block` gives each particle its own power-of-two fraction
    /// of a longest step (`--dt-max`), with a limiter: a blast's cold gas
    /// then takes a few long steps while the shock takes many short ones;
    /// `--steps N` counts its sub-steps and the run stops at the end time
    /// at the latest. `global`: one step for all, the seed paper's and
    /// SPH-EXA's integrator. `kdk`: the block integrator with every
    /// particle in the smallest bin. `block` covers every scheme and
    /// equation of state, with or without self-gravity or driving;
    /// snapshots asked for at a time hold the state at that time,
    /// checkpoints wait for a synchronisation point
    /// (`docs/block-timesteps.md`).
    #[arg(long, value_parser = choice::<TimeSteps>())]
    pub(crate) time_steps: Option<TimeSteps>,
    /// Block time steps: the longest step a particle may take (default:
    /// a quarter of the run's span to its end time).
    #[arg(long, value_name = "DT", value_parser = parse_positive)]
    pub(crate) dt_max: Option<f64>,
    /// Block time steps: the limiter (Saitoh & Makino 2009; default on).
    /// `off` lets a particle's step run far above its neighbours' and
    /// leaves it asleep when a shock reaches it: for tests only.
    #[arg(long, value_name = "on|off", value_parser = parse_on_off)]
    pub(crate) limiter: Option<bool>,
    /// Block time steps: how many times longer than its neighbours'
    /// steps a particle's step may be, a power of two (default 4).
    #[arg(long, value_name = "F", value_parser = parse_limiter_factor)]
    pub(crate) limiter_factor: Option<u8>,
    /// Leave out the grad-h correction (Omega = 1): `--grad-h off`.
    #[arg(long, conflicts_with = "grad_h", help_heading = HEADING)]
    pub(crate) no_grad_h: bool,
    /// Equation of state over the case's: `ideal:GAMMA` (GAMMA > 1),
    /// `isothermal:C0`, `polytropic:K:GAMMA`, `tait:RHO0:C0:P0` (default:
    /// the case's, see `sphexa cases`). With `isothermal` and `polytropic`
    /// pressure does not read u (u is still integrated; pressure-energy
    /// volumes and conductivity are refused with them).
    #[arg(long, value_name = "SPEC", value_parser = parse_eos)]
    pub(crate) eos: Option<Eos>,
    /// Turbulence driving (Federrath et al. 2010, as SPH-EXA) over the
    /// case's (default: `turbulence` stirs, other cases do not): `off`,
    /// `on` (SPH-EXA's defaults), or `KEY=VALUE,...` over the defaults:
    /// `velocity=0.3` (target rms Mach at c = 1), `energy-prefactor=0.005`
    /// (injected energy prefactor * velocity^3 / L), `sol-weight=0.5`
    /// (1 solenoidal, 0 compressive), `seed=251299`,
    /// `correlation-time=auto` (L / (2 velocity)). Needs a periodic cube.
    #[arg(long, value_name = "SPEC", value_parser = parse_stir)]
    pub(crate) stir: Option<StirArg>,
    /// Self-gravity: opening angle theta of the tree, a positive number
    /// (cases with gravity only).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true,
          value_parser = parse_positive)]
    pub(crate) theta: f64,
    /// Self-gravity: pairs are softened within SOFTENING * (h_i + h_j), a
    /// number >= 0 (1 = SPH-EXA's choice; default: the case's, see
    /// `sphexa cases`; cases with gravity only).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_non_negative)]
    pub(crate) softening: Option<f64>,
    /// Also write the final state of every particle (particles.csv, sorted
    /// by id, exact decimal round-trip of every value).
    #[arg(long)]
    pub(crate) write_particles: bool,
    /// Every rank but 0 also writes its own stage timings
    /// (timings.rankR.csv, the columns of timings.csv, which is rank 0's):
    /// where a multi-rank run waits. A pair stage slower on one rank is
    /// imbalance; the others' `halos` and `conserved` columns hold their
    /// wait for it.
    #[arg(long)]
    pub(crate) rank_timings: bool,
    /// Measure the time bins block (individual) time steps would give the
    /// particles: every step computes each particle's own step from its
    /// criteria; summary.json gets `bins` (particle-steps by how many
    /// doublings of the global step each could take, and the updates a
    /// block-step run would need at best). The run itself does not change.
    #[arg(long)]
    pub(crate) report_bins: bool,
    /// No progress output.
    #[arg(short, long)]
    pub(crate) quiet: bool,
    /// Stop with an error at the first conserved quantity past its bound
    /// (--max-energy-drift, --max-momentum-drift, total mass exact, every
    /// particle mass > 0), naming the quantity, the step and the particle
    /// to blame. Without it the run warns once per quantity and records
    /// the step in summary.json.
    #[arg(long)]
    pub(crate) strict: bool,
    /// Bound of the relative total-energy drift |E - E0| / |E0| checked
    /// after every step, a number >= 0.
    #[arg(long, value_name = "X", default_value_t = 1e-2, allow_negative_numbers = true,
          value_parser = parse_non_negative)]
    pub(crate) max_energy_drift: f64,
    /// Bound of the momentum drift |p - p0| relative to the momentum scale
    /// (the largest sqrt(2 M (E_kin + |E_int|)) so far: M times the rms of
    /// speed and thermal speed), a number >= 0. Left at its default 1e-10,
    /// runs with self-gravity or block time steps use 1e-4 (the tree's
    /// forces conserve momentum only to its accuracy; under block steps a
    /// pair's two forces act over different steps).
    #[arg(long, value_name = "X", default_value_t = DEFAULT_MOMENTUM_BOUND, allow_negative_numbers = true,
          value_parser = parse_non_negative)]
    pub(crate) max_momentum_drift: f64,
    /// Fields of the snapshots, comma-separated (default:
    /// x,y,z,vx,vy,vz,h,m,u,rho,p,id). Snapshots are written when a
    /// --snapshot-every-steps, --snapshot-every-time or --snapshot-at
    /// schedule is given, as OUT/snapshots/snapshot_SSSSSSSS.h5 (HDF5,
    /// H5Part layout: h5py, ParaView and SPH-EXA's scripts read them).
    /// Fields: see the full help (--help).
    #[arg(long, value_name = "LIST", value_parser = parse_field_list,
          long_help = snapshot_fields_help())]
    pub(crate) snapshot_fields: Option<FieldList>,
    /// The layout of the snapshots (checkpoints are always ours). `swift`
    /// writes OUT/snapshots/snapshot_SSSSSSSS.hdf5 with SWIFT's names and
    /// h convention for the run's kernel; rank 0 writes the file.
    #[arg(long, value_enum, default_value = "h5part")]
    pub(crate) snapshot_format: FormatArg,
    /// Write a snapshot after every N-th step (N >= 1).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_steps)]
    pub(crate) snapshot_every_steps: Option<u64>,
    /// Write a snapshot after the first step reaching each multiple of T
    /// (simulated time, positive). Steps are never shortened for outputs.
    #[arg(long, value_name = "T", allow_negative_numbers = true, value_parser = parse_positive)]
    pub(crate) snapshot_every_time: Option<f64>,
    /// Write a snapshot after the first step reaching each of these times
    /// (comma-separated, each >= 0).
    #[arg(long, value_name = "T1,T2,...", allow_negative_numbers = true, value_parser = parse_times)]
    pub(crate) snapshot_at: Option<Times>,
    /// Write the velocity power spectrum and the PDF of ln rho (as
    /// `sphexa spectrum`) into spectra/ after the first step reaching each
    /// multiple of T (simulated time, positive; periodic cubes only).
    #[arg(long, value_name = "T", allow_negative_numbers = true, value_parser = parse_positive)]
    pub(crate) spectra_every_time: Option<f64>,
    /// Write checkpoints (every field a restart needs, full precision) as
    /// OUT/checkpoints/checkpoint_SSSSSSSS.h5: `N` after every N-th step;
    /// `time:T` after the first step reaching each multiple of simulated
    /// time T; `wall:DURATION` every DURATION of wall-clock time (`90s`,
    /// `10m`, `2h`, `1d`; a plain number is seconds); `auto` every
    /// sqrt(2 C M) of wall-clock time (Young/Daly), with C the measured time
    /// of the last checkpoint (the first is written after step 1) and M
    /// from --mtbf.
    #[arg(long, value_name = "SPEC", value_parser = parse_checkpoint_every)]
    pub(crate) checkpoint_every: Option<CheckpointSpec>,
    /// Mean time between failures of the machine, for `--checkpoint-every
    /// auto`: a DURATION (`6h`, `30m`, `2d`, or seconds).
    #[arg(long, value_name = "DURATION", value_parser = parse_duration)]
    pub(crate) mtbf: Option<f64>,
    /// Checkpoints of this run to keep: older ones are deleted once a newer
    /// one is complete (0 keeps all).
    #[arg(long, value_name = "K", default_value_t = 2, allow_negative_numbers = true,
          value_parser = parse_keep)]
    pub(crate) checkpoint_keep: usize,
    /// Continue the run of checkpoint FILE (its step STEP, default the
    /// last step group): the checkpoint's configuration applies, options
    /// given here override it (a changed physics option makes the
    /// continuation differ from the run that wrote it). --steps and
    /// --end-time count from the run's start, not from the checkpoint.
    /// conserved.csv in --out keeps its lines up to the checkpoint;
    /// timings.csv and summary.json cover the continued part.
    #[arg(long, value_name = "FILE[:STEP]", conflicts_with = "init")]
    pub(crate) restart: Option<String>,
    /// Start from the particles of snapshot FILE (Step#K, default the
    /// last): ours, or an H5Part file of SPH-EXA (group Step#K with 1-D
    /// datasets x, y, z, h, m, u and optionally vx, vy, vz, id, any float
    /// or integer type; the box from attribute `box` if present), or a
    /// SWIFT/GADGET file (IC or snapshot: Header/BoxSize, PartType0 gas
    /// only; its box [0, BoxSize) is centred on the case's, its smoothing
    /// lengths converted from SWIFT's convention for its kernel, cubic
    /// spline if unnamed; values in the file's units). Time starts at 0.
    /// With a case, the case supplies the physics, the scheme and the
    /// reference. Without one, the file is a scene of your own: the
    /// physics comes from --boundary, --box, --eos, --gravity and
    /// --softening or else from the file's attributes (`periodic` or
    /// `boundaryType`, `box`, `gamma`, `gravConstant`), and --end-time or
    /// --steps is needed; what matters and is not said is an error that
    /// names the option (the scheme: `gas`).
    #[arg(long, value_name = "FILE[:K]")]
    pub(crate) init: Option<String>,
    /// A scene's boundaries (--init FILE without a case): `periodic`,
    /// `open`, or one per axis, e.g. `periodic,periodic,open` (default:
    /// the file's `periodic` or `boundaryType` attribute).
    #[arg(long, value_name = "KINDS", value_parser = parse_boundary)]
    pub(crate) boundary: Option<BoundaryArg>,
    /// A scene's box (--init FILE without a case): `LO:HI` on every axis or
    /// `X0:X1,Y0:Y1,Z0:Z1` (default: the file's `box` attribute; needed for
    /// periodic axes, open axes follow the particles).
    #[arg(long = "box", value_name = "LO:HI", allow_hyphen_values = true, value_parser = parse_box)]
    pub(crate) cube: Option<BoxArg>,
    /// A scene's self-gravity (--init FILE without a case): `on` (open
    /// boundaries only; G from the file's `gravConstant`, else 1), the
    /// constant G itself (a positive number, on), or `off` (default: the
    /// file's `gravConstant`, non-zero for on; a periodic box has none; an
    /// open box must say).
    #[arg(long, value_name = "on|off|G", allow_hyphen_values = true, value_parser = parse_gravity)]
    pub(crate) gravity: Option<SceneGravity>,
    /// Read options from a TOML file: one key per option, named as the
    /// option without its dashes (`side = 20`, `end-time = 0.05`,
    /// `av-switches = "on"`, `snapshot-at = [0.01, 0.02]`, `case =
    /// "sedov"`); options on the command line override it. Every run writes
    /// its resolved configuration as OUT/config.toml, which repeats it.
    #[arg(long, value_name = "FILE")]
    pub(crate) config: Option<PathBuf>,
}

/// `sphexa run` options alone (to parse a configuration's options).
#[derive(Parser, Debug)]
#[command(name = "sphexa run", no_binary_name = true)]
pub(crate) struct RunOnly {
    #[command(flatten)]
    pub(crate) args: RunArgs,
}
