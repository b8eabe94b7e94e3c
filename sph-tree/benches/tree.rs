//! Hot paths of the tree crate: keys + sort, tree build and neighbour
//! search, on uniform random particles with about 100 neighbours each.

use criterion::{criterion_main, BatchSize, Criterion};
use sph_tree::{
    apply_permutation, compute_keys, Boundary, BoundingBox, CompactNeighborList, Curve, KeySorter,
    NeighborList, NeighborSearch, Octree, GROUP_LANES,
};
use std::hint::black_box;

struct Set {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    h: Vec<f64>,
    keys: Vec<u64>,
    bbox: BoundingBox,
}

fn random_set(n: usize) -> Set {
    let mut s: u64 = 0x1234_5678;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let x: Vec<f64> = (0..n).map(|_| next()).collect();
    let y: Vec<f64> = (0..n).map(|_| next()).collect();
    let z: Vec<f64> = (0..n).map(|_| next()).collect();
    // (4/3) pi (2h)^3 n = 100 neighbours.
    let h = vec![0.5 * (100.0 * 3.0 / (4.0 * std::f64::consts::PI * n as f64)).cbrt(); n];
    let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
    Set {
        x,
        y,
        z,
        h,
        keys: Vec::new(),
        bbox,
    }
}

fn sorted_set(n: usize) -> Set {
    let mut s = random_set(n);
    compute_keys(&s.bbox, Curve::Hilbert, &s.x, &s.y, &s.z, &mut s.keys);
    let mut perm = Vec::new();
    KeySorter::new().sort(&s.keys, None, &mut perm);
    let mut f = Vec::new();
    for a in [&mut s.x, &mut s.y, &mut s.z, &mut s.h] {
        apply_permutation(&perm, a, &mut f);
    }
    let mut k = Vec::new();
    apply_permutation(&perm, &mut s.keys, &mut k);
    s
}

fn benches(c: &mut Criterion) {
    for &n in &[100_000usize, 1_000_000] {
        let label = if n == 100_000 { "1e5" } else { "1e6" };
        let raw = random_set(n);
        let mut g = c.benchmark_group(format!("tree_{label}"));
        g.sample_size(10);

        let mut keys = Vec::new();
        let mut perm = Vec::new();
        let mut sorter = KeySorter::new();
        g.bench_function("keys_and_sort", |b| {
            b.iter(|| {
                compute_keys(&raw.bbox, Curve::Hilbert, &raw.x, &raw.y, &raw.z, &mut keys);
                sorter.sort(&keys, None, &mut perm);
                black_box(perm[0])
            })
        });

        let s = sorted_set(n);
        let mut tree = Octree::build(&s.keys, &s.x, &s.y, &s.z, 16).unwrap();
        g.bench_function("build_bucket16", |b| {
            b.iter(|| {
                tree.rebuild(&s.keys, &s.x, &s.y, &s.z, 16).unwrap();
                black_box(tree.num_nodes())
            })
        });

        let mut list = NeighborList::new();
        let search = NeighborSearch::default();
        g.bench_function("neighbors_100", |b| {
            b.iter_batched_ref(
                || (),
                |_| {
                    let st = search
                        .find(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, 0..n, &mut list)
                        .unwrap();
                    black_box(st.total)
                },
                BatchSize::PerIteration,
            )
        });
        let mut compact = CompactNeighborList::new();
        let symmetric = NeighborSearch {
            symmetric: true,
            ..Default::default()
        };
        g.bench_function("neighbors_100_compact_symmetric", |b| {
            b.iter(|| {
                let st = symmetric
                    .find_compact(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, 0..n, &mut compact)
                    .unwrap();
                black_box(st.total)
            })
        });
        let compact_bytes = compact.bytes();
        // One list per 8 targets (the SIMD pair loops' lists).
        let grouped = NeighborSearch {
            grouped: true,
            ..symmetric
        };
        g.bench_function("neighbors_100_compact_symmetric_grouped", |b| {
            b.iter(|| {
                let st = grouped
                    .find_compact(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, 0..n, &mut compact)
                    .unwrap();
                black_box(st.total)
            })
        });
        // Block time steps: the grouped symmetric lists of the flagged groups
        // only, 10% and 100% of them. The active 10% is one run of targets
        // (compact in space along the curve, as a shock region is).
        let groups = n.div_ceil(GROUP_LANES);
        for percent in [10usize, 100] {
            let on = groups * percent / 100;
            let first = (groups - on) / 2;
            let active: Vec<bool> = (0..groups).map(|g| g >= first && g < first + on).collect();
            g.bench_function(format!("neighbors_100_compact_groups_{percent}pct"), |b| {
                b.iter(|| {
                    let st = grouped
                        .find_compact_groups(
                            &tree,
                            &s.bbox,
                            &s.x,
                            &s.y,
                            &s.z,
                            &s.h,
                            0..n,
                            &active,
                            &mut compact,
                        )
                        .unwrap();
                    black_box(st.total)
                })
            });
        }
        // After a drift of up to 0.1 h per axis (in the periodic unit cube):
        // refit the tree.
        let moved: Vec<Vec<f64>> = [&s.x, &s.y, &s.z]
            .iter()
            .enumerate()
            .map(|(d, c)| {
                c.iter()
                    .enumerate()
                    .map(|(i, &v)| {
                        let u = ((i * 7 + d * 13) % 101) as f64 / 50.0 - 1.0;
                        (v + 0.1 * s.h[i] * u).rem_euclid(1.0)
                    })
                    .collect()
            })
            .collect();
        g.bench_function("refit", |b| {
            b.iter(|| {
                tree.refit(&moved[0], &moved[1], &moved[2]).unwrap();
                black_box(tree.num_nodes())
            })
        });
        tree.rebuild(&s.keys, &s.x, &s.y, &s.z, 16).unwrap();
        let st = search
            .find(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, 0..n, &mut list)
            .unwrap();
        eprintln!(
            "{label}: mean neighbours {:.1}, bytes per particle: CSR lists {:.1}, compact lists {:.1}, grouped compact lists {:.1}; tree nodes {}",
            st.total as f64 / n as f64,
            list.bytes() as f64 / n as f64,
            compact_bytes as f64 / n as f64,
            compact.bytes() as f64 / n as f64,
            tree.num_nodes()
        );
        g.finish();
    }
}

/// The benchmark group: `criterion_group!` defines a `pub fn` without docs, which
/// a private module keeps out of the public items that `missing_docs` checks.
mod group {
    criterion::criterion_group!(tree_benches, super::benches);
}
criterion_main!(group::tree_benches);
