//! Equations of state: pressure and sound speed from density and specific
//! internal energy.

use rayon::prelude::*;
use std::fmt;
use std::str::FromStr;

/// Tait pressure and sound speed about `(rho0, p0)`.
#[inline]
fn tait(rho: f64, rho0: f64, c0: f64, p0: f64) -> (f64, f64) {
    let s = rho / rho0;
    let s3 = s * s * s;
    let s7 = s3 * s3 * s;
    (rho0 * c0 * c0 / 7.0 * (s7 - 1.0) + p0, c0 * s3)
}

/// An equation of state.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Eos {
    /// `P = (gamma - 1) rho u`, `c = sqrt(gamma P / rho)`.
    IdealGas {
        /// Adiabatic index.
        gamma: f64,
    },
    /// `P = c0^2 rho`, `c = c0`.
    Isothermal {
        /// Sound speed.
        c0: f64,
    },
    /// `P = K rho^Gamma`, `c = sqrt(Gamma P / rho)`.
    Polytropic {
        /// Polytropic constant.
        k: f64,
        /// Polytropic exponent.
        gamma: f64,
    },
    /// Stiff Tait EOS: `P = rho0 c0^2 / 7 ((rho/rho0)^7 - 1) + p0`,
    /// `c = c0 (rho/rho0)^3`.
    Tait {
        /// Reference density.
        rho0: f64,
        /// Reference sound speed.
        c0: f64,
        /// Background pressure.
        p0: f64,
    },
    /// Tait EOS relative to each particle's own reference state (the
    /// SPH-EXA square patch): `P = c0^2/7 rho_ref,i ((rho/rho_ref,i)^7 - 1) + p_ref,i`
    /// with `rho_ref` the particle's density at the first step (calibrated
    /// by the pipeline) and `p_ref` its initial pressure, `c = c0 (rho/rho_ref)^3`.
    /// Needs [`Particles::eos_ref`](crate::Particles).
    TaitReferenced {
        /// Reference sound speed.
        c0: f64,
    },
}

impl Eos {
    /// Pressure and sound speed.
    #[inline]
    pub fn pressure_sound(&self, rho: f64, u: f64) -> (f64, f64) {
        match *self {
            Eos::IdealGas { gamma } => {
                let p = (gamma - 1.0) * rho * u;
                (p, (gamma * p / rho).sqrt())
            }
            Eos::Isothermal { c0 } => (c0 * c0 * rho, c0),
            Eos::Polytropic { k, gamma } => {
                let p = k * rho.powf(gamma);
                (p, (gamma * p / rho).sqrt())
            }
            Eos::Tait { rho0, c0, p0 } => tait(rho, rho0, c0, p0),
            Eos::TaitReferenced { c0 } => tait(rho, rho, c0, 0.0),
        }
    }

    /// Pressure and sound speed with a per-particle reference state
    /// `(rho_ref, p_ref)`, used by [`Eos::TaitReferenced`] (other variants
    /// ignore it).
    #[inline]
    pub fn pressure_sound_ref(&self, rho: f64, u: f64, rho_ref: f64, p_ref: f64) -> (f64, f64) {
        match *self {
            Eos::TaitReferenced { c0 } => tait(rho, rho_ref, c0, p_ref),
            _ => self.pressure_sound(rho, u),
        }
    }

    /// Whether pressure depends on the internal energy (else `u` is only
    /// carried along, and may go negative without harm).
    pub fn uses_internal_energy(&self) -> bool {
        matches!(self, Eos::IdealGas { .. })
    }

    /// The specific internal energy a barotropic EOS gives a density: the
    /// work done compressing the gas from density 1 (code units),
    /// `e = int_1^rho P / rho'^2 drho'`: `c0^2 ln rho` (isothermal),
    /// `K (rho^(G-1) - 1) / (G-1)` (polytropic; `K ln rho` at `G = 1`).
    /// `None` where the pressure reads `u` or a reference state (ideal gas,
    /// Tait): there `u` is the particles' own.
    ///
    /// The energy equation integrates `du/dt = P / rho^2 Drho/Dt` plus the
    /// dissipative heat, so starting from `u = e(rho)` keeps `u - e(rho)`
    /// equal to the heat made, and `E_kin + sum m u` is the conserved total.
    ///
    /// ```
    /// use sph_core::Eos;
    /// let iso = Eos::Isothermal { c0: 2.0 };
    /// assert_eq!(iso.energy(1.0), Some(0.0));
    /// assert!((iso.energy(std::f64::consts::E).unwrap() - 4.0).abs() < 1e-15);
    /// assert_eq!(Eos::IdealGas { gamma: 1.4 }.energy(2.0), None);
    /// ```
    pub fn energy(&self, rho: f64) -> Option<f64> {
        match *self {
            Eos::Isothermal { c0 } => Some(c0 * c0 * rho.ln()),
            Eos::Polytropic { k, gamma: 1.0 } => Some(k * rho.ln()),
            Eos::Polytropic { k, gamma } => Some(k * (rho.powf(gamma - 1.0) - 1.0) / (gamma - 1.0)),
            _ => None,
        }
    }

    /// Whether the EOS needs a per-particle reference state.
    pub fn needs_reference(&self) -> bool {
        matches!(self, Eos::TaitReferenced { .. })
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), crate::CoreError> {
        let ok = match *self {
            Eos::IdealGas { gamma } => gamma > 1.0 && gamma.is_finite(),
            Eos::Isothermal { c0 } => c0 > 0.0 && c0.is_finite(),
            Eos::Polytropic { k, gamma } => {
                k > 0.0 && gamma > 0.0 && k.is_finite() && gamma.is_finite()
            }
            Eos::Tait { rho0, c0, p0 } => {
                rho0 > 0.0 && c0 > 0.0 && p0.is_finite() && rho0.is_finite() && c0.is_finite()
            }
            Eos::TaitReferenced { c0 } => c0 > 0.0 && c0.is_finite(),
        };
        if ok {
            Ok(())
        } else {
            Err(crate::CoreError::Invalid(format!(
                "equation of state {self:?}: gamma > 1 (ideal gas), positive finite c0, K, rho0 required"
            )))
        }
    }

    /// Fills `p` and `c` for every particle (parallel); `reference` holds
    /// the per-particle `(rho_ref, p_ref)` arrays when
    /// [`Eos::needs_reference`].
    pub fn apply(
        &self,
        rho: &[f64],
        u: &[f64],
        reference: Option<(&[f64], &[f64])>,
        p: &mut [f64],
        c: &mut [f64],
    ) {
        if let Some((rr, pr)) = reference {
            p.par_iter_mut()
                .zip(c.par_iter_mut())
                .enumerate()
                .for_each(|(i, (p, c))| {
                    (*p, *c) = self.pressure_sound_ref(rho[i], u[i], rr[i], pr[i]);
                });
            return;
        }
        p.par_iter_mut()
            .zip(c.par_iter_mut())
            .zip(rho.par_iter().zip(u.par_iter()))
            .for_each(|((p, c), (&rho, &u))| {
                let (pp, cc) = self.pressure_sound(rho, u);
                *p = pp;
                *c = cc;
            });
    }
}

/// The accepted forms of an equation of state written as text.
pub const EOS_FORMS: &str =
    "ideal:GAMMA (GAMMA > 1), isothermal:C0, polytropic:K:GAMMA, tait:RHO0:C0:P0, tait-ref:C0 (positive C0, K, GAMMA, RHO0; finite P0)";

impl fmt::Display for Eos {
    /// The text [`Eos::from_str`] reads back (`ideal:1.4`,
    /// `isothermal:1`, `polytropic:K:GAMMA`, `tait:RHO0:C0:P0`,
    /// `tait-ref:C0`), each number written so that it parses to the same
    /// bits.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Eos::IdealGas { gamma } => write!(f, "ideal:{gamma}"),
            Eos::Isothermal { c0 } => write!(f, "isothermal:{c0}"),
            Eos::Polytropic { k, gamma } => write!(f, "polytropic:{k}:{gamma}"),
            Eos::Tait { rho0, c0, p0 } => write!(f, "tait:{rho0}:{c0}:{p0}"),
            Eos::TaitReferenced { c0 } => write!(f, "tait-ref:{c0}"),
        }
    }
}

impl FromStr for Eos {
    type Err = crate::CoreError;

    /// Reads `ideal:GAMMA`, `isothermal:C0`, `polytropic:K:GAMMA`,
    /// `tait:RHO0:C0:P0` or `tait-ref:C0` and checks the values
    /// ([`Eos::validate`]).
    ///
    /// ```
    /// use sph_core::Eos;
    /// let e: Eos = "isothermal:1".parse().unwrap();
    /// assert_eq!(e, Eos::Isothermal { c0: 1.0 });
    /// assert_eq!(e.to_string().parse::<Eos>().unwrap(), e);
    /// assert!("ideal:1".parse::<Eos>().is_err());
    /// assert!("stiff:7".parse::<Eos>().unwrap_err().to_string().contains("isothermal:C0"));
    /// ```
    ///
    /// # Errors
    /// [`CoreError::Invalid`](crate::CoreError::Invalid) naming the text
    /// and the accepted forms.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let bad = |why: &str| {
            crate::CoreError::Invalid(format!(
                "equation of state '{text}': {why}; accepted: {EOS_FORMS}"
            ))
        };
        let mut parts = text.trim().split(':');
        let kind = parts.next().unwrap_or("");
        let numbers: Vec<f64> = parts
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad("its parameters must be numbers"))?;
        let want = match kind {
            "ideal" | "isothermal" | "tait-ref" => 1,
            "polytropic" => 2,
            "tait" => 3,
            _ => return Err(bad("unknown kind")),
        };
        if numbers.len() != want {
            return Err(bad(&format!("'{kind}' takes {want} number(s)")));
        }
        let eos = match kind {
            "ideal" => Eos::IdealGas { gamma: numbers[0] },
            "isothermal" => Eos::Isothermal { c0: numbers[0] },
            "tait-ref" => Eos::TaitReferenced { c0: numbers[0] },
            "polytropic" => Eos::Polytropic {
                k: numbers[0],
                gamma: numbers[1],
            },
            _ => Eos::Tait {
                rho0: numbers[0],
                c0: numbers[1],
                p0: numbers[2],
            },
        };
        eos.validate().map_err(|_| bad("a value is out of range"))?;
        Ok(eos)
    }
}

#[cfg(test)]
mod text_tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every valid equation of state written as text reads back to
        /// the same bits.
        #[test]
        fn text_round_trips(a in 1e-6f64..1e6, b in 1e-6f64..1e3, c in -1e6f64..1e6, kind in 0usize..5) {
            let eos = match kind {
                0 => Eos::IdealGas { gamma: 1.0 + b },
                1 => Eos::Isothermal { c0: a },
                2 => Eos::Polytropic { k: a, gamma: b },
                3 => Eos::Tait { rho0: a, c0: b, p0: c },
                _ => Eos::TaitReferenced { c0: a },
            };
            let back: Eos = eos.to_string().parse().unwrap();
            prop_assert_eq!(back, eos);
        }
    }

    #[test]
    fn bad_text_is_named_with_the_forms() {
        for text in [
            "",
            "ideal",
            "ideal:x",
            "ideal:1",
            "ideal:1.4:2",
            "polytropic:1",
            "isothermal:-1",
            "tait:1:1",
            "gas:1",
        ] {
            let e = text.parse::<Eos>().unwrap_err().to_string();
            assert!(
                e.contains(&format!("'{text}'")) && e.contains("ideal:GAMMA"),
                "{e}"
            );
        }
    }
}
