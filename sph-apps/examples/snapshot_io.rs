//! Write and read speed of distributed snapshot files: every rank writes
//! its share of `N` particles x 12 fields (11 `f64` + `id`) into one H5Part
//! file and reads its share back (checksums verified), as `sphexa run` does.
//!
//! ```sh
//! cargo run --release -p sph-apps --example snapshot_io -- 1000000 DIR
//! cargo build --release -p sph-apps --features mpi --example snapshot_io
//! mpirun -n 2 target/release/examples/snapshot_io 1000000 DIR
//! ```
//!
//! Prints, for each of 3 repetitions, the slowest rank's seconds and MB/s
//! (file bytes / seconds) of the write (including the fsync and the
//! rename) and of the read (from the page cache: the file was just
//! written), and the file's bytes per particle.

use sph_apps::output::snapshot as snapfile;
use sph_comm::Communicator;
use sph_io::{BoxSpec, FieldData, Selection, Snapshot};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let total: u64 = args.get(1).map_or(Ok(1_000_000), |s| s.parse())?;
    let dir = std::path::PathBuf::from(args.get(2).map_or("snapshot-io", String::as_str));
    #[cfg(feature = "mpi")]
    let comm = sph_comm::MpiComm::init()?;
    #[cfg(not(feature = "mpi"))]
    let comm = sph_comm::SerialComm::new();
    let (r, size) = (comm.rank() as u64, comm.size() as u64);
    if r == 0 {
        std::fs::create_dir_all(&dir)?;
    }
    comm.barrier();
    let rows = total * r / size..total * (r + 1) / size;
    let mut snap = Snapshot::new(1, 0.5, 1e-3, BoxSpec::default());
    for (k, name) in ["x", "y", "z", "vx", "vy", "vz", "h", "m", "u", "rho", "p"]
        .iter()
        .enumerate()
    {
        let v: Vec<f64> = rows
            .clone()
            .map(|i| ((i as f64) * 1e-3 + k as f64).sin())
            .collect();
        snap.set_field(name, FieldData::F64(v));
    }
    snap.set_field("id", FieldData::U64(rows.clone().collect()));
    let path = dir.join(format!("io_{size}ranks.h5"));
    for rep in 0..3 {
        let write_s = snapfile::write(&comm, &path, &snap)?;
        let t = std::time::Instant::now();
        let (back, n) = snapfile::read_share(&comm, &path, 0, &Selection::All)?;
        let read_s = comm.all_reduce_scalar(t.elapsed().as_secs_f64(), sph_comm::ReduceOp::Max);
        assert!(back.bits_eq(&snap) && n == total, "read back differs");
        if r == 0 {
            let bytes = std::fs::metadata(&path)?.len() as f64;
            println!(
                "{size} rank(s), {total} particles x 12 fields, rep {rep}: write {write_s:.3} s = {:.0} MB/s, read {read_s:.3} s = {:.0} MB/s, {:.2} bytes/particle",
                bytes / write_s / 1e6,
                bytes / read_s / 1e6,
                bytes / total as f64
            );
        }
    }
    Ok(())
}
