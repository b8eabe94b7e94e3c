//! Romberg quadrature for the smooth one-dimensional integrals of the references.

/// Most halvings of the trapezoid step: at most 2^16 + 1 evaluations per call. The bound
/// matters where round-off noise in the integrand keeps the tolerance from being met.
const MAX_LEVEL: usize = 16;
/// Fewest halvings before the convergence test is trusted (2^5 intervals), so that an
/// integrand concentrated between the first few nodes cannot fake agreement.
const MIN_LEVEL: usize = 5;

/// Integrates `f` over `[a, b]` to a relative tolerance `rel_tol` by Romberg's method
/// (trapezoid rule with repeated Richardson extrapolation).
///
/// Suited to integrands that are smooth (analytic) on the closed interval; the cost is
/// bounded even when the tolerance is not reached, in which case the best estimate is
/// returned.
pub(crate) fn integrate(f: impl Fn(f64) -> f64, a: f64, b: f64, rel_tol: f64) -> f64 {
    let width = b - a;
    let mut trapezoid = 0.5 * width * (f(a) + f(b));
    let mut previous = vec![trapezoid];
    for level in 1..=MAX_LEVEL {
        // Add the midpoints of the 2^(level-1) current intervals.
        let intervals = 1_usize << level;
        let step = width / intervals as f64;
        let midpoints: f64 = (0..intervals / 2)
            .map(|i| f(a + step * (2 * i + 1) as f64))
            .sum();
        trapezoid = 0.5 * trapezoid + step * midpoints;
        let mut row = Vec::with_capacity(level + 1);
        row.push(trapezoid);
        let mut factor = 1.0;
        for k in 1..=level {
            factor *= 4.0;
            let better = row[k - 1] + (row[k - 1] - previous[k - 1]) / (factor - 1.0);
            row.push(better);
        }
        let (new, old) = (row[level], previous[level - 1]);
        if level >= MIN_LEVEL && ((new - old).abs() <= rel_tol * new.abs() || new.is_nan()) {
            return new;
        }
        previous = row;
    }
    previous[MAX_LEVEL]
}

#[cfg(test)]
mod tests {
    use super::integrate;

    #[test]
    fn integrates_a_peaked_function() {
        // ∫_0^50 x^3 e^{-x} dx = 6 (up to e^{-50} terms).
        let got = integrate(|x| x.powi(3) * (-x).exp(), 0.0, 50.0, 1e-13);
        assert!((got - 6.0).abs() < 1e-10, "{got}");
    }

    #[test]
    fn stops_on_noise() {
        // A tolerance below the noise is never met: the call still ends with a fair estimate.
        let noisy = |x: f64| 1.0 + 1e-10 * (x * 1e7).sin();
        let got = integrate(noisy, 0.0, 1.0, 1e-16);
        assert!((got - 1.0).abs() < 1e-9, "{got}");
    }
}
