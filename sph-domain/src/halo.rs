//! Halo discovery geometry: which particles of this rank lie within the
//! interaction radius of another rank's cells (periodic aware).

use sph_tree::BoundingBox;

/// Squared minimum-image gap between two axis-aligned boxes (zero when they
/// overlap). Periodic axes take the nearest image.
pub fn box_gap2(bbox: &BoundingBox, a: ([f64; 3], [f64; 3]), b: ([f64; 3], [f64; 3])) -> f64 {
    let lengths = bbox.lengths();
    let mut d2 = 0.0;
    for k in 0..3 {
        let ca = 0.5 * (a.0[k] + a.1[k]);
        let cb = 0.5 * (b.0[k] + b.1[k]);
        let mut d = ca - cb;
        if bbox.is_periodic(k) {
            d -= lengths[k] * (d / lengths[k]).round();
        }
        let gap = d.abs() - 0.5 * (a.1[k] - a.0[k]) - 0.5 * (b.1[k] - b.0[k]);
        if gap > 0.0 {
            d2 += gap * gap;
        }
    }
    d2
}

/// For each of `mine` (cell boxes of this rank), the indices into `remote`
/// of the cells closer than `radius`.
pub fn candidate_cells(
    bbox: &BoundingBox,
    mine: &[([f64; 3], [f64; 3])],
    remote: &[([f64; 3], [f64; 3])],
    radius: f64,
) -> Vec<Vec<u32>> {
    use rayon::prelude::*;
    let r2 = radius * radius;
    mine.par_iter()
        .map(|&a| {
            remote
                .iter()
                .enumerate()
                .filter(|(_, &b)| box_gap2(bbox, a, b) < r2)
                .map(|(j, _)| j as u32)
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use sph_tree::Boundary;

    #[test]
    fn periodic_gap_wraps() {
        let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
        let a = ([0.0, 0.0, 0.0], [0.1, 0.1, 0.1]);
        let b = ([0.85, 0.0, 0.0], [0.95, 0.1, 0.1]);
        assert!((box_gap2(&bbox, a, b) - 0.05f64.powi(2)).abs() < 1e-15);
        let open = BoundingBox::cube(0.0, 1.0, Boundary::Open).unwrap();
        assert!((box_gap2(&open, a, b) - 0.75f64.powi(2)).abs() < 1e-12);
    }
}
