//! The discretisation as one value: [`Scheme`] names the gradient
//! operator, the grad-h terms, the artificial viscosity (constant or
//! switched, with its parameters) and the artificial conductivity. It is
//! validated in one place ([`Scheme::validate`]), the per-particle fields a
//! run allocates follow from it ([`Scheme::fields`]), and named presets
//! ([`Scheme::preset`], [`PRESETS`]) give the schemes the cases use.
//!
//! ```
//! use sph_core::{Gradients, Scheme, Viscosity};
//!
//! // The seed paper's scheme, then the same with kernel gradients and
//! // viscosity switches up to alpha = 0.7.
//! let mut s = Scheme::preset("paper").unwrap();
//! assert_eq!(s, Scheme::PAPER);
//! s.gradients = Gradients::Kernel;
//! s.set_switches(true);
//! s.set_alpha(0.7);
//! assert!(matches!(s.viscosity, Viscosity::Switched(p) if p.alpha_max == 0.7));
//! assert_eq!(s, Scheme::preset("noh").unwrap());
//! assert!(!s.fields(false).iad);
//! // Bad values are refused with a message naming them.
//! s.set_alpha(-1.0);
//! assert!(s.validate().unwrap_err().to_string().contains("-1"));
//! assert!(Scheme::preset("nope").unwrap_err().to_string().contains("paper"));
//! ```

use crate::av_switch::AvSwitchParams;
use crate::pair_loop::Gradients;
use crate::{CoreError, FieldSet};
use serde::{Deserialize, Serialize};

/// The artificial viscosity of the momentum and energy equations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Viscosity {
    /// One strength `alpha` for every pair (the seed paper's eq. 5).
    Constant {
        /// Viscosity strength.
        alpha: f64,
    },
    /// A strength per particle, raised ahead of shocks and decaying
    /// elsewhere ([`av_switch`](crate::av_switch)); pairs use the mean.
    Switched(AvSwitchParams),
}

/// Everything that defines the discretisation of the hydrodynamics.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Scheme {
    /// Gradient operator (IAD or plain kernel gradients).
    pub gradients: Gradients,
    /// Whether the grad-h factor Omega enters the equations (its field is
    /// allocated only then).
    pub grad_h: bool,
    /// Artificial viscosity.
    pub viscosity: Viscosity,
    /// Artificial conductivity of internal energy `alpha_u` (Price 2008),
    /// or none (the paper's scheme).
    pub conductivity: Option<f64>,
}

impl Default for Scheme {
    fn default() -> Self {
        Self::PAPER
    }
}

/// The named schemes: (name, scheme, one line on what it is).
pub const PRESETS: [(&str, Scheme, &str); 3] = [
    (
        "paper",
        Scheme::PAPER,
        "the seed paper's eqs. 1-5 (SPH-EXA `std`): IAD gradients, grad-h, constant alpha = 1",
    ),
    (
        "noh",
        Scheme::NOH,
        "strong shocks in cold flows: kernel gradients, grad-h, viscosity switches up to alpha 0.7",
    ),
    (
        "evrard",
        Scheme::EVRARD,
        "self-gravitating collapse: kernel gradients, no grad-h, viscosity switches up to alpha 0.5",
    ),
];

impl Scheme {
    /// The SPH-EXA paper's scheme ("std"): IAD gradients, grad-h terms,
    /// constant `alpha = 1`, no conductivity.
    pub const PAPER: Scheme = Scheme {
        gradients: Gradients::Iad,
        grad_h: true,
        viscosity: Viscosity::Constant { alpha: 1.0 },
        conductivity: None,
    };

    /// The `noh` case's scheme: kernel gradients, grad-h, viscosity
    /// switches up to `alpha = 0.7`.
    pub const NOH: Scheme = Scheme {
        gradients: Gradients::Kernel,
        grad_h: true,
        viscosity: Viscosity::Switched(AvSwitchParams {
            alpha_max: 0.7,
            ..AvSwitchParams::DEFAULT
        }),
        conductivity: None,
    };

    /// The `evrard` case's scheme: kernel gradients, no grad-h, viscosity
    /// switches up to `alpha = 0.5`.
    pub const EVRARD: Scheme = Scheme {
        gradients: Gradients::Kernel,
        grad_h: false,
        viscosity: Viscosity::Switched(AvSwitchParams {
            alpha_max: 0.5,
            ..AvSwitchParams::DEFAULT
        }),
        conductivity: None,
    };

    /// The preset called `name` (see [`PRESETS`]).
    ///
    /// # Errors
    /// [`CoreError::Invalid`] naming the unknown name and the known ones.
    pub fn preset(name: &str) -> Result<Scheme, CoreError> {
        PRESETS
            .iter()
            .find(|p| p.0 == name)
            .map(|p| p.1)
            .ok_or_else(|| {
                let names: Vec<&str> = PRESETS.iter().map(|p| p.0).collect();
                CoreError::Invalid(format!(
                    "unknown scheme '{name}'; presets: {}",
                    names.join(", ")
                ))
            })
    }

    /// The viscosity strength: the constant, or the maximum of the switches.
    pub fn alpha(&self) -> f64 {
        match self.viscosity {
            Viscosity::Constant { alpha } => alpha,
            Viscosity::Switched(p) => p.alpha_max,
        }
    }

    /// Sets the constant strength, or the maximum of the switches.
    pub fn set_alpha(&mut self, alpha: f64) {
        match &mut self.viscosity {
            Viscosity::Constant { alpha: a } => *a = alpha,
            Viscosity::Switched(p) => p.alpha_max = alpha,
        }
    }

    /// Turns the viscosity switches on (default parameters, maximum = the
    /// current strength) or off (a constant strength = the current maximum).
    pub fn set_switches(&mut self, on: bool) {
        let alpha = self.alpha();
        self.viscosity = match (on, self.viscosity) {
            (true, v @ Viscosity::Switched(_)) | (false, v @ Viscosity::Constant { .. }) => v,
            (true, Viscosity::Constant { .. }) => Viscosity::Switched(AvSwitchParams {
                alpha_max: alpha,
                ..AvSwitchParams::DEFAULT
            }),
            (false, Viscosity::Switched(_)) => Viscosity::Constant { alpha },
        };
    }

    /// The switch parameters, when the viscosity is switched.
    pub fn switches(&self) -> Option<AvSwitchParams> {
        match self.viscosity {
            Viscosity::Switched(p) => Some(p),
            Viscosity::Constant { .. } => None,
        }
    }

    /// Checks every parameter.
    ///
    /// # Errors
    /// [`CoreError::Invalid`] naming the bad value and what is allowed.
    pub fn validate(&self) -> Result<(), CoreError> {
        match self.viscosity {
            Viscosity::Constant { alpha } if !(alpha >= 0.0 && alpha.is_finite()) => {
                return Err(CoreError::Invalid(format!(
                    "viscosity alpha {alpha} must be a finite number >= 0"
                )));
            }
            Viscosity::Switched(p) if !p.is_valid() => {
                return Err(CoreError::Invalid(format!(
                    "AV switch parameters {p:?} are invalid: need 0 <= alpha_min <= alpha_max (finite), decay > 0 and sound_weight >= 0"
                )));
            }
            _ => {}
        }
        if let Some(a) = self.conductivity {
            if !(a > 0.0 && a.is_finite()) {
                return Err(CoreError::Invalid(format!(
                    "conductivity {a} must be a finite number > 0 (or off)"
                )));
            }
        }
        Ok(())
    }

    /// The optional per-particle fields the scheme needs (`gravity`: the
    /// run has self-gravity).
    pub fn fields(&self, gravity: bool) -> FieldSet {
        FieldSet {
            iad: self.gradients == Gradients::Iad,
            grad_h: self.grad_h,
            gravity,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_valid_and_distinct() {
        for (i, (name, s, _)) in PRESETS.iter().enumerate() {
            s.validate().unwrap();
            assert_eq!(Scheme::preset(name).unwrap(), *s);
            for (other, t, _) in &PRESETS[i + 1..] {
                assert_ne!(s, t, "{name} and {other}");
            }
        }
    }

    #[test]
    fn switches_keep_the_strength() {
        let mut s = Scheme::PAPER;
        s.set_alpha(0.8);
        s.set_switches(true);
        assert_eq!(s.switches().unwrap().alpha_max, 0.8);
        s.set_switches(true);
        assert_eq!(s.alpha(), 0.8);
        s.set_switches(false);
        assert_eq!(s.viscosity, Viscosity::Constant { alpha: 0.8 });
    }

    #[test]
    fn bad_values_are_named() {
        let mut s = Scheme::PAPER;
        s.conductivity = Some(f64::NAN);
        assert!(s.validate().unwrap_err().to_string().contains("NaN"));
        s.conductivity = None;
        s.set_switches(true);
        s.set_alpha(-0.5);
        assert!(s.validate().is_err());
    }
}
