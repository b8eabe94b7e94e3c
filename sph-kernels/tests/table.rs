//! Accuracy of the lookup tables against the exact kernels.
//!
//! Measured with `Tabulated::DEFAULT_POINTS` (20,000) nodes and 2,000,003
//! sample points over [0, 2) (run with `--nocapture` to print the numbers):
//!
//! ```text
//! kernel         max|dw|/w(0)  max rel w (v<1.9)  max|dw'|/max|w'|  max rel w' (v<1.9)
//! m4                   3.75e-9            7.49e-7           5.63e-9             7.43e-5
//! wendland-c2          6.25e-9            1.46e-6           1.78e-8             1.49e-4
//! wendland-c4          5.83e-9            3.62e-6           1.26e-8             2.38e-6
//! wendland-c6          6.88e-9            6.75e-6           1.52e-8             5.01e-6
//! sinc:1               1.03e-9            1.07e-8           1.68e-9             2.47e-9
//! sinc:1.5             5.24e-8            1.18e-7           1.74e-3 (edge)      1.94e-8
//! sinc:2               2.06e-9            2.94e-7           4.21e-9             3.06e-8
//! sinc:3               3.08e-9            8.49e-7           6.56e-9             3.35e-7
//! sinc:5               5.14e-9            2.78e-6           1.12e-8             1.76e-6
//! sinc:5.5             5.66e-9            3.43e-6           1.24e-8             2.29e-6
//! sinc:6               6.17e-9            4.15e-6           1.36e-8             2.88e-6
//! sinc:10              1.03e-8            1.24e-5           2.29e-8             1.01e-5
//! sinc:12              1.23e-8            1.81e-5           2.76e-8             1.53e-5
//! ```
//!
//! Relative to the kernel's scale the error is ~1e-8 everywhere (the linear
//! interpolation bound dv^2/8 |w''| with dv = 1e-4). Pointwise relative errors
//! grow towards v = 2 because w -> 0 there, and for the derivative near the
//! zero of w'' (M4, Wendland C2). For 1 < n < 2 the sinc derivative behaves
//! like (2 - v)^(n-1) at the edge, so the last interval is only ~dv^(n-1)
//! accurate.

mod common;

use proptest::prelude::*;
use sph_kernels::{Kernel, KernelChoice, Tabulated};

/// Error statistics of a table against its source kernel.
#[derive(Debug, Default)]
struct Errors {
    /// max |table - exact| / w(0).
    shape_scaled: f64,
    /// max |table - exact| / |exact| for v < 1.9.
    shape_relative: f64,
    /// max |table' - exact'| / max |exact'|.
    derivative_scaled: f64,
    /// max |table' - exact'| / |exact'| for 0 < v < 1.9.
    derivative_relative: f64,
}

fn errors(kernel: &dyn Kernel, samples: usize) -> Errors {
    let table = Tabulated::new(kernel, Tabulated::DEFAULT_POINTS).unwrap();
    let support = kernel.support();
    let (mut max_w, mut max_dw) = (0.0f64, 0.0f64);
    let (mut abs_w, mut abs_dw) = (0.0f64, 0.0f64);
    let mut e = Errors::default();
    for i in 0..samples {
        // Incommensurate with the table spacing, so samples fall everywhere
        // between nodes.
        let v = support * i as f64 / samples as f64;
        let (w, dw) = kernel.shape_and_derivative(v);
        let (tw, tdw) = table.shape_and_derivative(v);
        max_w = max_w.max(w.abs());
        max_dw = max_dw.max(dw.abs());
        abs_w = abs_w.max((tw - w).abs());
        abs_dw = abs_dw.max((tdw - dw).abs());
        if v < 1.9 {
            e.shape_relative = e.shape_relative.max((tw - w).abs() / w.abs());
            if dw != 0.0 {
                e.derivative_relative = e.derivative_relative.max((tdw - dw).abs() / dw.abs());
            }
        }
    }
    e.shape_scaled = abs_w / max_w;
    e.derivative_scaled = abs_dw / max_dw;
    e
}

#[test]
fn default_tables_are_accurate() {
    eprintln!(
        "{:<14} {:>13} {:>18} {:>17} {:>19}",
        "kernel", "max|dw|/w(0)", "max rel w (v<1.9)", "max|dw'|/max|w'|", "max rel w' (v<1.9)"
    );
    for (name, kernel) in common::analytic_kernels() {
        let e = errors(kernel.as_ref(), 2_000_003);
        eprintln!(
            "{:<14} {:>13.2e} {:>18.2e} {:>17.2e} {:>19.2e}",
            name, e.shape_scaled, e.shape_relative, e.derivative_scaled, e.derivative_relative
        );
        assert!(e.shape_scaled < 1e-6, "{name}: {e:?}");
        // For 1 < n < 2, S_n' ~ (2 - v)^(n-1) has an infinite slope at the
        // edge, so the last table interval is only accurate to ~dv^(n-1).
        let exponent = name
            .strip_prefix("sinc:")
            .map(|n| n.parse::<f64>().unwrap());
        let tolerance = match exponent {
            Some(n) if n > 1.0 && n < 2.0 => 1e-2,
            _ => 1e-6,
        };
        assert!(e.derivative_scaled < tolerance, "{name}: {e:?}");
    }
}

#[test]
fn table_of_a_table_is_the_table() {
    // Re-sampling a table at its own nodes reproduces it.
    let kernel = KernelChoice::default().tabulate(1001).unwrap();
    let again = Tabulated::new(&kernel, 1001).unwrap();
    for i in 0..=2000 {
        let v = i as f64 * 1e-3;
        let (a, b) = (
            kernel.shape_and_derivative(v),
            again.shape_and_derivative(v),
        );
        assert!(
            (a.0 - b.0).abs() < 1e-14 && (a.1 - b.1).abs() < 1e-13,
            "v = {v}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn table_matches_exact_at_random_points(n in 3.0f64..=12.0, v in 0.0f64..2.0) {
        let exact = KernelChoice::Sinc(n).exact().unwrap();
        let table = KernelChoice::Sinc(n).tabulate(Tabulated::DEFAULT_POINTS).unwrap();
        let (w, dw) = exact.shape_and_derivative(v);
        let (tw, tdw) = table.shape_and_derivative(v);
        prop_assert!((tw - w).abs() < 1e-6, "n = {}, v = {}: {} vs {}", n, v, tw, w);
        prop_assert!((tdw - dw).abs() < 1e-6, "n = {}, v = {}: {} vs {}", n, v, tdw, dw);
    }

    /// The lane forms are the scalar forms bit for bit, in and out of range
    /// (negative, beyond the support, infinite, NaN), for tables and for the
    /// exact kernels' default lane methods alike.
    #[test]
    fn lanes_equal_scalar_bit_for_bit(
        n in 3.0f64..=12.0,
        v in proptest::array::uniform8(prop_oneof![
            4 => 0.0f64..2.2,
            1 => prop::num::f64::ANY,
        ]),
    ) {
        let exact = KernelChoice::Sinc(n).exact().unwrap();
        let table = KernelChoice::Sinc(n).tabulate(Tabulated::DEFAULT_POINTS).unwrap();
        let kernels: [&dyn Kernel; 2] = [&table, exact.as_ref()];
        for k in kernels {
            common::lanes_match_scalar(k, v)?;
        }
    }
}
