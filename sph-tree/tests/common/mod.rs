//! Reference distances for the brute-force checks, written without
//! `BoundingBox::distance2` / `distance2_to_box` (the code under test) so
//! that a bug in the minimum image cannot pass both sides of a comparison.
//! Also included by `sph-domain/tests/domain.rs`.
#![allow(dead_code)]

use sph_tree::BoundingBox;

/// The periodic images of a box: shifts `(s_x, s_y, s_z)` with each
/// component `-L`, `0` or `+L` along a periodic axis and `0` along an open
/// one (all 27 combinations when every axis is periodic).
#[derive(Debug, Clone, Copy)]
pub struct Images {
    shifts: [[f64; 3]; 27],
    count: usize,
}

impl Images {
    /// The images of `bbox`; build once per box, the distances are then
    /// minima over `count` shifts.
    pub fn of(bbox: &BoundingBox) -> Self {
        let (lo, hi) = (bbox.lo(), bbox.hi());
        let options = |axis: usize| {
            let l = hi[axis] - lo[axis];
            if bbox.is_periodic(axis) {
                ([-l, 0.0, l], 3)
            } else {
                ([0.0; 3], 1)
            }
        };
        let ((ox, nx), (oy, ny), (oz, nz)) = (options(0), options(1), options(2));
        let mut shifts = [[0.0; 3]; 27];
        let mut count = 0;
        for &sx in &ox[..nx] {
            for &sy in &oy[..ny] {
                for &sz in &oz[..nz] {
                    shifts[count] = [sx, sy, sz];
                    count += 1;
                }
            }
        }
        Self { shifts, count }
    }

    /// Squared distance from `a` to the nearest image of `b`.
    pub fn distance2(&self, a: [f64; 3], b: [f64; 3]) -> f64 {
        self.shifts[..self.count]
            .iter()
            .map(|s| {
                let d = [0, 1, 2].map(|k| a[k] - b[k] + s[k]);
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Squared distance from `p` to the nearest image of the box
    /// `[blo, bhi]` (zero inside).
    pub fn distance2_to_box(&self, p: [f64; 3], blo: [f64; 3], bhi: [f64; 3]) -> f64 {
        self.shifts[..self.count]
            .iter()
            .map(|s| {
                let mut d2 = 0.0;
                for k in 0..3 {
                    let (lo, hi) = (blo[k] + s[k], bhi[k] + s[k]);
                    let gap = if p[k] < lo {
                        lo - p[k]
                    } else if p[k] > hi {
                        p[k] - hi
                    } else {
                        0.0
                    };
                    d2 += gap * gap;
                }
                d2
            })
            .fold(f64::INFINITY, f64::min)
    }
}
