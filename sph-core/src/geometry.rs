//! Pair separations with the minimum image on periodic axes.

use crate::lanes::F64s;
use sph_tree::BoundingBox;

/// Computes `x_i - x_j` for particle pairs, folding periodic axes.
#[derive(Debug, Clone, Copy)]
pub struct Separation {
    /// Half the box length on periodic axes, infinity on open ones (so
    /// the fold below never triggers there and needs no branch per axis).
    half: [f64; 3],
    /// Box length on periodic axes, 0 on open ones.
    length: [f64; 3],
}

impl Separation {
    /// For the given box.
    pub fn new(bbox: &BoundingBox) -> Self {
        let l = bbox.lengths();
        let periodic = |k: usize| bbox.is_periodic(k);
        Self {
            half: std::array::from_fn(|k| {
                if periodic(k) {
                    0.5 * l[k]
                } else {
                    f64::INFINITY
                }
            }),
            length: std::array::from_fn(|k| if periodic(k) { l[k] } else { 0.0 }),
        }
    }

    /// `d` folded into `[-L/2, L/2]` on periodic axes (compiles to selects).
    #[inline(always)]
    fn fold(&self, k: usize, d: f64) -> f64 {
        let (h, l) = (self.half[k], self.length[k]);
        if d > h {
            d - l
        } else if d < -h {
            d + l
        } else {
            d
        }
    }

    /// `a - b` with the minimum image along periodic axes.
    #[inline(always)]
    pub fn between(&self, a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|k| self.fold(k, a[k] - b[k]))
    }

    /// [`between`](Self::between) for a lane of points `a = (x, y, z)[l]`
    /// and one partner `b`, as `[dx, dy, dz]`; lane `l` equals the scalar
    /// result bit for bit.
    #[inline(always)]
    pub fn between_lanes(&self, a: [F64s; 3], b: [f64; 3]) -> [F64s; 3] {
        let axis = |k: usize| (a[k] - b[k]).fold(self.half[k], self.length[k]);
        [axis(0), axis(1), axis(2)]
    }
}
