//! Hot paths of the communication crate: `ExactSum` accumulation against a
//! plain `f64` sum (the conserved quantities add ~12 values per particle per
//! step), merging partial sums, and the serial sparse exchange and
//! all-to-all-v (the serial cost of a halo exchange).

use criterion::{criterion_main, Criterion, Throughput};
use sph_comm::{Communicator, ExactSum, SerialComm};
use std::hint::black_box;

fn values(n: usize) -> Vec<f64> {
    let mut s: u64 = 0x1234_5678;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            u * 2f64.powi((s % 40) as i32 - 20)
        })
        .collect()
}

fn sums(c: &mut Criterion) {
    let n = 1 << 20;
    let xs = values(n);
    let mut g = c.benchmark_group("sum_1M");
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("plain_f64", |b| {
        b.iter(|| black_box(&xs).iter().sum::<f64>())
    });
    g.bench_function("exact_sum", |b| {
        b.iter(|| {
            let mut s = ExactSum::new();
            s.add_slice(black_box(&xs));
            s.value()
        })
    });
    g.finish();

    let parts: Vec<ExactSum> = xs
        .chunks(n / 64)
        .map(|c| c.iter().copied().collect())
        .collect();
    c.bench_function("exact_sum_merge_64_and_round", |b| {
        b.iter(|| {
            let mut s = ExactSum::new();
            for p in black_box(&parts) {
                s.merge(p);
            }
            s.value()
        })
    });
}

fn exchange(c: &mut Criterion) {
    let comm = SerialComm::new();
    // A halo-exchange-sized message: 8 fields of 20k particles.
    let data = values(160_000);
    let mut g = c.benchmark_group("serial_exchange_160k");
    g.throughput(Throughput::Bytes((data.len() * 8) as u64));
    g.bench_function("sparse_exchange", |b| {
        b.iter(|| comm.sparse_exchange(&[(0, black_box(&data[..]))]).unwrap())
    });
    g.bench_function("all_to_all_v", |b| {
        b.iter(|| comm.all_to_all_v(black_box(&data), &[data.len()]).unwrap())
    });
    g.finish();
}

/// The benchmark group: `criterion_group!` defines a `pub fn` without docs, which
/// a private module keeps out of the public items that `missing_docs` checks.
mod group {
    criterion::criterion_group!(benches, super::sums, super::exchange);
}
criterion_main!(group::benches);
