//! What a case runs with, and how a run overrides it: the one place where
//! a case's scheme ([`Scheme`], from sph-core) and physics ([`Physics`])
//! are written into a [`HydroConfig`].

use super::scheme_options::{Setting, SCHEME_OPTIONS, SCHEME_OPTION_COUNT};
use crate::AppError;
use sph_core::stirring::StirParams;
pub use sph_core::timestep::FirstStep;
pub use sph_core::Scheme;
use sph_core::{Eos, HydroConfig};
use sph_gravity::GravityParams;

/// The physics of a case besides its scheme: the equation of state,
/// self-gravity and, where its flow allows a longer step than the default,
/// the Courant factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Physics {
    /// Equation of state.
    pub eos: Eos,
    /// Self-gravity with pairs softened within
    /// `softening * (h_i + h_j)`, or none.
    pub softening: Option<f64>,
    /// The case's Courant factor, or `None` to keep the run's
    /// (`TimestepParams::k_courant`, default 0.2).
    pub courant: Option<f64>,
    /// Turbulence driving ([`sph_core::stirring`]; periodic cubes), or
    /// none.
    pub stirring: Option<StirParams>,
}

impl Physics {
    /// An ideal gas with gamma = 5/3, no self-gravity, the run's Courant
    /// factor.
    pub const IDEAL_GAS: Physics = Physics {
        eos: Eos::IdealGas { gamma: 5.0 / 3.0 },
        softening: None,
        courant: None,
        stirring: None,
    };
}

/// What a run changes in a case's scheme: a preset (`--scheme`), the
/// scheme options of [`SCHEME_OPTIONS`] (`--gradients`, `--alpha`, ...),
/// and the run's `--softening`, `--courant`, `--first-step` and `--eos`; `None`
/// keeps the case's choice. The default overrides nothing.
///
/// ```
/// use sph_apps::cases::{Scheme, SchemeOverrides, Setting};
///
/// let o = SchemeOverrides::default().with("alpha", Setting::Number(0.5)).unwrap();
/// assert_eq!(o.over(Scheme::PAPER).alpha(), 0.5);
/// assert!(SchemeOverrides::default().with("alfa", Setting::Number(0.5)).is_err());
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SchemeOverrides {
    /// A whole scheme in place of the case's (a preset), before the
    /// single options.
    pub preset: Option<Scheme>,
    /// The value of each option of [`SCHEME_OPTIONS`] (same order), if set.
    pub options: [Option<Setting>; SCHEME_OPTION_COUNT],
    /// Self-gravity softening scale (cases with self-gravity).
    pub softening: Option<f64>,
    /// Courant factor (over the case's, see [`Physics::courant`]).
    pub courant: Option<f64>,
    /// The first step (over the run's, `TimestepParams::first_step`,
    /// default [`FirstStep::Ramp`]).
    pub first_step: Option<FirstStep>,
    /// The equation of state (over the case's, [`Physics::eos`]).
    pub eos: Option<Eos>,
    /// The driving (over the case's, [`Physics::stirring`]): `Some(None)`
    /// switches it off.
    pub stirring: Option<Option<StirParams>>,
}

impl SchemeOverrides {
    /// These overrides with the scheme option `key` (its long option
    /// without dashes) set to `value`.
    ///
    /// # Errors
    /// [`AppError::Usage`] naming `key` and the scheme options, when no
    /// scheme option has that name.
    pub fn with(mut self, key: &str, value: Setting) -> Result<Self, AppError> {
        let i = SCHEME_OPTIONS
            .iter()
            .position(|o| o.key == key)
            .ok_or_else(|| {
                let keys: Vec<&str> = SCHEME_OPTIONS.iter().map(|o| o.key).collect();
                AppError::Usage(format!(
                    "{key}: no such scheme option; scheme options: {}",
                    keys.join(", ")
                ))
            })?;
        self.options[i] = Some(value);
        Ok(self)
    }

    /// The value set for the scheme option `key`, if any.
    pub fn get(&self, key: &str) -> Option<Setting> {
        SCHEME_OPTIONS
            .iter()
            .zip(&self.options)
            .find(|(o, _)| o.key == key)
            .and_then(|(_, v)| *v)
    }

    /// `base` (or the preset) with these overrides, applied in the order of
    /// [`SCHEME_OPTIONS`].
    pub fn over(&self, base: Scheme) -> Scheme {
        let mut s = self.preset.unwrap_or(base);
        for (o, v) in SCHEME_OPTIONS.iter().zip(&self.options) {
            if let Some(v) = *v {
                (o.set)(&mut s, v);
            }
        }
        s
    }

    /// Writes the case's scheme with these overrides, and its physics,
    /// into `config`. Self-gravity keeps the parameters `config` already
    /// has (e.g. the opening angle) with the case's (or the overridden)
    /// softening, or the defaults; without it `config.gravity` is `None`
    /// whatever the caller passed.
    pub fn apply(&self, scheme: Scheme, physics: Physics, config: &mut HydroConfig) {
        config.scheme = self.over(scheme);
        config.eos = self.eos.unwrap_or(physics.eos);
        config.stirring = self.stirring.unwrap_or(physics.stirring);
        config.gravity = physics.softening.map(|s| GravityParams {
            softening: self.softening.unwrap_or(s),
            ..config.gravity.unwrap_or_default()
        });
        if let Some(k) = self.courant.or(physics.courant) {
            config.timestep.k_courant = k;
        }
        if let Some(f) = self.first_step {
            config.timestep.first_step = f;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sph_core::Viscosity;

    #[test]
    fn the_paper_scheme_is_the_default_config() {
        let mut config = HydroConfig::default();
        SchemeOverrides::default().apply(Scheme::PAPER, Physics::IDEAL_GAS, &mut config);
        assert_eq!(config, HydroConfig::default());
    }

    #[test]
    fn gravity_keeps_the_callers_parameters_with_the_cases_softening() {
        let mut config = HydroConfig::default();
        config.gravity = Some(GravityParams {
            theta: 0.7,
            ..Default::default()
        });
        let gravity = Physics {
            softening: Some(0.25),
            ..Physics::IDEAL_GAS
        };
        let none = SchemeOverrides::default();
        none.apply(Scheme::PAPER, gravity, &mut config);
        let g = config.gravity.expect("gravity on");
        assert_eq!((g.theta, g.softening), (0.7, 0.25));
        // Without self-gravity the caller's parameters are dropped.
        none.apply(Scheme::PAPER, Physics::IDEAL_GAS, &mut config);
        assert!(config.gravity.is_none());
        // And switched on from nothing, with the defaults.
        none.apply(Scheme::PAPER, gravity, &mut config);
        assert_eq!(config.gravity.expect("gravity on").theta, 0.5);
    }

    #[test]
    fn the_cases_courant_factor_applies_unless_overridden() {
        let mut config = HydroConfig::default();
        let fast = Physics {
            courant: Some(0.4),
            ..Physics::IDEAL_GAS
        };
        SchemeOverrides::default().apply(Scheme::PAPER, fast, &mut config);
        assert_eq!(config.timestep.k_courant, 0.4);
        let o = SchemeOverrides {
            courant: Some(0.25),
            ..Default::default()
        };
        o.apply(Scheme::PAPER, fast, &mut config);
        assert_eq!(config.timestep.k_courant, 0.25);
        // A case without its own keeps the run's.
        SchemeOverrides::default().apply(Scheme::PAPER, Physics::IDEAL_GAS, &mut config);
        assert_eq!(config.timestep.k_courant, 0.25);
    }

    #[test]
    fn the_first_step_override_applies_and_none_keeps_the_runs() {
        let mut config = HydroConfig::default();
        let o = SchemeOverrides {
            first_step: Some(FirstStep::Criteria),
            ..Default::default()
        };
        o.apply(Scheme::PAPER, Physics::IDEAL_GAS, &mut config);
        assert_eq!(config.timestep.first_step, FirstStep::Criteria);
        SchemeOverrides::default().apply(Scheme::PAPER, Physics::IDEAL_GAS, &mut config);
        assert_eq!(config.timestep.first_step, FirstStep::Criteria);
        let o = SchemeOverrides {
            first_step: Some(FirstStep::Ramp),
            ..Default::default()
        };
        o.apply(Scheme::PAPER, Physics::IDEAL_GAS, &mut config);
        assert_eq!(config.timestep.first_step, FirstStep::Ramp);
    }

    #[test]
    fn overrides_change_only_what_they_name() {
        let none = SchemeOverrides::default();
        assert_eq!(none.over(Scheme::PAPER), Scheme::PAPER);
        let o = SchemeOverrides::default()
            .with("alpha", Setting::Number(0.3))
            .and_then(|o| o.with("av-switches", Setting::Switch(true)))
            .and_then(|o| o.with("conductivity", Setting::Number(0.0)))
            .expect("scheme options");
        let s = o.over(Scheme::PAPER);
        assert!(matches!(s.viscosity, Viscosity::Switched(p) if p.alpha_max == 0.3));
        assert_eq!(s.gradients, Scheme::PAPER.gradients);
        assert_eq!(s.conductivity, None);
        // A preset replaces the case's scheme, then the overrides apply.
        let p = SchemeOverrides {
            preset: Some(Scheme::NOH),
            ..Default::default()
        }
        .with("av-switches", Setting::Switch(false))
        .expect("a scheme option");
        assert_eq!(
            p.over(Scheme::PAPER).viscosity,
            Viscosity::Constant { alpha: 0.7 }
        );
    }
}
