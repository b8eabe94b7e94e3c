//! One SPH-EXA time step on one node: sort, tree, neighbours, density,
//! EOS, IAD, momentum and energy, time step, integration.

use crate::av_switch::{
    balsara, iad_and_velocity_divergence, update_alpha, velocity_divergence, FlowState,
};
use crate::conduction::Conductivity;
use crate::conserved::Conserved;
use crate::density::{density, pressure_energy_density, ve_density, xmass, Positions, VeOut};
use crate::eos::Eos;
use crate::iad::iad_volumes;
use crate::integrate::{integrate, HUpdate};
use crate::momentum::{
    momentum_energy_with, Alpha, ArtificialStress, AvCleaning, Gradients, HydroState,
    MomentumScheme, MomentumStats, PairFactors, Rates, VolumeWeights,
};
use crate::neighbors::{find_neighbors, NeighborParams};
use crate::scheme::{Scheme, Viscosity, Volume};
use crate::timestep::{DtLimit, TimestepParams};
use crate::{CoreError, FieldSet, Particles};
use rayon::prelude::*;
use sph_comm::{Communicator, ReduceOp, SerialComm};
use sph_domain::{Domain, DomainConfig};
use sph_gravity::{Decomposition, DistributedGravity, GravityField, GravityParams, GravityStats};
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList, Curve, NeighborStats, Octree};
use std::ops::Range;
use std::time::Instant;

/// `Positions` of a `Particles`, borrowing field by field (so other fields
/// stay free for mutable borrows).
macro_rules! positions {
    ($p:expr) => {
        Positions {
            x: &$p.x,
            y: &$p.y,
            z: &$p.z,
            h: &$p.h,
            m: &$p.m,
        }
    };
}

/// `HydroState` of a `Particles`, borrowing field by field.
macro_rules! hydro_state {
    ($p:expr) => {
        HydroState {
            pos: positions!($p),
            vx: &$p.vx,
            vy: &$p.vy,
            vz: &$p.vz,
            rho: &$p.rho,
            p: &$p.p,
            c: &$p.c,
            omega: &$p.omega,
            iad: std::array::from_fn(|k| $p.iad[k].as_slice()),
        }
    };
}

/// Everything a run of the hydrodynamics needs besides the particles and
/// the kernel: the scheme (discretisation), the physics (EOS, gravity)
/// and the numerical controls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HydroConfig {
    /// The discretisation: gradients, grad-h, viscosity, conductivity.
    pub scheme: Scheme,
    /// Equation of state.
    pub eos: Eos,
    /// Neighbour-count targets.
    pub neighbors: NeighborParams,
    /// Smoothing-length update rule.
    pub h_update: HUpdate,
    /// Time-step criteria.
    pub timestep: TimestepParams,
    /// Space-filling curve for sorting.
    pub curve: Curve,
    /// Octree bucket size.
    pub bucket: usize,
    /// Self-gravity (tree multipoles; open boxes only), or none.
    pub gravity: Option<GravityParams>,
}

impl Default for HydroConfig {
    fn default() -> Self {
        Self {
            scheme: Scheme::PAPER,
            eos: Eos::IdealGas { gamma: 5.0 / 3.0 },
            neighbors: NeighborParams::default(),
            h_update: HUpdate::default(),
            timestep: TimestepParams::default(),
            curve: Curve::Hilbert,
            bucket: 16,
            gravity: None,
        }
    }
}

impl HydroConfig {
    /// Checks the scheme, the EOS and the numerical controls.
    ///
    /// # Errors
    /// [`CoreError::Invalid`] naming the bad value and what is allowed.
    pub fn validate(&self) -> Result<(), CoreError> {
        self.scheme.validate()?;
        self.eos.validate()?;
        if self.bucket == 0 {
            return Err(CoreError::Invalid("bucket size must be at least 1".into()));
        }
        Ok(())
    }

    /// The optional per-particle fields a run with this configuration
    /// needs.
    pub fn fields(&self) -> FieldSet {
        FieldSet {
            eos_ref: self.eos.needs_reference(),
            ..self.scheme.fields(self.gravity.is_some())
        }
    }
}

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
pub const STAGES: [&str; 13] = [
    "sync",
    "tree",
    "neighbors",
    "density",
    "eos",
    "iad",
    "switches",
    "momentum",
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
struct StageClock {
    times: StageTimes,
    last: Instant,
}

impl StageClock {
    fn start() -> Self {
        Self {
            times: StageTimes::default(),
            last: Instant::now(),
        }
    }

    fn lap(&mut self, stage: Stage) {
        let now = Instant::now();
        self.times.0[stage as usize] += (now - self.last).as_secs_f64();
        self.last = now;
    }
}

/// The extremes of one step over all ranks, from one global minimum
/// (maxima travel as minima of their negatives).
#[derive(Debug, Clone, Copy, PartialEq)]
struct StepExtremes {
    min_h_over_vsig: f64,
    max_abs_div_v: f64,
    nc_min: f64,
    nc_max: f64,
    owned_min: f64,
    owned_max: f64,
    halo_ratio_max: f64,
    comm_seconds_max: f64,
    sync_seconds_max: f64,
    /// Largest |a| (self-gravity runs; 0 otherwise).
    acc_max: f64,
    /// Largest `-du/dt / u` (0 where no internal energy falls).
    cooling_max: f64,
    /// Largest `|v_n|` component on open axes (box growth).
    speed_max: f64,
    /// Largest `|a|` component on open axes (box growth).
    acc_component_max: f64,
    /// Largest h after this step's update (next step's halo reach).
    h_next_max: f64,
}

impl StepExtremes {
    fn all_reduce<C: Communicator>(self, comm: &C) -> Self {
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

/// The state of a [`Hydro`] between two steps that is not in the
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
    /// Neighbour statistics of this step over all ranks (`first_over_cap`
    /// is a local index of this rank).
    pub neighbors: NeighborStats,
    /// Seconds per stage in this step.
    pub times: StageTimes,
    /// Energy updates that fell back to first order.
    pub energy_fallbacks: usize,
    /// Decomposition figures over all ranks.
    pub domain: DomainStepStats,
}

/// The hydro pipeline of one rank with its reusable buffers. The domain
/// decomposition (`C` the communicator) is the only difference between a
/// serial and a distributed run: every rank runs the same stages on its
/// halos + owned particles.
#[derive(Debug)]
pub struct Hydro<K: Kernel, C: Communicator = SerialComm> {
    kernel: K,
    config: HydroConfig,
    domain: Domain<C>,
    tree: Octree,
    list: CompactNeighborList,
    factors: PairFactors,
    div_v: Vec<f64>,
    /// `|curl v|` (Balsara limiter only).
    curl_v: Vec<f64>,
    /// Viscosity strengths with the Balsara factor (limiter only).
    alpha_eff: Vec<f64>,
    /// Symmetric velocity gradient, six fields (AV cleaning only).
    grad_v: Vec<Vec<f64>>,
    /// Volume elements `X` and their normalisation `k` (generalised
    /// volumes only).
    xm: Vec<f64>,
    kx: Vec<f64>,
    next_h_max: Option<f64>,
    gravity: Option<DistributedGravity>,
    gravity_tree: Octree,
    field: GravityField,
    step: u64,
    t: f64,
    dt_prev: f64,
    dt_cap: f64,
}

impl<K: Kernel> Hydro<K> {
    /// A serial pipeline at time `t0`, whose previous step is taken as `dt0`
    /// (the first step is at most `max_growth * dt0` unless the time step
    /// says otherwise: [`FirstStep`](crate::timestep::FirstStep)). Initial conditions
    /// must have `dx = v dt0` (see [`Hydro::prepare`]).
    pub fn new(kernel: K, config: HydroConfig, t0: f64, dt0: f64) -> Result<Self, CoreError> {
        Self::with_comm(
            kernel,
            config,
            t0,
            dt0,
            SerialComm::new(),
            DomainConfig::default(),
        )
    }
}

impl<K: Kernel, C: Communicator> Hydro<K, C> {
    /// A pipeline on one rank of `comm`; each rank passes the particles it
    /// starts with (any split: the first step migrates them to their owners).
    pub fn with_comm(
        kernel: K,
        config: HydroConfig,
        t0: f64,
        dt0: f64,
        comm: C,
        domain: DomainConfig,
    ) -> Result<Self, CoreError> {
        config.validate()?;
        if !(dt0 > 0.0 && dt0.is_finite()) {
            return Err(CoreError::Invalid(format!(
                "first time step {dt0} must be positive"
            )));
        }
        let domain = Domain::new(
            comm,
            DomainConfig {
                curve: config.curve,
                ..domain
            },
        )?;
        Ok(Self {
            kernel,
            config,
            domain,
            tree: Octree::default(),
            list: CompactNeighborList::new(),
            factors: PairFactors::default(),
            div_v: Vec::new(),
            curl_v: Vec::new(),
            alpha_eff: Vec::new(),
            grad_v: Vec::new(),
            xm: Vec::new(),
            kx: Vec::new(),
            next_h_max: None,
            gravity: config
                .gravity
                .map(DistributedGravity::new)
                .transpose()
                .map_err(CoreError::GravitySetup)?,
            field: GravityField::new(),
            gravity_tree: Octree::default(),
            step: 0,
            t: t0,
            dt_prev: dt0,
            dt_cap: f64::INFINITY,
        })
    }

    /// Sets the integrator history of fresh initial conditions:
    /// `dx = v dt0` (first step of the Press scheme).
    pub fn prepare(&self, p: &mut Particles) {
        let dt0 = self.dt_prev;
        for i in 0..p.len() {
            p.dx[i] = p.vx[i] * dt0;
            p.dy[i] = p.vy[i] * dt0;
            p.dz[i] = p.vz[i] * dt0;
        }
        // Particles built with the configuration's fields hold alpha
        // already; others (FieldSet::default()) get it here.
        if let Some(sw) = self.config.scheme.switches() {
            p.enable_alpha(sw.alpha_min);
        }
    }

    /// The scheme.
    pub fn config(&self) -> &HydroConfig {
        &self.config
    }

    /// The kernel the pair stages evaluate.
    pub fn kernel(&self) -> &K {
        &self.kernel
    }

    /// Current time.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Steps done.
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// The integrator's run state besides the particles (for checkpoints):
    /// see [`RunState`].
    pub fn run_state(&self) -> RunState {
        RunState {
            step: self.step,
            t: self.t,
            dt_prev: self.dt_prev,
            h_next_max: self.next_h_max,
        }
    }

    /// Continues from a checkpoint's [`RunState`] (steps done, time,
    /// previous step, the next sync's largest h). The particles must be
    /// the checkpoint's, with their integrator history (`dx`, `du_prev`,
    /// `alpha`): do not [`prepare`](Self::prepare) them.
    pub fn restore_run_state(&mut self, s: RunState) {
        self.step = s.step;
        self.t = s.t;
        self.dt_prev = s.dt_prev;
        self.next_h_max = s.h_next_max;
        self.dt_cap = f64::INFINITY;
    }

    /// Caps the next step (to land exactly on an output or end time).
    pub fn limit_next_dt(&mut self, dt_max: f64) {
        self.dt_cap = dt_max;
    }

    /// Range of this rank's own particles in the local arrays (the rest are
    /// halos, copies of other ranks' particles).
    pub fn owned(&self) -> Range<usize> {
        self.domain.owned()
    }

    /// The domain decomposition.
    pub fn domain(&self) -> &Domain<C> {
        &self.domain
    }

    /// The neighbour lists of the last step.
    pub fn neighbor_list(&self) -> &CompactNeighborList {
        &self.list
    }

    /// Where the domain releases step buffers
    /// ([`Domain::releases_step_buffers`]: on several ranks), frees the
    /// buffers every step rebuilds from scratch (neighbour lists, octrees,
    /// pair factors, velocity divergence, volume elements) before the
    /// sync, whose halo messages then reuse the memory instead of adding
    /// to the peak. Measured (Sedov 80^3, 30 steps, `std`, 2 ranks x 1
    /// thread): peak RSS per rank 108 MiB with these and the tree freed
    /// after the search, 123 MiB without, the time per step within noise.
    fn release_step_buffers(&mut self) {
        if !self.domain.releases_step_buffers() {
            return;
        }
        self.list = CompactNeighborList::new();
        self.tree = Octree::default();
        self.gravity_tree = Octree::default();
        self.factors = PairFactors::default();
        self.grad_v = Vec::new();
        for v in [
            &mut self.div_v,
            &mut self.curl_v,
            &mut self.alpha_eff,
            &mut self.xm,
            &mut self.kx,
        ] {
            *v = Vec::new();
        }
    }

    /// Frees the octree once the neighbours are found, where nothing
    /// else reads it (no self-gravity) and the buffers are released
    /// ([`release_step_buffers`](Self::release_step_buffers)): the momentum
    /// stage's pair factors then take its place.
    fn release_tree_after_search(&mut self) {
        if self.gravity.is_none() && self.domain.releases_step_buffers() {
            self.tree = Octree::default();
        }
    }

    /// Bytes held by the pipeline's buffers (tree, neighbour lists, keys,
    /// pair factors, per-scheme fields), for memory reports.
    pub fn buffer_bytes(&self) -> usize {
        self.list.bytes()
            + self.factors.bytes()
            + self.domain.keys().len() * 8
            + (self.div_v.capacity()
                + self.curl_v.capacity()
                + self.alpha_eff.capacity()
                + self.grad_v.iter().map(Vec::capacity).sum::<usize>()
                + self.xm.capacity()
                + self.kx.capacity())
                * 8
            + self.tree.num_nodes() * 90
    }

    /// Advances `p` by one step. Open axes of `bbox` are refitted to the
    /// particles first (of all ranks); periodic axes stay.
    ///
    /// # Errors
    /// Particle arrays of different lengths or without the fields the
    /// configuration needs ([`HydroConfig::fields`]), and every numerical
    /// failure, named by particle id and step.
    pub fn step(
        &mut self,
        p: &mut Particles,
        bbox: &mut BoundingBox,
    ) -> Result<StepReport, CoreError> {
        let step = self.step + 1;
        p.check(self.config.fields())?;
        let mut clock = StageClock::start();

        // The per-step buffers are rebuilt below: hand their memory back
        // first, so that the sync's messages reuse it instead of adding to
        // the peak.
        self.release_step_buffers();
        let owned = self.domain.sync_with(p, bbox, self.next_h_max.take())?;
        clock.lap(Stage::Sync);
        self.tree
            .rebuild(self.domain.keys(), &p.x, &p.y, &p.z, self.config.bucket)?;
        clock.lap(Stage::Tree);
        let neighbours = self.search(p, bbox, step, owned.clone())?;
        self.release_tree_after_search();
        clock.lap(Stage::Neighbors);
        self.density(p, bbox)?;
        clock.lap(Stage::Density);
        self.eos(p, owned.clone())?;
        clock.lap(Stage::Eos);
        self.exchange_thermo(p)?;
        clock.lap(Stage::Halos);
        // With IAD gradients the velocity divergence the switches need is
        // summed in the IAD pass (one kernel evaluation per pair).
        let divergence_done =
            self.config.scheme.gradients == Gradients::Iad && self.config.scheme.needs_divergence();
        if self.config.scheme.gradients == Gradients::Iad {
            self.iad(p, bbox, step, divergence_done)?;
            clock.lap(Stage::Iad);
            let [c0, c1, c2, c3, c4, c5] = &mut p.iad;
            self.domain
                .exchange(&mut [c0, c1, c2, c3, c4, c5].map(|c| c.as_mut_slice()))?;
            clock.lap(Stage::Halos);
        }
        self.factors
            .fill_with(&hydro_state!(p), self.config.scheme.volume, &self.kx);
        if self.config.scheme.needs_divergence() {
            self.switches(p, bbox, step, &mut clock, divergence_done)?;
        }
        let forces = self.momentum(p, bbox);
        clock.lap(Stage::Momentum);
        if step == 1 {
            // Adams-Bashforth needs du_{n-1}; the first step uses du_0.
            p.du_prev[owned.clone()].copy_from_slice(&p.du[owned.clone()]);
        }
        let acc_max = self.add_gravity(p, bbox, owned.clone(), step)?;
        clock.lap(Stage::Gravity);

        // One global sum: conserved quantities, neighbour and domain totals.
        let sync = self.domain.stats();
        let (conserved, [nc_total, over_cap, halos_total, bytes_sent]) = Conserved::compute(
            p,
            owned.clone(),
            [
                neighbours.total as f64,
                neighbours.over_cap as f64,
                sync.halos as f64,
                sync.bytes_sent as f64,
            ],
            self.domain.comm(),
        );
        clock.lap(Stage::Conserved);

        // One global minimum: time-step criteria, neighbour and domain
        // extremes, and the next step's bounds: the largest h after this
        // step's update, and how far a particle can move (open axes).
        let h_update = self.config.neighbors.h_update(self.config.h_update);
        let guard = self.config.eos.uses_internal_energy();
        let [speed_max, acc_component_max, h_next_max, cooling_max] =
            self.motion_bounds(p, bbox, owned.clone(), h_update, guard);
        let (nc_min, nc_max) = if owned.is_empty() {
            (f64::INFINITY, f64::NEG_INFINITY)
        } else {
            (neighbours.min_count as f64, neighbours.max_count as f64)
        };
        let ext = StepExtremes {
            min_h_over_vsig: forces.min_h_over_vsig,
            max_abs_div_v: forces.max_abs_div_v,
            nc_min,
            nc_max,
            owned_min: sync.owned as f64,
            owned_max: sync.owned as f64,
            halo_ratio_max: sync.halos as f64 / sync.owned.max(1) as f64,
            comm_seconds_max: sync.comm_seconds,
            sync_seconds_max: sync.sync_seconds,
            acc_max,
            cooling_max,
            speed_max,
            acc_component_max,
            h_next_max,
        }
        .all_reduce(self.domain.comm());
        let global = MomentumStats {
            min_h_over_vsig: ext.min_h_over_vsig,
            max_abs_div_v: ext.max_abs_div_v,
        };
        let ts = self.config.timestep;
        let growth_base = ts.growth_base(step, self.dt_prev);
        let (dt, limit) = ts.dt_limited(&global, ext.acc_max, ext.cooling_max, growth_base);
        let capped = dt.min(self.dt_cap);
        let dt_limit = if capped < dt || dt.is_nan() {
            DtLimit::Cap
        } else {
            limit
        };
        let dt = capped;
        self.dt_cap = f64::INFINITY;
        clock.lap(Stage::Timestep);

        let report = integrate(
            p,
            owned,
            bbox,
            dt,
            self.dt_prev,
            (!self.config.scheme.fixed_h).then_some(h_update),
            guard,
            step,
        )?;
        // The same box on every rank, holding every particle after the
        // move: |dx| <= (max |v_n| + max |a| dt / 2) dt on each axis.
        let reach = (ext.speed_max + 0.5 * ext.acc_component_max * dt) * dt;
        grow_open_axes(bbox, reach)?;
        self.next_h_max = Some(ext.h_next_max);
        clock.lap(Stage::Integrate);

        let t = self.t;
        self.t += dt;
        self.dt_prev = dt;
        self.step = step;
        Ok(StepReport {
            step,
            t,
            dt,
            dt_limit,
            conserved,
            neighbors: NeighborStats {
                min_count: ext.nc_min as usize,
                max_count: ext.nc_max as usize,
                total: nc_total as usize,
                over_cap: over_cap as usize,
                // A local index: only meaningful on this rank.
                first_over_cap: neighbours.first_over_cap,
            },
            times: clock.times,
            energy_fallbacks: report.energy_fallbacks,
            domain: DomainStepStats {
                owned_min: ext.owned_min as usize,
                owned_max: ext.owned_max as usize,
                halos_total: halos_total as usize,
                halo_ratio_max: ext.halo_ratio_max,
                bytes_sent: bytes_sent as u64,
                comm_seconds_max: ext.comm_seconds_max,
                sync_seconds_max: ext.sync_seconds_max,
            },
        })
    }

    /// The IAD matrices of the owned particles, with volumes `m / rho` or
    /// the volume elements `X / k`.
    ///
    /// With `divergence` the velocity divergence (and the curl, for the
    /// Balsara limiter) of the owned particles is computed in the same pass.
    fn iad(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        step: u64,
        divergence: bool,
    ) -> Result<(), CoreError> {
        if divergence {
            self.size_gradient(p.len());
        }
        let pos = positions!(p);
        let volumes = match self.config.scheme.volume {
            Volume::Mass => [&p.m[..], &p.rho[..]],
            Volume::Generalised | Volume::PressureEnergy => [&self.xm[..], &self.kx[..]],
        };
        let result = if divergence {
            let n = p.len();
            self.div_v.resize(n, 0.0);
            if self.config.scheme.balsara {
                self.curl_v.resize(n, 0.0);
            }
            let flow = FlowState {
                pos,
                vx: &p.vx,
                vy: &p.vy,
                vz: &p.vz,
                rho: &p.rho,
                c: &p.c,
                iad: [&[]; 6],
            };
            iad_and_velocity_divergence(
                &self.kernel,
                bbox,
                flow,
                volumes,
                &self.list,
                &mut p.iad,
                &mut self.div_v,
                &mut self.curl_v,
                &mut self.grad_v,
            )
        } else {
            iad_volumes(&self.kernel, bbox, pos, volumes, &self.list, &mut p.iad)
        };
        result.map_err(|s| CoreError::SingularIad {
            step,
            id: p.id[s.index],
            det: s.det,
            neighbors: self.list.count(s.index),
        })
    }

    /// The viscosity switches and the Balsara limiter: velocity divergence
    /// (and curl, for the limiter), exchanged to the halos when the
    /// switches need it, then alpha advanced over the time since its last
    /// update (none before step 1); the strengths the momentum stage reads
    /// (`alpha`, or `alpha_eff` with the limiter) are exchanged too.
    fn switches(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        step: u64,
        clock: &mut StageClock,
        divergence_done: bool,
    ) -> Result<(), CoreError> {
        let scheme = self.config.scheme;
        let n = p.len();
        let g = scheme.gradients;
        if !divergence_done {
            self.size_gradient(n);
        }
        let (kernel, list) = (&self.kernel, &self.list);
        if !divergence_done {
            self.div_v.resize(n, 0.0);
            if scheme.balsara {
                self.curl_v.resize(n, 0.0);
            }
            let flow = FlowState::from(hydro_state!(p));
            velocity_divergence(
                kernel,
                bbox,
                flow,
                g,
                list,
                &mut self.div_v,
                &mut self.curl_v,
                &mut self.grad_v,
            );
            clock.lap(Stage::Switches);
        }
        if let Some(sw) = scheme.switches() {
            self.domain.exchange(&mut [self.div_v.as_mut_slice()])?;
            clock.lap(Stage::Halos);
            let elapsed = if step == 1 { 0.0 } else { self.dt_prev };
            let flow = FlowState::from(hydro_state!(p));
            update_alpha(
                kernel,
                bbox,
                flow,
                g,
                &self.div_v,
                &sw,
                elapsed,
                list,
                &mut p.alpha,
            );
            clock.lap(Stage::Switches);
        }
        if scheme.balsara {
            self.alpha_eff.resize(n, 0.0);
            let constant = scheme.alpha();
            let switched = scheme.switches().is_some();
            for i in list.targets() {
                let base = if switched { p.alpha[i] } else { constant };
                let f = balsara(self.div_v[i], self.curl_v[i], p.c[i], p.h[i]);
                self.alpha_eff[i] = base * f;
            }
            clock.lap(Stage::Switches);
            self.domain.exchange(&mut [self.alpha_eff.as_mut_slice()])?;
        } else if scheme.switches().is_some() {
            self.domain.exchange(&mut [p.alpha.as_mut_slice()])?;
        }
        if scheme.av_cleaning {
            let mut fields: Vec<&mut [f64]> =
                self.grad_v.iter_mut().map(Vec::as_mut_slice).collect();
            self.domain.exchange(&mut fields)?;
        }
        clock.lap(Stage::Halos);
        Ok(())
    }

    /// Sizes the six symmetric-gradient fields to `n` particles when the
    /// scheme cleans the viscosity (none otherwise).
    fn size_gradient(&mut self, n: usize) {
        if self.config.scheme.av_cleaning {
            self.grad_v.resize_with(6, Vec::new);
            for v in &mut self.grad_v {
                v.resize(n, 0.0);
            }
        }
    }

    /// Accelerations and du/dt of the owned particles, with the scheme's
    /// viscosity and volumes.
    fn momentum(&self, p: &mut Particles, bbox: &BoundingBox) -> MomentumStats {
        let state = hydro_state!(p);
        let rates = Rates {
            ax: &mut p.ax,
            ay: &mut p.ay,
            az: &mut p.az,
            du: &mut p.du,
        };
        let s = self.config.scheme;
        let alpha = if s.balsara {
            Alpha::PerParticle(&self.alpha_eff)
        } else {
            match s.viscosity {
                Viscosity::Constant { alpha } => Alpha::Constant(alpha),
                Viscosity::Switched(_) => Alpha::PerParticle(&p.alpha),
            }
        };
        let scheme = MomentumScheme {
            gradients: s.gradients,
            alpha,
            av_form: s.av_form,
            volumes: VolumeWeights::of(s.volume, &self.xm),
            cleaning: s.av_cleaning.then(|| AvCleaning {
                grad_v: std::array::from_fn(|k| self.grad_v[k].as_slice()),
                eta_crit: AvCleaning::eta_crit(self.config.neighbors.ng0),
            }),
            stress: s
                .artificial_stress
                .map(|e| ArtificialStress::new(e, self.config.neighbors.ng0, &self.kernel)),
            conduction: s.conductivity.map(|alpha_u| Conductivity {
                alpha_u,
                p: &p.p,
                u: &p.u,
            }),
        };
        let (k, f, list) = (&self.kernel, &self.factors, &self.list);
        momentum_energy_with(k, bbox, state, f, scheme, list, rates)
    }

    /// Adds self-gravity to the owned particles' accelerations (when the
    /// run has it) and returns their largest |a| (0 without gravity: the
    /// acceleration criterion is off).
    fn add_gravity(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        owned: Range<usize>,
        step: u64,
    ) -> Result<f64, CoreError> {
        if self.gravity.is_none() {
            return Ok(0.0);
        }
        self.gravity_field(p, bbox, owned.clone(), step)?;
        let f = &self.field;
        for (k, i) in owned.clone().enumerate() {
            p.ax[i] += f.ax[k];
            p.ay[i] += f.ay[k];
            p.az[i] += f.az[k];
        }
        Ok(owned
            .map(|i| (p.ax[i] * p.ax[i] + p.ay[i] * p.ay[i] + p.az[i] * p.az[i]).sqrt())
            .fold(0.0, f64::max))
    }
}

impl<K: Kernel, C: Communicator> Hydro<K, C> {
    /// Over the owned particles: `[max_k |v_n,k|, max_k |a_k|, max h_next,
    /// max -du/dt / u]` with `v_n = dX / dt_prev + a dt_prev / 2` (the
    /// Press velocity the integrator will use), `h_next = h * factor(nc)`
    /// (its h update) and the cooling rate over particles with `u > 0` and
    /// falling (0 unless `energy`: the pressure depends on `u`).
    fn motion_bounds(
        &self,
        p: &Particles,
        bbox: &BoundingBox,
        owned: Range<usize>,
        hu: HUpdate,
        energy: bool,
    ) -> [f64; 4] {
        let any_open = (0..3).any(|k| !bbox.is_periodic(k));
        let half = 0.5 * self.dt_prev;
        let inv = 1.0 / self.dt_prev;
        owned
            .into_par_iter()
            .map(|i| {
                let h_next = p.h[i] * hu.factor(p.nc[i]);
                // (Read only with `energy`: the fields may be empty.)
                let cooling = if energy && p.u[i] > 0.0 && p.du[i] < 0.0 {
                    -p.du[i] / p.u[i]
                } else {
                    0.0
                };
                if !any_open {
                    return [0.0, 0.0, h_next, cooling];
                }
                let a = [p.ax[i].abs(), p.ay[i].abs(), p.az[i].abs()];
                let d = [p.dx[i].abs(), p.dy[i].abs(), p.dz[i].abs()];
                let v = (0..3).map(|k| d[k] * inv + a[k] * half).fold(0.0, f64::max);
                [v, a[0].max(a[1]).max(a[2]), h_next, cooling]
            })
            .reduce(|| [0.0; 4], |x, y| std::array::from_fn(|k| x[k].max(y[k])))
    }

    /// Evaluates the self-gravity of all particles on the owned ones (into
    /// the gravity field buffer) and stores their potential in `phi`.
    fn gravity_field(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        owned: Range<usize>,
        step: u64,
    ) -> Result<GravityStats, CoreError> {
        let Some(solver) = self.gravity.as_mut() else {
            return Ok(GravityStats::default());
        };
        if p.phi.len() != p.len() {
            return Err(CoreError::Invalid(
                "self-gravity needs the potential field: build the particles with FieldSet { gravity: true, .. }".into(),
            ));
        }
        // The gravity tree holds the owned particles only (halos are
        // copies); on one rank that is the neighbour tree itself.
        let r = owned.clone();
        let tree = if owned.len() == p.len() {
            &self.tree
        } else {
            self.gravity_tree.rebuild(
                &self.domain.keys()[r.clone()],
                &p.x[r.clone()],
                &p.y[r.clone()],
                &p.z[r.clone()],
                self.config.bucket,
            )?;
            &self.gravity_tree
        };
        let dec = Decomposition {
            bbox,
            curve: self.config.curve,
            key_start: self.domain.key_ranges(),
            h_max: self.domain.h_limit(),
        };
        let stats = solver
            .compute(
                self.domain.comm(),
                dec,
                tree,
                &p.x[r.clone()],
                &p.y[r.clone()],
                &p.z[r.clone()],
                &p.m[r.clone()],
                Some(&p.h[r.clone()]),
                &mut self.field,
            )
            .map_err(|source| CoreError::Gravity { step, source })?;
        p.phi[owned].copy_from_slice(&self.field.phi);
        Ok(stats)
    }

    /// Recomputes neighbours, density, pressure (and the gravitational
    /// potential) at the current positions without advancing (for observables at the end of a run). Afterwards
    /// the local arrays hold halos again: use [`owned`](Self::owned).
    pub fn evaluate_density(
        &mut self,
        p: &mut Particles,
        bbox: &mut BoundingBox,
    ) -> Result<(), CoreError> {
        p.check(self.config.fields())?;
        self.release_step_buffers();
        let owned = self.domain.sync_with(p, bbox, self.next_h_max.take())?;
        self.tree
            .rebuild(self.domain.keys(), &p.x, &p.y, &p.z, self.config.bucket)?;
        self.search(p, bbox, self.step, owned.clone())?;
        self.release_tree_after_search();
        self.density(p, bbox)?;
        self.eos(p, owned.clone())?;
        self.exchange_thermo(p)?;
        if self.gravity.is_some() {
            self.gravity_field(p, bbox, owned, self.step)?;
        }
        Ok(())
    }

    /// Neighbour lists of the owned particles, with the h iteration. Counts
    /// are one-sided (`r < 2 h_i`), so each particle's iteration is its own
    /// business; the lists are symmetric (`r < 2 max(h_i, h_j)`), so once
    /// the halos' final h are known the lists are rebuilt if any changed.
    fn search(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        step: u64,
        owned: Range<usize>,
    ) -> Result<NeighborStats, CoreError> {
        let h_limit = self.domain.h_limit();
        let params = if self.config.scheme.fixed_h {
            self.config.neighbors.without_iteration()
        } else {
            self.config.neighbors
        };
        let run = |p: &mut Particles, list: &mut CompactNeighborList| {
            find_neighbors(
                &params,
                self.config.h_update,
                &self.tree,
                bbox,
                &p.x,
                &p.y,
                &p.z,
                &mut p.h,
                &p.id,
                owned.clone(),
                h_limit,
                list,
                &mut p.nc,
                step,
            )
        };
        let stats = run(p, &mut self.list)?;
        if self.domain.comm().size() == 1 {
            return Ok(stats);
        }
        // Only halos change in the exchange: keep their h alone.
        let halos = |h: &[f64]| {
            let (low, rest) = h.split_at(owned.start);
            low.iter()
                .chain(&rest[owned.len()..])
                .map(|v| v.to_bits())
                .collect::<Vec<u64>>()
        };
        let before = halos(&p.h);
        self.domain.exchange(&mut [p.h.as_mut_slice()])?;
        let changed = before != halos(&p.h);
        // Every rank's lists must see every particle's final h.
        if changed {
            return run(p, &mut self.list);
        }
        Ok(stats)
    }

    /// Density and grad-h factor of the owned particles; with generalised
    /// volumes, `X` (exchanged to the halos), then `k`, the density
    /// `k m / X` and the grad-h factor.
    fn density(&mut self, p: &mut Particles, bbox: &BoundingBox) -> Result<(), CoreError> {
        let pos = positions!(p);
        if self.config.scheme.volume == Volume::Mass {
            density(
                &self.kernel,
                bbox,
                pos,
                &self.list,
                &mut p.rho,
                &mut p.omega,
            );
            return Ok(());
        }
        let n = p.len();
        self.xm.resize(n, 0.0);
        self.kx.resize(n, 0.0);
        if self.config.scheme.volume == Volume::PressureEnergy {
            // X = m u, halos included (their u came with them).
            for ((x, m), u) in self.xm.iter_mut().zip(&p.m).zip(&p.u) {
                *x = m * u;
            }
            if let Some(i) = self.xm.iter().position(|&x| !(x > 0.0 && x.is_finite())) {
                return Err(CoreError::Invalid(format!(
                    "pressure-energy volumes need m u > 0: particle {} has m = {}, u = {} (use --volume mass or ve for cold gas)",
                    p.id[i], p.m[i], p.u[i]
                )));
            }
        } else {
            xmass(&self.kernel, bbox, pos, &self.list, &mut self.xm);
            self.domain.exchange(&mut [self.xm.as_mut_slice()])?;
        }
        let out = VeOut {
            kx: &mut self.kx,
            rho: &mut p.rho,
            omega: &mut p.omega,
        };
        if self.config.scheme.volume == Volume::PressureEnergy {
            pressure_energy_density(&self.kernel, bbox, positions!(p), &self.xm, &self.list, out);
        } else {
            ve_density(&self.kernel, bbox, positions!(p), &self.xm, &self.list, out);
        }
        Ok(())
    }

    /// Sends the owners' density, pressure, sound speed (and Omega) to the
    /// halos.
    fn exchange_thermo(&mut self, p: &mut Particles) -> Result<(), CoreError> {
        let mut fields: Vec<&mut [f64]> = vec![&mut p.rho, &mut p.p, &mut p.c];
        if !p.omega.is_empty() {
            fields.push(&mut p.omega);
        }
        if self.config.scheme.volume != Volume::Mass {
            fields.push(&mut self.kx);
        }
        self.domain.exchange(&mut fields)?;
        Ok(())
    }

    /// Pressure and sound speed of the owned particles; an EOS with a
    /// per-particle reference state calibrates reference densities left at
    /// zero to the current density.
    fn eos(&self, p: &mut Particles, owned: Range<usize>) -> Result<(), CoreError> {
        let r = owned;
        let reference = if self.config.eos.needs_reference() {
            // The field table's check at the start of `step` and
            // `evaluate_density` (HydroConfig::fields holds eos_ref) made
            // sure the reference state is there.
            for i in r.clone() {
                if p.eos_ref[0][i] == 0.0 {
                    p.eos_ref[0][i] = p.rho[i];
                }
            }
            Some((&p.eos_ref[0][r.clone()], &p.eos_ref[1][r.clone()]))
        } else {
            None
        };
        self.config.eos.apply(
            &p.rho[r.clone()],
            &p.u[r.clone()],
            reference,
            &mut p.p[r.clone()],
            &mut p.c[r],
        );
        Ok(())
    }
}

/// Widens the open axes of `bbox` by `reach` on both sides (with a margin
/// for rounding), so that particles moving at most `reach` stay inside.
fn grow_open_axes(bbox: &mut BoundingBox, reach: f64) -> Result<(), CoreError> {
    let b = bbox.boundary();
    if (0..3).all(|k| bbox.is_periodic(k)) {
        return Ok(());
    }
    let (mut lo, mut hi) = (bbox.lo(), bbox.hi());
    for k in 0..3 {
        if !bbox.is_periodic(k) {
            let pad = reach * (1.0 + 1e-9) + 1e-12 * (hi[k] - lo[k] + lo[k].abs() + hi[k].abs());
            lo[k] -= pad;
            hi[k] += pad;
        }
    }
    *bbox = BoundingBox::new(lo, hi, b)?;
    Ok(())
}
