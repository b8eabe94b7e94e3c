//! The global time step.

use crate::momentum::MomentumStats;

/// Time-step criteria (PHYSICS.md): Courant, density change, growth limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimestepParams {
    /// Courant factor on `h / v_sig`.
    pub k_courant: f64,
    /// Factor on `1 / |div v|`.
    pub k_rho: f64,
    /// Largest growth factor from one step to the next.
    pub max_growth: f64,
    /// Factor `eta` of the acceleration criterion `eta sqrt(eps / |a|)`
    /// (used when the run has self-gravity).
    pub eta_acc: f64,
    /// Length `eps` of the acceleration criterion.
    pub eps_acc: f64,
    /// How the first step relates to the given first time step `dt0`.
    pub first_step: FirstStep,
}

/// The first step of a run: held to `max_growth * dt0`, from which the
/// steps grow by `max_growth` each until a criterion takes over (SPH-EXA's
/// start: its Sedov begins at `dt0 = 1e-6` and spends about 60 steps
/// growing), or the criteria's step at once. Either way `dt0` is the
/// integrator's previous step (the first velocity update reads
/// `v_0 + a_0 dt0 / 2`). A resumed run continues from its checkpoint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FirstStep {
    /// At most `max_growth * dt0`.
    #[default]
    Ramp,
    /// The criteria's step (Courant, density change, acceleration).
    Criteria,
}

impl Default for TimestepParams {
    fn default() -> Self {
        Self {
            k_courant: 0.2,
            k_rho: 0.06,
            max_growth: 1.1,
            eta_acc: 0.2,
            eps_acc: 0.005,
            first_step: FirstStep::Ramp,
        }
    }
}

/// Which criterion set a step's `dt`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum DtLimit {
    /// Courant: `Kcour min h / v_sig`.
    Courant,
    /// Density change: `Krho / max |div v|`.
    Divergence,
    /// Acceleration: `eta sqrt(eps / max |a|)`.
    Acceleration,
    /// Growth limit: `max_growth * dt_prev`.
    Growth,
    /// A cap from outside (an output or end time).
    Cap,
}

impl DtLimit {
    /// Every limit, in the order above.
    pub const ALL: [DtLimit; 5] = [
        DtLimit::Courant,
        DtLimit::Divergence,
        DtLimit::Acceleration,
        DtLimit::Growth,
        DtLimit::Cap,
    ];

    /// Short lower-case name (for tables).
    pub fn name(self) -> &'static str {
        match self {
            DtLimit::Courant => "courant",
            DtLimit::Divergence => "divergence",
            DtLimit::Acceleration => "acceleration",
            DtLimit::Growth => "growth",
            DtLimit::Cap => "cap",
        }
    }
}

impl TimestepParams {
    /// `dt = min(Kcour min h/v_sig, Krho / max|div v|, eta sqrt(eps/max|a|),
    /// growth * dt_prev)`, from stats already reduced over all particles
    /// (and ranks); `max_acc` is zero when the acceleration criterion is off.
    pub fn dt(&self, stats: &MomentumStats, max_acc: f64, dt_prev: f64) -> f64 {
        self.dt_limited(stats, max_acc, dt_prev).0
    }

    /// [`dt`](Self::dt) and the criterion that set it (the first of
    /// [`DtLimit::ALL`] on a tie).
    ///
    /// ```
    /// use sph_core::momentum::MomentumStats;
    /// use sph_core::timestep::{DtLimit, TimestepParams};
    /// let p = TimestepParams::default();
    /// let s = MomentumStats { min_h_over_vsig: 1.0, max_abs_div_v: 0.0 };
    /// assert_eq!(p.dt_limited(&s, 0.0, 1.0), (0.2, DtLimit::Courant));
    /// assert_eq!(p.dt_limited(&s, 0.0, 0.1).1, DtLimit::Growth);
    /// ```
    pub fn dt_limited(&self, stats: &MomentumStats, max_acc: f64, dt_prev: f64) -> (f64, DtLimit) {
        let courant = self.k_courant * stats.min_h_over_vsig;
        let div = if stats.max_abs_div_v > 0.0 {
            self.k_rho / stats.max_abs_div_v
        } else {
            f64::INFINITY
        };
        let acc = if max_acc > 0.0 {
            self.eta_acc * (self.eps_acc / max_acc).sqrt()
        } else {
            f64::INFINITY
        };
        let dt = courant.min(div).min(acc).min(self.max_growth * dt_prev);
        let limit = [
            (courant, DtLimit::Courant),
            (div, DtLimit::Divergence),
            (acc, DtLimit::Acceleration),
        ]
        .into_iter()
        .find(|&(v, _)| v == dt)
        .map_or(DtLimit::Growth, |(_, l)| l);
        (dt, limit)
    }

    /// The previous step the growth limit of step `step` (1 for the
    /// first) compares with: `dt_prev`, or none (infinite) on the first
    /// step with [`FirstStep::Criteria`].
    ///
    /// ```
    /// use sph_core::timestep::{FirstStep, TimestepParams};
    /// let ramp = TimestepParams::default();
    /// assert_eq!(ramp.growth_base(1, 1e-6), 1e-6);
    /// let free = TimestepParams { first_step: FirstStep::Criteria, ..ramp };
    /// assert_eq!(free.growth_base(1, 1e-6), f64::INFINITY);
    /// assert_eq!(free.growth_base(2, 1e-6), 1e-6);
    /// ```
    pub fn growth_base(&self, step: u64, dt_prev: f64) -> f64 {
        match self.first_step {
            FirstStep::Criteria if step == 1 => f64::INFINITY,
            _ => dt_prev,
        }
    }
}
