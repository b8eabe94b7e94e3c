//! `Domain::exchange_where` and `Domain::exchange_reverse_min` on 1-4
//! in-process ranks (`sph_comm::run_ranks`), against `Domain::exchange` and
//! against a brute-force recomputation from every rank's data:
//!
//! - `exchange_where` puts in the halo slots of the chosen particles what
//!   `exchange` puts there (the same bits), and leaves every other slot,
//!   halo or owned, as it was; with every particle chosen it equals
//!   `exchange` bit for bit; `send` is asked about owned particles only;
//! - `exchange_reverse_min` gives each owned particle the minimum of its own
//!   value and the values of all its halo copies on every rank (gathered and
//!   recomputed), and leaves halo slots alone;
//! - on one rank (no halos; periodic images are folds) both do nothing.

use proptest::prelude::*;
use sph_comm::{run_ranks, Communicator, SerialComm};
use sph_domain::{Domain, DomainConfig, ParticleFields, Points};
use sph_tree::{Boundary, BoundingBox};
use std::collections::HashMap;

/// SplitMix64: a random `u64` from any seed (a hash of it).
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A uniform number in `[0, 1)` from a hash.
fn unit(h: u64) -> f64 {
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// `n` particles in the unit cube, half of them in a clump, h in [0.02, 0.06];
/// every `ranks`-th one (by id) on `rank`.
fn cloud(n: usize, seed: u64, rank: usize, ranks: usize) -> Points {
    let mut p = Points::default();
    for i in (rank..n).step_by(ranks) {
        let id = i as u64;
        let r = |k: u64| unit(mix(seed ^ mix(id.wrapping_mul(8) + k)));
        let clump = i % 2 == 0;
        let c = |k: u64| if clump { 0.7 + 0.1 * r(k) } else { r(k) };
        p.push(id, [c(0), c(1), c(2)], 0.02 + 0.04 * r(3));
    }
    p
}

/// The owner's value of field `f` of particle `id`: random, any sign, any
/// exponent, so bit-level equality means something.
fn owner_value(seed: u64, id: u64, f: usize) -> f64 {
    let h = mix(seed ^ mix(id) ^ ((f as u64) << 56));
    (unit(h) - 0.5) * 2f64.powi((h % 64) as i32 - 32)
}

/// What a halo slot holds before an exchange: a NaN whose payload names
/// the rank, slot and field, so it differs (bit for bit) from every owner
/// value and from every other stale value.
fn stale(rank: usize, slot: usize, f: usize) -> f64 {
    f64::from_bits(0x7ff8_0000_0000_0000 | ((rank as u64) << 40) | ((slot as u64) << 4) | f as u64)
}

/// Whether `id` is in the random subset of density `share`.
fn chosen(seed: u64, id: u64, share: f64) -> bool {
    unit(mix(seed.rotate_left(17) ^ mix(id ^ 0xabcd))) < share
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Synced domain on this rank.
fn synced<C: Communicator>(comm: C, n: usize, seed: u64, periodic: bool) -> (Domain<C>, Points) {
    let ranks = comm.size();
    let rank = comm.rank();
    let b = if periodic {
        Boundary::Periodic
    } else {
        Boundary::Open
    };
    let mut bbox = BoundingBox::cube(0.0, 1.0, b).unwrap();
    let config = DomainConfig {
        bucket: 32,
        ..DomainConfig::default()
    };
    let mut domain = Domain::new(comm, config).unwrap();
    let mut local = cloud(n, seed, rank, ranks);
    domain.sync(&mut local, &mut bbox).unwrap();
    (domain, local)
}

/// Fields before an exchange: owners' values in owned slots, stale ones in
/// halo slots.
fn initial<C: Communicator>(
    domain: &Domain<C>,
    local: &Points,
    seed: u64,
    nf: usize,
) -> Vec<Vec<f64>> {
    let owned = domain.owned();
    let rank = domain.comm().rank();
    (0..nf)
        .map(|f| {
            (0..local.len())
                .map(|i| {
                    if owned.contains(&i) {
                        owner_value(seed, local.id[i], f)
                    } else {
                        stale(rank, i, f)
                    }
                })
                .collect()
        })
        .collect()
}

fn slices(v: &mut [Vec<f64>]) -> Vec<&mut [f64]> {
    v.iter_mut().map(|f| f.as_mut_slice()).collect()
}

/// The `exchange_where` checks on one rank of `ranks`; returns the number
/// of halos refreshed and held.
fn check_where<C: Communicator>(
    comm: C,
    n: usize,
    seed: u64,
    periodic: bool,
    share: f64,
    nf: usize,
) -> (usize, usize) {
    let (mut domain, local) = synced(comm, n, seed, periodic);
    let owned = domain.owned();
    let ids = local.id.clone();
    let before = initial(&domain, &local, seed, nf);

    let mut full = before.clone();
    domain.exchange(&mut slices(&mut full)).unwrap();
    let mut all = before.clone();
    domain
        .exchange_where(&mut slices(&mut all), |i| {
            assert!(owned.contains(&i), "send asked about non-owned {i}");
            true
        })
        .unwrap();
    let mut sub = before.clone();
    domain
        .exchange_where(&mut slices(&mut sub), |i| {
            assert!(owned.contains(&i), "send asked about non-owned {i}");
            chosen(seed, ids[i], share)
        })
        .unwrap();

    let mut refreshed = 0;
    for f in 0..nf {
        assert_eq!(
            bits(&all[f]),
            bits(&full[f]),
            "send-all differs from exchange"
        );
        for i in 0..local.len() {
            let halo = !owned.contains(&i);
            let want = if halo && chosen(seed, ids[i], share) {
                refreshed += usize::from(f == 0);
                // What exchange delivers, and what the owner holds.
                assert_eq!(full[f][i].to_bits(), owner_value(seed, ids[i], f).to_bits());
                full[f][i]
            } else {
                before[f][i]
            };
            assert_eq!(
                sub[f][i].to_bits(),
                want.to_bits(),
                "slot {i} (halo: {halo}) field {f}"
            );
        }
    }
    (refreshed, local.len() - owned.len())
}

/// The `exchange_reverse_min` check on one rank, for `u8` values below
/// `top`: gathers every rank's (id, value) of its halos, recomputes the
/// minimum per id, and compares the owned particles with it. Returns the
/// owned particles lowered, those with halo copies, and the number of
/// distinct ids among all ranks' halos.
fn check_reverse_min<C: Communicator>(
    comm: C,
    n: usize,
    seed: u64,
    periodic: bool,
    top: u8,
) -> (usize, usize, usize) {
    let (mut domain, local) = synced(comm, n, seed, periodic);
    let owned = domain.owned();
    let rank = domain.comm().rank() as u64;
    let value = |i: usize| (mix(seed ^ mix(local.id[i] ^ (rank << 48))) % top as u64) as u8;
    let before: Vec<u8> = (0..local.len()).map(value).collect();

    let halos: Vec<usize> = (0..local.len()).filter(|i| !owned.contains(i)).collect();
    let halo_ids: Vec<u64> = halos.iter().map(|&i| local.id[i]).collect();
    let halo_values: Vec<u8> = halos.iter().map(|&i| before[i]).collect();
    let all_ids = domain.comm().all_gather_v(&halo_ids).unwrap().data;
    let all_values = domain.comm().all_gather_v(&halo_values).unwrap().data;
    // The smallest value among each id's halo copies, over all ranks.
    let mut copies: HashMap<u64, u8> = HashMap::new();
    for (&id, &v) in all_ids.iter().zip(&all_values) {
        let e = copies.entry(id).or_insert(u8::MAX);
        *e = (*e).min(v);
    }

    let mut field = before.clone();
    domain.exchange_reverse_min(&mut field).unwrap();
    let mut lowered = 0;
    let mut with_copies = 0;
    for i in 0..local.len() {
        if owned.contains(&i) {
            with_copies += usize::from(copies.contains_key(&local.id[i]));
            let copy = copies.get(&local.id[i]).copied().unwrap_or(u8::MAX);
            assert_eq!(
                field[i],
                before[i].min(copy),
                "owned {} (id {})",
                i,
                local.id[i]
            );
            lowered += usize::from(field[i] < before[i]);
        } else {
            assert_eq!(field[i], before[i], "halo slot {i} changed");
        }
    }

    // The same with u64 values, and idempotence: a second call changes nothing.
    let mut wide: Vec<u64> = before.iter().map(|&v| u64::from(v) << 40).collect();
    domain.exchange_reverse_min(&mut wide).unwrap();
    assert_eq!(
        wide,
        field
            .iter()
            .map(|&v| u64::from(v) << 40)
            .collect::<Vec<_>>()
    );
    let mut again = field.clone();
    domain.exchange_reverse_min(&mut again).unwrap();
    assert_eq!(again, field);
    (lowered, with_copies, copies.len())
}

#[test]
fn subset_exchange_on_2_3_4_ranks() {
    for ranks in [2, 3, 4] {
        for (k, share) in [0.0, 0.1, 0.5, 1.0].into_iter().enumerate() {
            let seed = 100 * ranks as u64 + k as u64;
            let periodic = k % 2 == 0;
            let counts = run_ranks(ranks, |comm| {
                check_where(comm, 1500, seed, periodic, share, 3)
            });
            let refreshed: usize = counts.iter().map(|c| c.0).sum();
            let halos: usize = counts.iter().map(|c| c.1).sum();
            assert!(halos > 0, "{ranks} ranks: no halos to test with");
            if share == 0.0 {
                assert_eq!(refreshed, 0);
            } else if share == 1.0 {
                assert_eq!(refreshed, halos);
            } else {
                assert!(0 < refreshed && refreshed < halos, "{refreshed} of {halos}");
            }
        }
    }
}

#[test]
fn reverse_min_on_2_3_4_ranks() {
    for ranks in [2, 3, 4] {
        for periodic in [true, false] {
            let seed = 7 * ranks as u64 + u64::from(periodic);
            let counts = run_ranks(ranks, |comm| {
                check_reverse_min(comm, 1500, seed, periodic, 16)
            });
            let lowered: usize = counts.iter().map(|c| c.0).sum();
            assert!(lowered > 0, "{ranks} ranks: nothing lowered");
            // Every halo copy's id is owned by exactly one rank.
            let owners: usize = counts.iter().map(|c| c.1).sum();
            assert_eq!(owners, counts[0].2);
        }
    }
}

/// Bins as the wake-up writes them: most halos hold "no request"
/// (`u8::MAX`), a few a small bin.
#[test]
fn reverse_min_keeps_sparse_requests() {
    for ranks in [2, 4] {
        run_ranks(ranks, |comm| {
            let (mut domain, local) = synced(comm, 1200, 5, true);
            let owned = domain.owned();
            let rank = domain.comm().rank() as u64;
            let mut wake: Vec<u8> = (0..local.len())
                .map(|i| {
                    let id = local.id[i];
                    if !owned.contains(&i) && id % 5 == 0 {
                        ((id + rank) % 3) as u8
                    } else {
                        u8::MAX
                    }
                })
                .collect();
            let halo_ids: Vec<u64> = (0..local.len())
                .filter(|&i| !owned.contains(&i) && local.id[i] % 5 == 0)
                .map(|i| local.id[i])
                .collect();
            let all = domain.comm().all_gather_v(&halo_ids).unwrap();
            let mut want: HashMap<u64, u8> = HashMap::new();
            for r in 0..domain.comm().size() {
                for &id in all.from_rank(r) {
                    let v = ((id + r as u64) % 3) as u8;
                    let e = want.entry(id).or_insert(u8::MAX);
                    *e = (*e).min(v);
                }
            }
            domain.exchange_reverse_min(&mut wake).unwrap();
            for i in owned {
                let w = want.get(&local.id[i]).copied().unwrap_or(u8::MAX);
                assert_eq!(wake[i], w, "id {}", local.id[i]);
            }
        });
    }
}

/// One rank, serial or threaded: no halos, so nothing moves.
#[test]
fn one_rank_is_a_no_op() {
    fn check<C: Communicator>(comm: C) {
        let (mut domain, local) = synced(comm, 800, 3, true);
        assert_eq!(domain.owned(), 0..local.len());
        let before = initial(&domain, &local, 3, 2);
        let mut q = before.clone();
        domain
            .exchange_where(&mut slices(&mut q), |_| true)
            .unwrap();
        assert_eq!(bits(&q[0]), bits(&before[0]));
        assert_eq!(bits(&q[1]), bits(&before[1]));
        let mut b: Vec<u8> = (0..local.len()).map(|i| (i % 7) as u8).collect();
        let b0 = b.clone();
        domain.exchange_reverse_min(&mut b).unwrap();
        assert_eq!(b, b0);
    }
    check(SerialComm::new());
    run_ranks(1, check);
}

/// Before any sync there are no peers: a collective no-op on every rank.
#[test]
fn before_a_sync_nothing_travels() {
    run_ranks(3, |comm| {
        let mut domain = Domain::new(&comm, DomainConfig::default()).unwrap();
        let mut q = vec![1.5; 4];
        domain
            .exchange_where(&mut [q.as_mut_slice()], |_| true)
            .unwrap();
        let mut b = vec![3u8; 4];
        domain.exchange_reverse_min(&mut b).unwrap();
        assert_eq!((q, b), (vec![1.5; 4], vec![3u8; 4]));
    });
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, failure_persistence: None, ..ProptestConfig::default() })]

    /// Any cloud, subset density, field count and rank count.
    #[test]
    fn subset_exchange_any_seed(
        seed in any::<u64>(),
        ranks in 2usize..=4,
        periodic in any::<bool>(),
        share in 0.0f64..=1.0,
        nf in 0usize..=3,
        n in 200usize..900,
    ) {
        run_ranks(ranks, |comm| check_where(comm, n, seed, periodic, share, nf));
    }

    /// Any cloud, value range and rank count.
    #[test]
    fn reverse_min_any_seed(
        seed in any::<u64>(),
        ranks in 2usize..=4,
        periodic in any::<bool>(),
        top in 1u8..=255,
        n in 200usize..900,
    ) {
        let counts = run_ranks(ranks, |comm| check_reverse_min(comm, n, seed, periodic, top));
        prop_assert_eq!(counts.iter().map(|c| c.1).sum::<usize>(), counts[0].2);
    }
}
