//! The value parsers of the command line, shared by the subcommands: each
//! refuses a bad value with what is allowed (clap adds the option and the
//! value), so that no subcommand ever sees one.

use crate::cases;
use crate::cases::scene::SceneGravity;
use crate::output::snapshot as snapfile;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use sph_core::Choice;
use sph_kernels::KernelChoice;

/// Most worker threads per rank.
const MAX_THREADS: i64 = 1 << 16;

/// Smallest and largest particles per side.
const SIDE_RANGE: (usize, usize) = (4, 1000);

/// A `--checkpoint-every` value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum CheckpointSpec {
    /// After every N-th step.
    Steps(u64),
    /// After the first step reaching each multiple of this simulated time.
    Time(f64),
    /// Every this many seconds of wall-clock time.
    Wall(f64),
    /// Young/Daly, with `--mtbf`.
    Auto,
}

impl std::fmt::Display for CheckpointSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CheckpointSpec::Steps(n) => write!(f, "{n}"),
            CheckpointSpec::Time(t) => write!(f, "time:{t}"),
            CheckpointSpec::Wall(s) => write!(f, "wall:{s}s"),
            CheckpointSpec::Auto => f.write_str("auto"),
        }
    }
}

/// A `--checkpoint-every` value: `N`, `time:T`, `wall:DURATION` or `auto`.
pub(crate) fn parse_checkpoint_every(s: &str) -> Result<CheckpointSpec, String> {
    let s = s.trim();
    let allowed = "allowed: N (steps, at least 1), time:T (positive simulated time), wall:DURATION (e.g. 90s, 10m, 2h), auto (with --mtbf)";
    if s == "auto" {
        return Ok(CheckpointSpec::Auto);
    }
    if let Some(t) = s.strip_prefix("time:") {
        return parse_positive(t)
            .map(CheckpointSpec::Time)
            .map_err(|_| format!("'{t}' is not a positive time; {allowed}"));
    }
    if let Some(d) = s.strip_prefix("wall:") {
        return parse_duration(d).map(CheckpointSpec::Wall);
    }
    parse_steps(s)
        .map(CheckpointSpec::Steps)
        .map_err(|_| allowed.to_owned())
}

/// A duration: a positive number with an optional unit s, m, h or d.
pub(crate) fn parse_duration(s: &str) -> Result<f64, String> {
    let s = s.trim();
    let (num, scale) = match s.char_indices().last() {
        Some((i, 's')) => (&s[..i], 1.0),
        Some((i, 'm')) => (&s[..i], 60.0),
        Some((i, 'h')) => (&s[..i], 3600.0),
        Some((i, 'd')) => (&s[..i], 86400.0),
        _ => (s, 1.0),
    };
    match num.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x * scale),
        _ => Err("a duration is a positive number with an optional unit s, m, h or d (e.g. 90s, 10m, 6h, 2d)".into()),
    }
}

/// A `--snapshot-fields` list.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FieldList(pub(crate) Vec<String>);

/// The long help of `--snapshot-fields`, its field list from the field
/// table.
pub(crate) fn snapshot_fields_help() -> String {
    format!(
        "Fields of the snapshots, comma-separated (default: {}). Snapshots are written when a \
         --snapshot-every-steps, --snapshot-every-time or --snapshot-at schedule is given, as \
         OUT/snapshots/snapshot_SSSSSSSS.h5 (HDF5, H5Part layout: h5py, ParaView and SPH-EXA's \
         scripts read them). Fields: {}; and, where the scheme has them: {}.",
        snapfile::DEFAULT_FIELDS.join(","),
        snapfile::base_fields().join(","),
        snapfile::optional_fields().join(",")
    )
}

/// A `--snapshot-fields` value: names of the field table.
pub(crate) fn parse_field_list(s: &str) -> Result<FieldList, String> {
    snapfile::parse_fields(s).map(FieldList)
}

/// A `--snapshot-at` list.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Times(pub(crate) Vec<f64>);

/// Times >= 0, separated by commas.
pub(crate) fn parse_times(s: &str) -> Result<Times, String> {
    s.split(',')
        .map(|t| {
            parse_number(t, |x| x >= 0.0, "").map_err(|_| {
                format!(
                    "'{}' is not a time >= 0; give times separated by commas",
                    t.trim()
                )
            })
        })
        .collect::<Result<Vec<f64>, String>>()
        .map(Times)
}

/// How many checkpoints to keep: a whole number >= 0.
pub(crate) fn parse_keep(s: &str) -> Result<usize, String> {
    match s.trim().parse::<i64>() {
        Ok(n) if n >= 0 => Ok(n as usize),
        _ => Err(
            "the number of checkpoints to keep must be a whole number >= 0 (0 keeps all)".into(),
        ),
    }
}

/// The values of a scheme option declared in `sph-core` ([`Choice`]: its
/// names, each with its one-line help for `--help`), so the command line
/// and `config.toml` take them from the one list beside the option's enum.
pub(crate) fn choice<T: Choice>() -> impl TypedValueParser<Value = T> {
    let values = T::ALL
        .iter()
        .map(|v| PossibleValue::new(v.name()).help(v.help()));
    // The names parser refuses anything not listed, so the lookup finds it.
    PossibleValuesParser::new(values).map(|name| T::from_name(&name).expect("a listed name"))
}

/// The registered cases as the allowed values of the case argument (with
/// their descriptions in `sphexa run --help`).
pub(crate) fn case_names() -> PossibleValuesParser {
    PossibleValuesParser::new(
        cases::registry()
            .iter()
            .map(|c| PossibleValue::new(c.name()).help(c.description())),
    )
}

/// An equation of state (`--eos`): the forms of [`sph_core::Eos`]'s
/// `FromStr` (`tait-ref` only on the case that has it: see
/// `check_eos`).
pub(crate) fn parse_eos(s: &str) -> Result<sph_core::Eos, String> {
    s.parse::<sph_core::Eos>().map_err(|e| e.to_string())
}

/// `--stir`: `off`, `on` (the defaults) or `KEY=VALUE,...` over the
/// defaults ([`sph_core::stirring::STIR_KEYS`]).
pub(crate) fn parse_stir(s: &str) -> Result<StirArg, String> {
    match s.trim() {
        "off" => Ok(StirArg(None)),
        "on" => Ok(StirArg(Some(sph_core::stirring::StirParams::default()))),
        spec => spec
            .parse()
            .map(|p| StirArg(Some(p)))
            .map_err(|e: sph_core::CoreError| e.to_string()),
    }
}

/// The value of `--stir`: the driving, or none (`off`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StirArg(pub(crate) Option<sph_core::stirring::StirParams>);

/// `LO:HI` with LO < HI, both finite.
pub(crate) fn parse_interval(s: &str) -> Result<(f64, f64), String> {
    let bad = || format!("'{s}': expected LO:HI with finite numbers LO < HI, e.g. -0.5:0.5");
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let (lo, hi): (f64, f64) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if lo.is_finite() && hi.is_finite() && lo < hi {
        Ok((lo, hi))
    } else {
        Err(bad())
    }
}

/// `--box`: `LO:HI` (the same on every axis) or `X0:X1,Y0:Y1,Z0:Z1`, as
/// `xmin, xmax, ymin, ymax, zmin, zmax`.
pub(crate) fn parse_box(s: &str) -> Result<BoxArg, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let axes = match parts.as_slice() {
        [one] => [parse_interval(one)?; 3],
        [x, y, z] => [parse_interval(x)?, parse_interval(y)?, parse_interval(z)?],
        _ => {
            return Err(format!(
                "'{s}': expected LO:HI (a cube) or X0:X1,Y0:Y1,Z0:Z1"
            ))
        }
    };
    Ok(BoxArg(
        axes.map(|(lo, hi)| [lo, hi])
            .concat()
            .try_into()
            .expect("6 numbers"),
    ))
}

/// The value of `--box`: `xmin, xmax, ymin, ymax, zmin, zmax`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BoxArg(pub(crate) [f64; 6]);

/// `X0:X1,Y0:Y1,Z0:Z1`, which [`parse_box`] reads back to the same bits.
impl std::fmt::Display for BoxArg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let b = self.0;
        write!(f, "{}:{},{}:{},{}:{}", b[0], b[1], b[2], b[3], b[4], b[5])
    }
}

/// `--boundary`: `periodic`, `open`, or one of them per axis
/// (`periodic,periodic,open`).
pub(crate) fn parse_boundary(s: &str) -> Result<BoundaryArg, String> {
    let kind = |w: &str| {
        match w.trim() {
        "periodic" => Ok(sph_tree::Boundary::Periodic),
        "open" => Ok(sph_tree::Boundary::Open),
        other => Err(format!(
            "'{other}' in '{s}': expected periodic or open (one for every axis, or one per axis: periodic,periodic,open)"
        )),
    }
    };
    let parts: Vec<&str> = s.split(',').collect();
    match parts.as_slice() {
        [one] => Ok(BoundaryArg([kind(one)?; 3])),
        [x, y, z] => Ok(BoundaryArg([kind(x)?, kind(y)?, kind(z)?])),
        _ => Err(format!(
            "'{s}': expected periodic, open, or three of them (x,y,z), e.g. periodic,periodic,open"
        )),
    }
}

/// The value of `--boundary`: the kind of each axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BoundaryArg(pub(crate) [sph_tree::Boundary; 3]);

/// `periodic,periodic,open`, which [`parse_boundary`] reads back.
impl std::fmt::Display for BoundaryArg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = |b: sph_tree::Boundary| match b {
            sph_tree::Boundary::Periodic => "periodic",
            sph_tree::Boundary::Open => "open",
        };
        let [x, y, z] = self.0.map(name);
        write!(f, "{x},{y},{z}")
    }
}

/// `--gravity`: `on`, `off`, or the gravitational constant G (a positive
/// number, which turns it on).
pub(crate) fn parse_gravity(s: &str) -> Result<SceneGravity, String> {
    match s.trim() {
        "on" => Ok(SceneGravity::On),
        "off" => Ok(SceneGravity::Off),
        g => match g.parse::<f64>() {
            Ok(v) if v.is_finite() && v > 0.0 => Ok(SceneGravity::Constant(v)),
            _ => Err(format!(
                "'{g}': expected on, off, or the gravitational constant G (a positive number)"
            )),
        },
    }
}

/// Particles per side, within [`SIDE_RANGE`].
pub(crate) fn parse_side(s: &str) -> Result<usize, String> {
    let (lo, hi) = SIDE_RANGE;
    match s.trim().parse::<i64>() {
        Ok(n) if (lo as i64..=hi as i64).contains(&n) => Ok(n as usize),
        _ => Err(format!(
            "particles per side must be a whole number from {lo} to {hi}"
        )),
    }
}

/// A step count (or repeat count): at least 1.
pub(crate) fn parse_steps(s: &str) -> Result<u64, String> {
    match s.trim().parse::<i64>() {
        Ok(n) if n >= 1 => Ok(n as u64),
        _ => Err("the number of steps must be a whole number, at least 1".into()),
    }
}

/// A thread (or rank) count: 1 to [`MAX_THREADS`].
pub(crate) fn parse_threads(s: &str) -> Result<usize, String> {
    match s.trim().parse::<i64>() {
        Ok(n) if (1..=MAX_THREADS).contains(&n) => Ok(n as usize),
        _ => Err(format!(
            "the thread count must be a whole number, at least 1 (at most {MAX_THREADS})"
        )),
    }
}

/// A neighbour count: at least 1 (the run checks the order of the two).
pub(crate) fn parse_count(s: &str) -> Result<usize, String> {
    match s.trim().parse::<i64>() {
        Ok(n) if n >= 1 => Ok(n as usize),
        _ => Err("a neighbour count must be a whole number, at least 1".into()),
    }
}

/// A finite number within `ok`, or `allowed` as the error.
fn parse_number(s: &str, ok: impl Fn(f64) -> bool, allowed: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && ok(x) => Ok(x),
        _ => Err(allowed.into()),
    }
}

/// A positive finite number.
/// A power of two from 1 to 64, as its exponent (`4` gives 2).
pub(crate) fn parse_limiter_factor(s: &str) -> Result<u8, String> {
    match s.parse::<u32>() {
        Ok(f) if f.is_power_of_two() && f <= 64 => Ok(f.trailing_zeros() as u8),
        _ => Err(format!(
            "'{s}': the limiter factor must be a power of two from 1 to 64 (1, 2, 4, ..., 64)"
        )),
    }
}

/// `on` or `off`.
pub(crate) fn parse_on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("'{s}': allowed values are on and off")),
    }
}

pub(crate) fn parse_positive(s: &str) -> Result<f64, String> {
    parse_number(s, |x| x > 0.0, "a positive finite number is required")
}

/// A finite number >= 0.
pub(crate) fn parse_non_negative(s: &str) -> Result<f64, String> {
    parse_number(s, |x| x >= 0.0, "a finite number >= 0 is required")
}

/// A Courant factor, in (0, 1].
pub(crate) fn parse_courant(s: &str) -> Result<f64, String> {
    parse_number(
        s,
        |x| x > 0.0 && x <= 1.0,
        "the Courant factor must be a number in (0, 1]",
    )
}

/// A kernel name (`sinc:6`, `m4`, ...).
pub(crate) fn parse_kernel(s: &str) -> Result<KernelChoice, String> {
    s.parse()
        .map_err(|e: sph_kernels::KernelError| e.to_string())
}
