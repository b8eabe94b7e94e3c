//! `ThreadComm` on 1, 2, 3 and 4 in-process ranks: the checks that
//! `tests/mpi.rs` runs under mpirun (all-gather, all-reduce of every type and
//! operation, many rounds of random sparse exchanges with self-sends, empty
//! and repeated messages, all-to-all-v round trips, `ExactSum` over ranks),
//! argument errors, misuse and panics (which must not hang), rayon inside
//! ranks, and a property test over random communication patterns.

use std::panic::{self, AssertUnwindSafe};
use std::time::Duration;

use proptest::prelude::*;
use rayon::prelude::*;
use sph_comm::{
    exact_sum, run_ranks, CommError, Communicator, ExactSum, ReduceOp, SerialComm, ThreadComm,
};

const SIZES: [usize; 4] = [1, 2, 3, 4];

/// Runs `check` on every rank for each size of [`SIZES`].
fn on_all_sizes(check: impl Fn(&ThreadComm) + Sync) {
    for size in SIZES {
        run_ranks(size, |comm| {
            assert_eq!(comm.size(), size);
            check(&comm);
            comm.barrier();
        });
    }
}

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

/// The panic message of a payload caught by `catch_unwind`.
fn message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        String::from("<non-string panic>")
    }
}

// ------------------------------------------------------------ basics

#[test]
fn results_come_back_in_rank_order() {
    for size in SIZES {
        let out = run_ranks(size, |comm| (comm.rank(), comm.size()));
        assert_eq!(out, (0..size).map(|r| (r, size)).collect::<Vec<_>>());
    }
    // The closure may borrow from the caller.
    let base = [10u64, 20, 30];
    let out = run_ranks(3, |comm| base[comm.rank()] + 1);
    assert_eq!(out, vec![11, 21, 31]);
}

#[test]
fn handles_are_send_sync_and_debug() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<ThreadComm>();
    let s = run_ranks(2, |comm| format!("{comm:?}"));
    assert!(
        s[1].contains("rank: 1") && s[1].contains("size: 2"),
        "{}",
        s[1]
    );
}

#[test]
fn barrier_orders_ranks() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    for size in SIZES {
        let arrived = AtomicUsize::new(0);
        run_ranks(size, |comm| {
            for round in 1..=50 {
                if (comm.rank() + round) % 3 == 0 {
                    std::thread::sleep(Duration::from_micros(200));
                }
                arrived.fetch_add(1, Ordering::SeqCst);
                comm.barrier();
                // Everybody has arrived at this barrier, nobody has passed
                // the next one.
                assert_eq!(arrived.load(Ordering::SeqCst), round * size);
                comm.barrier();
            }
        });
    }
}

// ------------------------------------------------------------ all-gather

#[test]
fn all_gather() {
    on_all_sizes(|comm| {
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
        // Nobody contributes anything.
        let g = comm.all_gather_v::<u8>(&[]).unwrap();
        assert!(g.data.is_empty());
        assert_eq!(g.counts, vec![0; size]);
        // Every element type.
        assert_eq!(
            comm.all_gather_v(&[rank as i32 - 1]).unwrap().data,
            (0..size as i32).map(|r| r - 1).collect::<Vec<_>>()
        );
        assert_eq!(
            comm.all_gather_scalar(rank as u8),
            (0..size as u8).collect::<Vec<_>>()
        );
        assert_eq!(
            comm.all_gather_scalar(-(rank as f64)),
            (0..size).map(|r| -(r as f64)).collect::<Vec<_>>()
        );
    });
}

// ------------------------------------------------------------ all-reduce

/// The reduction over ranks `0..size` of `f(r)`, folded in rank order.
fn fold<T: Copy>(size: usize, f: impl Fn(usize) -> T, op: impl Fn(T, T) -> T) -> T {
    (1..size).fold(f(0), |acc, r| op(acc, f(r)))
}

#[test]
fn all_reduce_every_type_and_op() {
    on_all_sizes(|comm| {
        let (rank, size) = (comm.rank(), comm.size());
        let n = size as i64;

        // The checks of tests/mpi.rs.
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

        // Every type with every operation, against a fold in rank order.
        let fv = |r: usize| (hash(&[r as u64, 1]) >> 11) as f64 * 1e-3 - 4e12;
        let uv = |r: usize| hash(&[r as u64, 2]) >> 3;
        let iv = |r: usize| (hash(&[r as u64, 3]) as i64) >> 3;
        let zv = |r: usize| (hash(&[r as u64, 4]) % 1000) as usize;
        for op in [ReduceOp::Sum, ReduceOp::Min, ReduceOp::Max] {
            let x = comm.all_reduce_scalar(fv(rank), op);
            let want = match op {
                ReduceOp::Sum => fold(size, fv, |a, b| a + b),
                ReduceOp::Min => fold(size, fv, f64::min),
                ReduceOp::Max => fold(size, fv, f64::max),
            };
            assert_eq!(x.to_bits(), want.to_bits(), "f64 {op:?}");
            let x = comm.all_reduce_scalar(uv(rank), op);
            let want = match op {
                ReduceOp::Sum => fold(size, uv, u64::wrapping_add),
                ReduceOp::Min => fold(size, uv, u64::min),
                ReduceOp::Max => fold(size, uv, u64::max),
            };
            assert_eq!(x, want, "u64 {op:?}");
            let x = comm.all_reduce_scalar(iv(rank), op);
            let want = match op {
                ReduceOp::Sum => fold(size, iv, i64::wrapping_add),
                ReduceOp::Min => fold(size, iv, i64::min),
                ReduceOp::Max => fold(size, iv, i64::max),
            };
            assert_eq!(x, want, "i64 {op:?}");
            let x = comm.all_reduce_scalar(zv(rank), op);
            let want = match op {
                ReduceOp::Sum => fold(size, zv, |a, b| a + b),
                ReduceOp::Min => fold(size, zv, usize::min),
                ReduceOp::Max => fold(size, zv, usize::max),
            };
            assert_eq!(x, want, "usize {op:?}");
        }
        // Integer sums wrap, like MPI's.
        assert_eq!(
            comm.all_reduce_scalar(u64::MAX, ReduceOp::Sum),
            u64::MAX.wrapping_mul(size as u64)
        );
    });
}

/// A floating-point sum is folded in rank order, so it is deterministic and
/// bitwise identical on all ranks, even when rounding makes the order
/// matter.
#[test]
fn float_sums_are_deterministic_and_identical_on_all_ranks() {
    // Rank order: ((1e16 + 1) + 1) + -1e16 = 0 with rounding, the exact sum is 2.
    let values = [1e16, 1.0, 1.0, -1e16];
    let want = values.iter().fold(0.0, |a, b| a + b);
    assert_eq!(want, 0.0);
    for _ in 0..20 {
        let got = run_ranks(4, |comm| {
            if comm.rank() % 2 == 1 {
                std::thread::yield_now();
            }
            let mut buf: Vec<f64> = (0..100).map(|i| values[comm.rank()] * i as f64).collect();
            comm.all_reduce(&mut buf, ReduceOp::Sum);
            buf.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        });
        for bits in &got {
            assert_eq!(bits, &got[0]);
        }
        assert_eq!(got[0][1], want.to_bits());
    }
}

// ------------------------------------------------------------ sparse exchange

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
    // Destinations in a scrambled order: the result is still sorted by
    // source, and messages to one destination keep their order.
    out.sort_by_key(|(d, _)| hash(&[round, *d as u64]));
    out
}

#[test]
fn sparse_exchange_random_rounds() {
    on_all_sizes(|comm| {
        let (rank, size) = (comm.rank(), comm.size());
        for round in 0..300u64 {
            // Skew the ranks now and then so that some are an exchange ahead.
            if hash(&[round, rank as u64, 99]).is_multiple_of(16) {
                std::thread::sleep(Duration::from_millis(1));
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
        // Everybody sends an empty message to everybody, twice.
        let empties: Vec<(usize, Vec<i32>)> =
            (0..2 * size).map(|k| (k % size, Vec::new())).collect();
        let got = comm.sparse_exchange(&empties).unwrap();
        let want: Vec<(usize, Vec<i32>)> = (0..size)
            .flat_map(|s| [(s, Vec::new()), (s, Vec::new())])
            .collect();
        assert_eq!(got, want);
    });
}

#[test]
fn sparse_exchange_back_to_back_rounds_do_not_mix() {
    on_all_sizes(|comm| {
        let (rank, size) = (comm.rank(), comm.size());
        for round in 0..200u64 {
            if rank == (round as usize) % size {
                std::thread::yield_now();
            }
            // Every rank sends the round number to the next rank only.
            let got = comm
                .sparse_exchange(&[((rank + 1) % size, [round, rank as u64])])
                .unwrap();
            let prev = (rank + size - 1) % size;
            assert_eq!(got, vec![(prev, vec![round, prev as u64])]);
        }
    });
}

#[test]
fn sparse_exchange_errors() {
    on_all_sizes(|comm| {
        let (rank, size) = (comm.rank(), comm.size());
        // An invalid destination is reported before anything is sent (so
        // the other ranks do not wait for this call).
        assert_eq!(
            comm.sparse_exchange(&[(0, vec![1u8]), (size, vec![1u8])]),
            Err(CommError::InvalidRank { rank: size, size })
        );
        // Rank 0 sends 3 bytes to the last rank, which expects u64s.
        if size >= 2 {
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
        }
        // Any other element type is reported too, even of the same size.
        let sent: Vec<(usize, Vec<f64>)> = vec![((rank + 1) % size, vec![1.0, 2.0])];
        let slices: Vec<(usize, &[f64])> = sent.iter().map(|(d, v)| (*d, &v[..])).collect();
        let got = if rank == 0 {
            comm.sparse_exchange(&[((rank + 1) % size, [7u64])])
                .map(|r| r.len())
        } else {
            comm.sparse_exchange(&slices).map(|r| r.len())
        };
        let want = if size == 1 {
            Ok(1)
        } else if rank == 0 {
            // Expects u64, receives two f64 from rank size - 1.
            Err(CommError::MessageSize {
                source_rank: size - 1,
                bytes: 16,
                elem_size: 8,
            })
        } else if rank == 1 {
            // Expects f64, receives one u64 from rank 0.
            Err(CommError::MessageSize {
                source_rank: 0,
                bytes: 8,
                elem_size: 8,
            })
        } else {
            Ok(1)
        };
        assert_eq!(got, want);
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
    });
}

// ------------------------------------------------------------ all-to-all-v

#[test]
fn all_to_all_v_round_trips() {
    on_all_sizes(|comm| {
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
            assert_eq!(g.counts.len(), size);
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
        // Argument errors, checked before communicating.
        assert_eq!(
            comm.all_to_all_v(&[1u8], &[1]).err(),
            (size != 1).then_some(CommError::CountsLength {
                expected: size,
                got: 1
            })
        );
        let mut counts = vec![0; size];
        counts[0] = 3;
        assert_eq!(
            comm.all_to_all_v(&[1.0f64, 2.0], &counts),
            Err(CommError::CountsSum {
                counts_sum: 3,
                data_len: 2
            })
        );
        // Everything empty.
        let g = comm.all_to_all_v::<u32>(&[], &vec![0; size]).unwrap();
        assert!(g.data.is_empty());
        assert_eq!(g.counts, vec![0; size]);
    });
}

// ------------------------------------------------------------ ExactSum

/// 4096 values defined independently of the rank count (dealt round-robin
/// to the ranks): 3072 of all magnitudes, then 512 giants and their 512
/// negations, placed so that each giant and its negation sit on different
/// ranks. The exact sum is moderate, the naive one is dominated by rounding.
fn global_values(set: u64) -> Vec<f64> {
    let mut v: Vec<f64> = (0..3072u64)
        .map(|i| {
            let h = hash(&[set, i]);
            if h.is_multiple_of(4) {
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

#[test]
fn exact_sum_over_ranks_matches_the_serial_sum() {
    let mut per_size = Vec::new();
    for size in SIZES {
        let bits = run_ranks(size, |comm| {
            let rank = comm.rank();
            let mut out = Vec::new();
            for set in 0..3u64 {
                let all = global_values(set);
                let mine: Vec<f64> = all.iter().skip(rank).step_by(size).copied().collect();
                let mut s: ExactSum = mine.iter().copied().collect();
                s.all_reduce(&comm);
                assert_eq!(s.value().to_bits(), exact_sum(&all).to_bits(), "set {set}");
                out.push(s.value().to_bits());
            }
            // Twelve at once, one all-reduce.
            let mut sums = vec![ExactSum::new(); 12];
            let all = global_values(10);
            for (i, &x) in all.iter().enumerate() {
                if i % size == rank {
                    sums[i % 12].add(x * (1 + i % 12) as f64);
                }
            }
            ExactSum::all_reduce_many(&mut sums, &comm);
            for (k, s) in sums.iter().enumerate() {
                let want: Vec<f64> = all
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| i % 12 == k)
                    .map(|(i, &x)| x * (1 + i % 12) as f64)
                    .collect();
                assert_eq!(s.value().to_bits(), exact_sum(&want).to_bits(), "sum {k}");
                out.push(s.value().to_bits());
            }
            // Special values on one rank reach everyone.
            let mut s = ExactSum::new();
            if rank == size - 1 {
                s.add(f64::INFINITY);
            }
            s.all_reduce(&comm);
            assert_eq!(s.value(), f64::INFINITY);
            out
        });
        for b in &bits {
            assert_eq!(b, &bits[0], "ranks disagree on {size} ranks");
        }
        per_size.push(bits[0].clone());
    }
    for b in &per_size {
        assert_eq!(b, &per_size[0], "rank-count dependence");
    }
}

// ------------------------------------------------------------ generic code

/// Code written against `C: Communicator` gives the same answer on
/// `SerialComm` and on any number of thread ranks, with rayon loops inside
/// every rank (the global pool is shared by the ranks).
#[test]
fn generic_code_with_rayon_inside_ranks() {
    fn total_mass<C: Communicator>(comm: &C, global_n: usize) -> (f64, u64) {
        let (rank, size) = (comm.rank(), comm.size());
        let ids: Vec<usize> = (rank..global_n).step_by(size).collect();
        let mut e: ExactSum = ids.par_iter().map(|&i| 1.0 / (1 + i) as f64).sum();
        e.all_reduce(comm);
        let count = comm.all_reduce_scalar(ids.par_iter().count() as u64, ReduceOp::Sum);
        (e.value(), count)
    }
    let serial = total_mass(&SerialComm::new(), 100_000);
    assert_eq!(serial.1, 100_000);
    for size in SIZES {
        for got in run_ranks(size, |comm| total_mass(&comm, 100_000)) {
            assert_eq!(got.0.to_bits(), serial.0.to_bits());
            assert_eq!(got.1, serial.1);
        }
    }
}

// ------------------------------------------------------------ failures

#[test]
fn a_panicking_rank_releases_the_others() {
    for size in [2, 3, 4] {
        for culprit in 0..size {
            let caught = panic::catch_unwind(AssertUnwindSafe(|| {
                run_ranks(size, |comm| {
                    comm.barrier();
                    let x = comm.all_reduce_scalar(1u64, ReduceOp::Sum);
                    if comm.rank() == culprit {
                        panic!("boom on rank {culprit}");
                    }
                    // The others wait for the culprit here, forever under MPI.
                    comm.barrier();
                    let _ = comm.sparse_exchange(&[(0, vec![x])]);
                    x
                })
            }));
            let payload = caught.expect_err("run_ranks must propagate the panic");
            assert_eq!(message(&*payload), format!("boom on rank {culprit}"));
        }
    }
}

#[test]
fn a_panic_outside_collectives_and_later_collectives() {
    // Rank 1 panics before the others enter any collective; they must not
    // block in the next one either.
    let caught = panic::catch_unwind(AssertUnwindSafe(|| {
        run_ranks(3, |comm| {
            if comm.rank() == 1 {
                panic!("early");
            }
            std::thread::sleep(Duration::from_millis(20));
            for _ in 0..10 {
                comm.barrier();
            }
        })
    }));
    assert_eq!(message(&*caught.unwrap_err()), "early");
    // A panic on the only rank.
    let caught = panic::catch_unwind(|| run_ranks(1, |_comm| -> u8 { panic!("alone") }));
    assert_eq!(message(&*caught.unwrap_err()), "alone");
}

#[test]
fn a_rank_that_returns_early_does_not_hang_the_others() {
    let caught = panic::catch_unwind(|| {
        run_ranks(3, |comm| {
            comm.barrier();
            if comm.rank() != 2 {
                // Ranks 0 and 1 make one more collective call than rank 2.
                comm.barrier();
            }
        })
    });
    let msg = message(&*caught.unwrap_err());
    assert!(msg.contains("rank 2 has returned"), "{msg}");
}

#[test]
fn mismatched_collectives_panic() {
    type Case = (&'static str, fn(&ThreadComm));
    let cases: Vec<Case> = vec![
        ("barrier vs all-reduce", |comm| {
            if comm.rank() == 0 {
                comm.barrier();
            } else {
                comm.all_reduce_scalar(1.0f64, ReduceOp::Sum);
            }
        }),
        ("different reduction", |comm| {
            let op = if comm.rank() == 0 {
                ReduceOp::Min
            } else {
                ReduceOp::Max
            };
            comm.all_reduce_scalar(1u64, op);
        }),
        ("different lengths", |comm| {
            let mut buf = vec![1i64; 1 + comm.rank()];
            comm.all_reduce(&mut buf, ReduceOp::Sum);
        }),
        ("different element types", |comm| {
            if comm.rank() == 0 {
                comm.all_gather_scalar(1u32);
            } else {
                comm.all_gather_scalar(1i32);
            }
        }),
    ];
    for (name, f) in cases {
        let caught = panic::catch_unwind(|| run_ranks(2, |comm| f(&comm)));
        let msg = message(&*caught.expect_err(name));
        assert!(msg.contains("collective mismatch"), "{name}: {msg}");
    }
}

// ------------------------------------------------------------ property test

/// Random communication pattern: `size` ranks, and for each rank a list of
/// `(dest selector, payload)`; the destination is `selector % size`.
/// What every rank sends: `(dest, payload)` lists indexed by source rank.
type Plan = Vec<Vec<(usize, Vec<u64>)>>;

fn pattern() -> impl Strategy<Value = (usize, Plan)> {
    (1usize..=4).prop_flat_map(|size| {
        let msg = (0..size, prop::collection::vec(any::<u64>(), 0..6));
        (
            Just(size),
            prop::collection::vec(prop::collection::vec(msg, 0..8), size),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn sparse_exchange_delivers_random_patterns((size, plan) in pattern()) {
        let got = run_ranks(size, |comm| {
            let rank = comm.rank();
            let a = comm.sparse_exchange(&plan[rank]).unwrap();
            // The same pattern again, as all-to-all-v (grouped by destination).
            let mut send: Vec<u64> = Vec::new();
            let mut counts = vec![0; size];
            for d in 0..size {
                for (dest, v) in &plan[rank] {
                    if *dest == d {
                        send.extend(v);
                        counts[d] += v.len();
                    }
                }
            }
            let b = comm.all_to_all_v(&send, &counts).unwrap();
            (a, b)
        });
        for (rank, (exchanged, gathered)) in got.iter().enumerate() {
            let want: Vec<(usize, Vec<u64>)> = (0..size)
                .flat_map(|src| {
                    plan[src]
                        .iter()
                        .filter(|(d, _)| *d == rank)
                        .map(move |(_, v)| (src, v.clone()))
                })
                .collect();
            prop_assert_eq!(exchanged, &want);
            for src in 0..size {
                let flat: Vec<u64> = want
                    .iter()
                    .filter(|(s, _)| *s == src)
                    .flat_map(|(_, v)| v.iter().copied())
                    .collect();
                prop_assert_eq!(gathered.from_rank(src), &flat[..]);
            }
        }
    }

    #[test]
    fn all_reduce_matches_rank_order_fold(
        (size, vals) in (1usize..=4).prop_flat_map(|n| (Just(n), prop::collection::vec(prop::collection::vec(-1e6f64..1e6, 3), n)))
    ) {
        let got = run_ranks(size, |comm| {
            let mut s = vals[comm.rank()].clone();
            comm.all_reduce(&mut s, ReduceOp::Sum);
            let mut m = vals[comm.rank()].clone();
            comm.all_reduce(&mut m, ReduceOp::Min);
            (s, m)
        });
        for k in 0..3 {
            let sum = (1..size).fold(vals[0][k], |a, r| a + vals[r][k]);
            let min = (1..size).fold(vals[0][k], |a, r| a.min(vals[r][k]));
            for (s, m) in &got {
                prop_assert_eq!(s[k].to_bits(), sum.to_bits());
                prop_assert_eq!(m[k], min);
            }
        }
    }
}

/// In-process ranks share one rayon pool, so none may be driven from it; a
/// serial rank is alone in its process and may.
#[test]
fn only_ranks_alone_in_their_process_drive_from_the_pool() {
    on_all_sizes(|comm| assert!(!comm.may_drive_from_pool()));
    assert!(SerialComm::new().may_drive_from_pool());
}
