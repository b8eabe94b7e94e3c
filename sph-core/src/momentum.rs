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
use crate::geometry::{max_reach, Separation};
use crate::lanes::{neighbour_lanes, F64s, GroupUnion, LANES};
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

/// `a[..n]`: slices of one length let the compiler drop bounds checks.
#[inline(always)]
fn cut(a: &[f64], n: usize) -> &[f64] {
    &a[..n]
}

/// The pair loop; `SWITCHED` selects `alpha_ij = (alpha_per[i] +
/// alpha_per[j]) / 2` over the constant `alpha` at compile time. Targets
/// go in groups of [`LANES`], one per lane ([`lanes`](crate::lanes)).
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
    let reach = max_reach(kernel.support(), s.pos.h);
    let targets = nl.targets();
    let norm = kernel.norm();
    let support = kernel.support();
    let pos = s.pos;
    // Every per-particle slice cut to the same length, so that one check
    // per run of neighbours covers all loads of the run (the compiler drops
    // the per-load bounds checks).
    let n = s.rho.len();
    let (x, y, z, h, m) = (
        cut(pos.x, n),
        cut(pos.y, n),
        cut(pos.z, n),
        cut(pos.h, n),
        cut(pos.m, n),
    );
    let (vx, vy, vz, cs) = (cut(s.vx, n), cut(s.vy, n), cut(s.vz, n), cut(s.c, n));
    let (inv_h, inv_rho, pre) = (cut(&f.inv_h, n), cut(&f.inv_rho, n), cut(&f.pre, n));
    let iad: [&[f64]; 6] = if IAD {
        s.iad.map(|a| cut(a, n))
    } else {
        [&[]; 6]
    };
    let alpha_per = if SWITCHED {
        cut(alpha_per, n)
    } else {
        alpha_per
    };
    let r = targets.clone();
    (
        out.ax[r.clone()].par_chunks_mut(LANES),
        out.ay[r.clone()].par_chunks_mut(LANES),
        out.az[r.clone()].par_chunks_mut(LANES),
        out.du[r].par_chunks_mut(LANES),
    )
        .into_par_iter()
        .enumerate()
        .map_init(GroupUnion::default, |union, (g, (ax, ay, az, du))| {
            let first = targets.start + g * LANES;
            let valid = ax.len();
            let load = |a: &[f64]| F64s::load(a, first, valid);
            let xi = [load(pos.x), load(pos.y), load(pos.z)];
            let sep = sep.for_group(xi, reach);
            let vi = [load(s.vx), load(s.vy), load(s.vz)];
            let reach_i = {
                let r = support * load(pos.h);
                r * r
            };
            let inv_hi = load(&f.inv_h);
            let ki3 = norm * inv_hi * inv_hi * inv_hi;
            let ci = load(s.c);
            let (pre_i, inv_rho_i) = (load(&f.pre), load(&f.inv_rho));
            let alpha_i = if SWITCHED {
                load(alpha_per)
            } else {
                F64s::splat(alpha)
            };
            let zero = F64s::splat(0.0);
            let ci_m = if IAD {
                [0, 1, 2, 3, 4, 5].map(|c| load(s.iad[c]))
            } else {
                [zero; 6]
            };
            let mut acc_a = [zero; 3];
            let mut acc_ep = zero; // sum_j m_j v_ij . A_ij(h_i)
            let mut acc_eav = zero;
            let mut acc_div = zero;
            let mut acc_vsig = ci;
            for run in union.build(nl, first..first + valid) {
                assert!(run.end <= n, "neighbour {} of {n} particles", run.end - 1);
                for j in run.clone() {
                    let xj = [x[j], y[j], z[j]];
                    let d = sep.between_lanes(xi, xj); // x_i - x_j
                    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    let reach_j = {
                        let r = support * h[j];
                        r * r
                    };
                    // Lanes whose target has j as neighbour get weight 1,
                    // the others compute with r = 1 (finite) and weight 0.
                    let (r2, weight) = neighbour_lanes(r2, reach_i, reach_j);
                    let mj = m[j] * weight;
                    let inv_r = 1.0 / r2.sqrt();
                    let rr = r2 * inv_r;
                    let inv_hj = inv_h[j];
                    // A_ij(h_i), A_ij(h_j).
                    let (ai, aj) = if IAD {
                        // A = C (x_j - x_i) W = -(C d) W
                        let wi =
                            ki3 * F64s::from_array(kernel.shape_lanes(&(rr * inv_hi).to_array()));
                        let kj3 = norm * inv_hj * inv_hj * inv_hj;
                        let wj =
                            kj3 * F64s::from_array(kernel.shape_lanes(&(rr * inv_hj).to_array()));
                        let cj = [
                            F64s::splat(iad[0][j]),
                            F64s::splat(iad[1][j]),
                            F64s::splat(iad[2][j]),
                            F64s::splat(iad[3][j]),
                            F64s::splat(iad[4][j]),
                            F64s::splat(iad[5][j]),
                        ];
                        let cd = mat_vec_lanes(&ci_m, d);
                        let cdj = mat_vec_lanes(&cj, d);
                        (scale3(cd, -wi), scale3(cdj, -wj))
                    } else {
                        // grad_i W(r, h) = K/h^4 w'(r/h) d / r
                        let (_, dwi) = kernel.shape_and_derivative_lanes(&(rr * inv_hi).to_array());
                        let (_, dwj) = kernel.shape_and_derivative_lanes(&(rr * inv_hj).to_array());
                        let gi = ki3 * inv_hi * F64s::from_array(dwi) * inv_r;
                        let kj4 = norm * inv_hj * inv_hj * inv_hj * inv_hj;
                        let gj = kj4 * F64s::from_array(dwj) * inv_r;
                        (scale3(d, gi), scale3(d, gj))
                    };
                    let vij = [vi[0] - vx[j], vi[1] - vy[j], vi[2] - vz[j]];
                    let w = (vij[0] * d[0] + vij[1] * d[1] + vij[2] * d[2]) * inv_r;
                    let vsig = ci + cs[j] - 3.0 * w.min(zero);
                    acc_vsig = acc_vsig.max(vsig * weight);
                    let alpha_ij = if SWITCHED {
                        0.5 * (alpha_i + alpha_per[j])
                    } else {
                        F64s::splat(alpha)
                    };
                    let visc = w.where_negative(-0.5 * alpha_ij * vsig * w);
                    let vi_r = 0.5 * visc * inv_rho_i;
                    let inv_rho_j = inv_rho[j];
                    let vj_r = 0.5 * visc * inv_rho_j;
                    let (ci_f, cj_f) = (pre_i + vi_r, pre[j] + vj_r);
                    for c in 0..3 {
                        acc_a[c] -= mj * (ci_f * ai[c] + cj_f * aj[c]);
                    }
                    let vai = vij[0] * ai[0] + vij[1] * ai[1] + vij[2] * ai[2];
                    let vaj = vij[0] * aj[0] + vij[1] * aj[1] + vij[2] * aj[2];
                    acc_ep += mj * vai;
                    acc_eav += mj * (vi_r * vai + vj_r * vaj);
                    acc_div -= mj * inv_rho_j * vai;
                }
            }
            acc_a[0].store(ax);
            acc_a[1].store(ay);
            acc_a[2].store(az);
            (pre_i * acc_ep + 0.5 * acc_eav).store(du);
            let h_over_vsig = (1.0 / (inv_hi * acc_vsig)).to_array();
            let div = acc_div.to_array();
            let mut st = MomentumStats {
                min_h_over_vsig: f64::INFINITY,
                max_abs_div_v: 0.0,
            };
            for l in 0..valid {
                st.min_h_over_vsig = st.min_h_over_vsig.min(h_over_vsig[l]);
                st.max_abs_div_v = st.max_abs_div_v.max(div[l].abs());
            }
            st
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
fn scale3(v: [F64s; 3], f: F64s) -> [F64s; 3] {
    [v[0] * f, v[1] * f, v[2] * f]
}

#[inline(always)]
fn mat_vec_lanes(c: &[F64s; 6], d: [F64s; 3]) -> [F64s; 3] {
    [
        c[0] * d[0] + c[1] * d[1] + c[2] * d[2],
        c[1] * d[0] + c[3] * d[1] + c[4] * d[2],
        c[2] * d[0] + c[4] * d[1] + c[5] * d[2],
    ]
}
