//! Shared helpers of the tests and benches: a seeded generator and
//! particle distributions, and error measures against direct summation.
#![allow(dead_code)]

use sph_gravity::GravityField;

/// SplitMix64: small, seeded, good enough for sampling test particles.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A uniformly random unit vector.
    pub fn direction(&mut self) -> [f64; 3] {
        let cz = 2.0 * self.uniform() - 1.0;
        let phi = 2.0 * std::f64::consts::PI * self.uniform();
        let s = (1.0 - cz * cz).sqrt();
        [s * phi.cos(), s * phi.sin(), cz]
    }
}

/// Particle set: positions and masses (structure of arrays).
#[derive(Debug, Clone, Default)]
pub struct Cloud {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub z: Vec<f64>,
    pub m: Vec<f64>,
}

impl Cloud {
    fn push(&mut self, p: [f64; 3], m: f64) {
        self.x.push(p[0]);
        self.y.push(p[1]);
        self.z.push(p[2]);
        self.m.push(m);
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }
}

/// Plummer sphere of total mass 1, scale radius 1, truncated at `rmax`
/// (equal masses).
pub fn plummer(n: usize, rmax: f64, seed: u64) -> Cloud {
    let mut rng = Rng::new(seed);
    let mut c = Cloud::default();
    while c.len() < n {
        // Inverse of the cumulative mass M(r) = r^3 / (1 + r^2)^{3/2}.
        let u = rng.uniform();
        if u == 0.0 {
            continue;
        }
        let r = 1.0 / (u.powf(-2.0 / 3.0) - 1.0).sqrt();
        if r > rmax {
            continue;
        }
        let d = rng.direction();
        c.push([r * d[0], r * d[1], r * d[2]], 1.0 / n as f64);
    }
    c
}

/// Uniform sphere of radius 1 and total mass 1 (equal masses).
pub fn uniform_sphere(n: usize, seed: u64) -> Cloud {
    let mut rng = Rng::new(seed);
    let mut c = Cloud::default();
    while c.len() < n {
        let p = [
            2.0 * rng.uniform() - 1.0,
            2.0 * rng.uniform() - 1.0,
            2.0 * rng.uniform() - 1.0,
        ];
        if p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= 1.0 {
            c.push(p, 1.0 / n as f64);
        }
    }
    c
}

/// Per-particle relative acceleration errors `|a - a_ref| / |a_ref|`, sorted.
pub fn relative_errors(a: &GravityField, reference: &GravityField) -> Vec<f64> {
    let mut e: Vec<f64> = (0..a.len())
        .map(|i| {
            let (p, q) = (a.acc(i), reference.acc(i));
            let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            let r = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            d / r
        })
        .collect();
    e.sort_by(f64::total_cmp);
    e
}

/// The `q`-quantile of sorted values.
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    let k = ((sorted.len() as f64 - 1.0) * q).round() as usize;
    sorted[k]
}

/// `|sum m a| / sum m |a|`: net force relative to the total force magnitude.
pub fn net_force_ratio(f: &GravityField, m: &[f64]) -> f64 {
    let mut s = [0.0; 3];
    let mut t = 0.0;
    for i in 0..f.len() {
        let a = f.acc(i);
        for k in 0..3 {
            s[k] += m[i] * a[k];
        }
        t += m[i] * (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    }
    (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt() / t
}
