//! The scheme options a run can set (`--gradients`, `--alpha`, ...): one
//! table, [`SCHEME_OPTIONS`], from which the command line builds its flags,
//! `config.toml` takes its keys, a run's overrides reach the [`Scheme`]
//! and a scheme is written back as options. Adding a scheme option is one
//! entry here (and the field in `sph_core::Scheme`).
//!
//! ```
//! use sph_apps::cases::{scheme_option, Scheme, Setting};
//!
//! let alpha = scheme_option("alpha").unwrap();
//! let mut s = Scheme::PAPER;
//! (alpha.set)(&mut s, Setting::Number(0.5));
//! assert_eq!((alpha.get)(&s), Setting::Number(0.5));
//! assert_eq!(s.alpha(), 0.5);
//! ```

use sph_core::conduction::Contrast;
use sph_core::{AvForm, Choice, Gradients, Scheme, Volume};
use std::fmt;

/// A scheme option's value as the command line writes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Setting {
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
    /// The named value as the `sph-core` option `T` it names.
    pub fn choice<T: Choice>(self) -> Option<T> {
        match self {
            Setting::Name(name) => T::from_name(name),
            _ => None,
        }
    }

    /// The number, if this is one.
    pub fn number(self) -> Option<f64> {
        match self {
            Setting::Number(x) => Some(x),
            _ => None,
        }
    }

    /// The switch, if this is one.
    pub fn on(self) -> Option<bool> {
        match self {
            Setting::Switch(on) => Some(on),
            _ => None,
        }
    }
}

/// The values a scheme option takes.
#[derive(Debug, Clone, Copy)]
#[non_exhaustive]
pub enum Values {
    /// One of these names, each with its one-line help.
    Names(fn() -> Vec<(&'static str, &'static str)>),
    /// A number >= 0.
    NonNegative,
    /// `on` or `off`.
    Switch,
}

/// The names and help of an option declared in `sph-core` ([`Choice`]).
fn choices<T: Choice>() -> Vec<(&'static str, &'static str)> {
    T::ALL.iter().map(|v| (v.name(), v.help())).collect()
}

/// The two values of `--smoothing-length`.
fn smoothing_lengths() -> Vec<(&'static str, &'static str)> {
    vec![
        ("adaptive", "Follows the neighbour count every step"),
        ("fixed", "Stays as set up"),
    ]
}

/// One scheme option: its flag (the long option without dashes, also its
/// `config.toml` key), its `--help` text and values, how it reads and
/// writes a [`Scheme`], and whether `sphexa cases` lists it for a scheme.
pub struct SchemeOption {
    /// The long option without dashes.
    pub key: &'static str,
    /// The option's help.
    pub help: &'static str,
    /// What values it takes.
    pub values: Values,
    /// Its value in a scheme.
    pub get: fn(&Scheme) -> Setting,
    /// Sets it in a scheme (a value of its [`Values`]; others are ignored).
    pub set: fn(&mut Scheme, Setting),
    /// Whether a scheme listing shows it (the four basic options always,
    /// the others where they differ from the paper's scheme).
    pub listed: fn(&Scheme) -> bool,
}

impl fmt::Debug for SchemeOption {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SchemeOption")
            .field("key", &self.key)
            .finish_non_exhaustive()
    }
}

/// The option named `key` (its long option without dashes).
pub fn scheme_option(key: &str) -> Option<&'static SchemeOption> {
    SCHEME_OPTIONS.iter().find(|o| o.key == key)
}

/// Every scheme option, in the order a run applies them (`--alpha` before
/// `--av-switches`, which keeps the strength) and `sphexa cases` lists
/// them.
pub const SCHEME_OPTIONS: &[SchemeOption] = &[
    SchemeOption {
        key: "gradients",
        help: "Gradient operator (default: the case's, see `sphexa cases`)",
        values: Values::Names(choices::<Gradients>),
        get: |s| Setting::Name(s.gradients.name()),
        set: |s, v| s.gradients = v.choice().unwrap_or(s.gradients),
        listed: |_| true,
    },
    SchemeOption {
        key: "grad-h",
        help: "The grad-h correction Omega (default: the case's, see `sphexa cases`)",
        values: Values::Switch,
        get: |s| Setting::Switch(s.grad_h),
        set: |s, v| s.grad_h = v.on().unwrap_or(s.grad_h),
        listed: |_| true,
    },
    SchemeOption {
        key: "alpha",
        help: "Artificial viscosity strength alpha, the maximum with switches; a number >= 0 \
               (default: the case's, see `sphexa cases`)",
        values: Values::NonNegative,
        get: |s| Setting::Number(s.alpha()),
        set: |s, v| {
            if let Some(a) = v.number() {
                s.set_alpha(a);
            }
        },
        listed: |_| true,
    },
    SchemeOption {
        key: "av-switches",
        help: "Time-dependent viscosity switches: each particle's alpha rises to --alpha in \
               shocks and decays to 0.05 elsewhere (SPH-EXA's \"ve\" switches). Default: the \
               case's, see `sphexa cases`",
        values: Values::Switch,
        get: |s| Setting::Switch(s.switches().is_some()),
        set: |s, v| {
            if let Some(on) = v.on() {
                s.set_switches(on);
            }
        },
        listed: |_| true,
    },
    SchemeOption {
        key: "weak-shock-alpha",
        help: "The viscosity switches' ceiling at weak shocks: a particle's alpha may rise to \
               --alpha + (W - --alpha) / (1 + (M / 0.5)^2), with M its fastest approaching \
               pair's speed over their mean sound speed, so weak shocks (Sod's) get \
               alpha near W and do not ring, strong ones into cold gas (Noh's, Sedov's) keep \
               --alpha; a number >= 0 (0 = off), no effect without switches. Default: the \
               scheme's (2 in `gas`, off in the other presets)",
        values: Values::NonNegative,
        get: |s| Setting::Number(s.weak_shock_alpha.unwrap_or(0.0)),
        set: |s, v| {
            if let Some(a) = v.number() {
                s.weak_shock_alpha = (a > 0.0).then_some(a);
            }
        },
        listed: |s| s.weak_shock_alpha.is_some(),
    },
    SchemeOption {
        key: "balsara",
        help: "The Balsara (1995) shear limiter: with f = |div v| / (|div v| + |curl v| + \
               1e-4 c/h) per particle, near 1 in compression and near 0 in shear, a constant \
               alpha acts on a pair as alpha (f_i + f_j)/2 and switched strengths as alpha_i \
               f_i, so shear flows keep their vorticity (default: off in every preset)",
        values: Values::Switch,
        get: |s| Setting::Switch(s.balsara),
        set: |s, v| s.balsara = v.on().unwrap_or(s.balsara),
        listed: |s| s.balsara,
    },
    SchemeOption {
        key: "conductivity",
        help: "Artificial conductivity of internal energy alpha_u, a number >= 0 (0 = off; ~1 \
               smooths wall heating at shocks and walls). Default: the scheme's (1 in `ve-ac`, \
               3 in `evrard`, 2 in `gas`, off in the other presets)",
        values: Values::NonNegative,
        get: |s| Setting::Number(s.conductivity.unwrap_or(0.0)),
        set: |s, v| {
            if let Some(c) = v.number() {
                s.conductivity = (c > 0.0).then_some(c);
            }
        },
        listed: |s| s.conductivity.is_some(),
    },
    SchemeOption {
        key: "conduction-contrast",
        help: "Weight each pair's conduction by a contrast in [0, 1]: heat crosses fronts (a \
               blast's hot gas against the cold) at full strength while neighbours that differ \
               little exchange less; no effect without --conductivity. Default: the scheme's \
               (`larger` in `gas`, `off` in the other presets)",
        values: Values::Names(choices::<Contrast>),
        get: |s| Setting::Name(s.conduction_contrast.name()),
        set: |s, v| s.conduction_contrast = v.choice().unwrap_or(s.conduction_contrast),
        listed: |s| s.conduction_contrast != Contrast::Off,
    },
    SchemeOption {
        key: "artificial-stress",
        help: "Artificial stress epsilon against the tensile instability (Monaghan 2000): a \
               repulsion between particles under negative pressure that close in below the \
               lattice spacing; a number >= 0 (0 = off; 0.2 is Monaghan's value). Default: the \
               case's (square-patch: 0.2; off elsewhere)",
        values: Values::NonNegative,
        get: |s| Setting::Number(s.artificial_stress.unwrap_or(0.0)),
        set: |s, v| {
            if let Some(e) = v.number() {
                s.artificial_stress = (e > 0.0).then_some(e);
            }
        },
        listed: |s| s.artificial_stress.is_some(),
    },
    SchemeOption {
        key: "smoothing-length",
        help: "Smoothing lengths: `adaptive` follows the neighbour count every step; `fixed` \
               keeps each particle's h as set up (weakly compressible flows with a free \
               surface). Default: the case's (square-patch: fixed; adaptive elsewhere)",
        values: Values::Names(smoothing_lengths),
        get: |s| Setting::Name(if s.fixed_h { "fixed" } else { "adaptive" }),
        set: |s, v| {
            if let Setting::Name(name) = v {
                s.fixed_h = name == "fixed";
            }
        },
        listed: |s| s.fixed_h,
    },
    SchemeOption {
        key: "volume",
        help: "Particle volumes (default: the case's, see `sphexa cases`)",
        values: Values::Names(choices::<Volume>),
        get: |s| Setting::Name(s.volume.name()),
        set: |s, v| s.volume = v.choice().unwrap_or(s.volume),
        listed: |s| s.volume != Volume::Mass,
    },
    SchemeOption {
        key: "av-cleaning",
        help: "AV cleaning after SPH-EXA's: the viscosity of an approaching pair acts on the \
               velocity jump left after a limited linear reconstruction from both sides, so \
               shear layers and smooth flows keep their kinetic energy while shocks keep their \
               full viscosity. Default: the case's (kelvin-helmholtz: see `sphexa cases`)",
        values: Values::Switch,
        get: |s| Setting::Switch(s.av_cleaning),
        set: |s, v| s.av_cleaning = v.on().unwrap_or(s.av_cleaning),
        listed: |s| s.av_cleaning,
    },
    SchemeOption {
        key: "av-form",
        help: "Form of the artificial viscosity and of the Courant signal velocity that goes \
               with it (default: the scheme's: `sph-exa` in `ve` and `ve-ac`, `paper` in the \
               other presets)",
        values: Values::Names(choices::<AvForm>),
        get: |s| Setting::Name(s.av_form.name()),
        set: |s, v| s.av_form = v.choice().unwrap_or(s.av_form),
        listed: |s| s.av_form != AvForm::Paper,
    },
];

/// The number of scheme options.
pub const SCHEME_OPTION_COUNT: usize = SCHEME_OPTIONS.len();

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use sph_core::PRESETS;

    #[test]
    fn keys_are_unique_and_named_values_known() {
        for (i, o) in SCHEME_OPTIONS.iter().enumerate() {
            assert!(
                SCHEME_OPTIONS[..i].iter().all(|p| p.key != o.key),
                "{}",
                o.key
            );
            assert_eq!(scheme_option(o.key).map(|p| p.key), Some(o.key));
        }
        assert!(scheme_option("no-such-option").is_none());
    }

    /// A scheme's value of every option, set into any other scheme, reads
    /// back as that value: `get` and `set` agree, and no option's `set`
    /// touches another option's value.
    #[test]
    fn every_option_reads_back_what_was_set() {
        for (_, from, _) in PRESETS {
            for (_, mut into, _) in PRESETS {
                for o in SCHEME_OPTIONS {
                    let others: Vec<Setting> = SCHEME_OPTIONS
                        .iter()
                        .filter(|p| p.key != o.key && p.key != "alpha")
                        .map(|p| (p.get)(&into))
                        .collect();
                    (o.set)(&mut into, (o.get)(&from));
                    assert_eq!((o.get)(&into), (o.get)(&from), "{}", o.key);
                    let after: Vec<Setting> = SCHEME_OPTIONS
                        .iter()
                        .filter(|p| p.key != o.key && p.key != "alpha")
                        .map(|p| (p.get)(&into))
                        .collect();
                    // Switches on/off keep alpha; alpha leaves the switches.
                    assert_eq!(others, after, "{} changed another option", o.key);
                }
            }
        }
    }

    /// Every named value of every option sets and reads back.
    #[test]
    fn every_named_value_round_trips() {
        for o in SCHEME_OPTIONS {
            if let Values::Names(names) = o.values {
                for (name, help) in names() {
                    assert!(!help.is_empty(), "{}: {name} has no help", o.key);
                    let mut s = Scheme::PAPER;
                    (o.set)(&mut s, Setting::Name(name));
                    assert_eq!((o.get)(&s), Setting::Name(name), "{}", o.key);
                }
            }
        }
    }

    proptest! {
        /// Numbers set read back exactly (0 reads back as 0: off).
        #[test]
        fn numbers_round_trip(x in 0.0f64..100.0) {
            for o in SCHEME_OPTIONS.iter().filter(|o| matches!(o.values, Values::NonNegative)) {
                let mut s = Scheme::PAPER;
                (o.set)(&mut s, Setting::Number(x));
                prop_assert_eq!((o.get)(&s), Setting::Number(x));
            }
        }
    }
}
