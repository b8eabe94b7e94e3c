//! Every run watches itself: the conserved quantities of each step are
//! checked against bounds ([`Bounds`]); the first step past a bound is
//! warned about once on the terminal and recorded in `summary.json`, and a
//! strict run ([`Watch::strict`]) stops there with an error naming the
//! quantity, the step and, where one particle can be blamed, that
//! particle's id and position.
//!
//! The per-step check reads only the step's [`Conserved`] sums, which every
//! rank already has, so it costs no communication; the reductions that find
//! the particle to blame run only on the step that crosses a bound. The
//! energy drift `E - E_0 - W` is measured against `|E_0|`, or, where the
//! equation of state fixes u by the density (isothermal, polytropic: an
//! internal energy with an arbitrary zero), against the gas's thermal
//! energy `sum m c^2` (one sum at the first step; [`energy_scale`]).
//!
//! The initial particles are checked too ([`Watch::check_initial`]): a
//! non-finite position, velocity, mass, smoothing length or internal energy,
//! a smoothing length <= 0 or a negative internal energy stops the run with
//! the particle named; a mass <= 0 is a violation of `particle mass` (a
//! warning, an error with `strict`).

use crate::analysis::exact_sums;
use crate::output::observer::{Observed, StepObserver, StepView};
use crate::AppError;
use serde::Serialize;
use sph_comm::{Communicator, ReduceOp};
use sph_core::{Conserved, CoreError, Particles, StepReport};
use std::ops::Range;

/// The bounds a run is held to.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bounds {
    /// Largest relative total-energy drift `|E - E_0| / |E_0|`.
    pub energy: f64,
    /// Largest momentum drift `|p - p_0|` relative to the momentum scale,
    /// the largest `sqrt(2 M (E_kin + |E_int|))` so far: at least
    /// `sum m |v|`, and `M` times a thermal speed, so that a fluid at rest
    /// (whose velocities are themselves round-off) is measured against its
    /// sound speed.
    pub momentum: f64,
}

/// The default momentum bound of runs with self-gravity: the tree's
/// multipole forces are not pairwise antisymmetric, so momentum is
/// conserved to the tree's accuracy (measured: Evrard at 912 particles,
/// 1.8e-9 after 2 steps and 5.3e-6 after 150), not to round-off.
pub const GRAVITY_MOMENTUM_BOUND: f64 = 1e-4;

/// The default momentum bound of block-time-step runs: a pair's two
/// forces are evaluated at different times, so momentum is conserved to
/// the time-stepping error (measured: Sod 10^3 3e-5 after 3 sub-steps,
/// sides 20 and 40 1.1e-5 and 5.0e-6 at the end), not to round-off.
pub const BLOCK_MOMENTUM_BOUND: f64 = 1e-4;

impl Bounds {
    /// The default bounds of a run with (`gravity`) or without
    /// self-gravity, with `block` time steps or global ones.
    pub fn for_run(gravity: bool, block: bool) -> Bounds {
        let mut b = Bounds::default();
        if gravity {
            b.momentum = GRAVITY_MOMENTUM_BOUND;
        }
        if block {
            b.momentum = b.momentum.max(BLOCK_MOMENTUM_BOUND);
        }
        b
    }
}

impl Default for Bounds {
    fn default() -> Self {
        Bounds {
            energy: 1e-2,
            momentum: 1e-10,
        }
    }
}

/// A particle blamed for a violation or a failure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Blame {
    /// Particle id.
    pub id: u64,
    /// Its position when it was found.
    pub position: [f64; 3],
    /// Why this particle.
    pub why: String,
}

impl std::fmt::Display for Blame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y, z] = self.position;
        write!(
            f,
            "particle id {} at ({x:.6e}, {y:.6e}, {z:.6e}) ({})",
            self.id, self.why
        )
    }
}

/// A conserved quantity past its bound (or a bad initial value).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Violation {
    /// Step (0: the initial state).
    pub step: u64,
    /// `energy`, `momentum`, `mass` or `particle mass`.
    pub quantity: String,
    /// The measured value (relative drift; for `mass` the relative change;
    /// for `particle mass` the mass).
    pub value: f64,
    /// The bound it crossed.
    pub bound: f64,
    /// The particle blamed, where one can be.
    pub particle: Option<Blame>,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.quantity.as_str() {
            "particle mass" => write!(
                f,
                "step {}: particle mass {:e} is not positive (allowed: finite masses > 0)",
                self.step, self.value
            )?,
            "mass" => write!(
                f,
                "step {}: total mass changed by {:e} (relative; allowed: exactly 0)",
                self.step, self.value
            )?,
            q => write!(
                f,
                "step {}: {q} drift {:.3e} exceeds its bound {:.1e}",
                self.step, self.value, self.bound
            )?,
        }
        if let Some(b) = &self.particle {
            write!(f, "; {b}")?;
        }
        Ok(())
    }
}

/// What `summary.json` records of the watch.
#[derive(Debug, Clone, Default, Serialize)]
pub struct WatchSummary {
    /// The bounds (absent when the watch was off).
    pub bounds: Option<Bounds>,
    /// Whether the run stops at the first violation.
    pub strict: bool,
    /// The first step past each bound, in the order they happened.
    pub violations: Vec<Violation>,
}

/// The checker of a run in progress.
#[derive(Debug, Clone)]
pub struct Watch {
    /// The bounds.
    pub bounds: Bounds,
    /// Stop with an error at the first violation.
    pub strict: bool,
    /// Print the first violation of each quantity (rank 0).
    pub warn: bool,
    /// The first step's sums and the stirring's work up to it.
    first: Option<(Conserved, f64)>,
    /// The work of the last step seen, and the sum of the steps' |work|
    /// since the first (the energy that went through the forcing).
    last_work: f64,
    work_through: f64,
    momentum_scale: f64,
    /// `sum m c^2` of the first step where the equation of state fixes u
    /// by the density (isothermal, polytropic): their internal energy has
    /// an arbitrary zero, so `|E_0|` is no scale for the energy drift.
    thermal: Option<f64>,
    barotropic: bool,
    violations: Vec<Violation>,
}

/// The scale of the energy drift `E - E_0 - W` from the first step's
/// sums: `|E_0|`, or where that is 0 the sum of the parts' magnitudes. A
/// gas whose EOS fixes u by the density (`thermal = Some(sum m c^2)`) has an
/// internal energy with an arbitrary zero (`c0^2 ln rho` is 0 at rho = 1):
/// its scale is `E_kin + |E_grav| + sum m c^2`, the energy pressure can
/// exchange with the flow. The stirring's work is added by the callers.
pub fn energy_scale(first: &Conserved, thermal: Option<f64>) -> f64 {
    match thermal {
        Some(t) => first.e_kin + first.e_grav.abs() + t,
        None if first.e_tot() != 0.0 => first.e_tot().abs(),
        None => first.e_kin + first.e_int.abs() + first.e_grav.abs(),
    }
}

impl Default for Watch {
    fn default() -> Self {
        Watch::new(Bounds::default(), false)
    }
}

impl Watch {
    /// A watch with these bounds; `strict` stops at the first violation.
    pub fn new(bounds: Bounds, strict: bool) -> Self {
        Watch {
            bounds,
            strict,
            warn: true,
            first: None,
            last_work: 0.0,
            work_through: 0.0,
            momentum_scale: 0.0,
            thermal: None,
            barotropic: false,
            violations: Vec::new(),
        }
    }

    /// `sum m c^2` of the first step for an EOS that fixes u by the
    /// density (the energy drift's scale, [`energy_scale`]), else `None`.
    pub fn thermal_scale(&self) -> Option<f64> {
        self.thermal
    }

    /// The violations so far.
    pub fn violations(&self) -> &[Violation] {
        &self.violations
    }

    /// The record for `summary.json`.
    pub fn summary(&self) -> WatchSummary {
        WatchSummary {
            bounds: Some(self.bounds),
            strict: self.strict,
            violations: self.violations.clone(),
        }
    }

    /// Checks the initial particles (`owned` of `p`) of a run with
    /// equation of state `eos`. Collective. A negative u is refused only
    /// where the EOS reads u (e.g. the Tait EOS ignores it); where the EOS
    /// fixes u by the density, the energy drift is measured against the
    /// gas's thermal energy `sum m c^2` (see [`energy_scale`]).
    ///
    /// # Errors
    /// A non-finite value or a smoothing length <= 0 or a negative internal
    /// energy ([`AppError::Input`]); with `strict`, a mass <= 0
    /// ([`AppError::Watch`]).
    pub fn check_initial<C: Communicator>(
        &mut self,
        p: &Particles,
        owned: Range<usize>,
        comm: &C,
        root: bool,
        eos: &sph_core::Eos,
        bbox: &sph_tree::BoundingBox,
    ) -> Result<(), AppError> {
        let internal_energy = eos.uses_internal_energy();
        self.barotropic = eos.energy(1.0).is_some();
        let bad_value = |i: usize| -> Option<String> {
            let fields = [
                ("x", p.x[i]),
                ("y", p.y[i]),
                ("z", p.z[i]),
                ("vx", p.vx[i]),
                ("vy", p.vy[i]),
                ("vz", p.vz[i]),
                ("m", p.m[i]),
                ("h", p.h[i]),
                ("u", p.u[i]),
            ];
            if let Some((name, v)) = fields.iter().find(|(_, v)| !v.is_finite()) {
                return Some(format!("{name} = {v} (allowed: finite numbers)"));
            }
            if p.h[i] <= 0.0 {
                return Some(format!("h = {:e} (allowed: h > 0)", p.h[i]));
            }
            if internal_energy && p.u[i] < 0.0 {
                return Some(format!("u = {:e} (allowed: u >= 0)", p.u[i]));
            }
            None
        };
        if let Some(b) = first_by_id(p, owned.clone(), comm, bad_value) {
            return Err(AppError::Input(b));
        }
        // A periodic axis holds its particles (to 1e-9 of its length: a
        // glass or lattice may sit on the upper face).
        let (lo, hi) = (bbox.lo(), bbox.hi());
        let outside = |i: usize| -> Option<String> {
            let x = [p.x[i], p.y[i], p.z[i]];
            (0..3)
                .find(|&k| {
                    let tol = 1e-9 * (hi[k] - lo[k]);
                    bbox.is_periodic(k) && (x[k] < lo[k] - tol || x[k] > hi[k] + tol)
                })
                .map(|k| {
                    format!(
                        "{} = {:e} outside the periodic box's [{}, {}) (allowed: inside it; give the box that holds the particles, e.g. --box, or move them in)",
                        ["x", "y", "z"][k],
                        x[k],
                        lo[k],
                        hi[k]
                    )
                })
        };
        if let Some(b) = first_by_id(p, owned.clone(), comm, outside) {
            return Err(AppError::Input(b));
        }
        let zero_mass = |i: usize| (p.m[i] <= 0.0).then(|| format!("m = {:e}", p.m[i]));
        if let Some(b) = first_by_id(p, owned.clone(), comm, zero_mass) {
            let m = comm.all_reduce_scalar(
                owned
                    .clone()
                    .find(|&i| p.id[i] == b.id)
                    .map_or(f64::INFINITY, |i| p.m[i]),
                ReduceOp::Min,
            );
            self.record(
                Violation {
                    step: 0,
                    quantity: "particle mass".into(),
                    value: m,
                    bound: 0.0,
                    particle: Some(b),
                },
                root,
            )?;
        }
        Ok(())
    }

    /// Checks the conserved quantities of step `r` (collective: every rank
    /// calls it with the same report; `p` and `owned` are this rank's
    /// particles after the step).
    ///
    /// # Errors
    /// A non-finite conserved quantity (always, naming the first particle
    /// with a non-finite value); with `strict`, the first quantity past its
    /// bound ([`AppError::Watch`]).
    pub fn check_step<C: Communicator>(
        &mut self,
        r: &StepReport,
        p: &Particles,
        owned: Range<usize>,
        comm: &C,
        root: bool,
    ) -> Result<(), AppError> {
        let c = r.conserved;
        let sums = [
            c.mass,
            c.e_kin,
            c.e_int,
            c.e_grav,
            c.momentum[0],
            c.momentum[1],
            c.momentum[2],
        ];
        if sums.iter().any(|v| !v.is_finite()) {
            let nonfinite = |i: usize| -> Option<String> {
                let fields = [
                    ("x", p.x[i]),
                    ("y", p.y[i]),
                    ("z", p.z[i]),
                    ("vx", p.vx[i]),
                    ("vy", p.vy[i]),
                    ("vz", p.vz[i]),
                    ("u", p.u[i]),
                    ("rho", p.rho[i]),
                    ("p", p.p[i]),
                    ("du", p.du[i]),
                    ("ax", p.ax[i]),
                    ("ay", p.ay[i]),
                    ("az", p.az[i]),
                    ("h", p.h[i]),
                ];
                fields
                    .iter()
                    .find(|(_, v)| !v.is_finite())
                    .map(|(name, v)| format!("{name} = {v}"))
            };
            let blame = first_by_id(p, owned, comm, nonfinite);
            return Err(AppError::NonFinite {
                step: r.step,
                particle: blame,
            });
        }
        // Between synchronisation points of block time steps the sums mix
        // fresh values of the active particles with predicted and held
        // ones (the potential of the last evaluation): the bounds apply
        // where every particle is fresh.
        if !r.all_active {
            return Ok(());
        }
        if self.first.is_none() && self.barotropic {
            let s = exact_sums(owned.clone(), 1, comm, |i, s| {
                s[0].add(p.m[i] * p.c[i] * p.c[i])
            });
            self.thermal = Some(s[0].value());
        }
        let (first, w0) = *self.first.get_or_insert_with(|| {
            self.last_work = r.external_work;
            (c, r.external_work)
        });
        self.work_through += (r.external_work - self.last_work).abs();
        self.last_work = r.external_work;
        self.momentum_scale = self
            .momentum_scale
            .max((2.0 * c.mass * (c.e_kin + c.e_int.abs())).max(0.0).sqrt());
        if c.mass.to_bits() != first.mass.to_bits() && !self.seen("mass") {
            let v = Violation {
                step: r.step,
                quantity: "mass".into(),
                value: (c.mass - first.mass) / first.mass.abs(),
                bound: 0.0,
                particle: None,
            };
            self.record(v, root)?;
        }
        // A driven run conserves E - W (W the stirring's work); its scale
        // grows by the energy that went through the forcing.
        let e_scale = energy_scale(&first, self.thermal) + self.work_through;
        let change = c.e_tot() - first.e_tot() - (r.external_work - w0);
        let drift = if e_scale > 0.0 {
            change.abs() / e_scale
        } else {
            0.0
        };
        if drift > self.bounds.energy && !self.seen("energy") {
            let blame = worst_energy_change(p, owned.clone(), r.dt, comm);
            let v = Violation {
                step: r.step,
                quantity: "energy".into(),
                value: drift,
                bound: self.bounds.energy,
                particle: blame,
            };
            self.record(v, root)?;
        }
        let dp = (0..3)
            .map(|k| (c.momentum[k] - first.momentum[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        let p_drift = if self.momentum_scale > 0.0 {
            dp / self.momentum_scale
        } else {
            dp
        };
        if p_drift > self.bounds.momentum && !self.seen("momentum") {
            let v = Violation {
                step: r.step,
                quantity: "momentum".into(),
                value: p_drift,
                bound: self.bounds.momentum,
                particle: None,
            };
            self.record(v, root)?;
        }
        Ok(())
    }

    fn seen(&self, quantity: &str) -> bool {
        self.violations.iter().any(|v| v.quantity == quantity)
    }

    fn record(&mut self, v: Violation, root: bool) -> Result<(), AppError> {
        if self.strict {
            return Err(AppError::Watch(Box::new(v)));
        }
        if self.warn && root {
            eprintln!("warning: {v} (recorded in summary.json; --strict stops here)");
        }
        self.violations.push(v);
        Ok(())
    }
}

/// The particle of smallest id (over all ranks) for which `bad` says why,
/// with its position. Collective.
pub fn first_by_id<C: Communicator>(
    p: &Particles,
    owned: Range<usize>,
    comm: &C,
    bad: impl Fn(usize) -> Option<String>,
) -> Option<Blame> {
    let local = owned
        .filter_map(|i| bad(i).map(|why| (p.id[i], i, why)))
        .min_by_key(|(id, _, _)| *id);
    let id = comm.all_reduce_scalar(local.as_ref().map_or(u64::MAX, |l| l.0), ReduceOp::Min);
    if id == u64::MAX {
        // Nobody found one.
        return None;
    }
    blame_of(p, comm, local.filter(|l| l.0 == id).map(|(_, i, w)| (i, w)))
}

/// Spreads the particle `mine` (held by at most one rank: local index and
/// reason) to every rank. Collective.
fn blame_of<C: Communicator>(
    p: &Particles,
    comm: &C,
    mine: Option<(usize, String)>,
) -> Option<Blame> {
    let mut buf = [0.0f64; 5];
    let mut reason = String::new();
    if let Some((i, why)) = &mine {
        buf = [1.0, p.id[*i] as f64, p.x[*i], p.y[*i], p.z[*i]];
        reason = why.clone();
    }
    // The id travels exactly as u64.
    let id = comm.all_reduce_scalar(mine.as_ref().map_or(0u64, |(i, _)| p.id[*i]), ReduceOp::Sum);
    comm.all_reduce(&mut buf, ReduceOp::Sum);
    if buf[0] != 1.0 {
        return None;
    }
    // The reason is known on the holding rank only; the others say what
    // was searched for.
    if reason.is_empty() {
        reason = "on another rank".into();
    }
    Some(Blame {
        id,
        position: [buf[2], buf[3], buf[4]],
        why: reason,
    })
}

/// The particle whose specific energy changed most in the step:
/// `|v . a + du/dt| dt`. Collective.
fn worst_energy_change<C: Communicator>(
    p: &Particles,
    owned: Range<usize>,
    dt: f64,
    comm: &C,
) -> Option<Blame> {
    let change = |i: usize| {
        ((p.vx[i] * p.ax[i] + p.vy[i] * p.ay[i] + p.vz[i] * p.az[i] + p.du[i]) * dt).abs()
    };
    let local = owned
        .map(|i| (change(i), i))
        .filter(|(c, _)| c.is_finite())
        .max_by(|a, b| a.0.total_cmp(&b.0).then(p.id[b.1].cmp(&p.id[a.1])));
    let top = comm.all_reduce_scalar(local.map_or(f64::NEG_INFINITY, |l| l.0), ReduceOp::Max);
    // Ties across ranks: the smallest id.
    let cand = local.filter(|l| l.0 == top).map(|l| p.id[l.1]);
    let id = comm.all_reduce_scalar(cand.unwrap_or(u64::MAX), ReduceOp::Min);
    let mine = local
        .filter(|l| l.0 == top && p.id[l.1] == id)
        .map(|(c, i)| {
            let e = 0.5 * (p.vx[i].powi(2) + p.vy[i].powi(2) + p.vz[i].powi(2)) + p.u[i];
            (
                i,
                format!(
                    "largest change of specific energy in the step: {c:.3e}, against its specific energy {e:.3e}"
                ),
            )
        });
    blame_of(p, comm, mine)
}

/// Finds the particle a numerical failure of the solver names (by id)
/// among this rank's particles and adds its position to the error.
pub fn locate(e: CoreError, p: &Particles, owned: Range<usize>) -> AppError {
    let id = match &e {
        CoreError::NonFinite { id, .. }
        | CoreError::NegativeEnergy { id, .. }
        | CoreError::SingularIad { id, .. }
        | CoreError::HIteration { id, .. } => *id,
        _ => return AppError::Core(e),
    };
    let at = owned
        .clone()
        .find(|&i| p.id.get(i) == Some(&id))
        .or_else(|| p.id.iter().position(|&j| j == id));
    match at {
        Some(i) => AppError::Located {
            source: e,
            position: [p.x[i], p.y[i], p.z[i]],
        },
        None => AppError::Core(e),
    }
}

/// The watch checks every step's conserved quantities (collective): every
/// sub-step for non-finite values, the bounds at synchronisation points.
impl<C: Communicator> StepObserver<C> for Watch {
    fn step(&mut self, view: &StepView<'_, C>) -> Result<Observed, AppError> {
        let root = view.comm.rank() == 0;
        self.check_step(
            view.report,
            view.particles,
            view.owned.clone(),
            view.comm,
            root,
        )?;
        Ok(Observed::Recorded)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sph_comm::SerialComm;
    use sph_core::FieldSet;

    fn particles() -> Particles {
        let mut p = Particles::new(4, FieldSet::default());
        for i in 0..4 {
            p.id[i] = 10 + i as u64;
            p.x[i] = i as f64;
            p.y[i] = 2.0 * i as f64;
            p.z[i] = -(i as f64);
            p.m[i] = 1.0;
            p.h[i] = 0.1;
        }
        p
    }

    /// A stuck h iteration names the particle's position beside its id.
    #[test]
    fn a_solver_failure_gets_the_particle_position() {
        let p = particles();
        let e = CoreError::HIteration {
            step: 7,
            id: 12,
            iterations: 30,
            count: 3,
            min: 25,
            max: 151,
            h: 0.1,
        };
        let msg = locate(e, &p, 0..4).to_string();
        assert!(msg.contains("step 7") && msg.contains("id 12"), "{msg}");
        assert!(
            msg.contains("(2.000000e0, 4.000000e0, -2.000000e0)"),
            "{msg}"
        );
    }

    /// The first bad particle is the one of smallest id, whatever its index.
    #[test]
    fn the_first_bad_particle_is_the_smallest_id() {
        let mut p = particles();
        p.id.swap(1, 3);
        p.u[1] = -1.0;
        p.u[3] = -1.0;
        let mut w = Watch::default();
        let e = w
            .check_initial(
                &p,
                0..4,
                &SerialComm::new(),
                false,
                &sph_core::Eos::IdealGas { gamma: 1.4 },
                &sph_tree::BoundingBox::cube(-10.0, 10.0, sph_tree::Boundary::Open).unwrap(),
            )
            .unwrap_err()
            .to_string();
        assert!(e.contains("id 11") && e.contains("u >= 0"), "{e}");
    }
}
