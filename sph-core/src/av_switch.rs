//! Time-dependent artificial-viscosity switches: a per-particle viscosity
//! strength `alpha_i` in `[alpha_min, alpha_max]` (SPH-EXA's "ve"
//! propagator, after Cullen & Dehnen 2010).
//!
//! Two passes over the neighbour lists, with an exchange of the halo
//! particles' `div v` between them:
//!
//! 1. [`velocity_divergence`]: `div v_i` (and optionally `|curl v_i|`) from
//!    the velocity gradient
//!    `d_a v_b (i) = sum_j V_j (v_j - v_i)_b A_ij,a`, `V_j = m_j / rho_j`,
//!    with `A_ij = C_i (x_j - x_i) W(r_ij, h_i)` (IAD, exact for linear
//!    velocity fields) or `A_ij = grad_i W(r_ij, h_i)` (plain kernel).
//! 2. [`update_alpha`] (or [`shock_indicator`] for the indicator alone):
//!    `grad(div v)_i = sum_j V_j (div v_j - div v_i) A_ij`, the local target
//!    [`AvSwitchParams::local_alpha`] and the signal velocity
//!    `v_sig,i = max(c_i, max_j (c_i + c_j - 3 min(w_ij, 0)))`
//!    (`w_ij = v_ij . x_ij / r_ij`), then the relaxation
//!    [`AvSwitchParams::advance`] of `alpha_i` over the elapsed time `dt`.
//!
//! The momentum stage then uses `alpha_ij = (alpha_i + alpha_j) / 2`
//! ([`momentum_energy_switched`](crate::momentum::momentum_energy_switched)),
//! which needs `alpha` of the halo particles: a second exchange.
//!
//! All stages run in parallel over the targets of the list and sum the
//! neighbours in ascending order, so the results do not depend on the
//! number of threads.
//!
//! # Differences from SPH-EXA
//! [`SwitchForm::SphExa`] (the `ve` preset) follows SPH-EXA's relaxation
//! and decay signal velocity as written; the default
//! [`SwitchForm::Smooth`] differs in the first two points below.
//! - SPH-EXA integrates `d alpha / dt = (target - alpha) / tau` with one
//!   explicit Euler step; here the exact solution over `dt` for a frozen
//!   target is used, `alpha <- target + (alpha - target) exp(-dt / tau)`,
//!   which agrees to first order and never overshoots for `dt > tau`.
//! - SPH-EXA's decay signal velocity counts approaching pairs only (and is
//!   `1e-40 c_i` without them, so `alpha` never decays in a uniform flow);
//!   here every neighbour counts with `min(w_ij, 0)`, as in the Courant
//!   signal velocity of the momentum stage, so `v_sig,i >= c_i`.
//! - Volumes are `m_j / rho_j`, the ones the IAD matrices of
//!   [`iad`](crate::iad::iad) are built with, so the IAD divergence of a
//!   linear field is exact (SPH-EXA divides by its grad-h factor as well).
//!   With generalised volume elements `m_j / rho_j = X_j / k_j`; SPH-EXA's
//!   `ve` divergence uses `X_j / k_i`, exact only where `k` is uniform.
//!
//! # Example
//! ```
//! use sph_core::av_switch::{update_alpha, velocity_divergence, AvSwitchParams, FlowState};
//! use sph_core::density::{density, Positions};
//! use sph_core::iad::iad;
//! use sph_core::{FieldSet, Gradients, Particles};
//! use sph_kernels::{Sinc, Tabulated};
//! use sph_tree::{Boundary, BoundingBox, CompactNeighborList, NeighborSearch, Octree};
//! use sph_tree::{apply_permutation, compute_keys, Curve, KeySorter};
//!
//! // A 10^3 lattice of cold gas in a periodic box, converging towards x = 0.
//! let n = 10;
//! let mut p = Particles::new(n * n * n, FieldSet::default());
//! for i in 0..p.len() {
//!     let c = [i % n, i / n % n, i / (n * n)].map(|k| (k as f64 + 0.5) / n as f64 - 0.5);
//!     (p.x[i], p.y[i], p.z[i]) = (c[0], c[1], c[2]);
//!     p.vx[i] = -(c[0] / 0.1).tanh();
//!     p.m[i] = 1.0 / p.len() as f64;
//!     p.h[i] = 1.3 / n as f64;
//!     p.c[i] = 1e-3;
//! }
//! let bbox = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
//! let mut keys = Vec::new();
//! compute_keys(&bbox, Curve::Hilbert, &p.x, &p.y, &p.z, &mut keys);
//! let mut perm = Vec::new();
//! KeySorter::new().sort(&keys, None, &mut perm);
//! p.reorder(&perm, &mut Vec::new());
//! apply_permutation(&perm, &mut keys, &mut Vec::new());
//! let tree = Octree::build(&keys, &p.x, &p.y, &p.z, 16).unwrap();
//! let mut nl = CompactNeighborList::new();
//! NeighborSearch::default()
//!     .find_compact(&tree, &bbox, &p.x, &p.y, &p.z, &p.h, 0..p.len(), &mut nl)
//!     .unwrap();
//! let kernel = Tabulated::new(&Sinc::new(6.0).unwrap(), Tabulated::DEFAULT_POINTS).unwrap();
//! let pos = Positions { x: &p.x, y: &p.y, z: &p.z, h: &p.h, m: &p.m };
//! density(&kernel, &bbox, pos, &nl, &mut p.rho, &mut p.omega);
//! iad(&kernel, &bbox, pos, &p.rho, &nl, &mut p.iad).unwrap();
//!
//! let flow = FlowState {
//!     pos,
//!     vx: &p.vx,
//!     vy: &p.vy,
//!     vz: &p.vz,
//!     rho: &p.rho,
//!     c: &p.c,
//!     iad: std::array::from_fn(|k| p.iad[k].as_slice()),
//! };
//! let mut div_v = vec![0.0; p.len()];
//! velocity_divergence(&kernel, &bbox, flow, Gradients::Iad, &nl, &mut div_v, &mut [], &mut []);
//! // (several ranks: exchange div_v of the halo particles here)
//! let params = AvSwitchParams::default();
//! let mut alpha = vec![params.alpha_min; p.len()];
//! update_alpha(&kernel, &bbox, flow, Gradients::Iad, &div_v, &params, 1e-3, &nl, &mut alpha);
//! // (several ranks: exchange alpha of the halo particles here)
//! let max = alpha.iter().cloned().fold(0.0, f64::max);
//! assert!(max > 0.5 && max <= params.alpha_max);
//! assert!(alpha.iter().all(|&a| a >= params.alpha_min));
//! ```

use crate::flow::Flow;
pub use crate::flow::FlowState;
use crate::iad::{store_matrices, FirstSingular, Singular, Tau, TauSums};
use crate::pair_loop::Gradients;
use crate::pair_loop::{
    neighbour_lanes, sym_mat_vec, with_gradients, F64s, Group, PairStage, WithGradients, LANES,
};
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList};

/// Parameters of the viscosity switch (defaults: SPH-EXA's).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AvSwitchParams {
    /// Lowest viscosity strength (0.05), the value `alpha` decays to away
    /// from shocks.
    pub alpha_min: f64,
    /// Highest viscosity strength (1); the local target approaches it for a
    /// strong shock indicator.
    pub alpha_max: f64,
    /// Decay constant `l` of the decay time `tau_i = h_i / (l v_sig,i)` (0.2).
    pub decay: f64,
    /// Weight of the sound speed in the denominator of the local target
    /// (0.05): compression slower than this fraction of `c` per `h` does
    /// not switch the viscosity on.
    pub sound_weight: f64,
    /// How `alpha` relaxes and which signal velocity sets the decay time.
    #[serde(default)]
    pub form: SwitchForm,
    /// The ceiling at weak shocks, or `None` for `alpha_max` at every
    /// shock. With it a particle's ceiling depends on the pair Mach
    /// number `M_i = max_j max(-w_ij, 0) / ((c_i + c_j) / 2)` of its
    /// fastest approaching neighbour ([`AvSwitchParams::ceiling`]): near
    /// `weak_alpha` for weak shocks and slow compression, `alpha_max` for
    /// strong shocks into cold gas. Weak shocks ring behind the front
    /// unless alpha is about 1 there (Sod); strong ones overheat the
    /// shocked gas with it (Noh), where the quadratic term carries the
    /// jump (`docs/schemes.md`, 2026-12-06, one scheme).
    #[serde(default)]
    pub weak_alpha: Option<f64>,
}

/// How the switch relaxes `alpha` towards its target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SwitchForm {
    /// Exact exponential decay over `dt` for a frozen target, clamped to
    /// `[alpha_min, alpha_max]`; the decay signal velocity counts every
    /// neighbour, `v_sig,i = max(c_i, max_j (c_i + c_j - 3 min(w_ij, 0)))`.
    #[default]
    Smooth,
    /// SPH-EXA's `hydro_ve` switch as written: one explicit Euler step
    /// `alpha += (max(alpha_loc, alpha_min) - alpha) / tau * dt` (no
    /// clamp), and a decay signal velocity over approaching pairs only,
    /// `v_sig,i = max(1e-40 c_i, max_{j: w_ij < 0} (c_i + c_j - 3 w_ij))`
    /// (so `alpha` stays put where nothing approaches).
    SphExa,
}

impl Default for AvSwitchParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl AvSwitchParams {
    /// SPH-EXA's parameters.
    pub const DEFAULT: AvSwitchParams = AvSwitchParams {
        alpha_min: 0.05,
        alpha_max: 1.0,
        decay: 0.2,
        sound_weight: 0.05,
        form: SwitchForm::Smooth,
        weak_alpha: None,
    };

    /// The pair Mach number at which the ceiling is half-way between
    /// `weak_alpha` and `alpha_max`: pairs approaching at a quarter of
    /// their summed sound speeds (Sod's shock is on the weak side; Noh's
    /// and Sedov's, into cold gas, far on the strong side). Not tuned
    /// beyond 0.5 and 1 (`docs/schemes.md`, 2026-12-06 evening).
    pub const WEAK_MACH: f64 = 0.5;

    /// SPH-EXA's `hydro_ve` switch: its parameters and
    /// [`SwitchForm::SphExa`].
    pub const SPHEXA: AvSwitchParams = AvSwitchParams {
        form: SwitchForm::SphExa,
        ..Self::DEFAULT
    };

    /// Whether `0 <= alpha_min <= alpha_max`, `decay > 0` and
    /// `sound_weight >= 0` (all finite).
    pub fn is_valid(&self) -> bool {
        self.alpha_min >= 0.0
            && self.alpha_min <= self.alpha_max
            && self.alpha_max.is_finite()
            && self.decay > 0.0
            && self.decay.is_finite()
            && self.sound_weight >= 0.0
            && self.sound_weight.is_finite()
            && self.weak_alpha.is_none_or(|a| a >= 0.0 && a.is_finite())
    }

    /// The ceiling of `alpha` for a particle whose fastest approaching
    /// neighbour has the pair Mach number `mach` (>= 0):
    ///
    /// ```text
    /// ceiling = alpha_max + (weak_alpha - alpha_max) / (1 + (mach / WEAK_MACH)^2)
    /// ```
    ///
    /// `alpha_max` without `weak_alpha`.
    ///
    /// ```
    /// use sph_core::av_switch::AvSwitchParams;
    /// let p = AvSwitchParams { alpha_max: 0.5, weak_alpha: Some(2.0), ..AvSwitchParams::DEFAULT };
    /// assert_eq!(p.ceiling(0.0), 2.0);
    /// assert_eq!(p.ceiling(AvSwitchParams::WEAK_MACH), 1.25);
    /// assert!(p.ceiling(100.0) < 0.5001);
    /// assert_eq!(AvSwitchParams::DEFAULT.ceiling(0.0), 1.0);
    /// ```
    #[inline]
    pub fn ceiling(&self, mach: f64) -> f64 {
        match self.weak_alpha {
            None => self.alpha_max,
            Some(weak) => {
                let m = mach / Self::WEAK_MACH;
                self.alpha_max + (weak - self.alpha_max) / (1.0 + m * m)
            }
        }
    }

    /// The local target of the switch from the shock indicator:
    ///
    /// ```text
    /// alpha_loc = alpha_max h^2 |grad div v| / (h^2 |grad div v| + h |div v| + sound_weight c)   if div v < 0
    ///           = 0                                                                             otherwise
    /// ```
    ///
    /// It is near `alpha_max` where the compression steepens quickly (ahead
    /// of a shock), and small in uniform compression (`grad div v = 0`).
    #[inline]
    pub fn local_alpha(&self, div_v: f64, grad_div_v: f64, h: f64, c: f64) -> f64 {
        if div_v < 0.0 {
            let a = h * h * grad_div_v;
            self.alpha_max * a / (a - h * div_v + self.sound_weight * c)
        } else {
            0.0
        }
    }

    /// The decay time `tau = h / (decay v_sig)`.
    #[inline]
    pub fn decay_time(&self, h: f64, v_sig: f64) -> f64 {
        h / (self.decay * v_sig)
    }

    /// Advances `alpha` over a time `dt >= 0` towards the local target:
    /// a jump to `alpha_loc` where `alpha_loc >= alpha`, else the
    /// exponential decay towards `target = max(alpha_loc, alpha_min)`,
    ///
    /// ```text
    /// alpha <- target + (alpha - target) exp(-dt / tau),
    /// ```
    ///
    /// the result clamped to `[alpha_min, alpha_max]`.
    ///
    /// ```
    /// use sph_core::av_switch::AvSwitchParams;
    /// let p = AvSwitchParams::default();
    /// // A shock ahead: jump up.
    /// assert_eq!(p.advance(0.1, 0.8, 1.0, 0.01), 0.8);
    /// // Quiet flow: decay to alpha_min with the time scale tau.
    /// let a = p.advance(1.0, 0.0, 2.0, 2.0);
    /// assert!((a - (0.05 + 0.95 * (-1.0f64).exp())).abs() < 1e-15);
    /// ```
    ///
    /// With [`SwitchForm::SphExa`]: the jump up as above, else one Euler
    /// step `alpha + (max(alpha_loc, alpha_min) - alpha) dt / tau`,
    /// unclamped.
    #[inline]
    pub fn advance(&self, alpha: f64, alpha_loc: f64, tau: f64, dt: f64) -> f64 {
        if self.form == SwitchForm::SphExa {
            if alpha_loc >= alpha {
                return alpha_loc;
            }
            let target = if alpha_loc >= self.alpha_min {
                alpha_loc
            } else {
                self.alpha_min
            };
            return alpha + (target - alpha) / tau * dt;
        }
        let next = if alpha_loc >= alpha {
            alpha_loc
        } else {
            let target = alpha_loc.max(self.alpha_min);
            target + (alpha - target) * (-dt / tau).exp()
        };
        next.clamp(self.alpha_min, self.alpha_max)
    }
}

/// The Balsara (1995) shear limiter of particle `i`:
///
/// ```text
/// f_i = |div v_i| / (|div v_i| + |curl v_i| + 1e-4 c_i / h_i)
/// ```
///
/// near 1 in compression (or expansion) without vorticity, near 0 in
/// shear; 0 when the flow and the sound speed vanish.
///
/// ```
/// use sph_core::av_switch::balsara;
/// assert!(balsara(-3.0, 0.0, 1.0, 0.1) > 0.999);
/// assert!(balsara(0.0, 1.0, 1.0, 0.1) == 0.0);
/// ```
#[inline]
pub fn balsara(div_v: f64, curl_v: f64, c: f64, h: f64) -> f64 {
    let d = div_v.abs();
    let denom = d + curl_v.abs() + 1e-4 * c / h;
    if denom > 0.0 {
        d / denom
    } else {
        0.0
    }
}

/// Weight of the pair term `d = x_i - x_j` before the final factors, for
/// a lane of targets at squared distances `r2`: with IAD `W` shape (the
/// gradient is `-C d W`), plain `S'(v) / r` (the gradient is
/// `K/h^4 S'(v) d / r`; lanes at `r = 0`, the target itself, get 0); both
/// from `r2` without a root.
#[inline(always)]
fn pair_weight<K: Kernel, const IAD: bool>(kernel: &K, r2: F64s, inv_h: F64s) -> F64s {
    if IAD {
        kernel.shape_sq_lanes(r2 * (inv_h * inv_h))
    } else {
        // S'(v) / r = (S'(v) / v) / h, from r^2 without a root or a division.
        let w = kernel.derivative_over_v_sq_lanes(r2 * (inv_h * inv_h)) * inv_h;
        F64s::select_positive(r2, w, F64s::splat(0.0))
    }
}

/// Velocity gradient `G_ab = d_a v_b` of every target: `div v` and,
/// optionally, `|curl v|`.
struct VelocityGradient<'a, K, const IAD: bool>(Flow<'a, K>);

/// A group's velocities, `1/h` and `m[c][b] = sum_j V_j w_j d_c (v_j - v_i)_b`.
type GradientSums = ([F64s; 3], F64s, [[F64s; 3]; 3]);

impl<K: Kernel, const IAD: bool> PairStage for VelocityGradient<'_, K, IAD> {
    type Sums = GradientSums;
    /// `div v`, optionally `|curl v|`, optionally the symmetric gradient
    /// `(G_xx, G_xy, G_xz, G_yy, G_yz, G_zz)`, `G_ab = (d_a v_b + d_b v_a) / 2`.
    type Out<'o> = (
        [&'o mut [f64]; 1],
        (Option<[&'o mut [f64]; 1]>, Option<[&'o mut [f64]; 6]>),
    );
    type Stats = ();

    #[inline(always)]
    fn start(&self, g: &Group) -> GradientSums {
        let f = &self.0;
        let vi = f.v.map(|v| g.load(v));
        (vi, 1.0 / g.load(f.h), [[F64s::splat(0.0); 3]; 3])
    }

    #[inline(always)]
    fn pair(&self, sums: &mut GradientSums, j: usize, d: [F64s; 3], r2: F64s) {
        self.add(sums, j, d, pair_weight::<K, IAD>(self.0.kernel, r2, sums.1));
    }

    #[inline(always)]
    fn finish(&self, g: &Group, sums: GradientSums, out: &mut Self::Out<'_>) {
        let c = if IAD {
            self.0.iad.map(|c| g.load(c))
        } else {
            [F64s::splat(0.0); 6]
        };
        self.store(c, sums, out);
    }
}

impl<K: Kernel, const IAD: bool> VelocityGradient<'_, K, IAD> {
    /// Adds partner `j` at separation `d` with kernel weight `weight`
    /// ([`pair_weight`]).
    #[inline(always)]
    fn add(&self, (vi, _, m): &mut GradientSums, j: usize, d: [F64s; 3], weight: F64s) {
        let f = &self.0;
        let w = f.m[j] / f.rho[j] * weight;
        let dv = [f.v[0][j] - vi[0], f.v[1][j] - vi[1], f.v[2][j] - vi[2]];
        for (mc, dc) in m.iter_mut().zip(d) {
            let wd = w * dc;
            for (mcb, dvb) in mc.iter_mut().zip(dv) {
                *mcb += wd * dvb;
            }
        }
    }

    /// `div v` (and `|curl v|`) of the group from its sums, with the
    /// targets' inverse IAD matrices `c` (read with IAD only).
    #[inline(always)]
    fn store(
        &self,
        c: [F64s; 6],
        (_, inv_h, m): GradientSums,
        ([dv], (cv, sym)): &mut <Self as PairStage>::Out<'_>,
    ) {
        let f = &self.0;
        let k3 = f.norm * inv_h * inv_h * inv_h;
        let zero = F64s::splat(0.0);
        let gr = if IAD {
            // A_ij = -C d W: G = -K/h^3 C m
            let mut out = [[zero; 3]; 3];
            for b in 0..3 {
                let col = sym_mat_vec(&c, [m[0][b], m[1][b], m[2][b]]);
                for a in 0..3 {
                    out[a][b] = -k3 * col[a];
                }
            }
            out
        } else {
            // A_ij = K/h^4 S' d / r: G = K/h^4 m
            let k4 = k3 * inv_h;
            m.map(|row| row.map(|v| k4 * v))
        };
        (gr[0][0] + gr[1][1] + gr[2][2]).store(dv);
        if let Some([cv]) = cv {
            let curl = [
                gr[1][2] - gr[2][1],
                gr[2][0] - gr[0][2],
                gr[0][1] - gr[1][0],
            ];
            (curl[0] * curl[0] + curl[1] * curl[1] + curl[2] * curl[2])
                .sqrt()
                .store(cv);
        }
        if let Some([xx, xy, xz, yy, yz, zz]) = sym {
            gr[0][0].store(xx);
            (0.5 * (gr[0][1] + gr[1][0])).store(xy);
            (0.5 * (gr[0][2] + gr[2][0])).store(xz);
            gr[1][1].store(yy);
            (0.5 * (gr[1][2] + gr[2][1])).store(yz);
            gr[2][2].store(zz);
        }
    }
}

/// Velocity divergence of every target of `nl`, and, when `curl_v` is not
/// empty, the magnitude of the curl:
///
/// ```text
/// d_a v_b (i) = sum_j (m_j / rho_j) (v_j - v_i)_b A_ij,a
/// div v_i  = sum_a d_a v_a,      |curl v_i| = |(d_y v_z - d_z v_y, d_z v_x - d_x v_z, d_x v_y - d_y v_x)|
/// ```
///
/// with `A_ij = C_i (x_j - x_i) W(r_ij, h_i)` ([`Gradients::Iad`]: exact
/// for a linear velocity field) or `A_ij = grad_i W(r_ij, h_i)`
/// ([`Gradients::Kernel`]). Reads positions, `h`, `m`, `rho`, `v` of the
/// targets and their neighbours and `C` of the targets; writes
/// `div_v[i]` (and `curl_v[i]`) for the targets only. When `grad_v` holds
/// six fields they receive the symmetric gradient `(d_a v_b + d_b v_a)/2`
/// in the order xx, xy, xz, yy, yz, zz (for [`AvCleaning`](crate::momentum::AvCleaning));
/// pass `&mut []` for none.
///
/// # Panics
/// If the arrays differ in length or do not cover the lists.
#[allow(clippy::too_many_arguments)]
pub fn velocity_divergence<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    flow: FlowState<'_>,
    gradients: Gradients,
    nl: &CompactNeighborList,
    div_v: &mut [f64],
    curl_v: &mut [f64],
    grad_v: &mut [Vec<f64>],
) {
    struct Run<'a, K> {
        kernel: &'a K,
        bbox: &'a BoundingBox,
        flow: FlowState<'a>,
        nl: &'a CompactNeighborList,
        div_v: &'a mut [f64],
        curl_v: &'a mut [f64],
        grad_v: &'a mut [Vec<f64>],
    }
    impl<K: Kernel> WithGradients for Run<'_, K> {
        type Output = ();
        fn run<const IAD: bool>(self) {
            let driver = Flow::driver(self.bbox, self.kernel, &self.flow, self.nl);
            let stage = VelocityGradient::<K, IAD>(Flow::new(self.kernel, &self.flow, IAD));
            let r = self.nl.targets();
            let curl = (!self.curl_v.is_empty()).then(|| [&mut self.curl_v[r.clone()]]);
            let sym = sym_out(self.grad_v, r.clone());
            driver.run(&stage, ([&mut self.div_v[r]], (curl, sym)));
        }
    }
    let run = Run {
        kernel,
        bbox,
        flow,
        nl,
        div_v,
        curl_v,
        grad_v,
    };
    with_gradients(gradients, run);
}

/// The targets' slices of the six symmetric-gradient fields, when there
/// are six (none asked for when empty).
fn sym_out(grad_v: &mut [Vec<f64>], r: std::ops::Range<usize>) -> Option<[&mut [f64]; 6]> {
    let [a, b, c, d, e, f] = grad_v else {
        return None;
    };
    Some([a, b, c, d, e, f].map(|v| &mut v[r.clone()]))
}

/// The IAD matrices ([`iad_volumes`](crate::iad::iad_volumes), volumes
/// `V_j = num_j / den_j`) and, in the same traversal of the lists, the
/// velocity divergence (and curl) of [`velocity_divergence`] with
/// [`Gradients::Iad`]: both sum the same kernel values, so one pass
/// evaluates the kernel once per pair instead of twice. The results are
/// those of the two separate calls bit for bit. `flow.iad` is not read
/// (the matrices come from this pass).
///
/// # Errors
/// The lowest-index singular matrix, as [`iad`](crate::iad::iad).
///
/// # Panics
/// If the arrays differ in length or do not cover the lists.
#[allow(clippy::too_many_arguments)]
pub fn iad_and_velocity_divergence<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    flow: FlowState<'_>,
    [num, den]: [&[f64]; 2],
    nl: &CompactNeighborList,
    c: &mut [Vec<f64>; 6],
    div_v: &mut [f64],
    curl_v: &mut [f64],
    grad_v: &mut [Vec<f64>],
) -> Result<(), Singular> {
    let driver = Flow::driver(bbox, kernel, &flow, nl);
    let n = flow.pos.x.len();
    let stage = IadGradient {
        tau: Tau {
            kernel,
            norm: kernel.norm(),
            h: flow.pos.h,
            m: &num[..n],
            rho: &den[..n],
        },
        grad: VelocityGradient(Flow::new(kernel, &flow, false)),
    };
    let r = nl.targets();
    let [c0, c1, c2, c3, c4, c5] = c;
    let matrices = [c0, c1, c2, c3, c4, c5].map(|c| &mut c[r.clone()]);
    let curl = (!curl_v.is_empty()).then(|| [&mut curl_v[r.clone()]]);
    let sym = sym_out(grad_v, r.clone());
    match driver.run(&stage, (matrices, ([&mut div_v[r]], (curl, sym)))) {
        FirstSingular(Some(s)) => Err(s),
        FirstSingular(None) => Ok(()),
    }
}

/// [`Tau`] and the IAD velocity gradient on one kernel evaluation.
struct IadGradient<'a, K> {
    tau: Tau<'a, K>,
    grad: VelocityGradient<'a, K, true>,
}

impl<K: Kernel> PairStage for IadGradient<'_, K> {
    type Sums = (TauSums, GradientSums);
    type Out<'o> = (
        [&'o mut [f64]; 6],
        <VelocityGradient<'o, K, true> as PairStage>::Out<'o>,
    );
    type Stats = FirstSingular;

    #[inline(always)]
    fn start(&self, g: &Group) -> Self::Sums {
        (self.tau.start(g), self.grad.start(g))
    }

    #[inline(always)]
    fn pair(&self, (tau, grad): &mut Self::Sums, j: usize, d: [F64s; 3], r2: F64s) {
        let shape = self.tau.kernel.shape_sq_lanes(r2 * (tau.0 * tau.0));
        self.tau.add(&mut tau.1, j, d, shape);
        self.grad.add(grad, j, d, shape);
    }

    #[inline(always)]
    fn finish(
        &self,
        g: &Group,
        (tau, grad): Self::Sums,
        (c_out, grad_out): &mut Self::Out<'_>,
    ) -> FirstSingular {
        let (c, first_bad) = self.tau.invert(g, tau);
        store_matrices(g, &c, c_out);
        // The lanes' matrices as the separate pass reads them back (padding
        // lanes repeat the last target).
        let lane = |k: usize| F64s::from_array(std::array::from_fn(|l| c[l.min(g.valid - 1)][k]));
        self.grad
            .store([0, 1, 2, 3, 4, 5].map(lane), grad, grad_out);
        first_bad
    }
}

/// The shock indicator's sums: `grad(div v)` and the signal velocity.
struct Indicator<'a, K, const IAD: bool> {
    flow: Flow<'a, K>,
    div_v: &'a [f64],
    params: AvSwitchParams,
}

/// One group's target values and sums in the indicator loop.
struct IndicatorSums {
    vi: [F64s; 3],
    hi: F64s,
    ci: F64s,
    div_i: F64s,
    inv_h: F64s,
    reach_i: F64s,
    /// `sum_j V_j w_j (div_j - div_i) d`
    s: [F64s; 3],
    v_sig: F64s,
    /// `max_j max(-w_ij, 0) / (c_i + c_j)`
    approach: F64s,
}

impl<K: Kernel, const IAD: bool> Indicator<'_, K, IAD> {
    #[inline(always)]
    fn start(&self, g: &Group) -> IndicatorSums {
        let f = &self.flow;
        let hi = g.load(f.h);
        let ci = g.load(f.c);
        let reach_i = {
            let r = f.support * hi;
            r * r
        };
        IndicatorSums {
            vi: f.v.map(|v| g.load(v)),
            hi,
            ci,
            div_i: g.load(self.div_v),
            inv_h: 1.0 / hi,
            reach_i,
            s: [F64s::splat(0.0); 3],
            approach: F64s::splat(0.0),
            v_sig: if self.params.form == SwitchForm::SphExa {
                1e-40 * ci
            } else {
                ci
            },
        }
    }

    #[inline(always)]
    fn pair(&self, t: &mut IndicatorSums, j: usize, d: [F64s; 3], r2: F64s) {
        let f = &self.flow;
        let zero = F64s::splat(0.0);
        // Pairs within either support (the lists' criterion), not the
        // target itself; the other lanes compute with r = 1.
        let reach_j = {
            let r = f.support * f.h[j];
            r * r
        };
        let (r2, pair) = neighbour_lanes(r2, t.reach_i, reach_j);
        let r = r2.sqrt();
        let vi = t.vi;
        let vij = [vi[0] - f.v[0][j], vi[1] - f.v[1][j], vi[2] - f.v[2][j]];
        let w_ij = (vij[0] * d[0] + vij[1] * d[1] + vij[2] * d[2]) / r;
        if self.params.form == SwitchForm::SphExa {
            // Approaching pairs only.
            let vs = w_ij.where_negative(t.ci + f.c[j] - 3.0 * w_ij);
            t.v_sig = t.v_sig.max(vs * pair);
        } else {
            let vs = t.ci + f.c[j] - 3.0 * w_ij.min(zero);
            t.v_sig = t.v_sig.max(vs * pair);
        }
        if self.params.weak_alpha.is_some() {
            // Cold pairs (c_i + c_j = 0) approaching: infinite Mach number.
            let a = (-w_ij).max(zero) / (t.ci + f.c[j]).max(F64s::splat(f64::MIN_POSITIVE));
            t.approach = t.approach.max(a * pair);
        }
        let w = f.m[j] / f.rho[j]
            * pair_weight::<K, IAD>(f.kernel, r2, t.inv_h)
            * (self.div_v[j] - t.div_i)
            * pair;
        for (sk, dk) in t.s.iter_mut().zip(d) {
            *sk += w * dk;
        }
    }

    /// `(alpha_loc, v_sig, ceiling)` of the group's lanes.
    #[inline(always)]
    fn finish(&self, g: &Group, t: IndicatorSums) -> ([f64; LANES], [f64; LANES], [f64; LANES]) {
        let f = &self.flow;
        let k3 = f.norm * t.inv_h * t.inv_h * t.inv_h;
        let s = t.s;
        let gd = if IAD {
            let c = f.iad.map(|c| g.load(c));
            let cs = sym_mat_vec(&c, s);
            k3 * (cs[0] * cs[0] + cs[1] * cs[1] + cs[2] * cs[2]).sqrt()
        } else {
            k3 * t.inv_h * (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt()
        };
        let (gd, h, c, dv) = (
            gd.to_array(),
            t.hi.to_array(),
            t.ci.to_array(),
            t.div_i.to_array(),
        );
        let approach = t.approach.to_array();
        let ceiling: [f64; LANES] = std::array::from_fn(|l| self.params.ceiling(2.0 * approach[l]));
        let alpha_loc = std::array::from_fn(|l| {
            let p = AvSwitchParams {
                alpha_max: ceiling[l],
                ..self.params
            };
            p.local_alpha(dv[l], gd[l], h[l], c[l])
        });
        (alpha_loc, t.v_sig.to_array(), ceiling)
    }
}

/// The indicator written out (`alpha_loc` and `v_sig` per target) or
/// applied (`alpha` advanced over `dt` per target).
struct IndicatorStage<'a, K, const IAD: bool> {
    indicator: Indicator<'a, K, IAD>,
    dt: Elapsed<'a>,
}

/// The time over which alpha advances: one for all targets, or each
/// particle's own (indexed like the particles; block time steps).
#[derive(Debug, Clone, Copy)]
pub enum Elapsed<'a> {
    /// Every target the same time.
    Uniform(f64),
    /// `elapsed[i]` for target `i`.
    PerParticle(&'a [f64]),
}

impl<K: Kernel, const IAD: bool> PairStage for IndicatorStage<'_, K, IAD> {
    type Sums = IndicatorSums;
    /// `[alpha_loc, v_sig]`, or `[alpha]`.
    type Out<'o> = (Option<[&'o mut [f64]; 2]>, Option<[&'o mut [f64]; 1]>);
    type Stats = ();

    #[inline(always)]
    fn start(&self, g: &Group) -> IndicatorSums {
        self.indicator.start(g)
    }

    #[inline(always)]
    fn pair(&self, t: &mut IndicatorSums, j: usize, d: [F64s; 3], r2: F64s) {
        self.indicator.pair(t, j, d, r2);
    }

    #[inline(always)]
    fn finish(&self, g: &Group, t: IndicatorSums, (shown, advanced): &mut Self::Out<'_>) {
        let (alpha_loc, v_sig, ceiling) = self.indicator.finish(g, t);
        if let Some([al, vs]) = shown {
            al.copy_from_slice(&alpha_loc[..g.valid]);
            vs.copy_from_slice(&v_sig[..g.valid]);
        }
        if let Some([alpha]) = advanced {
            let p = &self.indicator.params;
            let h = self.indicator.flow.h;
            for (l, a) in alpha.iter_mut().enumerate() {
                let tau = p.decay_time(h[g.first + l], v_sig[l]);
                let dt = match self.dt {
                    Elapsed::Uniform(dt) => dt,
                    Elapsed::PerParticle(e) => e[g.first + l],
                };
                let p = AvSwitchParams {
                    alpha_max: ceiling[l],
                    ..*p
                };
                *a = p.advance(*a, alpha_loc[l], tau, dt);
            }
        }
    }
}

/// What one indicator pass writes: `(alpha_loc, v_sig)` or `alpha`
/// advanced over `dt`.
enum IndicatorOut<'a> {
    Indicator(&'a mut [f64], &'a mut [f64]),
    Advance(&'a mut [f64], Elapsed<'a>),
}

/// The arguments of one indicator pass, run for one gradient operator.
struct IndicatorRun<'a, K> {
    kernel: &'a K,
    bbox: &'a BoundingBox,
    flow: FlowState<'a>,
    div_v: &'a [f64],
    params: AvSwitchParams,
    nl: &'a CompactNeighborList,
    out: IndicatorOut<'a>,
}

impl<'a, K: Kernel> IndicatorRun<'a, K> {
    fn new(
        kernel: &'a K,
        bbox: &'a BoundingBox,
        flow: FlowState<'a>,
        div_v: &'a [f64],
        params: &AvSwitchParams,
        nl: &'a CompactNeighborList,
        out: IndicatorOut<'a>,
    ) -> Self {
        Self {
            kernel,
            bbox,
            flow,
            div_v,
            params: *params,
            nl,
            out,
        }
    }

    /// Runs the pass with the gradient operator `g`.
    fn with(self, g: Gradients) {
        with_gradients(g, self);
    }
}

impl<K: Kernel> WithGradients for IndicatorRun<'_, K> {
    type Output = ();

    fn run<const IAD: bool>(self) {
        let driver = Flow::driver(self.bbox, self.kernel, &self.flow, self.nl);
        let n = self.flow.pos.x.len();
        let indicator = Indicator::<K, IAD> {
            flow: Flow::new(self.kernel, &self.flow, IAD),
            div_v: &self.div_v[..n],
            params: self.params,
        };
        let r = self.nl.targets();
        let (dt, out) = match self.out {
            IndicatorOut::Indicator(al, vs) => (
                Elapsed::Uniform(0.0),
                (Some([&mut al[r.clone()], &mut vs[r]]), None),
            ),
            IndicatorOut::Advance(alpha, dt) => (dt, (None, Some([&mut alpha[r]]))),
        };
        driver.run(&IndicatorStage { indicator, dt }, out);
    }
}

/// The shock indicator of every target of `nl`: the local target
/// `alpha_loc[i]` ([`AvSwitchParams::local_alpha`]) from
///
/// ```text
/// |grad div v|_i = |sum_j (m_j / rho_j) (div v_j - div v_i) A_ij|
/// ```
///
/// (`A_ij` as in [`velocity_divergence`]), and the signal velocity
/// `v_sig[i] = max(c_i, max_j (c_i + c_j - 3 min(w_ij, 0)))` of the decay
/// time. `div_v` must hold the divergence of the targets and of all their
/// neighbours (halos exchanged). [`update_alpha`] does the same and
/// advances `alpha` without storing these; this form is for diagnostics.
///
/// # Panics
/// If the arrays differ in length or do not cover the lists.
pub fn shock_indicator<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    flow: FlowState<'_>,
    gradients: Gradients,
    div_v: &[f64],
    params: &AvSwitchParams,
    nl: &CompactNeighborList,
    alpha_loc: &mut [f64],
    v_sig: &mut [f64],
) {
    let out = IndicatorOut::Indicator(alpha_loc, v_sig);
    IndicatorRun::new(kernel, bbox, flow, div_v, params, nl, out).with(gradients);
}

/// Advances the viscosity strength of every target of `nl` over the time
/// `dt` elapsed since its last update (`dt >= 0`; 0 on the first step):
///
/// ```text
/// alpha_i <- advance(alpha_i, alpha_loc,i, tau_i = h_i / (decay v_sig,i), dt)
/// ```
///
/// ([`AvSwitchParams::advance`]: jump up to `alpha_loc`, else exponential
/// decay towards `max(alpha_loc, alpha_min)`; result in
/// `[alpha_min, alpha_max]`), with `alpha_loc` and `v_sig` as computed by
/// [`shock_indicator`]. `div_v` must hold the divergence of the targets
/// and of all their neighbours (halos exchanged). Writes the targets of
/// `alpha` only; the momentum stage needs the halos' values too.
///
/// # Panics
/// If `params` is not [valid](AvSwitchParams::is_valid), or the arrays
/// differ in length or do not cover the lists.
pub fn update_alpha<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    flow: FlowState<'_>,
    gradients: Gradients,
    div_v: &[f64],
    params: &AvSwitchParams,
    dt: f64,
    nl: &CompactNeighborList,
    alpha: &mut [f64],
) {
    update_alpha_over(
        kernel,
        bbox,
        flow,
        gradients,
        div_v,
        params,
        Elapsed::Uniform(dt),
        nl,
        alpha,
    );
}

/// [`update_alpha`] over the time `elapsed` gives: one for all, or each
/// target's own since its last update (block time steps).
///
/// # Panics
/// As [`update_alpha`], and if a per-particle `elapsed` does not cover
/// the targets.
#[allow(clippy::too_many_arguments)]
pub fn update_alpha_over<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    flow: FlowState<'_>,
    gradients: Gradients,
    div_v: &[f64],
    params: &AvSwitchParams,
    elapsed: Elapsed<'_>,
    nl: &CompactNeighborList,
    alpha: &mut [f64],
) {
    assert!(params.is_valid(), "invalid AV switch parameters {params:?}");
    if let Elapsed::PerParticle(e) = elapsed {
        assert!(
            e.len() >= nl.targets().end,
            "elapsed times do not cover the targets"
        );
    }
    let out = IndicatorOut::Advance(alpha, elapsed);
    IndicatorRun::new(kernel, bbox, flow, div_v, params, nl, out).with(gradients);
}
