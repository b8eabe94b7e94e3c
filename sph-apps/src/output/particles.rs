//! `particles.csv`: the final state of every particle, one row per particle
//! in ascending id, every float in Rust's shortest round-trip form (`{:?}`),
//! so the file holds the exact bits.
//!
//! No rank ever holds all particles: the file is streamed in rounds of at
//! most [`CHUNK`] consecutive ids. In each round every rank sends its rows
//! of those ids to rank 0 (one all-to-all-v, empty for the other
//! destinations), which orders them by id and appends them to the file. The
//! rows are the same whatever the rank count, and so is the file, byte for
//! byte.

use super::CsvFile;
use crate::AppError;
use sph_comm::{Communicator, ReduceOp};
use sph_core::Particles;
use std::ops::Range;
use std::path::Path;

/// Column names of `particles.csv`.
pub const HEADER: &str = "id,x,y,z,vx,vy,vz,h,m,u,rho,p";

/// Words per row in transit: the id and the bits of eleven fields.
const WORDS: usize = 12;

/// Most ids (and therefore rows) per round: 32768 rows, 3 MB in transit.
pub const CHUNK: u64 = 1 << 15;

/// Writes the `owned` particles of `p` of every rank of `comm` into `path`
/// (collective: every rank calls it; rank 0 writes). Ids must be unique.
///
/// # Errors
/// On every rank if rank 0 could not write the file (rank 0 names the
/// cause); on a communication failure.
pub fn write<C: Communicator>(
    path: &Path,
    p: &Particles,
    owned: Range<usize>,
    comm: &C,
) -> Result<(), AppError> {
    write_in_rounds(path, p, owned, comm, CHUNK)
}

/// [`write`] with rounds of `chunk` ids.
fn write_in_rounds<C: Communicator>(
    path: &Path,
    p: &Particles,
    owned: Range<usize>,
    comm: &C,
    chunk: u64,
) -> Result<(), AppError> {
    let root = comm.rank() == 0;
    let mut file = None;
    let mut failure = None;
    if root {
        match CsvFile::create(path).and_then(|mut f| f.line(HEADER).map(|()| f)) {
            Ok(f) => file = Some(f),
            Err(e) => failure = Some(e),
        }
    }
    // This rank's particles in id order; `next` is the first not yet sent.
    let mut order: Vec<usize> = owned.collect();
    order.sort_unstable_by_key(|&i| p.id[i]);
    let mut next = 0;
    let mut send: Vec<u64> = Vec::new();
    let mut counts = vec![0usize; comm.size()];
    loop {
        // The round starts at the smallest id not yet written (every round
        // holds at least one row, however sparse the ids).
        let pending = order.get(next).map_or(u64::MAX, |&i| p.id[i]);
        let lo = comm.all_reduce_scalar(pending, ReduceOp::Min);
        if lo == u64::MAX {
            break;
        }
        let hi = lo.saturating_add(chunk);
        let end = next + order[next..].partition_point(|&i| p.id[i] < hi);
        send.clear();
        for &i in &order[next..end] {
            send.push(p.id[i]);
            send.extend(
                [
                    p.x[i], p.y[i], p.z[i], p.vx[i], p.vy[i], p.vz[i], p.h[i], p.m[i], p.u[i],
                    p.rho[i], p.p[i],
                ]
                .map(f64::to_bits),
            );
        }
        next = end;
        counts[0] = send.len();
        let got = comm.all_to_all_v(&send, &counts)?;
        if let Some(f) = file.as_mut() {
            let mut rows: Vec<&[u64]> = got.data.chunks_exact(WORDS).collect();
            rows.sort_unstable_by_key(|r| r[0]);
            if let Err(e) = rows.iter().try_for_each(|r| write_row(f, r)) {
                failure = Some(e);
                file = None;
            }
        }
    }
    if let Some(f) = file.as_mut() {
        if let Err(e) = f.flush() {
            failure = Some(e);
        }
    }
    let failed = comm.all_reduce_scalar(u64::from(failure.is_some()), ReduceOp::Max);
    match failure {
        Some(e) => Err(e),
        None if failed > 0 => Err(AppError::io(
            path,
            std::io::Error::other("rank 0 could not write the file"),
        )),
        None => Ok(()),
    }
}

/// One row: the id, then the fields in shortest round-trip form.
fn write_row(f: &mut CsvFile, r: &[u64]) -> Result<(), AppError> {
    let v = |k: usize| f64::from_bits(r[k]);
    f.line_fmt(format_args!(
        "{},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?}",
        r[0],
        v(1),
        v(2),
        v(3),
        v(4),
        v(5),
        v(6),
        v(7),
        v(8),
        v(9),
        v(10),
        v(11)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use sph_comm::{run_ranks, SerialComm};
    use sph_core::FieldSet;

    /// 23 particles with sparse ids (a permutation of 0..23, times 3, plus
    /// 0 or 1), in an order unrelated to the ids (as an SFC order would be).
    fn particles() -> Particles {
        let n = 23;
        let mut p = Particles::new(n, FieldSet::default());
        for k in 0..n {
            let id = ((k * 11) % n * 3 + k % 2) as u64;
            p.id[k] = id;
            let v = (id as f64 + 0.1) / 3.0;
            for (j, f) in [
                &mut p.x, &mut p.y, &mut p.z, &mut p.vx, &mut p.vy, &mut p.vz, &mut p.h, &mut p.m,
                &mut p.u, &mut p.rho, &mut p.p,
            ]
            .into_iter()
            .enumerate()
            {
                f[k] = v * (j as f64 + 1.0) - 7.0;
            }
        }
        p
    }

    fn dir(name: &str) -> std::path::PathBuf {
        crate::test_dir(&format!("particles-{name}"))
    }

    #[test]
    fn same_bytes_in_id_order_on_any_rank_count_and_chunk() {
        let p = particles();
        let n = p.len();
        let mut ids = p.id.clone();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), n, "ids unique");
        // The expected file: rows by id, fields in round-trip form.
        let mut want = format!("{HEADER}\n");
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by_key(|&i| p.id[i]);
        for i in order {
            want += &format!(
                "{},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?}\n",
                p.id[i],
                p.x[i],
                p.y[i],
                p.z[i],
                p.vx[i],
                p.vy[i],
                p.vz[i],
                p.h[i],
                p.m[i],
                p.u[i],
                p.rho[i],
                p.p[i]
            );
        }
        let d = dir("ranks");
        let path = d.join("serial.csv");
        write(&path, &p, 0..n, &SerialComm::new()).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), want);
        for ranks in 1..=3 {
            for chunk in [1, 4, 1000] {
                let path = d.join(format!("{ranks}-{chunk}.csv"));
                run_ranks(ranks, |comm| {
                    // Each rank owns a contiguous slice of the local arrays,
                    // with two halo-like particles in front of it.
                    let r = comm.rank();
                    let (lo, hi) = (n * r / ranks, n * (r + 1) / ranks);
                    let mut local = p.clone();
                    local.keep(lo.saturating_sub(2)..hi);
                    let owned = lo - lo.saturating_sub(2)..local.len();
                    write_in_rounds(&path, &local, owned, &comm, chunk).unwrap();
                });
                assert_eq!(
                    std::fs::read_to_string(&path).unwrap(),
                    want,
                    "{ranks} ranks, chunks of {chunk}"
                );
            }
        }
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn an_unwritable_file_fails_on_every_rank() {
        let p = particles();
        let n = p.len();
        let path = dir("fail").join("missing-folder").join("particles.csv");
        let results = run_ranks(2, |comm| {
            let r = comm.rank();
            let mut local = p.clone();
            local.keep(n * r / 2..n * (r + 1) / 2);
            write(&path, &local, 0..local.len(), &comm).is_err()
        });
        assert_eq!(results, vec![true, true]);
        std::fs::remove_dir_all(dir("fail")).ok();
    }
}
