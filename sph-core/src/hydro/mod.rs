//! One SPH-EXA time step on one node: sort, tree, neighbours, density,
//! EOS, IAD, momentum and energy, time step, integration.
//!
//! The pipeline is here ([`Hydro::step`]); its configuration in `config.rs`,
//! the stage reports in `report.rs`, the reusable buffers in `buffers.rs`
//! and the stages themselves in `stages.rs`.

use crate::conserved::Conserved;
use crate::density::Positions;
use crate::integrate::{close_steps, integrate};
use crate::momentum::{Gradients, HydroState, MomentumStats};
use crate::stirring::Stirring;
use crate::timestep::DtLimit;
use crate::{CoreError, Particles};
use sph_comm::{Communicator, SerialComm};
use sph_domain::{Domain, DomainConfig};
use sph_gravity::{DistributedGravity, GravityField, Targets};
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList, NeighborStats, Octree};
use std::ops::Range;

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

mod block;
mod block_conduction;
mod buffers;
mod config;
mod predict;
mod report;
mod stages;
mod stir;

use block::BlockState;
use block_conduction::ImpulseBuffers;
use buffers::StepBuffers;
pub use config::HydroConfig;
pub use predict::{predict_field, PREDICTED};
pub use report::{
    BlockRun, DomainStepStats, RunState, Stage, StageTimes, StepReport, BIN_OFFSETS, STAGES,
};
use report::{StageClock, StepExtremes};

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
    /// The stages' work arrays.
    buf: StepBuffers,
    next_h_max: Option<f64>,
    gravity: Option<DistributedGravity>,
    gravity_tree: Octree,
    field: GravityField,
    /// The turbulence driving's state (built at the first step, from the
    /// box), when the configuration stirs.
    stirring: Option<Stirring>,
    /// Work done by the stirring up to `t`.
    external_work: f64,
    step: u64,
    t: f64,
    dt_prev: f64,
    dt_cap: f64,
    /// Block time steps: the time line, the current tick and work arrays.
    block: BlockState,
    /// The conduction's impulses under block steps.
    impulses: ImpulseBuffers,
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
            buf: StepBuffers::default(),
            next_h_max: None,
            gravity: config
                .gravity
                .map(DistributedGravity::new)
                .transpose()
                .map_err(CoreError::GravitySetup)?,
            field: GravityField::new(),
            gravity_tree: Octree::default(),
            stirring: None,
            external_work: 0.0,
            step: 0,
            t: t0,
            dt_prev: dt0,
            dt_cap: f64::INFINITY,
            block: BlockState::default(),
            impulses: ImpulseBuffers::default(),
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
        if self.config.time_steps.on_time_line() && !p.fields().block {
            p.enable_block_steps(self.config.fields());
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
            external_work: self.external_work,
            block: self.block_run(),
        }
    }

    /// Continues from a checkpoint's [`RunState`] (steps done, time,
    /// previous step, the next sync's largest h, a block-step run's time
    /// line). The particles must be the checkpoint's, with their
    /// integrator history (`dx`, `du_prev`, `alpha`, and under block steps
    /// the held fields): do not [`prepare`](Self::prepare) them.
    ///
    /// # Errors
    /// A block-step state for a global configuration or the reverse, or a
    /// time line that is not one (named).
    pub fn restore_run_state(&mut self, s: RunState) -> Result<(), CoreError> {
        let block = self.config.time_steps.on_time_line();
        match (block, s.block) {
            (true, Some(b)) => self.restore_block_run(b)?,
            (false, None) => {}
            (true, None) => {
                return Err(CoreError::Invalid(format!(
                    "--time-steps {}: the checkpoint (step {}) holds no block-step time line; continue it with --time-steps global",
                    crate::Choice::name(&self.config.time_steps),
                    s.step
                )))
            }
            (false, Some(_)) => {
                return Err(CoreError::Invalid(format!(
                    "--time-steps global: the checkpoint (step {}) is of a block-step run; continue it with the time steps it was written with",
                    s.step
                )))
            }
        }
        self.step = s.step;
        self.t = s.t;
        self.dt_prev = s.dt_prev;
        self.next_h_max = s.h_next_max;
        self.external_work = s.external_work;
        self.dt_cap = f64::INFINITY;
        Ok(())
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
        if self.config.time_steps.on_time_line() {
            return self.substep(p, bbox);
        }
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
        let neighbours = self.search(p, bbox, step, owned.clone(), None)?;
        self.release_tree_after_search();
        clock.lap(Stage::Neighbors);
        self.density(p, bbox)?;
        clock.lap(Stage::Density);
        let forces = self.thermo_and_forces(p, bbox, owned.clone(), step, &mut clock)?;
        if step == 1 {
            // Adams-Bashforth needs du_{n-1}; the first step uses du_0.
            p.du_prev[owned.clone()].copy_from_slice(&p.du[owned.clone()]);
        }
        self.stir(p, bbox, owned.clone())?;
        clock.lap(Stage::Stirring);
        self.add_gravity(p, bbox, owned.clone(), Targets::ALL, step)?;
        // The largest |a| / eps (0 without gravity: the acceleration
        // criterion is off, and no pass over the particles).
        let criterion = self.acc_criterion();
        let acc_max = match self.gravity {
            Some(_) => owned
                .clone()
                .map(|i| criterion.at(p, i))
                .fold(0.0, f64::max),
            None => 0.0,
        };
        clock.lap(Stage::Gravity);
        // The sums below over the velocities at this time (the kick
        // recomputes the same ones from the history); the first step's
        // are the initial conditions'.
        let dt_prev = self.dt_prev;
        close_steps(p, owned.clone(), |_| (step > 1).then_some(dt_prev));

        // One global sum: conserved quantities, neighbour and domain totals,
        // and the stirring's work terms.
        let sync = self.domain.stats();
        let (conserved, [nc_total, over_cap, halos_total, bytes_sent, updates], work_terms) =
            Conserved::compute_with(
                p,
                owned.clone(),
                [
                    neighbours.total as f64,
                    neighbours.over_cap as f64,
                    sync.halos as f64,
                    sync.bytes_sent as f64,
                    sync.owned as f64,
                ],
                self.stir_work_sums(p, owned.clone()),
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
        let bins = self
            .config
            .bin_report
            .then(|| self.bin_counts(p, owned.clone(), dt, guard));
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
        let external_work = self.external_work;
        // The stirring's work over the step, with the time-centred velocity
        // v_n + a dt / 2 (the kick it gets): sum m a_s . v_n dt + sum m a_s . a dt^2 / 2.
        let [s1, s2] = work_terms;
        self.external_work += s1 * dt + 0.5 * s2 * dt * dt;
        self.t += dt;
        self.dt_prev = dt;
        self.step = step;
        self.block.updates += updates as u64;
        Ok(StepReport {
            step,
            t,
            dt,
            dt_limit,
            conserved,
            external_work,
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
            bins,
            updates: updates as u64,
            all_active: true,
            ends_synchronised: true,
        })
    }

    /// From new densities to forces, the stages both time-step modes
    /// share: EOS (with the barotropic calibration on step 1), halo
    /// thermodynamics, IAD matrices (and the velocity divergence with
    /// them), pair factors, viscosity switches, momentum and energy.
    fn thermo_and_forces(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        owned: Range<usize>,
        step: u64,
        clock: &mut StageClock,
    ) -> Result<MomentumStats, CoreError> {
        self.eos(p, owned.clone())?;
        if step == 1 {
            self.calibrate_energy(p, owned.clone());
        }
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
        self.buf
            .factors
            .fill_with(&hydro_state!(p), self.config.scheme.volume, &self.buf.kx);
        if self.config.scheme.needs_divergence() {
            self.switches(p, bbox, step, clock, divergence_done)?;
        }
        let forces = self.momentum(p, bbox);
        clock.lap(Stage::Momentum);
        Ok(forces)
    }

    /// Recomputes neighbours, density, pressure (and the gravitational
    /// potential) at the current positions without advancing (for observables at the end of a run). Afterwards
    /// the local arrays hold halos again: use [`owned`](Self::owned).
    pub fn evaluate_density(
        &mut self,
        p: &mut Particles,
        bbox: &mut BoundingBox,
    ) -> Result<(), CoreError> {
        let owned = self.evaluate_neighbourhoods(p, bbox)?;
        self.eos(p, owned.clone())?;
        self.exchange_thermo(p)?;
        if self.gravity.is_some() {
            self.gravity_field(p, bbox, owned, Targets::ALL, self.step)?;
        }
        Ok(())
    }

    /// [`evaluate_density`](Self::evaluate_density), then the forces, and
    /// the steps that end now closed: each particle whose step ends at the
    /// current time gets its velocity at this time, the closing half-kick
    /// `dX / dt + a dt / 2` of the step it finished ([`close_steps`]),
    /// instead of the prediction `v + a t` it carries between kicks. The
    /// state a run ends with, for its observables and conserved sums; a
    /// further step would not continue the run to the bit. Before the first step, and
    /// in stirred runs (the driving advances only with a step), the
    /// velocities stay as they are.
    ///
    /// # Errors
    /// As [`step`](Self::step).
    pub fn evaluate_closed(
        &mut self,
        p: &mut Particles,
        bbox: &mut BoundingBox,
    ) -> Result<(), CoreError> {
        let block = self.config.time_steps.on_time_line();
        if self.step == 0 || self.config.stirring.is_some() || (block && !self.block.started) {
            return self.evaluate_density(p, bbox);
        }
        let owned = self.evaluate_neighbourhoods(p, bbox)?;
        let step = self.step + 1;
        let mut clock = StageClock::start();
        if block {
            self.prepare_closing(p, owned.clone())?;
        }
        self.thermo_and_forces(p, bbox, owned.clone(), step, &mut clock)?;
        if block {
            self.gather_impulses(owned.clone())?;
        }
        self.add_gravity(p, bbox, owned.clone(), Targets::ALL, step)?;
        if block {
            self.close_block_steps(p, owned);
        } else {
            let dt_prev = self.dt_prev;
            close_steps(p, owned, |_| Some(dt_prev));
        }
        Ok(())
    }

    /// The sync, neighbour search and density of
    /// [`evaluate_density`](Self::evaluate_density); returns the owned
    /// range.
    fn evaluate_neighbourhoods(
        &mut self,
        p: &mut Particles,
        bbox: &mut BoundingBox,
    ) -> Result<Range<usize>, CoreError> {
        p.check(self.config.fields())?;
        self.release_step_buffers();
        let owned = self.domain.sync_with(p, bbox, self.next_h_max.take())?;
        self.tree
            .rebuild(self.domain.keys(), &p.x, &p.y, &p.z, self.config.bucket)?;
        self.search(p, bbox, self.step, owned.clone(), None)?;
        self.release_tree_after_search();
        self.density(p, bbox)?;
        Ok(owned)
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
