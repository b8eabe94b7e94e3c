//! Property tests of the tree crate's invariants.

mod common;

use common::Images;
use proptest::prelude::*;
use sph_tree::sfc::{
    hilbert_decode, hilbert_encode, hilbert_encode_lanes, morton_decode, morton_encode,
};
use sph_tree::{
    apply_permutation, compute_keys, Boundary, BoundingBox, Curve, KeySorter, NeighborList,
    NeighborSearch, Octree, CELLS_PER_AXIS, GROUP_LANES, MAX_LEVEL,
};

const MASK: u32 = CELLS_PER_AXIS - 1;

/// A tiny deterministic generator (SplitMix64), so sets are reproducible
/// from the proptest-chosen seed.
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

#[derive(Debug, Clone, Copy)]
enum Layout {
    Uniform,
    Plummer,
}

/// Particles sorted along the curve, with their keys and smoothing lengths.
struct SortedSet {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    h: Vec<f64>,
    keys: Vec<u64>,
    bbox: BoundingBox,
}

fn make_set(n: usize, seed: u64, layout: Layout, periodic: bool, h_spread: f64) -> SortedSet {
    let mut rng = Rng(seed);
    let (mut x, mut y, mut z, mut h) = (vec![], vec![], vec![], vec![]);
    for _ in 0..n {
        let p = match layout {
            Layout::Uniform => [rng.uniform(), rng.uniform(), rng.uniform()],
            Layout::Plummer => {
                // Plummer radius from the inverse cumulative mass, scale 0.05,
                // cut at 0.45 so the set stays in the unit cube.
                let r = loop {
                    let m: f64 = rng.uniform().max(1e-12);
                    let r = 0.05 / (m.powf(-2.0 / 3.0) - 1.0).sqrt();
                    if r < 0.45 {
                        break r;
                    }
                };
                let ct = 2.0 * rng.uniform() - 1.0;
                let st = (1.0 - ct * ct).sqrt();
                let ph = std::f64::consts::TAU * rng.uniform();
                [
                    0.5 + r * st * ph.cos(),
                    0.5 + r * st * ph.sin(),
                    0.5 + r * ct,
                ]
            }
        };
        x.push(p[0]);
        y.push(p[1]);
        z.push(p[2]);
        // About 100 neighbours in the uniform case, varied by up to h_spread;
        // periodic sets keep 2h below half the box (the minimum-image limit).
        let base = 0.5 * (24.0 / n as f64).cbrt();
        let hi = if periodic { 0.24 } else { f64::INFINITY };
        h.push((base * h_spread.powf(rng.uniform() - 0.5)).min(hi));
    }
    let bbox = if periodic {
        BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap()
    } else {
        BoundingBox::enclosing(&x, &y, &z).unwrap()
    };
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
    SortedSet {
        x,
        y,
        z,
        h,
        keys,
        bbox,
    }
}

fn brute_force(s: &SortedSet, i: usize, r: f64) -> Vec<u32> {
    let p = [s.x[i], s.y[i], s.z[i]];
    let images = Images::of(&s.bbox);
    (0..s.x.len())
        .filter(|&j| images.distance2(p, [s.x[j], s.y[j], s.z[j]]) < r * r)
        .map(|j| j as u32)
        .collect()
}

fn check_against_brute_force(s: &SortedSet, bucket: usize) {
    let tree = Octree::build(&s.keys, &s.x, &s.y, &s.z, bucket).unwrap();
    let mut list = NeighborList::new();
    let search = NeighborSearch::default();
    let n = s.x.len();
    let stats = search
        .find(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, 0..n, &mut list)
        .unwrap();
    let mut total = 0;
    for i in 0..n {
        let expect = brute_force(s, i, 2.0 * s.h[i]);
        assert_eq!(list.neighbors(i), &expect[..], "particle {i}");
        assert_eq!(list.count(i), expect.len());
        total += expect.len();
    }
    assert_eq!(stats.total, total);
    assert_eq!(stats.over_cap, 0);
    // The count-only search agrees.
    let mut counts = Vec::new();
    search
        .count(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, 0..n, &mut counts)
        .unwrap();
    for i in 0..n {
        assert_eq!(counts[i] as usize, list.count(i));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn morton_round_trip(a in 0..CELLS_PER_AXIS, b in 0..CELLS_PER_AXIS, c in 0..CELLS_PER_AXIS) {
        prop_assert_eq!(morton_decode(morton_encode(a, b, c)), (a, b, c));
    }

    #[test]
    fn hilbert_round_trip(a in 0..CELLS_PER_AXIS, b in 0..CELLS_PER_AXIS, c in 0..CELLS_PER_AXIS) {
        let k = hilbert_encode(a, b, c);
        prop_assert!(k < 1 << 63);
        prop_assert_eq!(hilbert_decode(k), (a, b, c));
    }

    /// Eight keys at once are the scalar keys bit for bit (any input bits,
    /// as the scalar form masks them too).
    #[test]
    fn hilbert_lanes_equal_scalar(
        a in proptest::array::uniform8(any::<u32>()),
        b in proptest::array::uniform8(0..CELLS_PER_AXIS),
        c in proptest::array::uniform8(0..CELLS_PER_AXIS),
    ) {
        let lanes = hilbert_encode_lanes(a, b, c);
        for l in 0..8 {
            prop_assert_eq!(lanes[l], hilbert_encode(a[l], b[l], c[l]));
        }
    }

    /// compute_keys (8 at a time, blocks, remainders) gives the per-particle
    /// keys for both curves.
    #[test]
    fn computed_keys_equal_per_particle_keys(seed in any::<u64>(), n in 0usize..3000, morton: bool) {
        let mut rng = Rng(seed);
        let p: Vec<[f64; 3]> = (0..n).map(|_| [rng.uniform(), rng.uniform(), rng.uniform()]).collect();
        let (x, y, z): (Vec<f64>, Vec<f64>, Vec<f64>) = (
            p.iter().map(|q| q[0]).collect(),
            p.iter().map(|q| q[1]).collect(),
            p.iter().map(|q| q[2]).collect(),
        );
        let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
        let curve = if morton { Curve::Morton } else { Curve::Hilbert };
        let mut keys = Vec::new();
        compute_keys(&bbox, curve, &x, &y, &z, &mut keys);
        for (i, k) in keys.iter().enumerate() {
            let (a, b, c) = sph_tree::sfc::cell_of(&bbox, p[i]);
            prop_assert_eq!(*k, curve.encode(a, b, c));
        }
    }

    #[test]
    fn hilbert_successors_are_face_neighbours(k in 0u64..(1u64 << 63) - 1) {
        let (a, b, c) = hilbert_decode(k);
        let (d, e, f) = hilbert_decode(k + 1);
        let dist = a.abs_diff(d) + b.abs_diff(e) + c.abs_diff(f);
        prop_assert_eq!(dist, 1, "keys {} and {} decode to {:?} and {:?}", k, k + 1, (a, b, c), (d, e, f));
    }

    /// Every octree cell is one aligned key range, for both curves.
    #[test]
    fn key_prefixes_are_octree_cells(k in 0u64..(1u64 << 63), level in 0u32..=MAX_LEVEL, off in any::<u64>(), morton in any::<bool>()) {
        let curve = if morton { Curve::Morton } else { Curve::Hilbert };
        let shift = 3 * (MAX_LEVEL - level);
        let start = (k >> shift) << shift;
        let width = 1u64 << shift;
        let other = start + off % width;
        let cell = |key| {
            let (a, b, c) = curve.decode(key);
            let s = MAX_LEVEL - level;
            (a >> s, b >> s, c >> s)
        };
        prop_assert_eq!(cell(start), cell(other));
        prop_assert_eq!(cell(start), cell(start + width - 1));
    }

    #[test]
    fn encode_masks_high_bits(a in any::<u32>(), b in any::<u32>()) {
        prop_assert_eq!(hilbert_encode(a, b, 0), hilbert_encode(a & MASK, b & MASK, 0));
    }

    #[test]
    fn sort_permutation_orders_keys(keys in prop::collection::vec(0u64..64, 0..300)) {
        let mut perm = Vec::new();
        KeySorter::new().sort(&keys, None, &mut perm);
        let mut seen = vec![false; keys.len()];
        for &p in &perm { prop_assert!(!seen[p as usize]); seen[p as usize] = true; }
        for w in perm.windows(2) {
            let (a, b) = (w[0] as usize, w[1] as usize);
            prop_assert!((keys[a], a) < (keys[b], b));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn tree_invariants(n in 0usize..3000, seed in any::<u64>(), bucket in 1usize..64, plummer in any::<bool>()) {
        let layout = if plummer { Layout::Plummer } else { Layout::Uniform };
        let s = make_set(n, seed, layout, false, 1.0);
        let t = Octree::build(&s.keys, &s.x, &s.y, &s.z, bucket).unwrap();
        prop_assert_eq!(t.num_particles(), n);
        // Leaves tile the particle range in order: each particle in exactly one leaf.
        let mut next = 0;
        for &leaf in t.leaves() {
            let r = t.particles(leaf);
            prop_assert_eq!(r.start, next);
            prop_assert!(!r.is_empty());
            prop_assert!(r.len() <= bucket || t.level(leaf) == MAX_LEVEL);
            next = r.end;
        }
        prop_assert_eq!(next, n);
        for node in 0..t.num_nodes() as u32 {
            let r = t.particles(node);
            if !t.is_leaf(node) {
                // Children partition the parent's particles, in key order.
                let mut c_next = r.start;
                for c in t.children(node) {
                    prop_assert_eq!(t.particles(c).start, c_next);
                    prop_assert_eq!(t.level(c), t.level(node) + 1);
                    c_next = t.particles(c).end;
                }
                prop_assert_eq!(c_next, r.end);
            }
            // Keys of the node's particles lie in its cell; the box holds them.
            let width = 1u64 << (3 * (MAX_LEVEL - t.level(node)));
            let (lo, hi) = t.node_box(node);
            for i in r {
                prop_assert!(s.keys[i] >= t.key(node) && s.keys[i] - t.key(node) < width);
                let p = [s.x[i], s.y[i], s.z[i]];
                for d in 0..3 { prop_assert!(lo[d] <= p[d] && p[d] <= hi[d]); }
            }
        }
    }

    #[test]
    fn neighbours_match_brute_force_uniform(seed in any::<u64>(), n in 1usize..1500, bucket in 1usize..48) {
        check_against_brute_force(&make_set(n, seed, Layout::Uniform, false, 1.0), bucket);
    }

    #[test]
    fn neighbours_match_brute_force_clustered(seed in any::<u64>(), n in 1usize..1500, bucket in 1usize..48) {
        check_against_brute_force(&make_set(n, seed, Layout::Plummer, false, 1.0), bucket);
    }

    #[test]
    fn neighbours_match_brute_force_periodic(seed in any::<u64>(), n in 100usize..1500, bucket in 1usize..48) {
        check_against_brute_force(&make_set(n, seed, Layout::Uniform, true, 1.0), bucket);
    }

    /// h varying by a factor of 10 across the set, open and periodic.
    #[test]
    fn neighbours_match_brute_force_varying_h(seed in any::<u64>(), n in 100usize..1500, periodic in any::<bool>(), plummer in any::<bool>()) {
        let layout = if plummer && !periodic { Layout::Plummer } else { Layout::Uniform };
        check_against_brute_force(&make_set(n, seed, layout, periodic, 10.0), 16);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    /// Symmetric lists: j listed for i iff |x_i - x_j| < 2 max(h_i, h_j),
    /// so every pair appears in both lists; counts stay one-sided.
    #[test]
    fn symmetric_lists_match_brute_force(seed in any::<u64>(), n in 50usize..1200, periodic in any::<bool>()) {
        let s = make_set(n, seed, Layout::Uniform, periodic, 6.0);
        let tree = Octree::build(&s.keys, &s.x, &s.y, &s.z, 8).unwrap();
        let mut list = NeighborList::new();
        let search = NeighborSearch { symmetric: true, ..Default::default() };
        search.find(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, 0..n, &mut list).unwrap();
        let images = Images::of(&s.bbox);
        for i in 0..n {
            let p = [s.x[i], s.y[i], s.z[i]];
            let expect: Vec<u32> = (0..n)
                .filter(|&j| {
                    let r = 2.0 * s.h[i].max(s.h[j]);
                    images.distance2(p, [s.x[j], s.y[j], s.z[j]]) < r * r
                })
                .map(|j| j as u32)
                .collect();
            prop_assert_eq!(list.neighbors(i), &expect[..], "particle {}", i);
            prop_assert_eq!(list.count(i), brute_force(&s, i, 2.0 * s.h[i]).len());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    /// The run-length-encoded lists hold exactly the CSR lists.
    #[test]
    fn compact_lists_equal_csr(seed in any::<u64>(), n in 1usize..1500, periodic in any::<bool>(), symmetric in any::<bool>(), lo in 0usize..200) {
        let s = make_set(n, seed, Layout::Uniform, periodic, 4.0);
        let tree = Octree::build(&s.keys, &s.x, &s.y, &s.z, 8).unwrap();
        let search = NeighborSearch { symmetric, ..Default::default() };
        let targets = lo.min(n)..n;
        let mut csr = NeighborList::new();
        let a = search.find(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, targets.clone(), &mut csr).unwrap();
        let mut compact = sph_tree::CompactNeighborList::new();
        let b = search.find_compact(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, targets.clone(), &mut compact).unwrap();
        prop_assert_eq!(a, b);
        for i in targets {
            let got: Vec<u32> = compact.neighbors(i).map(|j| j as u32).collect();
            prop_assert_eq!(&got[..], csr.neighbors(i), "particle {}", i);
            prop_assert_eq!(compact.count(i), csr.count(i));
            prop_assert_eq!(compact.listed(i), csr.neighbors(i).len());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    /// A grouped list is exactly the union of the per-target lists of its
    /// GROUP_LANES targets (counted from the first target), the same for
    /// each of them, and the counts are the per-target counts.
    #[test]
    fn grouped_lists_are_unions(seed in any::<u64>(), n in 1usize..1500, periodic in any::<bool>(), symmetric in any::<bool>(), lo in 0usize..200) {
        let s = make_set(n, seed, Layout::Uniform, periodic, 4.0);
        let tree = Octree::build(&s.keys, &s.x, &s.y, &s.z, 8).unwrap();
        let single = NeighborSearch { symmetric, ..Default::default() };
        let grouped = NeighborSearch { grouped: true, ..single };
        let targets = lo.min(n)..n;
        let mut one = sph_tree::CompactNeighborList::new();
        let a = single.find_compact(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, targets.clone(), &mut one).unwrap();
        let mut group = sph_tree::CompactNeighborList::new();
        let b = grouped.find_compact(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, targets.clone(), &mut group).unwrap();
        prop_assert_eq!(a, b);
        prop_assert_eq!(group.width(), GROUP_LANES);
        for i in targets.clone() {
            let g0 = targets.start + (i - targets.start) / GROUP_LANES * GROUP_LANES;
            let members = g0..(g0 + GROUP_LANES).min(targets.end);
            let mut union: Vec<usize> = members.flat_map(|t| one.neighbors(t).collect::<Vec<_>>()).collect();
            union.sort_unstable();
            union.dedup();
            let got: Vec<usize> = group.neighbors(i).collect();
            prop_assert_eq!(&got, &union, "particle {}", i);
            prop_assert_eq!(group.count(i), one.count(i));
        }
    }
}

#[test]
fn cap_is_reported_not_silent() {
    let s = make_set(2000, 7, Layout::Uniform, true, 1.0);
    let tree = Octree::build(&s.keys, &s.x, &s.y, &s.z, 16).unwrap();
    let n = s.x.len();
    let mut full = NeighborList::new();
    let all = NeighborSearch::default()
        .find(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, 0..n, &mut full)
        .unwrap();
    let cap = all.max_count - 5;
    let mut cut = NeighborList::new();
    let search = NeighborSearch {
        cap,
        ..Default::default()
    };
    let st = search
        .find(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, 0..n, &mut cut)
        .unwrap();
    let over: Vec<usize> = (0..n).filter(|&i| full.count(i) > cap).collect();
    assert!(!over.is_empty());
    assert_eq!(st.over_cap, over.len());
    assert_eq!(st.first_over_cap, Some(over[0]));
    assert_eq!(st.max_count, all.max_count);
    for &i in &over {
        assert_eq!(cut.neighbors(i).len(), cap);
        assert_eq!(cut.count(i), full.count(i));
        assert_eq!(cut.neighbors(i), &full.neighbors(i)[..cap]);
    }
}

#[test]
fn sub_range_of_targets() {
    let s = make_set(1000, 3, Layout::Uniform, false, 2.0);
    let tree = Octree::build(&s.keys, &s.x, &s.y, &s.z, 8).unwrap();
    let mut list = NeighborList::new();
    NeighborSearch::default()
        .find(&tree, &s.bbox, &s.x, &s.y, &s.z, &s.h, 300..700, &mut list)
        .unwrap();
    assert_eq!(list.targets(), 300..700);
    for i in 300..700 {
        assert_eq!(list.neighbors(i), &brute_force(&s, i, 2.0 * s.h[i])[..]);
    }
}

#[test]
fn periodic_radius_too_large_is_an_error() {
    let s = make_set(50, 1, Layout::Uniform, true, 1.0);
    let tree = Octree::build(&s.keys, &s.x, &s.y, &s.z, 8).unwrap();
    let h = vec![0.3; 50];
    let err = NeighborSearch::default()
        .find(
            &tree,
            &s.bbox,
            &s.x,
            &s.y,
            &s.z,
            &h,
            0..50,
            &mut NeighborList::new(),
        )
        .unwrap_err();
    assert!(err.to_string().contains("0.6"), "{err}");
}

#[test]
fn bad_inputs_are_errors() {
    assert!(BoundingBox::cube(1.0, 0.0, Boundary::Open).is_err());
    assert!(Octree::build(&[0], &[0.0], &[0.0], &[0.0], 0).is_err());
    let e = Octree::build(&[0, 1], &[0.0], &[0.0], &[0.0], 4).unwrap_err();
    assert!(e.to_string().contains("keys has 2"), "{e}");
    assert!(BoundingBox::enclosing(&[f64::NAN], &[0.0], &[0.0]).is_err());
}

#[test]
fn rebuild_reuses_and_matches_fresh_build() {
    let a = make_set(2000, 11, Layout::Plummer, false, 1.0);
    let b = make_set(500, 12, Layout::Uniform, false, 1.0);
    let mut t = Octree::build(&a.keys, &a.x, &a.y, &a.z, 16).unwrap();
    t.rebuild(&b.keys, &b.x, &b.y, &b.z, 16).unwrap();
    let fresh = Octree::build(&b.keys, &b.x, &b.y, &b.z, 16).unwrap();
    assert_eq!(t.num_nodes(), fresh.num_nodes());
    assert_eq!(t.leaves(), fresh.leaves());
    for node in 0..t.num_nodes() as u32 {
        assert_eq!(t.particles(node), fresh.particles(node));
        assert_eq!(t.node_box(node), fresh.node_box(node));
    }
}

#[test]
fn wrap_maps_into_periodic_box() {
    let b = BoundingBox::new(
        [0.0; 3],
        [1.0, 2.0, 3.0],
        [Boundary::Periodic, Boundary::Open, Boundary::Periodic],
    )
    .unwrap();
    let p = b.wrap([1.25, 5.0, -0.5]);
    assert!((p[0] - 0.25).abs() < 1e-15);
    assert_eq!(p[1], 5.0);
    assert!((p[2] - 2.5).abs() < 1e-15);
}

/// Where a coordinate sits along one axis of a box: anywhere (a fraction of
/// the length), on a face, or a few ulps inside a face.
#[derive(Debug, Clone, Copy)]
enum Place {
    Inside(f64),
    OnLo,
    OnHi,
    NearLo(u8),
    NearHi(u8),
}

impl Place {
    fn at(self, lo: f64, hi: f64) -> f64 {
        let step = |mut v: f64, k: u8, up: bool| {
            for _ in 0..k {
                v = if up { v.next_up() } else { v.next_down() };
            }
            v
        };
        match self {
            Place::Inside(u) => (lo + u * (hi - lo)).clamp(lo, hi),
            Place::OnLo => lo,
            Place::OnHi => hi,
            Place::NearLo(k) => step(lo, k, true).min(hi),
            Place::NearHi(k) => step(hi, k, false).max(lo),
        }
    }
}

fn place() -> impl Strategy<Value = Place> {
    prop_oneof![
        4 => (0.0..=1.0f64).prop_map(Place::Inside),
        1 => Just(Place::OnLo),
        1 => Just(Place::OnHi),
        1 => (1u8..8).prop_map(Place::NearLo),
        1 => (1u8..8).prop_map(Place::NearHi),
    ]
}

fn point_in(bbox: &BoundingBox, p: [Place; 3]) -> [f64; 3] {
    let (lo, hi) = (bbox.lo(), bbox.hi());
    std::array::from_fn(|k| p[k].at(lo[k], hi[k]))
}

/// Boxes anywhere in [-1e3, 1e3], edges from 1e-3 to 1e3 (different per
/// axis), each axis periodic or open.
fn any_box() -> impl Strategy<Value = BoundingBox> {
    (
        prop::array::uniform3(-1e3..1e3f64),
        prop::array::uniform3(-3.0..3.0f64),
        prop::array::uniform3(any::<bool>()),
    )
        .prop_map(|(lo, log_len, periodic)| {
            let hi = std::array::from_fn(|k| lo[k] + 10f64.powf(log_len[k]));
            let b = periodic.map(|p| {
                if p {
                    Boundary::Periodic
                } else {
                    Boundary::Open
                }
            });
            BoundingBox::new(lo, hi, b).unwrap()
        })
}

/// How far from half a box length a separation is: exactly half, a few
/// ulps off, or a small relative offset.
fn off_half() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        (-8i32..=8).prop_map(|k| f64::from(k) * f64::EPSILON),
        prop::sample::select(vec![-1e-6, -1e-9, -1e-12, 1e-12, 1e-9, 1e-6]),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2048))]

    /// `distance2` is the nearest of the 27 images (to rounding), for
    /// points anywhere in the box, on its faces and next to them.
    #[test]
    fn distance2_is_the_nearest_image(bbox in any_box(), a in prop::array::uniform3(place()), b in prop::array::uniform3(place())) {
        let (a, b) = (point_in(&bbox, a), point_in(&bbox, b));
        let got = bbox.distance2(a, b);
        let want = Images::of(&bbox).distance2(a, b);
        prop_assert!((got - want).abs() <= 8.0 * f64::EPSILON * want,
            "{:?}: distance2({:?}, {:?}) = {}, nearest image {}", bbox, a, b, got, want);
    }

    /// Separations within rounding of half a box length, where the choice
    /// between the two nearest images is decided.
    #[test]
    fn distance2_near_half_the_box(bbox in any_box(), a in prop::array::uniform3(place()), off in prop::array::uniform3(off_half()), sign in prop::array::uniform3(any::<bool>())) {
        let a = point_in(&bbox, a);
        let (lo, hi, l) = (bbox.lo(), bbox.hi(), bbox.lengths());
        let b: [f64; 3] = std::array::from_fn(|k| {
            let d = (0.5 + off[k]) * l[k];
            let mut v = if sign[k] { a[k] + d } else { a[k] - d };
            // Back into the box by one length (the image L/2 away on the other side).
            if v > hi[k] {
                v -= l[k];
            } else if v < lo[k] {
                v += l[k];
            }
            v.clamp(lo[k], hi[k])
        });
        let got = bbox.distance2(a, b);
        let want = Images::of(&bbox).distance2(a, b);
        prop_assert!((got - want).abs() <= 8.0 * f64::EPSILON * want,
            "{:?}: distance2({:?}, {:?}) = {}, nearest image {}", bbox, a, b, got, want);
    }

    /// `distance2_to_box` is the distance to the nearest of the 27 images of
    /// a sub-box (to rounding of the coordinates).
    #[test]
    fn distance2_to_box_is_the_nearest_image(bbox in any_box(), p in prop::array::uniform3(place()), c0 in prop::array::uniform3(place()), c1 in prop::array::uniform3(place())) {
        let p = point_in(&bbox, p);
        let (c0, c1) = (point_in(&bbox, c0), point_in(&bbox, c1));
        let blo = std::array::from_fn(|k| c0[k].min(c1[k]));
        let bhi = std::array::from_fn(|k| c0[k].max(c1[k]));
        let got = bbox.distance2_to_box(p, blo, bhi);
        let want = Images::of(&bbox).distance2_to_box(p, blo, bhi);
        let scale = (0..3).map(|k| bbox.lo()[k].abs() + bbox.hi()[k].abs()).fold(0.0, f64::max);
        prop_assert!((got.sqrt() - want.sqrt()).abs() <= 64.0 * f64::EPSILON * scale,
            "{:?}: distance2_to_box({:?}, {:?}, {:?}) = {}, nearest image {}", bbox, p, blo, bhi, got, want);
    }
}

/// The oracle itself on hand-computed cases (so a wrong oracle cannot make
/// the comparisons above vacuous).
#[test]
fn reference_distances_by_hand() {
    let b = BoundingBox::new(
        [0.0; 3],
        [1.0, 2.0, 4.0],
        [Boundary::Periodic, Boundary::Periodic, Boundary::Open],
    )
    .unwrap();
    // x through the face (0.2), y through the face with its own length (0.5),
    // z plain (3.5, no wrap on an open axis).
    let images = Images::of(&b);
    let d2 = images.distance2([0.9, 1.75, 0.25], [0.1, 0.25, 3.75]);
    assert!((d2 - (0.04 + 0.25 + 12.25)).abs() < 1e-12, "{d2}");
    assert_eq!(images.distance2([0.0; 3], [1.0, 2.0, 0.0]), 0.0);
    // Point at x = 0.95 against the box [0.1, 0.2] x [0, 2] x [0, 1]: 0.15
    // through the x face; inside along y and z.
    let g = images.distance2_to_box([0.95, 1.0, 0.5], [0.1, 0.0, 0.0], [0.2, 2.0, 1.0]);
    assert!((g - 0.0225).abs() < 1e-12, "{g}");
    // Along open z the box at [0, 1] is 2.5 from z = 3.5, never wrapped.
    let g = images.distance2_to_box([0.15, 1.0, 3.5], [0.1, 0.0, 0.0], [0.2, 2.0, 1.0]);
    assert!((g - 6.25).abs() < 1e-12, "{g}");
}
