//! One SPH-EXA time step on one node: sort, tree, neighbours, density,
//! EOS, IAD, momentum and energy, time step, integration.

use crate::conserved::Conserved;
use crate::density::{density, Positions};
use crate::eos::Eos;
use crate::iad::iad;
use crate::integrate::{integrate, HUpdate};
use crate::momentum::{momentum_energy, Gradients, HydroState, MomentumStats, PairFactors, Rates};
use crate::neighbors::{find_neighbors, NeighborParams};
use crate::timestep::TimestepParams;
use crate::{CoreError, Particles};
use sph_kernels::Kernel;
use sph_tree::{
    compute_keys, Boundary, BoundingBox, CompactNeighborList, Curve, KeySorter, NeighborStats,
    Octree,
};
use std::time::Instant;

/// Everything that defines the hydrodynamics scheme.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HydroConfig {
    /// Equation of state.
    pub eos: Eos,
    /// IAD or plain kernel gradients.
    pub gradients: Gradients,
    /// Artificial viscosity strength.
    pub alpha: f64,
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
    /// Whether the grad-h factor Omega enters the equations (its field is
    /// only allocated then).
    pub grad_h: bool,
}

impl Default for HydroConfig {
    fn default() -> Self {
        Self {
            eos: Eos::IdealGas { gamma: 5.0 / 3.0 },
            gradients: Gradients::Iad,
            alpha: 1.0,
            neighbors: NeighborParams::default(),
            h_update: HUpdate::default(),
            timestep: TimestepParams::default(),
            curve: Curve::Hilbert,
            bucket: 16,
            grad_h: true,
        }
    }
}

/// Names of the timed stages, in pipeline order.
pub const STAGES: [&str; 9] = [
    "sort",
    "tree",
    "neighbors",
    "density",
    "eos",
    "iad",
    "momentum",
    "conserved",
    "integrate",
];

/// Wall-clock seconds per stage, accumulated.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageTimes(pub [f64; 9]);

impl StageTimes {
    /// Sum over stages.
    pub fn total(&self) -> f64 {
        self.0.iter().sum()
    }
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
    /// Conserved quantities at `t`.
    pub conserved: Conserved,
    /// Neighbour statistics of this step.
    pub neighbors: NeighborStats,
    /// Seconds per stage in this step.
    pub times: StageTimes,
    /// Energy updates that fell back to first order.
    pub energy_fallbacks: usize,
}

/// The single-node hydro pipeline with its reusable buffers.
#[derive(Debug)]
pub struct Hydro<K: Kernel> {
    kernel: K,
    config: HydroConfig,
    tree: Octree,
    list: CompactNeighborList,
    factors: PairFactors,
    keys: Vec<u64>,
    perm: Vec<u32>,
    sorter: KeySorter,
    scratch: Vec<u64>,
    step: u64,
    t: f64,
    dt_prev: f64,
    dt_cap: f64,
}

impl<K: Kernel> Hydro<K> {
    /// A pipeline at time `t0`, whose previous step is taken as `dt0` (the
    /// first step is at most `max_growth * dt0`). Initial conditions must
    /// have `dx = v dt0` and `du_prev = du` (see [`Hydro::prepare`]).
    pub fn new(kernel: K, config: HydroConfig, t0: f64, dt0: f64) -> Result<Self, CoreError> {
        config.eos.validate()?;
        if !(dt0 > 0.0 && dt0.is_finite()) {
            return Err(CoreError::Invalid(format!(
                "first time step {dt0} must be positive"
            )));
        }
        if config.bucket == 0 {
            return Err(CoreError::Invalid("bucket size must be at least 1".into()));
        }
        Ok(Self {
            kernel,
            config,
            tree: Octree::default(),
            list: CompactNeighborList::new(),
            factors: PairFactors::default(),
            keys: Vec::new(),
            perm: Vec::new(),
            sorter: KeySorter::new(),
            scratch: Vec::new(),
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
    }

    /// The scheme.
    pub fn config(&self) -> &HydroConfig {
        &self.config
    }

    /// Current time.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Steps done.
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// Caps the next step (to land exactly on an output or end time).
    pub fn limit_next_dt(&mut self, dt_max: f64) {
        self.dt_cap = dt_max;
    }

    /// The last step size.
    pub fn dt_prev(&self) -> f64 {
        self.dt_prev
    }

    /// The neighbour lists of the last step.
    pub fn neighbor_list(&self) -> &CompactNeighborList {
        &self.list
    }

    /// Bytes held by the pipeline's buffers (tree, neighbour lists, keys,
    /// permutation, scratch), for memory reports.
    pub fn buffer_bytes(&self) -> usize {
        self.list.bytes()
            + self.factors.bytes()
            + self.keys.capacity() * 8
            + self.perm.capacity() * 4
            + self.scratch.capacity() * 8
            + self.tree.num_nodes() * 90
    }

    /// Advances `p` by one step. Open axes of `bbox` are refitted to the
    /// particles first; periodic axes stay.
    pub fn step(
        &mut self,
        p: &mut Particles,
        bbox: &mut BoundingBox,
    ) -> Result<StepReport, CoreError> {
        let step = self.step + 1;
        let n = p.len();
        let mut times = StageTimes::default();
        let mut clock = Instant::now();
        let mut lap = |k: usize, times: &mut StageTimes| {
            let now = Instant::now();
            times.0[k] += (now - clock).as_secs_f64();
            clock = now;
        };

        self.sort(p, bbox)?;
        lap(0, &mut times);
        self.tree
            .rebuild(&self.keys, &p.x, &p.y, &p.z, self.config.bucket)?;
        lap(1, &mut times);
        let stats = self.search(p, bbox, step)?;
        lap(2, &mut times);
        self.density(p, bbox);
        lap(3, &mut times);
        self.eos(p)?;
        lap(4, &mut times);

        let pos = Positions {
            x: &p.x,
            y: &p.y,
            z: &p.z,
            h: &p.h,
            m: &p.m,
        };
        if self.config.gradients == Gradients::Iad {
            if let Err(s) = iad(&self.kernel, bbox, pos, &p.rho, &self.list, &mut p.iad) {
                return Err(CoreError::SingularIad {
                    step,
                    id: p.id[s.index],
                    det: s.det,
                    neighbors: self.list.count(s.index),
                });
            }
        }
        lap(5, &mut times);

        let iad_ref: [&[f64]; 6] = std::array::from_fn(|k| p.iad[k].as_slice());
        let state = HydroState {
            pos,
            vx: &p.vx,
            vy: &p.vy,
            vz: &p.vz,
            rho: &p.rho,
            p: &p.p,
            c: &p.c,
            omega: &p.omega,
            iad: iad_ref,
        };
        self.factors.fill(&state);
        let rates = Rates {
            ax: &mut p.ax,
            ay: &mut p.ay,
            az: &mut p.az,
            du: &mut p.du,
        };
        let mstats: MomentumStats = momentum_energy(
            &self.kernel,
            bbox,
            state,
            &self.factors,
            self.config.gradients,
            self.config.alpha,
            &self.list,
            rates,
        );
        if step == 1 {
            // Adams-Bashforth needs du_{n-1}; the first step uses du_0.
            p.du_prev.copy_from_slice(&p.du);
        }
        lap(6, &mut times);

        let conserved = Conserved::compute(p, n);
        lap(7, &mut times);

        let dt = self
            .config
            .timestep
            .dt(&mstats, self.dt_prev)
            .min(self.dt_cap);
        self.dt_cap = f64::INFINITY;
        let h_update = self.config.neighbors.h_update(self.config.h_update);
        let guard = self.config.eos.uses_internal_energy();
        let report = integrate(p, bbox, dt, self.dt_prev, Some(h_update), guard, step)?;
        lap(8, &mut times);

        let t = self.t;
        self.t += dt;
        self.dt_prev = dt;
        self.step = step;
        Ok(StepReport {
            step,
            t,
            dt,
            conserved,
            neighbors: stats,
            times,
            energy_fallbacks: report.energy_fallbacks,
        })
    }
}

impl<K: Kernel> Hydro<K> {
    /// Recomputes neighbours, density and pressure at the current positions
    /// without advancing (for observables at the end of a run).
    pub fn evaluate_density(
        &mut self,
        p: &mut Particles,
        bbox: &mut BoundingBox,
    ) -> Result<(), CoreError> {
        self.sort(p, bbox)?;
        self.tree
            .rebuild(&self.keys, &p.x, &p.y, &p.z, self.config.bucket)?;
        self.search(p, bbox, self.step)?;
        self.density(p, bbox);
        self.eos(p)
    }

    /// Refits open axes, computes keys and puts the particles in curve order.
    fn sort(&mut self, p: &mut Particles, bbox: &mut BoundingBox) -> Result<(), CoreError> {
        refit_open_axes(bbox, p)?;
        compute_keys(bbox, self.config.curve, &p.x, &p.y, &p.z, &mut self.keys);
        self.sorter.sort(&self.keys, Some(&p.id), &mut self.perm);
        p.reorder(&self.perm, &mut self.scratch);
        sph_tree::apply_permutation(&self.perm, &mut self.keys, &mut self.scratch);
        Ok(())
    }

    /// Neighbour lists of every particle, with the h iteration.
    fn search(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        step: u64,
    ) -> Result<NeighborStats, CoreError> {
        let n = p.len();
        find_neighbors(
            &self.config.neighbors,
            self.config.h_update,
            &self.tree,
            bbox,
            &p.x,
            &p.y,
            &p.z,
            &mut p.h,
            &p.id,
            0..n,
            &mut self.list,
            &mut p.nc,
            step,
        )
    }

    /// Density and grad-h factor.
    fn density(&self, p: &mut Particles, bbox: &BoundingBox) {
        let pos = Positions {
            x: &p.x,
            y: &p.y,
            z: &p.z,
            h: &p.h,
            m: &p.m,
        };
        density(
            &self.kernel,
            bbox,
            pos,
            &self.list,
            &mut p.rho,
            &mut p.omega,
        );
    }

    /// Pressure and sound speed; an EOS with a per-particle reference state
    /// calibrates reference densities left at zero to the current density.
    fn eos(&self, p: &mut Particles) -> Result<(), CoreError> {
        let n = p.len();
        let reference = if self.config.eos.needs_reference() {
            if p.eos_ref[0].len() != n || p.eos_ref[1].len() != n {
                return Err(CoreError::Invalid(format!(
                    "equation of state {:?} needs per-particle reference density and pressure (eos_ref) for all {n} particles",
                    self.config.eos
                )));
            }
            for i in 0..n {
                if p.eos_ref[0][i] == 0.0 {
                    p.eos_ref[0][i] = p.rho[i];
                }
            }
            Some((p.eos_ref[0].as_slice(), p.eos_ref[1].as_slice()))
        } else {
            None
        };
        self.config
            .eos
            .apply(&p.rho, &p.u, reference, &mut p.p, &mut p.c);
        Ok(())
    }
}

/// Refits the open axes of `bbox` to the particles (periodic axes keep
/// their bounds).
pub fn refit_open_axes(bbox: &mut BoundingBox, p: &Particles) -> Result<(), CoreError> {
    let b = bbox.boundary();
    if b.iter().all(|&k| k == Boundary::Periodic) || p.is_empty() {
        return Ok(());
    }
    let fit = BoundingBox::enclosing(&p.x, &p.y, &p.z)?;
    let (mut lo, mut hi) = (bbox.lo(), bbox.hi());
    for k in 0..3 {
        if b[k] == Boundary::Open {
            lo[k] = fit.lo()[k];
            hi[k] = fit.hi()[k];
        }
    }
    *bbox = BoundingBox::new(lo, hi, b)?;
    Ok(())
}
