//! The numerical choices of a case, and how a run overrides them: the one
//! place where a case's scheme is written into a [`HydroConfig`].

use sph_core::{AvSwitchParams, Eos, Gradients, HydroConfig};
use sph_gravity::GravityParams;

/// The physics and numerics a case runs with: its default comes from
/// [`Case::default_scheme`](super::Case::default_scheme), and
/// [`SchemeOverrides`] change the parts a user may change.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scheme {
    /// Gradient operator.
    pub gradients: Gradients,
    /// Whether the grad-h factor Omega enters.
    pub grad_h: bool,
    /// Viscosity strength (the maximum when switches are on).
    pub alpha: f64,
    /// Time-dependent viscosity switches.
    pub av_switches: bool,
    /// Self-gravity softening scale (pairs softened within
    /// `softening * (h_i + h_j)`); used only with `gravity`.
    pub softening: f64,
    /// Whether the case has self-gravity.
    pub gravity: bool,
    /// Equation of state.
    pub eos: Eos,
}

impl Scheme {
    /// The SPH-EXA paper's scheme ("std"): IAD gradients, grad-h terms,
    /// constant alpha = 1; an ideal gas with gamma = 5/3, no self-gravity.
    pub const PAPER: Scheme = Scheme {
        gradients: Gradients::Iad,
        grad_h: true,
        alpha: 1.0,
        av_switches: false,
        softening: 1.0,
        gravity: false,
        eos: Eos::IdealGas { gamma: 5.0 / 3.0 },
    };

    /// Writes these choices into `config`. Self-gravity keeps the
    /// parameters `config` already has (e.g. the opening angle) with this
    /// softening, or the defaults; without it `config.gravity` is `None`
    /// whatever the caller passed.
    pub fn apply(&self, config: &mut HydroConfig) {
        config.eos = self.eos;
        config.gradients = self.gradients;
        config.grad_h = self.grad_h;
        config.alpha = self.alpha;
        config.av_switch = self.av_switches.then(|| AvSwitchParams {
            alpha_max: self.alpha,
            ..Default::default()
        });
        config.gravity = self.gravity.then(|| GravityParams {
            softening: self.softening,
            ..config.gravity.unwrap_or_default()
        });
    }
}

/// The parts of a case's scheme a run may change (the command line's
/// `--gradients`, `--grad-h`, `--alpha`, `--av-switches`, `--softening`);
/// `None` keeps the case's choice. The default overrides nothing.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SchemeOverrides {
    /// Gradient operator.
    pub gradients: Option<Gradients>,
    /// Whether the grad-h factor Omega enters.
    pub grad_h: Option<bool>,
    /// Viscosity strength (the maximum when switches are on).
    pub alpha: Option<f64>,
    /// Time-dependent viscosity switches.
    pub av_switches: Option<bool>,
    /// Self-gravity softening scale (cases with self-gravity).
    pub softening: Option<f64>,
}

impl SchemeOverrides {
    /// `base` with these overrides.
    pub fn over(&self, base: Scheme) -> Scheme {
        Scheme {
            gradients: self.gradients.unwrap_or(base.gradients),
            grad_h: self.grad_h.unwrap_or(base.grad_h),
            alpha: self.alpha.unwrap_or(base.alpha),
            av_switches: self.av_switches.unwrap_or(base.av_switches),
            softening: self.softening.unwrap_or(base.softening),
            ..base
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paper_scheme_is_the_default_config() {
        let mut config = HydroConfig::default();
        Scheme::PAPER.apply(&mut config);
        assert_eq!(config, HydroConfig::default());
    }

    #[test]
    fn gravity_keeps_the_callers_parameters_with_the_schemes_softening() {
        let mut config = HydroConfig {
            gravity: Some(GravityParams {
                theta: 0.7,
                ..Default::default()
            }),
            ..Default::default()
        };
        let scheme = Scheme {
            gravity: true,
            softening: 0.25,
            ..Scheme::PAPER
        };
        scheme.apply(&mut config);
        let g = config.gravity.expect("gravity on");
        assert_eq!((g.theta, g.softening), (0.7, 0.25));
        // Without self-gravity the caller's parameters are dropped.
        Scheme::PAPER.apply(&mut config);
        assert!(config.gravity.is_none());
        // And switched on from nothing, with the defaults.
        scheme.apply(&mut config);
        assert_eq!(config.gravity.expect("gravity on").theta, 0.5);
    }

    #[test]
    fn overrides_change_only_what_they_name() {
        let none = SchemeOverrides::default();
        assert_eq!(none.over(Scheme::PAPER), Scheme::PAPER);
        let o = SchemeOverrides {
            alpha: Some(0.3),
            av_switches: Some(true),
            ..Default::default()
        };
        let s = o.over(Scheme::PAPER);
        assert_eq!((s.alpha, s.av_switches), (0.3, true));
        assert_eq!(s.gradients, Scheme::PAPER.gradients);
        let mut config = HydroConfig::default();
        s.apply(&mut config);
        assert_eq!(config.av_switch.expect("switches on").alpha_max, 0.3);
    }
}
