//! The seed paper's viscosity ([`AvForm::Paper`](super::AvForm::Paper)):
//! `Pi'_ij = -alpha_ij/2 v_sig w_ij` with `v_sig = c_i + c_j - 3 min(w_ij, 0)`,
//! the same signal velocity for the Courant condition (at least `c_i`).

use super::ViscosityForm;
use crate::pair_loop::F64s;

/// The seed paper's form.
pub(crate) struct Paper;

impl ViscosityForm for Paper {
    #[inline(always)]
    fn vsig_start(ci: F64s) -> F64s {
        ci
    }

    #[inline(always)]
    fn pair(ci: F64s, cj: f64, w: F64s, alpha_ij: F64s, weight: F64s, vsig: &mut F64s) -> F64s {
        let v = F64s::splat(-3.0).mul_add(w.min(F64s::splat(0.0)), ci + cj);
        *vsig = vsig.max(v * weight);
        w.where_negative(-0.5 * alpha_ij * v * w)
    }

    #[inline(always)]
    fn vsig_finish(vsig: F64s, _ci: F64s) -> F64s {
        vsig
    }

    #[inline(always)]
    fn compression(div_v: f64) -> f64 {
        div_v.abs()
    }
}
