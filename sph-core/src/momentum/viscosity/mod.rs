//! The artificial viscosity's forms: each is one [`AvForm`] value and one
//! file holding its pair term and its Courant signal velocity. Adding a
//! form is a variant here (with its name and help in the [`Choice`]
//! impl, from which the command line takes its values, and its arm in
//! [`with_form`]) and its file beside this one.

mod paper;
mod sph_exa;

use crate::choice::Choice;
use crate::pair_loop::F64s;
use serde::{Deserialize, Serialize};

/// The form of the artificial viscosity and of the Courant signal
/// velocity (`w_ij = v_ij . x_ij / r_ij`, pairs approaching when
/// `w_ij < 0`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum AvForm {
    /// The seed paper's: `Pi'_ij = -alpha_ij/2 (c_i + c_j - 3 w_ij) w_ij`;
    /// Courant `v_sig,i = max(c_i, max_j (c_i + c_j - 3 min(w_ij, 0)))`;
    /// density criterion on `max_i |div v_i|`.
    #[default]
    Paper,
    /// SPH-EXA's `hydro_ve`: `Pi'_ij = -(alpha_ij/2 (c_i + c_j) - 2 w_ij) w_ij`
    /// (`beta = 2` not scaled by `alpha`); Courant
    /// `v_sig,i = max_j ((c_i + c_j)/2 - 2 w_ij)` over all neighbours (`c_i`
    /// when that is not positive); density criterion on the largest
    /// expansion `max_i max(div v_i, 0)` (SPH-EXA takes the largest signed
    /// `div v`, which is the same whenever some particle expands).
    SphExa,
}

/// `--av-form` and the `av-form` key.
impl Choice for AvForm {
    const ALL: &'static [Self] = &[AvForm::Paper, AvForm::SphExa];

    fn name(&self) -> &'static str {
        match self {
            AvForm::Paper => "paper",
            AvForm::SphExa => "sph-exa",
        }
    }

    fn help(&self) -> &'static str {
        match self {
            AvForm::Paper => {
                "The seed paper's: Pi_ij = -alpha_ij/2 (c_i + c_j - 3 w_ij) w_ij, and the \
                 Courant signal velocity c_i + c_j - 3 min(w_ij, 0)"
            }
            AvForm::SphExa => {
                "SPH-EXA's `ve`: Pi_ij = -(alpha_ij/2 (c_i + c_j) - 2 w_ij) w_ij (its beta = 2 \
                 term not scaled by alpha), and the Courant signal velocity (c_i + c_j)/2 - 2 w_ij"
            }
        }
    }
}

/// One form's pair term, as the momentum stage uses it (compile-time
/// dispatch: the forms are zero-sized types).
pub(crate) trait ViscosityForm: Sync {
    /// The targets' Courant signal velocity before any pair.
    fn vsig_start(ci: F64s) -> F64s;

    /// `Pi'_ij` of the pairs with sound speeds `ci`, `cj`, approach speed
    /// `w` and strength `alpha_ij`, raising the targets' signal velocity
    /// `vsig` over the lanes of nonzero `weight` (the pair's neighbours).
    fn pair(ci: F64s, cj: f64, w: F64s, alpha_ij: F64s, weight: F64s, vsig: &mut F64s) -> F64s;

    /// The Courant signal velocity from the pairs' maximum `vsig`.
    fn vsig_finish(vsig: F64s, ci: F64s) -> F64s;

    /// What the density-change criterion takes of `div v_i`.
    fn compression(div_v: f64) -> f64;
}

/// A computation run with the viscosity form as a type parameter.
pub(crate) trait WithForm {
    /// What it returns.
    type Output;
    /// The computation for form `F`.
    fn run<F: ViscosityForm>(self) -> Self::Output;
}

/// Runs `w` with the term of `form`: the one place an [`AvForm`] value
/// becomes a type.
pub(crate) fn with_form<W: WithForm>(form: AvForm, w: W) -> W::Output {
    match form {
        AvForm::Paper => w.run::<paper::Paper>(),
        AvForm::SphExa => w.run::<sph_exa::SphExa>(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `Pi'` of one lane for form `F`, and the lane's signal velocity.
    fn one<F: ViscosityForm>(ci: f64, cj: f64, w: f64, alpha: f64) -> (f64, f64) {
        let ci = F64s::splat(ci);
        let mut vsig = F::vsig_start(ci);
        let pi = F::pair(
            ci,
            cj,
            F64s::splat(w),
            F64s::splat(alpha),
            F64s::splat(1.0),
            &mut vsig,
        );
        (pi.to_array()[0], F::vsig_finish(vsig, ci).to_array()[0])
    }

    proptest! {
        /// Every form: no viscosity between receding pairs, a positive
        /// `Pi'` (a repulsion and heating) between approaching ones, and a
        /// positive signal velocity, at least `(c_i + c_j) / 2` on approach.
        #[test]
        fn forms_act_on_approach_only(
            ci in 0.01f64..10.0, cj in 0.01f64..10.0, w in -10.0f64..10.0, alpha in 0.01f64..2.0,
        ) {
            for (name, (pi, vsig)) in [
                ("paper", one::<paper::Paper>(ci, cj, w, alpha)),
                ("sph-exa", one::<sph_exa::SphExa>(ci, cj, w, alpha)),
            ] {
                if w >= 0.0 {
                    prop_assert_eq!(pi, 0.0, "{} w {}", name, w);
                } else {
                    prop_assert!(pi > 0.0, "{} w {} pi {}", name, w, pi);
                }
                prop_assert!(vsig > 0.0, "{} vsig {}", name, vsig);
                if w < 0.0 {
                    prop_assert!(vsig >= 0.5 * (ci + cj), "{} vsig {}", name, vsig);
                }
            }
        }
    }

    /// The paper's form at rest-frame numbers: `alpha/2 (c_i + c_j - 3 w) (-w)`.
    #[test]
    fn paper_form_is_the_seed_papers() {
        let (pi, vsig) = one::<paper::Paper>(1.0, 2.0, -0.5, 1.0);
        assert!((pi - 0.5 * (3.0 + 1.5) * 0.5).abs() < 1e-15);
        assert!((vsig - 4.5).abs() < 1e-15);
        let (pi, vsig) = one::<sph_exa::SphExa>(1.0, 2.0, -0.5, 1.0);
        assert!((pi - (0.5 * 3.0 + 1.0) * 0.5).abs() < 1e-15);
        assert!((vsig - 2.5).abs() < 1e-15);
    }
}
