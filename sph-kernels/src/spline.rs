//! The cubic B-spline (M4) kernel of Monaghan & Lattanzio (1985).

use std::f64::consts::FRAC_1_PI;

use crate::kernel::Kernel;

/// Cubic spline (M4), support `2h`:
/// `w = 1 - 1.5 v^2 + 0.75 v^3` for `v < 1`, `0.25 (2 - v)^3` for `1 <= v < 2`,
/// with `K = 1/pi`. It is C^2; its third derivative jumps at `v = 1`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CubicSpline;

impl CubicSpline {
    /// The M4 kernel.
    pub fn new() -> Self {
        Self
    }
}

/// `((2 - v)_+, (1 - v)_+)`: M4 is `1/4 [(2-v)_+^3 - 4 (1-v)_+^3]`, which
/// evaluates without branches (random distances mispredict a piecewise `if`).
/// `f64::max` returns 0 for NaN, so NaN maps to zero like `v >= 2`. (For
/// `v -> 0` the derivative `3 b^2 - 3/4 a^2` cancels to ~1e-16 absolute.)
#[inline]
fn truncated_powers_base(v: f64) -> (f64, f64) {
    ((2.0 - v).max(0.0), (1.0 - v).max(0.0))
}

impl Kernel for CubicSpline {
    // One formula for all three methods, so they agree bit for bit; the
    // unused half optimises away.
    #[inline]
    fn shape(&self, v: f64) -> f64 {
        self.shape_and_derivative(v).0
    }

    #[inline]
    fn shape_derivative(&self, v: f64) -> f64 {
        self.shape_and_derivative(v).1
    }

    #[inline]
    fn shape_and_derivative(&self, v: f64) -> (f64, f64) {
        let (a, b) = truncated_powers_base(v);
        let (a2, b2) = (a * a, b * b);
        (0.25 * a2 * a - b2 * b, 3.0 * b2 - 0.75 * a2)
    }

    #[inline]
    fn norm(&self) -> f64 {
        FRAC_1_PI
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_piecewise_definition() {
        for i in 0..=2500 {
            let v = i as f64 * 1e-3;
            let (w, dw) = if v < 1.0 {
                (
                    1.0 - 1.5 * v * v + 0.75 * v * v * v,
                    -3.0 * v + 2.25 * v * v,
                )
            } else if v < 2.0 {
                (0.25 * (2.0 - v).powi(3), -0.75 * (2.0 - v).powi(2))
            } else {
                (0.0, 0.0)
            };
            let got = CubicSpline.shape_and_derivative(v);
            assert!(
                (got.0 - w).abs() < 1e-15 && (got.1 - dw).abs() < 1e-15,
                "v = {v}"
            );
            assert_eq!(got, (CubicSpline.shape(v), CubicSpline.shape_derivative(v)));
        }
        assert_eq!(CubicSpline.shape(0.0), 1.0);
        assert_eq!(CubicSpline.shape_and_derivative(f64::NAN), (0.0, 0.0));
    }
}
