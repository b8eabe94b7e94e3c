//! Tree gravity on Plummer spheres (1e5 and 1e6 particles, theta 0.5,
//! quadrupoles), the evaluation for a share of active targets on a
//! drifted tree (block time steps: 1%, 10%, 100% of 1e5), and the direct
//! sum on 1e4 particles for comparison. The interaction counts of each
//! tree evaluation are printed once.

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{criterion_main, BenchmarkId, Criterion};
use sph_gravity::{direct, GravityField, GravityParams, Targets, TreeGravity};
use sph_tree::{compute_keys, BoundingBox, Curve, KeySorter, Octree};
use std::time::{Duration, Instant};

fn tree_gravity(c: &mut Criterion) {
    let mut group = c.benchmark_group("tree_gravity_plummer_theta0.5");
    group.sample_size(10);
    for n in [100_000usize, 1_000_000] {
        let cloud = common::plummer(n, 10.0, 42);
        let mut solver = TreeGravity::new(GravityParams::default()).unwrap();
        let mut out = GravityField::new();
        // One untimed evaluation: counts, and the buffers get their capacity.
        let t = Instant::now();
        let st = solver
            .compute_unsorted(&cloud.x, &cloud.y, &cloud.z, &cloud.m, None, &mut out)
            .unwrap();
        let dt = t.elapsed().as_secs_f64();
        let total = (st.p2p + st.m2p) as f64;
        println!(
            "n = {n}: {:.0} interactions/particle (p2p {:.0}, m2p {:.0}), {} groups; \
             first evaluation {dt:.3} s = {:.3e} interactions/s",
            st.interactions_per_particle(),
            st.p2p_per_particle(),
            st.m2p_per_particle(),
            st.groups,
            total / dt,
        );
        group.measurement_time(Duration::from_secs(if n > 100_000 { 20 } else { 10 }));
        group.bench_with_input(BenchmarkId::from_parameter(n), &cloud, |b, cl| {
            b.iter(|| {
                solver
                    .compute_unsorted(&cl.x, &cl.y, &cl.z, &cl.m, None, &mut out)
                    .unwrap()
            })
        });
    }
    group.finish();
}

/// Active targets (every k-th particle along the curve) on a tree whose
/// cells are 0.001 of a Plummer radius out of date.
fn active_targets(c: &mut Criterion) {
    let mut group = c.benchmark_group("tree_gravity_active_targets_1e5");
    group.sample_size(10);
    let cloud = common::plummer(100_000, 10.0, 42);
    let bbox = BoundingBox::enclosing(&cloud.x, &cloud.y, &cloud.z).unwrap();
    let mut keys = Vec::new();
    compute_keys(
        &bbox,
        Curve::Hilbert,
        &cloud.x,
        &cloud.y,
        &cloud.z,
        &mut keys,
    );
    let mut perm = Vec::new();
    KeySorter::new().sort(&keys, None, &mut perm);
    let pick = |a: &[f64]| perm.iter().map(|&k| a[k as usize]).collect::<Vec<f64>>();
    let (x, y, z, m) = (
        pick(&cloud.x),
        pick(&cloud.y),
        pick(&cloud.z),
        pick(&cloud.m),
    );
    let keys: Vec<u64> = perm.iter().map(|&k| keys[k as usize]).collect();
    let tree = Octree::build(&keys, &x, &y, &z, 16).unwrap();
    let mut solver = TreeGravity::new(GravityParams::default()).unwrap();
    let mut out = GravityField::new();
    for every in [100usize, 10, 1] {
        let active: Vec<bool> = (0..x.len()).map(|i| i % every == 0).collect();
        let targets = Targets {
            active: Some(&active),
            drift: 1e-3,
        };
        group.bench_function(BenchmarkId::from_parameter(format!("1/{every}")), |b| {
            b.iter(|| {
                solver
                    .compute_targets(&tree, &bbox, &x, &y, &z, &m, None, targets, &mut out)
                    .unwrap()
            })
        });
    }
    group.finish();
}

fn direct_sum(c: &mut Criterion) {
    let mut group = c.benchmark_group("direct_sum_plummer");
    group.sample_size(10);
    let n = 10_000usize;
    let cloud = common::plummer(n, 10.0, 42);
    let mut out = GravityField::new();
    println!("direct n = {n}: {} interactions/particle", n - 1);
    group.bench_with_input(BenchmarkId::from_parameter(n), &cloud, |b, cl| {
        b.iter(|| direct::direct_sum(&cl.x, &cl.y, &cl.z, &cl.m, None, 1.0, &mut out).unwrap())
    });
    group.finish();
}

/// The benchmark group: `criterion_group!` defines a `pub fn` without docs, which
/// a private module keeps out of the public items that `missing_docs` checks.
mod group {
    criterion::criterion_group!(
        benches,
        super::tree_gravity,
        super::active_targets,
        super::direct_sum
    );
}
criterion_main!(group::benches);
