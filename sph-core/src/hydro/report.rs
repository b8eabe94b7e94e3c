//! What a step reports: stage times, extremes, the run state.

use crate::conserved::Conserved;
use crate::timestep::DtLimit;
use sph_comm::{Communicator, ReduceOp};
use sph_tree::NeighborStats;
use std::time::Instant;

/// The timed stages of a step, in pipeline order; one row each in the
/// timings (`STAGES` holds their names).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Domain sync: box, decomposition, migration, halo discovery.
    Sync,
    /// Octree of the local particles.
    Tree,
    /// Neighbour search with the h iteration.
    Neighbors,
    /// Density and grad-h factor.
    Density,
    /// Equation of state.
    Eos,
    /// IAD matrices.
    Iad,
    /// Viscosity switches: velocity divergence and alpha update.
    Switches,
    /// Momentum and energy equations (with the artificial conductivity).
    Momentum,
    /// Turbulence driving: the OU update and the stirring acceleration.
    Stirring,
    /// Self-gravity.
    Gravity,
    /// Halo exchanges of fields between stages (rho, P, c, Omega; IAD;
    /// div v; alpha).
    Halos,
    /// Conserved quantities (one global sum).
    Conserved,
    /// Time-step criteria and next-step bounds (one global minimum).
    Timestep,
    /// Integrator and h update.
    Integrate,
}

/// Names of the timed stages, in pipeline order ([`Stage`]).
pub const STAGES: [&str; 14] = [
    "sync",
    "tree",
    "neighbors",
    "density",
    "eos",
    "iad",
    "switches",
    "momentum",
    "stirring",
    "gravity",
    "halos",
    "conserved",
    "timestep",
    "integrate",
];

/// Wall-clock seconds per stage ([`STAGES`] order), accumulated.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageTimes(pub [f64; STAGES.len()]);

impl StageTimes {
    /// Sum over stages.
    pub fn total(&self) -> f64 {
        self.0.iter().sum()
    }

    /// Seconds of one stage.
    pub fn get(&self, stage: Stage) -> f64 {
        self.0[stage as usize]
    }
}

/// Charges the time since the last lap to a stage.
pub(super) struct StageClock {
    pub(super) times: StageTimes,
    pub(super) last: Instant,
}

impl StageClock {
    pub(super) fn start() -> Self {
        Self {
            times: StageTimes::default(),
            last: Instant::now(),
        }
    }

    pub(super) fn lap(&mut self, stage: Stage) {
        let now = Instant::now();
        self.times.0[stage as usize] += (now - self.last).as_secs_f64();
        self.last = now;
    }
}

/// The extremes of one step over all ranks, from one global minimum
/// (maxima travel as minima of their negatives).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StepExtremes {
    pub(super) min_h_over_vsig: f64,
    pub(super) max_abs_div_v: f64,
    pub(super) nc_min: f64,
    pub(super) nc_max: f64,
    pub(super) owned_min: f64,
    pub(super) owned_max: f64,
    pub(super) halo_ratio_max: f64,
    pub(super) comm_seconds_max: f64,
    pub(super) sync_seconds_max: f64,
    /// Largest |a| (self-gravity runs; 0 otherwise).
    pub(super) acc_max: f64,
    /// Largest `-du/dt / u` (0 where no internal energy falls).
    pub(super) cooling_max: f64,
    /// Largest `|v_n|` component on open axes (box growth).
    pub(super) speed_max: f64,
    /// Largest `|a|` component on open axes (box growth).
    pub(super) acc_component_max: f64,
    /// Largest h after this step's update (next step's halo reach).
    pub(super) h_next_max: f64,
}

impl StepExtremes {
    pub(super) fn all_reduce<C: Communicator>(self, comm: &C) -> Self {
        let mut m = [
            self.min_h_over_vsig,
            -self.max_abs_div_v,
            self.nc_min,
            -self.nc_max,
            self.owned_min,
            -self.owned_max,
            -self.halo_ratio_max,
            -self.comm_seconds_max,
            -self.sync_seconds_max,
            -self.acc_max,
            -self.speed_max,
            -self.acc_component_max,
            -self.h_next_max,
            -self.cooling_max,
        ];
        comm.all_reduce(&mut m, ReduceOp::Min);
        Self {
            min_h_over_vsig: m[0],
            max_abs_div_v: -m[1],
            nc_min: m[2],
            nc_max: -m[3],
            owned_min: m[4],
            owned_max: -m[5],
            halo_ratio_max: -m[6],
            comm_seconds_max: -m[7],
            sync_seconds_max: -m[8],
            acc_max: -m[9],
            speed_max: -m[10],
            acc_component_max: -m[11],
            h_next_max: -m[12],
            cooling_max: -m[13],
        }
    }
}

/// The domain decomposition over all ranks in one step (from the step's
/// two global reductions; a serial run has one rank and no halos).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DomainStepStats {
    /// Fewest particles owned by a rank.
    pub owned_min: usize,
    /// Most particles owned by a rank.
    pub owned_max: usize,
    /// Halo particles summed over ranks.
    pub halos_total: usize,
    /// Largest halos / owned ratio of a rank.
    pub halo_ratio_max: f64,
    /// Bytes sent by all ranks (migration, halos, field exchanges).
    pub bytes_sent: u64,
    /// Longest time a rank spent in the domain's communication calls.
    pub comm_seconds_max: f64,
    /// Longest time a rank spent in `sync` (communication included).
    pub sync_seconds_max: f64,
}

/// The state of a [`Hydro`](super::Hydro) between two steps that is not in the
/// particles: what a checkpoint keeps so that a restart continues to the bit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunState {
    /// Steps done.
    pub step: u64,
    /// Current time.
    pub t: f64,
    /// The last step taken (the integrator's `dt_{n-1}`).
    pub dt_prev: f64,
    /// Largest smoothing length after the last step's update, which the
    /// next sync uses for its halos (none before the first step).
    pub h_next_max: Option<f64>,
    /// Work done on the gas by the stirring from the run's start to `t`
    /// (0 without stirring).
    pub external_work: f64,
    /// Where a block-step run stands on its time line (none for a global
    /// run, or before the first sub-step).
    pub block: Option<BlockRun>,
}

/// A block-step run's place on its time line, as checkpoints keep it:
/// the line (its span and longest step), the current tick and the run's
/// counts so far. A restart from a synchronisation point (every particle
/// active) with it continues the hierarchy to the bit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockRun {
    /// The line's start time.
    pub t_begin: f64,
    /// The line's end time (the run's end).
    pub t_end: f64,
    /// The longest step's bin (`2^bin` ticks).
    pub dt_max_bin: u8,
    /// The longest step any particle may take (every new line's cap).
    pub dt_max: f64,
    /// The start ramp's origin: no step exceeds `(max_growth - 1) (t -
    /// ramp_origin)` (`-inf`: no ramp).
    pub ramp_origin: f64,
    /// The current tick.
    pub ti: u64,
    /// Particle updates so far.
    pub updates: u64,
    /// Domain syncs so far.
    pub syncs: u64,
}

/// What one step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Step number (1 for the first).
    pub step: u64,
    /// Time at the start of the step (the time of `conserved`).
    pub t: f64,
    /// The step taken.
    pub dt: f64,
    /// The criterion that set `dt`.
    pub dt_limit: DtLimit,
    /// Conserved quantities at `t`.
    pub conserved: Conserved,
    /// Work done on the gas by the stirring from the run's start to `t`
    /// (0 without stirring): `conserved.e_tot() - external_work` is what
    /// the scheme conserves.
    pub external_work: f64,
    /// Neighbour statistics of this step over all ranks (`first_over_cap`
    /// is a local index of this rank).
    pub neighbors: NeighborStats,
    /// Seconds per stage in this step.
    pub times: StageTimes,
    /// Energy updates that fell back to first order.
    pub energy_fallbacks: usize,
    /// Decomposition figures over all ranks.
    pub domain: DomainStepStats,
    /// With [`HydroConfig::bin_report`](super::HydroConfig::bin_report):
    /// entry `k` counts the particles (over all ranks) whose own step is
    /// at least `2^k` times `dt` and, below the last entry, less than
    /// `2^(k+1)` times.
    pub bins: Option<[u64; BIN_OFFSETS]>,
    /// Particle updates of the step (all ranks): every particle in a
    /// global run, the active ones in a block-step sub-step.
    pub updates: u64,
    /// Whether every particle was active in the step, so that `conserved`
    /// holds fresh values of all of them (always in a global run; in a
    /// block-step run, the sub-steps starting at a synchronisation point).
    pub all_active: bool,
    /// Whether every particle's step ends where this one ends: the state
    /// after it is a synchronisation point, where block-step runs write
    /// checkpoints (always in a global run).
    pub ends_synchronised: bool,
}

/// The entries of [`StepReport::bins`].
pub const BIN_OFFSETS: usize = 24;
