//! Neighbour lists with the smoothing-length iteration: particles whose
//! count falls outside `[ng0/4, ngmax + 1]` get a new h and are searched
//! again, at most `max_iterations` times.

use crate::integrate::HUpdate;
use crate::CoreError;
use sph_tree::{BoundingBox, CompactNeighborList, NeighborSearch, NeighborStats, Octree};
use std::ops::Range;

/// Neighbour-count targets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeighborParams {
    /// Target count, self included.
    pub ng0: usize,
    /// Largest count (self excluded) accepted without iterating h.
    pub ngmax: usize,
    /// Most re-searches per step.
    pub max_iterations: usize,
}

impl Default for NeighborParams {
    fn default() -> Self {
        Self {
            ng0: 100,
            ngmax: 150,
            max_iterations: 10,
        }
    }
}

impl NeighborParams {
    /// Whether `nc` (self included) needs another h iteration.
    #[inline]
    pub fn out_of_range(&self, nc: usize) -> bool {
        nc * 4 < self.ng0 || nc.saturating_sub(1) > self.ngmax
    }

    /// These targets with no count out of range: the search never
    /// iterates h (fixed smoothing lengths).
    ///
    /// ```
    /// use sph_core::NeighborParams;
    /// let p = NeighborParams::default();
    /// assert!(p.out_of_range(3) && p.out_of_range(400));
    /// let fixed = p.without_iteration();
    /// assert!(!fixed.out_of_range(1) && !fixed.out_of_range(100_000));
    /// ```
    pub fn without_iteration(self) -> Self {
        Self {
            ng0: 0,
            ngmax: usize::MAX,
            ..self
        }
    }

    /// The h update rule with this target.
    pub fn h_update(&self, base: HUpdate) -> HUpdate {
        HUpdate {
            ng0: self.ng0 as f64,
            ..base
        }
    }
}

/// Builds the neighbour lists of `targets`, iterating h of the particles
/// whose count is out of range; h never grows beyond `h_limit` (what the
/// halos of a distributed run cover). Writes the final counts into `nc`
/// (indexed like the particles).
#[allow(clippy::too_many_arguments)]
pub fn find_neighbors(
    params: &NeighborParams,
    h_update: HUpdate,
    tree: &Octree,
    bbox: &BoundingBox,
    x: &[f64],
    y: &[f64],
    z: &[f64],
    h: &mut [f64],
    ids: &[u64],
    targets: Range<usize>,
    h_limit: f64,
    list: &mut CompactNeighborList,
    nc: &mut [u32],
    step: u64,
) -> Result<NeighborStats, CoreError> {
    find_neighbors_of(
        params,
        h_update,
        tree,
        bbox,
        [x, y, z],
        h,
        ids,
        targets,
        None,
        h_limit,
        list,
        nc,
        step,
    )
}

/// [`find_neighbors`] for the flagged targets only (`active`: one flag per
/// target, or `None` for all): the lists serve those targets
/// ([`CompactNeighborList::active_targets`], so the pair loops compute
/// them only), and only their h iterate and their counts are written. A
/// flagged target gets the list, h and count a full search gives it.
#[allow(clippy::too_many_arguments)]
pub fn find_neighbors_of(
    params: &NeighborParams,
    h_update: HUpdate,
    tree: &Octree,
    bbox: &BoundingBox,
    [x, y, z]: [&[f64]; 3],
    h: &mut [f64],
    ids: &[u64],
    targets: Range<usize>,
    active: Option<&[bool]>,
    h_limit: f64,
    list: &mut CompactNeighborList,
    nc: &mut [u32],
    step: u64,
) -> Result<NeighborStats, CoreError> {
    let groups: Option<Vec<bool>> = active.map(|a| {
        assert_eq!(a.len(), targets.len(), "one flag per target");
        a.chunks(sph_tree::GROUP_LANES)
            .map(|g| g.iter().any(|&on| on))
            .collect()
    });
    let is_target = |i: usize| active.is_none_or(|a| a[i - targets.start]);
    // Symmetric lists: a pair interacts through both W(h_i) and W(h_j), so
    // both partners must list each other for the forces to stay antisymmetric.
    // Grouped lists: the pair loops take LANES consecutive targets per
    // vector over the union of their lists.
    let search = NeighborSearch {
        symmetric: true,
        grouped: true,
        ..NeighborSearch::default()
    };
    let hu = params.h_update(h_update);
    let mut iterations = 0;
    loop {
        let stats = match &groups {
            None => search.find_compact(tree, bbox, x, y, z, h, targets.clone(), list)?,
            Some(g) => {
                let s =
                    search.find_compact_groups(tree, bbox, x, y, z, h, targets.clone(), g, list)?;
                list.set_active_targets(active.unwrap_or_default());
                s
            }
        };
        let mut bad = None;
        for i in targets.clone().filter(|&i| is_target(i)) {
            let c = list.count(i);
            nc[i] = c as u32;
            if params.out_of_range(c) {
                bad.get_or_insert(i);
            }
        }
        let Some(first) = bad else {
            return Ok(stats);
        };
        if iterations == params.max_iterations {
            return Err(CoreError::HIteration {
                step,
                id: ids[first],
                iterations,
                count: list.count(first),
                min: params.ng0.div_ceil(4),
                max: params.ngmax + 1,
                h: h[first],
            });
        }
        iterations += 1;
        // Keep periodic searches within the minimum-image limit.
        let lengths = bbox.lengths();
        let hmax = (0..3)
            .filter(|&k| bbox.is_periodic(k))
            .map(|k| 0.249 * lengths[k])
            .fold(h_limit, f64::min);
        for i in targets.clone().filter(|&i| is_target(i)) {
            let c = list.count(i);
            if params.out_of_range(c) {
                h[i] = (h[i] * hu.factor(c as u32)).min(hmax);
            }
        }
    }
}
