//! The scheme options of `sphexa run` as changes to the case's scheme
//! ([`SchemeOverrides`]), and their check in the options' terms.

use super::args::{RunArgs, SmoothingArg, Switch};
use crate::cases::{Scheme, SchemeOverrides};
use crate::AppError;
use sph_core::PRESETS;

/// Checks the scheme the run will use (the case's with the command line's
/// overrides) before the solver sees it, in the options' terms.
pub(crate) fn check_scheme(s: &Scheme, a: &RunArgs, case: &str) -> Result<(), AppError> {
    if let Some(sw) = s.switches() {
        if s.alpha() < sw.alpha_min || s.alpha().is_nan() {
            let origin = match (a.alpha, a.av_switches, &a.scheme) {
                (Some(_), Some(_), _) => "--av-switches on",
                (Some(_), None, Some(_)) => "the scheme given by --scheme",
                (Some(_), None, None) => "the scheme of case '{case}'",
                _ => "the scheme",
            }
            .replace("{case}", case);
            return Err(AppError::Usage(format!(
                "--alpha {}: with viscosity switches on ({origin}), --alpha is the largest viscosity and must be at least the switches' floor {}; give --alpha >= {}, or --av-switches off for one constant alpha (any value >= 0)",
                s.alpha(),
                sw.alpha_min,
                sw.alpha_min
            )));
        }
    }
    s.validate()
        .map_err(|e| AppError::Usage(format!("scheme options: {e}")))
}

/// What the command line changes in the case's scheme.
pub(crate) fn scheme_overrides(a: &RunArgs) -> Result<SchemeOverrides, AppError> {
    let preset = match &a.scheme {
        Some(name) => Some(Scheme::preset(name).map_err(|_| {
            let names: Vec<String> = PRESETS
                .iter()
                .map(|(n, _, what)| format!("{n} ({what})"))
                .collect();
            AppError::Usage(format!(
                "--scheme {name}: unknown scheme; presets: {}",
                names.join("; ")
            ))
        })?),
        None => None,
    };
    Ok(SchemeOverrides {
        preset,
        gradients: a.gradients,
        grad_h: if a.no_grad_h {
            Some(false)
        } else {
            a.grad_h.map(|g| g == Switch::On)
        },
        alpha: a.alpha,
        av_switches: a.av_switches.map(|s| s == Switch::On),
        conductivity: a.conductivity,
        artificial_stress: a.artificial_stress,
        fixed_h: a.smoothing_length.map(|s| s == SmoothingArg::Fixed),
        volume: a.volume,
        av_cleaning: a.av_cleaning.map(|s| s == Switch::On),
        av_form: a.av_form,
        softening: a.softening,
        courant: a.courant,
        first_step: a.first_step,
    })
}
