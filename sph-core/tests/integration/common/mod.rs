//! Checks and set-ups shared by the stage tests.

use sph_core::{FieldSet, Particles};
use sph_kernels::{Sinc, Tabulated};
use sph_tree::{
    apply_permutation, compute_keys, Boundary, BoundingBox, CompactNeighborList, Curve, KeySorter,
    NeighborSearch, Octree,
};

/// SplitMix64: seeded uniform numbers in [0, 1).
pub struct Rng(pub u64);

impl Rng {
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Particles sorted along the curve, their box, keys and neighbour lists.
pub struct Setup {
    pub p: Particles,
    pub bbox: BoundingBox,
    pub list: CompactNeighborList,
    pub keys: Vec<u64>,
}

/// An n^3 lattice in the periodic box [-0.5, 0.5)^3, each particle moved by
/// up to `jitter` lattice spacings (seeded by `seed`), sorted along the
/// curve, with h for about `ng` neighbours, unit total mass and symmetric
/// neighbour lists; every other field zero.
pub fn periodic_lattice(n: usize, jitter: f64, ng: f64, seed: u64) -> Setup {
    let mut rng = Rng(seed);
    let np = n * n * n;
    let mut p = Particles::new(np, FieldSet::default());
    let dx = 1.0 / n as f64;
    let bbox = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
    for i in 0..np {
        let c = [i % n, i / n % n, i / (n * n)];
        let mut q = [0.0; 3];
        for k in 0..3 {
            q[k] = (c[k] as f64 + 0.5) * dx - 0.5 + jitter * dx * (rng.uniform() - 0.5);
        }
        let q = bbox.wrap(q);
        (p.x[i], p.y[i], p.z[i]) = (q[0], q[1], q[2]);
        p.m[i] = 1.0 / np as f64;
        p.h[i] = 0.5 * (3.0 * ng / (4.0 * std::f64::consts::PI * np as f64)).cbrt();
    }
    let keys = sort_along_curve(&mut p, &bbox);
    let mut list = CompactNeighborList::new();
    symmetric_lists(&p, &bbox, &keys, &mut list);
    Setup {
        p,
        bbox,
        list,
        keys,
    }
}

/// Sorts `p` along the Hilbert curve of `bbox`; returns the keys in the
/// new order.
pub fn sort_along_curve(p: &mut Particles, bbox: &BoundingBox) -> Vec<u64> {
    let mut keys = Vec::new();
    compute_keys(bbox, Curve::Hilbert, &p.x, &p.y, &p.z, &mut keys);
    let mut perm = Vec::new();
    KeySorter::new().sort(&keys, None, &mut perm);
    p.reorder(&perm, &mut Vec::new());
    apply_permutation(&perm, &mut keys, &mut Vec::new());
    keys
}

/// Symmetric neighbour lists of every particle of `p` (sorted, with
/// `keys`) for its current h, as the pipeline builds them.
pub fn symmetric_lists(
    p: &Particles,
    bbox: &BoundingBox,
    keys: &[u64],
    list: &mut CompactNeighborList,
) {
    let tree = Octree::build(keys, &p.x, &p.y, &p.z, 16).unwrap();
    let search = NeighborSearch {
        symmetric: true,
        ..Default::default()
    };
    search
        .find_compact(&tree, bbox, &p.x, &p.y, &p.z, &p.h, 0..p.len(), list)
        .unwrap();
}

/// The stage tests' kernel: sinc with n = 6, tabulated.
pub fn kernel() -> Tabulated {
    Tabulated::new(&Sinc::new(6.0).unwrap(), Tabulated::DEFAULT_POINTS).unwrap()
}

/// How far one force evaluation is from conserving momentum and energy:
/// the largest `|sum_i m_i a_i|` over the axes relative to
/// `sum_i m_i |a_i|`, and `|sum_i m_i (v_i . a_i + du_i)|` relative to the
/// sum of the magnitudes of its terms (pressure + viscous work against the
/// kinetic energy change).
pub fn conservation_errors(p: &Particles) -> (f64, f64) {
    let (mut mom, mut scale, mut de, mut de_scale) = ([0.0f64; 3], 0.0, 0.0, 0.0);
    for i in 0..p.len() {
        let a = [p.ax[i], p.ay[i], p.az[i]];
        for k in 0..3 {
            mom[k] += p.m[i] * a[k];
            scale += p.m[i] * a[k].abs();
        }
        let work = p.m[i] * (p.vx[i] * a[0] + p.vy[i] * a[1] + p.vz[i] * a[2]);
        de += work + p.m[i] * p.du[i];
        de_scale += work.abs() + (p.m[i] * p.du[i]).abs();
    }
    let momentum = mom.iter().fold(0.0f64, |m, c| m.max(c.abs())) / scale;
    (momentum, de.abs() / de_scale)
}

/// Particle `i` of a random flow for the conservation checks: each velocity
/// component uniform in [-0.5, 0.5), u uniform in [1, 2), drawn from
/// `uniform` (values in [0, 1)) in that order.
pub fn random_flow(p: &mut Particles, i: usize, mut uniform: impl FnMut() -> f64) {
    p.vx[i] = uniform() - 0.5;
    p.vy[i] = uniform() - 0.5;
    p.vz[i] = uniform() - 0.5;
    p.u[i] = 1.0 + uniform();
}
