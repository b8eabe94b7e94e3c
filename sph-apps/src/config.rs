//! Configuration files of `sphexa run` (`--config FILE`, and the
//! configuration a checkpoint stores): a TOML table whose keys are the long
//! options without dashes (`case` for the case) and whose values are what
//! the option takes (`true`/`false` for flags; lists for comma-separated
//! options).
//!
//! The driver's command line knows which options exist and what values
//! they take; this module reads and checks a file against them: the option
//! list ([`OptionKey`]s) and a check of one option's command-line tokens
//! are passed in, so the reading and checking is tested here without the
//! driver.
//!
//! ```
//! use sph_apps::config::{table, OptionKey};
//!
//! let keys = [OptionKey::value("side"), OptionKey::flag("quiet")];
//! // The driver's check parses the tokens with its command line.
//! let check = |tokens: &[String]| match tokens[0].as_str() {
//!     "--side=0" => Err("invalid value '0' for '--side <N>': 4 to 1000".to_string()),
//!     _ => Ok(()),
//! };
//! let t = table("side = 8\nquiet = true\n", "run.toml", &keys, check).unwrap();
//! assert_eq!(t["side"].as_integer(), Some(8));
//! let e = table("side = 0\n", "run.toml", &keys, check).unwrap_err().to_string();
//! assert!(e.contains("run.toml") && e.contains("'side'") && e.contains("4 to 1000"));
//! let e = table("sides = 8\n", "run.toml", &keys, check).unwrap_err().to_string();
//! assert!(e.contains("unknown key 'sides'") && e.contains("allowed keys: side, quiet"));
//! ```

use crate::AppError;
use std::io::Read;
use std::path::Path;

/// The largest configuration file read: a run's resolved configuration
/// is about 2 kB; anything this large is not one.
pub const MAX_BYTES: u64 = 1 << 20;

/// One option of `sphexa run` as a configuration key.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OptionKey {
    /// The key: the long option without dashes (`case` for the case).
    pub key: String,
    /// The option's id in the command line.
    pub id: String,
    /// A flag (no value: `key = true` gives `--key`).
    pub flag: bool,
    /// A positional argument (the value alone, not `--key=value`).
    pub positional: bool,
}

impl OptionKey {
    /// An option `--key=VALUE`.
    pub fn value(key: &str) -> Self {
        OptionKey {
            key: key.to_owned(),
            id: key.to_owned(),
            flag: false,
            positional: false,
        }
    }

    /// A flag `--key`.
    pub fn flag(key: &str) -> Self {
        OptionKey {
            flag: true,
            ..Self::value(key)
        }
    }

    /// A positional argument.
    pub fn positional(key: &str) -> Self {
        OptionKey {
            positional: true,
            ..Self::value(key)
        }
    }
}

/// The text of configuration file `path` (what `--config` reads).
///
/// # Errors
/// A file that cannot be read, is larger than [`MAX_BYTES`] or is not
/// UTF-8, named (`--config FILE: ...`) before more than [`MAX_BYTES`] are
/// read.
pub fn read(path: &Path) -> Result<String, AppError> {
    let source = path.display();
    let cannot =
        |e: std::io::Error| AppError::Usage(format!("--config {source}: cannot read it ({e})"));
    let file = std::fs::File::open(path).map_err(cannot)?;
    // One byte past the limit tells a file at the limit from a larger one
    // (the length in the metadata is not there for pipes and devices).
    let mut bytes = Vec::new();
    file.take(MAX_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(cannot)?;
    if bytes.len() as u64 > MAX_BYTES {
        return Err(AppError::Usage(format!(
            "--config {source}: larger than {MAX_BYTES} bytes; a configuration file is a short \
             TOML table of run options (see the config.toml of a run)"
        )));
    }
    String::from_utf8(bytes).map_err(|e| {
        AppError::Usage(format!(
            "--config {source}: not UTF-8 text (byte {} is not valid UTF-8); a configuration \
             file is a TOML table of run options",
            e.utf8_error().valid_up_to()
        ))
    })
}

/// The command-line tokens of `key = value` from `source`.
///
/// # Errors
/// A value the key cannot take (a table, a date, a nested list; not a
/// boolean for a flag), named with `source`.
pub fn tokens(k: &OptionKey, value: &toml::Value, source: &str) -> Result<Vec<String>, AppError> {
    let bad = |what: &str| AppError::Usage(format!("{source}: key '{}' = {value}: {what}", k.key));
    if k.flag {
        return match value {
            toml::Value::Boolean(true) => Ok(vec![format!("--{}", k.key)]),
            toml::Value::Boolean(false) => Ok(Vec::new()),
            _ => Err(bad("must be true or false")),
        };
    }
    let scalar = |v: &toml::Value| match v {
        toml::Value::String(s) => Ok(s.clone()),
        toml::Value::Integer(i) => Ok(i.to_string()),
        // Display of f64 is the shortest text that parses back exactly.
        toml::Value::Float(f) => Ok(f.to_string()),
        toml::Value::Boolean(b) => Ok(if *b { "on" } else { "off" }.to_owned()),
        _ => Err(bad(
            "must be a string, a number, a boolean or a list of these",
        )),
    };
    let text = match value {
        toml::Value::Array(items) => items
            .iter()
            .map(scalar)
            .collect::<Result<Vec<_>, _>>()?
            .join(","),
        v => scalar(v)?,
    };
    Ok(if k.positional {
        vec![text]
    } else {
        vec![format!("--{}={text}", k.key)]
    })
}

/// Reads a configuration table from TOML `text` of `source`, refusing
/// unknown keys (named, with the allowed keys; `config` is not allowed in
/// a file) and values that `check` refuses: `check` gets the command-line
/// tokens of one key and returns the first line of the command line's
/// error.
///
/// # Errors
/// Text that is not TOML, an unknown key, a value of the wrong kind or
/// one `check` refuses, each named with `source`.
pub fn table(
    text: &str,
    source: &str,
    keys: &[OptionKey],
    check: impl Fn(&[String]) -> Result<(), String>,
) -> Result<toml::Table, AppError> {
    let table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| AppError::Usage(format!("{source}: not valid TOML: {e}")))?;
    for (name, value) in &table {
        let Some(k) = keys.iter().find(|k| &k.key == name && k.key != "config") else {
            let allowed: Vec<&str> = keys
                .iter()
                .map(|k| k.key.as_str())
                .filter(|k| *k != "config")
                .collect();
            return Err(AppError::Usage(format!(
                "{source}: unknown key '{name}'; allowed keys: {}",
                allowed.join(", ")
            )));
        };
        let tokens = tokens(k, value, source)?;
        if let Err(first) = check(&tokens) {
            return Err(AppError::Usage(format!(
                "{source}: key '{name}' = {value}: {first}"
            )));
        }
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_become_the_tokens_of_their_option() {
        let t = |k: &OptionKey, v: &str| {
            let value: toml::Value =
                format!("v = {v}").parse::<toml::Table>().unwrap()["v"].clone();
            tokens(k, &value, "f.toml")
        };
        assert_eq!(t(&OptionKey::flag("quiet"), "true").unwrap(), ["--quiet"]);
        assert!(t(&OptionKey::flag("quiet"), "false").unwrap().is_empty());
        let e = t(&OptionKey::flag("quiet"), "1").unwrap_err().to_string();
        assert!(e.contains("f.toml") && e.contains("true or false"), "{e}");
        assert_eq!(t(&OptionKey::value("side"), "8").unwrap(), ["--side=8"]);
        assert_eq!(
            t(&OptionKey::value("at"), "[0.5, 1, \"x\"]").unwrap(),
            ["--at=0.5,1,x"]
        );
        assert_eq!(
            t(&OptionKey::positional("case"), "\"sedov\"").unwrap(),
            ["sedov"]
        );
        let e = t(&OptionKey::value("side"), "{ a = 1 }")
            .unwrap_err()
            .to_string();
        assert!(e.contains("'side'") && e.contains("a list of these"), "{e}");
        let e = t(&OptionKey::value("side"), "[[1]]")
            .unwrap_err()
            .to_string();
        assert!(e.contains("'side'"), "{e}");
    }
}
