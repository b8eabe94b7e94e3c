//! Lane masks of the pair-loop driver (`PairLoop::run_masked`, issue 41's
//! block time steps): the active targets get the full run's outputs bit
//! for bit, the inactive keep what their outputs held, groups without an
//! active target are skipped, and all-active is `run` itself, on 1 and 2
//! threads.

use proptest::prelude::*;
use sph_core::pair_loop::{F64s, Group, PairLoop, PairStage, Reduce};
use sph_tree::{apply_permutation, compute_keys, Boundary, BoundingBox, CompactNeighborList};
use sph_tree::{Curve, KeySorter, NeighborSearch, Octree};

/// A stage with every shape of output the real ones have: plain slices,
/// an optional slice written read-modify-write (as conduction adds to
/// du), and a figure.
struct Probe<'a> {
    h: &'a [f64],
    w: &'a [f64],
}

/// Lanes finished and the largest first output: a figure to reduce.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Seen(u64, f64);

impl Reduce for Seen {
    fn identity() -> Self {
        Seen(0, f64::NEG_INFINITY)
    }
    fn merge(self, o: Self) -> Self {
        Seen(self.0 + o.0, self.1.max(o.1))
    }
}

impl PairStage for Probe<'_> {
    type Sums = (F64s, F64s, F64s);
    type Out<'o> = ([&'o mut [f64]; 2], Option<[&'o mut [f64]; 1]>);
    type Stats = Seen;

    fn start(&self, g: &Group) -> Self::Sums {
        let h = g.load(self.h);
        (h * h, F64s::splat(0.0), F64s::splat(0.0))
    }

    fn pair(&self, s: &mut Self::Sums, j: usize, _d: [F64s; 3], r2: F64s) {
        let near = r2.lt(s.0);
        s.1 += near.select(F64s::splat(self.w[j]), F64s::splat(0.0));
        s.2 += near.select(r2, F64s::splat(0.0));
    }

    fn finish(&self, g: &Group, s: Self::Sums, ([a, b], c): &mut Self::Out<'_>) -> Seen {
        s.1.store(a);
        s.2.store(b);
        if let Some([c]) = c {
            let add = s.1.to_array();
            for (c, v) in c.iter_mut().zip(add) {
                *c += v;
            }
        }
        let first = s.1.to_array();
        Seen(
            g.valid as u64,
            first[..g.valid]
                .iter()
                .fold(f64::NEG_INFINITY, |m, &v| m.max(v)),
        )
    }
}

/// `n` points in the periodic unit box, sorted along the curve, with
/// their neighbour lists within 2 h.
fn scene(
    coords: &[(f64, f64, f64)],
    h0: f64,
) -> (BoundingBox, [Vec<f64>; 3], Vec<f64>, CompactNeighborList) {
    let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
    let (mut x, mut y, mut z): (Vec<f64>, Vec<f64>, Vec<f64>) = (
        coords.iter().map(|c| c.0).collect(),
        coords.iter().map(|c| c.1).collect(),
        coords.iter().map(|c| c.2).collect(),
    );
    let mut keys = Vec::new();
    compute_keys(&bbox, Curve::Hilbert, &x, &y, &z, &mut keys);
    let mut perm = Vec::new();
    KeySorter::new().sort(&keys, None, &mut perm);
    for v in [&mut x, &mut y, &mut z] {
        *v = perm.iter().map(|&k| v[k as usize]).collect();
    }
    apply_permutation(&perm, &mut keys, &mut Vec::new());
    let h: Vec<f64> = (0..x.len())
        .map(|i| h0 * (1.0 + 0.1 * (i % 5) as f64))
        .collect();
    let tree = Octree::build(&keys, &x, &y, &z, 8).unwrap();
    let mut nl = CompactNeighborList::new();
    NeighborSearch::default()
        .find_compact(&tree, &bbox, &x, &y, &z, &h, 0..x.len(), &mut nl)
        .unwrap();
    (bbox, [x, y, z], h, nl)
}

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn masked_lanes_are_the_full_run_or_untouched(
        coords in proptest::collection::vec((0.0f64..1.0, 0.0f64..1.0, 0.0f64..1.0), 27..160),
        flags in proptest::collection::vec(any::<bool>(), 160),
        sparse in any::<bool>(),
        threads in 1usize..=2,
    ) {
        let n = coords.len();
        let (bbox, [x, y, z], h, nl) = scene(&coords, 0.4 / (n as f64).cbrt());
        let w: Vec<f64> = (0..n).map(|j| 1.0 + (j % 7) as f64 * 0.125).collect();
        let driver = PairLoop::new(&bbox, 2.0, [&x, &y, &z], &h, &nl).unwrap();
        let stage = Probe { h: &h, w: &w };
        // Sparse masks leave whole groups inactive.
        let active: Vec<bool> = flags[..n].iter().enumerate()
            .map(|(i, &f)| f && (!sparse || i % 16 < 4)).collect();
        let base: Vec<f64> = (0..n).map(|i| 0.5 + i as f64).collect();

        let (mut a, mut b, mut c) = (vec![-1.0; n], vec![-2.0; n], base.clone());
        let full = in_pool(threads, || driver.run(&stage, ([&mut a, &mut b], Some([&mut c]))));
        let (mut am, mut bm, mut cm) = (vec![-1.0; n], vec![-2.0; n], base.clone());
        let masked = in_pool(threads, || {
            driver.run_masked(&stage, ([&mut am, &mut bm], Some([&mut cm])), &active)
        });
        for i in 0..n {
            if active[i] {
                prop_assert_eq!(am[i].to_bits(), a[i].to_bits(), "a[{}]", i);
                prop_assert_eq!(bm[i].to_bits(), b[i].to_bits(), "b[{}]", i);
                prop_assert_eq!(cm[i].to_bits(), c[i].to_bits(), "c[{}]", i);
            } else {
                prop_assert_eq!((am[i], bm[i], cm[i]), (-1.0, -2.0, base[i]), "inactive {}", i);
            }
        }
        // The figure covers the groups that ran: all lanes of each group
        // with an active target.
        let groups_run: u64 = (0..n).step_by(8)
            .filter(|&g| active[g..(g + 8).min(n)].iter().any(|&f| f))
            .map(|g| ((g + 8).min(n) - g) as u64)
            .sum();
        prop_assert_eq!(masked.0, groups_run);
        prop_assert_eq!(full.0, n as u64);

        // All active: `run`, bit for bit, the figure included.
        let (mut a1, mut b1, mut c1) = (vec![-1.0; n], vec![-2.0; n], base.clone());
        let all = in_pool(threads, || {
            driver.run_masked(&stage, ([&mut a1, &mut b1], Some([&mut c1])), &vec![true; n])
        });
        prop_assert_eq!(all, full);
        for (u, v) in [(&a1, &a), (&b1, &b), (&c1, &c)] {
            prop_assert!(u.iter().zip(v.iter()).all(|(p, q)| p.to_bits() == q.to_bits()));
        }
        // Without the optional output.
        let (mut a2, mut b2) = (vec![-1.0; n], vec![-2.0; n]);
        driver.run_masked(&stage, ([&mut a2, &mut b2], None), &active);
        prop_assert_eq!(&a2, &am);
        prop_assert_eq!(&b2, &bm);
    }
}

#[test]
#[should_panic(expected = "active flags vs targets")]
fn a_mask_of_the_wrong_length_is_refused() {
    let coords: Vec<(f64, f64, f64)> = (0..20).map(|i| (i as f64 / 20.0, 0.5, 0.5)).collect();
    let (bbox, [x, y, z], h, nl) = scene(&coords, 0.1);
    let w = vec![1.0; 20];
    let driver = PairLoop::new(&bbox, 2.0, [&x, &y, &z], &h, &nl).unwrap();
    let (mut a, mut b) = (vec![0.0; 20], vec![0.0; 20]);
    driver.run_masked(
        &Probe { h: &h, w: &w },
        ([&mut a, &mut b], None),
        &[true; 19],
    );
}
