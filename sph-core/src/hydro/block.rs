//! Block time steps ([`TimeSteps::Block`](crate::TimeSteps::Block)): one
//! call of [`Hydro::step`] is one sub-step of the hierarchy
//! (`docs/block-timesteps.md`).
//!
//! Each particle steps `2^bin` ticks of an integer time line
//! ([`TimeLine`]) from a multiple of that length; a sub-step ends at the
//! nearest step end of any particle. The particles whose step ends there
//! (the active ones) get new forces and are kicked with the global
//! integrator's formulas over their own step: with `dX` the displacement
//! of the step just finished and `dt_b` its length,
//! `v_n = dX / dt_b + a_n dt_b / 2`, then the new bin `b'`,
//! `dX' = (v_n + a_n dt_b' / 2) dt_b'`, and the Adams-Bashforth correction
//! of `u` over `dt_b'`. Every particle then drifts to the next step end:
//! `x += dX' (ticks / 2^bin)`, `v += a dt`, `u += du dt`, and density and
//! smoothing length by the density's rate over the particle's last step
//! (`rho *= exp(r dt)`, `h *= exp(-r dt / 3)`); inactive particles keep
//! their accelerations and matrices (held fields) and get `P`, `c` of
//! their drifted `u` and `rho`. Without the density prediction the held
//! densities of inactive neighbours are an O(dt) error in the active
//! particles' forces, and Sedov loses 1.4e-3 of its energy at 30^3.
//!
//! The limiter: a new bin is at most `limiter_delta` above the smallest
//! bin among the particle's neighbours, and an active particle wakes the
//! neighbours whose bin is more than `limiter_delta` above its new one:
//! their step is cut to one of `2^(b' + delta)` ticks containing now,
//! with the velocity they would have had at its start.
//!
//! The domain syncs (migration, sort, halos, tree rebuild) on the first
//! sub-step, at every synchronisation point (every particle active: where
//! checkpoints are written, so a restart continues to the bit) and
//! whenever the largest h plus the largest drift since the last sync
//! passes the halos' reach; in between, halos get their owners'
//! state by a plain exchange and the tree is refitted to the drifted
//! positions (same cells, exact boxes), so searches stay exact.

use super::report::{DomainStepStats, Stage, StageClock};
use super::{grow_open_axes, BlockRun, Hydro, StepReport};
use crate::conserved::Conserved;
use crate::fields::Needs;
use crate::pair_loop::{neighbour_lanes, F64s, Group, PairLoop, PairStage};
use crate::timeline::{is_active, step_begin, Bin, Ticks, TimeLine, LINE, MAX_BIN};
use crate::timestep::{DtLimit, FirstStep, TimeSteps};
use crate::{CoreError, Particles};
use rayon::prelude::*;
use sph_comm::{Communicator, ReduceOp};
use sph_gravity::Targets;
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList, NeighborStats};
use std::ops::Range;
use std::sync::atomic::{AtomicU8, Ordering};

/// The default longest step is the run's span over this. The cold gas
/// ahead of a blast takes that step (`DT_MAX_PER_SPAN` updates per
/// particle) until the limiter wakes it; Sedov 40^3 to t = 0.05: 1.861 M
/// updates at span / 8, 1.714 M at span / 4, the same L1 and energy.
const DT_MAX_PER_SPAN: f64 = 4.0;

/// The block-step state of a pipeline besides the particles' bins.
#[derive(Debug, Default)]
pub(super) struct BlockState {
    /// The integer time line (set by [`Hydro::set_time_line`], started
    /// anew at every synchronisation point).
    pub(super) line: Option<TimeLine>,
    /// The run's end: the last line ends there.
    run_end: f64,
    /// The start ramp's origin `t_r`: no particle's step exceeds
    /// `(max_growth - 1) (t - t_r)`, the global ramp's step at `t`, nor
    /// is held by it more than the limiter's factor below its own
    /// criteria (`-inf`: no ramp, `--first-step criteria`).
    pub(super) ramp_origin: f64,
    /// The longest step any particle may take.
    dt_cap: f64,
    /// The current tick.
    pub(super) ti: Ticks,
    /// Whether the particles hold bins (false before the first sub-step).
    pub(super) started: bool,
    /// Particle updates so far (active particles summed over sub-steps).
    pub(super) updates: u64,
    /// Domain syncs so far (migration, sort, halos, tree rebuild).
    pub(super) syncs: u64,
    /// The most any particle can have moved since the last sync (the sum
    /// of each sub-step's largest move, all ranks).
    drift_since_sync: f64,
    /// The box the domain's keys were computed in at the last sync (open
    /// axes grow between syncs; the gravity tree's cells are those of
    /// this box).
    sync_box: Option<BoundingBox>,
    /// Whether every particle is active at the current tick (a
    /// synchronisation point): the sub-step there reports `all_active`
    /// and syncs the domain, so that a restart from a checkpoint written
    /// just before it continues to the bit.
    at_sync_point: bool,
    /// A restored run: its first sub-step checks that every particle is
    /// active (the checkpoint was written at a synchronisation point).
    restored: bool,
    /// Whether the next sub-step syncs: when the largest h plus that
    /// drift passes the halos' reach (`Domain::h_limit`), a pair of the
    /// next sub-step might be missing from the halos or the tree's cells.
    sync_due: bool,
    /// Work arrays: active flags of the owned particles, their new bins,
    /// the smallest neighbour bins, and the wake-up requests of every
    /// local particle.
    active: Vec<bool>,
    /// Each local particle's time since its last update (alpha's advance).
    elapsed: Vec<f64>,
    rho_before: Vec<f64>,
    /// Each active owned particle's step by its own criteria (infinite
    /// for the inactive).
    dt_criteria: Vec<f64>,
    new_bin: Vec<u8>,
    neighbour_bin: Vec<f64>,
    wake: Vec<AtomicU8>,
    /// Per local particle, the bin a wake-up request must be below to
    /// change anything ([`WakeUp::limit`]).
    wake_limit: Vec<u8>,
}

impl BlockState {
    /// Whether owned particle `k` (from the first owned) starts a step
    /// at this sub-step.
    pub(super) fn is_active(&self, k: usize) -> bool {
        self.active[k]
    }

    /// Each local particle's time since its last update (its own step;
    /// 0 at the first sub-step), for the viscosity switches.
    pub(super) fn elapsed(&self) -> &[f64] {
        &self.elapsed
    }

    /// Marks the owned particles whose step ends at the current tick
    /// (every one with `all`: the first sub-step).
    fn mark_active(&mut self, bins: &[f64], owned: Range<usize>, all: bool) {
        let ti = self.ti;
        self.active.clear();
        self.active
            .extend(owned.map(|i| all || is_active(ti, bin_of(bins[i]))));
    }

    /// Sets each owned particle's step as its time since its last update
    /// (read where it is active; none before the first sub-step) and 0
    /// for the other `len - owned` local particles.
    fn mark_elapsed(&mut self, line: &TimeLine, bins: &[f64], len: usize, owned: Range<usize>) {
        self.elapsed.clear();
        self.elapsed.resize(len, 0.0);
        if self.started {
            for i in owned {
                self.elapsed[i] = line.dt(bin_of(bins[i]));
            }
        }
    }
}

/// A particle's bin, stored as an exact `f64` in `Particles::bin`.
#[inline]
pub(super) fn bin_of(stored: f64) -> Bin {
    Bin(stored as u8)
}

impl<K: Kernel, C: Communicator> Hydro<K, C> {
    /// The time line of a block-step run, from the current time to
    /// `t_end` (the run's end), with the longest step
    /// [`TimestepParams::dt_max`](crate::TimestepParams::dt_max) (a
    /// quarter of the span when unset). A synchronisation point may start
    /// a new line (one step for every particle where a scene needs about
    /// the same step everywhere); the last line ends exactly at `t_end`.
    /// Call it
    /// before the first step (a restored run: before its first step after
    /// the restore, which keeps the restored line and its longest step
    /// and ends at this `t_end`); global runs ignore it.
    ///
    /// # Errors
    /// An end not after the current time, or a longest step below one
    /// tick.
    pub fn set_time_line(&mut self, t_end: f64) -> Result<(), CoreError> {
        self.block.run_end = t_end;
        if self.block.started {
            return Ok(());
        }
        let span = t_end - self.t;
        let ts = self.config.timestep;
        // The global ramp's steps: dt0 g^n at t_n = t0 + dt0 (g^n - 1) / (g - 1),
        // i.e. (g - 1) (t_n - t_r) with this origin.
        self.block.ramp_origin = if ts.first_step == FirstStep::Ramp && ts.max_growth > 1.0 {
            self.t - self.dt_prev / (ts.max_growth - 1.0)
        } else {
            f64::NEG_INFINITY
        };
        let dt_max = self
            .config
            .timestep
            .dt_max
            .unwrap_or(span / DT_MAX_PER_SPAN);
        self.block.line = Some(TimeLine::new(self.t, t_end, dt_max)?);
        self.block.dt_cap = dt_max;
        self.block.ti = 0;
        Ok(())
    }

    /// The block-step time line, when set.
    pub fn time_line(&self) -> Option<&TimeLine> {
        self.block.line.as_ref()
    }

    /// The current tick of the time line (block-step runs; 0 before the
    /// first sub-step).
    pub fn tick(&self) -> Ticks {
        self.block.ti
    }

    /// Domain syncs of a block-step run so far (a global run syncs every
    /// step).
    pub fn domain_syncs(&self) -> u64 {
        if self.config.time_steps.on_time_line() {
            self.block.syncs
        } else {
            self.step
        }
    }

    /// Particle updates so far: the active particles summed over the
    /// sub-steps of a block-step run, particles times steps in a global
    /// one.
    pub fn particle_updates(&self) -> u64 {
        self.block.updates
    }

    /// The run's place on its time line, once the first sub-step has
    /// given the particles bins (for checkpoints).
    pub(super) fn block_run(&self) -> Option<BlockRun> {
        let line = self.block.line?;
        (self.config.time_steps.on_time_line() && self.block.started).then(|| BlockRun {
            t_begin: line.time(0),
            t_end: line.time(LINE),
            dt_max_bin: line.dt_max_bin().0,
            dt_max: self.block.dt_cap,
            ramp_origin: self.block.ramp_origin,
            ti: self.block.ti,
            updates: self.block.updates,
            syncs: self.block.syncs,
        })
    }

    /// Continues the time line of a checkpoint written at a
    /// synchronisation point: the next sub-step syncs the domain, as the
    /// run that wrote it did there. A checkpoint at the end of its line
    /// (a line short of the run's end: one step for all, in a scene whose
    /// particles need about the same step) continues with the next line,
    /// as the run that wrote it did.
    pub(super) fn restore_block_run(&mut self, b: BlockRun) -> Result<(), CoreError> {
        let line = TimeLine::with_top_bin(b.t_begin, b.t_end, Bin(b.dt_max_bin))?;
        if b.ti > LINE {
            return Err(CoreError::Invalid(format!(
                "the checkpoint's tick {} is past its time line's end ({LINE})",
                b.ti
            )));
        }
        self.block.line = Some(line);
        self.block.dt_cap = b.dt_max;
        self.block.ramp_origin = b.ramp_origin;
        self.block.run_end = b.t_end;
        self.block.ti = b.ti;
        self.block.started = true;
        self.block.updates = b.updates;
        self.block.syncs = b.syncs;
        self.block.sync_due = true;
        self.block.at_sync_point = true;
        self.block.restored = true;
        Ok(())
    }

    /// One sub-step of a block-step run (see the module's text).
    pub(super) fn substep(
        &mut self,
        p: &mut Particles,
        bbox: &mut BoundingBox,
    ) -> Result<StepReport, CoreError> {
        let step = self.step + 1;
        p.check(self.config.fields())?;
        let line = self.block.line.ok_or_else(|| {
            CoreError::Invalid(
                "block time steps need a time line: call Hydro::set_time_line with the run's end time before the first step".into(),
            )
        })?;
        // A line's end is a synchronisation point, where the next line
        // starts, unless it is the run's end.
        if self.block.ti >= LINE && line.time(LINE) >= self.block.run_end {
            return Err(CoreError::Invalid(format!(
                "block time steps: the time line ends at t = {}; set a later end",
                line.time(LINE)
            )));
        }
        let mut clock = StageClock::start();
        let first = !self.block.started;
        let owned = if first || self.block.sync_due {
            self.release_step_buffers();
            // Where every particle is active, each recomputes its held
            // fields before any reads them: the sort need not move them.
            p.held_recomputed = self.block.at_sync_point && !first;
            let synced = self.domain.sync_with(p, bbox, self.next_h_max.take());
            p.held_recomputed = false;
            let owned = synced?;
            clock.lap(Stage::Sync);
            self.tree
                .rebuild(self.domain.keys(), &p.x, &p.y, &p.z, self.config.bucket)?;
            self.block.drift_since_sync = 0.0;
            self.block.sync_box = Some(*bbox);
            self.block.syncs += 1;
            owned
        } else {
            self.refresh_halos(p)?;
            clock.lap(Stage::Halos);
            self.tree.refit(&p.x, &p.y, &p.z)?;
            self.domain.owned()
        };
        clock.lap(Stage::Tree);

        let ti = self.block.ti;
        let all_active = first || self.block.at_sync_point;
        self.block.mark_active(&p.bin, owned.clone(), first);
        let active = std::mem::take(&mut self.block.active);
        if std::mem::take(&mut self.block.restored) {
            let behind = owned.clone().zip(&active).find(|(_, &a)| !a);
            let behind = self.domain.comm().all_reduce_scalar(
                behind.map_or(f64::INFINITY, |(i, _)| p.id[i] as f64),
                ReduceOp::Min,
            );
            if behind.is_finite() {
                self.block.active = active;
                return Err(CoreError::Invalid(format!(
                    "the checkpoint is not at a synchronisation point: particle {behind} is inside its step at tick {ti}; block-step runs write checkpoints where every particle's step ends"
                )));
            }
        }
        let active_here = active.iter().filter(|&&a| a).count();
        let searched = self.search(p, bbox, step, owned.clone(), Some(&active));
        self.block.active = active;
        let neighbours = searched?;
        clock.lap(Stage::Neighbors);
        // The held buffers of the scheme's stages (div v, X, k) come from
        // the table for this sub-step and go back after it.
        self.swap_held_buffers(p);
        self.block
            .mark_elapsed(&line, &p.bin, p.len(), owned.clone());
        let before = &mut self.block.rho_before;
        before.clear();
        before.extend_from_slice(&p.rho[owned.clone()]);
        self.density(p, bbox)?;
        self.density_rates(p, &line, owned.clone(), first);
        self.predict_pressure_energy_norm(p, owned.clone());
        clock.lap(Stage::Density);
        // The EOS covers every owned particle: the active ones from their
        // new density, the others from their predicted density and u.
        self.prepare_impulses(p, &line, owned.clone(), self.block.ti)?;
        self.thermo_and_forces(p, bbox, owned.clone(), step, &mut clock)?;
        self.gather_impulses(owned.clone())?;
        self.swap_held_buffers(p);
        if first {
            // Adams-Bashforth needs du_{n-1}; the first step uses du_0.
            p.du_prev[owned.clone()].copy_from_slice(&p.du[owned.clone()]);
        }
        if self.config.stirring.is_some() {
            let active = std::mem::take(&mut self.block.active);
            let stirred = self.stir_active(p, bbox, owned.clone(), &active);
            self.block.active = active;
            stirred?;
            clock.lap(Stage::Stirring);
        }
        if self.gravity.is_some() {
            // The active particles' groups, on the tree of the last sync
            // (refitted) with its cells widened by the drift since.
            let active = std::mem::take(&mut self.block.active);
            let keyed = self.block.sync_box.unwrap_or(*bbox);
            let targets = Targets {
                active: Some(&active),
                drift: self.block.drift_since_sync,
            };
            let added = self.add_gravity(p, &keyed, owned.clone(), targets, step);
            self.block.active = active;
            added?;
            clock.lap(Stage::Gravity);
        }

        // The sums below over the velocities at this time of the particles
        // whose step ends here (the kick recomputes the same ones); the
        // first sub-step's are the initial conditions'.
        let b = &self.block;
        let o = owned.start;
        crate::integrate::close_steps(p, owned.clone(), |i| {
            (!first && b.active[i - o]).then(|| b.elapsed[i])
        });
        let sync = self.domain.stats();
        let (conserved, [nc_total, over_cap, halos_total, bytes_sent, updates], _) =
            Conserved::compute_with(
                p,
                owned.clone(),
                [
                    neighbours.total as f64,
                    neighbours.over_cap as f64,
                    sync.halos as f64,
                    sync.bytes_sent as f64,
                    active_here as f64,
                ],
                [],
                self.domain.comm(),
            );
        clock.lap(Stage::Conserved);

        self.criteria_steps(p, owned.clone(), first);
        // Every particle starts a step here: a new line from now, its bins
        // those of the last line's steps.
        let next = if all_active {
            self.next_line(&line, ti)?
        } else {
            line
        };
        let ti = if next == line {
            ti
        } else {
            for b in p.bin.iter_mut() {
                *b = f64::from(next.bin_of_dt(line.dt(bin_of(*b))).0);
            }
            self.block.line = Some(next);
            0
        };
        let line = next;
        self.new_bins(p, bbox, &line, owned.clone(), ti, first)?;
        let fallbacks = self.kick(p, &line, owned.clone(), ti, first, step)?
            + self.apply_impulses(p, owned.clone());
        let (next, limit) = self.next_tick(p, owned.clone(), ti);
        clock.lap(Stage::Timestep);

        let reach = self.drift(p, bbox, &line, owned.clone(), ti, next, step)?;
        grow_open_axes(bbox, reach)?;
        // The stirring's work up to now (that of the conserved sums above);
        // then the drift's, each particle along its share of its step.
        let external_work = self.external_work;
        let ticks = (next - ti) as f64;
        let bins = &p.bin;
        self.external_work +=
            self.stir_drift_work(p, owned.clone(), |i| ticks / bin_of(bins[i]).ticks() as f64);
        clock.lap(Stage::Integrate);

        let (nc_min, nc_max, h_max) =
            owned_extremes(p, owned.clone(), &neighbours, &self.block.active);
        // Whether some particle's step goes on past `next`.
        let goes_on = owned.clone().any(|i| !is_active(next, bin_of(p.bin[i])));
        let mut ext = [
            -nc_min,
            nc_max,
            h_max,
            sync.owned as f64,
            -(sync.owned as f64),
            f64::from(u8::from(goes_on)),
        ];
        let comm = self.domain.comm();
        comm.all_reduce(&mut ext, ReduceOp::Max);
        let halo_ratio =
            comm.all_reduce_scalar(sync.halos as f64 / sync.owned.max(1) as f64, ReduceOp::Max);
        let comm_times = [sync.comm_seconds, sync.sync_seconds];
        let mut times = comm_times;
        comm.all_reduce(&mut times, ReduceOp::Max);
        self.next_h_max = Some(ext[2]);
        // Between syncs particles keep their halos and their tree cells
        // (refitted): valid while every pair within 2 max(h_i, h_j) now
        // was within 2 h_limit at the sync, i.e. h_max + drift <= h_limit.
        // Global figures only, so every rank count syncs at the same
        // sub-steps and sums in the same order.
        self.block.drift_since_sync += reach;
        let ends_synchronised = ext[5] == 0.0;
        self.block.at_sync_point = ends_synchronised;
        let h_limit = self.domain.h_limit();
        let drift = self.block.drift_since_sync;
        self.block.sync_due = ends_synchronised
            || ext[2] + drift > h_limit
            || (self.gravity.is_some() && drift > GRAVITY_SYNC_DRIFT * h_limit);

        let t = self.t;
        let t_next = line.time(next);
        let dt = t_next - t;
        self.block.ti = next;
        self.block.started = true;
        self.block.updates += updates as u64;
        self.t = t_next;
        self.dt_prev = dt;
        self.step = step;
        Ok(StepReport {
            step,
            t,
            dt,
            dt_limit: limit,
            conserved,
            external_work,
            neighbors: NeighborStats {
                min_count: (-ext[0]).max(0.0) as usize,
                max_count: ext[1] as usize,
                total: nc_total as usize,
                over_cap: over_cap as usize,
                first_over_cap: neighbours.first_over_cap,
            },
            times: clock.times,
            energy_fallbacks: fallbacks,
            domain: DomainStepStats {
                owned_min: (-ext[4]) as usize,
                owned_max: ext[3] as usize,
                halos_total: halos_total as usize,
                halo_ratio_max: halo_ratio,
                bytes_sent: bytes_sent as u64,
                comm_seconds_max: times[0],
                sync_seconds_max: times[1],
            },
            bins: None,
            updates: updates as u64,
            all_active,
            ends_synchronised,
        })
    }

    /// The active set of a closing evaluation
    /// ([`Hydro::evaluate_closed`]): the owned particles whose step ends at
    /// the current tick (all of them at a synchronisation point, as at a
    /// run's end), each with the step it finished, and the impulses'
    /// inputs as a sub-step there has them. Collective.
    pub(super) fn prepare_closing(
        &mut self,
        p: &Particles,
        owned: Range<usize>,
    ) -> Result<(), CoreError> {
        let line = self.block.line.ok_or_else(|| {
            CoreError::Invalid("closing block steps needs the run's time line".into())
        })?;
        self.block.mark_active(&p.bin, owned.clone(), false);
        self.block
            .mark_elapsed(&line, &p.bin, p.len(), owned.clone());
        self.prepare_impulses(p, &line, owned, self.block.ti)
    }

    /// Closes the steps of the active set of
    /// [`prepare_closing`](Self::prepare_closing).
    pub(super) fn close_block_steps(&self, p: &mut Particles, owned: Range<usize>) {
        let b = &self.block;
        let o = owned.start;
        crate::integrate::close_steps(p, owned, |i| b.active[i - o].then(|| b.elapsed[i]));
    }

    /// Swaps the held fields of the table (`div_v`, `xm`, `kx`,
    /// `alpha_eff`, the velocity gradients, where the scheme holds them)
    /// with the step buffers the stages use. A buffer whose field is not
    /// held stays with the stages: AV cleaning or the Balsara limiter
    /// with one constant alpha computes `div v` without holding it.
    fn swap_held_buffers(&mut self, p: &mut Particles) {
        let f = p.fields();
        if f.holds(Needs::BlockSwitches) {
            std::mem::swap(&mut self.buf.div_v, &mut p.div_v);
        }
        if f.holds(Needs::BlockVolumes) {
            std::mem::swap(&mut self.buf.xm, &mut p.xm);
            std::mem::swap(&mut self.buf.kx, &mut p.kx);
        }
        if f.holds(Needs::BlockBalsara) {
            std::mem::swap(&mut self.buf.alpha_eff, &mut p.alpha_eff);
        }
        if f.holds(Needs::BlockCleaning) {
            self.buf.grad_v.resize_with(6, Vec::new);
            for (held, buffer) in p.grad_v.iter_mut().zip(&mut self.buf.grad_v) {
                std::mem::swap(held, buffer);
            }
        }
    }

    /// Brings the owners' current state to their halo copies (the halos
    /// of the last sync), between syncs: every field a halo carries.
    fn refresh_halos(&mut self, p: &mut Particles) -> Result<(), CoreError> {
        if self.domain.comm().size() == 1 {
            return Ok(());
        }
        let Particles {
            x,
            y,
            z,
            vx,
            vy,
            vz,
            h,
            u,
            bin,
            dlnrho,
            rho,
            p: pressure,
            c,
            ax,
            ay,
            az,
            du,
            omega,
            iad,
            alpha,
            div_v,
            xm,
            kx,
            ..
        } = p;
        let mut fields: Vec<&mut [f64]> = vec![
            x, y, z, vx, vy, vz, h, u, bin, dlnrho, rho, pressure, c, ax, ay, az, du,
        ]
        .into_iter()
        .map(|v| v.as_mut_slice())
        .collect();
        for v in [omega, alpha, div_v, xm, kx] {
            if !v.is_empty() {
                fields.push(v);
            }
        }
        for m in iad.iter_mut().filter(|m| !m.is_empty()) {
            fields.push(m);
        }
        self.domain.exchange(&mut fields)?;
        Ok(())
    }

    /// The new bins of the active particles (into `block.new_bin`, one per
    /// owned particle; the inactive keep theirs), and with the limiter
    /// the wake-up requests they make of their neighbours
    /// (`block.wake`, every local particle, brought to the owners).
    ///
    /// The limiter's pair passes are skipped where the bins' global
    /// extremes show that they cannot change a bin (every bin within the
    /// factor of every other: a near-uniform scene's sub-steps); the bins
    /// are then those the passes would give.
    fn new_bins(
        &mut self,
        p: &Particles,
        bbox: &BoundingBox,
        line: &TimeLine,
        owned: Range<usize>,
        ti: Ticks,
        first: bool,
    ) -> Result<(), CoreError> {
        let ts = self.config.timestep;
        let delta = ts.limiter_delta;
        let factor = f64::from(delta);
        let n = p.len();
        let o = owned.start;
        let limiter = ts.limiter && self.config.time_steps == TimeSteps::Block;
        self.block.neighbour_bin.clear();
        self.block.neighbour_bin.resize(owned.len(), f64::INFINITY);
        self.choose_bins(p, line, owned.clone(), ti, first)?;
        // The cap new <= (smallest neighbour bin) + delta binds nowhere
        // if no candidate exceeds the smallest bin of all by delta.
        if limiter && !first {
            let b = &self.block;
            let candidates = (0..owned.len()).filter(|&k| b.active[k]);
            let mut ext = [
                -owned
                    .clone()
                    .map(|i| p.bin[i])
                    .fold(f64::INFINITY, f64::min),
                candidates
                    .map(|k| f64::from(b.new_bin[k]))
                    .fold(f64::NEG_INFINITY, f64::max),
            ];
            self.domain.comm().all_reduce(&mut ext, ReduceOp::Max);
            if ext[1] > -ext[0] + factor {
                let b = &mut self.block;
                let driver = pair_driver(&self.kernel, bbox, p, &self.list)?;
                driver.run(
                    &NeighbourBins {
                        h: &p.h,
                        support: self.kernel.support(),
                        bin: &p.bin,
                    },
                    [&mut b.neighbour_bin[..]],
                );
                self.choose_bins(p, line, owned.clone(), ti, first)?;
            }
        }
        let b = &mut self.block;
        if self.config.time_steps == TimeSteps::Kdk {
            // One bin for all: every particle is active at every sub-step.
            let local = b.new_bin.iter().copied().min().unwrap_or(MAX_BIN);
            let all = self
                .domain
                .comm()
                .all_reduce_scalar(f64::from(local), ReduceOp::Min) as u8;
            b.new_bin.fill(all);
        }
        b.wake.clear();
        if !limiter {
            return Ok(());
        }
        // Nobody is woken or lowered if the smallest new bin plus delta
        // reaches every bin (the inactive particles' and the new ones).
        let mut ext = [f64::NEG_INFINITY; 2];
        for k in 0..owned.len() {
            if b.active[k] {
                let new = f64::from(b.new_bin[k]);
                ext[0] = ext[0].max(-new);
                ext[1] = ext[1].max(new);
            } else {
                ext[1] = ext[1].max(p.bin[o + k]);
            }
        }
        self.domain.comm().all_reduce(&mut ext, ReduceOp::Max);
        if ext[1] <= -ext[0] + factor {
            return Ok(());
        }
        let b = &mut self.block;
        b.wake.resize_with(n, || AtomicU8::new(u8::MAX));
        // Wake-ups until no active particle is lowered: an active
        // particle woken by another wakes its own neighbours in the same
        // sub-step, so every active particle ends within the factor of
        // all its neighbours (a fixed point: the same on any rank count).
        // A request changes an owned particle's bin only below its
        // current bin (inactive) or its new one (active; the loop only
        // lowers that further); a halo's is its owner's business.
        b.wake_limit.clear();
        b.wake_limit.resize(n, u8::MAX);
        for k in 0..owned.len() {
            b.wake_limit[o + k] = if b.active[k] {
                b.new_bin[k]
            } else {
                bin_of(p.bin[o + k]).0
            };
        }
        let mut lowered: Vec<bool> = Vec::new();
        loop {
            let driver = pair_driver(&self.kernel, bbox, p, &self.list)?;
            let stage = WakeUp {
                h: &p.h,
                support: self.kernel.support(),
                new_bin: &b.new_bin,
                first: o,
                delta,
                wake: &b.wake,
                limit: &b.wake_limit,
            };
            if lowered.is_empty() {
                driver.run(&stage, []);
            } else {
                driver.run_masked(&stage, [], &lowered);
            }
            if self.domain.comm().size() > 1 {
                let mut wake: Vec<u8> = b.wake.iter().map(|w| w.load(Ordering::Relaxed)).collect();
                self.domain.exchange_reverse_min(&mut wake)?;
                for (w, v) in b.wake.iter().zip(wake) {
                    w.store(v, Ordering::Relaxed);
                }
            }
            lowered.clear();
            lowered.extend((0..owned.len()).map(|k| {
                let w = b.wake[o + k].load(Ordering::Relaxed);
                b.active[k] && w < b.new_bin[k]
            }));
            let mut count = 0u64;
            for (k, &l) in lowered.iter().enumerate() {
                if l {
                    b.new_bin[k] = b.wake[o + k].load(Ordering::Relaxed);
                    count += 1;
                }
            }
            let count = self
                .domain
                .comm()
                .all_reduce_scalar(count as f64, ReduceOp::Sum);
            if count == 0.0 {
                break;
            }
        }
        Ok(())
    }

    /// Each active owned particle's step by its own criteria (Courant
    /// with its signal velocity, density change, acceleration with
    /// gravity, cooling), into `block.dt_criteria`.
    fn criteria_steps(&mut self, p: &Particles, owned: Range<usize>, first: bool) {
        let ts = self.config.timestep;
        let criterion = self.acc_criterion();
        let o = owned.start;
        let b = &mut self.block;
        let (hv, comp) = (&self.buf.h_over_vsig, &self.buf.compression);
        let energy = self.config.eos.uses_internal_energy();
        let active = &b.active;
        // The start ramp, never more than the limiter's factor below a
        // particle's own criteria.
        let ramp = (ts.max_growth - 1.0) * (self.t - b.ramp_origin);
        let depth = f64::from(ts.limiter_factor());
        b.dt_criteria.clear();
        b.dt_criteria.resize(owned.len(), f64::INFINITY);
        b.dt_criteria
            .par_iter_mut()
            .enumerate()
            .filter(|(k, _)| first || active[*k])
            .for_each(|(k, out)| {
                let i = o + k;
                let cooling = super::stages::cooling_rate(p, i, energy);
                // The acceleration criterion with self-gravity, as the
                // global step has it.
                let acc = criterion.at(p, i);
                let own = ts.particle_dt(hv[i], comp[i], acc, cooling);
                *out = own.min(ramp.max(own / depth));
            });
    }

    /// The line from now, at a synchronisation point (every particle
    /// starts a step): the line so far while it runs to the run's end,
    /// else a line to the end; or, where that costs fewer particle
    /// updates per unit time, a line of one step a hair below the
    /// smallest criterion step, which every particle takes. Bins of a
    /// line to the end are powers of two of its span, so a scene whose
    /// particles all need about the same step can lose up to a factor 2
    /// there (Gresho: 1.5x the global run's steps); the one-step line
    /// steps them at their criteria, as a global run does.
    fn next_line(&self, line: &TimeLine, ti: Ticks) -> Result<TimeLine, CoreError> {
        let b = &self.block;
        let (t, end) = (self.t, b.run_end);
        let longest = b.dt_cap.min(end - t);
        let to_end = if line.time(LINE) >= end && ti < LINE {
            *line
        } else {
            TimeLine::new(t, end, longest)?
        };
        // Each particle's bin on that line by its criteria (the limiter
        // aside), counted per bin: exact integer sums, the same decision
        // on every rank count.
        let comm = self.domain.comm();
        let mut counts = vec![0.0; usize::from(MAX_BIN) + 1];
        let mut dt_min = f64::INFINITY;
        for &dt in &b.dt_criteria {
            counts[usize::from(to_end.bin_of_dt(dt.min(longest)).0)] += 1.0;
            dt_min = dt_min.min(dt);
        }
        comm.all_reduce(&mut counts, ReduceOp::Sum);
        let dt_min = comm.all_reduce_scalar(dt_min, ReduceOp::Min);
        // A hair below: particles whose criteria differ from the smallest
        // by rounding (a lattice's mirror images) share its step.
        let pace = dt_min * (1.0 - 1.0 / 1024.0);
        if pace > 0.0 && pace <= longest && t + 2.0 * pace <= end {
            let n: f64 = counts.iter().sum();
            let rate: f64 = counts
                .iter()
                .enumerate()
                .map(|(bin, &c)| c / to_end.dt(Bin(bin as u8)))
                .sum();
            if n / pace < rate {
                // One step: the top bin is the whole line (whose span is
                // `pace` up to the rounding of `t + pace`).
                return TimeLine::with_top_bin(t, t + pace, Bin(MAX_BIN));
            }
        }
        Ok(to_end)
    }

    /// Each active particle's bin from its criteria step, capped by the
    /// neighbours' smallest bin in `block.neighbour_bin` (infinite: no
    /// cap), into `block.new_bin`; the inactive keep theirs.
    fn choose_bins(
        &mut self,
        p: &Particles,
        line: &TimeLine,
        owned: Range<usize>,
        ti: Ticks,
        first: bool,
    ) -> Result<(), CoreError> {
        let delta = self.config.timestep.limiter_delta;
        let o = owned.start;
        let b = &mut self.block;
        b.new_bin.clear();
        b.new_bin.resize(owned.len(), 0);
        let (active, nb, dt) = (&b.active, &b.neighbour_bin, &b.dt_criteria);
        b.new_bin
            .par_iter_mut()
            .enumerate()
            .try_for_each(|(k, out)| {
                let i = o + k;
                if !active[k] {
                    *out = bin_of(p.bin[i]).0;
                    return Ok(());
                }
                let old = (!first).then(|| bin_of(p.bin[i]));
                let ngb = nb[k].is_finite().then(|| bin_of(nb[k]));
                let (bin, _) = line
                    .new_bin(dt[k], old, ti, ngb, delta)
                    .map_err(|e| CoreError::Invalid(format!("particle {}: {e}", p.id[i])))?;
                *out = bin.0;
                Ok::<(), CoreError>(())
            })?;
        Ok(())
    }

    /// `d ln rho / dt` of the active particles over the step they end,
    /// from their new density and the one predicted for now:
    /// `ln(rho / rho_pred) / dt + dlnrho` (0 at the first sub-step).
    fn density_rates(
        &mut self,
        p: &mut Particles,
        line: &TimeLine,
        owned: Range<usize>,
        first: bool,
    ) {
        let b = &self.block;
        let o = owned.start;
        let (rho, bins) = (&p.rho, &p.bin);
        p.dlnrho[owned]
            .par_iter_mut()
            .enumerate()
            .filter(|(k, _)| b.active[*k])
            .for_each(|(k, r)| {
                let i = o + k;
                *r = if first {
                    0.0
                } else {
                    (rho[i] / b.rho_before[k]).ln() / line.dt(bin_of(bins[i])) + *r
                };
            });
    }

    /// Pressure-energy volumes: an inactive particle's `X = m u` comes
    /// from its drifted `u` (the density stage sets it), so its `k` must
    /// follow its predicted density and `u`, `k = rho u` (`X / k = m /
    /// rho`, and `P = (gamma - 1) k` as its EOS has it); the `k` of its
    /// last evaluation against a drifted `X` gave inconsistent volumes.
    fn predict_pressure_energy_norm(&mut self, p: &Particles, owned: Range<usize>) {
        if self.config.scheme.volume != crate::Volume::PressureEnergy {
            return;
        }
        let (active, o) = (&self.block.active, owned.start);
        for i in owned.filter(|&i| !active[i - o]) {
            self.buf.kx[i] = p.rho[i] * p.u[i];
        }
    }

    /// Kicks the active particles over their new steps and cuts the steps
    /// of the woken ones; returns the energy updates that fell back to
    /// first order.
    fn kick(
        &mut self,
        p: &mut Particles,
        line: &TimeLine,
        owned: Range<usize>,
        ti: Ticks,
        first: bool,
        step: u64,
    ) -> Result<usize, CoreError> {
        let dt0 = self.dt_prev;
        let guard = self.config.eos.uses_internal_energy();
        let h_update = (!self.config.scheme.fixed_h)
            .then(|| self.config.neighbors.h_update(self.config.h_update));
        let limiter = !self.block.wake.is_empty();
        let b = &self.block;
        let o = owned.start;
        let (ax, ay, az, du, nc, id) = (&p.ax, &p.ay, &p.az, &p.du, &p.nc, &p.id);
        let t_now = line.time(ti);
        let r = owned.clone();
        (
            p.vx[r.clone()].par_iter_mut(),
            p.vy[r.clone()].par_iter_mut(),
            p.vz[r.clone()].par_iter_mut(),
            p.dx[r.clone()].par_iter_mut(),
            p.dy[r.clone()].par_iter_mut(),
            p.dz[r.clone()].par_iter_mut(),
            p.u[r.clone()].par_iter_mut(),
            p.du_prev[r.clone()].par_iter_mut(),
            p.h[r.clone()].par_iter_mut(),
            p.bin[r.clone()].par_iter_mut(),
        )
            .into_par_iter()
            .enumerate()
            .map(|(k, (vx, vy, vz, dx, dy, dz, u, du_prev, h, bin))| {
                let i = o + k;
                let a = [ax[i], ay[i], az[i]];
                let vel = [vx, vy, vz];
                let dpos = [dx, dy, dz];
                let woken = if limiter {
                    b.wake[i].load(Ordering::Relaxed)
                } else {
                    u8::MAX
                };
                if !b.active[k] {
                    let old = bin_of(*bin);
                    if woken >= old.0 {
                        return Ok(0);
                    }
                    // Cut short: a step of 2^woken ticks containing now,
                    // from the velocity the particle had at its start.
                    let new = Bin(woken);
                    let since = t_now - line.time(step_begin(ti, new));
                    let dt_new = line.dt(new);
                    for c in 0..3 {
                        let v_start = *vel[c] - a[c] * since;
                        *dpos[c] = (v_start + 0.5 * a[c] * dt_new) * dt_new;
                    }
                    *bin = f64::from(new.0);
                    return Ok(0);
                }
                // The step just ended (on the last line, at a
                // synchronisation point).
                let old_dt = if first { dt0 } else { b.elapsed[i] };
                let new = Bin(b.new_bin[k].min(woken));
                let dt = line.dt(new);
                for c in 0..3 {
                    let v_n = crate::integrate::velocity_now(*dpos[c], a[c], old_dt);
                    *dpos[c] = (v_n + 0.5 * a[c] * dt) * dt;
                    *vel[c] = v_n;
                }
                // Adams-Bashforth 2 over the new step: the correction now,
                // du dt through the drifts; first order if that would go
                // negative.
                let d = du[i];
                let mut fallback = 0;
                let mut corr = 0.5 * (d - *du_prev) / old_dt * dt * dt;
                let end = *u + corr + d * dt;
                if guard && (end.is_nan() || end < 0.0 || *u + corr < 0.0) {
                    fallback = 1;
                    corr = 0.0;
                    let first_order = *u + d * dt;
                    if first_order.is_nan() || first_order < 0.0 {
                        return Err(CoreError::NegativeEnergy {
                            step,
                            id: id[i],
                            u: first_order,
                            du: d,
                            dt,
                        });
                    }
                }
                *u += corr;
                *du_prev = d;
                if let Some(hu) = h_update {
                    *h *= hu.factor(nc[i]);
                }
                *bin = f64::from(new.0);
                Ok(fallback)
            })
            .try_reduce(|| 0, |a, b| Ok(a + b))
    }

    /// The next tick: the nearest step end of any particle (all ranks).
    fn next_tick(&self, p: &Particles, owned: Range<usize>, ti: Ticks) -> (Ticks, DtLimit) {
        let local = owned
            .into_par_iter()
            .map(|i| {
                let bin = bin_of(p.bin[i]);
                step_begin(ti, bin) + bin.ticks()
            })
            .min()
            .unwrap_or(LINE);
        // Ticks are at most 2^52: exact in f64.
        let next = self
            .domain
            .comm()
            .all_reduce_scalar(local as f64, ReduceOp::Min) as Ticks;
        (next.min(LINE), DtLimit::StepEnd)
    }

    /// Drifts every owned particle from tick `ti` to `next`: positions by
    /// their share of the step's displacement, `v += a dt`, `u += du dt`,
    /// then `P` and `c` are those of the drifted `u` at the next sub-step's
    /// EOS. Returns the largest coordinate change over all ranks (for the
    /// open axes of the box).
    #[allow(clippy::too_many_arguments)]
    fn drift(
        &self,
        p: &mut Particles,
        bbox: &BoundingBox,
        line: &TimeLine,
        owned: Range<usize>,
        ti: Ticks,
        next: Ticks,
        step: u64,
    ) -> Result<f64, CoreError> {
        let ticks = next - ti;
        let dt = ticks as f64 * line.time_base();
        let (ax, ay, az, du, id, bins) = (&p.ax, &p.ay, &p.az, &p.du, &p.id, &p.bin);
        let dlnrho = &p.dlnrho;
        let fixed_h = self.config.scheme.fixed_h;
        let r = owned.clone();
        let o = owned.start;
        let moved = (
            p.x[r.clone()].par_iter_mut(),
            p.y[r.clone()].par_iter_mut(),
            p.z[r.clone()].par_iter_mut(),
            p.vx[r.clone()].par_iter_mut(),
            p.vy[r.clone()].par_iter_mut(),
            p.vz[r.clone()].par_iter_mut(),
            p.dx[r.clone()].par_iter(),
            p.dy[r.clone()].par_iter(),
            p.dz[r.clone()].par_iter(),
            p.u[r.clone()].par_iter_mut(),
            p.rho[r.clone()].par_iter_mut(),
            p.h[r.clone()].par_iter_mut(),
        )
            .into_par_iter()
            .enumerate()
            .map(|(k, (x, y, z, vx, vy, vz, dx, dy, dz, u, rho, h))| {
                let i = o + k;
                // An exact ratio of integers (a power of two below).
                let share = ticks as f64 / bin_of(bins[i]).ticks() as f64;
                let a = [ax[i], ay[i], az[i]];
                let pos = [x, y, z];
                let vel = [vx, vy, vz];
                let d = [*dx, *dy, *dz];
                let mut newp = [0.0; 3];
                let mut moved: f64 = 0.0;
                for c in 0..3 {
                    let s = if share == 1.0 { d[c] } else { d[c] * share };
                    newp[c] = *pos[c] + s;
                    moved = moved.max(s.abs());
                    *vel[c] += a[c] * dt;
                }
                crate::integrate::place(pos, newp, [*vel[0], *vel[1], *vel[2]], bbox, step, id[i])?;
                *u += du[i] * dt;
                // Density by its rate, and h with it so that the kernel
                // keeps its mass (h^3 rho constant), unless h is fixed.
                if dlnrho[i] != 0.0 {
                    let r = drift_rate(dlnrho[i], line.dt(bin_of(bins[i])));
                    *rho *= density_drift(r, dt);
                    if !fixed_h {
                        *h *= h_drift(r, dt);
                    }
                }
                Ok::<f64, CoreError>(moved)
            })
            .try_reduce(|| 0.0, |a, b| Ok(a.max(b)))?;
        // Volume elements X ~ m / rho0 go with the volume: X *= exp(-r dt)
        // (their normalisation k stays).
        if !p.xm.is_empty() {
            let (dlnrho, bins) = (&p.dlnrho, &p.bin);
            p.xm[owned.clone()]
                .par_iter_mut()
                .zip(dlnrho[owned.clone()].par_iter())
                .zip(bins[owned].par_iter())
                .filter(|((_, &r), _)| r != 0.0)
                .for_each(|((x, &r), &b)| {
                    *x *= (-drift_rate(r, line.dt(bin_of(b))) * dt).exp();
                });
        }
        Ok(self.domain.comm().all_reduce_scalar(moved, ReduceOp::Max))
    }
}

/// The density rate a drift applies: the particle's rate `r` over its
/// last step, bounded so that the density it predicts changes by at most
/// a factor 2 over the particle's current `step`. The density criterion
/// keeps a compression's change within 6% a step; a rate that would
/// exceed the bound comes from a density that jumped (a dense clump's
/// particle passing by), and extrapolated over a long step it would
/// inflate h without bound.
#[inline]
pub(super) fn drift_rate(r: f64, step: f64) -> f64 {
    let bound = std::f64::consts::LN_2 / step;
    r.clamp(-bound, bound)
}

/// The factor the drift applies to a density over `dt` at the rate
/// `r = d ln rho / dt` of the particle's last step (also what a snapshot
/// between sub-steps is predicted with: `predict.rs`).
#[inline]
pub(super) fn density_drift(r: f64, dt: f64) -> f64 {
    (r * dt).exp()
}

/// The factor for the smoothing length that goes with
/// [`density_drift`]: the kernel keeps its mass (`h^3 rho` constant).
#[inline]
pub(super) fn h_drift(r: f64, dt: f64) -> f64 {
    (-r * dt / 3.0).exp()
}

/// The smallest and largest neighbour count over the active owned
/// particles (the others were not searched; none: +inf, -inf) and the
/// largest h of the owned particles.
fn owned_extremes(
    p: &Particles,
    owned: Range<usize>,
    stats: &NeighborStats,
    active: &[bool],
) -> (f64, f64, f64) {
    let h_max = p.h[owned].iter().copied().fold(0.0, f64::max);
    if active.iter().any(|&a| a) {
        (stats.min_count as f64, stats.max_count as f64, h_max)
    } else {
        (f64::INFINITY, f64::NEG_INFINITY, h_max)
    }
}

/// Under self-gravity the domain also syncs (a new tree) once the
/// particles have drifted by this fraction of the halos' reach since the
/// last sync: the multipole acceptance widens each cell of the last
/// sync's tree by the drift (`sph_gravity::Targets::drift`), which costs
/// more interactions than a sync costs. Evrard to t = 1.0, block steps:
/// at -n 32 52 -> 96 syncs, gravity 10.2-10.9 -> 9.2-9.5 s, sync 0.12 ->
/// 0.21 s (0.02: 181 syncs, 0.1: 61, both slower).
const GRAVITY_SYNC_DRIFT: f64 = 0.05;

/// The pair driver over the lists of the active particles.
fn pair_driver<'a, K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    p: &'a Particles,
    list: &'a CompactNeighborList,
) -> Result<PairLoop<'a>, CoreError> {
    PairLoop::new(bbox, kernel.support(), [&p.x, &p.y, &p.z], &p.h, list)
}

/// The smallest bin among each target's neighbours (`r < support
/// max(h_i, h_j)`, the target itself left out).
struct NeighbourBins<'a> {
    h: &'a [f64],
    support: f64,
    bin: &'a [f64],
}

impl PairStage for NeighbourBins<'_> {
    type Sums = (F64s, F64s);
    type Out<'o> = [&'o mut [f64]; 1];
    type Stats = ();

    fn start(&self, g: &Group) -> Self::Sums {
        let reach = g.load(self.h) * self.support;
        (reach * reach, F64s::splat(f64::INFINITY))
    }

    fn pair(&self, s: &mut Self::Sums, j: usize, _d: [F64s; 3], r2: F64s) {
        let reach_j = self.h[j] * self.support;
        let (_, w) = neighbour_lanes(r2, s.0, reach_j * reach_j);
        let b = w
            .gt(F64s::splat(0.0))
            .select(F64s::splat(self.bin[j]), F64s::splat(f64::INFINITY));
        s.1 = s.1.min(b);
    }

    fn finish(&self, _g: &Group, s: Self::Sums, [out]: &mut Self::Out<'_>) {
        s.1.store(out);
    }
}

/// The limiter's wake-up: each active target lowers `wake[j]` of its
/// neighbours to its new bin plus `delta` (a minimum: the order of the
/// requests does not matter).
struct WakeUp<'a> {
    h: &'a [f64],
    support: f64,
    /// New bins of the owned particles, from `first`.
    new_bin: &'a [u8],
    first: usize,
    delta: u8,
    wake: &'a [AtomicU8],
    /// Per local particle: requests at or above it change nothing, so a
    /// group whose smallest request reaches it skips the partner (most
    /// pairs: neighbours' bins are within the factor already).
    limit: &'a [u8],
}

impl PairStage for WakeUp<'_> {
    /// Squared reach of the targets, the bin each asks of its neighbours
    /// (infinite in lanes without an active target), and the smallest.
    type Sums = (F64s, F64s, f64);
    type Out<'o> = [&'o mut [f64]; 0];
    type Stats = ();

    fn start(&self, g: &Group) -> Self::Sums {
        let reach = g.load(self.h) * self.support;
        let ask = std::array::from_fn(|l| {
            if l < g.valid && g.active & (1 << l) != 0 {
                f64::from(self.new_bin[g.first + l - self.first].saturating_add(self.delta))
            } else {
                f64::INFINITY
            }
        });
        let smallest = ask.iter().copied().fold(f64::INFINITY, f64::min);
        (reach * reach, F64s::from_array(ask), smallest)
    }

    fn pair(&self, s: &mut Self::Sums, j: usize, _d: [F64s; 3], r2: F64s) {
        if s.2 >= f64::from(self.limit[j]) {
            return;
        }
        let reach_j = self.h[j] * self.support;
        let (_, w) = neighbour_lanes(r2, s.0, reach_j * reach_j);
        let ask = w
            .gt(F64s::splat(0.0))
            .select(s.1, F64s::splat(f64::INFINITY))
            .min_lane();
        // An atomic operation only where the request lowers what is there.
        if ask.is_finite() {
            let ask = ask as u8;
            if ask < self.wake[j].load(Ordering::Relaxed) {
                self.wake[j].fetch_min(ask, Ordering::Relaxed);
            }
        }
    }

    fn finish(&self, _g: &Group, _s: Self::Sums, _out: &mut Self::Out<'_>) {}
}
