//! What the domain needs to know of a particle container.

use std::ops::Range;

/// A structure-of-arrays particle container that a
/// [`Domain`](crate::Domain) can sort, migrate and extend with halos.
///
/// Particles travel as packed `u64` words (`f64` fields as their bits), so a
/// container decides itself which fields persist across steps (positions,
/// velocities, h, mass, internal energy, integrator history, ...). Fields
/// that every step recomputes (density, forces) need not travel: unpacked
/// particles may hold anything there.
pub trait ParticleFields {
    /// Number of particles held (owned and halos).
    fn len(&self) -> usize;
    /// Whether no particle is held.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Unique particle ids.
    fn ids(&self) -> &[u64];
    /// Coordinates.
    fn positions(&self) -> [&[f64]; 3];
    /// Smoothing lengths.
    fn smoothing_lengths(&self) -> &[f64];
    /// Words per packed particle.
    fn packed_words(&self) -> usize;
    /// Appends particle `i`, packed, to `out`.
    fn pack(&self, i: usize, out: &mut Vec<u64>);
    /// Appends one particle from `packed_words()` words.
    fn push_packed(&mut self, words: &[u64]);
    /// Words per packed halo. A halo is a read-only copy for one step,
    /// dropped at the next sync, so a container may leave out what only
    /// the owner uses (integrator history). Default: [`packed_words`](Self::packed_words).
    fn halo_words(&self) -> usize {
        self.packed_words()
    }
    /// Appends particle `i`, packed as a halo, to `out`. Default:
    /// [`pack`](Self::pack).
    fn pack_halo(&self, i: usize, out: &mut Vec<u64>) {
        self.pack(i, out);
    }
    /// Appends one halo from `halo_words()` words. Default:
    /// [`push_packed`](Self::push_packed).
    fn push_halo(&mut self, words: &[u64]) {
        self.push_packed(words);
    }
    /// Appends the particles `idx`, packed as halos, to `out` (a container
    /// can set up its field list once). Default: [`pack_halo`](Self::pack_halo)
    /// for each.
    fn pack_halos(&self, idx: &[u32], out: &mut Vec<u64>) {
        for &i in idx {
            self.pack_halo(i as usize, out);
        }
    }
    /// Appends every halo of `packed` (`halo_words()` words each; a
    /// container can fill its arrays field by field). Default:
    /// [`push_halo`](Self::push_halo) for each.
    fn push_halos(&mut self, packed: &[u64]) {
        let words = self.halo_words().max(1);
        for chunk in packed.chunks_exact(words) {
            self.push_halo(chunk);
        }
    }
    /// Makes room for `additional` more particles before a run of
    /// [`push_packed`](Self::push_packed). The domain calls it with the exact
    /// count of arrivals, so a container can grow its arrays to what they
    /// will hold instead of doubling them. Does nothing by default.
    fn reserve(&mut self, additional: usize) {
        let _ = additional;
    }
    /// Keeps only the particles in `range` (in order).
    fn keep(&mut self, range: Range<usize>);
    /// Reorders every field: `new[i] = old[perm[i]]`.
    fn reorder(&mut self, perm: &[u32], scratch: &mut Vec<u64>);
    /// Reorders what a sync must keep: the fields that carry state between
    /// steps (what [`pack`](Self::pack) moves) and the ids; a container may
    /// reset the fields it recomputes every step before reading them
    /// instead of moving them. Default: [`reorder`](Self::reorder).
    fn reorder_carried(&mut self, perm: &[u32], scratch: &mut Vec<u64>) {
        self.reorder(perm, scratch);
    }
    /// Puts the particles from `n_owned` on (the halos just received)
    /// around the owned ones: `order[k]` is the offset from `n_owned` of the
    /// halo that goes k-th; the first `n_low` go before the owned
    /// particles, the rest after them. The result is that of
    /// [`reorder`](Self::reorder) with the permutation
    /// [`halo_placement`] builds, which the default runs; a container can
    /// instead move only the halos and shift the owned block.
    fn place_halos(&mut self, n_owned: usize, order: &[u32], n_low: usize, scratch: &mut Vec<u64>) {
        let mut perm = Vec::new();
        halo_placement(n_owned, order, n_low, &mut perm);
        self.reorder(&perm, scratch);
    }
}

/// The permutation (`new[i] = old[perm[i]]`) of
/// [`ParticleFields::place_halos`]: the first `n_low` halos of `order`,
/// the `n_owned` owned particles in place, the other halos.
///
/// ```
/// let mut perm = Vec::new();
/// // Two owned particles, three halos: the third and first go in front.
/// sph_domain::halo_placement(2, &[2, 0, 1], 2, &mut perm);
/// assert_eq!(perm, [4, 2, 0, 1, 3]);
/// ```
pub fn halo_placement(n_owned: usize, order: &[u32], n_low: usize, perm: &mut Vec<u32>) {
    let halo = |&k: &u32| k + n_owned as u32;
    perm.clear();
    perm.extend(order[..n_low].iter().map(halo));
    perm.extend(0..n_owned as u32);
    perm.extend(order[n_low..].iter().map(halo));
}

/// The new index, under [`halo_placement`], of the halo at position `k`
/// of `order`: the first `n_low` go in front of the owned block, the
/// others after it.
///
/// ```
/// // Two owned particles, three halos of which two go in front.
/// let slots: Vec<usize> = (0..3).map(|k| sph_domain::halo_slot(k, 2, 2)).collect();
/// assert_eq!(slots, [0, 1, 4]);
/// ```
#[inline]
pub fn halo_slot(k: usize, n_low: usize, n_owned: usize) -> usize {
    if k < n_low {
        k
    } else {
        n_owned + k
    }
}
