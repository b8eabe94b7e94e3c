//! Pair separations with the minimum image on periodic axes.

use sph_kernels::F64s;
use sph_tree::BoundingBox;

/// Computes `x_i - x_j` for particle pairs, folding periodic axes.
#[derive(Debug, Clone, Copy)]
pub struct Separation {
    /// Half the box length on periodic axes, infinity on open ones (so
    /// the fold below never triggers there and needs no branch per axis).
    half: [f64; 3],
    /// Box length on periodic axes, 0 on open ones.
    length: [f64; 3],
    /// Box corners.
    lo: [f64; 3],
    hi: [f64; 3],
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
            lo: bbox.lo(),
            hi: bbox.hi(),
        }
    }

    /// The separations of a group of targets (lanes of `a`, inside the
    /// box) from partners within `reach` of one of them: the fold is
    /// skipped on every axis where it is the identity for all such pairs
    /// (open axes, and periodic axes where the group lies more than `reach`
    /// from both faces and its extent plus `reach` stays below half the
    /// box), so results are unchanged bit for bit while interior groups
    /// save the fold's compares and selects.
    #[inline(always)]
    pub fn for_group(&self, a: [F64s; 3], reach: f64) -> GroupSeparation {
        // A relative margin absorbs the rounding of the tests below.
        let reach = reach * (1.0 + 1e-6);
        let fold = std::array::from_fn(|k| {
            if self.length[k] == 0.0 {
                return false;
            }
            let (mn, mx) = (a[k].min_lane(), a[k].max_lane());
            let interior = mn - reach > self.lo[k] && mx + reach < self.hi[k];
            !(interior && (mx - mn) + reach < self.half[k])
        });
        GroupSeparation { sep: *self, fold }
    }
}

/// [`Separation`] for one group of targets ([`Separation::for_group`]).
#[derive(Debug, Clone, Copy)]
pub struct GroupSeparation {
    sep: Separation,
    fold: [bool; 3],
}

impl GroupSeparation {
    /// `a - b` for the group's lanes `a` and a partner `b` within the
    /// reach given to [`Separation::for_group`], folded to the minimum
    /// image on periodic axes; lane `l` is the scalar result bit for bit.
    #[inline(always)]
    pub fn between_lanes(&self, a: [F64s; 3], b: [f64; 3]) -> [F64s; 3] {
        let axis = |k: usize| {
            let d = a[k] - b[k];
            if self.fold[k] {
                d.fold(self.sep.half[k], self.sep.length[k])
            } else {
                d
            }
        };
        [axis(0), axis(1), axis(2)]
    }
}
