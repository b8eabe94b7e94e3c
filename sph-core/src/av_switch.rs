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
//! velocity_divergence(&kernel, &bbox, flow, Gradients::Iad, &nl, &mut div_v, &mut []);
//! // (several ranks: exchange div_v of the halo particles here)
//! let params = AvSwitchParams::default();
//! let mut alpha = vec![params.alpha_min; p.len()];
//! update_alpha(&kernel, &bbox, flow, Gradients::Iad, &div_v, &params, 1e-3, &nl, &mut alpha);
//! // (several ranks: exchange alpha of the halo particles here)
//! let max = alpha.iter().cloned().fold(0.0, f64::max);
//! assert!(max > 0.5 && max <= params.alpha_max);
//! assert!(alpha.iter().all(|&a| a >= params.alpha_min));
//! ```

use crate::density::Positions;
use crate::geometry::{max_reach, Separation};
use crate::lanes::{neighbour_lanes, F64s, GroupUnion, LANES};
use crate::momentum::{Gradients, HydroState};
use rayon::prelude::*;
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList};
use std::ops::Range;

/// Parameters of the viscosity switch (defaults: SPH-EXA's).
#[derive(Debug, Clone, Copy, PartialEq)]
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
}

impl Default for AvSwitchParams {
    fn default() -> Self {
        Self {
            alpha_min: 0.05,
            alpha_max: 1.0,
            decay: 0.2,
            sound_weight: 0.05,
        }
    }
}

impl AvSwitchParams {
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
    #[inline]
    pub fn advance(&self, alpha: f64, alpha_loc: f64, tau: f64, dt: f64) -> f64 {
        let next = if alpha_loc >= alpha {
            alpha_loc
        } else {
            let target = alpha_loc.max(self.alpha_min);
            target + (alpha - target) * (-dt / tau).exp()
        };
        next.clamp(self.alpha_min, self.alpha_max)
    }
}

/// The per-particle state the switch stages read.
#[derive(Debug, Clone, Copy)]
pub struct FlowState<'a> {
    /// Positions, smoothing lengths and masses.
    pub pos: Positions<'a>,
    /// Velocity x.
    pub vx: &'a [f64],
    /// Velocity y.
    pub vy: &'a [f64],
    /// Velocity z.
    pub vz: &'a [f64],
    /// Density (volumes `m / rho`).
    pub rho: &'a [f64],
    /// Sound speed (read by the second pass only).
    pub c: &'a [f64],
    /// Inverse IAD matrices `(xx, xy, xz, yy, yz, zz)` (read with
    /// [`Gradients::Iad`] only).
    pub iad: [&'a [f64]; 6],
}

impl<'a> From<HydroState<'a>> for FlowState<'a> {
    fn from(s: HydroState<'a>) -> Self {
        Self {
            pos: s.pos,
            vx: s.vx,
            vy: s.vy,
            vz: s.vz,
            rho: s.rho,
            c: s.c,
            iad: s.iad,
        }
    }
}

/// Weight of the pair term `d = x_i - x_j` before the final factors, for
/// a lane of targets at distances `r` (`r > 0`): with IAD `W` shape (the
/// gradient is `-C d W`), plain `S'(v) / r` (the gradient is
/// `K/h^4 S'(v) d / r`). Lanes at `r = 0` (the target itself) get 0.
#[inline(always)]
fn pair_weight<K: Kernel, const IAD: bool>(kernel: &K, r: F64s, inv_h: F64s) -> F64s {
    let v = (r * inv_h).to_array();
    if IAD {
        F64s::from_array(kernel.shape_lanes(&v))
    } else {
        let zero = F64s::splat(0.0);
        let r_safe = F64s::select_positive(r, r, F64s::splat(1.0));
        let w = F64s::from_array(kernel.shape_and_derivative_lanes(&v).1) / r_safe;
        F64s::select_positive(r, w, zero)
    }
}

/// A group of [`LANES`] consecutive targets, padded with the last one.
#[derive(Clone, Copy)]
struct Group {
    first: usize,
    valid: usize,
}

impl Group {
    #[inline(always)]
    fn load(&self, a: &[f64]) -> F64s {
        F64s::load(a, self.first, self.valid)
    }
}

/// Velocity gradient `G_ab = d_a v_b` of a group of targets, one per lane.
#[inline(always)]
fn velocity_gradient<K: Kernel, const IAD: bool>(
    kernel: &K,
    sep: &Separation,
    flow: &FlowState<'_>,
    union: &[Range<usize>],
    g: Group,
    reach: f64,
) -> [[F64s; 3]; 3] {
    let pos = flow.pos;
    let n = pos.x.len();
    let xi = [g.load(pos.x), g.load(pos.y), g.load(pos.z)];
    let sep = sep.for_group(xi, reach);
    let vi = [g.load(flow.vx), g.load(flow.vy), g.load(flow.vz)];
    let inv_h = 1.0 / g.load(pos.h);
    let k3 = kernel.norm() * inv_h * inv_h * inv_h;
    // m[c][b] = sum_j V_j w_j d_c (v_j - v_i)_b
    let zero = F64s::splat(0.0);
    let mut m = [[zero; 3]; 3];
    for run in union {
        assert!(run.end <= n, "neighbour {} of {n} particles", run.end - 1);
        for j in run.clone() {
            let d = sep.between_lanes(xi, [pos.x[j], pos.y[j], pos.z[j]]);
            let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let w = pos.m[j] / flow.rho[j] * pair_weight::<K, IAD>(kernel, r, inv_h);
            let dv = [flow.vx[j] - vi[0], flow.vy[j] - vi[1], flow.vz[j] - vi[2]];
            for (mc, dc) in m.iter_mut().zip(d) {
                let wd = w * dc;
                for (mcb, dvb) in mc.iter_mut().zip(dv) {
                    *mcb += wd * dvb;
                }
            }
        }
    }
    if IAD {
        // A_ij = -C d W: G = -K/h^3 C m
        let c = [0, 1, 2, 3, 4, 5].map(|k| g.load(flow.iad[k]));
        let rows = [[c[0], c[1], c[2]], [c[1], c[3], c[4]], [c[2], c[4], c[5]]];
        let mut out = [[zero; 3]; 3];
        for a in 0..3 {
            for b in 0..3 {
                out[a][b] =
                    -k3 * (rows[a][0] * m[0][b] + rows[a][1] * m[1][b] + rows[a][2] * m[2][b]);
            }
        }
        out
    } else {
        // A_ij = K/h^4 S' d / r: G = K/h^4 m
        let k4 = k3 * inv_h;
        m.map(|row| row.map(|v| k4 * v))
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
/// `div_v[i]` (and `curl_v[i]`) for the targets only.
pub fn velocity_divergence<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    flow: FlowState<'_>,
    gradients: Gradients,
    nl: &CompactNeighborList,
    div_v: &mut [f64],
    curl_v: &mut [f64],
) {
    match gradients {
        Gradients::Iad => divergence_loop::<K, true>(kernel, bbox, flow, nl, div_v, curl_v),
        Gradients::Kernel => divergence_loop::<K, false>(kernel, bbox, flow, nl, div_v, curl_v),
    }
}

fn divergence_loop<K: Kernel, const IAD: bool>(
    kernel: &K,
    bbox: &BoundingBox,
    flow: FlowState<'_>,
    nl: &CompactNeighborList,
    div_v: &mut [f64],
    curl_v: &mut [f64],
) {
    let sep = Separation::new(bbox);
    let reach = max_reach(kernel.support(), flow.pos.h);
    let targets = nl.targets();
    let with_curl = !curl_v.is_empty();
    let div_t = div_v[targets.clone()].par_chunks_mut(LANES);
    // Without a curl, one-element stand-ins keep a single loop.
    let mut none = vec![0.0; targets.len().div_ceil(LANES)];
    let curl_t = if with_curl {
        curl_v[targets.clone()].par_chunks_mut(LANES)
    } else {
        none.par_chunks_mut(1)
    };
    div_t
        .zip(curl_t)
        .enumerate()
        .for_each_init(GroupUnion::default, |union, (k, (dv, cv))| {
            let g = Group {
                first: targets.start + k * LANES,
                valid: dv.len(),
            };
            let runs = union.build(nl, g.first..g.first + g.valid);
            let gr = velocity_gradient::<K, IAD>(kernel, &sep, &flow, runs, g, reach);
            (gr[0][0] + gr[1][1] + gr[2][2]).store(dv);
            if with_curl {
                let curl = [
                    gr[1][2] - gr[2][1],
                    gr[2][0] - gr[0][2],
                    gr[0][1] - gr[1][0],
                ];
                (curl[0] * curl[0] + curl[1] * curl[1] + curl[2] * curl[2])
                    .sqrt()
                    .store(cv);
            }
        });
}

/// `(alpha_loc, v_sig)` of a group of targets, one per lane.
#[inline(always)]
fn indicator<K: Kernel, const IAD: bool>(
    kernel: &K,
    sep: &Separation,
    flow: &FlowState<'_>,
    div_v: &[f64],
    params: &AvSwitchParams,
    union: &[Range<usize>],
    g: Group,
    reach: f64,
) -> ([f64; LANES], [f64; LANES]) {
    let pos = flow.pos;
    let n = pos.x.len();
    let xi = [g.load(pos.x), g.load(pos.y), g.load(pos.z)];
    let sep = sep.for_group(xi, reach);
    let vi = [g.load(flow.vx), g.load(flow.vy), g.load(flow.vz)];
    let (hi, ci, div_i) = (g.load(pos.h), g.load(flow.c), g.load(div_v));
    let inv_h = 1.0 / hi;
    let k3 = kernel.norm() * inv_h * inv_h * inv_h;
    let support = kernel.support();
    let reach_i = {
        let r = support * hi;
        r * r
    };
    let zero = F64s::splat(0.0);
    // s = sum_j V_j w_j (div_j - div_i) d
    let mut s = [zero; 3];
    let mut v_sig = ci;
    for run in union {
        assert!(run.end <= n, "neighbour {} of {n} particles", run.end - 1);
        for j in run.clone() {
            let d = sep.between_lanes(xi, [pos.x[j], pos.y[j], pos.z[j]]);
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            // Pairs within either support (the lists' criterion), not
            // the target itself; the other lanes compute with r = 1.
            let reach_j = {
                let r = support * pos.h[j];
                r * r
            };
            let (r2, pair) = neighbour_lanes(r2, reach_i, reach_j);
            let r = r2.sqrt();
            let vij = [vi[0] - flow.vx[j], vi[1] - flow.vy[j], vi[2] - flow.vz[j]];
            let w_ij = (vij[0] * d[0] + vij[1] * d[1] + vij[2] * d[2]) / r;
            let vs = ci + flow.c[j] - 3.0 * w_ij.min(zero);
            v_sig = v_sig.max(vs * pair);
            let f = pos.m[j] / flow.rho[j]
                * pair_weight::<K, IAD>(kernel, r, inv_h)
                * (div_v[j] - div_i)
                * pair;
            for (sk, dk) in s.iter_mut().zip(d) {
                *sk += f * dk;
            }
        }
    }
    let gd = if IAD {
        let c = [0, 1, 2, 3, 4, 5].map(|k| g.load(flow.iad[k]));
        let cs = [
            c[0] * s[0] + c[1] * s[1] + c[2] * s[2],
            c[1] * s[0] + c[3] * s[1] + c[4] * s[2],
            c[2] * s[0] + c[4] * s[1] + c[5] * s[2],
        ];
        k3 * (cs[0] * cs[0] + cs[1] * cs[1] + cs[2] * cs[2]).sqrt()
    } else {
        k3 * inv_h * (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt()
    };
    let (gd, h, c, dv) = (
        gd.to_array(),
        hi.to_array(),
        ci.to_array(),
        div_i.to_array(),
    );
    let alpha_loc = std::array::from_fn(|l| params.local_alpha(dv[l], gd[l], h[l], c[l]));
    (alpha_loc, v_sig.to_array())
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
    match gradients {
        Gradients::Iad => {
            indicator_loop::<K, true>(kernel, bbox, flow, div_v, params, nl, alpha_loc, v_sig)
        }
        Gradients::Kernel => {
            indicator_loop::<K, false>(kernel, bbox, flow, div_v, params, nl, alpha_loc, v_sig)
        }
    }
}

fn indicator_loop<K: Kernel, const IAD: bool>(
    kernel: &K,
    bbox: &BoundingBox,
    flow: FlowState<'_>,
    div_v: &[f64],
    params: &AvSwitchParams,
    nl: &CompactNeighborList,
    alpha_loc: &mut [f64],
    v_sig: &mut [f64],
) {
    let sep = Separation::new(bbox);
    let reach = max_reach(kernel.support(), flow.pos.h);
    let targets = nl.targets();
    alpha_loc[targets.clone()]
        .par_chunks_mut(LANES)
        .zip(v_sig[targets.clone()].par_chunks_mut(LANES))
        .enumerate()
        .for_each_init(GroupUnion::default, |union, (k, (al, vs))| {
            let g = Group {
                first: targets.start + k * LANES,
                valid: al.len(),
            };
            let runs = union.build(nl, g.first..g.first + g.valid);
            let (a, v) = indicator::<K, IAD>(kernel, &sep, &flow, div_v, params, runs, g, reach);
            al.copy_from_slice(&a[..g.valid]);
            vs.copy_from_slice(&v[..g.valid]);
        });
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
/// If `params` is not [valid](AvSwitchParams::is_valid).
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
    assert!(params.is_valid(), "invalid AV switch parameters {params:?}");
    match gradients {
        Gradients::Iad => update_loop::<K, true>(kernel, bbox, flow, div_v, params, dt, nl, alpha),
        Gradients::Kernel => {
            update_loop::<K, false>(kernel, bbox, flow, div_v, params, dt, nl, alpha)
        }
    }
}

fn update_loop<K: Kernel, const IAD: bool>(
    kernel: &K,
    bbox: &BoundingBox,
    flow: FlowState<'_>,
    div_v: &[f64],
    params: &AvSwitchParams,
    dt: f64,
    nl: &CompactNeighborList,
    alpha: &mut [f64],
) {
    let sep = Separation::new(bbox);
    let reach = max_reach(kernel.support(), flow.pos.h);
    let targets = nl.targets();
    alpha[targets.clone()]
        .par_chunks_mut(LANES)
        .enumerate()
        .for_each_init(GroupUnion::default, |union, (k, a)| {
            let g = Group {
                first: targets.start + k * LANES,
                valid: a.len(),
            };
            let runs = union.build(nl, g.first..g.first + g.valid);
            let (alpha_loc, v_sig) =
                indicator::<K, IAD>(kernel, &sep, &flow, div_v, params, runs, g, reach);
            for (l, a) in a.iter_mut().enumerate() {
                let tau = params.decay_time(flow.pos.h[g.first + l], v_sig[l]);
                *a = params.advance(*a, alpha_loc[l], tau, dt);
            }
        });
}
