//! Gravity over several ranks: each rank evaluates its own particles with
//! its local tree, then receives from every other rank a locally essential
//! set — the multipoles of that rank's nodes that pass the opening
//! criterion for this rank's whole domain, and the particles of the leaves
//! that do not — and adds their field. No rank ever holds all particles.
//!
//! A rank's domain is the contiguous SFC key range it owns (as assigned by a
//! domain decomposition such as `sph-domain`), described to the senders as
//! the few aligned octree cells that tile it; the sender tests its nodes
//! against those cells, so the criterion holds for every target inside.
//! The receiver applies each remote multipole and particle to each of its
//! particles directly: `O(N_local x N_essential)`, fine for moderate rank
//! counts and sizes, and exact in the order of summation (ascending source
//! rank, then the sender's traversal order), so results do not depend on
//! the number of threads.

use crate::multipole::Multipole;
use crate::pair::softened_p2p;
use crate::traversal::{check_targets, dist2_point_box, mac_radius, max_of};
use crate::{GravityError, GravityField, GravityParams, GravityStats, Targets, TreeGravity};
use rayon::prelude::*;
use sph_comm::Communicator;
use sph_tree::{BoundingBox, Curve, NodeId, Octree, CELLS_PER_AXIS, MAX_LEVEL};

/// Floats per multipole (mass, centre, 6 quadrupole components) and per
/// essential particle (x, y, z, m, h) in messages.
const MP_WORDS: usize = 10;
const P_WORDS: usize = 5;

/// Tree gravity of a distributed particle set (see the module docs).
#[derive(Debug, Clone)]
pub struct DistributedGravity {
    local: TreeGravity,
    hmax: Vec<f64>,
}

/// Where this rank's particles live globally.
#[derive(Debug, Clone, Copy)]
pub struct Decomposition<'a> {
    /// The global box the keys were computed in (open on every axis).
    pub bbox: &'a BoundingBox,
    /// The curve of the keys.
    pub curve: Curve,
    /// First key owned by each rank, then the end of the key space
    /// (`size + 1` entries, the same on every rank).
    pub key_start: &'a [u64],
    /// The largest smoothing length `h` of any particle on any rank (the
    /// softening scale of the parameters applies on top).
    pub h_max: f64,
}

impl DistributedGravity {
    /// A solver with the given parameters (checked).
    pub fn new(params: GravityParams) -> Result<Self, GravityError> {
        Ok(Self {
            local: TreeGravity::new(params)?,
            hmax: Vec::new(),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &GravityParams {
        self.local.params()
    }

    /// Field of all ranks' particles on this rank's `targets` (see
    /// [`Targets`]: all, on a tree of the current positions, for a plain
    /// evaluation), which are sorted along the curve and held by `tree`
    /// (built over them alone, from the keys of `dec`). Collective: every
    /// rank of `comm` calls it, with the same drift bound.
    #[allow(clippy::too_many_arguments)]
    pub fn compute<C: Communicator>(
        &mut self,
        comm: &C,
        dec: Decomposition<'_>,
        tree: &Octree,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        m: &[f64],
        h: Option<&[f64]>,
        targets: Targets<'_>,
        out: &mut GravityField,
    ) -> Result<GravityStats, GravityError> {
        if dec.key_start.len() != comm.size() + 1 {
            return Err(GravityError::InvalidDecomposition {
                bounds: dec.key_start.len(),
                ranks: comm.size(),
            });
        }
        check_targets(&targets, x.len())?;
        let mut stats = self
            .local
            .compute_targets(tree, dec.bbox, x, y, z, m, h, targets, out)?;
        if comm.size() == 1 {
            return Ok(stats);
        }
        let params = *self.local.params();
        // Largest h per node, for the softening condition of multipoles.
        self.hmax.clear();
        self.hmax.resize(tree.num_nodes(), 0.0);
        if let Some(h) = h {
            for node in 0..tree.num_nodes() as NodeId {
                self.hmax[node as usize] = max_of(&h[tree.particles(node)]);
            }
        }
        let mps = self.local.multipoles().as_slice();
        let me = comm.rank();
        let mut sends: Vec<(usize, Vec<f64>)> = Vec::new();
        for r in 0..comm.size() {
            let (klo, khi) = (dec.key_start[r], dec.key_start[r + 1]);
            if r == me || klo >= khi || x.is_empty() {
                continue;
            }
            let cells = range_cells(klo, khi, dec.bbox, dec.curve);
            let mut mult: Vec<f64> = Vec::new();
            let mut parts: Vec<f64> = Vec::new();
            tree.traverse(
                |node| {
                    let mp = &mps[node as usize];
                    let mac = mac_radius(
                        tree,
                        node,
                        mp.com,
                        dec.bbox,
                        1.0 / params.theta,
                        targets.drift > 0.0,
                    );
                    let soft = params.softening * (self.hmax[node as usize] + dec.h_max);
                    // The receiver's particles lie within the drift of
                    // its cells.
                    let reach = mac.max(soft) + targets.drift;
                    let far = cells
                        .iter()
                        .all(|&(lo, hi)| dist2_point_box(mp.com, lo, hi) > reach * reach);
                    if far {
                        mult.push(mp.mass);
                        mult.extend_from_slice(&mp.com);
                        mult.extend_from_slice(&mp.quad);
                    }
                    !far
                },
                |leaf| {
                    for i in tree.particles(leaf) {
                        parts.extend([x[i], y[i], z[i], m[i], h.map_or(0.0, |h| h[i])]);
                    }
                },
            );
            let mut buf = Vec::with_capacity(1 + mult.len() + parts.len());
            buf.push((mult.len() / MP_WORDS) as f64);
            buf.extend(mult);
            buf.extend(parts);
            sends.push((r, buf));
        }
        let received = comm.sparse_exchange(&sends)?;

        // Remote multipoles and particles, in ascending source rank.
        let mut remote_mp: Vec<Multipole> = Vec::new();
        let mut remote_p: Vec<[f64; P_WORDS]> = Vec::new();
        for (_, buf) in &received {
            let nm = buf.first().copied().unwrap_or(0.0) as usize;
            let (mbuf, pbuf) = buf[1..].split_at(nm * MP_WORDS);
            remote_mp.extend(mbuf.chunks_exact(MP_WORDS).map(|w| Multipole {
                mass: w[0],
                com: [w[1], w[2], w[3]],
                quad: [w[4], w[5], w[6], w[7], w[8], w[9]],
            }));
            remote_p.extend(
                pbuf.chunks_exact(P_WORDS)
                    .map(|w| [w[0], w[1], w[2], w[3], w[4]]),
            );
        }
        let g = params.g;
        let order = params.order;
        let soft_scale = params.softening;
        let GravityField { ax, ay, az, phi } = out;
        (ax, ay, az, phi)
            .into_par_iter()
            .enumerate()
            .filter(|(i, _)| targets.is_active(*i))
            .for_each(|(i, (ax, ay, az, phi))| {
                let pi = [x[i], y[i], z[i]];
                let hi = h.map_or(0.0, |h| h[i]);
                let (mut s, mut a) = (0.0, [0.0; 3]);
                for mp in &remote_mp {
                    let (p, acc) = mp.evaluate(pi, 1.0, order);
                    s += p;
                    for k in 0..3 {
                        a[k] += acc[k];
                    }
                }
                for q in &remote_p {
                    let d = [q[0] - pi[0], q[1] - pi[1], q[2] - pi[2]];
                    let eps = soft_scale * (hi + q[4]);
                    let (acc, p) = softened_p2p::<true>(d, q[3], eps, true);
                    for k in 0..3 {
                        a[k] += acc[k];
                    }
                    s += p;
                }
                *ax += g * a[0];
                *ay += g * a[1];
                *az += g * a[2];
                *phi += g * s;
            });
        let evaluated = targets.count(x.len());
        stats.m2p += (remote_mp.len() * evaluated) as u64;
        stats.p2p += (remote_p.len() * evaluated) as u64;
        Ok(stats)
    }
}

/// The aligned octree cells (as boxes) that tile the key range `[lo, hi)`:
/// at most two per level.
fn range_cells(
    mut lo: u64,
    hi: u64,
    bbox: &BoundingBox,
    curve: Curve,
) -> Vec<([f64; 3], [f64; 3])> {
    let mut out = Vec::new();
    let (blo, blen) = (bbox.lo(), bbox.lengths());
    let scale = f64::from(CELLS_PER_AXIS);
    while lo < hi {
        // Largest aligned block starting at lo that fits below hi.
        let mut level = 0;
        loop {
            let size = 1u64 << (3 * (MAX_LEVEL - level));
            if lo.is_multiple_of(size) && lo + size <= hi {
                break;
            }
            level += 1;
        }
        let side = 1u32 << (MAX_LEVEL - level);
        let (a, b, c) = curve.decode(lo);
        let corner = [a & !(side - 1), b & !(side - 1), c & !(side - 1)];
        let mut bl = [0.0; 3];
        let mut bh = [0.0; 3];
        for k in 0..3 {
            bl[k] = blo[k] + f64::from(corner[k]) / scale * blen[k];
            bh[k] = blo[k] + f64::from(corner[k] + side) / scale * blen[k];
        }
        out.push((bl, bh));
        lo += 1u64 << (3 * (MAX_LEVEL - level));
    }
    out
}
