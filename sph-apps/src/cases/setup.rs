//! What building a case's particles needs below the registry (so that
//! the glass relaxation can use it too): a rank's share of the particles
//! and the initial smoothing length.

use sph_core::{FieldSet, Particles};

/// Which part of a case's particles a rank builds: the contiguous index
/// range `total * rank / ranks .. total * (rank + 1) / ranks`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Share {
    /// This rank.
    pub rank: usize,
    /// Ranks sharing the particles.
    pub ranks: usize,
}

impl Share {
    /// Every particle (one rank).
    pub const WHOLE: Share = Share { rank: 0, ranks: 1 };

    /// This share's indices of `total` particles.
    pub fn range(&self, total: usize) -> std::ops::Range<usize> {
        let ranks = self.ranks.max(1);
        total * self.rank / ranks..total * (self.rank + 1) / ranks
    }

    /// Particles for this share of `total` (with `fields`), ids set to
    /// their global indices, and that index range.
    pub fn particles(&self, total: usize, fields: FieldSet) -> (Particles, std::ops::Range<usize>) {
        let mine = self.range(total);
        let mut p = Particles::new(mine.len(), fields);
        for (id, g) in p.id.iter_mut().zip(mine.clone()) {
            *id = g as u64;
        }
        (p, mine)
    }
}

/// Smoothing length giving `ng0` neighbours (within 2h) at number density
/// `n / volume`: `h = 1/2 (3/(4 pi) ng0 V / N)^(1/3)`.
pub fn initial_h(ng0: usize, volume: f64, n: usize) -> f64 {
    0.5 * (3.0 / (4.0 * std::f64::consts::PI) * ng0 as f64 * volume / n as f64).cbrt()
}
