//! Self-gravity on the octree of [`sph_tree`]: Cartesian multipoles up to
//! the quadrupole (P2M on the leaves, M2M upwards), a Barnes-Hut traversal
//! with the vector opening criterion ("vector MAC"), softened
//! particle-particle (P2P) interactions, and an exact direct-sum reference
//! ([`direct`]).
//!
//! # Quick start (N-body, positions and masses only)
//!
//! [`compute_gravity`] takes particles in any order, sorts them along the
//! Hilbert curve internally, builds the tree and returns the accelerations
//! and potentials in the caller's order:
//!
//! ```
//! use sph_gravity::{compute_gravity, direct, GravityField, GravityParams};
//!
//! // 2000 particles on a deterministic pseudo-random cloud in the unit cube.
//! let n = 2000;
//! let mut s = 12345u64;
//! let mut rnd = || {
//!     s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
//!     (s >> 11) as f64 / (1u64 << 53) as f64
//! };
//! let (mut x, mut y, mut z) = (Vec::new(), Vec::new(), Vec::new());
//! for _ in 0..n {
//!     x.push(rnd());
//!     y.push(rnd());
//!     z.push(rnd());
//! }
//! let m = vec![1.0 / n as f64; n];
//!
//! // Tree gravity: theta = 0.5, quadrupoles, G = 1, no softening.
//! let (field, stats) = compute_gravity(&x, &y, &z, &m, None, &GravityParams::default()).unwrap();
//! assert_eq!(field.len(), n);
//! assert!(stats.interactions_per_particle() < n as f64);
//!
//! // Compare with the exact O(N^2) sum.
//! let mut exact = GravityField::new();
//! direct::direct_sum(&x, &y, &z, &m, None, 1.0, &mut exact).unwrap();
//! for i in 0..n {
//!     let err = (0..3).map(|k| (field.acc(i)[k] - exact.acc(i)[k]).powi(2)).sum::<f64>().sqrt();
//!     let norm = exact.acc(i).iter().map(|a| a * a).sum::<f64>().sqrt();
//!     assert!(err < 1e-2 * norm);
//! }
//! let e_tree = field.potential_energy(&m);
//! let e_exact = exact.potential_energy(&m);
//! assert!((e_tree - e_exact).abs() < 1e-3 * e_exact.abs());
//! ```
//!
//! Codes that already keep their particles sorted along a space-filling
//! curve and hold an [`Octree`](sph_tree::Octree) over them (like the SPH
//! solver) call [`TreeGravity::compute`] with that tree instead.
//!
//! # Physics and numerics
//!
//! * **Multipoles** ([`Multipole`]): mass, centre of mass and the
//!   *traceless* Cartesian quadrupole `Q_ab = sum m (3 d_a d_b - |d|^2
//!   delta_ab)` about each node's centre of mass (the dipole vanishes
//!   there). P2M on leaves, M2M by the parallel-axis shift.
//! * **Opening criterion** (vector MAC, as in SPH-EXA): a node whose
//!   geometric SFC cell (the octree cell of its level in the box the keys
//!   were computed in) has largest edge `l` and centre `c`, and whose
//!   centre of mass is `com`, is used as a multipole for a target group
//!   when the distance from the group's tight bounding box to `com` exceeds
//!   `l / theta + s`, `s = |com - c|`. (The geometric cell rather than the
//!   tight particle box: slightly more interactions, measurably smaller
//!   errors.) Two more conditions keep the expansion honest: a node
//!   that contains particles of the target group is always opened, and a
//!   node is only accepted when that distance also exceeds
//!   `h_max(node) + h_max(group)`, so every pair it stands for is beyond its
//!   softening length (irrelevant without softening).
//! * **Targets** are groups of [`GravityParams::group_size`] consecutive
//!   particles of the sorted order; one traversal builds the interaction
//!   lists of a whole group. With some particles active ([`Targets`]), a
//!   group is up to that many consecutive active ones.
//! * **Softening** (as in SPH-EXA): `r_eff^2 = max(r^2, (h_i + h_j)^2)` for
//!   particle pairs, so `a = G m (x_j - x_i) / r_eff^3`, and the matching
//!   potential, `-G m / r` outside `h_i + h_j` and that of a uniform sphere
//!   of radius `eps = h_i + h_j` inside, `-G m (3 eps^2 - r^2) / (2 eps^3)`
//!   (SPH-EXA keeps `-G m / r_eff`, whose gradient is not the force; ours
//!   is, so total energy including `sum m phi / 2` is conserved). Without
//!   `h`, plain Newtonian gravity.
//!   The self pair `i == j` is always skipped, and so is a pair of
//!   coincident particles with zero softening (`r_eff = 0`).
//! * **Determinism**: each particle's contributions are summed in a fixed
//!   order (the traversal order of its group), so the result is independent
//!   of the number of threads.
//! * **Boundaries**: open only; a periodic box is refused with
//!   [`GravityError::PeriodicBox`] (periodic gravity needs Ewald sums).

#![forbid(unsafe_code)]

pub mod direct;
pub mod distributed;
mod error;
pub mod multipole;
mod pair;
mod traversal;

pub use distributed::{Decomposition, DistributedGravity};
pub use error::GravityError;
pub use multipole::{ExpansionOrder, Multipole, Multipoles};
pub use traversal::TreeGravity;

/// Which target particles an evaluation writes, and how far any particle
/// may have moved since the tree's cells (its keys) were made.
///
/// Codes with individual time steps evaluate gravity only on the
/// particles that start a new step, on a tree whose cells stay those of
/// the last rebuild while the particles drift (its boxes refitted to the
/// current positions). With a drift, a node's size in the opening
/// criterion is that of the cube about its geometric cell's centre
/// holding the cell and the node's tight box (its own particles' drift,
/// not the largest anywhere), and a distributed evaluation demands
/// `drift` more distance from the receiver's domain. Only the targets'
/// entries are written, every other entry is left as it was: the targets
/// form groups of up to `group_size` consecutive active particles within
/// spans of 8 groups along the curve, and each group's lists are made for
/// the box of its targets, so the kernels' loops over targets stay full.
/// With every particle active these are the groups of a full evaluation,
/// bit for bit.
///
/// ```
/// use sph_gravity::Targets;
/// let all = Targets::ALL;
/// assert!(all.active.is_none() && all.drift == 0.0);
/// let flags = [true, false, false];
/// let some = Targets { active: Some(&flags), drift: 1e-3 };
/// assert_eq!(some.count(3), 1);
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Targets<'a> {
    /// One flag per particle (in the tree's order); `None`: all.
    pub active: Option<&'a [bool]>,
    /// The largest distance any particle has moved since the keys were
    /// computed (`>= 0`, finite).
    pub drift: f64,
}

impl Targets<'_> {
    /// Every particle, on a tree built at the current positions.
    pub const ALL: Targets<'static> = Targets {
        active: None,
        drift: 0.0,
    };

    /// Whether particle `i` is a target.
    #[inline]
    pub fn is_active(&self, i: usize) -> bool {
        self.active.is_none_or(|a| a[i])
    }

    /// The number of targets among `n` particles.
    pub fn count(&self, n: usize) -> usize {
        self.active.map_or(n, |a| a.iter().filter(|&&b| b).count())
    }
}

/// Parameters of the tree evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GravityParams {
    /// Opening angle of the vector MAC (finite, `> 0`); smaller is more
    /// accurate and slower. Default 0.5.
    pub theta: f64,
    /// Gravitational constant. Default 1.
    pub g: f64,
    /// Multipole order of accepted nodes. Default quadrupole.
    pub order: ExpansionOrder,
    /// Particles per target group (consecutive in the sorted order).
    /// Default 32 (fewer interactions than 64: the opening test sees a
    /// tighter box).
    pub group_size: usize,
    /// Leaf size (bucket) of the tree that [`compute_gravity`] and
    /// [`TreeGravity::compute_unsorted`] build; ignored when the caller
    /// passes its own tree. Default 32.
    pub leaf_size: usize,
    /// Scale of the pair softening length: pairs are softened within
    /// `softening * (h_i + h_j)`. Default 1 (SPH-EXA's choice); smaller
    /// values follow Newtonian gravity closer and depend less on h.
    pub softening: f64,
}

impl Default for GravityParams {
    fn default() -> Self {
        Self {
            theta: 0.5,
            g: 1.0,
            order: ExpansionOrder::Quadrupole,
            group_size: 32,
            leaf_size: 32,
            softening: 1.0,
        }
    }
}

impl GravityParams {
    /// Checks every parameter, naming the first bad one.
    pub fn validate(&self) -> Result<(), GravityError> {
        if !(self.theta.is_finite() && self.theta > 0.0) {
            return Err(GravityError::InvalidTheta(self.theta));
        }
        if !self.g.is_finite() {
            return Err(GravityError::InvalidG(self.g));
        }
        if !(self.softening.is_finite() && self.softening >= 0.0) {
            return Err(GravityError::InvalidSoftening(self.softening));
        }
        if self.group_size == 0 {
            return Err(GravityError::InvalidGroupSize(self.group_size));
        }
        if self.leaf_size == 0 {
            return Err(sph_tree::TreeError::InvalidBucketSize(self.leaf_size).into());
        }
        Ok(())
    }
}

/// Accelerations and potentials per particle (structure of arrays).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GravityField {
    /// Acceleration, x component.
    pub ax: Vec<f64>,
    /// Acceleration, y component.
    pub ay: Vec<f64>,
    /// Acceleration, z component.
    pub az: Vec<f64>,
    /// Gravitational potential (per unit mass; negative).
    pub phi: Vec<f64>,
}

impl GravityField {
    /// An empty field.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.ax.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.ax.is_empty()
    }

    /// Resizes every array to `n` (new entries are zero).
    pub fn resize(&mut self, n: usize) {
        for v in [&mut self.ax, &mut self.ay, &mut self.az, &mut self.phi] {
            v.resize(n, 0.0);
        }
    }

    /// Acceleration of particle `i`.
    #[inline]
    pub fn acc(&self, i: usize) -> [f64; 3] {
        [self.ax[i], self.ay[i], self.az[i]]
    }

    /// Total potential energy `0.5 sum_i m_i phi_i`.
    ///
    /// # Panics
    /// If `m` has a different length than the field.
    pub fn potential_energy(&self, m: &[f64]) -> f64 {
        assert_eq!(m.len(), self.len(), "masses and field differ in length");
        0.5 * m.iter().zip(&self.phi).map(|(m, p)| m * p).sum::<f64>()
    }
}

/// Interaction counts of one tree evaluation.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct GravityStats {
    /// Particle-particle interactions (ordered pairs, self pairs excluded).
    pub p2p: u64,
    /// Multipole-to-particle interactions.
    pub m2p: u64,
    /// Number of target particles.
    pub particles: u64,
    /// Number of target groups (one traversal each).
    pub groups: u64,
}

impl GravityStats {
    /// Interactions of both kinds per particle (0 without particles).
    pub fn interactions_per_particle(&self) -> f64 {
        if self.particles == 0 {
            0.0
        } else {
            (self.p2p + self.m2p) as f64 / self.particles as f64
        }
    }

    /// P2P interactions per particle.
    pub fn p2p_per_particle(&self) -> f64 {
        self.p2p as f64 / self.particles.max(1) as f64
    }

    /// M2P interactions per particle.
    pub fn m2p_per_particle(&self) -> f64 {
        self.m2p as f64 / self.particles.max(1) as f64
    }
}

impl std::ops::Add for GravityStats {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            p2p: self.p2p + o.p2p,
            m2p: self.m2p + o.m2p,
            particles: self.particles + o.particles,
            groups: self.groups + o.groups,
        }
    }
}

/// Tree gravity for particles in any order: sorts them along the Hilbert
/// curve, builds an octree with leaves of at most `params.leaf_size`
/// particles, evaluates and returns the field in the caller's order.
/// `h` (optional) are the softening lengths (see the crate docs for the
/// softening rule). For repeated calls, keep a [`TreeGravity`] and use
/// [`TreeGravity::compute_unsorted`], which reuses its buffers.
pub fn compute_gravity(
    x: &[f64],
    y: &[f64],
    z: &[f64],
    m: &[f64],
    h: Option<&[f64]>,
    params: &GravityParams,
) -> Result<(GravityField, GravityStats), GravityError> {
    let mut solver = TreeGravity::new(*params)?;
    let mut out = GravityField::new();
    let stats = solver.compute_unsorted(x, y, z, m, h, &mut out)?;
    Ok((out, stats))
}

/// Checks lengths and finiteness of the inputs (and `h >= 0`).
pub(crate) fn validate(
    x: &[f64],
    y: &[f64],
    z: &[f64],
    m: &[f64],
    h: Option<&[f64]>,
) -> Result<(), GravityError> {
    let n = x.len();
    let mut slices: Vec<(&'static str, &[f64])> = vec![("x", x), ("y", y), ("z", z), ("m", m)];
    if let Some(h) = h {
        slices.push(("h", h));
    }
    for &(what, s) in &slices {
        if s.len() != n {
            return Err(GravityError::LengthMismatch {
                what,
                len: s.len(),
                expected: n,
            });
        }
    }
    // One branch-free pass per array finds whether anything is wrong (a
    // block-step run calls this every sub-step for a few active
    // particles); the search for the first bad index runs only then.
    for &(what, s) in &slices {
        if !all_finite(s) {
            if let Some(index) = s.iter().position(|v| !v.is_finite()) {
                return Err(GravityError::NonFinite {
                    index,
                    what,
                    value: s[index],
                });
            }
        }
    }
    if let Some(h) = h {
        if h.iter().copied().fold(0.0, f64::min) < 0.0 {
            if let Some(index) = h.iter().position(|&v| v < 0.0) {
                return Err(GravityError::NegativeSoftening {
                    index,
                    value: h[index],
                });
            }
        }
    }
    Ok(())
}

/// Whether every value is finite: `0 * v` is (signed) zero for a finite
/// `v` and NaN otherwise, and a NaN survives the sum. Eight partial sums
/// let the loop vectorise.
fn all_finite(s: &[f64]) -> bool {
    let mut acc = [0.0f64; 8];
    let chunks = s.chunks_exact(8);
    let rest = chunks.remainder();
    for c in chunks {
        for k in 0..8 {
            acc[k] += c[k] * 0.0;
        }
    }
    let tail: f64 = rest.iter().map(|v| v * 0.0).sum();
    acc.iter().sum::<f64>() + tail == 0.0
}
