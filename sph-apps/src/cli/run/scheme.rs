//! The scheme options of `sphexa run` (their flags: `scheme_args.rs`): the
//! changes they make to the case's scheme ([`scheme_overrides`]), a scheme
//! written back in their terms ([`scheme_flags`], and the resolved
//! `config.toml`), and their check in the options' terms.

use super::args::RunArgs;
use crate::cases::{Scheme, SchemeOverrides, Setting, SCHEME_OPTIONS};
use crate::AppError;
use sph_core::{Eos, PRESETS};

/// Checks the scheme the run will use (the case's with the command line's
/// overrides) before the solver sees it, in the options' terms.
pub(crate) fn check_scheme(o: &SchemeOverrides, base: Scheme, case: &str) -> Result<(), AppError> {
    let s = o.over(base);
    if let Some(sw) = s.switches() {
        if s.alpha() < sw.alpha_min || s.alpha().is_nan() {
            let given = |key| o.get(key).is_some();
            let origin = match (given("alpha"), given("av-switches"), o.preset) {
                (true, true, _) => "--av-switches on",
                (true, false, Some(_)) => "the scheme given by --scheme",
                (true, false, None) => "the scheme of case '{case}'",
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

/// Refuses `--eos tait-ref:C0` on a case whose own equation of state is
/// not referenced: each particle's reference pressure comes from the case
/// that has it (the square patch).
pub(crate) fn check_eos(a: &RunArgs, case: &dyn crate::cases::Case) -> Result<(), AppError> {
    match a.eos {
        Some(e @ Eos::TaitReferenced { .. }) if !case.physics().eos.needs_reference() => {
            Err(AppError::Usage(format!(
                "--eos {e}: tait-ref takes each particle's reference pressure from a case that sets it (square-patch); case '{}' does not; accepted: {}",
                case.name(),
                sph_core::eos::EOS_FORMS
            )))
        }
        _ => Ok(()),
    }
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
    let overrides = SchemeOverrides {
        preset,
        options: a.scheme_options.0,
        softening: a.softening,
        courant: a.courant,
        first_step: a.first_step,
        eos: a.eos,
        stirring: a.stir.map(|s| s.0),
    };
    if a.no_grad_h {
        return overrides.with("grad-h", Setting::Switch(false));
    }
    Ok(overrides)
}

/// A setting as a `config.toml` value.
pub(crate) fn toml_value(s: Setting) -> toml::Value {
    match s {
        Setting::Number(x) => toml::Value::Float(x),
        other => toml::Value::String(other.to_string()),
    }
}

/// `s` as the options that select it (those [`crate::cases::SchemeOption::listed`]
/// shows), e.g. `--gradients iad --grad-h on --alpha 1 --av-switches off`.
pub(crate) fn scheme_flags(s: &Scheme) -> String {
    let flags: Vec<String> = SCHEME_OPTIONS
        .iter()
        .filter(|o| (o.listed)(s))
        .map(|o| format!("--{} {}", o.key, (o.get)(s)))
        .collect();
    flags.join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::run::args::RunArgs;
    use clap::Parser;

    /// `sphexa run` options alone, for the test.
    #[derive(Parser)]
    #[command(no_binary_name = true)]
    struct Run {
        #[command(flatten)]
        args: RunArgs,
    }

    /// Every preset written as options and read back by the command line
    /// (over the paper's scheme) is the preset: the two directions agree.
    #[test]
    fn presets_round_trip_through_the_options() {
        for (name, preset, _) in PRESETS {
            let mut tokens = vec!["sedov".to_owned()];
            for o in SCHEME_OPTIONS {
                tokens.push(format!("--{}", o.key));
                tokens.push((o.get)(&preset).to_string());
            }
            let run = Run::try_parse_from(&tokens).expect("the options parse");
            let over = scheme_overrides(&run.args).expect("valid overrides");
            let mut back = sph_core::HydroConfig::default();
            over.apply(Scheme::PAPER, crate::cases::Physics::IDEAL_GAS, &mut back);
            let (mut want, mut got) = (preset, back.scheme);
            // The options do not carry the switches' own parameters beyond
            // alpha; compare them apart.
            if let (Some(a), Some(b)) = (want.switches(), got.switches()) {
                assert_eq!(a.alpha_max, b.alpha_max, "{name}");
                got.viscosity = want.viscosity;
            }
            want.viscosity = got.viscosity;
            assert_eq!(got, want, "{name}: {tokens:?}");
        }
    }
}
