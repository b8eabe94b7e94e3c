//! Every kernel integrates to 1 in 3-D; reference values of the norms.

mod common;

use std::f64::consts::PI;

use proptest::prelude::*;
use sph_kernels::{normalisation, CubicSpline, Kernel, Sinc, WendlandC2, WendlandC4, WendlandC6};

/// SPHYNX's fit of K_n (Cabezón et al.), quoted in `docs/physics.md`.
fn sphynx_fit(n: f64) -> f64 {
    let (b0, b1, b2, b3) = (2.7012593e-2, 2.0410827e-2, 3.7451957e-3, 4.7013839e-2);
    b0 + b1 * n.sqrt() + b2 * n + b3 * n.powf(1.5)
}

#[test]
fn every_builtin_kernel_integrates_to_one() {
    for (name, kernel) in common::analytic_kernels() {
        let mass = common::mass(kernel.as_ref());
        assert!((mass - 1.0).abs() < 1e-10, "{name}: mass {mass}");
    }
}

#[test]
fn extreme_sinc_exponents_integrate_to_one() {
    for n in [1.0, 1.01, 2.5, 100.0, 1000.0] {
        let kernel = Sinc::new(n).unwrap();
        let mass = common::mass(&kernel);
        assert!((mass - 1.0).abs() < 1e-10, "n = {n}: mass {mass}");
    }
}

#[test]
fn analytic_norms() {
    let cases: [(&str, &dyn Kernel, f64); 4] = [
        ("m4", &CubicSpline, 1.0 / PI),
        ("c2", &WendlandC2, 21.0 / (16.0 * PI)),
        ("c4", &WendlandC4, 495.0 / (256.0 * PI)),
        ("c6", &WendlandC6, 1365.0 / (512.0 * PI)),
    ];
    for (name, kernel, want) in cases {
        assert!((kernel.norm() / want - 1.0).abs() < 1e-15, "{name}");
        // The generic numeric normalisation reproduces the closed forms.
        let numeric = normalisation(|v| kernel.shape(v), 2.0);
        assert!(
            (numeric / want - 1.0).abs() < 1e-14,
            "{name}: {numeric} vs {want}"
        );
    }
}

#[test]
fn sinc6_reference_value() {
    let k = Sinc::new(6.0).unwrap().norm();
    assert!((k - 0.790450).abs() < 1e-5, "{k}");
    assert!((k - sphynx_fit(6.0)).abs() < 5e-5);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn sinc_integrates_to_one(n in 3.0f64..=12.0) {
        let kernel = Sinc::new(n).unwrap();
        let mass = common::mass(&kernel);
        prop_assert!((mass - 1.0).abs() < 1e-10, "n = {}: mass {}", n, mass);
    }

    #[test]
    fn sinc_norm_matches_sphynx_fit(n in 3.0f64..=12.0) {
        let k = Sinc::new(n).unwrap().norm();
        let fit = sphynx_fit(n);
        prop_assert!((k - fit).abs() < 5e-5, "n = {}: K = {}, fit = {}", n, k, fit);
    }
}
