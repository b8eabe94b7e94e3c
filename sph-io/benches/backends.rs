//! Write and read MB/s of the two backends (feature `hdf5-c`): 1e6
//! particles x 12 fields (11 `f64`, one `u64` id; 96 MB of field data),
//! each write including the CRC32s, the fsync and the rename, each read
//! including the checks. Prints every repeat and the range, per backend:
//! `cargo bench -p sph-io --features hdf5-c --bench backends [-- REPEATS] [c-first]`.

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use sph_io::{
    BoxSpec, FieldData, H5Part, H5PartC, Selection, Snapshot, SnapshotReader, SnapshotWriter,
};

const N: usize = 1_000_000;

fn snapshot() -> Snapshot {
    let mut s = Snapshot::new(1000, 0.1, 1e-4, BoxSpec::default());
    let mut r: u64 = 0x1234_5678;
    for name in ["x", "y", "z", "vx", "vy", "vz", "h", "m", "u", "rho", "p"] {
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

fn main() {
    // `cargo bench` passes `--bench`; a bare number is the repeat count.
    let repeats = std::env::args()
        .skip(1)
        .find_map(|a| a.parse::<usize>().ok())
        .unwrap_or(5);
    let snap = snapshot();
    let mb = (N * 8 * snap.fields.len()) as f64 / 1e6;
    let dir = tempfile::tempdir().expect("temp dir");
    let write = |c: bool, p: &Path| {
        if c {
            H5PartC.write(p, &snap, &Selection::All)
        } else {
            H5Part.write(p, &snap, &Selection::All)
        }
        .expect("write")
    };
    let read = |c: bool, p: &Path| {
        if c {
            H5PartC.read_step(p, 0, &Selection::All)
        } else {
            H5Part.read_step(p, 0, &Selection::All)
        }
        .expect("read")
    };
    println!(
        "1e6 particles x {} fields = {mb:.0} MB, {repeats} repeats",
        snap.fields.len()
    );
    let mut order = [("hdf5-pure (H5Part)", false), ("libhdf5 (H5PartC)", true)];
    // `c-first`: measure the libhdf5 backend first (order effects of the
    // page cache and of the disk's write-back).
    if std::env::args().any(|a| a == "c-first") {
        order.reverse();
    }
    for (name, c) in order {
        let path = dir.path().join("bench.h5");
        let (mut w, mut r) = (Vec::new(), Vec::new());
        for _ in 0..repeats {
            let t = Instant::now();
            write(c, &path);
            w.push(mb / t.elapsed().as_secs_f64());
            let t = Instant::now();
            let back = black_box(read(c, &path));
            r.push(mb / t.elapsed().as_secs_f64());
            assert_eq!(back.len(), N);
        }
        let size = std::fs::metadata(&path).expect("file").len();
        let range = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            format!(
                "{:.0}-{:.0} MB/s (median {:.0})",
                v[0],
                v[v.len() - 1],
                v[v.len() / 2]
            )
        };
        println!(
            "{name}: write {}, read {}; file {size} bytes",
            range(&mut w),
            range(&mut r)
        );
    }
    // Each backend reads the other's file: the same snapshot.
    let (a, b) = (dir.path().join("a.h5"), dir.path().join("b.h5"));
    H5Part.write(&a, &snap, &Selection::All).expect("write");
    H5PartC.write(&b, &snap, &Selection::All).expect("write");
    assert!(H5PartC
        .read_step(&a, 0, &Selection::All)
        .expect("read")
        .bits_eq(&snap));
    assert!(H5Part
        .read_step(&b, 0, &Selection::All)
        .expect("read")
        .bits_eq(&snap));
}
