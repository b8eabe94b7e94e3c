//! The momentum and energy pair stage, composed of its terms: the
//! pressure gradient with its volume weights ([`PressureWeights`]), the
//! viscosity (strength [`Strength`], form [`ViscosityForm`], cleaning
//! [`AvCleaning`]), the artificial stress and the conduction. Each term
//! is a type; the stage is monomorphised over the ones a scheme picks.

use super::cleaning::AvCleaning;
use super::pressure::PressureWeights;
use super::strength::Strength;
use super::stress::ArtificialStress;
use super::viscosity::ViscosityForm;
use super::MomentumStats;
use crate::conduction::{ConductionTarget, Conductivity};
use crate::flow::Flow;
use crate::pair_loop::{neighbour_lanes, F64s, Group, PairStage, Reduce};
use sph_kernels::Kernel;
use std::marker::PhantomData;

/// The momentum and energy sums over `flow` with the gradient operator
/// `IAD`, the viscosity strength `S`, form `F` and the volume weights `W`.
pub(super) struct Momentum<'a, K, const IAD: bool, S, F, W> {
    pub(super) flow: Flow<'a, K>,
    /// `1/h`, `1/rho` and `P / (Omega rho^2)` (or the volume elements'
    /// pressure factor) of every particle.
    pub(super) inv_h: &'a [f64],
    pub(super) inv_rho: &'a [f64],
    pub(super) pre: &'a [f64],
    pub(super) strength: S,
    pub(super) weights: W,
    pub(super) stress: Option<ArtificialStress>,
    pub(super) cleaning: Option<AvCleaning<'a>>,
    pub(super) conduction: Option<Conductivity<'a>>,
    pub(super) form: PhantomData<F>,
}

/// The values of one group's targets, loaded once.
pub(super) struct Targets<T> {
    v: [F64s; 3],
    /// `(support h)^2`.
    reach: F64s,
    inv_h: F64s,
    /// `1 / h^2`.
    inv_h2: F64s,
    /// `K / h^3`, `K / h^5`.
    k3: F64s,
    k5: F64s,
    c: F64s,
    pre: F64s,
    inv_rho: F64s,
    /// The IAD matrices (IAD only).
    iad: [F64s; 6],
    alpha: F64s,
    /// `R_i` of the artificial stress.
    stress: F64s,
    /// The velocity gradients (AV cleaning only).
    grad_v: [F64s; 6],
    /// What the volume weights load.
    weights: T,
    /// The conduction's side of the targets (conductivity only).
    cond: Option<ConductionTarget>,
}

/// One group's running sums.
pub(super) struct Sums {
    a: [F64s; 3],
    /// `sum_j m_j v_ij . A_ij(h_i)` (weighted with volume elements).
    ep: F64s,
    /// The viscosity's (and stress's) heating.
    eav: F64s,
    div: F64s,
    vsig: F64s,
    /// The conduction sum, before the factor `alpha_u`.
    cond: F64s,
}

impl<K, const IAD: bool, S, F, W> PairStage for Momentum<'_, K, IAD, S, F, W>
where
    K: Kernel,
    S: Strength,
    F: ViscosityForm,
    W: PressureWeights,
{
    type Sums = (Targets<W::Target>, Sums);
    /// `a`, `du/dt`, and where asked for each target's `h / v_sig` and
    /// compression.
    type Out<'o> = (
        [&'o mut [f64]; 4],
        (Option<[&'o mut [f64]; 2]>, Option<[&'o mut [f64]; 1]>),
    );
    type Stats = MomentumStats;

    #[inline(always)]
    fn start(&self, g: &Group) -> Self::Sums {
        let zero = F64s::splat(0.0);
        let reach = {
            let r = self.flow.support * g.load(self.flow.h);
            r * r
        };
        let inv_h = g.load(self.inv_h);
        let c = g.load(self.flow.c);
        let pre = g.load(self.pre);
        let targets = Targets {
            v: self.flow.v.map(|v| g.load(v)),
            reach,
            inv_h,
            inv_h2: inv_h * inv_h,
            k3: self.flow.norm * inv_h * inv_h * inv_h,
            k5: self.flow.norm * inv_h * inv_h * inv_h * inv_h * inv_h,
            c,
            pre,
            inv_rho: g.load(self.inv_rho),
            iad: if IAD {
                self.flow.iad.map(|c| g.load(c))
            } else {
                [zero; 6]
            },
            alpha: self.strength.target(g),
            stress: self.stress.map_or(zero, |s| s.target(pre)),
            grad_v: self.cleaning.map_or([zero; 6], |cl| cl.target(g)),
            weights: self.weights.target(g),
            cond: self.conduction.map(|c| {
                ConductionTarget::load(g, self.flow.norm, inv_h, self.flow.rho, self.flow.m, &c)
            }),
        };
        let sums = Sums {
            a: [zero; 3],
            ep: zero,
            eav: zero,
            div: zero,
            vsig: F::vsig_start(c),
            cond: zero,
        };
        (targets, sums)
    }

    #[inline(always)]
    fn pair(&self, (t, acc): &mut Self::Sums, j: usize, d: [F64s; 3], r2: F64s) {
        let zero = F64s::splat(0.0);
        let norm = self.flow.norm;
        let reach_j = {
            let r = self.flow.support * self.flow.h[j];
            r * r
        };
        // Lanes whose target has j as neighbour get weight 1, the others
        // compute with r = 1 (finite) and weight 0.
        let r2_true = r2;
        let (r2, weight) = neighbour_lanes(r2, t.reach, reach_j);
        let mj = self.flow.m[j] * weight;
        let inv_r = 1.0 / r2.sqrt();
        let rr = r2 * inv_r;
        let inv_hj = self.inv_h[j];
        let inv_hi = t.inv_h;
        // A_ij(h_i), A_ij(h_j), the kernel shapes w(r/h_i), w(r/h_j) and,
        // with conduction, (K/h_i^4 w'(r/h_i) + K/h_j^4 w'(r/h_j)) / 2.
        let (ai, aj, shape_i, shape_j, dw_mean) = if IAD {
            // A = C (x_j - x_i) W = -(C d) W
            // The shapes from v^2 = r^2 / h^2: no root on their path.
            let si = self.flow.kernel.shape_sq_lanes(r2 * t.inv_h2);
            let sj = self.flow.kernel.shape_sq_lanes(r2 * (inv_hj * inv_hj));
            // The derivatives at the true distance, as the conduction's own
            // pass takes them (measured faster than from `rr` here).
            let dw_mean = match &t.cond {
                Some(ci) => ci.mean_derivative(self.flow.kernel, norm, r2_true, inv_hi, inv_hj),
                None => zero,
            };
            let kj3 = norm * inv_hj * inv_hj * inv_hj;
            let wi = t.k3 * si;
            let wj = kj3 * sj;
            let cj = [0, 1, 2, 3, 4, 5].map(|k| F64s::splat(self.flow.iad[k][j]));
            let cd = sym_mat_vec_fused(&t.iad, d);
            let cdj = sym_mat_vec_fused(&cj, d);
            (scale3(cd, -wi), scale3(cdj, -wj), si, sj, dw_mean)
        } else {
            // grad_i W(r, h) = K/h^4 w'(r/h) d / r = K/h^5 (w'(v)/v) d, from
            // v^2 = r^2 / h^2: no root on the gradient's path.
            let (v2i, v2j) = (r2 * t.inv_h2, r2 * (inv_hj * inv_hj));
            let gi = t.k5 * self.flow.kernel.derivative_over_v_sq_lanes(v2i);
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
        if let (Some(c), Some(ci)) = (&self.conduction, &t.cond) {
            let (rho_j, p_j, u_j) = (self.flow.rho[j], c.p[j], c.u[j]);
            let term = ci.term(mj, dw_mean, rho_j, p_j, u_j);
            acc.cond += ci.weigh(c, j, self.flow.m[j], term);
        }
        let vi = t.v;
        let vij = [
            vi[0] - self.flow.v[0][j],
            vi[1] - self.flow.v[1][j],
            vi[2] - self.flow.v[2][j],
        ];
        let mut rv = dot_fused(vij, d);
        if let Some(cl) = &self.cleaning {
            let cleaned = rv + cl.correction(t.grad_v, j, d, rr * inv_hi.min(F64s::splat(inv_hj)));
            // Only approaching pairs: the viscous heating uses the raw jump.
            rv = rv.where_negative(cleaned);
        }
        let w = rv * inv_r;
        let alpha_ij = self.strength.pair(t.alpha, j);
        let visc = F::pair(t.c, self.flow.c[j], w, alpha_ij, weight, &mut acc.vsig);
        let mut vi_r = 0.5 * visc * t.inv_rho;
        let inv_rho_j = self.inv_rho[j];
        let mut vj_r = 0.5 * visc * inv_rho_j;
        if let Some(s) = self.stress {
            // R_ij f^4 / 2 on each side: -m_j R_ij f^4 (A_i + A_j) / 2.
            let half = s.pair(t.stress, self.pre[j], shape_i, shape_j);
            vi_r += half;
            vj_r += half;
        }
        let (a, b) = self.weights.pair(&t.weights, j);
        let (ci_f, cj_f) = (t.pre * a + vi_r, self.pre[j] * b + vj_r);
        // The sums by fused multiply-adds where the build has them (fewer
        // operations and a shorter chain per pair; the scalar reference of
        // the lane test takes the same forms).
        let neg_mj = -mj;
        for c in 0..3 {
            let f = ci_f.mul_add(ai[c], cj_f * aj[c]);
            acc.a[c] = neg_mj.mul_add(f, acc.a[c]);
        }
        let vai = dot_fused(vij, ai);
        let vaj = dot_fused(vij, aj);
        acc.ep = (mj * a).mul_add(vai, acc.ep);
        acc.eav = mj.mul_add(vi_r.mul_add(vai, vj_r * vaj), acc.eav);
        acc.div = (neg_mj * inv_rho_j).mul_add(vai, acc.div);
    }

    #[inline(always)]
    fn finish(&self, g: &Group, (t, acc): Self::Sums, out: &mut Self::Out<'_>) -> MomentumStats {
        let ([ax, ay, az, du], (criteria, impulse)) = out;
        acc.a[0].store(ax);
        acc.a[1].store(ay);
        acc.a[2].store(az);
        let du_i = t.pre * acc.ep + 0.5 * acc.eav;
        match (self.conduction, impulse) {
            (Some(c), Some([impulse])) if c.impulses.is_some() => {
                du_i.store(du);
                (c.alpha_u * acc.cond).store(impulse);
            }
            (Some(c), _) => (du_i + c.alpha_u * acc.cond).store(du),
            (None, _) => du_i.store(du),
        }
        let vsig = F::vsig_finish(acc.vsig, t.c);
        let h_over_vsig = (1.0 / (t.inv_h * vsig)).to_array();
        let div = acc.div.to_array();
        let mut st = MomentumStats::identity();
        for l in 0..g.valid {
            st.min_h_over_vsig = st.min_h_over_vsig.min(h_over_vsig[l]);
            st.max_abs_div_v = st.max_abs_div_v.max(F::compression(div[l]));
        }
        if let Some([hv, comp]) = criteria {
            hv.copy_from_slice(&h_over_vsig[..g.valid]);
            for (c, &d) in comp.iter_mut().zip(&div[..g.valid]) {
                *c = F::compression(d);
            }
        }
        st
    }
}

/// `a . b` as `a_z b_z + (a_y b_y + a_x b_x)`, fused where the build has
/// multiply-adds.
#[inline(always)]
fn dot_fused(a: [F64s; 3], b: [F64s; 3]) -> F64s {
    a[2].mul_add(b[2], a[1].mul_add(b[1], a[0] * b[0]))
}

/// `C v` for a symmetric matrix (as
/// [`sym_mat_vec`](crate::pair_loop::sym_mat_vec)), each row a
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
