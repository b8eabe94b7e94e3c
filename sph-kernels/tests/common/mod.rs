//! Helpers shared by the integration tests.
#![allow(dead_code)]

use proptest::prelude::*;
use sph_kernels::{CubicSpline, F64s, Kernel, Sinc, WendlandC2, WendlandC4, WendlandC6, LANES};

/// Every built-in analytic kernel, with a name for failure messages.
pub fn analytic_kernels() -> Vec<(String, Box<dyn Kernel>)> {
    let mut out: Vec<(String, Box<dyn Kernel>)> = vec![
        ("m4".into(), Box::new(CubicSpline::new())),
        ("wendland-c2".into(), Box::new(WendlandC2::new())),
        ("wendland-c4".into(), Box::new(WendlandC4::new())),
        ("wendland-c6".into(), Box::new(WendlandC6::new())),
    ];
    for n in [
        1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 5.5, 6.0, 7.25, 10.0, 12.0,
    ] {
        out.push((format!("sinc:{n}"), Box::new(Sinc::new(n).unwrap())));
    }
    out
}

/// `∫_a^b f` by composite Simpson with `intervals` (even) sub-intervals.
pub fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, intervals: usize) -> f64 {
    assert!(intervals.is_multiple_of(2));
    let h = (b - a) / intervals as f64;
    let inner: f64 = (1..intervals)
        .map(|i| {
            let weight = if i % 2 == 1 { 4.0 } else { 2.0 };
            weight * f(a + i as f64 * h)
        })
        .sum();
    (f(a) + inner + f(b)) * h / 3.0
}

/// `4 pi K ∫_0^2 w(v) v^2 dv` by Simpson's rule, split at v = 1 (the M4 joint),
/// independent of the crate's Gauss-Legendre `normalisation`.
pub fn mass(kernel: &dyn Kernel) -> f64 {
    // Just below 2 so the kernel's left limit, not its cut-off, is used.
    let f = |v: f64| kernel.shape(v.min(2.0 * (1.0 - f64::EPSILON))) * v * v;
    let n = 100_000;
    4.0 * std::f64::consts::PI * kernel.norm() * (simpson(f, 0.0, 1.0, n) + simpson(f, 1.0, 2.0, n))
}

/// The lane forms of `k` at `v` equal its scalar forms bit for bit.
pub fn lanes_match_scalar(k: &dyn Kernel, v: [f64; LANES]) -> Result<(), TestCaseError> {
    let lanes = F64s::from_array(v);
    let w = k.shape_lanes(lanes).to_array();
    let (w2, dw) = k.shape_and_derivative_lanes(lanes);
    let (w2, dw) = (w2.to_array(), dw.to_array());
    for l in 0..LANES {
        let (sw, sdw) = k.shape_and_derivative(v[l]);
        prop_assert_eq!(w[l].to_bits(), k.shape(v[l]).to_bits(), "v = {}", v[l]);
        prop_assert_eq!(w2[l].to_bits(), sw.to_bits(), "v = {}", v[l]);
        prop_assert_eq!(dw[l].to_bits(), sdw.to_bits(), "v = {}", v[l]);
    }
    // The squared-argument forms, at v^2.
    let v2 = lanes * lanes;
    let w = k.shape_sq_lanes(v2).to_array();
    let (w2, vdw) = k.shape_and_v_derivative_sq_lanes(v2);
    let (w2, vdw) = (w2.to_array(), vdw.to_array());
    for (l, v2) in v2.to_array().into_iter().enumerate() {
        let (sw, svdw) = k.shape_and_v_derivative_sq(v2);
        prop_assert_eq!(w[l].to_bits(), k.shape_sq(v2).to_bits(), "v2 = {}", v2);
        prop_assert_eq!(w2[l].to_bits(), sw.to_bits(), "v2 = {}", v2);
        prop_assert_eq!(vdw[l].to_bits(), svdw.to_bits(), "v2 = {}", v2);
        prop_assert_eq!(
            k.derivative_over_v_sq_lanes(F64s::splat(v2)).to_array()[0].to_bits(),
            k.derivative_over_v_sq(v2).to_bits(),
            "v2 = {}",
            v2
        );
    }
    Ok(())
}
