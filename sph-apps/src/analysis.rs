//! Observables of a finished run: radial profiles, L1 errors against a
//! reference, shock radius, plateau density, peak density, closest pair and
//! the scales of the drift figures.
//!
//! Each observable is a distributed reduction: every rank passes its own
//! particles (`owned`, a range of the local arrays, which also hold halos)
//! and the communicator, every rank gets the global result, and no particle
//! leaves its rank. Floating-point sums are exact ([`ExactSum`]), so the
//! results do not depend on the number of ranks or threads.

use crate::cases::{Curve, Reference, CURVE_MAX_SUMS};
use crate::reference::Sedov;
use nalgebra::Vector3;
use rayon::prelude::*;
use serde::Serialize;
use sph_comm::{Communicator, ExactSum, ReduceOp};
use sph_core::Particles;
use std::ops::Range;

/// Particles per rayon task of the exact sums.
const CHUNK: usize = 1 << 14;

/// Per-particle mean absolute errors against the reference.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct L1 {
    /// Density.
    pub rho: f64,
    /// Pressure.
    pub p: f64,
    /// Speed (|v| against the reference's |v_r|; for a tube the signed
    /// velocity along it, see [`Reference::flow_speed`]).
    pub v: f64,
}

/// Position of particle `i`.
fn position(p: &Particles, i: usize) -> Vector3<f64> {
    Vector3::new(p.x[i], p.y[i], p.z[i])
}

/// Velocity of particle `i`.
fn velocity(p: &Particles, i: usize) -> Vector3<f64> {
    Vector3::new(p.vx[i], p.vy[i], p.vz[i])
}

fn radius(p: &Particles, i: usize) -> f64 {
    position(p, i).norm()
}

fn speed(p: &Particles, i: usize) -> f64 {
    velocity(p, i).norm()
}

/// Particle `i`'s coordinate of `reference` (the radius without one).
fn coordinate(reference: Option<&Reference>, p: &Particles, i: usize) -> f64 {
    match reference {
        Some(rf) => rf.coordinate(position(p, i).into()),
        None => radius(p, i),
    }
}

/// Particle `i`'s speed as `reference` compares it (`|v|` without one).
fn flow_speed(reference: Option<&Reference>, p: &Particles, i: usize) -> f64 {
    match reference {
        Some(rf) => rf.flow_speed(position(p, i).into(), velocity(p, i).into()),
        None => speed(p, i),
    }
}

/// `n` exact sums over the owned particles of every rank: `add(i, sums)`
/// adds particle `i`'s terms. One all-reduce.
pub(crate) fn exact_sums<C, F>(owned: Range<usize>, n: usize, comm: &C, add: F) -> Vec<ExactSum>
where
    C: Communicator,
    F: Fn(usize, &mut [ExactSum]) + Sync,
{
    let zero = || vec![ExactSum::new(); n];
    let mut sums = (0..owned.len().div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut s = zero();
            let lo = owned.start + c * CHUNK;
            for i in lo..(lo + CHUNK).min(owned.end) {
                add(i, &mut s);
            }
            s
        })
        .reduce(zero, |mut a, b| {
            for (x, y) in a.iter_mut().zip(&b) {
                x.merge(y);
            }
            a
        });
    ExactSum::all_reduce_many(&mut sums, comm);
    sums
}

/// Number of particles on all ranks.
pub fn count<C: Communicator>(owned: Range<usize>, comm: &C) -> usize {
    comm.all_reduce_scalar(owned.len(), ReduceOp::Sum)
}

/// `1/N sum_i |f_i - f_ref(r_i)|` over the particles of all ranks that
/// the reference covers ([`Reference::covers`]: all but a vortex's
/// corners), for rho, P and the speed.
pub fn l1<C: Communicator>(
    p: &Particles,
    owned: Range<usize>,
    comm: &C,
    reference: &Reference,
    t: f64,
) -> L1 {
    let covered = |i: usize| reference.covers(coordinate(Some(reference), p, i));
    let local = owned.clone().filter(|&i| covered(i)).count();
    let n = comm.all_reduce_scalar(local, ReduceOp::Sum).max(1) as f64;
    let s = exact_sums(owned, 3, comm, |i, s| {
        let x = coordinate(Some(reference), p, i);
        if !reference.covers(x) {
            return;
        }
        let r = reference.state(x, t);
        s[0].add((p.rho[i] - r.rho).abs());
        s[1].add((p.p[i] - r.p).abs());
        s[2].add((flow_speed(Some(reference), p, i) - reference.reference_speed(&r)).abs());
    });
    L1 {
        rho: s[0].value() / n,
        p: s[1].value() / n,
        v: s[2].value() / n,
    }
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

/// Mean rho, P, |v| of all ranks' particles in `nbins` radial bins on
/// `[0, r_max]`: per-bin counts and exact sums, reduced over the ranks.
pub fn radial_profile<C: Communicator>(
    p: &Particles,
    owned: Range<usize>,
    comm: &C,
    reference: Option<&Reference>,
    t: f64,
    r_max: f64,
    nbins: usize,
) -> Vec<Bin> {
    let dr = r_max / nbins as f64;
    let bin = |i: usize| Some((coordinate(reference, p, i) / dr) as usize).filter(|&k| k < nbins);
    let mut counts = vec![0usize; nbins];
    for k in owned.clone().filter_map(bin) {
        counts[k] += 1;
    }
    comm.all_reduce(&mut counts, ReduceOp::Sum);
    let sums = exact_sums(owned, 3 * nbins, comm, |i, s| {
        if let Some(k) = bin(i) {
            s[3 * k].add(p.rho[i]);
            s[3 * k + 1].add(p.p[i]);
            s[3 * k + 2].add(flow_speed(reference, p, i));
        }
    });
    counts
        .iter()
        .zip(sums.chunks_exact(3))
        .enumerate()
        .map(|(k, (&count, s))| {
            let r = (k as f64 + 0.5) * dr;
            let c = count.max(1) as f64;
            let nan = f64::NAN;
            let mean = |s: &ExactSum| if count > 0 { s.value() / c } else { nan };
            let refs = reference.map(|rf| rf.state(r, t));
            Bin {
                r,
                count,
                rho: mean(&s[0]),
                p: mean(&s[1]),
                v: mean(&s[2]),
                rho_ref: refs.map_or(nan, |x| x.rho),
                p_ref: refs.map_or(nan, |x| x.p),
                v_ref: match (reference, refs) {
                    (Some(rf), Some(x)) => rf.reference_speed(&x),
                    _ => nan,
                },
            }
        })
        .collect()
}

/// Shock radius of the similarity solution whose enclosed-mass profile is
/// closest to the particles' (a blast wave's front): `s R(t)` for the
/// scale `s` in [0.8, 1.2] that minimises `sum_k |M(r_k) - M_s(r_k)|` over
/// radii `r_k` on `[0.5, 1.25] R(t)`. `M(r)` is the particles' mass within
/// `r`; `M_s(r) = s^3 M_ref(r / s)` the solution's with its shock at
/// `s R(t)` (the profile depends on `r / R` only). Scales are scanned in
/// steps of 0.01, then of 0.0005 around the best.
///
/// The particles' positions carry the shock, not the smoothed density: a
/// scheme that smooths the jump more moves its densest radial bin behind
/// the shock and its foot ahead of it, not the mass it has swept up.
pub fn similarity_radius<C: Communicator>(
    p: &Particles,
    owned: Range<usize>,
    comm: &C,
    sedov: &Sedov,
    t: f64,
) -> f64 {
    const BINS: usize = 600;
    let r_s = sedov.shock_radius(t);
    let r_max = 1.25 * r_s;
    let dr = r_max / BINS as f64;
    // Mass in each shell [k dr, (k + 1) dr), then within each outer edge.
    let shells = exact_sums(owned, BINS, comm, |i, sums| {
        let k = (radius(p, i) / dr) as usize;
        if k < BINS {
            sums[k].add(p.m[i]);
        }
    });
    let enclosed: Vec<f64> = shells
        .iter()
        .scan(0.0, |m, s| {
            *m += s.value();
            Some(*m)
        })
        .collect();
    let reference = EnclosedMass::new(sedov, t);
    // Shell edges from 0.5 R(t) out.
    let first = 2 * BINS / 5 - 1;
    let misfit = |s: f64| -> f64 {
        (first..BINS)
            .map(|k| (enclosed[k] - s.powi(3) * reference.at((k + 1) as f64 * dr / s)).abs())
            .sum()
    };
    let best = |scales: &mut dyn Iterator<Item = f64>| -> f64 {
        scales
            .map(|s| (misfit(s), s))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map_or(1.0, |(_, s)| s)
    };
    let (lo, hi, coarse, fine) = SCALES;
    let steps = ((hi - lo) / coarse).round() as i32;
    let s0 = best(&mut (0..=steps).map(|k| lo + coarse * f64::from(k)));
    let n = (coarse / fine).round() as i32;
    r_s * best(&mut (-n..=n).map(|k| s0 + fine * f64::from(k)))
}

/// The scales [`similarity_radius`] tries: from, to, coarse and fine step.
const SCALES: (f64, f64, f64, f64) = (0.8, 1.2, 0.01, 0.0005);

/// The mass of a Sedov solution within radius `r`, tabulated by the
/// trapezoid rule on a grid with a node at the shock (the density jumps
/// there); ambient gas beyond it.
struct EnclosedMass {
    dx: f64,
    mass: Vec<f64>,
    r_s: f64,
    rho0: f64,
}

impl EnclosedMass {
    /// Intervals of the table inside the shock.
    const NODES: usize = 4000;

    fn new(sedov: &Sedov, t: f64) -> Self {
        let r_s = sedov.shock_radius(t);
        let dx = r_s / Self::NODES as f64;
        let shell = |x: f64| 4.0 * std::f64::consts::PI * x * x * sedov.state(x, t).rho;
        let mass = (0..=Self::NODES)
            .scan(0.0, |m, k| {
                if k > 0 {
                    let x = k as f64 * dx;
                    *m += 0.5 * dx * (shell(x - dx) + shell(x));
                }
                Some(*m)
            })
            .collect();
        Self {
            dx,
            mass,
            r_s,
            rho0: sedov.rho0(),
        }
    }

    /// Mass within `r` (linear between the table's nodes).
    fn at(&self, r: f64) -> f64 {
        if r >= self.r_s {
            let m_s = self.mass[Self::NODES];
            return m_s
                + 4.0 / 3.0 * std::f64::consts::PI * self.rho0 * (r.powi(3) - self.r_s.powi(3));
        }
        let x = r.max(0.0) / self.dx;
        let k = (x as usize).min(Self::NODES - 1);
        let w = x - k as f64;
        (1.0 - w) * self.mass[k] + w * self.mass[k + 1]
    }
}

/// The values of `curve` over the owned particles of all ranks (exact
/// sums, one all-reduce).
///
/// # Panics
/// If the curve asks for more than [`CURVE_MAX_SUMS`] sums.
pub fn curve_values<C: Communicator>(
    p: &Particles,
    owned: Range<usize>,
    comm: &C,
    curve: &Curve,
) -> Vec<f64> {
    let k = curve.sums;
    assert!(
        k <= CURVE_MAX_SUMS,
        "a curve has at most {CURVE_MAX_SUMS} sums"
    );
    let sums = exact_sums(owned, k, comm, |i, s| {
        let mut terms = [0.0; CURVE_MAX_SUMS];
        (curve.terms)(p, i, &mut terms[..k]);
        for (sum, &t) in s.iter_mut().zip(&terms[..k]) {
            sum.add(t);
        }
    });
    let totals: Vec<f64> = sums.iter().map(ExactSum::value).collect();
    (curve.finish)(&totals)
}

/// The outermost coordinate where the binned density falls through
/// `level` (a front moving into thinner gas), linearly interpolated between
/// the bin centres on either side; NaN if no bin reaches `level`.
pub fn front_position(bins: &[Bin], level: f64) -> f64 {
    let filled: Vec<&Bin> = bins.iter().filter(|b| b.count > 0).collect();
    match filled.iter().rposition(|b| b.rho >= level) {
        None => f64::NAN,
        Some(k) if k + 1 == filled.len() => filled[k].r,
        Some(k) => {
            let (a, b) = (filled[k], filled[k + 1]);
            a.r + (a.rho - level) / (a.rho - b.rho) * (b.r - a.r)
        }
    }
}

/// Mean density of all ranks' particles with `reference`'s coordinate (the
/// radius without one) in `[r0, r1)` (NaN if there are none).
pub fn mean_density_in_shell<C: Communicator>(
    p: &Particles,
    owned: Range<usize>,
    comm: &C,
    reference: Option<&Reference>,
    [r0, r1]: [f64; 2],
) -> f64 {
    let inside = |i: usize| {
        let r = coordinate(reference, p, i);
        r >= r0 && r < r1
    };
    let c = comm.all_reduce_scalar(owned.clone().filter(|&i| inside(i)).count(), ReduceOp::Sum);
    let s = exact_sums(owned, 1, comm, |i, s| {
        if inside(i) {
            s[0].add(p.rho[i]);
        }
    });
    if c == 0 {
        f64::NAN
    } else {
        s[0].value() / c as f64
    }
}

/// Highest density of all ranks' particles (-inf if there are none).
pub fn peak_density<C: Communicator>(p: &Particles, owned: Range<usize>, comm: &C) -> f64 {
    let local = p.rho[owned]
        .iter()
        .cloned()
        .fold(f64::NEG_INFINITY, f64::max);
    comm.all_reduce_scalar(local, ReduceOp::Max)
}

/// The scales of the drift figures over all ranks' particles:
/// `[sum m |v|, sum m |x| |v|]` (exact sums).
pub fn drift_scales<C: Communicator>(p: &Particles, owned: Range<usize>, comm: &C) -> [f64; 2] {
    let s = exact_sums(owned, 2, comm, |i, s| {
        let v = speed(p, i);
        s[0].add(p.m[i] * v);
        s[1].add(p.m[i] * radius(p, i) * v);
    });
    [s[0].value(), s[1].value()]
}

/// Smallest distance between two particles among each owned particle's
/// neighbours (self excluded), from the last neighbour lists, over all
/// ranks.
pub fn min_pair_distance<C: Communicator>(
    p: &Particles,
    list: &sph_tree::CompactNeighborList,
    bbox: &sph_tree::BoundingBox,
    comm: &C,
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
    comm.all_reduce_scalar(best.sqrt(), ReduceOp::Min)
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

#[cfg(test)]
mod tests {
    use super::*;
    use sph_comm::SerialComm;
    use sph_core::FieldSet;

    fn blast() -> Sedov {
        Sedov::spherical(5.0 / 3.0, 1.0, 1.0).expect("a valid blast")
    }

    /// The similarity solution sweeps up all the gas within its shock: the
    /// table's mass there is the ambient gas's (the trapezoid rule's error on
    /// 4000 nodes, with the steep shell, is well below 1e-3).
    #[test]
    fn enclosed_mass_at_the_shock_is_the_swept_up_gas() {
        let (sedov, t) = (blast(), 0.05);
        let r_s = sedov.shock_radius(t);
        let m = EnclosedMass::new(&sedov, t);
        let swept = 4.0 / 3.0 * std::f64::consts::PI * r_s.powi(3);
        assert!(
            (m.at(r_s) / swept - 1.0).abs() < 1e-3,
            "{} vs {swept}",
            m.at(r_s)
        );
        assert!(m.at(0.5 * r_s) < 0.05 * swept, "the shell holds the mass");
        let r = 1.2 * r_s;
        let ambient = 4.0 / 3.0 * std::f64::consts::PI * (r.powi(3) - r_s.powi(3));
        assert!((m.at(r) - m.at(r_s) - ambient).abs() < 1e-12);
    }

    /// Equal-mass particles on spheres whose radii follow the solution's
    /// mass profile with its shock at `scale R(t)`: the fit finds `scale`
    /// to its fine step, whichever side of the exact radius it lies.
    #[test]
    fn similarity_radius_finds_a_displaced_shock() {
        let (sedov, t) = (blast(), 0.05);
        let r_s = sedov.shock_radius(t);
        let table = EnclosedMass::new(&sedov, t);
        for scale in [0.9f64, 1.0, 1.07] {
            // Mass within r for the displaced blast, and its inverse by
            // bisection at each particle's mass coordinate.
            let mass_within = |r: f64| scale.powi(3) * table.at(r / scale);
            let (n_shells, per_shell) = (400, 200);
            let r_out = 1.5 * r_s;
            let dm = mass_within(r_out) / n_shells as f64;
            let mut p = Particles::new(n_shells * per_shell, FieldSet::NONE);
            for j in 0..n_shells {
                let target = (j as f64 + 0.5) * dm;
                let (mut lo, mut hi) = (0.0, r_out);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if mass_within(mid) < target {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                // A Fibonacci sphere of `per_shell` points at that radius.
                for q in 0..per_shell {
                    let i = j * per_shell + q;
                    let z = 1.0 - (2.0 * q as f64 + 1.0) / per_shell as f64;
                    let phi = q as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt()) + j as f64;
                    let rho = (1.0 - z * z).sqrt();
                    p.x[i] = lo * rho * phi.cos();
                    p.y[i] = lo * rho * phi.sin();
                    p.z[i] = lo * z;
                    p.m[i] = dm / per_shell as f64;
                }
            }
            let r = similarity_radius(&p, 0..p.len(), &SerialComm, &sedov, t);
            assert!(
                (r / (scale * r_s) - 1.0).abs() < 1e-3,
                "shock at {scale} R: found {} R",
                r / r_s
            );
        }
    }
}
