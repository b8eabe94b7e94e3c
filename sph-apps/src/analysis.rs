//! Observables of a finished run: radial profiles, L1 errors against a
//! reference, shock radius, peak density, closest pair.

use crate::cases::Reference;
use serde::Serialize;
use sph_core::Particles;

/// Per-particle mean absolute errors against the reference.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct L1 {
    /// Density.
    pub rho: f64,
    /// Pressure.
    pub p: f64,
    /// Speed (|v| against the reference's |v_r|).
    pub v: f64,
}

fn radius(p: &Particles, i: usize) -> f64 {
    (p.x[i] * p.x[i] + p.y[i] * p.y[i] + p.z[i] * p.z[i]).sqrt()
}

fn speed(p: &Particles, i: usize) -> f64 {
    (p.vx[i] * p.vx[i] + p.vy[i] * p.vy[i] + p.vz[i] * p.vz[i]).sqrt()
}

/// `1/N sum_i |f_i - f_ref(r_i)|` over all particles, for rho, P and |v|.
pub fn l1(p: &Particles, reference: &Reference, t: f64) -> L1 {
    let n = p.len().max(1) as f64;
    let mut e = L1::default();
    for i in 0..p.len() {
        let s = reference.state(radius(p, i), t);
        e.rho += (p.rho[i] - s.rho).abs();
        e.p += (p.p[i] - s.p).abs();
        e.v += (speed(p, i) - s.v.abs()).abs();
    }
    e.rho /= n;
    e.p /= n;
    e.v /= n;
    e
}

/// One radial bin of the particle profile and the reference.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Bin {
    /// Bin centre.
    pub r: f64,
    /// Particles in the bin.
    pub count: usize,
    /// Mean density.
    pub rho: f64,
    /// Mean pressure.
    pub p: f64,
    /// Mean speed.
    pub v: f64,
    /// Reference density at the bin centre (NaN without reference).
    pub rho_ref: f64,
    /// Reference pressure.
    pub p_ref: f64,
    /// Reference speed.
    pub v_ref: f64,
}

/// Mean rho, P, |v| in `nbins` radial bins on `[0, r_max]`.
pub fn radial_profile(
    p: &Particles,
    reference: Option<&Reference>,
    t: f64,
    r_max: f64,
    nbins: usize,
) -> Vec<Bin> {
    let dr = r_max / nbins as f64;
    let mut sums = vec![(0usize, 0.0, 0.0, 0.0); nbins];
    for i in 0..p.len() {
        let k = (radius(p, i) / dr) as usize;
        if k < nbins {
            let s = &mut sums[k];
            s.0 += 1;
            s.1 += p.rho[i];
            s.2 += p.p[i];
            s.3 += speed(p, i);
        }
    }
    sums.iter()
        .enumerate()
        .map(|(k, s)| {
            let r = (k as f64 + 0.5) * dr;
            let c = s.0.max(1) as f64;
            let nan = f64::NAN;
            let refs = reference.map(|rf| rf.state(r, t));
            Bin {
                r,
                count: s.0,
                rho: if s.0 > 0 { s.1 / c } else { nan },
                p: if s.0 > 0 { s.2 / c } else { nan },
                v: if s.0 > 0 { s.3 / c } else { nan },
                rho_ref: refs.map_or(nan, |x| x.rho),
                p_ref: refs.map_or(nan, |x| x.p),
                v_ref: refs.map_or(nan, |x| x.v.abs()),
            }
        })
        .collect()
}

/// Radius of the densest bin (the shock of a blast wave).
pub fn peak_radius(bins: &[Bin]) -> f64 {
    bins.iter()
        .filter(|b| b.count > 0)
        .max_by(|a, b| a.rho.total_cmp(&b.rho))
        .map_or(f64::NAN, |b| b.r)
}

/// Mean density of the particles with radius in `[r0, r1)`.
pub fn mean_density_in_shell(p: &Particles, r0: f64, r1: f64) -> f64 {
    let (mut s, mut c) = (0.0, 0usize);
    for i in 0..p.len() {
        let r = radius(p, i);
        if r >= r0 && r < r1 {
            s += p.rho[i];
            c += 1;
        }
    }
    if c == 0 {
        f64::NAN
    } else {
        s / c as f64
    }
}

/// Smallest distance between two particles among each particle's
/// neighbours (self excluded), from the last neighbour lists.
pub fn min_pair_distance(
    p: &Particles,
    list: &sph_tree::CompactNeighborList,
    bbox: &sph_tree::BoundingBox,
) -> f64 {
    let mut best = f64::INFINITY;
    for i in list.targets() {
        for j in list.neighbors(i) {
            if j != i {
                let d = bbox.distance2([p.x[i], p.y[i], p.z[i]], [p.x[j], p.y[j], p.z[j]]);
                best = best.min(d);
            }
        }
    }
    best.sqrt()
}

/// Peak resident memory of this process (bytes), from /proc (0 elsewhere).
pub fn peak_rss_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}
