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

/// Radius of the densest bin (the shock of a blast wave).
pub fn peak_radius(bins: &[Bin]) -> f64 {
    bins.iter()
        .filter(|b| b.count > 0)
        .max_by(|a, b| a.rho.total_cmp(&b.rho))
        .map_or(f64::NAN, |b| b.r)
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
