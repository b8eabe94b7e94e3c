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

use crate::density::Positions;
use crate::geometry::Separation;
use rayon::prelude::*;
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList};

/// How gradients are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Gradients {
    /// Integral approach to derivatives (exact for linear fields).
    #[default]
    Iad,
    /// Plain kernel gradients `grad W`.
    Kernel,
}

/// The per-particle state the momentum and energy equations read.
#[derive(Debug, Clone, Copy)]
pub struct HydroState<'a> {
    /// Positions, smoothing lengths and masses.
    pub pos: Positions<'a>,
    /// Velocity x.
    pub vx: &'a [f64],
    /// Velocity y.
    pub vy: &'a [f64],
    /// Velocity z.
    pub vz: &'a [f64],
    /// Density.
    pub rho: &'a [f64],
    /// Pressure.
    pub p: &'a [f64],
    /// Sound speed.
    pub c: &'a [f64],
    /// grad-h factor (empty: 1).
    pub omega: &'a [f64],
    /// Inverse IAD matrices (used with [`Gradients::Iad`]).
    pub iad: [&'a [f64]; 6],
}

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
        let n = s.rho.len();
        for v in [&mut self.inv_h, &mut self.inv_rho, &mut self.pre] {
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
                *pre = s.p[i] * *ir * *ir / om;
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
    match gradients {
        Gradients::Iad => pair_loop::<K, true, false>(kernel, bbox, s, f, alpha, &[], nl, out),
        Gradients::Kernel => pair_loop::<K, false, false>(kernel, bbox, s, f, alpha, &[], nl, out),
    }
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
    assert!(
        alpha.len() >= s.rho.len(),
        "alpha has {} values for {} particles",
        alpha.len(),
        s.rho.len()
    );
    match gradients {
        Gradients::Iad => pair_loop::<K, true, true>(kernel, bbox, s, f, 0.0, alpha, nl, out),
        Gradients::Kernel => pair_loop::<K, false, true>(kernel, bbox, s, f, 0.0, alpha, nl, out),
    }
}

/// The pair loop; `SWITCHED` selects `alpha_ij = (alpha_per[i] +
/// alpha_per[j]) / 2` over the constant `alpha` at compile time.
fn pair_loop<K: Kernel, const IAD: bool, const SWITCHED: bool>(
    kernel: &K,
    bbox: &BoundingBox,
    s: HydroState<'_>,
    f: &PairFactors,
    alpha: f64,
    alpha_per: &[f64],
    nl: &CompactNeighborList,
    out: Rates<'_>,
) -> MomentumStats {
    let sep = Separation::new(bbox);
    let targets = nl.targets();
    let norm = kernel.norm();
    let pos = s.pos;
    let r = targets.clone();
    (
        out.ax[r.clone()].par_iter_mut(),
        out.ay[r.clone()].par_iter_mut(),
        out.az[r.clone()].par_iter_mut(),
        out.du[r].par_iter_mut(),
    )
        .into_par_iter()
        .enumerate()
        .map(|(k, (ax, ay, az, du))| {
            let i = targets.start + k;
            let pi = [pos.x[i], pos.y[i], pos.z[i]];
            let vi = [s.vx[i], s.vy[i], s.vz[i]];
            let inv_hi = f.inv_h[i];
            let ki3 = norm * inv_hi * inv_hi * inv_hi;
            let ci = s.c[i];
            let (pre_i, inv_rho_i) = (f.pre[i], f.inv_rho[i]);
            let alpha_i = if SWITCHED { alpha_per[i] } else { alpha };
            let ci_m = if IAD {
                [
                    s.iad[0][i],
                    s.iad[1][i],
                    s.iad[2][i],
                    s.iad[3][i],
                    s.iad[4][i],
                    s.iad[5][i],
                ]
            } else {
                [0.0; 6]
            };
            let mut a = [0.0; 3];
            let mut e_p = 0.0; // sum_j m_j v_ij . A_ij(h_i)
            let mut e_av = 0.0;
            let mut div_v = 0.0;
            let mut vsig_max = ci;
            for run in nl.runs(i) {
                for j in run {
                    if j == i {
                        continue;
                    }
                    let d = sep.between(pi, [pos.x[j], pos.y[j], pos.z[j]]); // x_i - x_j
                    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    let inv_r = 1.0 / r2.sqrt();
                    let rr = r2 * inv_r;
                    let inv_hj = f.inv_h[j];
                    let (ai, aj) = if IAD {
                        // A = C (x_j - x_i) W = -(C d) W
                        let wi = ki3 * kernel.shape(rr * inv_hi);
                        let kj3 = norm * inv_hj * inv_hj * inv_hj;
                        let wj = kj3 * kernel.shape(rr * inv_hj);
                        let cd = mat_vec(&ci_m, d);
                        let cj = [
                            s.iad[0][j],
                            s.iad[1][j],
                            s.iad[2][j],
                            s.iad[3][j],
                            s.iad[4][j],
                            s.iad[5][j],
                        ];
                        let cdj = mat_vec(&cj, d);
                        (
                            [-cd[0] * wi, -cd[1] * wi, -cd[2] * wi],
                            [-cdj[0] * wj, -cdj[1] * wj, -cdj[2] * wj],
                        )
                    } else {
                        // grad_i W(r, h) = K/h^4 w'(r/h) d / r
                        let gi = ki3 * inv_hi * kernel.shape_derivative(rr * inv_hi) * inv_r;
                        let kj4 = norm * inv_hj * inv_hj * inv_hj * inv_hj;
                        let gj = kj4 * kernel.shape_derivative(rr * inv_hj) * inv_r;
                        (
                            [gi * d[0], gi * d[1], gi * d[2]],
                            [gj * d[0], gj * d[1], gj * d[2]],
                        )
                    };
                    let vij = [vi[0] - s.vx[j], vi[1] - s.vy[j], vi[2] - s.vz[j]];
                    let w = (vij[0] * d[0] + vij[1] * d[1] + vij[2] * d[2]) * inv_r;
                    let vsig = ci + s.c[j] - 3.0 * w.min(0.0);
                    vsig_max = vsig_max.max(vsig);
                    let visc = if w < 0.0 {
                        let alpha_ij = if SWITCHED {
                            0.5 * (alpha_i + alpha_per[j])
                        } else {
                            alpha
                        };
                        -0.5 * alpha_ij * vsig * w
                    } else {
                        0.0
                    };
                    let mj = pos.m[j];
                    let inv_rho_j = f.inv_rho[j];
                    let (vi_r, vj_r) = (0.5 * visc * inv_rho_i, 0.5 * visc * inv_rho_j);
                    let (ci_f, cj_f) = (pre_i + vi_r, f.pre[j] + vj_r);
                    for k in 0..3 {
                        a[k] -= mj * (ci_f * ai[k] + cj_f * aj[k]);
                    }
                    let vai = vij[0] * ai[0] + vij[1] * ai[1] + vij[2] * ai[2];
                    let vaj = vij[0] * aj[0] + vij[1] * aj[1] + vij[2] * aj[2];
                    e_p += mj * vai;
                    e_av += mj * (vi_r * vai + vj_r * vaj);
                    div_v -= mj * inv_rho_j * vai;
                }
            }
            *ax = a[0];
            *ay = a[1];
            *az = a[2];
            *du = pre_i * e_p + 0.5 * e_av;
            MomentumStats {
                min_h_over_vsig: 1.0 / (inv_hi * vsig_max),
                max_abs_div_v: div_v.abs(),
            }
        })
        .reduce(
            || MomentumStats {
                min_h_over_vsig: f64::INFINITY,
                max_abs_div_v: 0.0,
            },
            |a, b| MomentumStats {
                min_h_over_vsig: a.min_h_over_vsig.min(b.min_h_over_vsig),
                max_abs_div_v: a.max_abs_div_v.max(b.max_abs_div_v),
            },
        )
}

#[inline(always)]
fn mat_vec(c: &[f64; 6], d: [f64; 3]) -> [f64; 3] {
    [
        c[0] * d[0] + c[1] * d[1] + c[2] * d[2],
        c[1] * d[0] + c[3] * d[1] + c[4] * d[2],
        c[2] * d[0] + c[4] * d[1] + c[5] * d[2],
    ]
}
