//! Cartesian multipoles up to the quadrupole: particle-to-multipole (P2M),
//! multipole-to-multipole (M2M) and multipole-to-particle (M2P).
//!
//! Every expansion is taken about its own centre of mass, so the dipole
//! vanishes identically and is not stored. The quadrupole is the
//! **traceless** Cartesian one,
//!
//! ```text
//! Q_ab = sum_k m_k (3 d_a d_b - |d|^2 delta_ab),   d = x_k - com,
//! ```
//!
//! stored as its six upper-triangle components `[xx, xy, xz, yy, yz, zz]`
//! (`xx + yy + zz = 0` up to round-off). With `r` the vector from the centre
//! of mass to the evaluation point, the far field is
//!
//! ```text
//! phi(r) = -G (M / |r| + (r . Q r) / (2 |r|^5))
//! a(r)   = -grad phi = G (-M r / |r|^3 + Q r / |r|^5 - 5/2 (r . Q r) r / |r|^7).
//! ```

use rayon::prelude::*;
use sph_tree::{NodeId, Octree};

/// Indices into the six stored quadrupole components.
const XX: usize = 0;
const XY: usize = 1;
const XZ: usize = 2;
const YY: usize = 3;
const YZ: usize = 4;
const ZZ: usize = 5;

/// Expansion order used when a tree node is accepted as a whole.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ExpansionOrder {
    /// Mass at the centre of mass only (the dipole vanishes about it).
    Monopole,
    /// Monopole plus the traceless Cartesian quadrupole.
    #[default]
    Quadrupole,
}

/// The multipole expansion of a set of point masses about their centre of
/// mass: total mass, centre of mass and traceless quadrupole (see the
/// [module documentation](self) for the convention).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Multipole {
    /// Total mass.
    pub mass: f64,
    /// Expansion centre: the centre of mass (the plain mean of the
    /// positions when the total mass is exactly zero).
    pub com: [f64; 3],
    /// Traceless quadrupole `[xx, xy, xz, yy, yz, zz]` about `com`.
    pub quad: [f64; 6],
}

/// Adds `w (3 d d^T - |d|^2 I)` to a quadrupole.
#[inline]
fn add_outer(q: &mut [f64; 6], w: f64, d: [f64; 3]) {
    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    q[XX] += w * (3.0 * d[0] * d[0] - r2);
    q[XY] += w * (3.0 * d[0] * d[1]);
    q[XZ] += w * (3.0 * d[0] * d[2]);
    q[YY] += w * (3.0 * d[1] * d[1] - r2);
    q[YZ] += w * (3.0 * d[1] * d[2]);
    q[ZZ] += w * (3.0 * d[2] * d[2] - r2);
}

impl Multipole {
    /// P2M: the expansion of the point masses `m` at `(x, y, z)` (slices
    /// of equal length) about their centre of mass. Two passes: the centre
    /// of mass first, then the quadrupole about it.
    ///
    /// ```
    /// use sph_gravity::Multipole;
    /// let mp = Multipole::from_particles(&[-1.0, 1.0], &[0.0, 0.0], &[0.0, 0.0], &[1.0, 3.0]);
    /// assert_eq!(mp.mass, 4.0);
    /// assert_eq!(mp.com, [0.5, 0.0, 0.0]);
    /// ```
    pub fn from_particles(x: &[f64], y: &[f64], z: &[f64], m: &[f64]) -> Self {
        let n = x.len();
        assert!(
            y.len() == n && z.len() == n && m.len() == n,
            "P2M slices differ in length"
        );
        let mut mass = 0.0;
        let mut s = [0.0; 3];
        for i in 0..n {
            mass += m[i];
            s[0] += m[i] * x[i];
            s[1] += m[i] * y[i];
            s[2] += m[i] * z[i];
        }
        let com = if mass != 0.0 {
            [s[0] / mass, s[1] / mass, s[2] / mass]
        } else if n > 0 {
            // Zero total mass: any centre is exact for the monopole; take
            // the plain mean so it lies among the particles.
            let inv = 1.0 / n as f64;
            [
                x.iter().sum::<f64>() * inv,
                y.iter().sum::<f64>() * inv,
                z.iter().sum::<f64>() * inv,
            ]
        } else {
            [0.0; 3]
        };
        let mut quad = [0.0; 6];
        for i in 0..n {
            add_outer(
                &mut quad,
                m[i],
                [x[i] - com[0], y[i] - com[1], z[i] - com[2]],
            );
        }
        Self { mass, com, quad }
    }

    /// M2M: the expansion of the union of the given expansions, about the
    /// combined centre of mass. Each child quadrupole is shifted by the
    /// parallel-axis rule `Q += m_c (3 d d^T - |d|^2 I)`, `d = com_c - com`,
    /// which is exact because each child's dipole about its own centre of
    /// mass vanishes.
    pub fn from_children(children: &[Multipole]) -> Self {
        let mut mass = 0.0;
        let mut s = [0.0; 3];
        for c in children {
            mass += c.mass;
            for d in 0..3 {
                s[d] += c.mass * c.com[d];
            }
        }
        let com = if mass != 0.0 {
            [s[0] / mass, s[1] / mass, s[2] / mass]
        } else if !children.is_empty() {
            let inv = 1.0 / children.len() as f64;
            let mut c = [0.0; 3];
            for ch in children {
                for d in 0..3 {
                    c[d] += ch.com[d] * inv;
                }
            }
            c
        } else {
            [0.0; 3]
        };
        let mut quad = [0.0; 6];
        for c in children {
            for k in 0..6 {
                quad[k] += c.quad[k];
            }
            let d = [c.com[0] - com[0], c.com[1] - com[1], c.com[2] - com[2]];
            add_outer(&mut quad, c.mass, d);
        }
        Self { mass, com, quad }
    }

    /// M2P at one point `p` (outside the particle distribution): returns
    /// `(phi, [ax, ay, az])` including the factor `g`. No softening: the
    /// tree only uses it where every pair is beyond its softening length.
    ///
    /// ```
    /// use sph_gravity::{ExpansionOrder, Multipole};
    /// let mp = Multipole { mass: 2.0, com: [0.0; 3], quad: [0.0; 6] };
    /// let (phi, a) = mp.evaluate([2.0, 0.0, 0.0], 1.0, ExpansionOrder::Quadrupole);
    /// assert_eq!(phi, -1.0);
    /// assert_eq!(a, [-0.5, 0.0, 0.0]);
    /// ```
    pub fn evaluate(&self, p: [f64; 3], g: f64, order: ExpansionOrder) -> (f64, [f64; 3]) {
        let d = [p[0] - self.com[0], p[1] - self.com[1], p[2] - self.com[2]];
        let mut phi = 0.0;
        let mut a = [0.0; 3];
        match order {
            ExpansionOrder::Monopole => m2p_point::<false>(self, d, &mut phi, &mut a),
            ExpansionOrder::Quadrupole => m2p_point::<true>(self, d, &mut phi, &mut a),
        }
        (g * phi, [g * a[0], g * a[1], g * a[2]])
    }
}

/// Adds the field (without `G`) of `mp` at separation `d = target - com`
/// (non-zero) to the accumulators; `QUAD` adds the quadrupole term.
#[inline(always)]
pub(crate) fn m2p_point<const QUAD: bool>(
    mp: &Multipole,
    d: [f64; 3],
    phi: &mut f64,
    a: &mut [f64; 3],
) {
    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let inv_r = 1.0 / r2.sqrt();
    let inv_r2 = inv_r * inv_r;
    let m_r = mp.mass * inv_r;
    let m_r3 = m_r * inv_r2;
    let mut p = -m_r;
    let mut f = [-m_r3 * d[0], -m_r3 * d[1], -m_r3 * d[2]];
    if QUAD {
        let q = &mp.quad;
        let qr = [
            q[XX] * d[0] + q[XY] * d[1] + q[XZ] * d[2],
            q[XY] * d[0] + q[YY] * d[1] + q[YZ] * d[2],
            q[XZ] * d[0] + q[YZ] * d[1] + q[ZZ] * d[2],
        ];
        let rqr = d[0] * qr[0] + d[1] * qr[1] + d[2] * qr[2];
        let inv_r5 = inv_r2 * inv_r2 * inv_r;
        let inv_r7 = inv_r5 * inv_r2;
        p -= 0.5 * rqr * inv_r5;
        let c = 2.5 * rqr * inv_r7;
        for k in 0..3 {
            f[k] += qr[k] * inv_r5 - c * d[k];
        }
    }
    *phi += p;
    for k in 0..3 {
        a[k] += f[k];
    }
}

/// Per-node multipoles of an [`Octree`], computed by P2M on the leaves and
/// M2M upwards, one tree level at a time (parallel within a level). The
/// buffer is reused between evaluations.
#[derive(Debug, Clone, Default)]
pub struct Multipoles {
    nodes: Vec<Multipole>,
}

impl Multipoles {
    /// An empty set; fill it with [`Multipoles::compute`].
    pub fn new() -> Self {
        Self::default()
    }

    /// Upward pass over `tree`, built over the particles `(x, y, z)` with
    /// masses `m` in the tree's (SFC-sorted) order.
    ///
    /// # Panics
    /// If a slice is shorter than the number of particles in the tree.
    pub fn compute(&mut self, tree: &Octree, x: &[f64], y: &[f64], z: &[f64], m: &[f64]) {
        let n = tree.num_particles();
        assert!(
            x.len() >= n && y.len() >= n && z.len() >= n && m.len() >= n,
            "multipole inputs shorter than the tree's {n} particles"
        );
        upward(
            tree,
            &mut self.nodes,
            |node| {
                let r = tree.particles(node);
                Multipole::from_particles(&x[r.clone()], &y[r.clone()], &z[r.clone()], &m[r])
            },
            Multipole::from_children,
        );
    }

    /// The expansion of one node.
    #[inline]
    pub fn get(&self, node: NodeId) -> &Multipole {
        &self.nodes[node as usize]
    }

    /// The expansion of every node, indexed by [`NodeId`].
    pub fn as_slice(&self) -> &[Multipole] {
        &self.nodes
    }

    /// The root's expansion (all particles); `None` before the first
    /// [`compute`](Multipoles::compute) or for an empty tree.
    pub fn root(&self) -> Option<&Multipole> {
        self.nodes.first()
    }
}

/// Generic bottom-up pass: `leaf(node)` for leaves, `combine(children)` for
/// internal nodes (children are contiguous and on the next level).
pub(crate) fn upward<T: Copy + Default + Send + Sync>(
    tree: &Octree,
    out: &mut Vec<T>,
    leaf: impl Fn(NodeId) -> T + Sync,
    combine: impl Fn(&[T]) -> T + Sync,
) {
    out.clear();
    out.resize(tree.num_nodes(), T::default());
    if tree.num_particles() == 0 {
        return;
    }
    for lvl in (0..tree.num_levels()).rev() {
        let r = tree.level_nodes(lvl);
        let (a, b) = (r.start as usize, r.end as usize);
        let (head, tail) = out.split_at_mut(b);
        head[a..b].par_iter_mut().enumerate().for_each(|(k, v)| {
            let node = (a + k) as NodeId;
            let ch = tree.children(node);
            *v = if ch.is_empty() {
                leaf(node)
            } else {
                combine(&tail[ch.start as usize - b..ch.end as usize - b])
            };
        });
    }
}
