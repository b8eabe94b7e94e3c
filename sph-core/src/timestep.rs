//! The global time step.

use crate::momentum::MomentumStats;

/// Time-step criteria (`docs/physics.md`): Courant, density change, acceleration,
/// falling internal energy, growth limit.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
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
    /// Length `eps` of the acceleration criterion where gravity is not
    /// softened (SPH-EXA's 0.005). With softened gravity each particle's
    /// `eps` is its own softening length, so the criterion follows the
    /// resolution (as GADGET's and SWIFT's do).
    pub eps_acc: f64,
    /// Factor `k_u` of the energy criterion `k_u min u_i / |du_i/dt|` over
    /// the particles whose internal energy falls: at first order no step
    /// takes more than this fraction of a particle's `u`. Adiabatic
    /// expansion gives `|du/dt| / u = (gamma - 1) |div v|`, which the
    /// density-change criterion already bounds more tightly; this one
    /// catches pressure work that outruns it (a cold clump far below the
    /// resolution of its surroundings) before `u` turns negative.
    pub k_u: f64,
    /// How the first step relates to the given first time step `dt0`.
    pub first_step: FirstStep,
    /// Block time steps: the longest step a particle may take, or `None`
    /// for a quarter of the run's span (the cold gas of a blast costs
    /// `span / dt_max` updates per particle; the limiter wakes it before
    /// the front arrives).
    pub dt_max: Option<f64>,
    /// Block time steps: the limiter (Saitoh & Makino 2009). No
    /// particle's bin is more than `limiter_delta` above its
    /// neighbours': a new bin is capped by the neighbours' bins, and an
    /// active particle wakes neighbours whose steps are longer than
    /// `2^limiter_delta` times its new one.
    pub limiter: bool,
    /// Bins a particle may sit above its neighbours (2: a factor 4).
    pub limiter_delta: u8,
}

/// How particles share time steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum TimeSteps {
    /// One step for all, the smallest any particle needs (the
    /// Press / Adams-Bashforth integrator of the seed paper and SPH-EXA).
    #[default]
    Global,
    /// Each particle its own power-of-two fraction of a longest step
    /// (block time steps), with the same integrator's formulas over each
    /// particle's own step; inactive particles drift.
    Block,
    /// The block-step integrator with every particle in the smallest bin
    /// any needs: what block steps change against one step for all,
    /// without the bins.
    Kdk,
}

impl TimeSteps {
    /// Whether particles step on the integer time line (block or kdk).
    pub fn on_time_line(self) -> bool {
        self != TimeSteps::Global
    }
}

/// `--time-steps` and the `time-steps` key.
impl crate::Choice for TimeSteps {
    const ALL: &'static [Self] = &[TimeSteps::Global, TimeSteps::Block, TimeSteps::Kdk];

    fn name(&self) -> &'static str {
        match self {
            TimeSteps::Global => "global",
            TimeSteps::Block => "block",
            TimeSteps::Kdk => "kdk",
        }
    }

    fn help(&self) -> &'static str {
        match self {
            TimeSteps::Global => {
                "One time step for every particle, the smallest any needs (the seed paper's \
                 and SPH-EXA's integrator)"
            }
            TimeSteps::Block => {
                "Each particle its own power-of-two fraction of a longest step, with a limiter \
                 (block time steps; every scheme, equation of state and driving)"
            }
            TimeSteps::Kdk => {
                "The block-step integrator with every particle in the smallest bin any needs \
                 (to tell what the bins change)"
            }
        }
    }
}

/// The first step of a run: held to `max_growth * dt0`, from which the
/// steps grow by `max_growth` each until a criterion takes over (SPH-EXA's
/// start: its Sedov begins at `dt0 = 1e-6` and spends about 60 steps
/// growing), or the criteria's step at once. Either way `dt0` is the
/// integrator's previous step (the first velocity update reads
/// `v_0 + a_0 dt0 / 2`). A resumed run continues from its checkpoint.
///
/// Under block time steps the ramp is that of the global run in time,
/// `dt <= (max_growth - 1) (t - t0) + dt0` (the global ramp's step at
/// `t`), but it holds no particle more than the limiter's factor below
/// its own criteria: a blast's hot centre starts two bins down and
/// catches up as the ramp grows, the cold gas keeps its long steps
/// (measured: Sedov 12^3 at Courant 0.5 / 1.0 energy drift 2.7e-3 /
/// 3.0e-3 against 1.2e-2 / 2.6e-2 without it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum FirstStep {
    /// At most `max_growth * dt0`.
    #[default]
    Ramp,
    /// The criteria's step (Courant, density change, acceleration,
    /// falling internal energy).
    Criteria,
}

/// `--first-step` and the `first-step` key.
impl crate::Choice for FirstStep {
    const ALL: &'static [Self] = &[FirstStep::Ramp, FirstStep::Criteria];

    fn name(&self) -> &'static str {
        match self {
            FirstStep::Ramp => "ramp",
            FirstStep::Criteria => "criteria",
        }
    }

    fn help(&self) -> &'static str {
        match self {
            FirstStep::Ramp => {
                "At most 1.1 times the case's first dt, growing by 1.1 per step until a \
                 time-step criterion takes over (SPH-EXA's start); under block steps the same \
                 ramp in time, holding no particle more than the limiter's factor below its \
                 criteria"
            }
            FirstStep::Criteria => {
                "The time-step criteria's step at once (Courant, density change, acceleration, \
                 falling internal energy)"
            }
        }
    }
}

impl Default for TimestepParams {
    fn default() -> Self {
        Self {
            k_courant: 0.2,
            k_rho: 0.06,
            max_growth: 1.1,
            eta_acc: 0.2,
            eps_acc: 0.005,
            k_u: 0.5,
            first_step: FirstStep::Ramp,
            dt_max: None,
            limiter: true,
            limiter_delta: 2,
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
    /// Falling internal energy: `k_u min u / |du/dt|`.
    Energy,
    /// Growth limit: `max_growth * dt_prev`.
    Growth,
    /// A cap from outside (an output or end time).
    Cap,
    /// Block time steps: the nearest end of a particle's own step.
    StepEnd,
}

impl DtLimit {
    /// Every limit, in the order above.
    pub const ALL: [DtLimit; 7] = [
        DtLimit::Courant,
        DtLimit::Divergence,
        DtLimit::Acceleration,
        DtLimit::Energy,
        DtLimit::Growth,
        DtLimit::Cap,
        DtLimit::StepEnd,
    ];

    /// Short lower-case name (for tables).
    pub fn name(self) -> &'static str {
        match self {
            DtLimit::Courant => "courant",
            DtLimit::Divergence => "divergence",
            DtLimit::Acceleration => "acceleration",
            DtLimit::Energy => "energy",
            DtLimit::Growth => "growth",
            DtLimit::Cap => "cap",
            DtLimit::StepEnd => "step-end",
        }
    }
}

impl TimestepParams {
    /// The limiter's factor, `2^limiter_delta`: how many times longer
    /// than its neighbours' a particle's step may be (and how far below
    /// its own criteria the start ramp may hold it).
    ///
    /// ```
    /// let ts = sph_core::TimestepParams::default();
    /// assert_eq!(ts.limiter_factor(), 4);
    /// ```
    pub fn limiter_factor(&self) -> u32 {
        1u32 << self.limiter_delta.min(31)
    }

    /// `dt = min(Kcour min h/v_sig, Krho / max|div v|, eta / sqrt(max |a|/eps),
    /// k_u / max(-du/dt / u), growth * dt_prev)`, from stats already
    /// reduced over all particles (and ranks); `max_acc` (the largest
    /// [`acc_per_length`](Self::acc_per_length)) is zero when the
    /// acceleration criterion is off, `max_cooling` (the largest
    /// `-du_i/dt / u_i` over particles with `u_i > 0`) zero when no
    /// internal energy falls or the equation of state ignores `u`.
    pub fn dt(&self, stats: &MomentumStats, max_acc: f64, max_cooling: f64, dt_prev: f64) -> f64 {
        self.dt_limited(stats, max_acc, max_cooling, dt_prev).0
    }

    /// [`dt`](Self::dt) and the criterion that set it (the first of
    /// [`DtLimit::ALL`] on a tie).
    ///
    /// ```
    /// use sph_core::momentum::MomentumStats;
    /// use sph_core::timestep::{DtLimit, TimestepParams};
    /// let p = TimestepParams::default();
    /// let s = MomentumStats { min_h_over_vsig: 1.0, max_abs_div_v: 0.0 };
    /// assert_eq!(p.dt_limited(&s, 0.0, 0.0, 1.0), (0.2, DtLimit::Courant));
    /// assert_eq!(p.dt_limited(&s, 0.0, 0.0, 0.1).1, DtLimit::Growth);
    /// // A particle losing 10 times its u per unit time: at most k_u / 10.
    /// assert_eq!(p.dt_limited(&s, 0.0, 10.0, 1.0), (0.05, DtLimit::Energy));
    /// ```
    pub fn dt_limited(
        &self,
        stats: &MomentumStats,
        max_acc: f64,
        max_cooling: f64,
        dt_prev: f64,
    ) -> (f64, DtLimit) {
        let [courant, div, acc, energy] = self.criteria(
            stats.min_h_over_vsig,
            stats.max_abs_div_v,
            max_acc,
            max_cooling,
        );
        let dt = courant
            .min(div)
            .min(acc)
            .min(energy)
            .min(self.max_growth * dt_prev);
        let limit = [
            (courant, DtLimit::Courant),
            (div, DtLimit::Divergence),
            (acc, DtLimit::Acceleration),
            (energy, DtLimit::Energy),
        ]
        .into_iter()
        .find(|&(v, _)| v == dt)
        .map_or(DtLimit::Growth, |(_, l)| l);
        (dt, limit)
    }

    /// The steps the four criteria allow, `[courant, divergence,
    /// acceleration, energy]`, from `h / v_sig`, `|div v|` (the
    /// compression the scheme's form counts), `|a| / eps` (0: criterion
    /// off) and `-du/dt / u` (0: not falling): of one particle, or the
    /// extremes over all.
    fn criteria(&self, h_over_vsig: f64, abs_div_v: f64, acc: f64, cooling: f64) -> [f64; 4] {
        let courant = self.k_courant * h_over_vsig;
        let div = if abs_div_v > 0.0 {
            self.k_rho / abs_div_v
        } else {
            f64::INFINITY
        };
        let acc = if acc > 0.0 {
            self.eta_acc / acc.sqrt()
        } else {
            f64::INFINITY
        };
        let energy = if cooling > 0.0 {
            self.k_u / cooling
        } else {
            f64::INFINITY
        };
        [courant, div, acc, energy]
    }

    /// One particle's own step: the smallest of the criteria of
    /// [`dt_limited`](Self::dt_limited) with its own `h / v_sig`,
    /// compression `|div v|`, `|a| / eps` ([`acc_per_length`](Self::acc_per_length);
    /// 0 without the acceleration criterion) and cooling rate `-du/dt / u` (0 unless falling); no growth limit.
    /// The global step is at most every particle's.
    ///
    /// ```
    /// use sph_core::timestep::TimestepParams;
    /// let p = TimestepParams::default();
    /// assert_eq!(p.particle_dt(1.0, 0.0, 0.0, 0.0), 0.2);
    /// assert_eq!(p.particle_dt(1.0, 1.0, 0.0, 0.0), 0.06);
    /// ```
    pub fn particle_dt(&self, h_over_vsig: f64, abs_div_v: f64, acc: f64, cooling: f64) -> f64 {
        let [courant, div, acc, energy] = self.criteria(h_over_vsig, abs_div_v, acc, cooling);
        courant.min(div).min(acc).min(energy)
    }

    /// `|a| / eps`, what the acceleration criterion `eta sqrt(eps / |a|)`
    /// reads: `eps` the particle's gravitational softening length where
    /// gravity is softened, else [`eps_acc`](Self::eps_acc).
    ///
    /// ```
    /// use sph_core::timestep::TimestepParams;
    /// let p = TimestepParams::default();
    /// // Softened within 0.1: eta sqrt(0.1 / 10) = 0.02.
    /// assert!((p.particle_dt(1.0, 0.0, p.acc_per_length(10.0, Some(0.1)), 0.0) - 0.02).abs() < 1e-15);
    /// assert_eq!(p.acc_per_length(10.0, None), 10.0 / p.eps_acc);
    /// ```
    pub fn acc_per_length(&self, acc: f64, softening_length: Option<f64>) -> f64 {
        acc / softening_length.unwrap_or(self.eps_acc)
    }

    /// The previous step the growth limit of step `step` (1 for the
    /// first) compares with: `dt_prev`, or none (infinite) on the first
    /// step with [`FirstStep::Criteria`].
    ///
    /// ```
    /// use sph_core::timestep::{FirstStep, TimestepParams};
    /// let ramp = TimestepParams::default();
    /// assert_eq!(ramp.growth_base(1, 1e-6), 1e-6);
    /// let mut free = ramp;
    /// free.first_step = FirstStep::Criteria;
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
