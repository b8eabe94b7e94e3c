//! Equations of state: pressure and sound speed from density and specific
//! internal energy.

use rayon::prelude::*;

/// An equation of state.
#[derive(Debug, Clone, Copy, PartialEq)]
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
            Eos::Tait { rho0, c0, p0 } => {
                let s = rho / rho0;
                let s3 = s * s * s;
                let s7 = s3 * s3 * s;
                (rho0 * c0 * c0 / 7.0 * (s7 - 1.0) + p0, c0 * s3)
            }
        }
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
        };
        if ok {
            Ok(())
        } else {
            Err(crate::CoreError::Invalid(format!(
                "equation of state {self:?}: gamma > 1 (ideal gas), positive finite c0, K, rho0 required"
            )))
        }
    }

    /// Fills `p` and `c` for every particle (parallel).
    pub fn apply(&self, rho: &[f64], u: &[f64], p: &mut [f64], c: &mut [f64]) {
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
