//! Pair separations with the minimum image on periodic axes.

use sph_tree::BoundingBox;

/// Computes `x_i - x_j` for particle pairs, folding periodic axes.
#[derive(Debug, Clone, Copy)]
pub struct Separation {
    periodic: [bool; 3],
    length: [f64; 3],
}

impl Separation {
    /// For the given box.
    pub fn new(bbox: &BoundingBox) -> Self {
        Self {
            periodic: [
                bbox.is_periodic(0),
                bbox.is_periodic(1),
                bbox.is_periodic(2),
            ],
            length: bbox.lengths(),
        }
    }

    /// `a - b` with the minimum image along periodic axes.
    #[inline(always)]
    pub fn between(&self, a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        let mut d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        for k in 0..3 {
            if self.periodic[k] {
                let l = self.length[k];
                if d[k] > 0.5 * l {
                    d[k] -= l;
                } else if d[k] < -0.5 * l {
                    d[k] += l;
                }
            }
        }
        d
    }
}
