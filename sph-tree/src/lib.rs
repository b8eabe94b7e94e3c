//! Spatial machinery for particle codes: a periodic-aware box,
//! space-filling-curve keys, a flat octree built from sorted keys, a
//! fixed-radius neighbour search and a generic tree traversal.
//!
//! Everything works on structure-of-arrays coordinates (`x`, `y`, `z`
//! slices) sorted along the curve: compute keys, sort, reorder your arrays,
//! build the tree, search.
//!
//! ```
//! use sph_tree::{apply_permutation, compute_keys, Boundary, BoundingBox, Curve, KeySorter,
//!                NeighborList, NeighborSearch, Octree};
//!
//! // A 10^3 lattice in a periodic unit cube.
//! let n = 10;
//! let (mut x, mut y, mut z) = (Vec::new(), Vec::new(), Vec::new());
//! for i in 0..n * n * n {
//!     x.push(((i % n) as f64 + 0.5) / n as f64);
//!     y.push(((i / n % n) as f64 + 0.5) / n as f64);
//!     z.push(((i / (n * n)) as f64 + 0.5) / n as f64);
//! }
//! let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
//!
//! // Sort along the Hilbert curve.
//! let mut keys = Vec::new();
//! compute_keys(&bbox, Curve::Hilbert, &x, &y, &z, &mut keys);
//! let mut perm = Vec::new();
//! KeySorter::new().sort(&keys, None, &mut perm);
//! let mut scratch = Vec::new();
//! for a in [&mut x, &mut y, &mut z] {
//!     apply_permutation(&perm, a, &mut scratch);
//! }
//! let mut scratch_keys = Vec::new();
//! apply_permutation(&perm, &mut keys, &mut scratch_keys);
//!
//! // Tree with at most 16 particles per leaf, then all pairs closer than 2h.
//! let tree = Octree::build(&keys, &x, &y, &z, 16).unwrap();
//! let h = vec![0.075; x.len()]; // 2h = 1.5 spacings: 6 face + 12 edge neighbours + self
//! let mut list = NeighborList::new();
//! let stats = NeighborSearch::default()
//!     .find(&tree, &bbox, &x, &y, &z, &h, 0..x.len(), &mut list)
//!     .unwrap();
//! assert_eq!((stats.min_count, stats.max_count), (19, 19));
//! let nb = list.neighbors(0);
//! assert!(nb.windows(2).all(|w| w[0] < w[1])); // ascending
//! ```

mod bbox;
pub mod compact;
mod error;
pub mod neighbors;
pub mod octree;
pub mod sfc;

pub use bbox::{Boundary, BoundingBox};
pub use compact::CompactNeighborList;
pub use error::TreeError;
pub use neighbors::{NeighborList, NeighborSearch, NeighborStats, GROUP_LANES};
pub use octree::{NodeId, Octree};
pub use sfc::{
    apply_permutation, apply_permutation_f64, compute_keys, Curve, KeySorter, CELLS_PER_AXIS,
    MAX_LEVEL,
};

/// Checks that the coordinate slices (and optionally one more array) have
/// equal lengths.
pub(crate) fn check_lengths(
    x: &[f64],
    y: &[f64],
    z: &[f64],
    other: Option<(&str, usize)>,
) -> Result<(), TreeError> {
    let bad_other = other.is_some_and(|(_, n)| n != x.len());
    if x.len() != y.len() || x.len() != z.len() || bad_other {
        return Err(TreeError::LengthMismatch {
            x: x.len(),
            y: y.len(),
            z: z.len(),
            extra: other
                .map(|(name, n)| format!(", {name} has {n}"))
                .unwrap_or_default(),
        });
    }
    Ok(())
}
