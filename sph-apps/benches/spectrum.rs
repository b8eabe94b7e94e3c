//! The spectrum of one snapshot: TSC deposit of 32^3 particles (a jittered
//! lattice with a smooth velocity field) on a 32^3 grid, the deconvolved
//! velocity spectrum of that grid, and both together.

use criterion::{criterion_main, Criterion, Throughput};
use sph_apps::rng::SplitMix64;
use sph_apps::spectrum::{velocity_spectrum, DepositScale, Extremes, SpectrumGrid};
use std::f64::consts::PI;
use std::hint::black_box;

const N: usize = 32;

struct Particles {
    pos: [Vec<f64>; 3],
    m: Vec<f64>,
    v: [Vec<f64>; 3],
}

fn particles() -> Particles {
    let mut rng = SplitMix64(42);
    let count = N * N * N;
    let mut p = Particles {
        pos: Default::default(),
        m: vec![1.0 / count as f64; count],
        v: Default::default(),
    };
    for i in 0..count {
        let idx = [i / (N * N), i / N % N, i % N];
        let x = idx.map(|j| (j as f64 + 0.5 + 0.3 * (rng.uniform() - 0.5)) / N as f64);
        let v = [
            (2.0 * PI * x[1]).sin() + 0.1 * (6.0 * PI * x[2]).cos(),
            (2.0 * PI * x[2]).sin(),
            (4.0 * PI * x[0]).cos(),
        ];
        for d in 0..3 {
            p.pos[d].push(x[d]);
            p.v[d].push(v[d]);
        }
    }
    p
}

fn deposit(p: &Particles, scale: DepositScale) -> SpectrumGrid {
    let mut g = SpectrumGrid::new(N, [0.0; 3], 1.0, scale).expect("grid");
    g.deposit(
        &p.pos[0], &p.pos[1], &p.pos[2], &p.m, &p.v[0], &p.v[1], &p.v[2],
    )
    .expect("deposit");
    g
}

fn spectrum(c: &mut Criterion) {
    let p = particles();
    let extremes = Extremes::local(&p.m, &p.v[0], &p.v[1], &p.v[2]).expect("extremes");
    let scale = DepositScale::new(extremes, p.m.len() as u64).expect("scale");
    let grid = deposit(&p, scale);
    let mut g = c.benchmark_group("spectrum_32");
    g.throughput(Throughput::Elements(p.m.len() as u64));
    g.sample_size(20);
    g.bench_function("deposit", |b| b.iter(|| deposit(black_box(&p), scale)));
    g.bench_function("velocity_spectrum", |b| {
        b.iter(|| velocity_spectrum(black_box(&grid), true).expect("spectrum"))
    });
    g.bench_function("deposit_and_spectrum", |b| {
        b.iter(|| velocity_spectrum(&deposit(black_box(&p), scale), true).expect("spectrum"))
    });
    g.finish();
}

/// The benchmark group: `criterion_group!` defines a `pub fn` without docs, which
/// a private module keeps out of the public items that `missing_docs` checks.
mod group {
    criterion::criterion_group!(benches, super::spectrum);
}
criterion_main!(group::benches);
