//! The decomposition on 1-4 in-process ranks (`sph_comm::run_ranks`):
//! after every sync each particle is owned exactly once, by the rank whose
//! key range holds its key; the local arrays are in (key, id) order; every
//! particle within reach of an owned one is present locally (checked by
//! brute force over the global set); halo exchange delivers the owners'
//! values; and all of this survives particles moving across ranks and
//! across periodic boundaries.

// The reference minimum-image distance of sph-tree's tests (27 images, not
// `BoundingBox::distance2`), so the halo check does not trust the code it
// relies on.
#[path = "../../sph-tree/tests/common/mod.rs"]
mod tree_oracle;

use proptest::prelude::*;
use sph_comm::{run_ranks, Communicator};
use sph_domain::{Domain, DomainConfig, DomainError, ParticleFields, Points};
use sph_tree::{compute_keys, Boundary, BoundingBox, Curve};

struct Rng(u64);
impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `n` particles in the unit cube, half of them in a tight clump, h in
/// [0.02, 0.06].
fn global_cloud(n: usize, seed: u64) -> Points {
    let mut rng = Rng(seed);
    let mut c = Points::default();
    for i in 0..n as u64 {
        let clump = i % 2 == 0;
        let mut p = || {
            if clump {
                0.7 + 0.1 * rng.uniform()
            } else {
                rng.uniform()
            }
        };
        let pos = [p(), p(), p()];
        c.push(i, pos, 0.02 + 0.04 * rng.uniform());
    }
    c
}

fn value(id: u64) -> f64 {
    (id as f64).sqrt() + 1.0
}

/// Checks the invariants on every rank; returns the global owned ids.
fn check_sync<C: Communicator>(
    comm: &C,
    domain: &Domain<C>,
    local: &Points,
    global: &Points,
    bbox: &BoundingBox,
) -> Vec<u64> {
    let owned = domain.owned();
    let rank = comm.rank();
    // Keys ascending (ties by id) and owned keys within this rank's range.
    let keys = domain.keys();
    assert_eq!(keys.len(), local.len());
    for w in 1..keys.len() {
        assert!(
            (keys[w - 1], local.id[w - 1]) < (keys[w], local.id[w]),
            "rank {rank}: local order broken at {w}"
        );
    }
    let ranges = domain.key_ranges();
    for i in owned.clone() {
        assert!(ranges[rank] <= keys[i] && keys[i] < ranges[rank + 1]);
    }
    let mut mine = Vec::new();
    compute_keys(
        bbox,
        Curve::Hilbert,
        &local.x,
        &local.y,
        &local.z,
        &mut mine,
    );
    assert_eq!(mine, keys, "rank {rank}: keys do not match the positions");
    // Every particle within 2 max(h_i, h_j) of an owned one is present.
    let present: std::collections::HashSet<u64> = local.id.iter().copied().collect();
    let images = tree_oracle::Images::of(bbox);
    for i in owned.clone() {
        let pi = [local.x[i], local.y[i], local.z[i]];
        for j in 0..global.len() {
            let pj = [global.x[j], global.y[j], global.z[j]];
            let reach = 2.0 * local.h[i].max(global.h[j]);
            if images.distance2(pi, pj) < reach * reach {
                assert!(
                    present.contains(&global.id[j]),
                    "rank {rank}: particle {} within reach of {} is missing",
                    global.id[j],
                    local.id[i]
                );
            }
        }
    }
    let ids: Vec<u64> = local.id[owned].to_vec();
    let mut all = comm.all_gather_v(&ids).unwrap().data;
    all.sort_unstable();
    all
}

/// Distributes `global` over `ranks`, syncs, moves every particle by a
/// random displacement (wrapped on periodic axes), syncs again, and checks
/// the invariants and a halo exchange after each sync.
fn run(ranks: usize, n: usize, seed: u64, boundary: Boundary) {
    let global0 = global_cloud(n, seed);
    run_ranks(ranks, |comm| {
        let mut bbox = BoundingBox::cube(0.0, 1.0, boundary).unwrap();
        let config = DomainConfig {
            bucket: 32,
            ..DomainConfig::default()
        };
        let mut domain = Domain::new(&comm, config).unwrap();
        // Start from an arbitrary split: every rank-th particle.
        let mut local = Points::default();
        let mut buf = Vec::new();
        for i in (comm.rank()..n).step_by(ranks) {
            buf.clear();
            global0.pack(i, &mut buf);
            local.push_packed(&buf);
        }
        let mut global = global0.clone();
        let mut rng = Rng(seed ^ 0x5555);
        for round in 0..3 {
            domain.sync(&mut local, &mut bbox).unwrap();
            let ids = check_sync(domain.comm(), &domain, &local, &global, &bbox);
            assert_eq!(ids, (0..n as u64).collect::<Vec<_>>(), "round {round}: ids");
            // Halo exchange: owners' values by id, garbage in the halos;
            // after the exchange every halo holds its owner's value.
            let owned = domain.owned();
            let mut q: Vec<f64> = (0..local.len())
                .map(|i| {
                    if owned.contains(&i) {
                        value(local.id[i])
                    } else {
                        -1.0
                    }
                })
                .collect();
            domain.exchange(&mut [q.as_mut_slice()]).unwrap();
            for i in 0..local.len() {
                assert_eq!(q[i], value(local.id[i]), "round {round}: halo value");
            }
            // Move everything (the same displacement on every rank, by id).
            let shift = |id: u64, k: u64| {
                let mut r = Rng(seed ^ id.wrapping_mul(31) ^ (k << 40) ^ (round as u64) << 50);
                0.3 * (r.uniform() - 0.5)
            };
            for c in [&mut local, &mut global] {
                for i in 0..c.len() {
                    let p = [
                        c.x[i] + shift(c.id[i], 0),
                        c.y[i] + shift(c.id[i], 1),
                        c.z[i] + shift(c.id[i], 2),
                    ];
                    let w = bbox.wrap(p);
                    (c.x[i], c.y[i], c.z[i]) = (w[0], w[1], w[2]);
                }
            }
            let _ = rng.uniform();
        }
    });
}

#[test]
fn periodic_box_on_1_to_4_ranks() {
    for ranks in 1..=4 {
        run(ranks, 1500, 11 + ranks as u64, Boundary::Periodic);
    }
}

#[test]
fn open_box_on_2_and_3_ranks() {
    for ranks in [2, 3] {
        run(ranks, 1200, 5 + ranks as u64, Boundary::Open);
    }
}

/// A seed the proptest found: one of 4 ranks had no halo peers and skipped
/// the (collective) halo exchange.
#[test]
fn rank_without_peers_still_exchanges() {
    run(4, 600, 9901396551980440087, Boundary::Periodic);
}

/// A bad configuration is refused with the offending value.
#[test]
fn bad_config_is_refused_with_its_value() {
    let new = |config| Domain::new(sph_comm::SerialComm::new(), config).map(|_| ());
    let bucket = DomainConfig {
        bucket: 0,
        ..DomainConfig::default()
    };
    assert_eq!(new(bucket), Err(DomainError::InvalidBucket(0)));
    for margin in [0.9, f64::INFINITY] {
        let config = DomainConfig {
            h_margin: margin,
            ..DomainConfig::default()
        };
        assert_eq!(new(config), Err(DomainError::InvalidHMargin(margin)));
    }
    let nan = DomainConfig {
        h_margin: f64::NAN,
        ..DomainConfig::default()
    };
    assert!(matches!(new(nan), Err(DomainError::InvalidHMargin(m)) if m.is_nan()));
    assert_eq!(new(DomainConfig::default()), Ok(()));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]
    #[test]
    fn any_seed_any_rank_count(seed in any::<u64>(), ranks in 1usize..=4, periodic in any::<bool>()) {
        let b = if periodic { Boundary::Periodic } else { Boundary::Open };
        run(ranks, 600, seed, b);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// `halo_slot` names, halo by halo, the slot `halo_placement`'s
    /// gather puts it in, and the owned block keeps its order.
    #[test]
    fn halo_slots_are_the_placement(n_owned in 0usize..20, halos in proptest::collection::vec(any::<u32>(), 0..20), low in any::<prop::sample::Index>()) {
        let mut order: Vec<u32> = (0..halos.len() as u32).collect();
        order.sort_by_key(|&k| halos[k as usize]);
        let n_low = if order.is_empty() { 0 } else { low.index(order.len() + 1) };
        let mut perm = Vec::new();
        sph_domain::halo_placement(n_owned, &order, n_low, &mut perm);
        prop_assert_eq!(perm.len(), n_owned + order.len());
        for (k, &old) in order.iter().enumerate() {
            prop_assert_eq!(perm[sph_domain::halo_slot(k, n_low, n_owned)], n_owned as u32 + old);
        }
        for i in 0..n_owned {
            prop_assert_eq!(perm[n_low + i], i as u32);
        }
    }
}
