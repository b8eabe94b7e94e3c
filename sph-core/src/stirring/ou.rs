//! The Ornstein-Uhlenbeck phases of the modes and their projection onto
//! solenoidal and compressive parts.

use super::modes::ModeSet;
use super::rng::{Mt19937, Polar};

/// Numbers per mode entry: real and imaginary part of each of the three
/// components, stored `[re x, im x, re y, im y, re z, im z]` (the C++
/// layout, so the draws land on the same numbers).
pub const PER_ENTRY: usize = 6;

/// The OU state: [`PER_ENTRY`] numbers per mode entry.
#[derive(Debug, Clone, PartialEq)]
pub struct OuState {
    /// The numbers, entry by entry.
    pub phases: Vec<f64>,
}

impl OuState {
    /// The stationary start: each number drawn from `N(0, sigma^2)`.
    pub fn new(entries: usize, sigma: f64, rng: &mut Mt19937) -> Self {
        let mut normal = Polar::new();
        let phases = (0..entries * PER_ENTRY)
            .map(|_| sigma * normal.sample(rng))
            .collect();
        Self { phases }
    }

    /// One exact OU transition over `dt` with correlation time `t_corr`:
    /// `x <- f x + sigma sqrt(1 - f^2) z`, `f = exp(-dt / t_corr)`, `z`
    /// standard normal, which keeps the variance at `sigma^2`. A new normal
    /// distribution per call, as the C++ driver makes one per step.
    pub fn advance(&mut self, dt: f64, t_corr: f64, sigma: f64, rng: &mut Mt19937) {
        let f = (-dt / t_corr).exp();
        let kick = sigma * (1.0 - f * f).sqrt();
        let mut normal = Polar::new();
        for x in &mut self.phases {
            *x = f * *x + kick * normal.sample(rng);
        }
    }
}

/// `sqrt(3) / sqrt(1 - 2w + 3w^2)`: the factor that keeps the rms of the
/// projected field that of the unprojected one for any weight `w`.
pub fn projection_norm(w: f64) -> f64 {
    3f64.sqrt() / (1.0 - 2.0 * w + 3.0 * w * w).sqrt()
}

/// The complex 3-vector of each entry after projection, multiplied by the
/// norm and the entry's amplitude, as structure of arrays: the field is
/// `a_c(x) = sum_e re[c][e] cos(k_e.x) - im[c][e] sin(k_e.x)`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Amplitudes {
    /// Real parts per component, one value per entry.
    pub re: [Vec<f64>; 3],
    /// Imaginary parts per component, one value per entry.
    pub im: [Vec<f64>; 3],
}

impl Amplitudes {
    /// Number of entries.
    pub fn len(&self) -> usize {
        self.re[0].len()
    }

    /// Whether there are no entries.
    pub fn is_empty(&self) -> bool {
        self.re[0].is_empty()
    }
}

/// Projects each entry's real and imaginary vectors: `w` times the part
/// normal to `k` plus `1 - w` times the part along it (w = 1: solenoidal,
/// w = 0: compressive), then scales by `norm * amp`.
pub fn project(ou: &OuState, modes: &ModeSet, w: f64, norm: f64) -> Amplitudes {
    let m = modes.len();
    assert_eq!(
        ou.phases.len(),
        m * PER_ENTRY,
        "OU state and mode set differ"
    );
    let mut out = Amplitudes {
        re: std::array::from_fn(|_| vec![0.0; m]),
        im: std::array::from_fn(|_| vec![0.0; m]),
    };
    for (e, (k, &amp)) in modes.k.iter().zip(&modes.amp).enumerate() {
        let p = &ou.phases[e * PER_ENTRY..(e + 1) * PER_ENTRY];
        let re = project_vector(k, [p[0], p[2], p[4]], w);
        let im = project_vector(k, [p[1], p[3], p[5]], w);
        let scale = norm * amp;
        for c in 0..3 {
            out.re[c][e] = scale * re[c];
            out.im[c][e] = scale * im[c];
        }
    }
    out
}

/// `w (v - k^ (k^.v)) + (1 - w) k^ (k^.v)`, with `k^ (k^.v)` as
/// `k (k.v) / |k|^2`.
pub fn project_vector(k: &[f64; 3], v: [f64; 3], w: f64) -> [f64; 3] {
    let kk = k[0] * k[0] + k[1] * k[1] + k[2] * k[2];
    let kv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
    std::array::from_fn(|c| {
        let along = k[c] * kv / kk;
        w * (v[c] - along) + (1.0 - w) * along
    })
}

#[cfg(test)]
mod tests {
    use super::super::modes::Spectrum;
    use super::*;

    fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    fn vectors(a: &Amplitudes, e: usize) -> ([f64; 3], [f64; 3]) {
        (
            std::array::from_fn(|c| a.re[c][e]),
            std::array::from_fn(|c| a.im[c][e]),
        )
    }

    #[test]
    fn variance_and_lag_autocorrelation() {
        // 2e4 steps of T/10 (2,000 correlation times) of 672 numbers.
        let (sigma, t) = (0.009, 1.0);
        let mut rng = Mt19937::new(251_299);
        let mut ou = OuState::new(112, sigma, &mut rng);
        let (steps, lag) = (20_000, 10);
        // The last `lag` states in a ring: slot s % lag holds step s - lag
        // when step s is reached.
        let mut ring: Vec<Vec<f64>> = vec![Vec::new(); lag];
        let (mut var, mut cov, mut nv, mut nc) = (0.0, 0.0, 0.0, 0.0);
        for s in 0..=steps {
            if s > 0 {
                ou.advance(t / 10.0, t, sigma, &mut rng);
            }
            let old = &mut ring[s % lag];
            for (i, &x) in ou.phases.iter().enumerate() {
                var += x * x;
                nv += 1.0;
                if s >= lag {
                    cov += x * old[i];
                    nc += 1.0;
                }
            }
            old.clone_from(&ou.phases);
        }
        let var = var / nv;
        let rho = cov / nc / var;
        eprintln!(
            "variance / sigma^2 = {:.4}, lag-T autocorrelation {rho:.4} (e^-1 = 0.3679)",
            var / (sigma * sigma)
        );
        assert!(
            (var / (sigma * sigma) - 1.0).abs() < 0.03,
            "variance ratio {}",
            var / (sigma * sigma)
        );
        assert!(
            (rho - (-1f64).exp()).abs() < 0.03,
            "lag-T autocorrelation {rho}"
        );
    }

    #[test]
    fn norm_identity() {
        for w in [0.0, 0.25, 0.5, 1.0] {
            let n = projection_norm(w);
            assert!(
                (n * n * (1.0 - 2.0 * w + 3.0 * w * w) - 3.0).abs() < 1e-14,
                "w = {w}"
            );
        }
        assert!((projection_norm(0.5) - 2.0).abs() < 1e-15);
    }

    #[test]
    fn solenoidal_and_compressive_limits() {
        let modes = ModeSet::new(1.0, Spectrum::Parabolic);
        let mut rng = Mt19937::new(9);
        let ou = OuState::new(modes.len(), 1.0, &mut rng);
        let sol = project(&ou, &modes, 1.0, projection_norm(1.0));
        let comp = project(&ou, &modes, 0.0, projection_norm(0.0));
        for (e, n) in modes.n.iter().enumerate() {
            let n = n.map(f64::from);
            let (re, im) = vectors(&sol, e);
            let scale = dot(re, re).sqrt() + dot(im, im).sqrt() + 1e-300;
            assert!(
                dot(n, re).abs() < 1e-14 * scale * 3.0,
                "w = 1: n.re = {}",
                dot(n, re)
            );
            assert!(
                dot(n, im).abs() < 1e-14 * scale * 3.0,
                "w = 1: n.im = {}",
                dot(n, im)
            );
            let (re, im) = vectors(&comp, e);
            for v in [re, im] {
                // Parallel: the cross product with n vanishes.
                let cross = [
                    n[1] * v[2] - n[2] * v[1],
                    n[2] * v[0] - n[0] * v[2],
                    n[0] * v[1] - n[1] * v[0],
                ];
                let size = dot(v, v).sqrt() * 3.0 + 1e-300;
                assert!(
                    dot(cross, cross).sqrt() < 1e-14 * size,
                    "w = 0: not parallel"
                );
            }
        }
    }
}
