//! The layers of a run's options: the command line over a `--config`
//! file over the configuration stored in a `--restart` checkpoint, each
//! layer's values checked by the options' own parsers.

use super::args::{RunArgs, RunOnly};
use crate::config::{self, OptionKey};
use crate::{checkpoint, AppError};
use clap::parser::ValueSource;
use clap::{ArgAction, ArgMatches, CommandFactory, Parser};
use std::ffi::OsString;

/// Every option of `sphexa run`, with its configuration key (the long
/// option without dashes; `case` for the case).
fn option_keys() -> Vec<OptionKey> {
    RunOnly::command()
        .get_arguments()
        .filter(|a| !matches!(a.get_id().as_str(), "help" | "version"))
        .map(|a| OptionKey {
            key: a
                .get_long()
                .map(str::to_owned)
                .unwrap_or_else(|| a.get_id().to_string()),
            id: a.get_id().to_string(),
            flag: matches!(a.get_action(), ArgAction::SetTrue),
            positional: a.is_positional(),
        })
        .collect()
}

/// Options that exclude each other: a layer's key is dropped when a
/// higher layer sets its partner.
const EXCLUSIVE: &[[&str; 2]] = &[
    ["steps", "end-time"],
    ["grad-h", "no-grad-h"],
    ["restart", "init"],
];

/// The first line of a command-line error, without clap's `error: `.
fn first_line(e: &clap::Error) -> String {
    let msg = e.render().to_string();
    msg.lines()
        .next()
        .unwrap_or("")
        .trim_start_matches("error: ")
        .to_owned()
}

/// Reads a configuration table from TOML `text` of `source`, refusing
/// unknown keys (named, with the allowed keys) and values the option's own
/// parser refuses.
fn config_table(text: &str, source: &str, keys: &[OptionKey]) -> Result<toml::Table, AppError> {
    config::table(text, source, keys, |tokens| {
        RunOnly::try_parse_from(tokens)
            .map(drop)
            .map_err(|e| first_line(&e))
    })
}

/// The run's options: the command line over the configuration file
/// (`--config`) over the checkpoint's configuration (`--restart`).
pub(crate) fn layered(cli: RunArgs, m: &ArgMatches) -> Result<RunArgs, AppError> {
    if cli.config.is_none() && cli.restart.is_none() {
        return Ok(cli);
    }
    let keys = option_keys();
    let mut taken: Vec<String> = keys
        .iter()
        .filter(|k| m.value_source(&k.id) == Some(ValueSource::CommandLine))
        .map(|k| k.key.clone())
        .collect();
    let mut layers: Vec<(String, toml::Table)> = Vec::new();
    if let Some(path) = &cli.config {
        let source = path.display().to_string();
        let text = config::read(path)?;
        layers.push((source.clone(), config_table(&text, &source, &keys)?));
    }
    let restart = cli.restart.clone().or_else(|| {
        layers
            .first()
            .and_then(|(_, t)| t.get("restart"))
            .and_then(|v| v.as_str().map(str::to_owned))
    });
    if let Some(spec) = restart {
        let (path, step) = checkpoint::split_spec(&spec)?;
        let k = checkpoint::group_of_step(&path, step)?;
        let meta = sph_io::SnapshotReader::read_step(
            &sph_io::H5Part,
            &path,
            k,
            &sph_io::Selection::Names(Vec::new()),
        )?;
        let source = format!("{} (the checkpoint's configuration)", path.display());
        if let Some(sph_io::Attr::Str(text)) = meta.attr("config") {
            let mut table = config_table(text, &source, &keys)?;
            for key in ["restart", "init", "config"] {
                table.remove(key);
            }
            // Written before block steps became the default: the run
            // that wrote it stepped globally.
            table
                .entry("time-steps")
                .or_insert_with(|| toml::Value::String("global".into()));
            layers.push((source, table));
        }
    }
    let mut tokens: Vec<OsString> = Vec::new();
    for (source, table) in &layers {
        let mut mine = Vec::new();
        for (name, value) in table {
            let partner_taken = EXCLUSIVE.iter().any(|pair| {
                pair.contains(&name.as_str()) && pair.iter().any(|p| taken.iter().any(|t| t == p))
            });
            if taken.contains(name) || partner_taken {
                continue;
            }
            let k = keys.iter().find(|k| &k.key == name).expect("checked key");
            tokens.extend(
                config::tokens(k, value, source)?
                    .into_iter()
                    .map(OsString::from),
            );
            mine.push(name.clone());
        }
        taken.extend(mine);
    }
    // The command line's own tokens, after `run`.
    let argv: Vec<OsString> = std::env::args_os().collect();
    if let Some(at) = argv.iter().position(|a| a == "run") {
        tokens.extend(argv[at + 1..].iter().cloned());
    }
    RunOnly::try_parse_from(&tokens)
        .map(|r| r.args)
        .map_err(|e| AppError::Usage(first_line(&e)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::run::resolved::resolved_config;
    use crate::simulation::Stop;
    use proptest::prelude::*;
    use sph_core::HydroConfig;
    use std::path::Path;

    /// The resolved configuration of a Sedov run, as `sphexa run` writes
    /// it: every key of the defaults.
    fn resolved() -> String {
        let a = RunOnly::try_parse_from([
            "sedov",
            "--checkpoint-every",
            "3",
            "--snapshot-at",
            "0.1,0.2",
        ])
        .expect("options")
        .args;
        let config = HydroConfig::default();
        let t = resolved_config(
            &a,
            "sedov",
            8,
            Stop::Steps(5),
            Path::new("out"),
            &config,
            None,
        );
        toml::to_string(&t).expect("TOML")
    }

    /// What `--config hostile.toml` holding `text` gives: a table, or an
    /// error that names the file; the table's tokens parse or are refused,
    /// never a panic.
    fn configure(text: &str) -> Result<(), String> {
        let keys = option_keys();
        let table = config_table(text, "hostile.toml", &keys).map_err(|e| e.to_string())?;
        let mut tokens = Vec::new();
        for (name, value) in &table {
            let k = keys.iter().find(|k| &k.key == name).expect("checked key");
            tokens.extend(config::tokens(k, value, "hostile.toml").map_err(|e| e.to_string())?);
        }
        RunOnly::try_parse_from(&tokens)
            .map(drop)
            .map_err(|e| format!("hostile.toml: {}", first_line(&e)))
    }

    #[test]
    fn the_resolved_configuration_reads_back() {
        let text = resolved();
        assert!(
            text.contains("case = \"sedov\"") && text.contains("checkpoint-every"),
            "{text}"
        );
        configure(&text).expect("valid");
        let e = configure("side = 0\n").unwrap_err();
        assert!(
            e.contains("hostile.toml") && e.contains("'side'") && e.contains("4 to 1000"),
            "{e}"
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        /// A changed byte or a cut in a run's configuration, checked by the
        /// driver's own option parsers: an error naming the file, or read.
        #[test]
        fn a_damaged_configuration_is_refused_by_name_or_read(
            pos in any::<prop::sample::Index>(),
            mask in 1u8..=255,
            keep in any::<prop::sample::Index>(),
        ) {
            let text = resolved();
            let mut bytes = text.as_bytes().to_vec();
            let i = pos.index(bytes.len());
            bytes[i] ^= mask;
            // Not UTF-8: config::read refuses it before any parsing.
            if let Ok(flipped) = String::from_utf8(bytes) {
                if let Err(e) = configure(&flipped) {
                    prop_assert!(e.contains("hostile.toml"), "{}", e);
                }
            }
            let n = keep.index(text.len() + 1);
            if let Err(e) = configure(&text[..n]) {
                prop_assert!(e.contains("hostile.toml"), "{}", e);
            }
        }

        /// Random text of TOML's characters and option-like words.
        #[test]
        fn random_configurations_are_refused_by_name_or_read(
            text in "(side|steps|end-time|kernel|alpha|snapshot-at|checkpoint-every|quiet|case|[a-z-]{1,8})( ?= ?)([0-9.e+-]{0,8}|\"[a-z0-9:.,-]{0,10}\"|true|false|\\[[0-9., ]{0,12}\\]|\\{\\})\n{0,2}",
            junk in "[a-z0-9 =\"'\\[\\]{}.,#\n_+:-]{0,128}",
        ) {
            for t in [text.as_str(), junk.as_str()] {
                if let Err(e) = configure(t) {
                    prop_assert!(e.contains("hostile.toml"), "{}", e);
                }
            }
        }
    }
}
