//! `Simulation`: the run loop. It steps a scene's pipeline and feeds the
//! output writers of [`crate::output`] (`conserved.csv`, `timings.csv`,
//! `profile.csv`, the plots, `particles.csv`, `summary.json`).
//!
//! Every observable of the final state is a distributed reduction over each
//! rank's own particles ([`crate::analysis`]); no rank ever holds all
//! particles.

use crate::analysis::{self, Bin, L1};
use crate::cases::{Reference, Scene, Share};
use crate::output::conserved::ConservedCsv;
use crate::output::curve::{CurveCsv, CurveObserver};
use crate::output::energies::EnergyTrack;
use crate::output::files::FileOutputs;
use crate::output::observer::{self, StepObserver, StepView};
use crate::output::progress::ProgressReporter;
use crate::output::snapshot as snapfile;
use crate::output::spectra::SpectraObserver;
use crate::output::timings::{RankTimings, StageTotals, TimingsCsv};
use crate::output::{particles, profile, summary};
use crate::watch::{self, Watch, WatchSummary};
use crate::AppError;
use serde::Serialize;
use sph_comm::{Communicator, ReduceOp, SerialComm};
use sph_core::{Conserved, Hydro, RunState, StepReport};
use sph_domain::DomainConfig;
use sph_kernels::FastKernel;
use std::path::Path;
use std::time::Instant;

pub use crate::output::energies::EnergyCheck;
pub use crate::output::files::{CheckpointEvery, IoSummary, Outputs, SnapshotFormat};
pub use crate::output::progress::{Progress, Stop};
pub use crate::output::timings::DomainSummary;
pub use crate::output::totals::BinSummary;

/// Everything the summary holds; written as `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Case name.
    pub case: String,
    /// Particle count.
    pub particles: usize,
    /// Steps run (sub-steps of a block-step run).
    pub steps: u64,
    /// How the particles shared time steps (`--time-steps`: global,
    /// block or kdk).
    pub time_steps: String,
    /// Particle updates over the run: particles times steps in a global
    /// run, the active particles summed over the sub-steps of a
    /// block-step run (since this process started or restarted the run).
    pub particle_updates: u64,
    /// `particle_updates / particles`: the global steps the run's work
    /// amounts to.
    pub full_step_equivalents: f64,
    /// Domain syncs (migration, sort, halos, tree rebuild): every step of
    /// a global run; under block steps only when particles have drifted
    /// past the halos' margin.
    pub domain_syncs: u64,
    /// Time reached.
    pub t_end: f64,
    /// Wall-clock seconds of the whole loop.
    pub wall_s: f64,
    /// Mean seconds per step over steps 2..N (step 1 holds set-up).
    pub mean_step_s: f64,
    /// particles / mean_step_s.
    pub particle_steps_per_s: f64,
    /// Peak resident memory of the process (the largest rank's), read
    /// after every output but this file was written; never below
    /// `solver_peak_rss_bytes` (some kernels, sandboxed ones among them,
    /// report a high-water mark that can fall).
    pub peak_rss_bytes: u64,
    /// Peak resident memory of the process (the largest rank's) at the end
    /// of the time-step loop, before the final observables and outputs:
    /// the solver's own peak.
    pub solver_peak_rss_bytes: u64,
    /// Particle arrays + neighbour lists + tree and scratch buffers, per particle.
    pub bytes_per_particle: f64,
    /// Worker threads.
    pub threads: usize,
    /// Kernel used.
    pub kernel: String,
    /// How the solver evaluates it (`power 6 of a polynomial of degree 7
    /// in v^2`, `table of 20000 points`).
    pub kernel_form: String,
    /// Mean neighbour count of the last step (self included).
    pub neighbors_mean: f64,
    /// Mean seconds per stage over steps 2..N.
    pub stage_seconds: std::collections::BTreeMap<String, f64>,
    /// Steps whose time step each criterion set (courant, divergence,
    /// acceleration, growth, cap).
    pub dt_limits: std::collections::BTreeMap<String, u64>,
    /// L1 errors against the reference (if any).
    pub l1: Option<L1>,
    /// `(E_end - E_0 - W) / (|E_0| + |W|)`, `W` the stirring's work over
    /// the run (0 without stirring: `(E_end - E_0) / |E_0|`).
    pub energy_rel_drift: f64,
    /// The stirring's work over the run (stirred runs only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub injected_work: Option<f64>,
    /// |p_end - p_0| / sum m |v| (a scale for round-off).
    pub momentum_rel_drift: f64,
    /// |L_end - L_0| / |L_0| (or over sum m |x||v| when L_0 ~ 0).
    pub angular_momentum_rel_drift: f64,
    /// Measured shock radius, blast cases: Sedov's the radius of the
    /// similarity solution closest to the particles' density
    /// ([`analysis::similarity_radius`]), Noh's where the binned density
    /// passes half-way to the shocked gas; a shock tube's shock position.
    pub shock_radius: Option<f64>,
    /// Reference shock radius.
    pub shock_radius_ref: Option<f64>,
    /// Highest particle density.
    pub peak_density: f64,
    /// Mean density in the post-shock plateau (Noh).
    pub plateau_density: Option<f64>,
    /// Expected plateau density (Noh: 64 rho0).
    pub plateau_density_ref: Option<f64>,
    /// Closest particle pair (square patch).
    pub min_pair_distance: f64,
    /// Initial and final angular momentum z (square patch).
    pub angular_momentum_z: [f64; 2],
    /// Energy updates that fell back to first order.
    pub energy_fallbacks: usize,
    /// MPI ranks (1 for a serial run).
    pub ranks: usize,
    /// Decomposition figures, means over steps 2..N.
    pub domain: DomainSummary,
    /// Energies against the case's reference table (times up to t_end;
    /// the run's values interpolated linearly between steps).
    pub energies: Vec<EnergyCheck>,
    /// Snapshot and checkpoint files written (absent when none were asked
    /// for).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub io: Option<IoSummary>,
    /// The run's watch of its conserved quantities: bounds, and the first
    /// step past each (see [`crate::watch`]).
    pub watch: WatchSummary,
    /// The time bins block steps would give the particles (`--report-bins`
    /// only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bins: Option<BinSummary>,
    /// Block time steps: the particles of each bin at the end of the run
    /// (bins holding none left out), longest steps first.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_bins: Option<Vec<TimeBin>>,
}

/// One bin of a block-step run's particles (`summary.json`, `time_bins`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TimeBin {
    /// The bin: steps of `2^bin` ticks.
    pub bin: u8,
    /// Its step.
    pub dt: f64,
    /// Particles in it (all ranks).
    pub particles: u64,
}

/// Whether a run of `hydro` has reached `stop`; if not, with an end time,
/// the next step is cut to land on it.
fn stop_reached<C: Communicator>(
    hydro: &mut Hydro<FastKernel, C>,
    stop: Stop,
    line_end: Option<f64>,
) -> bool {
    let t = hydro.time();
    match stop {
        // Block steps: the time line's end is the run's at the latest.
        Stop::Steps(s) => hydro.steps() >= s || line_end.is_some_and(|te| t >= te * (1.0 - 1e-12)),
        Stop::Time(te) if t >= te * (1.0 - 1e-12) => true,
        Stop::Time(te) => {
            hydro.limit_next_dt(te - t);
            false
        }
    }
}

/// A run in progress: the scene's particles (this rank's share) and the
/// pipeline.
#[derive(Debug)]
pub struct Simulation<C: Communicator = SerialComm> {
    scene: Scene,
    hydro: Hydro<FastKernel, C>,
    kernel_name: String,
    total: usize,
    write_particles: bool,
    rank_timings: bool,
    outputs: Outputs,
    resumed_at: Option<u64>,
    watch: Option<Watch>,
    after_step: Option<fn()>,
    /// The end of a block-step run's time line when it stops after a
    /// number of steps (`Stop::Time` ends it at its time).
    line_end: Option<f64>,
}

impl Simulation {
    /// Assembles the serial pipeline the scene needs with the given kernel
    /// table.
    pub fn new(scene: Scene, kernel: FastKernel, kernel_name: String) -> Result<Self, AppError> {
        Simulation::with_comm(scene, kernel, kernel_name, SerialComm::new())
    }

    /// [`Simulation::run`] of the serial pipeline, compiled once, here: a
    /// crate that calls this links the solver instead of compiling its own
    /// copy of it, as a call of the generic `run` would make it do
    /// (optimised builds share no generic code between crates).
    ///
    /// # Errors
    /// As [`Simulation::run`].
    pub fn run_serial(
        &mut self,
        stop: Stop,
        out: &Path,
        progress: Progress,
    ) -> Result<Summary, AppError> {
        self.run(stop, out, progress)
    }
}

#[cfg(feature = "mpi")]
impl Simulation<sph_comm::MpiComm> {
    /// [`Simulation::run`] on MPI ranks, compiled once, here (as
    /// [`Simulation::run_serial`]).
    ///
    /// # Errors
    /// As [`Simulation::run`].
    pub fn run_mpi(
        &mut self,
        stop: Stop,
        out: &Path,
        progress: Progress,
    ) -> Result<Summary, AppError> {
        self.run(stop, out, progress)
    }
}

impl<C: Communicator> Simulation<C> {
    /// Assembles the pipeline on one rank of `comm`. Each rank passes its
    /// share of the scene ([`Case::setup_share`](crate::cases::Case::setup_share)
    /// with this rank's [`Share`]), or the whole scene, of which it keeps
    /// its share; the first step migrates particles to their owners.
    ///
    /// # Errors
    /// A scene holding neither all particles nor this rank's share.
    pub fn with_comm(
        scene: Scene,
        kernel: FastKernel,
        kernel_name: String,
        comm: C,
    ) -> Result<Self, AppError> {
        Self::build(scene, kernel, kernel_name, comm, None)
    }

    /// Continues a run from a checkpoint: `scene` holds the checkpoint's
    /// particles (this rank's share, with their integrator history, see
    /// [`checkpoint::particles`](crate::checkpoint::particles)) and box, `state` its run state. Steps,
    /// time and every output go on from there; `conserved.csv` in the
    /// output folder keeps its lines up to the checkpoint's step.
    pub fn resume(
        scene: Scene,
        kernel: FastKernel,
        kernel_name: String,
        comm: C,
        state: RunState,
    ) -> Result<Self, AppError> {
        Self::build(scene, kernel, kernel_name, comm, Some(state))
    }

    fn build(
        scene: Scene,
        kernel: FastKernel,
        kernel_name: String,
        comm: C,
        resume: Option<RunState>,
    ) -> Result<Self, AppError> {
        let mut scene = scene;
        let total = scene.total;
        let share = Share {
            rank: comm.rank(),
            ranks: comm.size(),
        };
        let mine = share.range(total);
        let held = scene.particles.len();
        if held == total && mine.len() != total {
            scene.particles.keep(mine);
            scene.particles.shrink_to_fit();
        } else if held != mine.len() {
            return Err(AppError::Usage(format!(
                "rank {} of {}: the scene holds {held} particles, neither all {total} nor this rank's share of {}",
                share.rank,
                share.ranks,
                mine.len()
            )));
        }
        let (t0, dt0) = resume.map_or((0.0, scene.dt0), |s| (s.t, s.dt_prev));
        let scene_gravity = scene.config.gravity.is_some();
        let scene_block = scene.config.time_steps.on_time_line();
        let mut hydro =
            Hydro::with_comm(kernel, scene.config, t0, dt0, comm, DomainConfig::default())?;
        match resume {
            Some(state) => hydro
                .restore_run_state(state)
                .map_err(|e| AppError::Usage(e.to_string()))?,
            None => hydro.prepare(&mut scene.particles),
        }
        Ok(Self {
            scene,
            hydro,
            kernel_name,
            total,
            write_particles: false,
            rank_timings: false,
            after_step: None,
            line_end: None,
            outputs: Outputs::default(),
            resumed_at: resume.map(|s| s.step),
            watch: Some(Watch::new(
                watch::Bounds::for_run(scene_gravity, scene_block),
                false,
            )),
        })
    }

    /// Continues the driving of a resumed run from its checkpoint's state
    /// (`state`; `None` for a checkpoint without one).
    ///
    /// # Errors
    /// A stirred run resumed past its first step from a checkpoint without
    /// a driving state, a driving state given to a run that does not stir,
    /// or a state of the wrong size.
    pub fn restore_stirring(
        &mut self,
        state: Option<&crate::checkpoint::StirState>,
    ) -> Result<(), AppError> {
        let stirs = self.hydro.config().stirring.is_some();
        match state {
            Some(s) if stirs => Ok(self
                .hydro
                .restore_stirring(&self.scene.bbox, &s.phases, &s.rng)?),
            Some(_) => Err(AppError::Usage(
                "the checkpoint holds a stirring state but the run does not stir; restart with its --stir".into(),
            )),
            None if stirs && self.resumed_at.is_some_and(|k| k > 0) => Err(AppError::Usage(
                "the run stirs but the checkpoint holds no stirring state (stir_phases, stir_rng): it is of an unstirred run; give --stir off".into(),
            )),
            None => Ok(()),
        }
    }

    /// Snapshot and checkpoint outputs (none by default).
    ///
    /// # Errors
    /// A snapshot field this run does not have, named with those it has.
    pub fn set_outputs(&mut self, outputs: Outputs) -> Result<(), AppError> {
        if let Some((fields, _)) = &outputs.snapshots {
            let p = &self.scene.particles;
            for name in fields {
                if snapfile::field(p, 0..0, name).is_none() {
                    let have: Vec<&str> =
                        sph_core::fields::held(p.fields()).map(|f| f.name).collect();
                    return Err(AppError::Usage(format!(
                        "--snapshot-fields: this run has no field '{name}' (its scheme does not use it); it has: {}",
                        have.join(",")
                    )));
                }
            }
        }
        self.outputs = outputs;
        Ok(())
    }

    /// The run state of the pipeline (steps done, time, last step).
    pub fn run_state(&self) -> RunState {
        self.hydro.run_state()
    }

    /// The scene (this rank's particles at the current state, halos
    /// included after a step: see [`Simulation::owned`]).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Range of this rank's own particles in the scene's arrays.
    pub fn owned(&self) -> std::ops::Range<usize> {
        self.hydro.owned()
    }

    /// Whether this rank writes the outputs (rank 0).
    pub fn is_root(&self) -> bool {
        self.hydro.domain().comm().rank() == 0
    }

    /// Also write the final state of every particle (`particles.csv`: one
    /// row per particle in ascending id, shortest round-trip decimals, i.e.
    /// the exact bits; streamed to rank 0 in bounded chunks, see
    /// [`crate::output::particles`]).
    pub fn set_write_particles(&mut self, on: bool) {
        self.write_particles = on;
    }

    /// Also write every other rank's stage timings (`timings.rankR.csv`,
    /// the columns of `timings.csv`, which is rank 0's): where a
    /// multi-rank run waits. A pair stage that takes longer on one rank is
    /// imbalance; the `halos` and `conserved` columns of the others then
    /// hold their wait for it. A rank that cannot write its file warns and
    /// goes on without it (the run does not depend on a diagnostic).
    pub fn set_rank_timings(&mut self, on: bool) {
        self.rank_timings = on;
    }

    /// A function the loop calls after every step (none by default; the
    /// `sphexa` binary passes
    /// [`memory::return_free_heap_to_os`](crate::memory::return_free_heap_to_os),
    /// a process-wide allocator action a library must not take on its
    /// caller's behalf).
    pub fn set_after_step(&mut self, hook: Option<fn()>) {
        self.after_step = hook;
    }

    /// Where the time line of a block-step run that stops after a number
    /// of steps ends (a run to an end time ends its line there).
    pub fn set_time_line_end(&mut self, t_end: f64) {
        self.line_end = Some(t_end);
    }

    /// How the run watches its conserved quantities (default: the bounds
    /// of [`watch::Bounds::for_run`], warnings only); `None` turns the
    /// watch off.
    pub fn set_watch(&mut self, watch: Option<Watch>) {
        self.watch = watch;
    }

    /// Runs until `stop`, writing outputs into `out` (created if needed, by
    /// rank 0, which writes every file). Collective: every rank calls it.
    /// After every step the run's observers ([`StepObserver`]) write its
    /// lines and files in turn; an error stops the run with the files of
    /// the steps before it (and its last checkpoint) intact.
    ///
    /// Where the communicator allows it
    /// ([`Communicator::may_drive_from_pool`]), the loop runs on a worker
    /// of rayon's pool, so that its stages fork and join there instead of
    /// waking the pool from outside and sleeping until each stage ends
    /// (Evrard `-n 32`, 2 threads: block steps 19.2-21.0 -> 18.6-18.9 s,
    /// global steps 44.6 -> 39.5 s; the same output to the bit).
    pub fn run(&mut self, stop: Stop, out: &Path, progress: Progress) -> Result<Summary, AppError> {
        let on_pool = rayon::current_thread_index().is_some();
        if !on_pool && self.hydro.domain().comm().may_drive_from_pool() {
            rayon::scope(|_| self.run_here(stop, out, progress))
        } else {
            self.run_here(stop, out, progress)
        }
    }

    /// [`Simulation::run`] on the calling thread.
    fn run_here(
        &mut self,
        stop: Stop,
        out: &Path,
        progress: Progress,
    ) -> Result<Summary, AppError> {
        let root = self.is_root();
        let n = self.total;
        let mut outputs = self.open_outputs(stop, out, progress)?;
        if let Some(w) = self.watch.as_mut() {
            let all = 0..self.scene.particles.len();
            let eos = self.scene.config.eos;
            let comm = self.hydro.domain().comm();
            w.check_initial(
                &self.scene.particles,
                all,
                comm,
                root,
                &eos,
                &self.scene.bbox,
            )?;
        }
        // Block time steps: the run's end (a restored run keeps the line
        // of its checkpoint up to its next synchronisation point, which
        // is its first sub-step).
        let mut line_end = None;
        if self.scene.config.time_steps.on_time_line() {
            let end = match stop {
                Stop::Time(te) => Some(te),
                Stop::Steps(_) => self.line_end,
            };
            let end = end.ok_or_else(|| {
                AppError::Usage(
                    "block time steps need an end time for their time line: give --end-time with --steps".into(),
                )
            })?;
            self.hydro.set_time_line(end)?;
            line_end = Some(end);
        }
        let mut tally = Tally::new(n);
        let start = outputs.start;
        let mut observers = outputs.observers(self.watch.as_mut());
        while !stop_reached(&mut self.hydro, stop, line_end) {
            let r = self
                .hydro
                .step(&mut self.scene.particles, &mut self.scene.bbox)
                .map_err(|e| watch::locate(e, &self.scene.particles, self.hydro.owned()))?;
            if let Some(hook) = self.after_step {
                hook();
            }
            tally.record(&r);
            let view = StepView {
                report: &r,
                totals: &tally.totals,
                state: self.hydro.run_state(),
                particles: &self.scene.particles,
                owned: self.hydro.owned(),
                bbox: &self.scene.bbox,
                comm: self.hydro.domain().comm(),
                total: n,
                stirring: self.hydro.stirring(),
            };
            observer::notify(&mut observers, &view)?;
        }
        let wall_s = start.elapsed().as_secs_f64();
        observers.iter_mut().for_each(|o| o.ended(&tally.totals));
        let solver_peak_rss = self
            .hydro
            .domain()
            .comm()
            .all_reduce_scalar(analysis::peak_rss_bytes(), ReduceOp::Max);
        observers.iter_mut().try_for_each(|o| o.finish())?;
        drop(observers);

        let end = self.observe_end()?;
        tally.energies.push(end.t, &end.conserved);
        let io = outputs.files.any().then_some(outputs.files.summary);
        let mut summary = self.summary(&tally, &end, wall_s, solver_peak_rss, io);
        // Rank 0's files; an error is returned after the collectives below,
        // so that the other ranks do not wait for rank 0 forever.
        let written = match outputs.logs {
            Some((_, timings)) => {
                self.write_root_outputs(out, timings, &tally.totals, &end, &tally.energies)
            }
            None => Ok(()),
        };
        let comm = self.hydro.domain().comm();
        if self.write_particles {
            particles::write(
                &out.join("particles.csv"),
                &self.scene.particles,
                self.hydro.owned(),
                comm,
            )?;
        }
        summary.peak_rss_bytes = comm
            .all_reduce_scalar(analysis::peak_rss_bytes(), ReduceOp::Max)
            .max(solver_peak_rss);
        written?;
        if root {
            summary::write(&out.join("summary.json"), &summary)?;
        }
        Ok(summary)
    }

    /// Opens the outputs of a run into `out`: rank 0's `conserved.csv` and
    /// `timings.csv` (continued after a restart's step), this rank's own
    /// timings with [`set_rank_timings`](Self::set_rank_timings), the
    /// progress report, the case's curve and the snapshot and checkpoint
    /// files.
    fn open_outputs(
        &self,
        stop: Stop,
        out: &Path,
        progress: Progress,
    ) -> Result<RunOutputs, AppError> {
        let root = self.is_root();
        let mut logs = None;
        if root {
            std::fs::create_dir_all(out).map_err(|e| AppError::io(out, e))?;
            let path = out.join("conserved.csv");
            let driven = self.hydro.config().stirring.is_some();
            logs = Some((
                match self.resumed_at {
                    Some(step) => ConservedCsv::resume(&path, step, driven)?,
                    None => ConservedCsv::create(&path, driven)?,
                },
                TimingsCsv::create(&out.join("timings.csv"))?,
            ));
        }
        let rank = self.hydro.domain().comm().rank();
        let rank_log = (self.rank_timings && !root).then(|| RankTimings::open(out, rank));
        let bar = ProgressReporter::new(if root { progress } else { Progress::Quiet }, stop);
        let start = Instant::now();
        let t0 = match self.resumed_at {
            Some(_) => self.hydro.time(),
            None => f64::NEG_INFINITY,
        };
        let curve = match self.scene.curve {
            Some(c) => {
                let path = out.join("curve.csv");
                let file = match (root, self.resumed_at) {
                    (false, _) => None,
                    (true, Some(step)) => Some(CurveCsv::resume(&path, c, step)?),
                    (true, None) => Some(CurveCsv::create(&path, c)?),
                };
                let title = format!("{}, {} particles", self.scene.case, self.total);
                Some(CurveObserver::new(c, file, (out.join("curve.png"), title)))
            }
            None => None,
        };
        let spectra = self
            .outputs
            .spectra_every_time
            .map(|dt| SpectraObserver::new(dt, t0, root.then(|| out.join("spectra"))));
        let fixed_h = self.scene.config.scheme.fixed_h;
        let files = FileOutputs::new(&self.outputs, self.scene.case, out, t0, fixed_h)?;
        if files.any() && root {
            files.create_dirs()?;
        }
        Ok(RunOutputs {
            logs,
            rank_log,
            bar,
            start,
            curve,
            spectra,
            files,
        })
    }

    /// The summary of the run that `tally` recorded, ending in `end`.
    fn summary(
        &self,
        tally: &Tally,
        end: &EndState,
        wall_s: f64,
        solver_peak_rss: u64,
        io: Option<IoSummary>,
    ) -> Summary {
        let n = self.total;
        let totals = &tally.totals;
        let work_end = self.hydro.run_state().external_work;
        let (first, work_first) = tally.first.unwrap_or((end.conserved, work_end));
        // What the stirring did over the run (0 unstirred: then the drift
        // below is (E_end - E_0) / |E_0| to the bit).
        let work = work_end - work_first;
        let mean_step_s = totals.mean_step_s();
        let per_particle = |x: f64| x / n.max(1) as f64;
        let norm = |v: [f64; 3]| nalgebra::Vector3::from(v).norm();
        let dp = norm(std::array::from_fn(|k| {
            end.conserved.momentum[k] - first.momentum[k]
        }));
        let l0 = first.angular_momentum;
        let dl = norm(std::array::from_fn(|k| {
            end.conserved.angular_momentum[k] - l0[k]
        }));
        let [scale_p, l_abs] = end.drift_scales;
        // A scale for round-off: sum m |x||v| (at the end), unless the
        // initial angular momentum is itself significant.
        let l_scale = if norm(l0) > 1e-6 * l_abs {
            norm(l0)
        } else {
            l_abs
        };
        Summary {
            case: self.scene.case.to_string(),
            particles: n,
            steps: self.hydro.steps(),
            time_steps: sph_core::Choice::name(&self.scene.config.time_steps).to_owned(),
            particle_updates: self.hydro.particle_updates(),
            full_step_equivalents: self.hydro.particle_updates() as f64 / n.max(1) as f64,
            domain_syncs: self.hydro.domain_syncs(),
            t_end: end.t,
            wall_s,
            mean_step_s,
            particle_steps_per_s: n as f64 / mean_step_s,
            peak_rss_bytes: 0,
            solver_peak_rss_bytes: solver_peak_rss,
            bytes_per_particle: per_particle(end.buffer_bytes as f64),
            threads: rayon::current_num_threads(),
            kernel: self.kernel_name.clone(),
            kernel_form: self.hydro.kernel().describe(),
            neighbors_mean: tally
                .neighbors_total
                .map_or(0.0, |t| per_particle(t as f64)),
            stage_seconds: totals.stage_seconds(),
            dt_limits: totals.dt_limits(),
            bins: totals.bins(),
            time_bins: self.time_bins(),
            l1: end.l1,
            energy_rel_drift: (end.conserved.e_tot() - first.e_tot() - work)
                / (watch::energy_scale(&first, self.watch.as_ref().and_then(Watch::thermal_scale))
                    + work.abs()),
            injected_work: self.hydro.config().stirring.map(|_| work),
            momentum_rel_drift: if scale_p > 0.0 { dp / scale_p } else { dp },
            angular_momentum_rel_drift: if l_scale > 0.0 { dl / l_scale } else { dl },
            shock_radius: end.shock_radius,
            shock_radius_ref: end.shock_radius_ref,
            peak_density: end.peak_density,
            plateau_density: end.plateau,
            plateau_density_ref: end.plateau_ref,
            min_pair_distance: end.min_pair_distance,
            angular_momentum_z: [first.angular_momentum[2], end.conserved.angular_momentum[2]],
            energy_fallbacks: tally.fallbacks,
            ranks: self.hydro.domain().comm().size(),
            domain: totals.domain(),
            energies: tally
                .energies
                .checks(self.scene.energies.unwrap_or(&[]), end.t),
            io,
            watch: self
                .watch
                .as_ref()
                .map_or_else(WatchSummary::default, Watch::summary),
        }
    }

    /// The histogram of the particles' bins of a block-step run (all
    /// ranks; collective), none in a global run.
    fn time_bins(&self) -> Option<Vec<TimeBin>> {
        let line = self.hydro.time_line()?;
        let p = &self.scene.particles;
        if p.bin.len() != p.len() {
            return None;
        }
        let top = usize::from(sph_core::timeline::MAX_BIN);
        let mut counts = vec![0.0; top + 1];
        for i in self.hydro.owned() {
            counts[(p.bin[i] as usize).min(top)] += 1.0;
        }
        // Counts below 2^53: exact in f64 sums.
        self.hydro
            .domain()
            .comm()
            .all_reduce(&mut counts, ReduceOp::Sum);
        Some(
            counts
                .iter()
                .enumerate()
                .rev()
                .filter(|(_, &c)| c > 0.0)
                .map(|(b, &c)| TimeBin {
                    bin: b as u8,
                    dt: line.dt(sph_core::timeline::Bin(b as u8)),
                    particles: c as u64,
                })
                .collect(),
        )
    }

    /// Rank 0's files at the end of a run: the last line of `timings.csv`,
    /// the profile and the energy plot.
    fn write_root_outputs(
        &self,
        out: &Path,
        timings: TimingsCsv,
        totals: &StageTotals,
        end: &EndState,
        energies: &EnergyTrack,
    ) -> Result<(), AppError> {
        let (case, n) = (self.scene.case, self.total);
        timings.finish(totals)?;
        let title = format!("{case}, {n} particles, t = {:.4}", end.t);
        profile::write(out, &end.bins, &title)?;
        if self.scene.config.gravity.is_some() || self.scene.energies.is_some() {
            energies.plot(
                &out.join("energies.png"),
                &format!("{case}, {n} particles"),
                self.scene.energies.unwrap_or(&[]),
            )?;
        }
        Ok(())
    }

    /// Recomputes density and pressure at the final positions, then every
    /// observable of the final state, each reduced over the ranks.
    fn observe_end(&mut self) -> Result<EndState, AppError> {
        let t = self.hydro.time();
        self.hydro
            .evaluate_closed(&mut self.scene.particles, &mut self.scene.bbox)?;
        let p = &self.scene.particles;
        let owned = self.hydro.owned();
        let comm = self.hydro.domain().comm();
        let min_pair_distance =
            analysis::min_pair_distance(p, self.hydro.neighbor_list(), &self.scene.bbox, comm);
        let local_bytes = (p.bytes_per_particle() * owned.len() + self.hydro.buffer_bytes()) as u64;
        let buffer_bytes = comm.all_reduce_scalar(local_bytes, ReduceOp::Sum);
        let (conserved, []) = Conserved::compute(p, owned.clone(), [], comm);
        let reference = self.scene.reference.as_ref();
        // Radial bins out to the half-width of the (final) box, which every
        // case centres on the origin.
        let [lx, ly, lz] = self.scene.bbox.lengths();
        let r_max = 0.5 * lx.max(ly).max(lz);
        let bins = analysis::radial_profile(p, owned.clone(), comm, reference, t, r_max, 100);
        let (shock_radius, shock_radius_ref, plateau, plateau_ref) = match reference {
            Some(Reference::Sedov(s)) => (
                Some(analysis::similarity_radius(p, owned.clone(), comm, s, t)),
                Some(s.shock_radius(t)),
                None,
                None,
            ),
            Some(Reference::Noh(nh)) => {
                let rs = nh.shock_radius(t);
                let shell = analysis::mean_density_in_shell(
                    p,
                    owned.clone(),
                    comm,
                    reference,
                    [0.3 * rs, 0.8 * rs],
                );
                // The shock where the binned density passes half-way from
                // the inflow just outside it to the shocked gas.
                let post = nh.shocked_density();
                let level = 0.5 * (nh.state(rs * (1.0 + 1e-9), t).rho + post);
                (
                    Some(analysis::front_position(&bins, level)),
                    Some(rs),
                    Some(shell),
                    Some(post),
                )
            }
            Some(Reference::Tube(tube)) => {
                // The shock where the binned density passes half-way from
                // the outer gas to the shocked gas; the plateau is the
                // middle half of the shocked gas (contact to shock).
                let rho_outer = tube.riemann.state(1.0, 0.0).rho;
                let rho_shocked = tube.riemann.rho_star().1;
                let level = 0.5 * (rho_outer + rho_shocked);
                let (contact, shock) = (tube.contact_position(t), tube.shock_position(t));
                let gap = shock - contact;
                let shell = analysis::mean_density_in_shell(
                    p,
                    owned.clone(),
                    comm,
                    reference,
                    [contact + 0.25 * gap, shock - 0.25 * gap],
                );
                (
                    Some(analysis::front_position(&bins, level)),
                    Some(shock),
                    Some(shell),
                    Some(rho_shocked),
                )
            }
            Some(Reference::Vortex(_) | Reference::Stationary(_)) | None => {
                (None, None, None, None)
            }
        };
        Ok(EndState {
            t,
            conserved,
            l1: reference.map(|rf| analysis::l1(p, owned.clone(), comm, rf, t)),
            shock_radius,
            shock_radius_ref,
            plateau,
            plateau_ref,
            peak_density: analysis::peak_density(p, owned.clone(), comm),
            min_pair_distance,
            drift_scales: analysis::drift_scales(p, owned, comm),
            buffer_bytes,
            bins,
        })
    }
}

/// The outputs of a run in progress, opened by
/// [`Simulation::open_outputs`].
#[derive(Debug)]
struct RunOutputs {
    /// Rank 0's `conserved.csv` and `timings.csv`.
    logs: Option<(ConservedCsv, TimingsCsv)>,
    /// This rank's own timings (ranks but 0, with `--rank-timings`).
    rank_log: Option<RankTimings>,
    bar: ProgressReporter,
    /// When the loop's clock started (`wall_s` of the summary).
    start: Instant,
    curve: Option<CurveObserver>,
    spectra: Option<SpectraObserver>,
    files: FileOutputs,
}

impl RunOutputs {
    /// The observers of every step, in the order they see it: the lines
    /// of the step, the watch, the progress report, then the files due.
    fn observers<'a, C: Communicator>(
        &'a mut self,
        watch: Option<&'a mut Watch>,
    ) -> Vec<Box<dyn StepObserver<C> + 'a>> {
        let mut list: Vec<Box<dyn StepObserver<C> + 'a>> = Vec::new();
        if let Some(r) = self.rank_log.as_mut() {
            list.push(Box::new(r));
        }
        if let Some((conserved, timings)) = self.logs.as_mut() {
            list.push(Box::new(conserved));
            list.push(Box::new(timings));
        }
        if let Some(c) = self.curve.as_mut() {
            list.push(Box::new(c));
        }
        if let Some(s) = self.spectra.as_mut() {
            list.push(Box::new(s));
        }
        if let Some(w) = watch {
            list.push(Box::new(w));
        }
        list.push(Box::new(&mut self.bar));
        list.push(Box::new(&mut self.files));
        list
    }
}

/// What the summary takes from the steps of a run.
#[derive(Debug)]
struct Tally {
    /// The conserved quantities at the first step, and the stirring's
    /// work up to it.
    first: Option<(Conserved, f64)>,
    /// Energies of every step.
    energies: EnergyTrack,
    /// Stage times and decomposition figures.
    totals: StageTotals,
    /// Energy updates that fell back to first order.
    fallbacks: usize,
    /// Neighbours of the last step.
    neighbors_total: Option<usize>,
}

impl Tally {
    /// Nothing recorded yet, for `n` particles.
    fn new(n: usize) -> Self {
        Self {
            first: None,
            energies: EnergyTrack::new(),
            totals: StageTotals::new(n),
            fallbacks: 0,
            neighbors_total: None,
        }
    }

    /// Records step `r`.
    fn record(&mut self, r: &StepReport) {
        self.first.get_or_insert((r.conserved, r.external_work));
        self.energies.push(r.t, &r.conserved);
        self.totals.record(r);
        self.fallbacks += r.energy_fallbacks;
        self.neighbors_total = Some(r.neighbors.total);
    }
}

/// The observables of a run's final state, the same on every rank.
#[derive(Debug)]
struct EndState {
    /// Time.
    t: f64,
    /// Energies, momentum, angular momentum (exact sums).
    conserved: Conserved,
    /// Radial profile.
    bins: Vec<Bin>,
    /// L1 errors against the reference.
    l1: Option<L1>,
    /// The measured shock radius (Sedov: [`analysis::similarity_radius`]; Noh and tubes: where the density passes half-way).
    shock_radius: Option<f64>,
    /// Reference shock radius.
    shock_radius_ref: Option<f64>,
    /// Mean density in the shocked shell (Noh).
    plateau: Option<f64>,
    /// Expected plateau density.
    plateau_ref: Option<f64>,
    /// Highest density.
    peak_density: f64,
    /// Closest pair.
    min_pair_distance: f64,
    /// `[sum m |v|, sum m |x||v|]`.
    drift_scales: [f64; 2],
    /// Particle arrays and solver buffers, all ranks.
    buffer_bytes: u64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases;
    use sph_comm::run_ranks;
    use sph_core::HydroConfig;
    use sph_kernels::KernelChoice;

    /// A small case with its own scheme.
    fn scene(case: &str) -> Scene {
        cases::lookup(case)
            .and_then(|c| c.setup(12, HydroConfig::default()))
            .expect("set-up")
    }

    /// Runs `case` for 4 steps on `ranks` in-process ranks; rank 0's
    /// summary and output folder.
    fn run(case: &str, ranks: usize) -> (Summary, std::path::PathBuf) {
        let out = crate::test_dir(&format!("simulation-{case}-{ranks}"));
        let summaries = run_ranks(ranks, |comm| {
            let kernel = KernelChoice::default().fast().expect("kernel");
            let mut sim = Simulation::with_comm(scene(case), kernel, "default".into(), comm)
                .expect("pipeline");
            sim.set_write_particles(true);
            sim.set_rank_timings(true);
            sim.run(Stop::Steps(4), &out, Progress::Quiet).expect("run")
        });
        (summaries.into_iter().next().expect("rank 0"), out)
    }

    /// The observables (all reductions over the ranks) and the files are
    /// the same on 1 and 2 ranks, to the bit.
    #[test]
    fn outputs_do_not_depend_on_the_rank_count() {
        for case in ["sedov", "noh"] {
            let (a, dir_a) = run(case, 1);
            let (b, dir_b) = run(case, 2);
            assert_eq!((a.ranks, b.ranks), (1, 2));
            assert_eq!(a.particles, b.particles);
            let figures = |s: &Summary| {
                let l1 = s.l1.expect("reference");
                [
                    l1.rho,
                    l1.p,
                    l1.v,
                    s.shock_radius.unwrap_or(0.0),
                    s.plateau_density.unwrap_or(0.0),
                    s.peak_density,
                    s.min_pair_distance,
                    s.energy_rel_drift,
                    s.momentum_rel_drift,
                    s.angular_momentum_rel_drift,
                    s.angular_momentum_z[1],
                ]
                .map(f64::to_bits)
            };
            assert_eq!(figures(&a), figures(&b), "{case}: {a:?}\n{b:?}");
            assert!(a.peak_density.is_finite() && a.min_pair_distance > 0.0);
            assert!(a.shock_radius.is_some(), "{case}: shock");
            assert_eq!(a.plateau_density.is_some(), case == "noh");
            // One serial rank drives its loop from rayon's pool (the
            // in-process ranks from their own threads): the same files.
            let dir_s = crate::test_dir(&format!("simulation-{case}-serial"));
            let kernel = KernelChoice::default().fast().expect("kernel");
            let mut serial =
                Simulation::new(scene(case), kernel, "default".into()).expect("pipeline");
            assert!(serial.hydro.domain().comm().may_drive_from_pool());
            serial.set_write_particles(true);
            serial
                .run(Stop::Steps(4), &dir_s, Progress::Quiet)
                .expect("run");
            for file in ["conserved.csv", "profile.csv", "particles.csv"] {
                let read = |d: &Path| std::fs::read(d.join(file)).expect("output");
                assert!(read(&dir_a) == read(&dir_b), "{case}: {file} differs");
                assert!(
                    read(&dir_a) == read(&dir_s),
                    "{case}: {file} differs on the pool"
                );
            }
            std::fs::remove_dir_all(dir_s).ok();
            // particles.csv: every particle once, in id order.
            let text = std::fs::read_to_string(dir_a.join("particles.csv")).expect("output");
            let ids: Vec<u64> = text
                .lines()
                .skip(1)
                .map(|l| l.split(',').next().unwrap().parse().unwrap())
                .collect();
            assert_eq!(ids, (0..a.particles as u64).collect::<Vec<_>>(), "{case}");
            // Rank 1's timings: the steps and the means of timings.csv.
            let lines = |d: &Path, f: &str| {
                std::fs::read_to_string(d.join(f)).map(|t| {
                    t.lines()
                        .map(|l| l.split(',').next().unwrap_or("").to_string())
                        .collect::<Vec<_>>()
                })
            };
            let rank1 = lines(&dir_b, "timings.rank1.csv").expect("rank 1's timings");
            assert_eq!(rank1, lines(&dir_b, "timings.csv").expect("timings"));
            assert_eq!(rank1.len(), 6, "{case}: header, 4 steps, means");
            assert!(!dir_a.join("timings.rank0.csv").exists());
            // The summary reports the process peak, at least the solver's
            // (where /proc tells it).
            assert!(a.peak_rss_bytes >= a.solver_peak_rss_bytes);
            if Path::new("/proc/self/status").exists() {
                assert!(a.solver_peak_rss_bytes > 0, "{case}: no peak read");
            }
            for d in [dir_a, dir_b] {
                std::fs::remove_dir_all(d).ok();
            }
        }
    }
}
