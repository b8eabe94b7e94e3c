//! The values of a scheme option as the command line and `config.toml`
//! name them, declared beside each option's enum so that a front end
//! derives its flags' values and help from them instead of listing them
//! again.
//!
//! ```
//! use sph_core::{AvForm, Choice, Volume};
//! assert_eq!(AvForm::from_name("sph-exa"), Some(AvForm::SphExa));
//! assert_eq!(Volume::from_name("ve"), Some(Volume::Generalised));
//! assert_eq!(Volume::names(), ["mass", "ve", "pressure-energy"]);
//! assert!(AvForm::Paper.help().starts_with("The seed paper's"));
//! ```

/// An option whose values are a closed list of names.
pub trait Choice: Copy + Send + Sync + 'static {
    /// Every value, in the order the command line lists them.
    const ALL: &'static [Self];

    /// The value's name on the command line and in `config.toml`.
    fn name(&self) -> &'static str;

    /// One line on what the value does, for `--help` (no final period).
    fn help(&self) -> &'static str;

    /// The value called `name`, if any.
    fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|v| v.name() == name)
    }

    /// Every name, in the order of [`ALL`](Self::ALL).
    fn names() -> Vec<&'static str> {
        Self::ALL.iter().map(Self::name).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timestep::FirstStep;
    use crate::{AvForm, Gradients, Volume};

    fn round_trips<T: Choice + PartialEq + std::fmt::Debug>() {
        let names = T::names();
        for (i, v) in T::ALL.iter().enumerate() {
            assert_eq!(T::from_name(v.name()), Some(*v));
            assert!(
                !v.help().is_empty() && !v.help().ends_with('.'),
                "{}",
                v.name()
            );
            assert!(!names[..i].contains(&v.name()), "{} twice", v.name());
        }
        assert_eq!(T::from_name("no-such-value"), None);
    }

    #[test]
    fn names_are_unique_and_round_trip() {
        round_trips::<Gradients>();
        round_trips::<Volume>();
        round_trips::<AvForm>();
        round_trips::<FirstStep>();
        round_trips::<crate::conduction::Contrast>();
    }
}
