//! Searches for block time steps: the neighbour lists of flagged groups of
//! targets only (`NeighborSearch::find_compact_groups`), and trees refitted
//! to drifted positions (`Octree::refit`).

mod common;

use common::Images;
use proptest::prelude::*;
use sph_tree::{
    apply_permutation, compute_keys, Boundary, BoundingBox, CompactNeighborList, Curve, KeySorter,
    NeighborList, NeighborSearch, NeighborStats, Octree, GROUP_LANES,
};
use std::ops::Range;

/// SplitMix64, so sets are reproducible from the proptest-chosen seed.
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Particles in the unit cube sorted along the Hilbert curve, with their
/// keys and smoothing lengths (about 100 neighbours, varied by `h_spread`).
#[derive(Clone)]
struct Set {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    h: Vec<f64>,
    keys: Vec<u64>,
    bbox: BoundingBox,
}

impl Set {
    fn random(n: usize, seed: u64, periodic: bool, h_spread: f64) -> Self {
        let mut rng = Rng(seed);
        let (mut x, mut y, mut z, mut h) = (vec![], vec![], vec![], vec![]);
        let base = 0.5 * (24.0 / n as f64).cbrt();
        let h_top = if periodic { 0.24 } else { f64::INFINITY };
        for _ in 0..n {
            x.push(rng.uniform());
            y.push(rng.uniform());
            z.push(rng.uniform());
            h.push((base * h_spread.powf(rng.uniform() - 0.5)).min(h_top));
        }
        let bbox = if periodic {
            BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap()
        } else {
            BoundingBox::enclosing(&x, &y, &z).unwrap()
        };
        Self::sorted(x, y, z, h, bbox).0
    }

    /// The set sorted along the curve of `bbox`, and the permutation
    /// (`sorted[k] = given[perm[k]]`).
    fn sorted(
        mut x: Vec<f64>,
        mut y: Vec<f64>,
        mut z: Vec<f64>,
        mut h: Vec<f64>,
        bbox: BoundingBox,
    ) -> (Self, Vec<u32>) {
        let mut keys = Vec::new();
        compute_keys(&bbox, Curve::Hilbert, &x, &y, &z, &mut keys);
        let mut perm = Vec::new();
        KeySorter::new().sort(&keys, None, &mut perm);
        let mut s = Vec::new();
        for a in [&mut x, &mut y, &mut z, &mut h] {
            apply_permutation(&perm, a, &mut s);
        }
        let mut sk = Vec::new();
        apply_permutation(&perm, &mut keys, &mut sk);
        let set = Self {
            x,
            y,
            z,
            h,
            keys,
            bbox,
        };
        (set, perm)
    }

    fn tree(&self, bucket: usize) -> Octree {
        Octree::build(&self.keys, &self.x, &self.y, &self.z, bucket).unwrap()
    }

    fn compact(
        &self,
        tree: &Octree,
        search: &NeighborSearch,
        targets: Range<usize>,
        active: Option<&[bool]>,
        list: &mut CompactNeighborList,
    ) -> NeighborStats {
        let (x, y, z, h, b) = (&self.x, &self.y, &self.z, &self.h, &self.bbox);
        match active {
            None => search.find_compact(tree, b, x, y, z, h, targets, list),
            Some(a) => search.find_compact_groups(tree, b, x, y, z, h, targets, a, list),
        }
        .unwrap()
    }
}

/// Random flags, each on with probability `p`, or (`clustered`) on in
/// runs, as the groups of a block-step run's active region are.
fn flags(n_groups: usize, seed: u64, p: f64, clustered: bool) -> Vec<bool> {
    let mut rng = Rng(seed ^ 0x5EED);
    let mut on = rng.uniform() < p;
    (0..n_groups)
        .map(|_| {
            if !clustered {
                return rng.uniform() < p;
            }
            // Runs of about 16 groups, the share on about p.
            if rng.uniform() < 1.0 / 16.0 {
                on = rng.uniform() < p;
            }
            on
        })
        .collect()
}

/// The flagged groups' lists and counts are the full search's, bit for bit
/// (the same runs in the same order); the others are empty with counts 0;
/// the stats are those of the flagged targets.
fn check_flagged(
    full: &CompactNeighborList,
    some: &CompactNeighborList,
    st: NeighborStats,
    targets: Range<usize>,
    active: &[bool],
) -> Result<(), TestCaseError> {
    prop_assert_eq!(some.targets(), targets.clone());
    prop_assert_eq!(some.width(), full.width());
    let mut want: Vec<usize> = Vec::new();
    for i in targets.clone() {
        if active[(i - targets.start) / GROUP_LANES] {
            prop_assert!(some.runs(i).eq(full.runs(i)), "target {}", i);
            prop_assert_eq!(some.count(i), full.count(i), "target {}", i);
            want.push(full.count(i));
        } else {
            prop_assert_eq!(some.runs(i).count(), 0, "target {}", i);
            prop_assert_eq!(some.count(i), 0, "target {}", i);
        }
    }
    let expect = NeighborStats {
        min_count: want.iter().copied().min().unwrap_or(0),
        max_count: want.iter().copied().max().unwrap_or(0),
        total: want.iter().sum(),
        over_cap: 0,
        first_over_cap: None,
    };
    prop_assert_eq!(st, expect);
    Ok(())
}

fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// Random sets (open and periodic, h varied 4x), random target ranges,
    /// flags at any density, scattered or in runs, every search mode.
    #[test]
    fn flagged_groups_get_the_full_lists(
        seed in any::<u64>(), n in 1usize..1500, periodic: bool, symmetric: bool,
        grouped: bool, lo in 0usize..200, p in 0.0..=1.0f64, clustered: bool,
        bucket in 1usize..33,
    ) {
        let s = Set::random(n, seed, periodic, 4.0);
        let tree = s.tree(bucket);
        let search = NeighborSearch { symmetric, grouped, ..Default::default() };
        let targets = lo.min(n)..n;
        let active = flags(targets.len().div_ceil(GROUP_LANES), seed, p, clustered);
        let mut full = CompactNeighborList::new();
        s.compact(&tree, &search, targets.clone(), None, &mut full);
        // A list that held a full search before (buffers reused).
        let mut some = full.clone();
        let st = s.compact(&tree, &search, targets.clone(), Some(&active), &mut some);
        check_flagged(&full, &some, st, targets, &active)?;
    }

    /// Every flag on is the full search, stats included; no flag on gives
    /// empty lists.
    #[test]
    fn all_flags_on_is_the_full_search(
        seed in any::<u64>(), n in 1usize..1500, periodic: bool, symmetric: bool, grouped: bool,
    ) {
        let s = Set::random(n, seed, periodic, 4.0);
        let tree = s.tree(8);
        let search = NeighborSearch { symmetric, grouped, ..Default::default() };
        let groups = n.div_ceil(GROUP_LANES);
        let mut full = CompactNeighborList::new();
        let a = s.compact(&tree, &search, 0..n, None, &mut full);
        let mut all = CompactNeighborList::new();
        let b = s.compact(&tree, &search, 0..n, Some(&vec![true; groups]), &mut all);
        prop_assert_eq!(a, b);
        check_flagged(&full, &all, b, 0..n, &vec![true; groups])?;
        let none = s.compact(&tree, &search, 0..n, Some(&vec![false; groups]), &mut all);
        prop_assert_eq!(none, NeighborStats::default());
        check_flagged(&full, &all, none, 0..n, &vec![false; groups])?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(6))]

    /// Sets of several parallel chunks: the flagged lists on 1 and 2
    /// threads are identical (and the full search's).
    #[test]
    fn flagged_search_is_thread_count_independent(
        seed in any::<u64>(), periodic: bool, symmetric: bool, grouped: bool,
        p in 0.05..=1.0f64, clustered: bool,
    ) {
        let n = 12_000;
        let s = Set::random(n, seed, periodic, 2.0);
        let tree = s.tree(16);
        let search = NeighborSearch { symmetric, grouped, ..Default::default() };
        let targets = 37..n - 5;
        let active = flags(targets.len().div_ceil(GROUP_LANES), seed, p, clustered);
        let run = |threads| {
            on_threads(threads, || {
                let mut l = CompactNeighborList::new();
                let st = s.compact(&tree, &search, targets.clone(), Some(&active), &mut l);
                (l, st)
            })
        };
        let (one, st1) = run(1);
        let (two, st2) = run(2);
        prop_assert_eq!(st1, st2);
        for i in targets.clone() {
            prop_assert!(one.runs(i).eq(two.runs(i)), "target {}", i);
            prop_assert_eq!(one.count(i), two.count(i));
        }
        let mut full = CompactNeighborList::new();
        s.compact(&tree, &search, targets.clone(), None, &mut full);
        check_flagged(&full, &two, st2, targets, &active)?;
    }
}

/// Drifts every particle by up to `amp * h` per axis (wrapped into
/// periodic boxes), in the tree's order.
fn drift(s: &Set, seed: u64, amp: f64) -> Set {
    let mut rng = Rng(seed ^ 0xD81F7);
    let mut d = s.clone();
    for i in 0..s.x.len() {
        let step = amp * s.h[i];
        let p = [d.x[i], d.y[i], d.z[i]].map(|c| c + step * (2.0 * rng.uniform() - 1.0));
        [d.x[i], d.y[i], d.z[i]] = s.bbox.wrap(p);
    }
    d
}

/// Neighbour sets of every particle of `moved` (tree order), from a search
/// over `tree`.
fn neighbour_sets(moved: &Set, tree: &Octree, search: &NeighborSearch) -> NeighborList {
    let n = moved.x.len();
    let mut list = NeighborList::new();
    let (x, y, z, h) = (&moved.x, &moved.y, &moved.z, &moved.h);
    search
        .find(tree, &moved.bbox, x, y, z, h, 0..n, &mut list)
        .unwrap();
    list
}

/// After a drift, a refitted tree finds the neighbour sets a tree built
/// anew over the drifted positions (sorted again, so compared as sets
/// through the permutation), and its boxes are those of a build with the
/// old keys and the new positions.
fn check_refit(s: &Set, amp: f64, seed: u64, symmetric: bool) -> Result<(), TestCaseError> {
    let n = s.x.len();
    let mut tree = s.tree(8);
    let moved = drift(s, seed, amp);
    tree.refit(&moved.x, &moved.y, &moved.z).unwrap();

    let same_keys = Octree::build(&s.keys, &moved.x, &moved.y, &moved.z, 8).unwrap();
    prop_assert_eq!(tree.num_nodes(), same_keys.num_nodes());
    for node in 0..tree.num_nodes() as u32 {
        prop_assert_eq!(tree.particles(node), same_keys.particles(node));
        prop_assert_eq!(tree.node_box(node), same_keys.node_box(node));
    }

    let search = NeighborSearch {
        symmetric,
        ..Default::default()
    };
    let refitted = neighbour_sets(&moved, &tree, &search);
    // A new sort and tree over the drifted positions (open boxes enclose
    // them again).
    let bbox = if s.bbox.is_periodic(0) {
        s.bbox
    } else {
        BoundingBox::enclosing(&moved.x, &moved.y, &moved.z).unwrap()
    };
    let (fresh, perm) = Set::sorted(
        moved.x.clone(),
        moved.y.clone(),
        moved.z.clone(),
        moved.h.clone(),
        bbox,
    );
    let fresh_lists = neighbour_sets(&fresh, &fresh.tree(8), &search);
    let images = Images::of(&s.bbox);
    for k in 0..n {
        let i = perm[k] as usize; // particle k of the fresh order
        let mut want: Vec<u32> = fresh_lists
            .neighbors(k)
            .iter()
            .map(|&j| perm[j as usize])
            .collect();
        want.sort_unstable();
        prop_assert_eq!(refitted.neighbors(i), &want[..], "particle {}", i);
        prop_assert_eq!(refitted.count(i), fresh_lists.count(k));
    }
    // And the pairs are those within reach of the drifted positions.
    let count: usize = (0..n).map(|i| refitted.count(i)).sum();
    let mut brute = 0;
    for i in 0..n {
        let p = [moved.x[i], moved.y[i], moved.z[i]];
        let r = 2.0 * moved.h[i];
        brute += (0..n)
            .filter(|&j| images.distance2(p, [moved.x[j], moved.y[j], moved.z[j]]) < r * r)
            .count();
    }
    prop_assert_eq!(count, brute);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Drifts up to one smoothing length per axis, open and periodic boxes
    /// (particles crossing periodic faces are wrapped), one- and two-sided
    /// lists.
    #[test]
    fn refit_finds_the_neighbours_of_a_rebuild(
        seed in any::<u64>(), n in 50usize..1500, periodic: bool, symmetric: bool,
        amp in 0.0..1.0f64,
    ) {
        check_refit(&Set::random(n, seed, periodic, 4.0), amp, seed, symmetric)?;
    }
}

/// Large drifts (a few smoothing lengths, so boxes overlap widely): still
/// exact, only slower.
#[test]
fn refit_after_large_drifts() {
    for periodic in [false, true] {
        let s = Set::random(1200, 99, periodic, 2.0);
        check_refit(&s, 4.0, 7, true).unwrap();
    }
}

/// Flagged searches over a refitted tree give the lists a full search over
/// it does (the block-step sub-step: refit, then search the active groups).
#[test]
fn flagged_search_on_a_refitted_tree() {
    let s = Set::random(5000, 5, true, 3.0);
    let mut tree = s.tree(16);
    let moved = drift(&s, 5, 0.5);
    tree.refit(&moved.x, &moved.y, &moved.z).unwrap();
    let search = NeighborSearch {
        symmetric: true,
        grouped: true,
        ..Default::default()
    };
    let active = flags(5000usize.div_ceil(GROUP_LANES), 5, 0.1, true);
    let mut full = CompactNeighborList::new();
    moved.compact(&tree, &search, 0..5000, None, &mut full);
    let mut some = CompactNeighborList::new();
    let st = moved.compact(&tree, &search, 0..5000, Some(&active), &mut some);
    check_flagged(&full, &some, st, 0..5000, &active).unwrap();
}

#[test]
fn refit_checks_lengths() {
    let s = Set::random(100, 1, false, 1.0);
    let mut tree = s.tree(8);
    let e = tree.refit(&s.x[..99], &s.y[..99], &s.z[..99]).unwrap_err();
    assert!(e.to_string().contains("the tree has 100"), "{e}");
    assert!(tree.refit(&s.x, &s.y[..99], &s.z).is_err());
    let mut empty = Octree::default();
    empty.refit(&[], &[], &[]).unwrap();
}

#[test]
#[should_panic(expected = "one activity flag per group")]
fn wrong_flag_count_panics() {
    let s = Set::random(100, 1, false, 1.0);
    let tree = s.tree(8);
    let flags = vec![true; 100usize.div_ceil(GROUP_LANES) + 1];
    s.compact(
        &tree,
        &NeighborSearch::default(),
        0..100,
        Some(&flags),
        &mut CompactNeighborList::new(),
    );
}
