//! Property tests of invariants: P2M/M2M against direct sums, the exact
//! two-body force, tree = direct when every node is opened, translation
//! invariance, and the antisymmetry of the direct sum.

mod common;

use common::Rng;
use proptest::prelude::*;
use sph_gravity::{
    compute_gravity, direct, GravityField, GravityParams, Multipoles, Targets, TreeGravity,
};
use sph_tree::{apply_permutation, compute_keys, Boundary, BoundingBox, Curve, KeySorter, Octree};

/// Sorted particle arrays with a tree over them.
struct Sorted {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    m: Vec<f64>,
    tree: Octree,
}

fn sort_and_build(
    bbox: &BoundingBox,
    mut x: Vec<f64>,
    mut y: Vec<f64>,
    mut z: Vec<f64>,
    mut m: Vec<f64>,
    bucket: usize,
) -> Sorted {
    let mut keys = Vec::new();
    compute_keys(bbox, Curve::Hilbert, &x, &y, &z, &mut keys);
    let mut perm = Vec::new();
    KeySorter::new().sort(&keys, None, &mut perm);
    let mut scratch = Vec::new();
    for a in [&mut x, &mut y, &mut z, &mut m] {
        apply_permutation(&perm, a, &mut scratch);
    }
    let mut sk = Vec::new();
    apply_permutation(&perm, &mut keys, &mut sk);
    let tree = Octree::build(&keys, &x, &y, &z, bucket).unwrap();
    Sorted { x, y, z, m, tree }
}

fn random_cloud(n: usize, seed: u64) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut r = Rng::new(seed);
    let mut v = |s: f64| (0..n).map(|_| s * r.uniform()).collect::<Vec<f64>>();
    let (x, y, z) = (v(1.0), v(1.0), v(1.0));
    let m = v(1.0).into_iter().map(|u| 0.1 + u).collect();
    (x, y, z, m)
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// An evaluation for some targets writes exactly the targets and
    /// leaves every other entry as it was. With every particle flagged it
    /// has the bits of a full evaluation (the groups are the full ones);
    /// with some flagged and every node opened, each target's field is the
    /// direct sum (its gathered group finds every source and skips only
    /// its own self pair).
    #[test]
    fn target_groups_write_exactly_the_targets(
        n in 1usize..500,
        group in 1usize..40,
        seed in any::<u64>(),
        every in 2usize..200,
    ) {
        let (x, y, z, m) = random_cloud(n, seed);
        let bbox = BoundingBox::enclosing(&x, &y, &z).unwrap();
        let s = sort_and_build(&bbox, x, y, z, m, 8);
        let params = GravityParams { group_size: group, ..GravityParams::default() };
        let mut solver = TreeGravity::new(params).unwrap();
        let mut full = GravityField::new();
        solver.compute(&s.tree, &bbox, &s.x, &s.y, &s.z, &s.m, None, &mut full).unwrap();
        let all = vec![true; n];
        let mut out = GravityField::new();
        let targets = Targets { active: Some(&all), drift: 0.0 };
        solver
            .compute_targets(&s.tree, &bbox, &s.x, &s.y, &s.z, &s.m, None, targets, &mut out)
            .unwrap();
        for i in 0..n {
            prop_assert_eq!(out.phi[i].to_bits(), full.phi[i].to_bits());
            prop_assert_eq!(out.acc(i).map(f64::to_bits), full.acc(i).map(f64::to_bits));
        }

        let active: Vec<bool> = (0..n).map(|i| (i * 7919 + seed as usize % 97).is_multiple_of(every)).collect();
        let opened = GravityParams { theta: 1e-9, ..params };
        let mut solver = TreeGravity::new(opened).unwrap();
        let mut out = GravityField::new();
        out.resize(n);
        out.phi.fill(f64::NAN);
        let targets = Targets { active: Some(&active), drift: 0.0 };
        let st = solver
            .compute_targets(&s.tree, &bbox, &s.x, &s.y, &s.z, &s.m, None, targets, &mut out)
            .unwrap();
        prop_assert_eq!(st.m2p, 0);
        let mut e = GravityField::new();
        direct::direct_sum(&s.x, &s.y, &s.z, &s.m, None, 1.0, &mut e).unwrap();
        for i in 0..n {
            if active[i] {
                let scale = norm(e.acc(i));
                for k in 0..3 {
                    prop_assert!((out.acc(i)[k] - e.acc(i)[k]).abs() <= 1e-12 * scale);
                }
                prop_assert!((out.phi[i] - e.phi[i]).abs() <= 1e-12 * e.phi[i].abs());
            } else {
                prop_assert!(out.phi[i].is_nan(), "inactive particle {} written", i);
            }
        }
    }

    /// Every node's mass and centre of mass equal the direct sums over its
    /// particles, and the root quadrupole (after all M2M shifts) equals
    /// the quadrupole summed directly over all particles.
    #[test]
    fn p2m_m2m_match_direct_sums(n in 1usize..400, bucket in 1usize..20, seed in any::<u64>()) {
        let (x, y, z, m) = random_cloud(n, seed);
        let bbox = BoundingBox::enclosing(&x, &y, &z).unwrap();
        let s = sort_and_build(&bbox, x, y, z, m, bucket);
        let mut mp = Multipoles::new();
        mp.compute(&s.tree, &s.x, &s.y, &s.z, &s.m);
        for node in 0..s.tree.num_nodes() as u32 {
            let r = s.tree.particles(node);
            let mass: f64 = s.m[r.clone()].iter().sum();
            let com = [&s.x, &s.y, &s.z].map(|c| {
                r.clone().map(|i| s.m[i] * c[i]).sum::<f64>() / mass
            });
            let got = mp.get(node);
            prop_assert!((got.mass - mass).abs() <= 1e-12 * mass);
            for d in 0..3 {
                prop_assert!((got.com[d] - com[d]).abs() <= 1e-12, "node {node} com {:?} vs {com:?}", got.com);
            }
        }
        // Root quadrupole, written out independently.
        let root = mp.root().unwrap();
        let c = root.com;
        let mut q = [[0.0f64; 3]; 3];
        let mut scale = 0.0;
        for i in 0..n {
            let d = [s.x[i] - c[0], s.y[i] - c[1], s.z[i] - c[2]];
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            scale += s.m[i] * r2;
            for a in 0..3 {
                for b in 0..3 {
                    q[a][b] += s.m[i] * (3.0 * d[a] * d[b] - if a == b { r2 } else { 0.0 });
                }
            }
        }
        let got = [
            [root.quad[0], root.quad[1], root.quad[2]],
            [root.quad[1], root.quad[3], root.quad[4]],
            [root.quad[2], root.quad[4], root.quad[5]],
        ];
        for a in 0..3 {
            for b in 0..3 {
                prop_assert!((got[a][b] - q[a][b]).abs() <= 1e-11 * scale.max(1e-300),
                    "Q[{a}][{b}] = {} vs {}", got[a][b], q[a][b]);
            }
        }
        let trace = root.quad[0] + root.quad[3] + root.quad[5];
        prop_assert!(trace.abs() <= 1e-12 * scale.max(1e-300));
    }

    /// Two particles: the tree gives the exact softened Newtonian force
    /// and potential, `a_1 = G m_2 (x_2 - x_1) / r_eff^3`,
    /// `phi_1 = -G m_2 / r_eff (3/2 - r^2 / (2 r_eff^2))` (uniform-sphere
    /// potential inside the softening), `r_eff^2 = max(r^2, (h_1 + h_2)^2)`.
    #[test]
    fn two_body_is_exact(
        p in prop::array::uniform3(-10.0f64..10.0),
        q in prop::array::uniform3(-10.0f64..10.0),
        m1 in 0.01f64..10.0, m2 in 0.01f64..10.0,
        h in prop::option::of((0.0f64..3.0, 0.0f64..3.0)),
        g in 0.1f64..10.0,
    ) {
        let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        prop_assume!(r2 > 1e-6);
        let hs = h.map(|(a, b)| vec![a, b]);
        let r2_eff = match h { Some((a, b)) => r2.max((a + b) * (a + b)), None => r2 };
        let r_eff = r2_eff.sqrt();
        let params = GravityParams { g, ..GravityParams::default() };
        let (f, st) = compute_gravity(&[p[0], q[0]], &[p[1], q[1]], &[p[2], q[2]], &[m1, m2],
                                      hs.as_deref(), &params).unwrap();
        prop_assert_eq!(st.p2p, 2);
        let tol = 1e-13;
        for (i, mo, sign) in [(0, m2, 1.0), (1, m1, -1.0)] {
            let want = d.map(|c| sign * g * mo * c / (r2_eff * r_eff));
            let got = f.acc(i);
            let scale = norm(want);
            for k in 0..3 {
                prop_assert!((got[k] - want[k]).abs() <= tol * scale, "a{i} {got:?} vs {want:?}");
            }
            let phi = -g * mo / r_eff * (1.5 - 0.5 * r2 / r2_eff);
            prop_assert!((f.phi[i] - phi).abs() <= tol * phi.abs());
        }
    }

    /// With a tiny opening angle every node is opened: the tree sum is the
    /// direct sum (same pairs, same softening) up to round-off.
    #[test]
    fn tree_with_tiny_theta_is_direct(n in 2usize..300, group in 1usize..80, leaf in 1usize..40,
                                      soft in any::<bool>(), seed in any::<u64>()) {
        let (x, y, z, m) = random_cloud(n, seed);
        let h: Option<Vec<f64>> = soft.then(|| (0..n).map(|i| 0.02 * (i % 5) as f64).collect());
        let params = GravityParams { theta: 1e-9, group_size: group, leaf_size: leaf,
                                     ..GravityParams::default() };
        let (f, st) = compute_gravity(&x, &y, &z, &m, h.as_deref(), &params).unwrap();
        prop_assert_eq!(st.m2p, 0);
        prop_assert_eq!(st.p2p, (n * (n - 1)) as u64);
        let mut e = GravityField::new();
        direct::direct_sum(&x, &y, &z, &m, h.as_deref(), 1.0, &mut e).unwrap();
        for i in 0..n {
            let scale = norm(e.acc(i));
            for k in 0..3 {
                prop_assert!((f.acc(i)[k] - e.acc(i)[k]).abs() <= 1e-12 * scale);
            }
            prop_assert!((f.phi[i] - e.phi[i]).abs() <= 1e-12 * e.phi[i].abs());
        }
    }

    /// Shifting every particle and the box by the same vector leaves the
    /// accelerations unchanged. Positions on a 2^-20 grid and integer
    /// shifts make the shift exact, so the tree is the same and only the
    /// rounding of centres of mass differs.
    #[test]
    fn translation_invariant(n in 2usize..500, shift in prop::array::uniform3(-8i32..8),
                             seed in any::<u64>()) {
        let mut r = Rng::new(seed);
        let mut grid = || (0..n).map(|_| (r.next_u64() >> 44) as f64 / (1u64 << 20) as f64).collect::<Vec<f64>>();
        let (x, y, z) = (grid(), grid(), grid());
        let m: Vec<f64> = (0..n).map(|i| 1.0 + (i % 3) as f64).collect();
        let s = shift.map(f64::from);
        let run = |off: [f64; 3]| {
            let bbox = BoundingBox::new([off[0], off[1], off[2]], [off[0] + 1.0, off[1] + 1.0, off[2] + 1.0],
                                        [Boundary::Open; 3]).unwrap();
            let sh = |c: &[f64], o: f64| c.iter().map(|v| v + o).collect::<Vec<f64>>();
            let sorted = sort_and_build(&bbox, sh(&x, off[0]), sh(&y, off[1]), sh(&z, off[2]), m.clone(), 8);
            let mut solver = TreeGravity::new(GravityParams { group_size: 16, ..GravityParams::default() }).unwrap();
            let mut f = GravityField::new();
            let st = solver.compute(&sorted.tree, &bbox, &sorted.x, &sorted.y, &sorted.z, &sorted.m, None,
                                    &mut f).unwrap();
            (f, st)
        };
        let (a, sa) = run([0.0; 3]);
        let (b, sb) = run(s);
        prop_assert_eq!(sa, sb);
        for i in 0..a.len() {
            let scale = norm(a.acc(i)).max(1e-300);
            let d = norm([a.ax[i] - b.ax[i], a.ay[i] - b.ay[i], a.az[i] - b.az[i]]);
            prop_assert!(d <= 1e-9 * scale, "particle {i}: {:?} vs {:?}", a.acc(i), b.acc(i));
        }
    }

    /// The direct sum is antisymmetric: the net force vanishes to round-off.
    #[test]
    fn direct_sum_has_no_net_force(n in 2usize..300, soft in any::<bool>(), seed in any::<u64>()) {
        let (x, y, z, m) = random_cloud(n, seed);
        let h: Option<Vec<f64>> = soft.then(|| vec![0.05; n]);
        let mut f = GravityField::new();
        direct::direct_sum(&x, &y, &z, &m, h.as_deref(), 1.0, &mut f).unwrap();
        let ratio = common::net_force_ratio(&f, &m);
        prop_assert!(ratio <= 1e-13, "net force ratio {ratio}");
    }

    /// Input checks find the first non-finite value of an array, however
    /// long, wherever it sits, and whatever the finite values are (huge
    /// ones included); arrays with none pass.
    #[test]
    fn first_non_finite_input_is_named(
        n in 1usize..70,
        bad in prop::option::of((0usize..70, 0usize..3, 0usize..5)),
        seed in any::<u64>(),
    ) {
        let (x, mut y, z, m) = random_cloud(n, seed);
        let mut h = vec![0.05; n];
        // Finite values whose plain sum would overflow to infinity.
        if n > 2 {
            h[0] = f64::MAX;
            h[1] = f64::MAX;
        }
        let mut expected = None;
        if let Some((at, which, kind)) = bad {
            let at = at % n;
            let value = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][which];
            let (array, name) = match kind {
                0 => (&mut y, "y"),
                _ => (&mut h, "h"),
            };
            array[at] = value;
            if kind > 1 {
                // A second bad value after the first: the first is named.
                array[(at + 1).min(n - 1)] = f64::NAN;
            }
            expected = Some((at, name));
        }
        let r = compute_gravity(&x, &y, &z, &m, Some(&h), &GravityParams::default());
        match (expected, r) {
            (None, Ok(_)) => {}
            (Some((at, name)), Err(sph_gravity::GravityError::NonFinite { index, what, .. })) => {
                prop_assert_eq!((index, what), (at, name));
            }
            (e, r) => prop_assert!(false, "expected {:?}, got {:?}", e, r.map(|_| ())),
        }
    }
}

/// The softened potential's gradient is the softened force (so energy is
/// conserved): a central difference of the two-body potential along the
/// separation matches the acceleration inside and outside the softening.
#[test]
fn softened_potential_gradient_is_the_force() {
    let params = GravityParams::default();
    let h = [0.3, 0.2]; // softening length 0.5
    for r in [0.1, 0.3, 0.49, 0.7, 2.0] {
        let phi_at = |r: f64| {
            let (f, _) = compute_gravity(
                &[0.0, r],
                &[0.0; 2],
                &[0.0; 2],
                &[1.0, 2.0],
                Some(&h),
                &params,
            )
            .unwrap();
            f
        };
        let d = 1e-6;
        let grad = (phi_at(r + d).phi[0] - phi_at(r - d).phi[0]) / (2.0 * d);
        let a = phi_at(r).ax[0];
        assert!(
            (grad - a).abs() < 1e-6 * a.abs(),
            "r = {r}: dphi/dr = {grad}, a = {a}"
        );
    }
}

/// The softening scale is the same as scaling h: identical bits, and a
/// negative or non-finite scale is refused.
#[test]
fn softening_scale_equals_scaled_h() {
    let (x, y, z, m) = random_cloud(500, 3);
    let h: Vec<f64> = (0..x.len())
        .map(|i| 0.01 + 0.002 * (i % 7) as f64)
        .collect();
    let half: Vec<f64> = h.iter().map(|v| v * 0.5).collect();
    let scaled = GravityParams {
        softening: 0.5,
        ..GravityParams::default()
    };
    let (a, _) = compute_gravity(&x, &y, &z, &m, Some(&h), &scaled).unwrap();
    let (b, _) = compute_gravity(&x, &y, &z, &m, Some(&half), &GravityParams::default()).unwrap();
    assert_eq!(a, b);
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        let p = GravityParams {
            softening: bad,
            ..GravityParams::default()
        };
        let err = compute_gravity(&x, &y, &z, &m, Some(&h), &p).unwrap_err();
        assert!(err.to_string().contains("softening"), "{err}");
    }
}
