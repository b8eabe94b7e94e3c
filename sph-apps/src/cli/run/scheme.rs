//! The scheme options of `sphexa run` both ways: as changes to the case's
//! scheme ([`scheme_overrides`]), and a scheme written back in the
//! options' terms ([`SCHEME_OPTIONS`], read by the resolved `config.toml`
//! and by `sphexa cases`); and their check in the options' terms.

use super::args::{RunArgs, SmoothingArg, Switch};
use crate::cases::{Scheme, SchemeOverrides};
use crate::AppError;
use sph_core::{AvForm, Choice, Volume, PRESETS};
use std::fmt;

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

/// A scheme option's value as the command line writes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Setting {
    /// A named value (`--gradients iad`).
    Name(&'static str),
    /// A number (`--alpha 1`).
    Number(f64),
    /// `on` or `off`.
    Switch(bool),
}

impl fmt::Display for Setting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Setting::Name(name) => f.write_str(name),
            Setting::Number(x) => write!(f, "{x}"),
            Setting::Switch(on) => f.write_str(if *on { "on" } else { "off" }),
        }
    }
}

impl Setting {
    /// The value in a `config.toml`.
    pub(crate) fn toml(self) -> toml::Value {
        match self {
            Setting::Number(x) => toml::Value::Float(x),
            other => toml::Value::String(other.to_string()),
        }
    }
}

/// One scheme option seen from a [`Scheme`]: its flag (the long option,
/// also its `config.toml` key), its value in the scheme, and whether
/// `sphexa cases` shows it for that scheme.
pub(crate) struct SchemeOption {
    /// The long option without dashes.
    pub(crate) key: &'static str,
    /// Its value in a scheme.
    pub(crate) value: fn(&Scheme) -> Setting,
    /// Whether a scheme listing shows it (the four basic options always,
    /// the others where they differ from the paper's scheme).
    pub(crate) listed: fn(&Scheme) -> bool,
}

/// Every scheme option, written from a [`Scheme`], in the order
/// `sphexa cases` lists them: the one place the resolved `config.toml`
/// and the listing take a scheme's options from.
pub(crate) const SCHEME_OPTIONS: &[SchemeOption] = &[
    SchemeOption {
        key: "gradients",
        value: |s| Setting::Name(s.gradients.name()),
        listed: |_| true,
    },
    SchemeOption {
        key: "grad-h",
        value: |s| Setting::Switch(s.grad_h),
        listed: |_| true,
    },
    SchemeOption {
        key: "alpha",
        value: |s| Setting::Number(s.alpha()),
        listed: |_| true,
    },
    SchemeOption {
        key: "av-switches",
        value: |s| Setting::Switch(s.switches().is_some()),
        listed: |_| true,
    },
    SchemeOption {
        key: "conductivity",
        value: |s| Setting::Number(s.conductivity.unwrap_or(0.0)),
        listed: |s| s.conductivity.is_some(),
    },
    SchemeOption {
        key: "artificial-stress",
        value: |s| Setting::Number(s.artificial_stress.unwrap_or(0.0)),
        listed: |s| s.artificial_stress.is_some(),
    },
    SchemeOption {
        key: "smoothing-length",
        value: |s| Setting::Name(if s.fixed_h { "fixed" } else { "adaptive" }),
        listed: |s| s.fixed_h,
    },
    SchemeOption {
        key: "volume",
        value: |s| Setting::Name(s.volume.name()),
        listed: |s| s.volume != Volume::Mass,
    },
    SchemeOption {
        key: "av-cleaning",
        value: |s| Setting::Switch(s.av_cleaning),
        listed: |s| s.av_cleaning,
    },
    SchemeOption {
        key: "av-form",
        value: |s| Setting::Name(s.av_form.name()),
        listed: |s| s.av_form != AvForm::Paper,
    },
];

/// `s` as the options that select it (those [`SchemeOption::listed`]
/// shows), e.g. `--gradients iad --grad-h on --alpha 1 --av-switches off`.
pub(crate) fn scheme_flags(s: &Scheme) -> String {
    let flags: Vec<String> = SCHEME_OPTIONS
        .iter()
        .filter(|o| (o.listed)(s))
        .map(|o| format!("--{} {}", o.key, (o.value)(s)))
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
                tokens.push((o.value)(&preset).to_string());
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
