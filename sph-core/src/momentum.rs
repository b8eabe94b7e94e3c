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

use crate::conduction::{ConductionTarget, Conductivity};
pub use crate::flow::HydroState;
use crate::flow::{Flow, FlowState};
pub use crate::pair_loop::Gradients;
use crate::pair_loop::{
    neighbour_lanes, sym_mat_vec, with_gradients, F64s, Group, PairStage, Reduce, WithGradients,
    LANES,
};
pub use crate::scheme::AvForm;
use crate::scheme::Volume;
use rayon::prelude::*;
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList};

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
    let scheme = MomentumScheme {
        gradients,
        alpha: Alpha::Constant(alpha),
        av_form: AvForm::Paper,
        volumes: VolumeWeights::Mass,
        stress: None,
        cleaning: None,
        conduction: None,
    };
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
    let scheme = MomentumScheme {
        gradients,
        alpha: Alpha::PerParticle(alpha),
        av_form: AvForm::Paper,
        volumes: VolumeWeights::Mass,
        stress: None,
        cleaning: None,
        conduction: None,
    };
    momentum_energy_with(kernel, bbox, s, f, scheme, nl, out)
}

/// The particle volumes the momentum and energy equations weigh pairs
/// with (see [`momentum_energy_with`]).
#[derive(Debug, Clone, Copy)]
pub enum VolumeWeights<'a> {
    /// `m / rho`: the paper's equations.
    Mass,
    /// SPH-EXA's generalised volume elements `X` (every particle), with
    /// the Atwood-blended weights.
    Atwood(&'a [f64]),
    /// Volume elements `X` (every particle) in Hopkins's (2013)
    /// scale-free form: pair weights `X_i X_j`.
    Product(&'a [f64]),
}

impl<'a> VolumeWeights<'a> {
    /// The weights of `volume` with the elements `xm` (unused for
    /// [`Volume::Mass`]).
    pub fn of(volume: Volume, xm: &'a [f64]) -> Self {
        match volume {
            Volume::Mass => Self::Mass,
            Volume::Generalised => Self::Atwood(xm),
            Volume::PressureEnergy => Self::Product(xm),
        }
    }

    fn elements(&self) -> Option<&'a [f64]> {
        match *self {
            Self::Mass => None,
            Self::Atwood(x) | Self::Product(x) => Some(x),
        }
    }
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

/// SPH-EXA's "AV cleaning": the viscosity of pair `i, j` sees the
/// velocity jump left after a linear reconstruction from both sides,
/// `r . v_ij - phi_ij (r . G_i r + r . G_j r)` instead of `r . v_ij`,
/// with `G` the symmetric velocity gradient, `r = x_i - x_j` and the
/// van Leer type limiter
///
/// ```text
/// A = (r . G_i r) / (r . G_j r),   phi_ij = 1/2 damp(eta) clamp(4 A / (1 + A)^2, 0, 1)
/// ```
///
/// evaluated as `phi_ij (q_i + q_j) = damp 2 q_i q_j / (q_i + q_j)` where
/// `q_i = r . G_i r` and `q_j` agree in sign, else 0 (the harmonic mean of
/// the two reconstructions: one division, and the same bits for `j, i`).
///
/// (`damp = exp(-(5 (eta - eta_c))^2)` for pairs closer than
/// `eta = min(r/h_i, r/h_j) < eta_c`, else 1; `eta_c` the lattice spacing
/// over h for the target neighbour count). A linear velocity field
/// (shear, uniform compression) gives `A = 1`, `phi = 1/2` and no
/// viscosity at all; across a shock the two sides' gradients differ and
/// the limiter restores the full jump. The corrected jump is symmetric in
/// `i, j`, so momentum and energy stay conserved.
///
/// Only approaching pairs (`r . v_ij < 0`) are viscous, as without the
/// cleaning; SPH-EXA also applies the viscosity where the reconstructed
/// jump approaches but the particles recede, and there the viscous
/// "heating" `Pi_ij v_ij . grad W` is negative: heat turns into bulk
/// motion, and a cold particle can be drained below u = 0 (Evrard 40^3
/// with `best` and the cleaning stopped so at t = 1.78). Leaving such
/// pairs alone costs the Kelvin-Helmholtz mode some growth (M(1.5) 0.074
/// -> 0.066 at 32^2 x 8, 0.120 -> 0.117 at 64^2 x 8).
#[derive(Debug, Clone, Copy)]
pub struct AvCleaning<'a> {
    /// `G_xx, G_xy, G_xz, G_yy, G_yz, G_zz` of every particle (targets
    /// and halos).
    pub grad_v: [&'a [f64]; 6],
    /// `eta_c`.
    pub eta_crit: f64,
}

impl AvCleaning<'_> {
    /// The spacing over h of a lattice with `ng0` neighbours within 2 h:
    /// `(32 pi / (3 (ng0 + 1)))^(1/3)` (SPH-EXA's `eta_crit`).
    ///
    /// ```
    /// let e = sph_core::momentum::AvCleaning::eta_crit(100);
    /// assert!((e - 0.6923).abs() < 1e-4);
    /// ```
    pub fn eta_crit(ng0: usize) -> f64 {
        (32.0 * std::f64::consts::PI / (3.0 * (ng0 as f64 + 1.0))).cbrt()
    }
}

/// Monaghan's (2000) artificial stress for particles under tension: pair
/// `i, j` gains the repulsive term `R_ij f_ij^4` beside its pressure terms,
/// with `R_ij = R_i + R_j`, `R_i = epsilon max(-P_i, 0) / (Omega_i rho_i^2)`
/// and `f_ij = (w(r/h_i) + w(r/h_j)) / (2 w(q_s))`, `w` the kernel's shape
/// and `q_s` the particle spacing over h. It enters like a viscosity
/// term (force along the mean gradient, heating `1/2 R_ij f^4 v_ij . A`),
/// so momentum and energy stay conserved; it is zero where no pressure is
/// negative and falls off as `f^4` beyond the spacing, so it acts only on
/// pairs that close in under tension.
///
/// ```
/// use sph_core::momentum::ArtificialStress;
/// use sph_kernels::{Kernel, Sinc};
/// let k = Sinc::new(6.0).unwrap();
/// let s = ArtificialStress::new(0.2, 100, &k);
/// // The spacing of a lattice with 100 neighbours within 2 h is 0.694 h.
/// assert!((s.spacing_over_h - 0.6944).abs() < 1e-3);
/// assert!((s.inv_w_spacing * k.shape(s.spacing_over_h) - 1.0).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArtificialStress {
    /// Strength `epsilon` (Monaghan 2000: 0.2 for `n = 4`).
    pub epsilon: f64,
    /// Spacing over smoothing length `q_s`: `2 (4 pi / (3 ng0))^(1/3)`
    /// for `ng0` neighbours within `2 h` of a lattice.
    pub spacing_over_h: f64,
    /// `1 / w(q_s)`.
    pub inv_w_spacing: f64,
}

impl ArtificialStress {
    /// The stress of strength `epsilon` for a target of `ng0` neighbours
    /// (self included) with `kernel`.
    pub fn new<K: Kernel>(epsilon: f64, ng0: usize, kernel: &K) -> Self {
        let spacing_over_h = 2.0 * (4.0 * std::f64::consts::PI / (3.0 * ng0 as f64)).cbrt();
        Self {
            epsilon,
            spacing_over_h,
            inv_w_spacing: 1.0 / kernel.shape(spacing_over_h),
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
/// If the state's arrays (or `alpha`, `xm`) do not cover the lists.
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
    let run = MomentumRun {
        kernel,
        bbox,
        s,
        f,
        alpha: scheme.alpha,
        av_form: scheme.av_form,
        volumes: scheme.volumes,
        stress: scheme.stress,
        cleaning: scheme.cleaning,
        conduction: scheme.conduction,
        nl,
        out,
    };
    with_gradients(scheme.gradients, run)
}

/// Atwood numbers below this keep the weights `X_i^2, X_j^2`.
const ATWOOD_MIN: f64 = 0.1;
/// Atwood numbers above this use the weights `X_i X_j`.
const ATWOOD_MAX: f64 = 0.2;

/// The arguments of one momentum pass, run for one gradient operator.
struct MomentumRun<'a, K> {
    kernel: &'a K,
    bbox: &'a BoundingBox,
    s: HydroState<'a>,
    f: &'a PairFactors,
    alpha: Alpha<'a>,
    av_form: AvForm,
    volumes: VolumeWeights<'a>,
    stress: Option<ArtificialStress>,
    cleaning: Option<AvCleaning<'a>>,
    conduction: Option<Conductivity<'a>>,
    nl: &'a CompactNeighborList,
    out: Rates<'a>,
}

impl<K: Kernel> WithGradients for MomentumRun<'_, K> {
    type Output = MomentumStats;

    fn run<const IAD: bool>(self) -> MomentumStats {
        let (s, f) = (self.s, self.f);
        let flow_state = FlowState::from(s);
        let driver = Flow::driver(self.bbox, self.kernel, &flow_state, self.nl);
        let n = s.rho.len();
        let r = self.nl.targets();
        let o = self.out;
        let out = [
            &mut o.ax[r.clone()],
            &mut o.ay[r.clone()],
            &mut o.az[r.clone()],
            &mut o.du[r],
        ];
        let flow = Flow::new(self.kernel, &flow_state, IAD);
        let xm = self.volumes.elements().map_or(&[][..], |x| &x[..n]);
        let product = matches!(self.volumes, VolumeWeights::Product(_));
        let sphexa = self.av_form == AvForm::SphExa;
        let stress = (self.stress, self.cleaning, self.conduction);
        macro_rules! go {
            ($sw:literal, $a:expr, $per:expr) => {
                match (!xm.is_empty(), sphexa) {
                    (false, false) => driver.run(
                        &momentum::<K, IAD, $sw, false, false>(
                            flow,
                            f,
                            n,
                            $a,
                            $per,
                            (xm, product),
                            stress,
                        ),
                        out,
                    ),
                    (false, true) => driver.run(
                        &momentum::<K, IAD, $sw, false, true>(
                            flow,
                            f,
                            n,
                            $a,
                            $per,
                            (xm, product),
                            stress,
                        ),
                        out,
                    ),
                    (true, false) => driver.run(
                        &momentum::<K, IAD, $sw, true, false>(
                            flow,
                            f,
                            n,
                            $a,
                            $per,
                            (xm, product),
                            stress,
                        ),
                        out,
                    ),
                    (true, true) => driver.run(
                        &momentum::<K, IAD, $sw, true, true>(
                            flow,
                            f,
                            n,
                            $a,
                            $per,
                            (xm, product),
                            stress,
                        ),
                        out,
                    ),
                }
            };
        }
        match self.alpha {
            Alpha::Constant(a) => go!(false, a, &[]),
            Alpha::PerParticle(a) => go!(true, 0.0, &a[..n]),
        }
    }
}

/// The momentum stage over `flow` with the pair factors `f` (cut to `n`).
fn momentum<'a, K, const IAD: bool, const SWITCHED: bool, const VE: bool, const SPHEXA: bool>(
    flow: Flow<'a, K>,
    f: &'a PairFactors,
    n: usize,
    alpha: f64,
    alpha_per: &'a [f64],
    (xm, product): (&'a [f64], bool),
    (stress, cleaning, conduction): (
        Option<ArtificialStress>,
        Option<AvCleaning<'a>>,
        Option<Conductivity<'a>>,
    ),
) -> Momentum<'a, K, IAD, SWITCHED, VE, SPHEXA> {
    Momentum {
        flow,
        inv_h: &f.inv_h[..n],
        inv_rho: &f.inv_rho[..n],
        pre: &f.pre[..n],
        alpha,
        alpha_per,
        xm,
        product,
        stress,
        cleaning,
        conduction,
    }
}

/// The momentum and energy sums; `SWITCHED` selects `alpha_ij =
/// (alpha_per[i] + alpha_per[j]) / 2` over the constant `alpha` at compile
/// time, `IAD` the gradient operator, `VE` the volume-element weights
/// (`xm`), `SPHEXA` the viscosity and signal-velocity form
/// ([`AvForm::SphExa`]).
struct Momentum<'a, K, const IAD: bool, const SWITCHED: bool, const VE: bool, const SPHEXA: bool> {
    flow: Flow<'a, K>,
    inv_h: &'a [f64],
    inv_rho: &'a [f64],
    pre: &'a [f64],
    alpha: f64,
    alpha_per: &'a [f64],
    xm: &'a [f64],
    /// Weights `X_i X_j` ([`VolumeWeights::Product`]) instead of the
    /// Atwood blend.
    product: bool,
    stress: Option<ArtificialStress>,
    cleaning: Option<AvCleaning<'a>>,
    conduction: Option<Conductivity<'a>>,
}

/// One group's target values and sums in the momentum loop.
struct MomentumSums {
    vi: [F64s; 3],
    reach_i: F64s,
    inv_hi: F64s,
    /// `1 / h_i^2`.
    inv_hi2: F64s,
    ki3: F64s,
    /// `K / h_i^5`.
    ki5: F64s,
    ci: F64s,
    pre_i: F64s,
    inv_rho_i: F64s,
    alpha_i: F64s,
    /// The targets' `R_i` of the artificial stress.
    stress_i: F64s,
    /// Density and volume element of the targets (volume elements only).
    rho_i: F64s,
    xm_i: F64s,
    /// `ln X_i` of the targets, for the Atwood ramp (volume elements with
    /// blended weights only).
    ln_xm_i: F64s,
    /// `1 / m_i` (weights `X_i X_j` only).
    inv_m_i: F64s,
    /// The targets' symmetric velocity gradients (AV cleaning only).
    grad_i: [F64s; 6],
    ci_m: [F64s; 6],
    /// The targets' side of the conduction (conductivity only).
    cond_i: Option<ConductionTarget>,
    acc_a: [F64s; 3],
    /// `sum_j m_j v_ij . A_ij(h_i)`
    acc_ep: F64s,
    acc_eav: F64s,
    acc_div: F64s,
    acc_vsig: F64s,
    /// The conduction sum, before the factor `alpha_u`.
    acc_cond: F64s,
}

impl<K: Kernel, const IAD: bool, const SWITCHED: bool, const VE: bool, const SPHEXA: bool> PairStage
    for Momentum<'_, K, IAD, SWITCHED, VE, SPHEXA>
{
    type Sums = MomentumSums;
    type Out<'o> = [&'o mut [f64]; 4];
    type Stats = MomentumStats;

    #[inline(always)]
    fn start(&self, g: &Group) -> MomentumSums {
        let zero = F64s::splat(0.0);
        let reach_i = {
            let r = self.flow.support * g.load(self.flow.h);
            r * r
        };
        let inv_hi = g.load(self.inv_h);
        let ci = g.load(self.flow.c);
        MomentumSums {
            vi: self.flow.v.map(|v| g.load(v)),
            reach_i,
            inv_hi,
            inv_hi2: inv_hi * inv_hi,
            ki3: self.flow.norm * inv_hi * inv_hi * inv_hi,
            ki5: self.flow.norm * inv_hi * inv_hi * inv_hi * inv_hi * inv_hi,
            ci,
            pre_i: g.load(self.pre),
            inv_rho_i: g.load(self.inv_rho),
            alpha_i: if SWITCHED {
                g.load(self.alpha_per)
            } else {
                F64s::splat(self.alpha)
            },
            stress_i: self.stress.map_or(zero, |s| {
                let pre = g.load(self.pre);
                F64s::splat(s.epsilon) * (zero - pre).max(zero)
            }),
            rho_i: if VE { g.load(self.flow.rho) } else { zero },
            xm_i: if VE { g.load(self.xm) } else { zero },
            ln_xm_i: if VE && !self.product {
                F64s::from_array(g.load(self.xm).to_array().map(f64::ln))
            } else {
                zero
            },
            grad_i: match &self.cleaning {
                Some(cl) => cl.grad_v.map(|f| g.load(f)),
                None => [zero; 6],
            },
            inv_m_i: if VE && self.product {
                F64s::splat(1.0) / g.load(self.flow.m)
            } else {
                zero
            },
            ci_m: if IAD {
                self.flow.iad.map(|c| g.load(c))
            } else {
                [zero; 6]
            },
            acc_a: [zero; 3],
            acc_ep: zero,
            acc_eav: zero,
            acc_div: zero,
            acc_vsig: if SPHEXA { zero } else { ci },
            cond_i: self
                .conduction
                .map(|c| ConductionTarget::load(g, self.flow.norm, inv_hi, self.flow.rho, &c)),
            acc_cond: zero,
        }
    }

    #[inline(always)]
    fn pair(&self, t: &mut MomentumSums, j: usize, d: [F64s; 3], r2: F64s) {
        let zero = F64s::splat(0.0);
        let norm = self.flow.norm;
        let reach_j = {
            let r = self.flow.support * self.flow.h[j];
            r * r
        };
        // Lanes whose target has j as neighbour get weight 1, the others
        // compute with r = 1 (finite) and weight 0.
        let r2_true = r2;
        let (r2, weight) = neighbour_lanes(r2, t.reach_i, reach_j);
        let mj = self.flow.m[j] * weight;
        let inv_r = 1.0 / r2.sqrt();
        let rr = r2 * inv_r;
        let inv_hj = self.inv_h[j];
        let inv_hi = t.inv_hi;
        // A_ij(h_i), A_ij(h_j), the kernel shapes w(r/h_i), w(r/h_j) and,
        // with conduction, (K/h_i^4 w'(r/h_i) + K/h_j^4 w'(r/h_j)) / 2.
        let (ai, aj, shape_i, shape_j, dw_mean) = if IAD {
            // A = C (x_j - x_i) W = -(C d) W
            // The shapes from v^2 = r^2 / h^2: no root on their path.
            let si = self.flow.kernel.shape_sq_lanes(r2 * t.inv_hi2);
            let sj = self.flow.kernel.shape_sq_lanes(r2 * (inv_hj * inv_hj));
            // The derivatives at the true distance, as the conduction's own
            // pass takes them (measured faster than from `rr` here).
            let dw_mean = match &t.cond_i {
                Some(ci) => ci.mean_derivative(self.flow.kernel, norm, r2_true, inv_hi, inv_hj),
                None => zero,
            };
            let kj3 = norm * inv_hj * inv_hj * inv_hj;
            let wi = t.ki3 * si;
            let wj = kj3 * sj;
            let cj = [0, 1, 2, 3, 4, 5].map(|k| F64s::splat(self.flow.iad[k][j]));
            let cd = sym_mat_vec_fused(&t.ci_m, d);
            let cdj = sym_mat_vec_fused(&cj, d);
            (scale3(cd, -wi), scale3(cdj, -wj), si, sj, dw_mean)
        } else {
            // grad_i W(r, h) = K/h^4 w'(r/h) d / r = K/h^5 (w'(v)/v) d, from
            // v^2 = r^2 / h^2: no root on the gradient's path.
            let (v2i, v2j) = (r2 * t.inv_hi2, r2 * (inv_hj * inv_hj));
            let gi = t.ki5 * self.flow.kernel.derivative_over_v_sq_lanes(v2i);
            let kj5 = norm * inv_hj * inv_hj * inv_hj * inv_hj * inv_hj;
            let gj = kj5 * self.flow.kernel.derivative_over_v_sq_lanes(v2j);
            // The shapes only feed the artificial stress.
            let (si, sj) = match self.stress {
                Some(_) => (
                    self.flow.kernel.shape_sq_lanes(v2i),
                    self.flow.kernel.shape_sq_lanes(v2j),
                ),
                None => (zero, zero),
            };
            // K/h^4 w'(r/h) = (K/h^5 w'/v) r.
            (scale3(d, gi), scale3(d, gj), si, sj, 0.5 * (gi + gj) * rr)
        };
        if let (Some(c), Some(ci)) = (&self.conduction, &t.cond_i) {
            let (rho_j, p_j, u_j) = (self.flow.rho[j], c.p[j], c.u[j]);
            t.acc_cond += ci.term(mj, dw_mean, rho_j, p_j, u_j);
        }
        let vi = t.vi;
        let vij = [
            vi[0] - self.flow.v[0][j],
            vi[1] - self.flow.v[1][j],
            vi[2] - self.flow.v[2][j],
        ];
        let mut rv = dot_fused(vij, d);
        if let Some(cl) = &self.cleaning {
            let cleaned =
                rv + cleaning_correction(cl, t.grad_i, j, d, rr * inv_hi.min(F64s::splat(inv_hj)));
            // Only approaching pairs: the viscous heating uses the raw jump.
            rv = rv.where_negative(cleaned);
        }
        let w = rv * inv_r;
        let alpha_ij = if SWITCHED {
            0.5 * (t.alpha_i + self.alpha_per[j])
        } else {
            F64s::splat(self.alpha)
        };
        let visc = if SPHEXA {
            let cij = t.ci + self.flow.c[j];
            // Courant: (c_i + c_j)/2 - 2 w over every neighbour.
            let minus_two = F64s::splat(-2.0);
            t.acc_vsig = t.acc_vsig.max(minus_two.mul_add(w, 0.5 * cij) * weight);
            w.where_negative(-minus_two.mul_add(w, 0.5 * alpha_ij * cij) * w)
        } else {
            let vsig = F64s::splat(-3.0).mul_add(w.min(zero), t.ci + self.flow.c[j]);
            t.acc_vsig = t.acc_vsig.max(vsig * weight);
            w.where_negative(-0.5 * alpha_ij * vsig * w)
        };
        let mut vi_r = 0.5 * visc * t.inv_rho_i;
        let inv_rho_j = self.inv_rho[j];
        let mut vj_r = 0.5 * visc * inv_rho_j;
        if let Some(s) = self.stress {
            // R_ij f^4 / 2 on each side: -m_j R_ij f^4 (A_i + A_j) / 2.
            let rj = s.epsilon * (-self.pre[j]).max(0.0);
            let f = 0.5 * s.inv_w_spacing * (shape_i + shape_j);
            let f2 = f * f;
            let half = 0.5 * (t.stress_i + rj) * f2 * f2;
            vi_r += half;
            vj_r += half;
        }
        let (ci_f, cj_f, a_mom) = if VE {
            let (a, b) = if self.product {
                // X_i X_j / m_j and, for the j side, X_i X_j / m_i.
                let cross = t.xm_i * self.xm[j];
                (cross * (1.0 / self.flow.m[j]), cross * t.inv_m_i)
            } else {
                atwood_weights(t.rho_i, self.flow.rho[j], t.xm_i, t.ln_xm_i, self.xm[j])
            };
            (t.pre_i * a + vi_r, self.pre[j] * b + vj_r, a)
        } else {
            (t.pre_i + vi_r, self.pre[j] + vj_r, F64s::splat(1.0))
        };
        // The sums by fused multiply-adds where the build has them (fewer
        // operations and a shorter chain per pair; the scalar reference of
        // the lane test takes the same forms).
        let neg_mj = -mj;
        for c in 0..3 {
            let f = ci_f.mul_add(ai[c], cj_f * aj[c]);
            t.acc_a[c] = neg_mj.mul_add(f, t.acc_a[c]);
        }
        let vai = dot_fused(vij, ai);
        let vaj = dot_fused(vij, aj);
        let ep_weight = if VE { mj * a_mom } else { mj };
        t.acc_ep = ep_weight.mul_add(vai, t.acc_ep);
        t.acc_eav = mj.mul_add(vi_r.mul_add(vai, vj_r * vaj), t.acc_eav);
        t.acc_div = (neg_mj * inv_rho_j).mul_add(vai, t.acc_div);
    }

    #[inline(always)]
    fn finish(&self, g: &Group, t: MomentumSums, [ax, ay, az, du]: Self::Out<'_>) -> MomentumStats {
        t.acc_a[0].store(ax);
        t.acc_a[1].store(ay);
        t.acc_a[2].store(az);
        let du_i = t.pre_i * t.acc_ep + 0.5 * t.acc_eav;
        match self.conduction {
            Some(c) => (du_i + c.alpha_u * t.acc_cond).store(du),
            None => du_i.store(du),
        }
        let vsig = if SPHEXA {
            F64s::select_positive(t.acc_vsig, t.acc_vsig, t.ci)
        } else {
            t.acc_vsig
        };
        let h_over_vsig = (1.0 / (t.inv_hi * vsig)).to_array();
        let div = t.acc_div.to_array();
        let mut st = MomentumStats::identity();
        for l in 0..g.valid {
            st.min_h_over_vsig = st.min_h_over_vsig.min(h_over_vsig[l]);
            let d = if SPHEXA {
                div[l].max(0.0)
            } else {
                div[l].abs()
            };
            st.max_abs_div_v = st.max_abs_div_v.max(d);
        }
        st
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

/// The AV cleaning's additive correction to `r . v_ij` ([`AvCleaning`])
/// for partner `j` at separation `d = x_i - x_j`, `eta = min(r/h_i, r/h_j)`.
#[inline(always)]
fn cleaning_correction(
    cl: &AvCleaning<'_>,
    gi: [F64s; 6],
    j: usize,
    d: [F64s; 3],
    eta: F64s,
) -> F64s {
    let zero = F64s::splat(0.0);
    let gj = cl.grad_v.map(|g| F64s::splat(g[j]));
    let quad = |g: [F64s; 6]| {
        let gd = sym_mat_vec(&g, d);
        gd[0] * d[0] + gd[1] * d[1] + gd[2] * d[2]
    };
    let (qi, qj) = (quad(gi), quad(gj));
    // phi (qi + qj) with phi = clamp(4 A / (1 + A)^2, 0, 1) / 2, A = qi / qj,
    // is 2 qi qj / (qi + qj), the harmonic mean of the two sides'
    // reconstructions, where they agree in sign (AM-GM keeps 4 A / (1 + A)^2
    // within (0, 1] there), and 0 where they do not: one division, no clamp.
    let prod = qi * qj;
    let agree = prod.gt(zero);
    let mean = agree.select(2.0 * prod / agree.select(qi + qj, F64s::splat(1.0)), zero);
    let mut damp = F64s::splat(1.0);
    if eta.min_lane() < cl.eta_crit {
        // Pairs closer than the spacing (rare): damped toward r = 0.
        let e = eta.to_array();
        damp = F64s::from_array(std::array::from_fn(|l| {
            if e[l] < cl.eta_crit {
                let x = 5.0 * (e[l] - cl.eta_crit);
                (-x * x).exp()
            } else {
                1.0
            }
        }));
    }
    -(damp * mean)
}

/// SPH-EXA's momentum weights `(a_ij, b_ij)` of pair `i, j` from the
/// Atwood number of the densities and the volume elements (see
/// [`momentum_energy_with`]; `ln_xi` holds `ln X_i`); `b_ij` of `i, j` is
/// bit for bit `a_ji`, so the pair terms stay antisymmetric.
#[inline(always)]
fn atwood_weights(rho_i: F64s, rho_j: f64, xi: F64s, ln_xi: F64s, xj: f64) -> (F64s, F64s) {
    let rho_j = F64s::splat(rho_j);
    // At < c as |rho_i - rho_j| < c (rho_i + rho_j): no division per pair
    // (the divider is the pair loop's scarcest unit).
    let (jump, sum) = ((rho_i - rho_j).abs(), rho_i + rho_j);
    let xj_l = F64s::splat(xj);
    let cross = xi * xj_l;
    let low = jump.lt(ATWOOD_MIN * sum);
    let high = jump.gt(ATWOOD_MAX * sum);
    let mut a = low.select(xi * xi, cross);
    let mut b = low.select(xj_l * xj_l, cross);
    if !(low | high).all() {
        // The ramp, lane by lane (interfaces, and wherever the density
        // varies by more than ~20% over a kernel: Evrard's whole sphere).
        // X_i^(2-s) X_j^s = X_i^2 exp(s d) with d = ln X_j - ln X_i: two
        // exponentials per lane where four powers cost a quarter of an
        // Evrard step. With i and j swapped d changes sign exactly, so
        // b_ij = X_j^2 exp(-s d) is a_ji bit for bit.
        let at_l = (jump / sum).to_array();
        // Lanes on the ramp: neither below nor above it.
        let on_ramp = !(low | high).bits();
        let (xi_l, ln_xi_l) = (xi.to_array(), ln_xi.to_array());
        let (mut al, mut bl) = (a.to_array(), b.to_array());
        let (ramp, ln_xj, xj2) = (1.0 / (ATWOOD_MAX - ATWOOD_MIN), xj.ln(), xj * xj);
        for l in 0..LANES {
            if on_ramp & (1 << l) != 0 {
                let s = (ramp * (at_l[l] - ATWOOD_MIN)).clamp(0.0, 1.0);
                let sd = s * (ln_xj - ln_xi_l[l]);
                al[l] = xi_l[l] * xi_l[l] * sd.exp();
                bl[l] = xj2 * (-sd).exp();
            }
        }
        a = F64s::from_array(al);
        b = F64s::from_array(bl);
    }
    (a, b)
}

/// `a . b` as `a_z b_z + (a_y b_y + a_x b_x)`, fused where the build has
/// multiply-adds.
#[inline(always)]
fn dot_fused(a: [F64s; 3], b: [F64s; 3]) -> F64s {
    a[2].mul_add(b[2], a[1].mul_add(b[1], a[0] * b[0]))
}

/// `C v` for a symmetric matrix (as [`sym_mat_vec`]), each row a
/// [`dot_fused`].
#[inline(always)]
fn sym_mat_vec_fused(c: &[F64s; 6], v: [F64s; 3]) -> [F64s; 3] {
    [
        dot_fused([c[0], c[1], c[2]], v),
        dot_fused([c[1], c[3], c[4]], v),
        dot_fused([c[2], c[4], c[5]], v),
    ]
}

#[inline(always)]
fn scale3(v: [F64s; 3], f: F64s) -> [F64s; 3] {
    [v[0] * f, v[1] * f, v[2] * f]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The Atwood weights are SPH-EXA's `X_i^(2-s) X_j^s` (to
        /// round-off) and `b_ij` is `a_ji` bit for bit, on and off the
        /// ramp.
        #[test]
        fn atwood_weights_are_the_blend_and_antisymmetric(
            rho in proptest::collection::vec(0.1f64..10.0, LANES + 1),
            x in proptest::collection::vec(1e-6f64..1.0, LANES + 1),
        ) {
            let rho_i = F64s::from_array(std::array::from_fn(|l| rho[l]));
            let x_i = F64s::from_array(std::array::from_fn(|l| x[l]));
            let ln_x_i = F64s::from_array(x_i.to_array().map(f64::ln));
            let (rho_j, x_j) = (rho[LANES], x[LANES]);
            let (a, b) = atwood_weights(rho_i, rho_j, x_i, ln_x_i, x_j);
            let (a, b) = (a.to_array(), b.to_array());
            for l in 0..LANES {
                let at = (rho[l] - rho_j).abs() / (rho[l] + rho_j);
                let s = ((at - ATWOOD_MIN) / (ATWOOD_MAX - ATWOOD_MIN)).clamp(0.0, 1.0);
                let want = x[l].powf(2.0 - s) * x_j.powf(s);
                prop_assert!((a[l] - want).abs() <= 1e-13 * want, "a {} vs {want} at At {at}", a[l]);
                // The pair seen from j: one lane holding j, partner i.
                let (a_ji, _) = atwood_weights(
                    F64s::splat(rho_j),
                    rho[l],
                    F64s::splat(x_j),
                    F64s::splat(x_j.ln()),
                    x[l],
                );
                prop_assert_eq!(b[l].to_bits(), a_ji.to_array()[0].to_bits());
            }
        }
    }
}
