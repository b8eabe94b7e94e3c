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
pub use crate::conduction::Contrast;
pub use crate::momentum::{AvForm, Volume};
use crate::pair_loop::Gradients;
use crate::{CoreError, FieldSet};
use serde::{Deserialize, Serialize};

/// The artificial viscosity of the momentum and energy equations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
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
///
/// It will grow with new options: build one from a preset ([`Scheme::preset`],
/// [`PRESETS`], the constants such as [`Scheme::PAPER`]) and set fields.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Scheme {
    /// Gradient operator (IAD or plain kernel gradients).
    pub gradients: Gradients,
    /// Whether the grad-h factor Omega enters the equations (its field is
    /// allocated only then).
    pub grad_h: bool,
    /// Particle volumes: mass over density, or generalised volume elements.
    #[serde(default)]
    pub volume: Volume,
    /// Artificial viscosity.
    pub viscosity: Viscosity,
    /// Form of the viscosity term and of the time-step signal velocity.
    #[serde(default)]
    pub av_form: AvForm,
    /// Balsara (1995) shear limiter: pair strengths scaled by
    /// `(f_i + f_j)/2` (constant alpha) or per-particle strengths
    /// `alpha_i f_i` (switches), with
    /// `f_i = |div v_i| / (|div v_i| + |curl v_i| + 1e-4 c_i / h_i)`
    /// ([`av_switch::balsara`](crate::av_switch::balsara)).
    #[serde(default)]
    pub balsara: bool,
    /// Artificial conductivity of internal energy `alpha_u` (Price 2008),
    /// or none (the paper's scheme).
    pub conductivity: Option<f64>,
    /// Monaghan's (2000) artificial stress against the tensile instability
    /// of particles under negative pressure, its strength `epsilon`
    /// ([`ArtificialStress`](crate::momentum::ArtificialStress)), or none.
    #[serde(default)]
    pub artificial_stress: Option<f64>,
    /// Smoothing lengths stay as set up instead of following the
    /// neighbour count each step (the weakly compressible free-surface
    /// choice: a particle's density then changes only as its neighbours
    /// move), and the neighbour search does not iterate them either: a
    /// particle left with few neighbours (a thin jet) keeps its h rather
    /// than grow it for good (measured on the square patch at 50^3: grown
    /// h, ~150 neighbours back in the bulk, and pairs at 0.07 of the
    /// spacing).
    #[serde(default)]
    pub fixed_h: bool,
    /// AV cleaning after SPH-EXA's: the viscosity of an approaching pair
    /// sees the velocity jump left after a limited linear reconstruction
    /// from both sides
    /// ([`AvCleaning`](crate::momentum::AvCleaning)), so shear and smooth
    /// compression are not damped; needs the symmetric velocity gradient
    /// (six fields, exchanged to the halos).
    #[serde(default)]
    pub av_cleaning: bool,
    /// The viscosity switches' ceiling at weak shocks
    /// ([`AvSwitchParams::weak_alpha`]: `alpha_max` at strong shocks, up
    /// to this at weak ones, by the pair Mach number), or none. Without
    /// switches it has no effect.
    #[serde(default)]
    pub weak_shock_alpha: Option<f64>,
    /// What weights the conduction's pair terms ([`Contrast`]: off, or
    /// the pair's contrast of internal energy or of pressure). Without
    /// conductivity it has no effect.
    #[serde(default, deserialize_with = "contrast_or_flag")]
    pub conduction_contrast: Contrast,
}

/// [`Scheme::conduction_contrast`] as written before it had a choice of
/// contrasts: `true` was the contrast of internal energy.
fn contrast_or_flag<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Contrast, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Written {
        Flag(bool),
        Named(Contrast),
    }
    Ok(match Written::deserialize(d)? {
        Written::Flag(true) => Contrast::Energy,
        Written::Flag(false) => Contrast::Off,
        Written::Named(c) => c,
    })
}

impl Default for Scheme {
    fn default() -> Self {
        Self::PAPER
    }
}

/// The named schemes: (name, scheme, one line on what it is).
pub const PRESETS: [(&str, Scheme, &str); 10] = [
    (
        "gas",
        Scheme::GAS,
        "issue 42's one scheme for the ideal-gas cases (`sphexa cases` lists those it is the default of; scenes of your own run it too): `best` with AV cleaning, switches that rise to alpha 2 at weak shocks (0.3 at strong ones) and conductivity 2 weighted by the larger of each pair's contrasts of u and of pressure",
    ),
    (
        "paper",
        Scheme::PAPER,
        "the seed paper's eqs. 1-5: IAD gradients, grad-h, constant alpha = 1",
    ),
    (
        "std",
        Scheme::STD,
        "SPH-EXA's `std` propagator: IAD gradients, no grad-h (Omega = 1), constant alpha = 1",
    ),
    (
        "ve",
        Scheme::VE,
        "SPH-EXA's default `ve` propagator: generalised volume elements, grad-h, IAD, its viscosity switches in [0.05, 1] and its signal velocities",
    ),
    (
        "ve-ac",
        Scheme::VE_AC,
        "`ve` without grad-h, with artificial conductivity alpha_u = 1: lower Sedov L1 rho, P and |v| than SPH-EXA's `ve` at 30^3, 40^3 and 50^3",
    ),
    (
        "best",
        Scheme::BEST,
        "`ve-ac` with the paper's viscosity and switches up to alpha 0.5: the lowest Sedov L1 rho and |v| per second of the presets (L1 P within 4% of `ve-ac`'s), nearer the references than `ve` and `ve-ac` on Noh and Evrard",
    ),
    (
        "shear",
        Scheme::SHEAR,
        "shear layers: the paper's IAD and grad-h, viscosity switches in [0.05, 1], AV cleaning after SPH-EXA's (the Kelvin-Helmholtz case's until 2026-12-07)",
    ),
    (
        "contact",
        Scheme::CONTACT,
        "contacts in pressure equilibrium: pressure-energy volumes (X = m u), kernel gradients, grad-h, constant alpha = 1 (the isobaric cube's)",
    ),
    (
        "noh",
        Scheme::NOH,
        "strong shocks in cold flows: kernel gradients, grad-h, viscosity switches up to alpha 0.7",
    ),
    (
        "evrard",
        Scheme::EVRARD,
        "self-gravitating collapse: kernel gradients, no grad-h, viscosity switches up to alpha 0.5, conductivity alpha_u = 3",
    ),
];

impl Scheme {
    /// The SPH-EXA paper's scheme ("std"): IAD gradients, grad-h terms,
    /// constant `alpha = 1`, no conductivity.
    pub const PAPER: Scheme = Scheme {
        gradients: Gradients::Iad,
        grad_h: true,
        volume: Volume::Mass,
        viscosity: Viscosity::Constant { alpha: 1.0 },
        av_form: AvForm::Paper,
        balsara: false,
        conductivity: None,
        artificial_stress: None,
        fixed_h: false,
        av_cleaning: false,
        weak_shock_alpha: None,
        conduction_contrast: Contrast::Off,
    };

    /// What SPH-EXA's `std` propagator runs: the paper's scheme without
    /// the grad-h terms (`Omega = 1`).
    pub const STD: Scheme = Scheme {
        grad_h: false,
        ..Scheme::PAPER
    };

    /// SPH-EXA's default `ve` propagator: generalised volume elements
    /// ([`Volume::Generalised`]), grad-h, IAD, its time-dependent
    /// viscosity switches (alpha in [0.05, 1],
    /// [`SwitchForm::SphExa`](crate::av_switch::SwitchForm::SphExa)) and its viscosity and
    /// time-step forms ([`AvForm::SphExa`]).
    ///
    /// Where it departs from SPH-EXA's code, for conservation or
    /// exactness: pair sums run over symmetric lists (`r < 2 max(h_i, h_j)`;
    /// SPH-EXA sums `r < 2 h_i` only, so its pair forces are not always
    /// antisymmetric); the viscous heating sum is not clamped at zero
    /// (SPH-EXA clamps it, which can add energy); the velocity divergence
    /// of the switches uses `X_j / k_j` (SPH-EXA: `X_j / k_i`), exact for
    /// linear fields. On Sedov t = 0.05 its L1 errors of rho, P and |v| are
    /// at most 1.3% above and up to 2.9% below SPH-EXA's `ve` at 30^3,
    /// 40^3 and 50^3 (`docs/schemes.md`).
    pub const VE: Scheme = Scheme {
        gradients: Gradients::Iad,
        grad_h: true,
        volume: Volume::Generalised,
        viscosity: Viscosity::Switched(AvSwitchParams::SPHEXA),
        av_form: AvForm::SphExa,
        balsara: false,
        conductivity: None,
        artificial_stress: None,
        fixed_h: false,
        av_cleaning: false,
        weak_shock_alpha: None,
        conduction_contrast: Contrast::Off,
    };

    /// [`Scheme::VE`] without the grad-h terms and with the artificial
    /// conductivity `alpha_u = 1` (Price 2008's value, not tuned): on
    /// Sedov (t = 0.05) its L1 of rho, P and |v| are below those of
    /// SPH-EXA's `ve` at 30^3, 40^3 and 50^3. On Noh and Evrard it is
    /// closer to the references than `ve` but still far (`docs/schemes.md`).
    pub const VE_AC: Scheme = Scheme {
        grad_h: false,
        conductivity: Some(1.0),
        ..Scheme::VE
    };

    /// [`Scheme::VE_AC`] with the paper's viscosity and time-step forms
    /// ([`AvForm::Paper`]: `beta` scaled by `alpha`, so converging flows
    /// that are not shocks are not heated) and switches up to
    /// `alpha = 0.5` (the `evrard` preset's ceiling, not tuned on Sedov:
    /// 0.4 gives the same L1 to 2 digits). On Sedov t = 0.05, at equal
    /// run time, its L1 rho is 12-15% and its L1 |v| 4-13% below `ve-ac`'s
    /// and its L1 P within 4% of it (the same cost per step, 19-37% more
    /// steps); on Noh its plateau is 50-54 rho0 (`ve`: 23) and on Evrard
    /// it is within 5.4% of the reference through t = 1.0 (`docs/schemes.md`).
    pub const BEST: Scheme = Scheme {
        av_form: AvForm::Paper,
        viscosity: Viscosity::Switched(AvSwitchParams {
            alpha_max: 0.5,
            ..AvSwitchParams::SPHEXA
        }),
        ..Scheme::VE_AC
    };

    /// One scheme for every ideal-gas case, issue 42's (the default of most
    /// of them and of scenes of your own: each case's `default_scheme`, as
    /// `sphexa cases` lists it; the isobaric cube keeps its own
    /// until it meets its bound): [`Scheme::BEST`] with AV cleaning (shear
    /// and smooth flows keep their kinetic energy: Gresho, Kelvin-Helmholtz),
    /// switches whose ceiling rises from 0.3 at strong shocks (Noh's and
    /// Sedov's, into cold gas: with the conduction below, Noh's plateau
    /// under block steps at 44^3 is 0.949 of the analytic at 0.4, 0.970
    /// at 0.35 and 1.006 at 0.3 (with the pressure contrast alone; 1.016
    /// at 37^3); Sedov's L1 moves in the third digit) to 2 at weak ones
    /// (Sod's: they ring behind the front with less)
    /// ([`AvSwitchParams::ceiling`]), and conductivity
    /// `alpha_u = 2` weighted by the larger of each pair's contrasts of
    /// `u` and of pressure ([`Contrast::Larger`]: Sedov's front and hot
    /// interior need the heat flux across their contrasts of `u`, Sod's
    /// contact, u differing by 2x at one pressure, smears with Price's
    /// full flux, and a collapse's shocked core needs it across its
    /// pressure noise, where neighbours' `u` differ little: with the
    /// contrast of `u` alone Evrard's E_kin at t = 2.0 is 13.1% low at
    /// 14k particles and its E_int 6.9% low at 65k). Measured on every
    /// case at two resolutions in `docs/schemes.md` (2026-12-06, one
    /// scheme; 2026-12-07 (evening), the larger contrast).
    pub const GAS: Scheme = Scheme {
        viscosity: Viscosity::Switched(AvSwitchParams {
            alpha_max: 0.3,
            ..AvSwitchParams::SPHEXA
        }),
        av_cleaning: true,
        conductivity: Some(2.0),
        conduction_contrast: Contrast::Larger,
        weak_shock_alpha: Some(2.0),
        ..Scheme::BEST
    };

    /// Shear layers (the `kelvin-helmholtz` case's scheme until
    /// 2026-12-07, when it moved to [`Scheme::GAS`]): the paper's (IAD, grad-h)
    /// with viscosity switches (alpha in [0.05, 1]) and the AV cleaning
    /// after SPH-EXA's ([`AvCleaning`](crate::momentum::AvCleaning)), which
    /// leaves a shear layer's linear velocity profile undamped.
    /// Kelvin-Helmholtz M(1.5) (reference 0.1479), global steps: 0.066 at
    /// 32^2 x 8 and 0.117 at 64^2 x 8 (block steps, 2026-12-07: 0.0775 and
    /// 0.1117); `ve`: 0.017 and 0.046, `ve` with cleaning 0.053 and 0.109.
    pub const SHEAR: Scheme = Scheme {
        viscosity: Viscosity::Switched(AvSwitchParams::DEFAULT),
        av_cleaning: true,
        ..Scheme::PAPER
    };

    /// The `isobaric-cube` case's scheme: the paper's with pressure-energy
    /// volumes ([`Volume::PressureEnergy`]) and kernel gradients. A
    /// density jump at one pressure keeps one smoothed pressure, so the
    /// contact feels no spurious force; kernel gradients keep the pair
    /// weights of two lattices of different spacing symmetric where IAD
    /// matrices of the two sides differ. Isobaric cube, v_rms / c at
    /// t = 1: 0.018 / 0.010 / 0.0085 at 16, 24 and 32 particles per side
    /// (the paper's scheme: 0.067 at 16, 0.062 at 24).
    pub const CONTACT: Scheme = Scheme {
        gradients: Gradients::Kernel,
        volume: Volume::PressureEnergy,
        ..Scheme::PAPER
    };

    /// The `noh` case's scheme: kernel gradients, grad-h, viscosity
    /// switches up to `alpha = 0.7`.
    pub const NOH: Scheme = Scheme {
        gradients: Gradients::Kernel,
        grad_h: true,
        volume: Volume::Mass,
        viscosity: Viscosity::Switched(AvSwitchParams {
            alpha_max: 0.7,
            ..AvSwitchParams::DEFAULT
        }),
        av_form: AvForm::Paper,
        balsara: false,
        conductivity: None,
        artificial_stress: None,
        fixed_h: false,
        av_cleaning: false,
        weak_shock_alpha: None,
        conduction_contrast: Contrast::Off,
    };

    /// The `evrard` case's scheme: kernel gradients, no grad-h, viscosity
    /// switches up to `alpha = 0.5`, artificial conductivity `alpha_u = 3`.
    /// Past the bounce the shocked core keeps a velocity dispersion that
    /// the conduction of its pressure noise turns into heat; `alpha_u` was
    /// chosen on Evrard at 30^3 (1, 2, 2.5, 3, 4 scanned) and holds at
    /// 40^3 (`docs/cases.md`, Evrard).
    pub const EVRARD: Scheme = Scheme {
        gradients: Gradients::Kernel,
        grad_h: false,
        volume: Volume::Mass,
        viscosity: Viscosity::Switched(AvSwitchParams {
            alpha_max: 0.5,
            ..AvSwitchParams::DEFAULT
        }),
        av_form: AvForm::Paper,
        balsara: false,
        conductivity: Some(3.0),
        artificial_stress: None,
        fixed_h: false,
        av_cleaning: false,
        weak_shock_alpha: None,
        conduction_contrast: Contrast::Off,
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

    /// The switch parameters, when the viscosity is switched, with the
    /// scheme's weak-shock ceiling ([`Scheme::weak_shock_alpha`]).
    pub fn switches(&self) -> Option<AvSwitchParams> {
        match self.viscosity {
            Viscosity::Switched(p) => Some(AvSwitchParams {
                weak_alpha: self.weak_shock_alpha,
                ..p
            }),
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
                    "viscosity switches: alpha_min {} and alpha_max {} must be finite with 0 <= alpha_min <= alpha_max, decay {} must be > 0 and sound_weight {} >= 0",
                    p.alpha_min, p.alpha_max, p.decay, p.sound_weight
                )));
            }
            _ => {}
        }
        if let Some(a) = self.weak_shock_alpha {
            if !(a > 0.0 && a.is_finite()) {
                return Err(CoreError::Invalid(format!(
                    "weak-shock alpha {a} must be a finite number > 0 (or off)"
                )));
            }
        }
        if let Some(a) = self.conductivity {
            if !(a > 0.0 && a.is_finite()) {
                return Err(CoreError::Invalid(format!(
                    "conductivity {a} must be a finite number > 0 (or off)"
                )));
            }
        }
        if self.volume == Volume::Generalised && self.gradients != Gradients::Iad {
            return Err(CoreError::Invalid(
                "generalised volume elements need IAD gradients (--gradients iad)".into(),
            ));
        }
        Ok(())
    }

    /// Whether the pipeline computes the velocity divergence (and curl)
    /// before the momentum stage: for the viscosity switches or the
    /// Balsara limiter.
    pub fn needs_divergence(&self) -> bool {
        self.switches().is_some() || self.balsara || self.av_cleaning
    }

    /// The optional per-particle fields the scheme needs (`gravity`: the
    /// run has self-gravity; the EOS's reference state is the
    /// [`HydroConfig`](crate::HydroConfig)'s to add).
    pub fn fields(&self, gravity: bool) -> FieldSet {
        FieldSet {
            iad: self.gradients == Gradients::Iad,
            grad_h: self.grad_h,
            gravity,
            alpha: self.switches().is_some(),
            eos_ref: false,
            block: false,
            volumes: self.volume != Volume::Mass,
            balsara: self.balsara,
            cleaning: self.av_cleaning,
            stirring: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The contrast as written before it was a choice (`true` / `false`)
    /// and as a name.
    #[test]
    fn conduction_contrast_reads_flags_and_names() {
        use serde::de::value::{BoolDeserializer, Error, StrDeserializer};
        let flag = |b| contrast_or_flag(BoolDeserializer::<Error>::new(b)).unwrap();
        let name = |n| contrast_or_flag(StrDeserializer::<Error>::new(n));
        assert_eq!(flag(true), Contrast::Energy);
        assert_eq!(flag(false), Contrast::Off);
        assert_eq!(name("larger").unwrap(), Contrast::Larger);
        assert_eq!(name("pressure").unwrap(), Contrast::Pressure);
        assert!(name("on").is_err());
    }

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
        s.weak_shock_alpha = Some(f64::INFINITY);
        assert!(s.validate().unwrap_err().to_string().contains("weak-shock"));
        s.weak_shock_alpha = None;
        s.set_switches(true);
        s.set_alpha(-0.5);
        assert!(s.validate().is_err());
    }
}
