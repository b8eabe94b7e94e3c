//! Cost of one `Domain::sync` (steady state: particles already in place,
//! as in a time step) on one rank and on 4 in-process ranks, and of one
//! halo exchange of 4 fields on 4 ranks: `exchange`, `exchange_where` for a
//! 10% subset and for every particle, and `exchange_reverse_min` of one `u8`
//! per particle. In-process ranks share this machine's cores: compare the
//! figures with each other, not with MPI.

use criterion::{criterion_main, BenchmarkId, Criterion};
use sph_comm::{run_ranks, Communicator, SerialComm};
use sph_domain::{Domain, DomainConfig, Points};
use sph_tree::{Boundary, BoundingBox};
use std::time::{Duration, Instant};

/// `side^3` lattice points of the unit periodic cube, jittered, h for ~100
/// neighbours; every `ranks`-th point on rank `rank`.
fn lattice(side: usize, rank: usize, ranks: usize) -> Points {
    let n = side * side * side;
    let h = 0.5 * (3.0 / (4.0 * std::f64::consts::PI) * 100.0 / n as f64).cbrt();
    let mut p = Points::default();
    for i in (rank..n).step_by(ranks) {
        let c = [i % side, i / side % side, i / (side * side)];
        let jitter = |k: usize| ((i * 2654435761 + k * 97) % 1000) as f64 * 1e-4;
        let pos = [0, 1, 2].map(|k| (c[k] as f64 + 0.25 + 0.5 * jitter(k)) / side as f64);
        p.push(i as u64, pos, h);
    }
    p
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("sync");
    g.sample_size(10).measurement_time(Duration::from_secs(10));
    for side in [50usize, 100] {
        let n = side * side * side;
        g.bench_function(BenchmarkId::new("serial", n), |b| {
            let mut p = lattice(side, 0, 1);
            let mut bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
            let mut d = Domain::new(SerialComm::new(), DomainConfig::default()).unwrap();
            d.sync(&mut p, &mut bbox).unwrap();
            b.iter(|| d.sync(&mut p, &mut bbox).unwrap());
        });
        g.bench_function(BenchmarkId::new("4 thread-ranks", n), |b| {
            b.iter_custom(|iters| {
                let times = run_ranks(4, |comm| {
                    let mut p = lattice(side, comm.rank(), 4);
                    let mut bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
                    let mut d = Domain::new(&comm, DomainConfig::default()).unwrap();
                    d.sync(&mut p, &mut bbox).unwrap();
                    comm.barrier();
                    let t = Instant::now();
                    for _ in 0..iters {
                        d.sync(&mut p, &mut bbox).unwrap();
                    }
                    t.elapsed()
                });
                times.into_iter().max().unwrap()
            });
        });
    }
    g.finish();

    let mut g = c.benchmark_group("exchange");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    let side = 50usize;
    let n = side * side * side;
    for kind in ["exchange", "where 10%", "where 100%", "reverse_min u8"] {
        g.bench_function(BenchmarkId::new(kind, n), |b| {
            b.iter_custom(|iters| {
                let times = run_ranks(4, |comm| {
                    let mut p = lattice(side, comm.rank(), 4);
                    let mut bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
                    let mut d = Domain::new(&comm, DomainConfig::default()).unwrap();
                    d.sync(&mut p, &mut bbox).unwrap();
                    let len = p.id.len();
                    let mut fields = vec![vec![1.0f64; len]; 4];
                    let mut bins = vec![7u8; len];
                    let ids = &p.id;
                    comm.barrier();
                    let t = Instant::now();
                    for _ in 0..iters {
                        let mut f: Vec<&mut [f64]> =
                            fields.iter_mut().map(|v| v.as_mut_slice()).collect();
                        match kind {
                            "exchange" => d.exchange(&mut f).unwrap(),
                            "where 10%" => d
                                .exchange_where(&mut f, |i| ids[i].is_multiple_of(10))
                                .unwrap(),
                            "where 100%" => d.exchange_where(&mut f, |_| true).unwrap(),
                            _ => d.exchange_reverse_min(&mut bins).unwrap(),
                        }
                    }
                    t.elapsed()
                });
                times.into_iter().max().unwrap()
            });
        });
    }
    g.finish();
}

/// The benchmark group: `criterion_group!` defines a `pub fn` without docs, which
/// a private module keeps out of the public items that `missing_docs` checks.
mod group {
    criterion::criterion_group!(benches, super::bench);
}
criterion_main!(group::benches);
