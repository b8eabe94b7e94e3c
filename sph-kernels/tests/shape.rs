//! Shape properties and derivatives of every kernel.

mod common;

use proptest::prelude::*;
use sph_kernels::{Kernel, KernelChoice, Tabulated};

#[test]
fn compact_support() {
    for (name, kernel) in common::analytic_kernels() {
        let table = Tabulated::new(kernel.as_ref(), 1000).unwrap();
        for v in [2.0, 2.0 + 1e-12, 2.5, 3.0, 1e10, f64::INFINITY] {
            assert_eq!(kernel.shape(v), 0.0, "{name} at {v}");
            assert_eq!(kernel.shape_derivative(v), 0.0, "{name} at {v}");
            assert_eq!(kernel.shape_and_derivative(v), (0.0, 0.0), "{name} at {v}");
            assert_eq!(
                table.shape_and_derivative(v),
                (0.0, 0.0),
                "{name} table at {v}"
            );
            assert_eq!(kernel.w(v, 1.0), 0.0);
        }
        assert_eq!(kernel.support(), 2.0);
    }
}

#[test]
fn unit_at_origin_positive_and_non_increasing() {
    for (name, kernel) in common::analytic_kernels() {
        assert_eq!(kernel.shape(0.0), 1.0, "{name}");
        assert_eq!(kernel.shape_derivative(0.0), 0.0, "{name}");
        let mut previous = kernel.shape(0.0);
        for i in 1..=200_000 {
            let v = i as f64 * 1e-5;
            let (w, dw) = kernel.shape_and_derivative(v);
            assert!(w >= 0.0, "{name}: w({v}) = {w}");
            assert!(dw <= 0.0, "{name}: w'({v}) = {dw}");
            assert!(w <= previous, "{name}: increases at {v}");
            previous = w;
        }
    }
}

#[test]
fn shape_and_derivative_agrees_with_separate_calls() {
    for (name, kernel) in common::analytic_kernels() {
        for i in 0..=400 {
            let v = i as f64 * 0.005;
            let both = kernel.shape_and_derivative(v);
            assert_eq!(
                both,
                (kernel.shape(v), kernel.shape_derivative(v)),
                "{name} at {v}"
            );
        }
    }
}

/// Any built-in kernel, sinc with a real exponent in [1, 12].
fn any_kernel() -> impl Strategy<Value = KernelChoice> {
    prop_oneof![
        Just(KernelChoice::CubicSpline),
        Just(KernelChoice::WendlandC2),
        Just(KernelChoice::WendlandC4),
        Just(KernelChoice::WendlandC6),
        (1.0f64..=12.0).prop_map(KernelChoice::Sinc),
        // Integer exponents take the `powi` path.
        (1i32..=12).prop_map(|n| KernelChoice::Sinc(n.into())),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, failure_persistence: None, ..ProptestConfig::default() })]

    // M4 is C^2 (only w''' jumps at v = 1), so a central difference straddling
    // the joint still has O(δ^2) error and v = 1 needs no exclusion.
    #[test]
    fn derivative_matches_central_difference(choice in any_kernel(), v in 0.01f64..1.99) {
        let kernel = choice.exact().unwrap();
        let delta = 1e-6;
        let fd = (kernel.shape(v + delta) - kernel.shape(v - delta)) / (2.0 * delta);
        let dw = kernel.shape_derivative(v);
        prop_assert!((fd - dw).abs() < 1e-7, "{} at v = {}: fd {} vs {}", choice, v, fd, dw);
    }

    #[test]
    fn dw_dh_matches_finite_difference_in_h(
        choice in any_kernel(),
        v in 0.01f64..1.99,
        h in 0.01f64..10.0,
    ) {
        let kernel = choice.exact().unwrap();
        let r = v * h;
        let delta = 1e-6 * h;
        let fd = (kernel.w(r, h + delta) - kernel.w(r, h - delta)) / (2.0 * delta);
        let exact = kernel.dw_dh(r, h);
        // Compare in units of K/h^4.
        let scale = kernel.norm() / h.powi(4);
        prop_assert!(
            ((fd - exact) / scale).abs() < 1e-7,
            "{} at r = {}, h = {}: fd {} vs {}", choice, r, h, fd, exact
        );
    }

    #[test]
    fn dw_dr_is_the_scaled_shape_derivative(choice in any_kernel(), v in 0.0f64..2.5, h in 0.01f64..10.0) {
        let kernel = choice.exact().unwrap();
        let want = kernel.norm() / h.powi(4) * kernel.shape_derivative(v);
        let got = kernel.dw_dr(v * h, h);
        // r = v h then r / h is v only to round-off, which moves w' near the
        // support edge by more than 1e-12 of its (tiny) value: compare in
        // units of K/h^4 (max |w'| is of order one).
        let scale = kernel.norm() / h.powi(4);
        prop_assert!((got - want).abs() <= 1e-12 * scale, "{}: {} vs {}", choice, got, want);
    }
}
