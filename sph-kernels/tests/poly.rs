//! The polynomial form of the kernels: faithful to the exact kernel within
//! the fit's tolerance everywhere on the support, lanes equal to scalars,
//! and the fallback to the table where no polynomial fits.

mod common;

use proptest::prelude::*;
use sph_kernels::{
    FastKernel, FitVariable, Kernel, KernelChoice, KernelError, Polynomial, Sinc, SinglePower,
};

/// Every built-in choice, sinc with integer and non-integer exponents.
fn any_choice() -> impl Strategy<Value = KernelChoice> {
    prop_oneof![
        (3u32..=12).prop_map(|n| KernelChoice::Sinc(f64::from(n))),
        (3.0f64..=12.0).prop_map(KernelChoice::Sinc),
        Just(KernelChoice::CubicSpline),
        Just(KernelChoice::WendlandC2),
        Just(KernelChoice::WendlandC4),
        Just(KernelChoice::WendlandC6),
    ]
}

/// The largest |w| and |w'| over the support, on a grid finer than the
/// fit's own check.
fn scales(k: &dyn Kernel) -> (f64, f64) {
    (0..20_000).fold((0.0f64, 0.0f64), |(a, b), i| {
        let (w, dw) = k.shape_and_derivative(2.0 * f64::from(i) / 20_000.0);
        (a.max(w.abs()), b.max(dw.abs()))
    })
}

#[test]
fn the_default_kernel_is_a_power_of_a_polynomial_in_v_squared() {
    let fast = KernelChoice::default().fast().unwrap();
    let FastKernel::Power(p) = &fast else {
        panic!("sinc:6 should be S_1^6: {fast:?}");
    };
    assert_eq!((p.power(), p.base().variable()), (6, FitVariable::Square));
    assert_eq!(
        fast.describe(),
        format!(
            "power 6 of a polynomial of degree {} in v^2",
            p.base().degree()
        )
    );
    // Under half the terms of the plain fit of S_6, and within the same
    // tolerance of the exact kernel (errors relative to the scales, on a
    // grid finer than the fit's own check).
    // The same power evaluated in f32.
    let solver = FastKernel::single(&Sinc::new(6.0).unwrap()).unwrap();
    let FastKernel::Single(single) = &solver else {
        panic!("sinc:6 in f32 should be S_1^6: {solver:?}");
    };
    assert_eq!((single.power(), single.degree()), (6, p.base().degree()));
    assert_eq!(
        solver.describe(),
        format!(
            "power 6 of a polynomial of degree {} in v^2, in f32",
            p.base().degree()
        )
    );
    let exact = Sinc::new(6.0).unwrap();
    let plain = Polynomial::fit(&exact, FastKernel::TOLERANCE).unwrap();
    let (base_terms, plain_terms) = (p.base().degree() + 1, plain.degree() + 1);
    assert!(
        2 * base_terms <= plain_terms,
        "{base_terms} vs {plain_terms} terms"
    );
    let (sw, sdw) = scales(&exact);
    for i in 0..=2000 {
        let v = 2.0 * f64::from(i) / 2000.0;
        let (w, dw) = exact.shape_and_derivative(v);
        let (pw, pdw) = p.shape_and_derivative(v);
        let tol = FastKernel::TOLERANCE;
        assert!((pw - w).abs() <= tol * sw, "v = {v}: {pw} vs {w}");
        assert!((pdw - dw).abs() <= tol * sdw, "v = {v}: {pdw} vs {dw}");
    }
}

#[test]
fn m4_falls_back_to_the_table() {
    assert!(matches!(
        Polynomial::fit(&sph_kernels::CubicSpline, FastKernel::TOLERANCE),
        Err(KernelError::NoPolynomialFit { .. })
    ));
    let fast = KernelChoice::CubicSpline.fast().unwrap();
    assert_eq!(fast.describe(), "table of 20000 points");
}

#[test]
fn a_tolerance_no_degree_reaches_is_an_error_naming_it() {
    let e = Polynomial::fit(&Sinc::new(6.0).unwrap(), 1e-17).unwrap_err();
    assert!(e.to_string().contains("1e-17"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    /// Within the tolerance of the scale everywhere on the support, not only
    /// at the fit's check points (1.5x margin for points between them).
    #[test]
    fn fast_form_matches_exact(choice in any_choice(), v in 0.0f64..2.0) {
        let exact = choice.exact().unwrap();
        let fast = choice.fast().unwrap();
        let (sw, sdw) = scales(exact.as_ref());
        let (w, dw) = exact.shape_and_derivative(v);
        let (fw, fdw) = fast.shape_and_derivative(v);
        // The table's own bound (tests/table.rs) where it is used.
        let tol = match fast {
            FastKernel::Polynomial(_) | FastKernel::Power(_) => 1.5 * FastKernel::TOLERANCE,
            FastKernel::Single(_) => SinglePower::TOLERANCE,
            FastKernel::Table(_) => 1e-7,
        };
        prop_assert!((fw - w).abs() <= tol * sw, "{choice} v = {v}: {fw} vs {w}");
        prop_assert!((fdw - dw).abs() <= tol * sdw, "{choice} v = {v}: {fdw} vs {dw}");
        prop_assert_eq!(fast.shape(2.0 + v), 0.0);
    }

    /// Lanes are the scalar forms bit for bit, in and out of range.
    #[test]
    fn lanes_equal_scalar_bit_for_bit(
        choice in any_choice(),
        v in proptest::array::uniform8(prop_oneof![
            4 => 0.0f64..2.2,
            1 => prop::num::f64::ANY,
        ]),
    ) {
        common::lanes_match_scalar(&choice.fast().unwrap(), v)?;
        // And in the f32 power form where the kernel has one.
        common::lanes_match_scalar(&FastKernel::single(&*choice.exact().unwrap()).unwrap(), v)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    /// The squared-argument forms (what density and IAD call, without a
    /// square root) give `w(v)` and `v w'(v)` of the root's forms to a few
    /// rounding steps of the scale (the polynomial's variable `v^2` is
    /// rounded once instead of through the root), and zero outside the
    /// support.
    #[test]
    fn squared_argument_forms_match_the_root_forms(
        choice in any_choice(),
        v in proptest::array::uniform8(0.0f64..2.2),
    ) {
        for fast in [choice.fast().unwrap(), FastKernel::single(&*choice.exact().unwrap()).unwrap()] {
        let (sw, sdw) = scales(&fast);
        let lanes = sph_kernels::F64s::from_array(v);
        let v2 = lanes * lanes;
        let w_root = fast.shape_lanes(lanes).to_array();
        let (w_r, dw_r) = fast.shape_and_derivative_lanes(lanes);
        let (w_sq, vdw_sq) = fast.shape_and_v_derivative_sq_lanes(v2);
        let w_sq_only = fast.shape_sq_lanes(v2).to_array();
        let (w_r, dw_r, w_sq, vdw_sq) =
            (w_r.to_array(), dw_r.to_array(), w_sq.to_array(), vdw_sq.to_array());
        for l in 0..8 {
            let tol = 1e-13;
            prop_assert!((w_sq_only[l] - w_root[l]).abs() <= tol * sw, "{choice} v = {}: {} vs {}", v[l], w_sq_only[l], w_root[l]);
            prop_assert!((w_sq[l] - w_r[l]).abs() <= tol * sw, "{choice} v = {}", v[l]);
            prop_assert!((vdw_sq[l] - v[l] * dw_r[l]).abs() <= tol * 2.0 * sdw, "{choice} v = {}: {} vs {}", v[l], vdw_sq[l], v[l] * dw_r[l]);
            if v[l] > 1e-3 {
                let d = fast.derivative_over_v_sq_lanes(v2).to_array()[l];
                prop_assert!((d * v[l] - dw_r[l]).abs() <= tol * 2.0 * sdw, "{choice} v = {}: {} vs {}", v[l], d * v[l], dw_r[l]);
            }
            if v[l] >= 2.0 {
                prop_assert_eq!(w_sq_only[l], 0.0);
                prop_assert_eq!(vdw_sq[l], 0.0);
            }
        }
        }
    }
}
