//! The Gresho-Chan vortex: a stationary, rotating flow whose centrifugal
//! force is balanced by a pressure gradient, so the exact solution at any
//! time is the initial state (Gresho & Chan 1990; Springel 2010 set-up with
//! R1 = 0.2, rho = 1, P0 = 5).

use super::{check_density, FlowState, ReferenceError};

/// The vortex: rigid rotation `v_phi = 5 r / (5 R1)` inside `R1`, falling
/// linearly to rest at `2 R1`, at rest outside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gresho {
    gamma: f64,
    rho: f64,
    p0: f64,
    r1: f64,
}

impl Gresho {
    /// The standard vortex (R1 = 0.2, peak speed 1, rho = 1, P0 = 5) for
    /// the adiabatic index `gamma`.
    ///
    /// # Errors
    /// A bad gamma.
    pub fn standard(gamma: f64) -> Result<Self, ReferenceError> {
        Self::new(gamma, 1.0, 5.0, 0.2)
    }

    /// A vortex of density `rho`, central pressure `p0`, inner radius `r1`
    /// (peak speed 1 at `r1`).
    ///
    /// # Errors
    /// A bad gamma or density, or a pressure or radius that is not finite
    /// and positive.
    pub fn new(gamma: f64, rho: f64, p0: f64, r1: f64) -> Result<Self, ReferenceError> {
        super::check_gamma(gamma)?;
        check_density(rho)?;
        if !(p0.is_finite() && p0 > 0.0) {
            return Err(ReferenceError::InvalidPressure { p: p0 });
        }
        if !(r1.is_finite() && r1 > 0.0) {
            return Err(ReferenceError::InvalidRadius { r: r1 });
        }
        Ok(Self { gamma, rho, p0, r1 })
    }

    /// Azimuthal speed at cylindrical radius `r`.
    pub fn v_phi(&self, r: f64) -> f64 {
        let s = r / self.r1;
        if s < 1.0 {
            s
        } else if s < 2.0 {
            2.0 - s
        } else {
            0.0
        }
    }

    /// Pressure at cylindrical radius `r`: `P0 + rho int_0^r v_phi^2 / r' dr'`.
    pub fn pressure(&self, r: f64) -> f64 {
        let s = (r / self.r1).min(2.0);
        let rho = self.rho;
        // int_0^s s' ds' = s^2/2 inside; int_1^s (2 - s')^2 / s' ds' beyond.
        let inner = 0.5 * s.min(1.0).powi(2);
        let outer = if s > 1.0 {
            4.0 * s.ln() - 4.0 * (s - 1.0) + 0.5 * (s * s - 1.0)
        } else {
            0.0
        };
        self.p0 + rho * (inner + outer)
    }

    /// The (time-independent) state at cylindrical radius `r`; `v` is
    /// `v_phi`.
    pub fn state(&self, r: f64) -> FlowState {
        if r.is_nan() {
            return FlowState::NAN;
        }
        let p = self.pressure(r);
        FlowState {
            rho: self.rho,
            p,
            v: self.v_phi(r),
            u: p / ((self.gamma - 1.0) * self.rho),
        }
    }

    /// Inner radius (peak speed).
    pub fn r1(&self) -> f64 {
        self.r1
    }

    /// Density.
    pub fn density(&self) -> f64 {
        self.rho
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The textbook closed form (Springel 2010, eq. 60 with R1 = 0.2):
    /// P = 5 + 12.5 r^2 inside 0.2, 9 + 12.5 r^2 - 20 r + 4 ln(r/0.2) to
    /// 0.4, 3 + 4 ln 2 outside.
    #[test]
    fn pressure_matches_the_closed_form() {
        let g = Gresho::standard(5.0 / 3.0).unwrap();
        for k in 0..=60 {
            let r = k as f64 * 0.01;
            let want = if r < 0.2 {
                5.0 + 12.5 * r * r
            } else if r < 0.4 {
                9.0 + 12.5 * r * r - 20.0 * r + 4.0 * (r / 0.2).ln()
            } else {
                3.0 + 4.0 * 2f64.ln()
            };
            assert!((g.pressure(r) - want).abs() < 1e-12, "r {r}");
        }
    }

    /// Radial balance dP/dr = rho v_phi^2 / r, by central differences.
    #[test]
    fn pressure_balances_the_centrifugal_force() {
        let g = Gresho::standard(5.0 / 3.0).unwrap();
        for k in 1..50 {
            let r = k as f64 * 0.01 + 0.003;
            let e = 1e-6;
            let dp = (g.pressure(r + e) - g.pressure(r - e)) / (2.0 * e);
            let v = g.v_phi(r);
            assert!(
                (dp - v * v / r).abs() < 1e-6,
                "r {r}: {dp} vs {}",
                v * v / r
            );
        }
    }
}
