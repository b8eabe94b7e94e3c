//! The scheme options of `sphexa run`: their flags, built from the one
//! table [`SCHEME_OPTIONS`] ([`SchemeArgs`]), the changes they make to the
//! case's scheme ([`scheme_overrides`]), a scheme written back in their
//! terms ([`scheme_flags`], and the resolved `config.toml`), and their
//! check in the options' terms.

use super::args::RunArgs;
use crate::cases::{Scheme, SchemeOverrides, Setting, Values, SCHEME_OPTIONS};
use crate::cli::parse::parse_non_negative;
use crate::AppError;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser, ValueParser};
use clap::{Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches};
use sph_core::PRESETS;

/// The heading of the scheme options in `sphexa run --help`.
pub(crate) const HEADING: &str = "Scheme (over the case's, or the --scheme preset's)";

/// The values of the scheme options given on the command line (same order
/// as [`SCHEME_OPTIONS`]).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SchemeArgs(pub(crate) [Option<Setting>; SCHEME_OPTIONS.len()]);

impl SchemeArgs {
    /// The value given for `key`, if any.
    pub(crate) fn get(&self, key: &str) -> Option<Setting> {
        SCHEME_OPTIONS
            .iter()
            .zip(&self.0)
            .find(|(o, _)| o.key == key)
            .and_then(|(_, v)| *v)
    }
}

/// The argument id of an option: its key with `_` for `-`, as clap's
/// derive names the other options' fields.
fn id(key: &str) -> String {
    key.replace('-', "_")
}

/// The names of `values` as a parser to [`Setting::Name`], each with its
/// help in `--help`.
fn names_parser(names: fn() -> Vec<(&'static str, &'static str)>) -> ValueParser {
    let values = names()
        .into_iter()
        .map(|(name, help)| PossibleValue::new(name).help(help));
    PossibleValuesParser::new(values)
        .map(move |given| {
            let (name, _) = names()
                .into_iter()
                .find(|(name, _)| *name == given)
                .expect("the parser accepts only listed names");
            Setting::Name(name)
        })
        .into()
}

/// The command-line argument of each scheme option.
fn scheme_args() -> impl Iterator<Item = Arg> {
    SCHEME_OPTIONS.iter().map(|o| {
        let parser: ValueParser = match o.values {
            Values::Names(names) => names_parser(names),
            Values::NonNegative => {
                ValueParser::new(|s: &str| parse_non_negative(s).map(Setting::Number))
            }
            Values::Switch => PossibleValuesParser::new([
                PossibleValue::new("on").help("Enabled"),
                PossibleValue::new("off").help("Disabled"),
            ])
            .map(|v| Setting::Switch(v == "on"))
            .into(),
        };
        Arg::new(id(o.key))
            .long(o.key)
            .help(o.help)
            .value_name(id(o.key).to_uppercase())
            .action(ArgAction::Set)
            .allow_negative_numbers(matches!(o.values, Values::NonNegative))
            .value_parser(parser)
            .help_heading(HEADING)
    })
}

impl FromArgMatches for SchemeArgs {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let mut a = SchemeArgs::default();
        a.update_from_arg_matches(m)?;
        Ok(a)
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        for (o, v) in SCHEME_OPTIONS.iter().zip(&mut self.0) {
            if let Some(s) = m.try_get_one::<Setting>(&id(o.key)).map_err(|e| {
                clap::Error::raw(clap::error::ErrorKind::InvalidValue, e.to_string())
            })? {
                *v = Some(*s);
            }
        }
        Ok(())
    }
}

impl Args for SchemeArgs {
    fn augment_args(cmd: Command) -> Command {
        cmd.args(scheme_args())
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

/// Checks the scheme the run will use (the case's with the command line's
/// overrides) before the solver sees it, in the options' terms.
pub(crate) fn check_scheme(s: &Scheme, a: &RunArgs, case: &str) -> Result<(), AppError> {
    if let Some(sw) = s.switches() {
        if s.alpha() < sw.alpha_min || s.alpha().is_nan() {
            let given = |key| a.scheme_options.get(key).is_some();
            let origin = match (given("alpha"), given("av-switches"), &a.scheme) {
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
