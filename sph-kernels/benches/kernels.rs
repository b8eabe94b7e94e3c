//! Per-evaluation cost of exact kernels vs lookup tables and polynomial fits.
//!
//! Each iteration evaluates `shape_and_derivative` at 1e6 pseudo-random
//! distances in [0, 2] (precomputed), so ns per evaluation = time / 1e6;
//! criterion also prints it as throughput (elements/s).

// criterion_group! defines a public function without docs.
#![allow(missing_docs)]

use std::hint::black_box;
use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, Criterion, Throughput};
use sph_kernels::{
    CubicSpline, F64s, FastKernel, Kernel, Polynomial, Sinc, SinglePower, Tabulated, WendlandC2,
    LANES,
};

const EVALUATIONS: usize = 1_000_000;

/// Reproducible distances in [0, 2] from a 64-bit LCG (no rand dependency).
fn distances() -> Vec<f64> {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    (0..EVALUATIONS)
        .map(|_| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            2.0 * (state >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

/// A scalar loop over all distances; statically dispatched like a solver's
/// generic hot loop would be.
fn sweep<K: Kernel>(kernel: &K, vs: &[f64]) -> f64 {
    let mut acc = 0.0;
    for &v in vs {
        let (w, dw) = kernel.shape_and_derivative(black_box(v));
        acc += w + dw;
    }
    acc
}

/// The lane form over all distances, [`LANES`] at a time: what the pair
/// loops call.
fn sweep_lanes<K: Kernel>(kernel: &K, vs: &[f64]) -> f64 {
    let mut acc = F64s::splat(0.0);
    for chunk in vs.chunks_exact(LANES) {
        let v = F64s::from_array(chunk.try_into().expect("a lane"));
        let (w, dw) = kernel.shape_and_derivative_lanes(black_box(v));
        acc += w + dw;
    }
    acc.sum()
}

/// The squared-argument lane form of the density and IAD passes (`w` and
/// `v w'` from `v^2`, no square root), over the same distances.
fn sweep_sq_lanes<K: Kernel>(kernel: &K, vs: &[f64]) -> f64 {
    let mut acc = F64s::splat(0.0);
    for chunk in vs.chunks_exact(LANES) {
        let v = F64s::from_array(chunk.try_into().expect("a lane"));
        let (w, vdw) = kernel.shape_and_v_derivative_sq_lanes(black_box(v * v));
        acc += w + vdw;
    }
    acc.sum()
}

fn bench<K: Kernel>(group: &mut BenchmarkGroup<'_, WallTime>, name: &str, kernel: &K, vs: &[f64]) {
    group.bench_function(name, |b| b.iter(|| black_box(sweep(kernel, vs))));
}

fn configure<'a>(c: &'a mut Criterion, name: &str) -> BenchmarkGroup<'a, WallTime> {
    let mut group = c.benchmark_group(name);
    group
        .throughput(Throughput::Elements(EVALUATIONS as u64))
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    group
}

fn sinc6(c: &mut Criterion) {
    let vs = distances();
    let exact = Sinc::new(6.0).unwrap();
    let table = Tabulated::new(&exact, Tabulated::DEFAULT_POINTS).unwrap();
    let mut group = configure(c, "sinc6");
    bench(&mut group, "exact", &exact, &vs);
    bench(&mut group, "table", &table, &vs);
    // A table that fits in L1 shows how much of the cost is cache traffic.
    let small = Tabulated::new(&exact, 2_000).unwrap();
    bench(&mut group, "table-2000-points", &small, &vs);
    let poly = Polynomial::fit(&exact, 1e-9).unwrap();
    bench(&mut group, "polynomial", &poly, &vs);
    group.bench_function("table-lanes", |b| {
        b.iter(|| black_box(sweep_lanes(&table, &vs)))
    });
    group.bench_function("polynomial-lanes", |b| {
        b.iter(|| black_box(sweep_lanes(&poly, &vs)))
    });
    group.bench_function("polynomial-squared-lanes", |b| {
        b.iter(|| black_box(sweep_sq_lanes(&poly, &vs)))
    });
    // The solver's forms: the power of the sinc base, in f64 and in f32.
    let FastKernel::Power(power) = FastKernel::new(&exact).unwrap() else {
        unreachable!("sinc:6 has a power form")
    };
    let single = SinglePower::new(&power);
    group.bench_function("power-squared-lanes", |b| {
        b.iter(|| black_box(sweep_sq_lanes(&power, &vs)))
    });
    group.bench_function("single-power-squared-lanes", |b| {
        b.iter(|| black_box(sweep_sq_lanes(&single, &vs)))
    });
    group.finish();
}

fn others(c: &mut Criterion) {
    let vs = distances();
    let mut group = configure(c, "others");
    bench(
        &mut group,
        "sinc5.5-exact-powf",
        &Sinc::new(5.5).unwrap(),
        &vs,
    );
    bench(&mut group, "m4-exact", &CubicSpline, &vs);
    bench(&mut group, "wendland-c2-exact", &WendlandC2, &vs);
    group.finish();
}

criterion_group!(benches, sinc6, others);
criterion_main!(benches);
