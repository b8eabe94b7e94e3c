//! The simulation box: bounds and a boundary kind per axis.

use crate::TreeError;

/// What happens at the faces of the box along one axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Boundary {
    /// Particles may sit anywhere; the box only serves to compute keys.
    #[default]
    Open,
    /// The axis wraps around: distances use the minimum image.
    Periodic,
}

/// An axis-aligned box with a boundary kind per axis.
///
/// ```
/// use sph_tree::{BoundingBox, Boundary};
/// let b = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
/// // 0.45 and -0.45 are 0.1 apart through the periodic face.
/// let d = b.min_image([0.45 - (-0.45), 0.0, 0.0]);
/// assert!((d[0] + 0.1).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundingBox {
    lo: [f64; 3],
    hi: [f64; 3],
    boundary: [Boundary; 3],
}

impl BoundingBox {
    /// A box from its corners and boundary kinds; `lo < hi` on every axis.
    pub fn new(lo: [f64; 3], hi: [f64; 3], boundary: [Boundary; 3]) -> Result<Self, TreeError> {
        for axis in 0..3 {
            if !(lo[axis].is_finite() && hi[axis].is_finite() && lo[axis] < hi[axis]) {
                return Err(TreeError::InvalidBox {
                    axis,
                    lo: lo[axis],
                    hi: hi[axis],
                });
            }
        }
        Ok(Self { lo, hi, boundary })
    }

    /// A cube `[lo, hi]^3` with the same boundary on every axis.
    pub fn cube(lo: f64, hi: f64, boundary: Boundary) -> Result<Self, TreeError> {
        Self::new([lo; 3], [hi; 3], [boundary; 3])
    }

    /// The smallest open box holding every point, padded by a relative
    /// `1e-9` of its extent so that points on the faces get valid keys.
    pub fn enclosing(x: &[f64], y: &[f64], z: &[f64]) -> Result<Self, TreeError> {
        crate::check_lengths(x, y, z, None)?;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (axis, c) in [x, y, z].into_iter().enumerate() {
            for (i, &v) in c.iter().enumerate() {
                if !v.is_finite() {
                    return Err(TreeError::NonFinite {
                        index: i,
                        what: ["x", "y", "z"][axis],
                        value: v,
                    });
                }
                lo[axis] = lo[axis].min(v);
                hi[axis] = hi[axis].max(v);
            }
        }
        if x.is_empty() {
            return Self::cube(0.0, 1.0, Boundary::Open);
        }
        for axis in 0..3 {
            // Relative padding; the scale never vanishes, so lo < hi even
            // when every point coincides.
            let scale = (hi[axis] - lo[axis])
                .max(lo[axis].abs().max(hi[axis].abs()))
                .max(f64::MIN_POSITIVE);
            lo[axis] -= scale * 1e-9;
            hi[axis] += scale * 1e-9;
        }
        Self::new(lo, hi, [Boundary::Open; 3])
    }

    /// Lower corner.
    pub fn lo(&self) -> [f64; 3] {
        self.lo
    }

    /// Upper corner.
    pub fn hi(&self) -> [f64; 3] {
        self.hi
    }

    /// Boundary kind per axis.
    pub fn boundary(&self) -> [Boundary; 3] {
        self.boundary
    }

    /// Edge lengths.
    pub fn lengths(&self) -> [f64; 3] {
        [
            self.hi[0] - self.lo[0],
            self.hi[1] - self.lo[1],
            self.hi[2] - self.lo[2],
        ]
    }

    /// Volume of the box.
    pub fn volume(&self) -> f64 {
        let l = self.lengths();
        l[0] * l[1] * l[2]
    }

    /// Whether `axis` wraps around.
    pub fn is_periodic(&self, axis: usize) -> bool {
        self.boundary[axis] == Boundary::Periodic
    }

    /// Minimum-image form of a separation vector: each periodic component is
    /// shifted by a box length into `[-L/2, L/2]`. Assumes both points lie in
    /// the box, so that one shift suffices.
    #[inline]
    pub fn min_image(&self, mut d: [f64; 3]) -> [f64; 3] {
        for axis in 0..3 {
            if self.boundary[axis] == Boundary::Periodic {
                let l = self.hi[axis] - self.lo[axis];
                if d[axis] > 0.5 * l {
                    d[axis] -= l;
                } else if d[axis] < -0.5 * l {
                    d[axis] += l;
                }
            }
        }
        d
    }

    /// Squared minimum-image distance between two points in the box.
    #[inline]
    pub fn distance2(&self, a: [f64; 3], b: [f64; 3]) -> f64 {
        let d = self.min_image([a[0] - b[0], a[1] - b[1], a[2] - b[2]]);
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    }

    /// Maps a point back into the box along periodic axes (open axes are
    /// left alone).
    #[inline]
    pub fn wrap(&self, mut p: [f64; 3]) -> [f64; 3] {
        for axis in 0..3 {
            if self.boundary[axis] == Boundary::Periodic {
                let l = self.hi[axis] - self.lo[axis];
                if p[axis] < self.lo[axis] || p[axis] >= self.hi[axis] {
                    p[axis] -= l * ((p[axis] - self.lo[axis]) / l).floor();
                    // Rounding can land exactly on hi; keep the half-open interval.
                    if p[axis] >= self.hi[axis] {
                        p[axis] = self.lo[axis];
                    }
                }
            }
        }
        p
    }

    /// Squared minimum-image distance from point `p` to the axis-aligned box
    /// `[blo, bhi]` (zero inside). Periodic axes take the nearest image.
    #[inline]
    pub fn distance2_to_box(&self, p: [f64; 3], blo: [f64; 3], bhi: [f64; 3]) -> f64 {
        let mut d2 = 0.0;
        for axis in 0..3 {
            let centre = 0.5 * (blo[axis] + bhi[axis]);
            let half = 0.5 * (bhi[axis] - blo[axis]);
            let mut dx = p[axis] - centre;
            if self.boundary[axis] == Boundary::Periodic {
                let l = self.hi[axis] - self.lo[axis];
                dx -= l * (dx / l).round();
            }
            let gap = dx.abs() - half;
            if gap > 0.0 {
                d2 += gap * gap;
            }
        }
        d2
    }
}
