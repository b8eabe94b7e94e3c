//! The Sedov-Taylor point blast in a uniform medium: the "standard" similarity solution of
//! Kamm & Timmes, "On efficient generation of numerically robust Sedov solutions",
//! LA-UR-07-2849 (2007), for ambient density exponent omega = 0.
//!
//! Kamm & Timmes write the solution in the similarity variable `V` through four linear
//! functions `x1 .. x4` of `V`; the dimensionless radius `lambda = r / R`, velocity `f`,
//! density `g` and pressure `h` are products of powers of them. `V` runs from `V0` (the
//! centre, where `x2 = 0`) to `V2` (the shock, where every `x_i = 1`). Close to the centre
//! `V - V0 ~ lambda^(1/|a2|)` falls below the resolution of a double long before the density
//! underflows, so this module parametrises the solution by `eta = ln x2` instead: `V` is
//! recovered without cancellation and `ln lambda`, `ln f`, `ln g`, `ln h` are smooth
//! (asymptotically linear) functions of `eta`.
//!
//! The solution is self-similar, so the dimensionless profiles are tabulated once at
//! construction on a grid uniform in `ln lambda`, with exact slopes, and interpolated by
//! cubic Hermite polynomials; [`Sedov::state`] then costs one logarithm, three exponentials
//! and one power.

use std::f64::consts::PI;
use std::fmt;
use std::sync::Arc;

use super::quadrature::integrate;
use super::{check_density, check_gamma, FlowState, ReferenceError};

/// Nodes of the profile table (spacing 1.7e-3 in `ln lambda`; interpolation error ~1e-12).
const TABLE_NODES: usize = 8192;
/// `ln lambda` of the innermost table node (lambda = 1e-6); inside it the profiles are the
/// central power laws, whose corrections are of relative order `lambda^(1/|a2|) < 1e-13`.
const TABLE_LN_LAMBDA_MIN: f64 = -13.815_510_557_964_274;
/// `ln (lambda^j)` where the energy integral is cut: the integrand carries `lambda^j`, so the
/// cut-off part is below 1e-16 of the total.
const ALPHA_LN_WEIGHT_MIN: f64 = -36.841_361_487_904_734;
/// Half-width of the excluded band around the singular gamma = 2. Near it the exponents `a4`,
/// `a5` blow up like `1 / (2 - gamma)` and cancel in the logarithms, losing about
/// `1e-16 / |2 - gamma|` of relative accuracy; 1e-6 keeps that below 1e-10.
const SINGULAR_GAMMA_BAND: f64 = 1e-6;

/// The Sedov-Taylor similarity solution for a point blast of energy `E` released at `t = 0`
/// in a cold gas of uniform density `rho0`.
///
/// The shock is at `R(t) = (E t^2 / (alpha rho0))^(1/(j+2))`, where the energy integral
/// `alpha(gamma, j)` is computed by quadrature at construction. Geometry `j` is 1 (planar),
/// 2 (cylindrical, `E` per unit length) or 3 (spherical). For `j = 1`, as in Kamm & Timmes,
/// `E` is the energy per unit area on one side of the blast plane: a symmetric slab holding
/// `E_total` per unit area in all is `Sedov::new(gamma, E_total / 2, rho0, 1)`.
///
/// Any `gamma > 1` is accepted except the two singular members of the standard family:
/// `gamma = 2` (all `j`; within 1e-6) and `gamma >= 7` for `j = 3`.
///
/// Accuracy: the profiles carry the blast energy to ~1e-10 for 1.1 <= gamma < 7; as gamma -> 1
/// the profile steepens like `lambda^(j/(gamma-1))` and the accuracy degrades (2e-6 at 1.02).
/// Construction takes 15-80 ms (quadrature and table); cloning is cheap (the table is shared).
///
/// # Example
///
/// ```
/// use sph_apps::reference::Sedov;
///
/// let sedov = Sedov::spherical(5.0 / 3.0, 1.0, 1.0).unwrap();
/// assert!((sedov.xi0() - 1.15167).abs() < 1e-4);
///
/// let radius = sedov.shock_radius(0.05);
/// assert!((radius - 0.3475).abs() < 1e-4);
///
/// // Just behind the shock the density is close to the strong-shock value 4 rho0 ...
/// let behind = sedov.state(0.99 * radius, 0.05);
/// assert!(behind.rho > 3.0 && behind.rho < 4.0 && behind.v > 0.0);
/// // ... and ahead of it the gas is at rest.
/// let ahead = sedov.state(1.01 * radius, 0.05);
/// assert_eq!((ahead.rho, ahead.v), (1.0, 0.0));
/// ```
#[derive(Clone)]
pub struct Sedov {
    gamma: f64,
    energy: f64,
    rho0: f64,
    geometry: u32,
    alpha: f64,
    p_ambient: f64,
    u_ambient: f64,
    profile: Arc<Profile>,
}

impl fmt::Debug for Sedov {
    // The profile table is thousands of numbers; leave it out.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Sedov")
            .field("gamma", &self.gamma)
            .field("energy", &self.energy)
            .field("rho0", &self.rho0)
            .field("geometry", &self.geometry)
            .field("alpha", &self.alpha)
            .field("p_ambient", &self.p_ambient)
            .field("u_ambient", &self.u_ambient)
            .finish_non_exhaustive()
    }
}

impl Sedov {
    /// Builds the solution for adiabatic index `gamma`, blast energy `energy`, ambient density
    /// `rho0` and geometry `geometry` (1 planar, 2 cylindrical, 3 spherical).
    ///
    /// The ambient gas is cold and at rest; see [`Sedov::with_ambient`] to label it with a
    /// pressure and internal energy.
    ///
    /// # Errors
    ///
    /// [`ReferenceError`] when `gamma` is not finite and > 1 or is a singular case (within
    /// 1e-6 of 2, or >= 7 for `j = 3`), `energy` or `rho0` is not finite and > 0, or
    /// `geometry` is not 1, 2 or 3.
    pub fn new(gamma: f64, energy: f64, rho0: f64, geometry: u32) -> Result<Self, ReferenceError> {
        check_gamma(gamma)?;
        if !(energy.is_finite() && energy > 0.0) {
            return Err(ReferenceError::InvalidEnergy { energy });
        }
        check_density(rho0)?;
        if !(1..=3).contains(&geometry) {
            return Err(ReferenceError::InvalidGeometry { geometry });
        }
        if (gamma - 2.0).abs() < SINGULAR_GAMMA_BAND {
            return Err(ReferenceError::UnsupportedGamma {
                gamma,
                geometry,
                reason: "the standard-family exponents are singular at gamma = 2 \
                         (Kamm & Timmes' omega3 case); use |gamma - 2| >= 1e-6",
            });
        }
        if geometry == 3 && gamma >= 7.0 - SINGULAR_GAMMA_BAND {
            return Err(ReferenceError::UnsupportedGamma {
                gamma,
                geometry,
                reason: "the spherical standard family needs gamma < 7 \
                         (gamma = 7 is Kamm & Timmes' omega2 case)",
            });
        }
        let family = Family::new(gamma, geometry);
        let unsupported = || ReferenceError::UnsupportedGamma {
            gamma,
            geometry,
            reason: "the similarity profile is not monotone or not finite in double precision \
                     for this gamma; use a gamma closer to the usual 1.1 .. 5",
        };
        let profile = Profile::new(&family).ok_or_else(unsupported)?;
        let alpha = family.alpha();
        if !(alpha.is_finite() && alpha > 0.0) {
            return Err(unsupported());
        }
        Ok(Self {
            gamma,
            energy,
            rho0,
            geometry,
            alpha,
            p_ambient: 0.0,
            u_ambient: 0.0,
            profile: Arc::new(profile),
        })
    }

    /// The spherical (`j = 3`) solution; see [`Sedov::new`].
    ///
    /// # Errors
    ///
    /// As [`Sedov::new`].
    pub fn spherical(gamma: f64, energy: f64, rho0: f64) -> Result<Self, ReferenceError> {
        Self::new(gamma, energy, rho0, 3)
    }

    /// Sets the state reported ahead of the shock: pressure `p_ambient` and specific internal
    /// energy `u_ambient` (density `rho0`, velocity 0).
    ///
    /// The two are taken as given, not made consistent through the equation of state, so a
    /// simulation's labels (e.g. `u = 1e-8` with `p = 0`) can be reproduced. They do not change
    /// the solution behind the shock, which is the strong-shock (cold ambient) limit.
    ///
    /// # Panics
    ///
    /// In debug builds, if either value is negative or not finite.
    #[must_use]
    pub fn with_ambient(self, p_ambient: f64, u_ambient: f64) -> Self {
        debug_assert!(
            p_ambient.is_finite() && p_ambient >= 0.0,
            "p_ambient = {p_ambient}"
        );
        debug_assert!(
            u_ambient.is_finite() && u_ambient >= 0.0,
            "u_ambient = {u_ambient}"
        );
        Self {
            p_ambient,
            u_ambient,
            ..self
        }
    }

    /// The adiabatic index.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// The blast energy.
    pub fn energy(&self) -> f64 {
        self.energy
    }

    /// The ambient density.
    pub fn rho0(&self) -> f64 {
        self.rho0
    }

    /// The geometry index `j` (1 planar, 2 cylindrical, 3 spherical).
    pub fn geometry(&self) -> u32 {
        self.geometry
    }

    /// The dimensionless energy integral `alpha` in `E = alpha rho0 R^(j+2) / t^2`.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// The shock-radius coefficient `xi0 = alpha^(-1/(j+2))`, so that
    /// `R = xi0 (E t^2 / rho0)^(1/(j+2))`.
    pub fn xi0(&self) -> f64 {
        self.alpha.powf(-1.0 / self.exponent_denominator())
    }

    /// The shock radius `R(t)`; 0 for `t <= 0` (before the blast).
    pub fn shock_radius(&self, t: f64) -> f64 {
        if t <= 0.0 {
            return 0.0;
        }
        (self.energy * t * t / (self.alpha * self.rho0)).powf(1.0 / self.exponent_denominator())
    }

    /// The shock speed `dR/dt = 2 R / ((j + 2) t)`; 0 for `t <= 0`.
    pub fn shock_speed(&self, t: f64) -> f64 {
        if t <= 0.0 {
            return 0.0;
        }
        2.0 * self.shock_radius(t) / (self.exponent_denominator() * t)
    }

    /// The state just behind the shock at time `t`: the strong-shock jump
    /// `rho = rho0 (gamma + 1)/(gamma - 1)`, `v = 2/(gamma + 1) dR/dt`,
    /// `p = 2/(gamma + 1) rho0 (dR/dt)^2`.
    pub fn post_shock(&self, t: f64) -> FlowState {
        self.state(self.shock_radius(t), t)
    }

    /// The state at distance `r` from the centre (a negative `r` is read as `|r|`; for `j = 1`
    /// it is the distance from the blast plane) at time `t`.
    ///
    /// Points with `r <= R(t)` are shocked (the shock itself reports the post-shock state);
    /// points beyond it, and every point for `t <= 0`, report the ambient state. At the centre
    /// the density goes to 0 while the pressure stays finite, so `u` grows without bound
    /// (it is infinite at `r = 0`). A NaN input gives an all-NaN state.
    pub fn state(&self, r: f64, t: f64) -> FlowState {
        if r.is_nan() || t.is_nan() {
            return FlowState::NAN;
        }
        let r = r.abs();
        let radius = self.shock_radius(t);
        if !(radius > 0.0 && r <= radius) {
            return FlowState {
                rho: self.rho0,
                p: self.p_ambient,
                v: 0.0,
                u: self.u_ambient,
            };
        }
        let speed = self.shock_speed(t);
        let [f, g, h] = self.profile.eval((r / radius).ln());
        let gp1 = self.gamma + 1.0;
        let gm1 = self.gamma - 1.0;
        let rho = self.rho0 * gp1 / gm1 * g;
        let p = 2.0 / gp1 * self.rho0 * speed * speed * h;
        FlowState {
            rho,
            p,
            v: 2.0 / gp1 * speed * f,
            u: p / (gm1 * rho),
        }
    }

    /// `j + 2`, the exponent denominator of the similarity scaling.
    fn exponent_denominator(&self) -> f64 {
        f64::from(self.geometry) + 2.0
    }
}

/// The constants of Kamm & Timmes' standard family (omega = 0) for one `(gamma, j)`: the
/// exponents `a0 .. a5` and the coefficients `a .. e` of `x1 = a V`, `x2 = b (c V - 1)`,
/// `x3 = d (1 - e V)`, `x4 = b (1 - c V / gamma)`.
#[derive(Clone, Copy, Debug)]
struct Family {
    gamma: f64,
    j: f64,
    a0: f64,
    a1: f64,
    a2: f64,
    a3: f64,
    a4: f64,
    a5: f64,
    a: f64,
    b: f64,
    c: f64,
    d: f64,
    e: f64,
}

/// The closed-form profile at one `eta = ln x2`, with derivatives with respect to `eta`.
#[derive(Clone, Copy, Debug)]
struct Point {
    ln_lambda: f64,
    ln_f: f64,
    ln_g: f64,
    ln_h: f64,
    d_ln_lambda: f64,
    d_ln_f: f64,
    d_ln_g: f64,
    d_ln_h: f64,
}

impl Family {
    fn new(gamma: f64, geometry: u32) -> Self {
        let g = gamma;
        let j = f64::from(geometry);
        let a0 = 2.0 / (j + 2.0);
        let a2 = (1.0 - g) / (2.0 * (g - 1.0) + j);
        let a1 = (j + 2.0) * g / (2.0 + j * (g - 1.0))
            * (2.0 * j * (2.0 - g) / (g * (j + 2.0) * (j + 2.0)) - a2);
        let a3 = j / (2.0 * (g - 1.0) + j);
        let a4 = a1 * (j + 2.0) / (2.0 - g);
        let a5 = -2.0 / (2.0 - g);
        let a = (j + 2.0) * (g + 1.0) / 4.0;
        let b = (g + 1.0) / (g - 1.0);
        let c = (j + 2.0) * g / 2.0;
        let d = (j + 2.0) * (g + 1.0) / ((j + 2.0) * (g + 1.0) - 2.0 * (2.0 + j * (g - 1.0)));
        let e = (2.0 + j * (g - 1.0)) / 2.0;
        Self {
            gamma,
            j,
            a0,
            a1,
            a2,
            a3,
            a4,
            a5,
            a,
            b,
            c,
            d,
            e,
        }
    }

    /// Evaluates the closed forms at `eta = ln x2` (`-inf < eta <= 0`, 0 at the shock).
    fn at(&self, eta: f64) -> Point {
        // c V - 1 = x2 / b: V comes from x2 directly, never from a difference near V0.
        let q = eta.exp() / self.b;
        let v = (1.0 + q) / self.c;
        let dv = q / self.c;
        let one_minus_ev = 1.0 - self.e * v;
        let one_minus_cv_g = 1.0 - self.c * v / self.gamma;
        let ln_x1 = (self.a * v).ln();
        let ln_x3 = (self.d * one_minus_ev).ln();
        let ln_x4 = (self.b * one_minus_cv_g).ln();
        let d_x1 = dv / v;
        let d_x3 = -self.e * dv / one_minus_ev;
        let d_x4 = -self.c / self.gamma * dv / one_minus_cv_g;

        let ln_lambda = -self.a0 * ln_x1 - self.a2 * eta - self.a1 * ln_x3;
        let d_ln_lambda = -self.a0 * d_x1 - self.a2 - self.a1 * d_x3;
        let h3 = self.a4 - 2.0 * self.a1;
        let h4 = 1.0 + self.a5;
        Point {
            ln_lambda,
            ln_f: ln_x1 + ln_lambda,
            ln_g: self.a3 * eta + self.a4 * ln_x3 + self.a5 * ln_x4,
            ln_h: self.a0 * self.j * ln_x1 + h3 * ln_x3 + h4 * ln_x4,
            d_ln_lambda,
            d_ln_f: d_x1 + d_ln_lambda,
            d_ln_g: self.a3 + self.a4 * d_x3 + self.a5 * d_x4,
            d_ln_h: self.a0 * self.j * d_x1 + h3 * d_x3 + h4 * d_x4,
        }
    }

    /// Solves `ln lambda(eta) = target` (`target <= 0`) by Newton's method safeguarded with
    /// bisection; `ln lambda` is increasing in `eta` with `ln lambda(0) = 0`.
    fn eta_at(&self, target: f64, guess: f64) -> f64 {
        if target >= 0.0 {
            return 0.0;
        }
        // Far inside, ln lambda ~ |a2| eta + const: start there and widen until bracketed.
        let slope = -self.a2;
        let mut lo = guess.min(target / slope) - 1.0;
        while self.at(lo).ln_lambda > target {
            lo = 2.0 * lo - 1.0;
        }
        let mut hi = 0.0_f64;
        let mut eta = guess.clamp(lo, hi);
        for _ in 0..200 {
            let point = self.at(eta);
            let residual = point.ln_lambda - target;
            if residual > 0.0 {
                hi = eta;
            } else {
                lo = eta;
            }
            let mut next = eta - residual / point.d_ln_lambda;
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            if (next - eta).abs() <= 1e-15 * (1.0 + eta.abs())
                || hi - lo <= 1e-15 * (1.0 + lo.abs())
            {
                return next;
            }
            eta = next;
        }
        eta
    }

    /// The energy integral `alpha` such that `E = alpha rho0 R^(j+2) / t^2`.
    ///
    /// Writing the total energy behind the shock with the post-shock scales gives
    /// `alpha = 8 A_j / ((j+2)^2 (gamma^2 - 1)) * Int_0^1 (g f^2 + h) lambda^(j-1) dlambda`,
    /// with `A_j = 1, 2 pi, 4 pi` (one side of the plane for `j = 1`, as Kamm & Timmes).
    ///
    /// The integral is taken in `ln lambda`, solving for the similarity variable at every
    /// abscissa. In `V` (or `eta`) the integrand has an endpoint singularity at `V0`, and as
    /// gamma -> 7 (j = 3) the whole profile crowds into a sliver of `V` next to the shock that
    /// a quadrature in `V` steps over; in `ln lambda` it is smooth and decays like `lambda^j`.
    fn alpha(&self) -> f64 {
        let j = self.j;
        let integrand = |ln_lambda: f64| {
            let p = self.at(self.eta_at(ln_lambda, ln_lambda / -self.a2));
            let weight = j * ln_lambda;
            (p.ln_g + 2.0 * p.ln_f + weight).exp() + (p.ln_h + weight).exp()
        };
        let integral = integrate(integrand, ALPHA_LN_WEIGHT_MIN / j, 0.0, 1e-13);
        let area = match self.j as u32 {
            1 => 1.0,
            2 => 2.0 * PI,
            _ => 4.0 * PI,
        };
        8.0 * area / ((j + 2.0) * (j + 2.0) * (self.gamma * self.gamma - 1.0)) * integral
    }
}

/// One table node: `ln f`, `ln g`, `ln h` and their slopes with respect to `ln lambda`.
#[derive(Clone, Copy, Debug)]
struct Node {
    value: [f64; 3],
    slope: [f64; 3],
}

/// The dimensionless profiles `f`, `g`, `h` tabulated uniformly in `ln lambda` on
/// `[TABLE_LN_LAMBDA_MIN, 0]`, continued inside by the central power laws.
#[derive(Clone, Debug)]
struct Profile {
    nodes: Vec<Node>,
    step: f64,
    /// Central exponents of `f`, `g`, `h` in `lambda`: 1, `j/(gamma-1)`, 0.
    central_slope: [f64; 3],
}

impl Profile {
    /// Tabulates the family; `None` when the profile is not finite and monotone in double
    /// precision (only for extreme gamma).
    fn new(family: &Family) -> Option<Self> {
        let step = -TABLE_LN_LAMBDA_MIN / (TABLE_NODES - 1) as f64;
        let mut eta = TABLE_LN_LAMBDA_MIN / -family.a2;
        let mut nodes = Vec::with_capacity(TABLE_NODES);
        for k in 0..TABLE_NODES {
            let target = TABLE_LN_LAMBDA_MIN + step * k as f64;
            // The last node is the shock, eta = 0, exactly.
            eta = if k + 1 == TABLE_NODES {
                0.0
            } else {
                family.eta_at(target, eta)
            };
            let p = family.at(eta);
            let node = Node {
                value: [p.ln_f, p.ln_g, p.ln_h],
                slope: [
                    p.d_ln_f / p.d_ln_lambda,
                    p.d_ln_g / p.d_ln_lambda,
                    p.d_ln_h / p.d_ln_lambda,
                ],
            };
            let finite = node.value.iter().chain(&node.slope).all(|x| x.is_finite());
            if !(finite && p.d_ln_lambda > 0.0 && node.slope[1] >= 0.0) {
                return None;
            }
            nodes.push(node);
        }
        Some(Self {
            nodes,
            step,
            central_slope: [1.0, family.j / (family.gamma - 1.0), 0.0],
        })
    }

    /// `[f, g, h]` at `ln lambda` (clamped to the shock for positive values).
    fn eval(&self, ln_lambda: f64) -> [f64; 3] {
        let offset = ln_lambda - TABLE_LN_LAMBDA_MIN;
        if offset < 0.0 {
            // Central power laws; an infinite offset (r = 0) gives f = g = 0, finite h.
            let first = &self.nodes[0];
            return std::array::from_fn(|i| {
                let tail = if self.central_slope[i] == 0.0 {
                    0.0
                } else {
                    self.central_slope[i] * offset
                };
                (first.value[i] + tail).exp()
            });
        }
        let x = offset / self.step;
        let k = (x as usize).min(TABLE_NODES - 2);
        let t = (x - k as f64).min(1.0);
        let (n0, n1) = (&self.nodes[k], &self.nodes[k + 1]);
        // Cubic Hermite basis on [0, 1].
        let t2 = t * t;
        let t3 = t2 * t;
        let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
        let h10 = t3 - 2.0 * t2 + t;
        let h01 = -2.0 * t3 + 3.0 * t2;
        let h11 = t3 - t2;
        std::array::from_fn(|i| {
            (h00 * n0.value[i]
                + h10 * self.step * n0.slope[i]
                + h01 * n1.value[i]
                + h11 * self.step * n1.slope[i])
                .exp()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed forms meet the shock values f = g = h = lambda = 1 at eta = 0.
    #[test]
    fn shock_point_is_unity() {
        for (gamma, j) in [(5.0 / 3.0, 3), (1.4, 1), (1.4, 2), (3.0, 3)] {
            let p = Family::new(gamma, j).at(0.0);
            for x in [p.ln_lambda, p.ln_f, p.ln_g, p.ln_h] {
                assert!(x.abs() < 1e-14, "gamma {gamma} j {j}: {p:?}");
            }
        }
    }

    /// The analytic eta-derivatives match finite differences.
    #[test]
    fn derivatives_match_finite_differences() {
        let family = Family::new(1.4, 3);
        for eta in [-20.0, -3.0, -0.5, -1e-3] {
            let h = 1e-6;
            let (p, lo, hi) = (family.at(eta), family.at(eta - h), family.at(eta + h));
            let fd = |a: f64, b: f64| (b - a) / (2.0 * h);
            assert!((fd(lo.ln_lambda, hi.ln_lambda) - p.d_ln_lambda).abs() < 1e-7);
            assert!((fd(lo.ln_f, hi.ln_f) - p.d_ln_f).abs() < 1e-7);
            assert!((fd(lo.ln_g, hi.ln_g) - p.d_ln_g).abs() < 1e-7);
            assert!((fd(lo.ln_h, hi.ln_h) - p.d_ln_h).abs() < 1e-7);
        }
    }

    /// Table interpolation agrees with the closed forms between nodes.
    #[test]
    fn table_matches_closed_forms() {
        let family = Family::new(5.0 / 3.0, 3);
        let profile = Profile::new(&family).unwrap();
        for k in 1..200 {
            let target = TABLE_LN_LAMBDA_MIN * (k as f64 / 200.0).powi(3);
            let p = family.at(family.eta_at(target, target / -family.a2));
            assert!((p.ln_lambda - target).abs() < 1e-12);
            let table = profile.eval(target);
            let exact = [p.ln_f.exp(), p.ln_g.exp(), p.ln_h.exp()];
            for i in 0..3 {
                let rel = (table[i] / exact[i] - 1.0).abs();
                assert!(rel < 1e-10, "ln lambda {target}: {table:?} vs {exact:?}");
            }
        }
    }
}
