//! The scheme options of `sphexa run` as command-line arguments, built
//! from the one table [`SCHEME_OPTIONS`] ([`SchemeArgs`], flattened into
//! the run's options under their own `--help` heading).

use crate::cases::{Setting, Values, SCHEME_OPTIONS};
use crate::cli::parse::parse_non_negative;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser, ValueParser};
use clap::{Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches};

/// The heading of the scheme options in `sphexa run --help`.
pub(crate) const HEADING: &str = "Scheme (over the case's, or the --scheme preset's)";

/// The values of the scheme options given on the command line (same order
/// as [`SCHEME_OPTIONS`]).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SchemeArgs(pub(crate) [Option<Setting>; SCHEME_OPTIONS.len()]);

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
