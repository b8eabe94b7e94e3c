//! The fixed-point triangular-shaped-cloud deposit of `m` and `m v`.

use super::SpectrumError;

/// Fraction bits of the largest particle term for sets of up to 1,242,756
/// particles (see [`DepositScale`]).
pub const FRACTION_BITS: u32 = 44;

/// The fewest fraction bits [`DepositScale::new`] accepts for large sets.
pub const MIN_FRACTION_BITS: u32 = 32;

/// Smallest and largest allowed grids (`N_g` per side): 4 gives shells
/// up to 2; 512 keeps the grids below about 8 GB.
const N_G_MIN: usize = 4;
const N_G_MAX: usize = 512;

/// The nearest node among the 27 cells `9 a + 3 b + c` of a deposit.
const CENTRE: usize = 13;

/// Bound on one particle's term in one cell, in units of `2^-bits` of the
/// largest term (see [`DepositScale`]).
fn cell_term_bound(bits: u32) -> u64 {
    27 * (1u64 << (bits - 6)) + 16
}

/// The largest particle count whose sums fit in `i64` at `bits`.
fn max_particles(bits: u32) -> u64 {
    i64::MAX as u64 / cell_term_bound(bits)
}

/// Largest `m` and largest `|m v_i|` of a particle set; reduce with `max`
/// over ranks before building a [`DepositScale`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Extremes {
    /// Largest particle mass.
    pub mass: f64,
    /// Largest `|m v_i|` over the particles and the three axes.
    pub momentum: f64,
}

impl Extremes {
    /// The extremes of the local particles (the products `m v_i` are the
    /// ones [`SpectrumGrid::deposit`] forms, bit for bit). Refuses
    /// non-finite values and negative masses.
    pub fn local(m: &[f64], vx: &[f64], vy: &[f64], vz: &[f64]) -> Result<Self, SpectrumError> {
        check_lengths(m.len(), &[("vx", vx), ("vy", vy), ("vz", vz)])?;
        let mut e = Extremes::default();
        for i in 0..m.len() {
            let q = terms(i, m[i], [vx[i], vy[i], vz[i]])?;
            e.mass = e.mass.max(q[0]);
            for p in &q[1..] {
                e.momentum = e.momentum.max(p.abs());
            }
        }
        Ok(e)
    }

    /// The larger of each (the reduction of two ranks' extremes).
    pub fn max(self, other: Extremes) -> Extremes {
        Extremes {
            mass: self.mass.max(other.mass),
            momentum: self.momentum.max(other.momentum),
        }
    }
}

/// The fixed-point scales of a deposit: built once from the global
/// [`Extremes`] and particle count, the same on every rank.
///
/// # Fixed point and headroom
/// Each particle's four terms `q` (`m`, `m vx`, `m vy`, `m vz`) are
/// multiplied by a power of two `s` chosen from the global maximum of `|q|`
/// so that the largest lies in `[2^(b-1), 2^b)`, `b` = [`FRACTION_BITS`]
/// (44: each term rounded to `2^-44 = 5.7e-14` of the largest, errors far
/// below what a spectrum of SPH particles resolves). `q s` is exact, and
/// `Q = round(q s)` is split over the 27 cells: 26 cells get
/// `round(w q s)` and the nearest node the remainder, so every particle
/// adds exactly `Q` to each total, whatever the cells.
///
/// A 1-D TSC weight is at most 3/4, so a cell gets at most `27/64` of a
/// particle: `|term| <= 27 * 2^(b-6) + 14` (the remainder carries at most
/// 27 half-unit roundings; we allow 16). With `N` particles in all, every
/// partial sum of one cell (in any order, on any rank) is bounded by
/// `N (27 * 2^(b-6) + 16)`, which must stay below `2^63`: at `b = 44` that
/// is `N <= 1,242,756` (107^3). Larger sets get fewer fraction bits, one per
/// doubling of `N` (`b = 32` still allows 5.09e9 particles, resolved to
/// `2^-32 = 2.3e-10` of the largest term); beyond that [`DepositScale::new`]
/// refuses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepositScale {
    extremes: Extremes,
    particles: u64,
    bits: u32,
    /// Multipliers (powers of two) of the mass and momentum terms.
    mass: f64,
    momentum: f64,
}

impl DepositScale {
    /// Scales for `particles` particles in all with the given (global)
    /// extremes; see above for the headroom.
    pub fn new(extremes: Extremes, particles: u64) -> Result<Self, SpectrumError> {
        let mut bits = FRACTION_BITS;
        while particles > max_particles(bits) {
            if bits == MIN_FRACTION_BITS {
                return Err(SpectrumError::TooManyParticles {
                    particles,
                    max: max_particles(bits),
                    bits,
                });
            }
            bits -= 1;
        }
        Ok(DepositScale {
            extremes,
            particles,
            bits,
            mass: power_of_two_scale("mass", extremes.mass, bits)?,
            momentum: power_of_two_scale("momentum", extremes.momentum, bits)?,
        })
    }

    /// Fraction bits of the largest term (44 unless the set is large).
    pub fn bits(&self) -> u32 {
        self.bits
    }

    /// The particle count the scale was built for.
    pub fn particles(&self) -> u64 {
        self.particles
    }

    /// The extremes the scale was built from.
    pub fn extremes(&self) -> Extremes {
        self.extremes
    }

    /// Fixed-point units per unit of mass.
    pub fn mass_scale(&self) -> f64 {
        self.mass
    }

    /// Fixed-point units per unit of momentum.
    pub fn momentum_scale(&self) -> f64 {
        self.momentum
    }
}

/// `2^(bits - e - 1)` for `max` in `[2^e, 2^(e+1))`, so `max` maps into
/// `[2^(bits-1), 2^bits)`; `2^bits` for `max = 0` (every term is 0).
fn power_of_two_scale(what: &'static str, max: f64, bits: u32) -> Result<f64, SpectrumError> {
    if max == 0.0 {
        return Ok(2f64.powi(bits as i32));
    }
    // Below 2^-900 the scale would pass 2^944; no data of ours comes near.
    if !(max.is_finite() && max >= 2f64.powi(-900)) {
        return Err(SpectrumError::BadExtreme { what, value: max });
    }
    let e = ((max.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    Ok(2f64.powi(bits as i32 - e - 1))
}

/// Mass and momentum of `N_g^3` cells as fixed-point integers; see
/// [`crate::spectrum`] for its use across ranks.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectrumGrid {
    n: usize,
    min: [f64; 3],
    length: f64,
    scale: DepositScale,
    /// `[mass | m vx | m vy | m vz]`, `N_g^3` cells each, cell `(i, j, k)`
    /// at `(i N_g + j) N_g + k`, then the particle count.
    data: Vec<i64>,
}

impl SpectrumGrid {
    /// An empty grid of `n^3` cells over the periodic cube
    /// `[min, min + length)^3`, node `(i, j, k)` at `min + (i, j, k) length / n`.
    pub fn new(
        n: usize,
        min: [f64; 3],
        length: f64,
        scale: DepositScale,
    ) -> Result<Self, SpectrumError> {
        if !(N_G_MIN..=N_G_MAX).contains(&n) {
            return Err(SpectrumError::GridSize {
                n,
                min: N_G_MIN,
                max: N_G_MAX,
            });
        }
        if !(min.iter().all(|v| v.is_finite()) && length.is_finite() && length > 0.0) {
            return Err(SpectrumError::BadBox { min, length });
        }
        Ok(SpectrumGrid {
            n,
            min,
            length,
            scale,
            data: vec![0; 4 * n * n * n + 1],
        })
    }

    /// Cells per side.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The box's lower corner.
    pub fn min(&self) -> [f64; 3] {
        self.min
    }

    /// The box's side.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// The fixed-point scales.
    pub fn scale(&self) -> DepositScale {
        self.scale
    }

    /// Particles deposited so far (summed over ranks after an all-reduce).
    pub fn particles(&self) -> u64 {
        self.data[4 * self.cells()] as u64
    }

    /// The mass field (0), or the momentum along axis `f - 1` (1-3), in
    /// fixed-point units of the scale.
    pub fn field(&self, f: usize) -> &[i64] {
        let c = self.cells();
        &self.data[f * c..(f + 1) * c]
    }

    /// The total deposited mass: the exact integer sum, rounded once.
    pub fn total_mass(&self) -> f64 {
        let sum: i128 = self.field(0).iter().map(|&v| i128::from(v)).sum();
        sum as f64 / self.scale.mass
    }

    /// All integers of the grid (the four fields, then the particle
    /// count), for an element-wise sum over ranks.
    pub fn integers(&self) -> &[i64] {
        &self.data
    }

    /// All integers of the grid, writable: sum them over the ranks (e.g.
    /// `comm.all_reduce(grid.integers_mut(), ReduceOp::Sum)`) to get the grid
    /// of all particles, bit-identical to a serial deposit. The scale must
    /// have been built from the global extremes and count.
    pub fn integers_mut(&mut self) -> &mut [i64] {
        &mut self.data
    }

    /// Adds another grid's integers (the grids of two particle subsets
    /// give the grid of their union). Refuses a different size, box or
    /// scale, or a count above the scale's.
    pub fn add(&mut self, other: &SpectrumGrid) -> Result<(), SpectrumError> {
        if self.n != other.n {
            return Err(SpectrumError::Mismatch("cells per side"));
        }
        if self.min != other.min || self.length != other.length {
            return Err(SpectrumError::Mismatch("box"));
        }
        if self.scale != other.scale {
            return Err(SpectrumError::Mismatch("deposit scale"));
        }
        self.check_count(other.particles())?;
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            *a += *b;
        }
        Ok(())
    }

    /// Deposits particles at `(x, y, z)` (wrapped into the periodic box)
    /// with masses `m` and velocities `v` by TSC: 27 cells each, the
    /// weights `(1/2 - d)^2 / 2`, `3/4 - d^2`, `(1/2 + d)^2 / 2` per axis
    /// for a particle at `d` cells from its nearest node. Any order or
    /// grouping of the same particles gives the same integers. On an error
    /// (mismatched slices, non-finite values, negative mass, a term above
    /// the scale's extremes, more particles than the scale's count) the
    /// grid is unchanged.
    pub fn deposit(
        &mut self,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        m: &[f64],
        vx: &[f64],
        vy: &[f64],
        vz: &[f64],
    ) -> Result<(), SpectrumError> {
        let np = x.len();
        check_lengths(
            np,
            &[
                ("y", y),
                ("z", z),
                ("m", m),
                ("vx", vx),
                ("vy", vy),
                ("vz", vz),
            ],
        )?;
        self.check_count(np as u64)?;
        // Validate everything first so that an error leaves the grid as it was.
        for i in 0..np {
            self.check_particle(i, [x[i], y[i], z[i]], m[i], [vx[i], vy[i], vz[i]])?;
        }
        let n = self.n;
        let cells = self.cells();
        let inv_h = n as f64 / self.length;
        let scales = [
            self.scale.mass,
            self.scale.momentum,
            self.scale.momentum,
            self.scale.momentum,
        ];
        for i in 0..np {
            let q = terms(i, m[i], [vx[i], vy[i], vz[i]])?;
            let (ix, wx) = axis_weights((x[i] - self.min[0]) * inv_h, n);
            let (iy, wy) = axis_weights((y[i] - self.min[1]) * inv_h, n);
            let (iz, wz) = axis_weights((z[i] - self.min[2]) * inv_h, n);
            // The 27 cells and weights, the nearest node at CENTRE.
            let mut cell = [0usize; 27];
            let mut w = [0.0; 27];
            for a in 0..3 {
                for b in 0..3 {
                    for c in 0..3 {
                        cell[9 * a + 3 * b + c] = (ix[a] * n + iy[b]) * n + iz[c];
                        w[9 * a + 3 * b + c] = wx[a] * wy[b] * wz[c];
                    }
                }
            }
            for f in 0..4 {
                // Exact: the scale is a power of two.
                let qs = q[f] * scales[f];
                let field = &mut self.data[f * cells..(f + 1) * cells];
                let mut rest = qs.round() as i64;
                for j in (0..27).filter(|&j| j != CENTRE) {
                    let t = (w[j] * qs).round() as i64;
                    field[cell[j]] += t;
                    rest -= t;
                }
                // The nearest node takes the remainder: each particle adds
                // exactly round(q s) to the field's total.
                field[cell[CENTRE]] += rest;
            }
        }
        self.data[4 * cells] += np as i64;
        Ok(())
    }

    fn cells(&self) -> usize {
        self.n * self.n * self.n
    }

    fn check_count(&self, more: u64) -> Result<(), SpectrumError> {
        let total = self.particles().saturating_add(more);
        if total > self.scale.particles {
            return Err(SpectrumError::TooManyParticles {
                particles: total,
                max: self.scale.particles,
                bits: self.scale.bits,
            });
        }
        Ok(())
    }

    fn check_particle(
        &self,
        i: usize,
        pos: [f64; 3],
        m: f64,
        v: [f64; 3],
    ) -> Result<(), SpectrumError> {
        for (what, value) in ["x", "y", "z"].into_iter().zip(pos) {
            if !value.is_finite() {
                return Err(SpectrumError::BadValue {
                    what,
                    index: i,
                    value,
                    why: "positions must be finite",
                });
            }
        }
        let q = terms(i, m, v)?;
        let ext = self.scale.extremes;
        if q[0] > ext.mass {
            return Err(SpectrumError::AboveScale {
                what: "m",
                index: i,
                value: q[0],
                max: ext.mass,
            });
        }
        for (what, p) in ["m vx", "m vy", "m vz"].into_iter().zip(&q[1..]) {
            if p.abs() > ext.momentum {
                return Err(SpectrumError::AboveScale {
                    what,
                    index: i,
                    value: p.abs(),
                    max: ext.momentum,
                });
            }
        }
        Ok(())
    }
}

/// The four deposited terms `m, m vx, m vy, m vz` of particle `i`, checked.
fn terms(i: usize, m: f64, v: [f64; 3]) -> Result<[f64; 4], SpectrumError> {
    if !(m.is_finite() && m >= 0.0) {
        return Err(SpectrumError::BadValue {
            what: "m",
            index: i,
            value: m,
            why: "masses must be finite and >= 0",
        });
    }
    let q = [m, m * v[0], m * v[1], m * v[2]];
    for (what, p) in ["m vx", "m vy", "m vz"].into_iter().zip(&q[1..]) {
        if !p.is_finite() {
            return Err(SpectrumError::BadValue {
                what,
                index: i,
                value: *p,
                why: "momenta must be finite",
            });
        }
    }
    Ok(q)
}

/// The three cells (periodic) and TSC weights along one axis for a
/// particle at `g` cells from node 0.
fn axis_weights(g: f64, n: usize) -> ([usize; 3], [f64; 3]) {
    let nearest = g.round();
    let d = g - nearest;
    let c = (nearest as i64).rem_euclid(n as i64) as usize;
    (
        [(c + n - 1) % n, c, (c + 1) % n],
        [
            0.5 * (0.5 - d) * (0.5 - d),
            0.75 - d * d,
            0.5 * (0.5 + d) * (0.5 + d),
        ],
    )
}

/// Refuses per-particle slices whose length is not `expected`.
pub(super) fn check_lengths(
    expected: usize,
    slices: &[(&'static str, &[f64])],
) -> Result<(), SpectrumError> {
    for &(what, s) in slices {
        if s.len() != expected {
            return Err(SpectrumError::Length {
                what,
                len: s.len(),
                expected,
            });
        }
    }
    Ok(())
}
