//! Snapshot throughput: write and read 1e6 particles x 10 fields (9 `f64`,
//! one `u64` id; 80 MB of field data) through the H5Part backend, and the
//! CRC32 of one field alone; the same particles written and read in the
//! SWIFT layout (`sph_io::swift`). Criterion reports bytes of field data
//! per second.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_main, Criterion, Throughput};
use sph_io::swift::{read_swift, write_swift, SwiftParticles};
use sph_io::{BoxSpec, FieldData, H5Part, Selection, Snapshot, SnapshotReader, SnapshotWriter};

const N: usize = 1_000_000;

fn snapshot() -> Snapshot {
    let mut s = Snapshot::new(1000, 0.1, 1e-4, BoxSpec::default());
    let mut r: u64 = 0x1234_5678;
    for name in ["x", "y", "z", "vx", "vy", "vz", "h", "m", "u"] {
        let v = (0..N)
            .map(|_| {
                r = r
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (r >> 11) as f64 / (1u64 << 53) as f64
            })
            .collect();
        s.set_field(name, FieldData::F64(v));
    }
    s.set_field("id", FieldData::U64((0..N as u64).collect()));
    s
}

fn io(c: &mut Criterion) {
    let snap = snapshot();
    let bytes = (N * 8 * snap.fields.len()) as u64;
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("bench.h5");

    let mut g = c.benchmark_group("h5part_1e6x10");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(10))
        .throughput(Throughput::Bytes(bytes));
    g.bench_function("write", |b| {
        b.iter(|| {
            H5Part
                .write(&path, black_box(&snap), &Selection::All)
                .expect("write")
        })
    });
    H5Part.write(&path, &snap, &Selection::All).expect("write");
    g.bench_function("read", |b| {
        b.iter(|| black_box(H5Part.read_step(&path, 0, &Selection::All).expect("read")))
    });
    g.finish();

    // The same particles as a SWIFT snapshot (N x 3 coordinates and
    // velocities, no checksums, finiteness checked both ways).
    let col = |name: &str| {
        snap.field(name)
            .and_then(FieldData::as_f64)
            .expect(name)
            .to_vec()
    };
    let gas = SwiftParticles {
        x: col("x"),
        y: col("y"),
        z: col("z"),
        vx: col("vx"),
        vy: col("vy"),
        vz: col("vz"),
        m: col("m"),
        h: col("h"),
        u: col("u"),
        id: (0..N as u64).collect(),
        box_size: [1.0; 3],
        ..SwiftParticles::default()
    };
    let swift = dir.path().join("bench.hdf5");
    let mut g = c.benchmark_group("swift_1e6x10");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(10))
        .throughput(Throughput::Bytes(bytes));
    g.bench_function("write", |b| {
        b.iter(|| write_swift(&swift, black_box(&gas)).expect("write"))
    });
    write_swift(&swift, &gas).expect("write");
    g.bench_function("read", |b| {
        b.iter(|| black_box(read_swift(&swift).expect("read")))
    });
    g.finish();

    let field = &snap.fields[0].data;
    let mut g = c.benchmark_group("crc32_1e6");
    g.throughput(Throughput::Bytes((N * 8) as u64));
    g.bench_function("f64_field", |b| b.iter(|| black_box(field).crc32()));
    g.finish();
}

/// The benchmark group (a plain function: `criterion_group!` leaves it undocumented).
fn benches() {
    let mut c = Criterion::default().configure_from_args();
    io(&mut c);
}

criterion_main!(benches);
