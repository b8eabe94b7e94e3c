//! MPI tests (built only with `--features mpi`).
//!
//! Run by `cargo test -p sph-comm --features mpi`: without arguments this
//! binary is the launcher, which starts itself under `mpirun -n 1`, `-n 2`
//! and `-n 4` (as `sph_comm::launch` builds the command) with
//! `--mpi-child N` and checks that every run succeeds and that the reproducible
//! sums have the same bits for every rank count. As a child it runs the
//! checks on `MpiComm`: all-reduce, sparse exchange (random peer sets,
//! self-sends, empty and large messages, many back-to-back rounds, a
//! type-mismatch error), all-to-all-v, all-gather-v and `ExactSum`.

use std::process::Stdio;
use std::time::{Duration, Instant};

use sph_comm::{exact_sum, CommError, Communicator, ExactSum, MpiComm, ReduceOp};

const RANK_COUNTS: [usize; 3] = [1, 2, 4];
const TIMEOUT: Duration = Duration::from_secs(180);

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--mpi-child") {
        let n: usize = args[i + 1].parse().expect("rank count");
        child(n);
    } else {
        launcher();
    }
}

// ---------------------------------------------------------------- launcher

fn launcher() {
    let exe = std::env::current_exe().expect("own path");
    let mpi = sph_comm::launch::Launcher::detect().unwrap_or_else(|e| panic!("{e}"));

    let (mut passed, mut failed) = (0, 0);
    let mut sums: Vec<(usize, String)> = Vec::new();
    for n in RANK_COUNTS {
        let mut cmd = mpi.command(n);
        cmd.arg(&exe).arg("--mpi-child").arg(n.to_string());
        cmd.stdout(Stdio::piped()).stderr(Stdio::piped());
        let start = Instant::now();
        let child = cmd.spawn().expect("spawn mpirun");
        let output = wait_with_timeout(child, TIMEOUT);
        let stdout = String::from_utf8_lossy(&output.0).to_string();
        let stderr = String::from_utf8_lossy(&output.1).to_string();
        let ok = output.2 == Some(true);
        println!(
            "mpirun -n {n}: {} in {:.1} s",
            if ok { "ok" } else { "FAILED" },
            start.elapsed().as_secs_f64()
        );
        if !ok {
            println!("--- stdout ---\n{stdout}\n--- stderr ---\n{stderr}");
            failed += 1;
            continue;
        }
        let lines: Vec<&str> = stdout
            .lines()
            .filter(|l| l.starts_with("exact-sum"))
            .collect();
        if lines.len() != 1 {
            println!("expected one exact-sum line from rank 0, got {lines:?}");
            failed += 1;
            continue;
        }
        sums.push((n, lines[0].to_string()));
        passed += 1;
    }
    if let Some((n0, s0)) = sums.first() {
        for (n, s) in &sums[1..] {
            if s != s0 {
                println!("ExactSum differs between {n0} and {n} ranks:\n  {s0}\n  {s}");
                failed += 1;
            }
        }
        println!("{s0} (same for all rank counts)");
    }
    println!("mpi: {passed} passed, {failed} failed");
    if failed > 0 {
        std::process::exit(1);
    }
}

/// Waits for the child, killing it after `timeout`. Returns stdout, stderr
/// and `Some(success)` (None after a timeout).
fn wait_with_timeout(
    mut child: std::process::Child,
    timeout: Duration,
) -> (Vec<u8>, Vec<u8>, Option<bool>) {
    use std::io::Read;
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let t_out = std::thread::spawn(move || {
        let mut v = Vec::new();
        out.read_to_end(&mut v).ok();
        v
    });
    let t_err = std::thread::spawn(move || {
        let mut v = Vec::new();
        err.read_to_end(&mut v).ok();
        v
    });
    let start = Instant::now();
    let status = loop {
        match child.try_wait().expect("wait") {
            Some(s) => break Some(s.success()),
            None if start.elapsed() > timeout => {
                eprintln!("mpirun timed out after {timeout:?}; killing it");
                child.kill().ok();
                child.wait().ok();
                break None;
            }
            None => std::thread::sleep(Duration::from_millis(20)),
        }
    };
    (t_out.join().unwrap(), t_err.join().unwrap(), status)
}

// ---------------------------------------------------------------- child

fn hash(words: &[u64]) -> u64 {
    let mut h = 0x243f_6a88_85a3_08d3u64;
    for &w in words {
        h = splitmix(h ^ w);
    }
    h
}

fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

fn child(expected_size: usize) {
    let comm = MpiComm::init().expect("MPI init");
    assert!(matches!(
        MpiComm::init(),
        Err(CommError::AlreadyInitialized)
    ));
    let (rank, size) = (comm.rank(), comm.size());
    // One rank per process: the pool may drive it unless MPI is funneled.
    assert_eq!(
        comm.may_drive_from_pool(),
        comm.thread_level() != sph_comm::ThreadLevel::Funneled
    );
    assert_eq!(size, expected_size, "communicator size");
    assert!(rank < size);

    let mut checks = 0;
    let mut run = |name: &str, f: &dyn Fn(&MpiComm)| {
        f(&comm);
        comm.barrier();
        checks += 1;
        if rank == 0 {
            println!("rank 0: {name} ok");
        }
    };
    run("all_gather", &check_all_gather);
    run("all_reduce", &check_all_reduce);
    run("sparse_exchange", &check_sparse_exchange);
    run("sparse_exchange type mismatch", &check_exchange_error);
    run("all_to_all_v", &check_all_to_all_v);
    run("exact_sum", &check_exact_sum);
    if rank == 0 {
        println!("rank 0 of {size}: {checks} checks passed");
    }
}

fn check_all_gather(comm: &MpiComm) {
    let (rank, size) = (comm.rank(), comm.size());
    assert_eq!(comm.all_gather_scalar(rank), (0..size).collect::<Vec<_>>());
    // Rank r contributes r elements (rank 0 nothing).
    let mine: Vec<u32> = (0..rank as u32).map(|i| 100 * rank as u32 + i).collect();
    let g = comm.all_gather_v(&mine).unwrap();
    assert_eq!(g.counts, (0..size).collect::<Vec<_>>());
    for r in 0..size {
        let want: Vec<u32> = (0..r as u32).map(|i| 100 * r as u32 + i).collect();
        assert_eq!(g.from_rank(r), &want[..]);
    }
}

fn check_all_reduce(comm: &MpiComm) {
    let (rank, size) = (comm.rank(), comm.size());
    let n = size as i64;
    let mut f = [rank as f64 + 0.5, -(rank as f64), 1.0];
    comm.all_reduce(&mut f, ReduceOp::Sum);
    assert_eq!(
        f,
        [
            (n * (n - 1) / 2) as f64 + 0.5 * n as f64,
            -((n * (n - 1) / 2) as f64),
            n as f64
        ]
    );
    let mut f = [rank as f64 + 0.5, -(rank as f64)];
    comm.all_reduce(&mut f, ReduceOp::Min);
    assert_eq!(f, [0.5, -((n - 1) as f64)]);
    let mut f = [rank as f64 + 0.5, -(rank as f64)];
    comm.all_reduce(&mut f, ReduceOp::Max);
    assert_eq!(f, [(n - 1) as f64 + 0.5, 0.0]);
    let mut u = [rank as u64, u64::MAX - rank as u64];
    comm.all_reduce(&mut u, ReduceOp::Max);
    assert_eq!(u, [(n - 1) as u64, u64::MAX]);
    let mut i = [rank as i64 - 7, 3];
    comm.all_reduce(&mut i, ReduceOp::Min);
    assert_eq!(i, [-7, 3]);
    let mut i = [rank as i64 - 7, 3];
    comm.all_reduce(&mut i, ReduceOp::Sum);
    assert_eq!(i, [n * (n - 1) / 2 - 7 * n, 3 * n]);
    assert_eq!(
        comm.all_reduce_scalar(rank + 1, ReduceOp::Sum),
        (size * (size + 1)) / 2
    );
    let mut empty: [f64; 0] = [];
    comm.all_reduce(&mut empty, ReduceOp::Sum);
}

/// The messages that `src` sends in round `round`: (dest, payload), several
/// to one destination possible, self included, lengths 0 to 5 and now and
/// then 20000 elements.
fn planned_sends(round: u64, src: usize, size: usize) -> Vec<(usize, Vec<u64>)> {
    let mut out = Vec::new();
    for dst in 0..size {
        let h = hash(&[round, src as u64, dst as u64]);
        let copies = match h % 8 {
            0..=3 => 0,
            4..=6 => 1,
            _ => 2,
        };
        for c in 0..copies {
            let hl = hash(&[h, c]);
            let len = if hl.is_multiple_of(29) {
                20_000
            } else {
                (hl % 6) as usize
            };
            let data = (0..len as u64).map(|i| hash(&[hl, i])).collect();
            out.push((dst, data));
        }
    }
    out
}

fn check_sparse_exchange(comm: &MpiComm) {
    let (rank, size) = (comm.rank(), comm.size());
    for round in 0..300u64 {
        // Skew the ranks now and then so that some are an exchange ahead.
        if hash(&[round, rank as u64, 99]).is_multiple_of(16) {
            std::thread::sleep(Duration::from_millis(2));
        }
        let sends = planned_sends(round, rank, size);
        let mut want = Vec::new();
        for src in 0..size {
            for (dst, data) in planned_sends(round, src, size) {
                if dst == rank {
                    want.push((src, data));
                }
            }
        }
        if round % 2 == 0 {
            let got = comm.sparse_exchange(&sends).unwrap();
            assert_eq!(got, want, "round {round}");
        } else {
            // Same pattern as f64, passed as slices.
            let as_f64: Vec<(usize, Vec<f64>)> = sends
                .iter()
                .map(|(d, v)| (*d, v.iter().map(|&x| (x >> 11) as f64).collect()))
                .collect();
            let slices: Vec<(usize, &[f64])> =
                as_f64.iter().map(|(d, v)| (*d, v.as_slice())).collect();
            let got = comm.sparse_exchange(&slices).unwrap();
            let want: Vec<(usize, Vec<f64>)> = want
                .into_iter()
                .map(|(s, v)| (s, v.iter().map(|&x| (x >> 11) as f64).collect()))
                .collect();
            assert_eq!(got, want, "round {round}");
        }
    }
    // Nobody sends anything.
    let none: Vec<(usize, Vec<u8>)> = Vec::new();
    assert!(comm.sparse_exchange(&none).unwrap().is_empty());
    // An invalid destination is reported before anything is sent.
    assert_eq!(
        comm.sparse_exchange(&[(size, vec![1u8])]),
        Err(CommError::InvalidRank { rank: size, size })
    );
}

/// Rank 0 sends 3 bytes to the last rank, which expects `u64`s.
fn check_exchange_error(comm: &MpiComm) {
    let (rank, size) = (comm.rank(), comm.size());
    if size < 2 {
        return;
    }
    if rank == 0 {
        let got = comm
            .sparse_exchange(&[(size - 1, vec![1u8, 2, 3])])
            .unwrap();
        assert!(got.is_empty());
    } else {
        let none: Vec<(usize, Vec<u64>)> = Vec::new();
        let got = comm.sparse_exchange(&none);
        if rank == size - 1 {
            assert_eq!(
                got,
                Err(CommError::MessageSize {
                    source_rank: 0,
                    bytes: 3,
                    elem_size: 8
                })
            );
        } else {
            assert!(got.unwrap().is_empty());
        }
    }
    // The next exchange is not disturbed.
    let ring = [((rank + 1) % size, vec![rank as i64])];
    let got = comm.sparse_exchange(&ring).unwrap();
    assert_eq!(
        got,
        vec![(
            (rank + size - 1) % size,
            vec![((rank + size - 1) % size) as i64]
        )]
    );
}

fn check_all_to_all_v(comm: &MpiComm) {
    let (rank, size) = (comm.rank(), comm.size());
    let payload = |round: u64, src: usize, dst: usize| -> Vec<i64> {
        let h = hash(&[round, src as u64, dst as u64, 7]);
        let len = (h % 5) as usize;
        (0..len as u64).map(|i| hash(&[h, i]) as i64).collect()
    };
    for round in 0..50u64 {
        let mut send = Vec::new();
        let mut counts = Vec::new();
        for dst in 0..size {
            let p = payload(round, rank, dst);
            counts.push(p.len());
            send.extend(p);
        }
        let g = comm.all_to_all_v(&send, &counts).unwrap();
        for src in 0..size {
            assert_eq!(
                g.from_rank(src),
                &payload(round, src, rank)[..],
                "round {round}"
            );
        }
        // Send it all back: a round trip restores the original.
        let back = comm.all_to_all_v(&g.data, &g.counts).unwrap();
        assert_eq!(back.data, send);
        assert_eq!(back.counts, counts);
    }
    assert_eq!(
        comm.all_to_all_v(&[1u8], &[1]).err(),
        (size != 1).then_some(CommError::CountsLength {
            expected: size,
            got: 1
        })
    );
}

/// 4096 values defined independently of the rank count (dealt round-robin
/// to the ranks): 3072 of all magnitudes, then 512 giants and their 512
/// negations, placed so that each giant and its negation sit on different
/// ranks. The exact sum is moderate, the naive one is dominated by rounding.
fn global_values(set: u64) -> Vec<f64> {
    let mut v: Vec<f64> = (0..3072u64)
        .map(|i| {
            let h = hash(&[set, i]);
            if h.is_multiple_of(4) {
                // Any finite double below 1e200 (tiny and subnormal included).
                let x = f64::from_bits(hash(&[h]));
                if x.is_finite() && x.abs() < 1e200 {
                    x
                } else {
                    1.0
                }
            } else {
                ((h >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2f64.powi((h % 64) as i32 - 32)
            }
        })
        .collect();
    let giants: Vec<f64> = (0..512u64)
        .map(|j| {
            let h = hash(&[set, j, 5]);
            ((h >> 11) as f64 / (1u64 << 53) as f64 + 0.5) * 2f64.powi(900 + (h % 100) as i32)
        })
        .collect();
    v.extend(&giants);
    v.extend((0..512).map(|j| -giants[(j + 1) % 512]));
    v
}

fn check_exact_sum(comm: &MpiComm) {
    let (rank, size) = (comm.rank(), comm.size());
    let mut line = String::from("exact-sum");
    // One at a time.
    for set in 0..3u64 {
        let all = global_values(set);
        let mine: Vec<f64> = all.iter().skip(rank).step_by(size).copied().collect();
        let mut s: ExactSum = mine.iter().copied().collect();
        s.all_reduce(comm);
        let want = exact_sum(&all);
        assert_eq!(s.value().to_bits(), want.to_bits(), "set {set}");
        line += &format!(" {:016x}", want.to_bits());
    }
    // Twelve at once, one all-reduce.
    let mut sums = vec![ExactSum::new(); 12];
    let all = global_values(10);
    for (i, &x) in all.iter().enumerate() {
        if i % size == rank {
            sums[i % 12].add(x * (1 + i % 12) as f64);
        }
    }
    ExactSum::all_reduce_many(&mut sums, comm);
    for (k, s) in sums.iter().enumerate() {
        let want: Vec<f64> = all
            .iter()
            .enumerate()
            .filter(|(i, _)| i % 12 == k)
            .map(|(i, &x)| x * (1 + i % 12) as f64)
            .collect();
        assert_eq!(s.value().to_bits(), exact_sum(&want).to_bits(), "sum {k}");
        line += &format!(" {:016x}", s.value().to_bits());
    }
    // Special values on one rank reach everyone.
    let mut s = ExactSum::new();
    if rank == size - 1 {
        s.add(f64::INFINITY);
    }
    s.all_reduce(comm);
    assert_eq!(s.value(), f64::INFINITY);
    if rank == 0 {
        println!("{line}");
    }
}
