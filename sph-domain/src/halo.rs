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
/// of the cells closer than `radius`, ascending.
///
/// The remote cells are first binned into a uniform grid of cells about
/// `radius` wide (each remote cell in every grid cell its `radius`-grown
/// box touches), so each of `mine` tests only the remote cells binned
/// where it lies instead of all of them; the exact test ([`box_gap2`])
/// decides as before.
pub fn candidate_cells(
    bbox: &BoundingBox,
    mine: &[([f64; 3], [f64; 3])],
    remote: &[([f64; 3], [f64; 3])],
    radius: f64,
) -> Vec<Vec<u32>> {
    use rayon::prelude::*;
    let r2 = radius * radius;
    let grid = CellGrid::new(bbox, remote, radius);
    mine.par_iter()
        .map(|&a| {
            let mut near = grid.near(a);
            near.retain(|&j| box_gap2(bbox, a, remote[j as usize]) < r2);
            near
        })
        .collect()
}

/// Remote cells binned into a uniform grid over the box.
struct CellGrid {
    dims: [usize; 3],
    lo: [f64; 3],
    width: [f64; 3],
    periodic: [bool; 3],
    bins: Vec<Vec<u32>>,
}

impl CellGrid {
    /// Most grid cells per axis.
    const MAX_DIM: usize = 32;

    fn new(bbox: &BoundingBox, remote: &[([f64; 3], [f64; 3])], radius: f64) -> Self {
        let lengths = bbox.lengths();
        let dims = std::array::from_fn(|k| {
            let d = (lengths[k] / radius).floor();
            if d.is_finite() && d >= 1.0 {
                (d as usize).min(Self::MAX_DIM)
            } else {
                1
            }
        });
        let mut grid = Self {
            dims,
            lo: bbox.lo(),
            width: std::array::from_fn(|k| lengths[k] / dims[k] as f64),
            periodic: std::array::from_fn(|k| bbox.is_periodic(k)),
            bins: vec![Vec::new(); dims[0] * dims[1] * dims[2]],
        };
        for (j, b) in remote.iter().enumerate() {
            let grown = (b.0.map(|v| v - radius), b.1.map(|v| v + radius));
            for bin in grid.bins_of(grown) {
                grid.bins[bin].push(j as u32);
            }
        }
        grid
    }

    /// Grid cells along `axis` touching `[from, to]` grown by a hair (for
    /// rounding): wrapped on periodic axes, clamped on open ones.
    fn axis_cells(&self, axis: usize, from: f64, to: f64) -> Vec<usize> {
        let n = self.dims[axis] as i64;
        let hair = 1e-9 * self.width[axis] * n as f64;
        let index = |v: f64| {
            let i = ((v - self.lo[axis]) / self.width[axis]).floor();
            i.is_finite()
                .then(|| i.clamp(-2.0 * n as f64, 3.0 * n as f64) as i64)
        };
        let (Some(i0), Some(i1)) = (index(from - hair), index(to + hair)) else {
            // NaN or infinite bounds: the whole axis.
            return (0..self.dims[axis]).collect();
        };
        if self.periodic[axis] {
            if i1 - i0 + 1 >= n {
                (0..self.dims[axis]).collect()
            } else {
                (i0..=i1).map(|i| i.rem_euclid(n) as usize).collect()
            }
        } else {
            (i0.max(0)..=i1.min(n - 1)).map(|i| i as usize).collect()
        }
    }

    /// Flat indices of the grid cells touching box `b`.
    fn bins_of(&self, b: ([f64; 3], [f64; 3])) -> Vec<usize> {
        let [cx, cy, cz] = [0, 1, 2].map(|k| self.axis_cells(k, b.0[k], b.1[k]));
        let mut out = Vec::with_capacity(cx.len() * cy.len() * cz.len());
        for &k in &cz {
            for &j in &cy {
                for &i in &cx {
                    out.push((k * self.dims[1] + j) * self.dims[0] + i);
                }
            }
        }
        out
    }

    /// The remote cells binned where box `a` lies, ascending, each once.
    fn near(&self, a: ([f64; 3], [f64; 3])) -> Vec<u32> {
        let mut near: Vec<u32> = self
            .bins_of(a)
            .into_iter()
            .flat_map(|bin| self.bins[bin].iter().copied())
            .collect();
        near.sort_unstable();
        near.dedup();
        near
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use sph_tree::Boundary;

    /// Random boxes inside `[0, 1)^3`, up to 0.3 wide.
    fn boxes(n: usize) -> impl Strategy<Value = Vec<([f64; 3], [f64; 3])>> {
        proptest::collection::vec(
            (
                proptest::array::uniform3(0.0f64..1.0),
                proptest::array::uniform3(0.0f64..0.3),
            ),
            1..n,
        )
        .prop_map(|v| {
            v.into_iter()
                .map(|(lo, w)| (lo, std::array::from_fn(|k| (lo[k] + w[k]).min(1.0))))
                .collect()
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

        /// The binned search finds exactly the cells the test of every
        /// pair finds, periodic or open, for radii from tiny to the box.
        #[test]
        fn binned_candidates_equal_all_pairs(
            mine in boxes(30),
            remote in boxes(60),
            radius in 1e-4f64..1.2,
            periodic: bool,
        ) {
            let b = if periodic { Boundary::Periodic } else { Boundary::Open };
            let bbox = BoundingBox::cube(0.0, 1.0, b).unwrap();
            let got = candidate_cells(&bbox, &mine, &remote, radius);
            for (a, near) in mine.iter().zip(&got) {
                let want: Vec<u32> = (0..remote.len() as u32)
                    .filter(|&j| box_gap2(&bbox, *a, remote[j as usize]) < radius * radius)
                    .collect();
                prop_assert_eq!(near, &want);
            }
        }
    }

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
