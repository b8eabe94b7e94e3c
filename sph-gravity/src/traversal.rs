//! The Barnes-Hut evaluation: upward pass, per-node opening radii, and one
//! traversal per target group feeding the M2P and P2P kernels.

use crate::multipole::{m2p_point, upward, ExpansionOrder, Multipole, Multipoles};
use crate::pair::softened_p2p;
use crate::{validate, GravityError, GravityField, GravityParams, GravityStats, Targets};
use rayon::prelude::*;
use sph_tree::{apply_permutation, compute_keys, BoundingBox, Curve, KeySorter, NodeId, Octree};
use std::ops::Range;

/// Target groups of a partly active evaluation gather up to `group_size`
/// consecutive active particles from a span of this many groups along the
/// curve: close enough in space for tight lists, full enough that the
/// kernels' inner loops over targets stay vector-wide.
const ACTIVE_SPAN: usize = 8;

/// What the opening test needs per node, packed together.
#[derive(Debug, Clone, Copy, Default)]
struct NodeCrit {
    /// Expansion centre (centre of mass).
    com: [f64; 3],
    /// Squared vector-MAC radius `(l / theta + s)^2`.
    mac2: f64,
    /// Largest smoothing length in the node (0 without softening).
    hmax: f64,
}

/// Evaluation state reused between calls: multipoles and opening data.
#[derive(Debug, Clone, Default)]
struct Evaluator {
    multipoles: Multipoles,
    hmax: Vec<f64>,
    crit: Vec<NodeCrit>,
}

/// Buffers of the convenience path that sorts the caller's particles.
#[derive(Debug, Clone, Default)]
struct SortBuffers {
    keys: Vec<u64>,
    scratch_keys: Vec<u64>,
    perm: Vec<u32>,
    inv: Vec<u32>,
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    m: Vec<f64>,
    h: Vec<f64>,
    tree: Octree,
    field: GravityField,
}

/// Tree-gravity solver. Holds its parameters and every buffer (multipoles,
/// opening radii, and for [`compute_unsorted`](TreeGravity::compute_unsorted)
/// the sorted copies and the tree), so repeated evaluations do not
/// reallocate.
///
/// ```
/// use sph_gravity::{GravityField, GravityParams, TreeGravity};
/// use sph_tree::{compute_keys, BoundingBox, Curve, KeySorter, Octree};
///
/// // Particles already sorted along the Hilbert curve, with a tree over them.
/// let n = 500;
/// let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.618).fract()).collect();
/// let y: Vec<f64> = (0..n).map(|i| (i as f64 * 0.414).fract()).collect();
/// let z: Vec<f64> = (0..n).map(|i| (i as f64 * 0.732).fract()).collect();
/// let bbox = BoundingBox::enclosing(&x, &y, &z).unwrap();
/// let mut keys = Vec::new();
/// compute_keys(&bbox, Curve::Hilbert, &x, &y, &z, &mut keys);
/// let mut perm = Vec::new();
/// KeySorter::new().sort(&keys, None, &mut perm);
/// let p = |a: &[f64]| perm.iter().map(|&k| a[k as usize]).collect::<Vec<f64>>();
/// let (x, y, z) = (p(&x), p(&y), p(&z));
/// let keys: Vec<u64> = perm.iter().map(|&k| keys[k as usize]).collect();
/// let tree = Octree::build(&keys, &x, &y, &z, 16).unwrap();
///
/// let m = vec![1.0; n];
/// let h = vec![0.01; n];
/// let mut solver = TreeGravity::new(GravityParams::default()).unwrap();
/// let mut field = GravityField::new();
/// let stats = solver.compute(&tree, &bbox, &x, &y, &z, &m, Some(&h), &mut field).unwrap();
/// assert_eq!(stats.particles, n as u64);
/// assert!(field.phi.iter().all(|&p| p < 0.0));
/// ```
#[derive(Debug, Clone)]
pub struct TreeGravity {
    params: GravityParams,
    eval: Evaluator,
    sort: SortBuffers,
    /// `softening * h`, when the scale is not 1.
    scaled_h: Vec<f64>,
}

impl TreeGravity {
    /// A solver with the given parameters (checked).
    pub fn new(params: GravityParams) -> Result<Self, GravityError> {
        params.validate()?;
        Ok(Self {
            params,
            eval: Evaluator::default(),
            sort: SortBuffers::default(),
            scaled_h: Vec::new(),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &GravityParams {
        &self.params
    }

    /// Replaces the parameters (checked; unchanged on error).
    pub fn set_params(&mut self, params: GravityParams) -> Result<(), GravityError> {
        params.validate()?;
        self.params = params;
        Ok(())
    }

    /// The node multipoles of the last evaluation (indexed by the node ids
    /// of the tree it used).
    pub fn multipoles(&self) -> &Multipoles {
        &self.eval.multipoles
    }

    /// Evaluates gravity on particles sorted in the order `tree` was built
    /// over (ascending SFC keys, as [`Octree::build`] requires), writing
    /// accelerations and potentials into `out` (resized) in that same
    /// order. `bbox` is the box the keys were computed in (the opening
    /// criterion uses the nodes' geometric cells in it); it must be open
    /// on every axis. `h`, when given, are softening lengths (`>= 0`).
    pub fn compute(
        &mut self,
        tree: &Octree,
        bbox: &BoundingBox,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        m: &[f64],
        h: Option<&[f64]>,
        out: &mut GravityField,
    ) -> Result<GravityStats, GravityError> {
        self.compute_targets(tree, bbox, x, y, z, m, h, Targets::ALL, out)
    }

    /// [`compute`](Self::compute) for the `targets` only, on a tree whose
    /// cells may be older than the positions (see [`Targets`]): the active
    /// particles form target groups of up to `group_size` consecutive ones
    /// (within spans of a few groups along the curve), each with the
    /// interaction lists of its own targets' box; only the targets'
    /// entries of `out` are written, the others are left as they were
    /// (`out` keeps its contents when its length is `x.len()`).
    #[allow(clippy::too_many_arguments)]
    pub fn compute_targets(
        &mut self,
        tree: &Octree,
        bbox: &BoundingBox,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        m: &[f64],
        h: Option<&[f64]>,
        targets: Targets<'_>,
        out: &mut GravityField,
    ) -> Result<GravityStats, GravityError> {
        check_targets(&targets, x.len())?;
        if let Some(axis) = (0..3).find(|&a| bbox.is_periodic(a)) {
            return Err(GravityError::PeriodicBox { axis });
        }
        validate(x, y, z, m, h)?;
        if tree.num_particles() != x.len() && !(x.is_empty() && tree.num_nodes() == 0) {
            return Err(GravityError::TreeMismatch {
                tree: tree.num_particles(),
                particles: x.len(),
            });
        }
        let h = scale_softening(self.params.softening, h, &mut self.scaled_h);
        Ok(self
            .eval
            .run(&self.params, tree, bbox, x, y, z, m, h, targets, out))
    }

    /// Evaluates gravity on particles in any order (no box needed: the
    /// enclosing open box is used): sorts copies along the Hilbert curve,
    /// builds a tree with leaves of at most `params.leaf_size` particles,
    /// evaluates, and writes the field into `out` (resized) in the caller's
    /// order. All buffers are kept for the next call.
    pub fn compute_unsorted(
        &mut self,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        m: &[f64],
        h: Option<&[f64]>,
        out: &mut GravityField,
    ) -> Result<GravityStats, GravityError> {
        validate(x, y, z, m, h)?;
        let n = x.len();
        let s = &mut self.sort;
        let bbox = BoundingBox::enclosing(x, y, z)?;
        compute_keys(&bbox, Curve::Hilbert, x, y, z, &mut s.keys);
        KeySorter::new().sort(&s.keys, None, &mut s.perm);
        apply_permutation(&s.perm, &mut s.keys, &mut s.scratch_keys);
        let perm = &s.perm;
        let gather = |src: &[f64], dst: &mut Vec<f64>| {
            dst.resize(n, 0.0);
            dst.par_iter_mut()
                .zip(perm.par_iter())
                .for_each(|(d, &p)| *d = src[p as usize]);
        };
        gather(x, &mut s.x);
        gather(y, &mut s.y);
        gather(z, &mut s.z);
        gather(m, &mut s.m);
        if let Some(h) = h {
            gather(h, &mut s.h);
        }
        s.tree
            .rebuild(&s.keys, &s.x, &s.y, &s.z, self.params.leaf_size)?;
        if h.is_some() && self.params.softening != 1.0 {
            let scale = self.params.softening;
            s.h.iter_mut().for_each(|v| *v *= scale);
        }
        let hs = h.map(|_| s.h.as_slice());
        let stats = self.eval.run(
            &self.params,
            &s.tree,
            &bbox,
            &s.x,
            &s.y,
            &s.z,
            &s.m,
            hs,
            Targets::ALL,
            &mut s.field,
        );
        // Back to the caller's order through the inverse permutation (a
        // parallel gather rather than a scatter).
        s.inv.resize(n, 0);
        for (k, &p) in s.perm.iter().enumerate() {
            s.inv[p as usize] = k as u32;
        }
        out.resize(n);
        let inv = &s.inv;
        let f = &s.field;
        (&mut out.ax, &mut out.ay, &mut out.az, &mut out.phi)
            .into_par_iter()
            .zip(inv.par_iter())
            .for_each(|((ax, ay, az, phi), &k)| {
                let k = k as usize;
                *ax = f.ax[k];
                *ay = f.ay[k];
                *az = f.az[k];
                *phi = f.phi[k];
            });
        Ok(stats)
    }
}

/// Target flags of the right length and a usable drift bound.
pub(crate) fn check_targets(targets: &Targets<'_>, n: usize) -> Result<(), GravityError> {
    if let Some(a) = targets.active {
        if a.len() != n {
            return Err(GravityError::TargetMismatch {
                flags: a.len(),
                particles: n,
            });
        }
    }
    if !(targets.drift >= 0.0 && targets.drift.is_finite()) {
        return Err(GravityError::InvalidDrift(targets.drift));
    }
    Ok(())
}

/// The vector-MAC radius `l / theta + s` of a node: `l` the size of its
/// geometric SFC cell (the level's cell holding the centre of its tight
/// box), `s` the distance from that cell's centre to the expansion centre.
/// When the particles have `drifted` since the keys were computed, `l` is
/// the side of the smallest cube about the cell's centre that holds both
/// the cell and the node's (refitted) tight box: the bound the cell gave
/// on where the node's particles lie, made good again.
pub(crate) fn mac_radius(
    tree: &Octree,
    node: NodeId,
    com: [f64; 3],
    bbox: &BoundingBox,
    inv_theta: f64,
    drifted: bool,
) -> f64 {
    let (blo, blen) = (bbox.lo(), bbox.lengths());
    let (lo, hi) = tree.node_box(node);
    let cells = f64::from(1u32 << tree.level(node));
    let mut l = 0.0f64;
    let mut s2 = 0.0;
    for d in 0..3 {
        let size = blen[d] / cells;
        let mid = 0.5 * (lo[d] + hi[d]);
        let idx = ((mid - blo[d]) / size).floor().clamp(0.0, cells - 1.0);
        let centre = blo[d] + (idx + 0.5) * size;
        l = l.max(size);
        if drifted {
            l = l.max(2.0 * (lo[d] - centre).abs().max((hi[d] - centre).abs()));
        }
        let off = com[d] - centre;
        s2 += off * off;
    }
    l * inv_theta + s2.sqrt()
}

/// `h` scaled by the softening factor (into `buf`), or `h` itself for 1.
pub(crate) fn scale_softening<'a>(
    scale: f64,
    h: Option<&'a [f64]>,
    buf: &'a mut Vec<f64>,
) -> Option<&'a [f64]> {
    match h {
        Some(h) if scale != 1.0 => {
            buf.clear();
            buf.extend(h.iter().map(|v| v * scale));
            Some(buf.as_slice())
        }
        other => other,
    }
}

/// The largest of `v` and 0 (0 for an empty slice): the largest
/// smoothing length of a node or group.
pub(crate) fn max_of(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |a: f64, &b| a.max(b))
}

/// Squared distance from point `p` to the box `[lo, hi]` (zero inside).
#[inline(always)]
pub(crate) fn dist2_point_box(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> f64 {
    let mut d2 = 0.0;
    for k in 0..3 {
        let gap = (lo[k] - p[k]).max(p[k] - hi[k]).max(0.0);
        d2 += gap * gap;
    }
    d2
}

/// Per-thread interaction lists of one target group.
#[derive(Debug, Default)]
struct Lists {
    m2p: Vec<NodeId>,
    p2p: Vec<NodeId>,
    /// A partly active group's active targets, gathered: their offsets in
    /// the group, positions (and softening), accumulators, and each
    /// group offset's place among them (`usize::MAX`: inactive).
    active: Vec<usize>,
    place: Vec<usize>,
    pos: [Vec<f64>; 4],
    acc: [Vec<f64>; 4],
}

impl Evaluator {
    /// Upward pass, opening radii, then the parallel loop over groups.
    /// Inputs are validated by the caller.
    #[allow(clippy::too_many_arguments)]
    fn run(
        &mut self,
        params: &GravityParams,
        tree: &Octree,
        bbox: &BoundingBox,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        m: &[f64],
        h: Option<&[f64]>,
        targets: Targets<'_>,
        out: &mut GravityField,
    ) -> GravityStats {
        let n = x.len();
        out.resize(n);
        if n == 0 {
            return GravityStats::default();
        }
        self.multipoles.compute(tree, x, y, z, m);
        match h {
            Some(h) => upward(
                tree,
                &mut self.hmax,
                |node| max_of(&h[tree.particles(node)]),
                max_of,
            ),
            None => {
                self.hmax.clear();
                self.hmax.resize(tree.num_nodes(), 0.0);
            }
        }
        let inv_theta = 1.0 / params.theta;
        let mps = self.multipoles.as_slice();
        let hmax = &self.hmax;
        self.crit.clear();
        self.crit.resize(tree.num_nodes(), NodeCrit::default());
        self.crit.par_iter_mut().enumerate().for_each(|(k, c)| {
            let com = mps[k].com;
            let mac = mac_radius(tree, k as NodeId, com, bbox, inv_theta, targets.drift > 0.0);
            *c = NodeCrit {
                com,
                mac2: mac * mac,
                hmax: hmax[k],
            };
        });

        let ctx = Ctx {
            tree,
            crit: &self.crit,
            mps,
            x,
            y,
            z,
            m,
            h,
            quad: params.order == ExpansionOrder::Quadrupole,
        };
        let gs = params.group_size;
        let g = params.g;
        // Blocks of ACTIVE_SPAN groups along the curve, in parallel; in
        // each, the active targets form groups of up to `gs` consecutive
        // ones (the fixed groups of `gs` particles when all are active).
        let span = gs.saturating_mul(ACTIVE_SPAN);
        let GravityField { ax, ay, az, phi } = out;
        (
            ax.par_chunks_mut(span),
            ay.par_chunks_mut(span),
            az.par_chunks_mut(span),
            phi.par_chunks_mut(span),
        )
            .into_par_iter()
            .enumerate()
            .map_init(Lists::default, |lists, (bi, (ax, ay, az, phi))| {
                let b0 = bi * span;
                let mut stats = GravityStats::default();
                let mut next = 0;
                while let Some(first) = (next..ax.len()).find(|&i| targets.is_active(b0 + i)) {
                    let mut end = first;
                    let mut count = 0;
                    while end < ax.len() && count < gs {
                        count += usize::from(targets.is_active(b0 + end));
                        end += 1;
                    }
                    let local = first..end;
                    // Flags only where some of the run are inactive.
                    let active = targets
                        .active
                        .filter(|_| count < end - first)
                        .map(|a| &a[b0 + first..b0 + end]);
                    stats = stats
                        + ctx.group(
                            b0 + first..b0 + end,
                            active,
                            lists,
                            &mut ax[local.clone()],
                            &mut ay[local.clone()],
                            &mut az[local.clone()],
                            &mut phi[local.clone()],
                        );
                    if g != 1.0 {
                        for i in local.filter(|&i| targets.is_active(b0 + i)) {
                            ax[i] *= g;
                            ay[i] *= g;
                            az[i] *= g;
                            phi[i] *= g;
                        }
                    }
                    next = end;
                }
                stats
            })
            .reduce(GravityStats::default, |a, b| a + b)
    }
}

/// Read-only data of one evaluation.
struct Ctx<'a> {
    tree: &'a Octree,
    crit: &'a [NodeCrit],
    mps: &'a [Multipole],
    x: &'a [f64],
    y: &'a [f64],
    z: &'a [f64],
    m: &'a [f64],
    h: Option<&'a [f64]>,
    quad: bool,
}

impl Ctx<'_> {
    /// One target group: traversal into interaction lists, then the
    /// kernels (M2P list first, then P2P, each in traversal order), into
    /// the group's output chunks (without the factor G). `active` flags
    /// `range` only where some of it is inactive: the targets are then the
    /// flagged ones, gathered, the lists are made for their box and the
    /// others' entries are left as they were.
    #[allow(clippy::too_many_arguments)]
    fn group(
        &self,
        range: Range<usize>,
        active: Option<&[bool]>,
        lists: &mut Lists,
        ax: &mut [f64],
        ay: &mut [f64],
        az: &mut [f64],
        phi: &mut [f64],
    ) -> GravityStats {
        let (tx, ty, tz) = (
            &self.x[range.clone()],
            &self.y[range.clone()],
            &self.z[range.clone()],
        );
        let nt = tx.len();
        let Lists {
            m2p,
            p2p,
            active: picked,
            place,
            pos,
            acc: gathered,
        } = lists;
        m2p.clear();
        p2p.clear();
        // Where some are inactive, the targets (group offsets) are the
        // active ones, gathered once.
        if let Some(a) = active {
            picked.clear();
            picked.extend((0..nt).filter(|&i| a[i]));
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let mut gh: f64 = 0.0;
        let mut extend = |i: usize| {
            let p = [tx[i], ty[i], tz[i]];
            for d in 0..3 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
            if let Some(h) = self.h {
                gh = gh.max(h[range.start + i]);
            }
        };
        match active {
            Some(_) => picked.iter().for_each(|&i| extend(i)),
            None => (0..nt).for_each(extend),
        }

        let tree = self.tree;
        let crit = self.crit;
        tree.traverse(
            |node| {
                let pr = tree.particles(node);
                if pr.start < range.end && range.start < pr.end {
                    return true; // holds targets: never a multipole
                }
                let c = &crit[node as usize];
                let d2 = dist2_point_box(c.com, lo, hi);
                let hs = c.hmax + gh;
                if d2 > c.mac2 && d2 > hs * hs {
                    m2p.push(node);
                    false
                } else {
                    true
                }
            },
            |leaf| p2p.push(leaf),
        );

        if active.is_some() {
            place.clear();
            place.resize(nt, usize::MAX);
            for (k, &i) in picked.iter().enumerate() {
                place[i] = k;
            }
            let th = self.h.map(|h| &h[range.clone()]);
            for (c, v) in pos.iter_mut().enumerate() {
                v.clear();
                let src = [tx, ty, tz, th.unwrap_or(tx)][c];
                v.extend(picked.iter().map(|&i| src[i]));
            }
            for v in gathered.iter_mut() {
                v.clear();
                v.resize(picked.len(), 0.0);
            }
            let [gx, gy, gz, gp] = gathered;
            let [px, py, pz, ph] = &*pos;
            let stats = self.kernels(
                (px, py, pz, ph),
                range.start,
                Some(place),
                m2p,
                p2p,
                Acc {
                    ax: gx,
                    ay: gy,
                    az: gz,
                    phi: gp,
                },
            );
            for (k, &i) in picked.iter().enumerate() {
                ax[i] = gx[k];
                ay[i] = gy[k];
                az[i] = gz[k];
                phi[i] = gp[k];
            }
            return stats;
        }
        for v in [&mut *ax, &mut *ay, &mut *az, &mut *phi] {
            v.fill(0.0);
        }
        let th = self.h.map_or(&[][..], |h| &h[range.clone()]);
        self.kernels(
            (tx, ty, tz, th),
            range.start,
            None,
            m2p,
            p2p,
            Acc { ax, ay, az, phi },
        )
    }

    /// The M2P list, then the P2P list, onto targets `t` (positions and
    /// softening) of the group starting at `t0`, into `acc`; `place` maps
    /// a group offset to its target (the identity when `None`) for the
    /// self pair.
    fn kernels(
        &self,
        (tx, ty, tz, th): (&[f64], &[f64], &[f64], &[f64]),
        t0: usize,
        place: Option<&[usize]>,
        m2p: &[NodeId],
        p2p: &[NodeId],
        acc: Acc<'_>,
    ) -> GravityStats {
        let tree = self.tree;
        let nt = tx.len();
        let range = t0..t0 + place.map_or(nt, <[usize]>::len);
        let mut stats = GravityStats {
            particles: nt as u64,
            groups: 1,
            m2p: (m2p.len() * nt) as u64,
            ..GravityStats::default()
        };
        let mut acc = acc;
        for &node in m2p.iter() {
            let mp = &self.mps[node as usize];
            if self.quad {
                m2p_group::<true>(mp, tx, ty, tz, &mut acc);
            } else {
                m2p_group::<false>(mp, tx, ty, tz, &mut acc);
            }
        }
        for &leaf in p2p.iter() {
            let sr = tree.particles(leaf);
            let (lo, hi) = (sr.start.max(range.start), sr.end.min(range.end));
            let overlap = match place {
                None => hi.saturating_sub(lo),
                Some(p) => (lo..hi).filter(|&i| p[i - t0] != usize::MAX).count(),
            };
            stats.p2p += (nt * sr.len() - overlap) as u64;
            let src = Src {
                x: &self.x[sr.clone()],
                y: &self.y[sr.clone()],
                z: &self.z[sr.clone()],
                m: &self.m[sr.clone()],
            };
            match self.h {
                Some(h) => p2p_group::<true>(
                    (tx, ty, tz, th),
                    (range.start, place),
                    &src,
                    &h[sr.clone()],
                    sr.start,
                    &mut acc,
                ),
                None => p2p_group::<false>(
                    (tx, ty, tz, &[]),
                    (range.start, place),
                    &src,
                    &[],
                    sr.start,
                    &mut acc,
                ),
            }
        }
        stats
    }
}

/// Output accumulators of one group.
struct Acc<'a> {
    ax: &'a mut [f64],
    ay: &'a mut [f64],
    az: &'a mut [f64],
    phi: &'a mut [f64],
}

/// Source particles of one leaf.
struct Src<'a> {
    x: &'a [f64],
    y: &'a [f64],
    z: &'a [f64],
    m: &'a [f64],
}

/// M2P of one node onto every particle of a group.
#[inline(always)]
fn m2p_group<const QUAD: bool>(
    mp: &Multipole,
    tx: &[f64],
    ty: &[f64],
    tz: &[f64],
    acc: &mut Acc<'_>,
) {
    let n = tx.len();
    let (ty, tz) = (&ty[..n], &tz[..n]);
    let (ax, ay, az, phi) = (
        &mut acc.ax[..n],
        &mut acc.ay[..n],
        &mut acc.az[..n],
        &mut acc.phi[..n],
    );
    for i in 0..n {
        let d = [tx[i] - mp.com[0], ty[i] - mp.com[1], tz[i] - mp.com[2]];
        let mut a = [0.0; 3];
        let mut p = 0.0;
        m2p_point::<QUAD>(mp, d, &mut p, &mut a);
        ax[i] += a[0];
        ay[i] += a[1];
        az[i] += a[2];
        phi[i] += p;
    }
}

/// P2P of one leaf's particles onto every particle of a group (global
/// index offsets `t0`, `s0` identify the self pair; `place` maps a group
/// offset to its target when the targets are a gathered subset). Sources
/// outer, targets inner, so the inner loop updates independent
/// accumulators.
#[inline(always)]
fn p2p_group<const SOFT: bool>(
    (tx, ty, tz, th): (&[f64], &[f64], &[f64], &[f64]),
    (t0, place): (usize, Option<&[usize]>),
    src: &Src<'_>,
    sh: &[f64],
    s0: usize,
    acc: &mut Acc<'_>,
) {
    let n = tx.len();
    let (ty, tz) = (&ty[..n], &tz[..n]);
    let th = if SOFT { &th[..n] } else { th };
    let (ax, ay, az, phi) = (
        &mut acc.ax[..n],
        &mut acc.ay[..n],
        &mut acc.az[..n],
        &mut acc.phi[..n],
    );
    for j in 0..src.x.len() {
        let (xj, yj, zj, mj) = (src.x[j], src.y[j], src.z[j], src.m[j]);
        let hj = if SOFT { sh[j] } else { 0.0 };
        // Target index of the self pair (>= n when the source is outside the
        // group or an inactive mate).
        let offset = (s0 + j).wrapping_sub(t0);
        let self_i = place.map_or(offset, |p| p.get(offset).copied().unwrap_or(usize::MAX));
        for i in 0..n {
            let d = [xj - tx[i], yj - ty[i], zj - tz[i]];
            let eps = if SOFT { th[i] + hj } else { 0.0 };
            let (a, p) = softened_p2p::<SOFT>(d, mj, eps, i != self_i);
            ax[i] += a[0];
            ay[i] += a[1];
            az[i] += a[2];
            phi[i] += p;
        }
    }
}
