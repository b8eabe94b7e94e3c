//! Momentum and energy equations (SPH-EXA paper eqs. 2-5) with the
//! signal-velocity artificial viscosity, IAD or plain kernel gradients.
//!
//! With `A_ij(h_k) = C_k (x_j - x_i) W(r_ij, h_k)` (IAD) or
//! `grad_i W(r_ij, h_k)` (plain), and `Pi'_ij = -alpha_ij/2 v_sig w_ij` for
//! approaching pairs (`w_ij = v_ij . x_ij / r_ij < 0`, `v_sig = c_i + c_j - 3 w_ij`),
//! where the viscosity strength is a constant `alpha_ij = alpha`
//! ([`momentum_energy`]) or the mean `alpha_ij = (alpha_i + alpha_j) / 2` of
//! per-particle switches ([`momentum_energy_switched`], see
//! [`av_switch`](crate::av_switch)), symmetric in `i, j` either way:
//!
//! ```text
//! dv_i/dt = - sum_j m_j [ P_i/(Omega_i rho_i^2) A_ij(h_i) + P_j/(Omega_j rho_j^2) A_ij(h_j)
//!                        + Pi'_ij/2 (A_ij(h_i)/rho_i + A_ij(h_j)/rho_j) ]
//! du_i/dt = P_i/(Omega_i rho_i^2) sum_j m_j v_ij . A_ij(h_i)
//!         + 1/4 sum_j m_j Pi'_ij v_ij . (A_ij(h_i)/rho_i + A_ij(h_j)/rho_j)
//! ```
//!
//! The paper prints `rho_a` instead of `rho_a^2` in the energy equation and
//! a `+` before the viscous acceleration; the forms above are the
//! dimensionally consistent ones for which the pairwise forces are
//! antisymmetric (momentum conserved to round-off), the pressure work
//! balances the kinetic energy change exactly, and viscosity only heats.
//!
//! The pass is composed of terms, each a small type in its own file: the
//! pressure gradient's volume weights (`pressure.rs`: [`Volume`]), the
//! viscosity's strength (`strength.rs`), its form (`viscosity/`, one file
//! per [`AvForm`]) and its cleaning (`cleaning.rs`: [`AvCleaning`]), the
//! artificial stress (`stress.rs`) and the conduction
//! ([`conduction`](crate::conduction)). [`momentum_energy_with`] turns a
//! [`MomentumScheme`] into the one pair stage (`stage.rs`) monomorphised
//! over the chosen terms.

mod cleaning;
mod pressure;
mod stage;
mod strength;
mod stress;
mod viscosity;

pub use cleaning::AvCleaning;
pub use pressure::{Volume, VolumeWeights};
pub use stress::ArtificialStress;
pub use viscosity::AvForm;

use crate::conduction::Conductivity;
pub use crate::flow::HydroState;
use crate::flow::{Flow, FlowState};
pub use crate::pair_loop::Gradients;
use crate::pair_loop::{with_gradients, Reduce, WithGradients};
use pressure::PressureWeights;
use rayon::prelude::*;
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList};
use stage::Momentum;
use std::marker::PhantomData;
use strength::Strength;
use viscosity::{with_form, ViscosityForm, WithForm};

/// Where the momentum stage writes.
#[derive(Debug)]
pub struct Rates<'a> {
    /// Acceleration x.
    pub ax: &'a mut [f64],
    /// Acceleration y.
    pub ay: &'a mut [f64],
    /// Acceleration z.
    pub az: &'a mut [f64],
    /// du/dt.
    pub du: &'a mut [f64],
    /// Each target's own time-step inputs, where asked for.
    pub criteria: Option<Criteria<'a>>,
    /// The conduction's impulse of `u` (alpha_u times the weighted sum)
    /// where [`Conductivity::impulses`] asks for it; required then.
    pub impulse: Option<&'a mut [f64]>,
}

/// Each target's own time-step inputs ([`TimestepParams::particle_dt`](crate::timestep::TimestepParams::particle_dt)),
/// indexed like the [`Rates`].
#[derive(Debug)]
pub struct Criteria<'a> {
    /// `h / v_sig` with the form's signal velocity.
    pub h_over_vsig: &'a mut [f64],
    /// The compression `|div v|` the form's density criterion counts.
    pub compression: &'a mut [f64],
}

/// What the time step needs from the momentum stage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MomentumStats {
    /// `min_i h_i / v_sig,i` (Courant condition).
    pub min_h_over_vsig: f64,
    /// `max_i |div v_i|` (density-change condition).
    pub max_abs_div_v: f64,
}

/// Per-particle factors of the pair terms, computed once per step so the
/// pair loop needs a single division (`1/r`): `1/h`, `1/rho` and
/// `P / (Omega rho^2)`. The buffers are reused between steps.
#[derive(Debug, Clone, Default)]
pub struct PairFactors {
    inv_h: Vec<f64>,
    inv_rho: Vec<f64>,
    pre: Vec<f64>,
}

impl PairFactors {
    /// Fills the factors of every particle of `s` (parallel).
    pub fn fill(&mut self, s: &HydroState<'_>) {
        self.fill_with(s, Volume::Mass, &[]);
    }

    /// As [`fill`](Self::fill) for the particle volumes `volume`, with
    /// the volume elements' normalisation `kx` (every particle; unused
    /// for [`Volume::Mass`]): the pressure factor is SPH-EXA's
    /// `P_i / (k_i m_i^2 Omega_i)` for [`Volume::Generalised`], which the
    /// pair loop multiplies by the Atwood-blended `X` weights, and
    /// `P_i / (k_i^2 m_i Omega_i)` for [`Volume::PressureEnergy`], which
    /// it multiplies by `X_i X_j / m_j`.
    ///
    /// # Panics
    /// If `kx` is shorter than the state with volume elements.
    pub fn fill_with(&mut self, s: &HydroState<'_>, volume: Volume, kx: &[f64]) {
        let n = s.rho.len();
        for v in [&mut self.inv_h, &mut self.inv_rho, &mut self.pre] {
            // Grow to what the particles need, not to twice the old size.
            v.reserve_exact(n.saturating_sub(v.len()));
            v.resize(n, 0.0);
        }
        (
            self.inv_h.par_iter_mut(),
            self.inv_rho.par_iter_mut(),
            self.pre.par_iter_mut(),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(i, (ih, ir, pre))| {
                let om = if s.omega.is_empty() { 1.0 } else { s.omega[i] };
                *ih = 1.0 / s.pos.h[i];
                *ir = 1.0 / s.rho[i];
                *pre = match volume {
                    Volume::Mass => s.p[i] * *ir * *ir / om,
                    Volume::Generalised => s.p[i] / (kx[i] * s.pos.m[i] * s.pos.m[i] * om),
                    Volume::PressureEnergy => s.p[i] / (kx[i] * kx[i] * s.pos.m[i] * om),
                };
            });
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        (self.inv_h.capacity() + self.inv_rho.capacity() + self.pre.capacity()) * 8
    }
}

/// Computes accelerations and du/dt of every target of `nl` with a
/// constant viscosity strength `alpha`; `f` must have been filled from the
/// same state.
///
/// # Panics
/// If the state's arrays differ in length or do not cover the lists.
pub fn momentum_energy<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    s: HydroState<'_>,
    f: &PairFactors,
    gradients: Gradients,
    alpha: f64,
    nl: &CompactNeighborList,
    out: Rates<'_>,
) -> MomentumStats {
    let scheme = MomentumScheme::paper(gradients, Alpha::Constant(alpha));
    momentum_energy_with(kernel, bbox, s, f, scheme, nl, out)
}

/// As [`momentum_energy`], with a viscosity strength per particle: pair
/// `i, j` uses `alpha_ij = (alpha_i + alpha_j) / 2`. `alpha` must cover
/// every particle the lists reach (targets and halos), as the other state
/// slices do. With all `alpha_i` equal to `a` the result is bit for bit
/// that of [`momentum_energy`] with `a`.
///
/// # Panics
/// If `alpha` is shorter than the density slice of `s`.
pub fn momentum_energy_switched<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    s: HydroState<'_>,
    f: &PairFactors,
    gradients: Gradients,
    alpha: &[f64],
    nl: &CompactNeighborList,
    out: Rates<'_>,
) -> MomentumStats {
    let scheme = MomentumScheme::paper(gradients, Alpha::PerParticle(alpha));
    momentum_energy_with(kernel, bbox, s, f, scheme, nl, out)
}

/// The viscosity strength of the pairs.
#[derive(Debug, Clone, Copy)]
pub enum Alpha<'a> {
    /// One strength for every pair.
    Constant(f64),
    /// One per particle (targets and halos); pairs use the mean.
    PerParticle(&'a [f64]),
}

/// The scheme elements of a momentum pass beyond the state: gradient
/// operator, viscosity strength and form, and the volume elements.
#[derive(Debug, Clone, Copy)]
pub struct MomentumScheme<'a> {
    /// Gradient operator.
    pub gradients: Gradients,
    /// Viscosity strength.
    pub alpha: Alpha<'a>,
    /// Viscosity and signal-velocity form.
    pub av_form: AvForm,
    /// The volumes the pressure terms are weighted with (with
    /// [`PairFactors::fill_with`] given the same kind and their `k`).
    pub volumes: VolumeWeights<'a>,
    /// Artificial stress against the tensile instability, or none.
    pub stress: Option<ArtificialStress>,
    /// Cleaning of the viscosity's velocity jump, or none.
    pub cleaning: Option<AvCleaning<'a>>,
    /// Artificial conductivity added to du/dt, or none (the sum of
    /// [`conduction`](crate::conduction::conduction), in this pass).
    pub conduction: Option<Conductivity<'a>>,
}

impl<'a> MomentumScheme<'a> {
    /// The seed paper's pass with `gradients` and the strength `alpha`:
    /// mass volumes, its viscosity form, no stress, cleaning or conduction.
    pub fn paper(gradients: Gradients, alpha: Alpha<'a>) -> Self {
        Self {
            gradients,
            alpha,
            av_form: AvForm::Paper,
            volumes: VolumeWeights::Mass,
            stress: None,
            cleaning: None,
            conduction: None,
        }
    }
}

/// Accelerations and du/dt of every target of `nl` for any scheme
/// ([`momentum_energy`] and [`momentum_energy_switched`] are the paper's
/// forms). With volume elements, the pressure terms of pair `i, j` are
///
/// ```text
/// - m_j [ a_ij P_i/(k_i m_i^2 Omega_i) A_ij(h_i) + b_ij P_j/(k_j m_j^2 Omega_j) A_ij(h_j) ]
/// ```
///
/// with `(a_ij, b_ij) = (X_i^2, X_j^2)` for Atwood numbers
/// `At = |rho_i - rho_j| / (rho_i + rho_j) < 0.1`, `(X_i X_j, X_i X_j)`
/// above 0.2 and `(X_i^(2-s) X_j^s, X_j^(2-s) X_i^s)`, `s = (At - 0.1)/0.1`,
/// between (SPH-EXA's `hydro_ve`); the energy equation takes `a_ij` in its
/// pressure work, so the pair terms stay antisymmetric and the work
/// balances the kinetic energy exactly. With `X = m / rho` and `k = 1`
/// this is the paper's form.
///
/// # Panics
/// If the state's arrays (or `alpha`, `xm`, the conduction's impulse
/// weights) do not cover the lists, or impulses have no output.
pub fn momentum_energy_with<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    s: HydroState<'_>,
    f: &PairFactors,
    scheme: MomentumScheme<'_>,
    nl: &CompactNeighborList,
    out: Rates<'_>,
) -> MomentumStats {
    let n = s.rho.len();
    if let Alpha::PerParticle(a) = scheme.alpha {
        assert!(
            a.len() >= n,
            "alpha has {} values for {n} particles",
            a.len()
        );
    }
    if let Some(x) = scheme.volumes.elements() {
        assert!(x.len() >= n, "X has {} values for {n} particles", x.len());
    }
    if let Some(w) = scheme.conduction.and_then(|c| c.impulses) {
        assert!(
            out.impulse.is_some(),
            "conduction impulses need Rates::impulse"
        );
        assert!(
            w.since.len() >= n && w.starts.len() >= n && w.gains.len() >= n,
            "conduction impulses: since, starts and gains must cover the {n} particles"
        );
    }
    let run = MomentumRun {
        kernel,
        bbox,
        s,
        f,
        scheme,
        nl,
        out,
    };
    with_gradients(scheme.gradients, run)
}

/// The arguments of one momentum pass; the dispatch below turns the
/// scheme's choices into the term types of one monomorphised
/// [`Momentum`] stage, one choice per step: gradient operator, strength,
/// viscosity form ([`with_form`]), volume weights.
struct MomentumRun<'a, K> {
    kernel: &'a K,
    bbox: &'a BoundingBox,
    s: HydroState<'a>,
    f: &'a PairFactors,
    scheme: MomentumScheme<'a>,
    nl: &'a CompactNeighborList,
    out: Rates<'a>,
}

impl<K: Kernel> WithGradients for MomentumRun<'_, K> {
    type Output = MomentumStats;

    fn run<const IAD: bool>(self) -> MomentumStats {
        let n = self.s.rho.len();
        match self.scheme.alpha {
            Alpha::Constant(a) => self.with_strength::<IAD, _>(strength::Constant(a)),
            Alpha::PerParticle(a) => self.with_strength::<IAD, _>(strength::Mean(&a[..n])),
        }
    }
}

impl<'a, K: Kernel> MomentumRun<'a, K> {
    fn with_strength<const IAD: bool, S: Strength>(self, strength: S) -> MomentumStats {
        let form = self.scheme.av_form;
        with_form(
            form,
            WithStrength::<K, S, IAD> {
                run: self,
                strength,
            },
        )
    }

    fn with_weights<const IAD: bool, S: Strength, F: ViscosityForm>(
        self,
        strength: S,
    ) -> MomentumStats {
        let n = self.s.rho.len();
        let (rho, m) = (&self.s.rho[..n], &self.s.pos.m[..n]);
        match self.scheme.volumes {
            VolumeWeights::Mass => self.stage::<IAD, S, F, _>(strength, pressure::Mass),
            VolumeWeights::Atwood(x) => {
                let w = pressure::Atwood { rho, x: &x[..n] };
                self.stage::<IAD, S, F, _>(strength, w)
            }
            VolumeWeights::Product(x) => {
                let w = pressure::Product { m, x: &x[..n] };
                self.stage::<IAD, S, F, _>(strength, w)
            }
        }
    }

    /// The pair loop of the stage with the chosen terms.
    fn stage<const IAD: bool, S: Strength, F: ViscosityForm, W: PressureWeights>(
        self,
        strength: S,
        weights: W,
    ) -> MomentumStats {
        let (s, f) = (self.s, self.f);
        let flow_state = FlowState::from(s);
        let driver = Flow::driver(self.bbox, self.kernel, &flow_state, self.nl);
        let n = s.rho.len();
        let r = self.nl.targets();
        let o = self.out;
        let criteria = o
            .criteria
            .map(|c| [&mut c.h_over_vsig[r.clone()], &mut c.compression[r.clone()]]);
        let out = (
            [
                &mut o.ax[r.clone()],
                &mut o.ay[r.clone()],
                &mut o.az[r.clone()],
                &mut o.du[r.clone()],
            ],
            (criteria, o.impulse.map(|d| [&mut d[r]])),
        );
        let stage = Momentum::<K, IAD, S, F, W> {
            flow: Flow::new(self.kernel, &flow_state, IAD),
            inv_h: &f.inv_h[..n],
            inv_rho: &f.inv_rho[..n],
            pre: &f.pre[..n],
            strength,
            weights,
            stress: self.scheme.stress,
            cleaning: self.scheme.cleaning,
            conduction: self.scheme.conduction,
            form: PhantomData,
        };
        driver.run(&stage, out)
    }
}

/// The pass with its strength chosen, waiting for the viscosity form.
struct WithStrength<'a, K, S, const IAD: bool> {
    run: MomentumRun<'a, K>,
    strength: S,
}

impl<K: Kernel, S: Strength, const IAD: bool> WithForm for WithStrength<'_, K, S, IAD> {
    type Output = MomentumStats;

    fn run<F: ViscosityForm>(self) -> MomentumStats {
        self.run.with_weights::<IAD, S, F>(self.strength)
    }
}

impl Reduce for MomentumStats {
    fn identity() -> Self {
        MomentumStats {
            min_h_over_vsig: f64::INFINITY,
            max_abs_div_v: 0.0,
        }
    }

    fn merge(self, b: Self) -> Self {
        MomentumStats {
            min_h_over_vsig: self.min_h_over_vsig.min(b.min_h_over_vsig),
            max_abs_div_v: self.max_abs_div_v.max(b.max_abs_div_v),
        }
    }
}
