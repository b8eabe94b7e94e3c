//! The exact solution of the Riemann problem of gas dynamics (ideal gas,
//! any gamma): two uniform states meeting at a plane at t = 0.
//!
//! The star-region pressure solves `f_L(p) + f_R(p) + u_R - u_L = 0`, with
//! shock branches (Rankine-Hugoniot) and rarefaction branches (isentropic)
//! of `f_K`, by Newton's method from the two-rarefaction guess; the
//! solution is then sampled along `xi = x / t` (Toro, *Riemann Solvers and
//! Numerical Methods for Fluid Dynamics*, ch. 4, whose Test 1 values the
//! tests reproduce).

use super::{check_density, check_gamma, FlowState, ReferenceError};

/// One uniform side of the problem.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GasState {
    /// Density.
    pub rho: f64,
    /// Velocity along the tube (positive to the right).
    pub v: f64,
    /// Pressure.
    pub p: f64,
}

/// The solved Riemann problem.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Riemann {
    gamma: f64,
    left: GasState,
    right: GasState,
    c_left: f64,
    c_right: f64,
    p_star: f64,
    v_star: f64,
}

/// The waves of the solution, as speeds (positions at `t = 1`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Waves {
    /// Left-going shock speed, or the rarefaction head if the left wave is one.
    pub left_head: f64,
    /// End of the left wave (= `left_head` for a shock).
    pub left_tail: f64,
    /// The contact discontinuity.
    pub contact: f64,
    /// Start of the right wave (= `right_head` for a shock).
    pub right_tail: f64,
    /// Right-going shock speed, or the rarefaction head.
    pub right_head: f64,
}

impl Riemann {
    /// Solves the problem of `left` (x < 0) and `right` (x > 0) states.
    ///
    /// # Errors
    /// A bad gamma, a density or pressure that is not finite and positive,
    /// or a pair of states that opens a vacuum (no star region).
    pub fn new(gamma: f64, left: GasState, right: GasState) -> Result<Self, ReferenceError> {
        check_gamma(gamma)?;
        for s in [left, right] {
            check_density(s.rho)?;
            if !(s.p.is_finite() && s.p > 0.0) {
                return Err(ReferenceError::InvalidPressure { p: s.p });
            }
            if !s.v.is_finite() {
                return Err(ReferenceError::InvalidVelocity { v: s.v });
            }
        }
        let sound = |s: GasState| (gamma * s.p / s.rho).sqrt();
        let (c_left, c_right) = (sound(left), sound(right));
        if 2.0 / (gamma - 1.0) * (c_left + c_right) <= right.v - left.v {
            return Err(ReferenceError::Vacuum);
        }
        let mut r = Self {
            gamma,
            left,
            right,
            c_left,
            c_right,
            p_star: 0.0,
            v_star: 0.0,
        };
        r.p_star = r.solve_pressure();
        let (fl, _) = r.f_side(r.p_star, left, c_left);
        let (fr, _) = r.f_side(r.p_star, right, c_right);
        r.v_star = 0.5 * (left.v + right.v) + 0.5 * (fr - fl);
        Ok(r)
    }

    /// Pressure between the two waves.
    pub fn p_star(&self) -> f64 {
        self.p_star
    }

    /// Velocity between the two waves (of the contact).
    pub fn v_star(&self) -> f64 {
        self.v_star
    }

    /// Densities left and right of the contact, in the star region.
    pub fn rho_star(&self) -> (f64, f64) {
        (self.star_density(self.left), self.star_density(self.right))
    }

    /// Speeds of the wave fronts.
    pub fn waves(&self) -> Waves {
        let (g, ps) = (self.gamma, self.p_star);
        let (l, r) = (self.left, self.right);
        let (left_head, left_tail) = if ps > l.p {
            let s = l.v - self.c_left * self.shock_factor(ps / l.p);
            (s, s)
        } else {
            let c_star = self.c_left * (ps / l.p).powf((g - 1.0) / (2.0 * g));
            (l.v - self.c_left, self.v_star - c_star)
        };
        let (right_head, right_tail) = if ps > r.p {
            let s = r.v + self.c_right * self.shock_factor(ps / r.p);
            (s, s)
        } else {
            let c_star = self.c_right * (ps / r.p).powf((g - 1.0) / (2.0 * g));
            (r.v + self.c_right, self.v_star + c_star)
        };
        Waves {
            left_head,
            left_tail,
            contact: self.v_star,
            right_tail,
            right_head,
        }
    }

    /// The state at position `x` (the states met at `x = 0`) and time `t`;
    /// the initial states for `t <= 0`. `v` of the result is the velocity
    /// along the tube, `u` the specific internal energy.
    pub fn state(&self, x: f64, t: f64) -> FlowState {
        if x.is_nan() || t.is_nan() {
            return FlowState::NAN;
        }
        let g = self.gamma;
        let s = if t > 0.0 {
            self.sample(x / t)
        } else if x < 0.0 {
            self.left
        } else {
            self.right
        };
        FlowState {
            rho: s.rho,
            p: s.p,
            v: s.v,
            u: s.p / ((g - 1.0) * s.rho),
        }
    }

    /// The state on the ray `x / t = xi`.
    fn sample(&self, xi: f64) -> GasState {
        let g = self.gamma;
        let w = self.waves();
        let (l, r) = (self.left, self.right);
        if xi <= self.v_star {
            if xi <= w.left_head {
                l
            } else if xi >= w.left_tail {
                self.star(l)
            } else {
                // Inside the left fan.
                let c = 2.0 / (g + 1.0) * (self.c_left + 0.5 * (g - 1.0) * (l.v - xi));
                self.fan(l, self.c_left, c, xi)
            }
        } else if xi >= w.right_head {
            r
        } else if xi <= w.right_tail {
            self.star(r)
        } else {
            let c = 2.0 / (g + 1.0) * (self.c_right - 0.5 * (g - 1.0) * (r.v - xi));
            self.fan(r, self.c_right, c, xi)
        }
    }

    /// The isentropic state of a fan with sound speed `c` on the ray `xi`.
    fn fan(&self, side: GasState, c_side: f64, c: f64, xi: f64) -> GasState {
        let g = self.gamma;
        let ratio = c / c_side;
        GasState {
            rho: side.rho * ratio.powf(2.0 / (g - 1.0)),
            v: xi + if xi < self.v_star { c } else { -c },
            p: side.p * ratio.powf(2.0 * g / (g - 1.0)),
        }
    }

    fn star(&self, side: GasState) -> GasState {
        GasState {
            rho: self.star_density(side),
            v: self.v_star,
            p: self.p_star,
        }
    }

    fn star_density(&self, side: GasState) -> f64 {
        let g = self.gamma;
        let ratio = self.p_star / side.p;
        if ratio > 1.0 {
            let k = (g - 1.0) / (g + 1.0);
            side.rho * (ratio + k) / (k * ratio + 1.0)
        } else {
            side.rho * ratio.powf(1.0 / g)
        }
    }

    /// Shock speed relative to the gas, in units of its sound speed.
    fn shock_factor(&self, ratio: f64) -> f64 {
        let g = self.gamma;
        ((g + 1.0) / (2.0 * g) * ratio + (g - 1.0) / (2.0 * g)).sqrt()
    }

    /// `f_K(p)` and its derivative for one side.
    fn f_side(&self, p: f64, s: GasState, c: f64) -> (f64, f64) {
        let g = self.gamma;
        if p > s.p {
            let a = 2.0 / ((g + 1.0) * s.rho);
            let b = (g - 1.0) / (g + 1.0) * s.p;
            let q = (a / (p + b)).sqrt();
            ((p - s.p) * q, q * (1.0 - 0.5 * (p - s.p) / (p + b)))
        } else {
            let e = (g - 1.0) / (2.0 * g);
            let ratio = p / s.p;
            (
                2.0 * c / (g - 1.0) * (ratio.powf(e) - 1.0),
                ratio.powf(-(g + 1.0) / (2.0 * g)) / (s.rho * c),
            )
        }
    }

    /// Newton iteration for the star pressure from the two-rarefaction
    /// guess (exact when both waves are rarefactions).
    fn solve_pressure(&self) -> f64 {
        let g = self.gamma;
        let (l, r) = (self.left, self.right);
        let e = (g - 1.0) / (2.0 * g);
        let guess = ((self.c_left + self.c_right - 0.5 * (g - 1.0) * (r.v - l.v))
            / (self.c_left / l.p.powf(e) + self.c_right / r.p.powf(e)))
        .powf(1.0 / e);
        let mut p = guess.max(1e-12 * l.p.min(r.p));
        for _ in 0..100 {
            let (fl, dl) = self.f_side(p, l, self.c_left);
            let (fr, dr) = self.f_side(p, r, self.c_right);
            let next = (p - (fl + fr + r.v - l.v) / (dl + dr)).max(1e-3 * p);
            let change = 2.0 * (next - p).abs() / (next + p);
            p = next;
            if change < 1e-15 {
                break;
            }
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sod(gamma: f64) -> Riemann {
        let left = GasState {
            rho: 1.0,
            v: 0.0,
            p: 1.0,
        };
        let right = GasState {
            rho: 0.125,
            v: 0.0,
            p: 0.1,
        };
        Riemann::new(gamma, left, right).unwrap()
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs()
    }

    /// Toro's Test 1 (Sod, gamma = 1.4), table 4.3: p* = 0.30313,
    /// u* = 0.92745, rho*L = 0.42632, rho*R = 0.26557.
    #[test]
    fn toro_test_one() {
        let r = sod(1.4);
        assert!(close(r.p_star(), 0.30313, 2e-5), "{}", r.p_star());
        assert!(close(r.v_star(), 0.92745, 2e-5), "{}", r.v_star());
        let (dl, dr) = r.rho_star();
        assert!(close(dl, 0.42632, 2e-5), "{dl}");
        assert!(close(dr, 0.26557, 2e-5), "{dr}");
    }

    /// The gamma = 5/3 values of the project's validation table (computed
    /// independently): p* = 0.29395, u* = 0.84119, rho*L = 0.47969,
    /// rho*R = 0.22981, shock at +0.3689 at t = 0.2.
    #[test]
    fn validation_table_gamma_five_thirds() {
        let r = sod(5.0 / 3.0);
        assert!(close(r.p_star(), 0.29395, 2e-5), "{}", r.p_star());
        assert!(close(r.v_star(), 0.84119, 2e-5), "{}", r.v_star());
        let (dl, dr) = r.rho_star();
        assert!(close(dl, 0.47969, 2e-5), "{dl}");
        assert!(close(dr, 0.22981, 2e-5), "{dr}");
        assert!(close(0.2 * r.waves().right_head, 0.3689, 2e-4));
    }

    /// Toro's Test 2 (123 problem): two rarefactions, p* = 0.00189,
    /// u* = 0, rho* = 0.02185.
    #[test]
    fn toro_test_two_rarefactions() {
        let left = GasState {
            rho: 1.0,
            v: -2.0,
            p: 0.4,
        };
        let right = GasState {
            rho: 1.0,
            v: 2.0,
            p: 0.4,
        };
        let r = Riemann::new(1.4, left, right).unwrap();
        assert!(close(r.p_star(), 0.00189, 3e-3), "{}", r.p_star());
        assert!(r.v_star().abs() < 1e-12);
        assert!(close(r.rho_star().0, 0.02185, 3e-3));
    }

    #[test]
    fn vacuum_and_bad_states_are_errors() {
        let left = GasState {
            rho: 1.0,
            v: -20.0,
            p: 0.4,
        };
        let right = GasState {
            rho: 1.0,
            v: 20.0,
            p: 0.4,
        };
        assert_eq!(Riemann::new(1.4, left, right), Err(ReferenceError::Vacuum));
        let bad = GasState {
            rho: 1.0,
            v: 0.0,
            p: -1.0,
        };
        assert!(Riemann::new(1.4, bad, right).is_err());
        let bad = GasState {
            rho: 0.0,
            v: 0.0,
            p: 1.0,
        };
        assert!(Riemann::new(1.4, bad, right).is_err());
        assert!(Riemann::new(1.0, left, right).is_err());
    }

    /// Across the solution: mass, momentum and energy fluxes balance the
    /// change of the totals (a check of the sampled profile as a whole,
    /// independent of the star-state formulas).
    #[test]
    fn sampled_profile_conserves_mass_momentum_energy() {
        let g = 5.0 / 3.0;
        let r = sod(g);
        let t = 0.2;
        let (a, b, n) = (-1.0, 1.0, 200_000);
        let dx = (b - a) / n as f64;
        let mut tot = [0.0f64; 3];
        let mut tot0 = [0.0f64; 3];
        for k in 0..n {
            let x = a + (k as f64 + 0.5) * dx;
            for (sum, s) in [(&mut tot, r.state(x, t)), (&mut tot0, r.state(x, 0.0))] {
                sum[0] += s.rho * dx;
                sum[1] += s.rho * s.v * dx;
                sum[2] += (0.5 * s.rho * s.v * s.v + s.p / (g - 1.0)) * dx;
            }
        }
        // Nothing reaches x = +-1 by t = 0.2; the states at rest exert
        // the boundary pressures 1 and 0.1 on the momentum.
        assert!((tot[0] - tot0[0]).abs() < 1e-4, "mass {tot:?} {tot0:?}");
        let dp = t * (1.0 - 0.1);
        assert!((tot[1] - tot0[1] - dp).abs() < 1e-4, "momentum {tot:?}");
        assert!((tot[2] - tot0[2]).abs() < 1e-4, "energy {tot:?} {tot0:?}");
    }

    #[test]
    fn fan_is_continuous_at_its_edges() {
        let r = sod(1.4);
        let w = r.waves();
        let t = 0.25;
        for x in [w.left_head * t, w.left_tail * t] {
            let (a, b) = (r.state(x - 1e-9, t), r.state(x + 1e-9, t));
            assert!((a.rho - b.rho).abs() < 1e-6 && (a.p - b.p).abs() < 1e-6);
            assert!((a.v - b.v).abs() < 1e-6);
        }
    }
}
