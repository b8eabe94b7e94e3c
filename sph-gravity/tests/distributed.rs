//! Distributed gravity on in-process ranks (`sph_comm::run_ranks`): a
//! Plummer sphere split into 1, 2 and 4 contiguous key ranges, each rank
//! holding only its own particles, against the direct sum and against the
//! one-rank tree.

mod common;

use common::{plummer, quantile, relative_errors, Cloud};
use sph_comm::{run_ranks, Communicator};
use sph_gravity::{
    direct, Decomposition, DistributedGravity, GravityField, GravityParams, Targets,
};
use sph_tree::{compute_keys, BoundingBox, Curve, KeySorter, Octree};

/// Each particle's field (in the cloud's order) computed on `ranks`
/// ranks, with softening `h`.
fn distributed(c: &Cloud, h: &[f64], ranks: usize) -> (GravityField, u64) {
    distributed_targets(c, c, h, ranks, 0.0, None)
}

/// [`distributed`] with the keys, the split and the tree cells of the
/// particles at `keyed` and the evaluation at `at` (each particle within
/// `drift` of where it was keyed), on the `active` particles only (cloud
/// order; the others' entries are left 0).
fn distributed_targets(
    keyed: &Cloud,
    at: &Cloud,
    h: &[f64],
    ranks: usize,
    drift: f64,
    active: Option<&[bool]>,
) -> (GravityField, u64) {
    let bbox = BoundingBox::enclosing(&keyed.x, &keyed.y, &keyed.z).unwrap();
    let mut keys = Vec::new();
    compute_keys(
        &bbox,
        Curve::Hilbert,
        &keyed.x,
        &keyed.y,
        &keyed.z,
        &mut keys,
    );
    let mut perm = Vec::new();
    KeySorter::new().sort(&keys, None, &mut perm);
    let pick = |a: &[f64]| perm.iter().map(|&k| a[k as usize]).collect::<Vec<f64>>();
    let c = at;
    let (x, y, z, m, hs) = (pick(&c.x), pick(&c.y), pick(&c.z), pick(&c.m), pick(h));
    let flags: Option<Vec<bool>> = active.map(|a| perm.iter().map(|&k| a[k as usize]).collect());
    let keys: Vec<u64> = perm.iter().map(|&k| keys[k as usize]).collect();
    let n = x.len();
    // Equal-count contiguous key ranges.
    let mut bounds: Vec<usize> = (0..=ranks).map(|r| n * r / ranks).collect();
    let mut key_start: Vec<u64> = bounds[..ranks].iter().map(|&b| keys[b]).collect();
    key_start[0] = 0;
    key_start.push(1u64 << 63);
    // Ties across a boundary would split equal keys: move the cut after them.
    for r in 1..ranks {
        bounds[r] = keys.partition_point(|&k| k < key_start[r]);
    }
    let h_max = hs.iter().fold(0.0, |a: f64, &b| a.max(b));
    let parts = run_ranks(ranks, |comm| {
        let r = comm.rank();
        let range = bounds[r]..bounds[r + 1];
        let tree = Octree::build(
            &keys[range.clone()],
            &x[range.clone()],
            &y[range.clone()],
            &z[range.clone()],
            32,
        )
        .unwrap();
        let mut solver = DistributedGravity::new(GravityParams::default()).unwrap();
        let mut out = GravityField::new();
        let dec = Decomposition {
            bbox: &bbox,
            curve: Curve::Hilbert,
            key_start: &key_start,
            h_max,
        };
        let stats = solver
            .compute(
                &comm,
                dec,
                &tree,
                &x[range.clone()],
                &y[range.clone()],
                &z[range.clone()],
                &m[range.clone()],
                Some(&hs[range.clone()]),
                Targets {
                    active: flags.as_ref().map(|f| &f[range.clone()]),
                    drift,
                },
                &mut out,
            )
            .unwrap();
        (out, stats.m2p + stats.p2p)
    });
    let mut all = GravityField::new();
    let mut interactions = 0;
    for (f, k) in parts {
        all.ax.extend(f.ax);
        all.ay.extend(f.ay);
        all.az.extend(f.az);
        all.phi.extend(f.phi);
        interactions += k;
    }
    // Back to the cloud's order.
    let mut out = GravityField::new();
    out.resize(n);
    for (s, &k) in perm.iter().enumerate() {
        let k = k as usize;
        (out.ax[k], out.ay[k], out.az[k], out.phi[k]) =
            (all.ax[s], all.ay[s], all.az[s], all.phi[s]);
    }
    (out, interactions)
}

#[test]
fn plummer_on_1_2_4_ranks_matches_direct_sum() {
    let c = plummer(10_000, 10.0, 7);
    let h: Vec<f64> = (0..c.len())
        .map(|i| 0.002 + 0.001 * (i % 3) as f64)
        .collect();
    let mut exact = GravityField::new();
    direct::direct_sum(&c.x, &c.y, &c.z, &c.m, Some(&h), 1.0, &mut exact).unwrap();
    let e_exact = exact.potential_energy(&c.m);
    let (one, _) = distributed(&c, &h, 1);
    for ranks in [1, 2, 4] {
        let (f, interactions) = distributed(&c, &h, ranks);
        let e = relative_errors(&f, &exact);
        let (p99, max) = (quantile(&e, 0.99), *e.last().unwrap());
        let de = ((f.potential_energy(&c.m) - e_exact) / e_exact).abs();
        println!(
            "{ranks} ranks: p99 {p99:.2e} max {max:.2e} potential {de:.2e}, {:.0} interactions/particle",
            interactions as f64 / c.len() as f64
        );
        assert!(p99 <= 1e-3, "{ranks} ranks: p99 {p99:e}");
        assert!(max <= 3e-2, "{ranks} ranks: max {max:e}");
        assert!(de <= 1e-2, "{ranks} ranks: potential {de:e}");
        // Against the one-rank tree: remote parts use a stricter criterion
        // (the whole remote domain), so the difference is below the tree's
        // own error.
        let d = relative_errors(&f, &one);
        assert!(
            quantile(&d, 0.99) <= 1e-3,
            "{ranks} ranks vs 1: {:e}",
            quantile(&d, 0.99)
        );
    }
}

/// Individual time steps: the tree and the domains of the last rebuild,
/// particles drifted since by up to 0.01 (a hundredth of the Plummer
/// radius), the field wanted on a random third of them. The drift margin
/// keeps the tree's accuracy against the direct sum at the drifted
/// positions on 1, 2 and 4 ranks, and the active particles' fields stay
/// within it of an all-active evaluation.
#[test]
fn drifted_active_targets_keep_the_tree_accuracy() {
    let keyed = plummer(10_000, 10.0, 11);
    let h: Vec<f64> = (0..keyed.len())
        .map(|i| 0.002 + 0.001 * (i % 3) as f64)
        .collect();
    let mut rng = common::Rng::new(5);
    let drift = 0.01;
    let mut at = keyed.clone();
    for i in 0..at.len() {
        let d = rng.direction();
        let r = drift * rng.uniform();
        at.x[i] += r * d[0];
        at.y[i] += r * d[1];
        at.z[i] += r * d[2];
    }
    let active: Vec<bool> = (0..at.len()).map(|_| rng.uniform() < 1.0 / 3.0).collect();
    let mut exact = GravityField::new();
    direct::direct_sum(&at.x, &at.y, &at.z, &at.m, Some(&h), 1.0, &mut exact).unwrap();
    let pick = |f: &GravityField| {
        let mut g = GravityField::new();
        for i in (0..f.len()).filter(|&i| active[i]) {
            g.ax.push(f.ax[i]);
            g.ay.push(f.ay[i]);
            g.az.push(f.az[i]);
            g.phi.push(f.phi[i]);
        }
        g
    };
    let exact = pick(&exact);
    let (all_active, _) = distributed_targets(&keyed, &at, &h, 1, drift, None);
    for ranks in [1, 2, 4] {
        let (f, _) = distributed_targets(&keyed, &at, &h, ranks, drift, Some(&active));
        let e = relative_errors(&pick(&f), &exact);
        let (p99, max) = (quantile(&e, 0.99), *e.last().unwrap());
        println!("{ranks} ranks, drifted: p99 {p99:.2e} max {max:.2e}");
        assert!(p99 <= 1e-3, "{ranks} ranks: p99 {p99:e}");
        assert!(max <= 3e-2, "{ranks} ranks: max {max:e}");
        // Against the all-active evaluation (groups of other members, the
        // same drift margin): within the tree's own error.
        let d = relative_errors(&pick(&f), &pick(&all_active));
        assert!(
            quantile(&d, 0.99) <= 1e-3,
            "{ranks} ranks vs all active: {:e}",
            quantile(&d, 0.99)
        );
    }
}
