//! The spherical Noh implosion (Noh 1987): a cold gas falling at uniform speed onto the
//! centre, stopped by an outgoing accretion shock.

use super::{check_density, check_gamma, FlowState, ReferenceError};

/// The exact spherical Noh solution for a cold ideal gas of density `rho0` falling radially
/// inwards at speed `v0`.
///
/// The shock leaves the centre at `t = 0` with speed `(gamma - 1) v0 / 2`. Behind it the gas
/// is at rest with `rho = rho0 ((gamma + 1)/(gamma - 1))^3`, `u = v0^2 / 2`,
/// `p = (gamma - 1) rho u`; ahead of it the gas still falls at `v0` and has been compressed
/// geometrically to `rho = rho0 (1 + v0 t / r)^2`. For `gamma = 5/3` these are `64 rho0`,
/// `1/2`, `64/3 rho0` and the shock is at `t / 3`.
///
/// [`FlowState::v`] is the signed radial velocity: `-v0` (inflow) ahead of the shock.
///
/// ```
/// use sph_apps::reference::Noh;
///
/// let noh = Noh::default(); // gamma = 5/3, rho0 = 1, v0 = 1
/// assert!((noh.shock_radius(0.6) - 0.2).abs() < 1e-15);
/// assert!((noh.state(0.1, 0.6).rho - 64.0).abs() < 1e-12);
/// assert_eq!(noh.state(0.4, 0.6).v, -1.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noh {
    gamma: f64,
    rho0: f64,
    v0: f64,
    u_ambient: f64,
}

impl Default for Noh {
    /// The standard test: `gamma = 5/3`, `rho0 = 1`, `v0 = 1`, cold gas.
    fn default() -> Self {
        Self {
            gamma: 5.0 / 3.0,
            rho0: 1.0,
            v0: 1.0,
            u_ambient: 0.0,
        }
    }
}

impl Noh {
    /// Builds the solution for adiabatic index `gamma`, initial density `rho0` and inflow
    /// speed `v0` (a magnitude; the gas moves towards the centre).
    ///
    /// # Errors
    ///
    /// [`ReferenceError`] when `gamma` is not finite and > 1, or `rho0` or `v0` is not finite
    /// and > 0.
    pub fn new(gamma: f64, rho0: f64, v0: f64) -> Result<Self, ReferenceError> {
        check_gamma(gamma)?;
        check_density(rho0)?;
        if !(v0.is_finite() && v0 > 0.0) {
            return Err(ReferenceError::InvalidSpeed { v0 });
        }
        Ok(Self {
            gamma,
            rho0,
            v0,
            u_ambient: 0.0,
        })
    }

    /// Sets the specific internal energy reported for the unshocked gas (the pressure there
    /// follows as `(gamma - 1) rho u_ambient`). It labels the infalling gas only: the shocked
    /// state is the cold-gas solution.
    ///
    /// # Panics
    ///
    /// In debug builds, if `u_ambient` is negative or not finite.
    #[must_use]
    pub fn with_ambient_u(self, u_ambient: f64) -> Self {
        debug_assert!(
            u_ambient.is_finite() && u_ambient >= 0.0,
            "u_ambient = {u_ambient}"
        );
        Self { u_ambient, ..self }
    }

    /// The adiabatic index.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// The initial density.
    pub fn rho0(&self) -> f64 {
        self.rho0
    }

    /// The inflow speed (a magnitude).
    pub fn v0(&self) -> f64 {
        self.v0
    }

    /// The shock speed `(gamma - 1) v0 / 2`.
    pub fn shock_speed(&self) -> f64 {
        0.5 * (self.gamma - 1.0) * self.v0
    }

    /// The shock radius `(gamma - 1) v0 t / 2`; 0 for `t <= 0`.
    pub fn shock_radius(&self, t: f64) -> f64 {
        self.shock_speed() * t.max(0.0)
    }

    /// The density of the shocked gas, `rho0 ((gamma + 1)/(gamma - 1))^3`.
    pub fn shocked_density(&self) -> f64 {
        self.rho0 * ((self.gamma + 1.0) / (self.gamma - 1.0)).powi(3)
    }

    /// The state at distance `r` from the centre (a negative `r` is read as `|r|`) at time `t`.
    ///
    /// Points with `r <= r_s(t)` are shocked (the shock itself reports the shocked state). For
    /// `t <= 0` every point reports the initial state `rho0`, `v = -v0`. A NaN input gives an
    /// all-NaN state.
    pub fn state(&self, r: f64, t: f64) -> FlowState {
        if r.is_nan() || t.is_nan() {
            return FlowState::NAN;
        }
        let r = r.abs();
        let gm1 = self.gamma - 1.0;
        if t > 0.0 && r <= self.shock_radius(t) {
            let rho = self.shocked_density();
            let u = 0.5 * self.v0 * self.v0;
            return FlowState {
                rho,
                p: gm1 * rho * u,
                v: 0.0,
                u,
            };
        }
        // Ahead of the shock each shell has fallen v0 t inwards; mass conservation in spherical
        // shells gives the (r + v0 t)^2 / r^2 compression.
        let compression = if t > 0.0 {
            (1.0 + self.v0 * t / r).powi(2)
        } else {
            1.0
        };
        let rho = self.rho0 * compression;
        FlowState {
            rho,
            p: gm1 * rho * self.u_ambient,
            v: -self.v0,
            u: self.u_ambient,
        }
    }
}
