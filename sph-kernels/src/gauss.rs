//! Composite Gauss-Legendre quadrature (private helper of [`crate::normalisation`]).

/// Nodes and weights of the `N`-point Gauss-Legendre rule on [-1, 1].
#[derive(Debug, Clone)]
pub(crate) struct GaussLegendre<const N: usize> {
    nodes: [f64; N],
    weights: [f64; N],
}

impl<const N: usize> GaussLegendre<N> {
    /// Computes the rule by Newton iteration on P_N (accurate to round-off;
    /// cheaper and safer than transcribing 16-digit tables).
    pub(crate) fn new() -> Self {
        let mut nodes = [0.0; N];
        let mut weights = [0.0; N];
        let n = N as f64;
        for i in 0..N.div_ceil(2) {
            // Tricomi's initial guess for the i-th largest root.
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n + 0.5)).cos();
            for _ in 0..100 {
                let (p, dp) = legendre_and_derivative(N, x);
                let dx = p / dp;
                x -= dx;
                // Quadratic convergence: once the step is this small, x is at round-off.
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            let dp = legendre_and_derivative(N, x).1;
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[i] = x;
            weights[i] = w;
            nodes[N - 1 - i] = -x;
            weights[N - 1 - i] = w;
        }
        Self { nodes, weights }
    }

    /// Integral of `f` over [a, b] with this rule.
    #[inline]
    pub(crate) fn integrate(&self, f: &impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
        let mid = 0.5 * (a + b);
        let half = 0.5 * (b - a);
        let sum: f64 = self
            .nodes
            .iter()
            .zip(&self.weights)
            .map(|(&x, &w)| w * f(mid + half * x))
            .sum();
        half * sum
    }
}

/// P_N(x) and P_N'(x) by the three-term recurrence.
fn legendre_and_derivative(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    let n = n as f64;
    (p1, n * (x * p1 - p0) / (x * x - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_two_and_polynomials_are_exact() {
        let rule = GaussLegendre::<20>::new();
        let total: f64 = rule.weights.iter().sum();
        assert!((total - 2.0).abs() < 1e-14, "{total}");
        // Degree 39 is the highest the 20-point rule integrates exactly.
        let got = rule.integrate(&|x: f64| x.powi(38), 0.0, 1.0);
        assert!((got - 1.0 / 39.0).abs() < 1e-15, "{got}");
        let got = rule.integrate(&|x: f64| x.cos(), 0.0, 1.0);
        assert!((got - 1f64.sin()).abs() < 1e-15, "{got}");
    }
}
