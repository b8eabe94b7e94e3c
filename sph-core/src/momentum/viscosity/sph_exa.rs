//! SPH-EXA's `hydro_ve` viscosity ([`AvForm::SphExa`](super::AvForm::SphExa)):
//! `Pi'_ij = -(alpha_ij/2 (c_i + c_j) - 2 w_ij) w_ij`, Courant signal
//! velocity `max_j ((c_i + c_j)/2 - 2 w_ij)` over every neighbour, and the
//! density criterion on expansion only.

use super::ViscosityForm;
use crate::pair_loop::F64s;

/// SPH-EXA's form.
pub(crate) struct SphExa;

impl ViscosityForm for SphExa {
    #[inline(always)]
    fn vsig_start(_ci: F64s) -> F64s {
        F64s::splat(0.0)
    }

    #[inline(always)]
    fn pair(ci: F64s, cj: f64, w: F64s, alpha_ij: F64s, weight: F64s, vsig: &mut F64s) -> F64s {
        let cij = ci + cj;
        let minus_two = F64s::splat(-2.0);
        *vsig = vsig.max(minus_two.mul_add(w, 0.5 * cij) * weight);
        w.where_negative(-minus_two.mul_add(w, 0.5 * alpha_ij * cij) * w)
    }

    #[inline(always)]
    fn vsig_finish(vsig: F64s, ci: F64s) -> F64s {
        // c_i where no neighbour gave a positive signal velocity.
        F64s::select_positive(vsig, vsig, ci)
    }

    #[inline(always)]
    fn compression(div_v: f64) -> f64 {
        div_v.max(0.0)
    }
}
