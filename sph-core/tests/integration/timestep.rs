//! Invariants of the global time step's criteria.

use proptest::prelude::*;
use sph_core::momentum::MomentumStats;
use sph_core::timestep::{DtLimit, TimestepParams};

proptest! {
    /// The step is the smallest criterion: no larger than any of them,
    /// equal to the one it names; with the energy criterion, a particle
    /// losing u at `rate` per unit time keeps at least `1 - k_u` of it
    /// at first order, and a run where no u falls (rate 0) has the same
    /// step as without the criterion.
    #[test]
    fn the_step_is_the_tightest_criterion(
        h_over_vsig in 1e-6f64..1e3,
        div in 0.0f64..1e4,
        // |a| / eps, what the acceleration criterion reads.
        acc in 0.0f64..1e6,
        rate in 0.0f64..1e6,
        dt_prev in 1e-9f64..1e2,
    ) {
        let p = TimestepParams::default();
        let s = MomentumStats { min_h_over_vsig: h_over_vsig, max_abs_div_v: div };
        let (dt, limit) = p.dt_limited(&s, acc, rate, dt_prev);
        prop_assert!(dt > 0.0 && dt.is_finite());
        prop_assert!(dt <= p.k_courant * h_over_vsig);
        prop_assert!(dt <= p.max_growth * dt_prev);
        if div > 0.0 {
            prop_assert!(dt <= p.k_rho / div);
        }
        if acc > 0.0 {
            prop_assert!(dt <= p.eta_acc / acc.sqrt());
        }
        if rate > 0.0 {
            prop_assert!(1.0 - dt * rate >= 1.0 - p.k_u - 1e-12);
        }
        let named = match limit {
            DtLimit::Courant => p.k_courant * h_over_vsig,
            DtLimit::Divergence => p.k_rho / div,
            DtLimit::Acceleration => p.eta_acc / acc.sqrt(),
            DtLimit::Energy => p.k_u / rate,
            DtLimit::Growth => p.max_growth * dt_prev,
            DtLimit::Cap | DtLimit::StepEnd => unreachable!("dt_limited never caps"),
        };
        prop_assert_eq!(dt, named);
        let without = p.dt_limited(&s, acc, 0.0, dt_prev);
        if limit != DtLimit::Energy {
            prop_assert_eq!((dt, limit), without);
        }
    }
}
