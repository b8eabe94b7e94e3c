//! The operations on the particle storage ([`Particles`]: structure of
//! arrays, one `Vec` per field).
//!
//! What each array is, and so what migration, halos, reordering and
//! checkpoints do with it, is declared once, beside the struct, in the
//! [field table](crate::fields); the operations here loop over that table.
//!
//! Only the fields the chosen physics needs hold data: the IAD matrix is
//! empty when plain kernel gradients are used, and the grad-h factor is
//! empty when grad-h terms are off. Arrays are kept in space-filling-curve
//! order by [`Particles::reorder`].

use crate::fields::{self, Column, Kind, FIELDS};
pub use crate::fields::{FieldSet, Particles};
use sph_domain::ParticleFields;
use sph_tree::{apply_permutation, apply_permutation_f64};
use std::ops::Range;

impl Particles {
    /// `n` particles at rest at the origin, with the fields of `fields`
    /// (ids `0..n`; derived fields at their arrival value, e.g. Omega 1).
    pub fn new(n: usize, fields: FieldSet) -> Self {
        let mut p = Self {
            fields,
            ..Self::default()
        };
        for f in fields::held(fields) {
            match f.column {
                Column::F64(_, get) => *get(&mut p) = vec![arrival(f.kind); n],
                Column::U64(_, get) => *get(&mut p) = (0..n as u64).collect(),
                Column::U32(_, get) => *get(&mut p) = vec![0; n],
            }
        }
        p
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// The optional fields held.
    pub fn fields(&self) -> FieldSet {
        self.fields
    }

    /// Every held `f64` array, in table order.
    fn f64_arrays(&mut self) -> impl Iterator<Item = fields::GetMut<f64>> {
        fields::f64_fields(self.fields).map(|(get, _)| get)
    }

    /// Gives every particle its own viscosity strength, `alpha0` (a
    /// persistent field: it migrates and travels with halos). Runs whose
    /// [`FieldSet`] comes from their scheme hold it from the start.
    pub fn enable_alpha(&mut self, alpha0: f64) {
        self.fields.alpha = true;
        self.alpha = vec![alpha0; self.len()];
    }

    /// Gives every particle the fields of block time steps (its bin and
    /// density rate, zero until its first step) and holds the derived
    /// fields inactive particles keep. Runs whose [`FieldSet`] comes from
    /// a block-step configuration hold them from the start.
    /// `scheme`: the scheme's fields ([`Scheme::fields`](crate::Scheme::fields));
    /// where its volume elements are not `m / rho`, `X` and `k` are held
    /// too, with the Balsara limiter its strengths, with viscosity
    /// cleaning the velocity gradients (as with switches `div v`).
    pub fn enable_block_steps(&mut self, scheme: FieldSet) {
        let old = self.fields;
        self.fields.block = true;
        self.fields.volumes |= scheme.volumes;
        self.fields.balsara |= scheme.balsara;
        self.fields.cleaning |= scheme.cleaning;
        let n = self.len();
        for f in fields::held(self.fields).filter(|f| !old.holds(f.needs)) {
            if let Column::F64(_, get) = f.column {
                *get(self) = vec![arrival(f.kind); n];
            }
        }
    }

    /// Gives every particle the reference state of a referenced EOS,
    /// zero (the density then comes from the first density evaluation).
    pub fn enable_eos_ref(&mut self) {
        self.fields.eos_ref = true;
        self.eos_ref = [vec![0.0; self.len()], vec![0.0; self.len()]];
    }

    /// Appends one packed particle; a `halo` comes without the integrator
    /// history (zeros there).
    fn push_words(&mut self, words: &[u64], halo: bool) {
        self.id.push(words[0]);
        let mut w = words[1..].iter().map(|&b| f64::from_bits(b));
        for (get, kind) in fields::f64_fields(self.fields) {
            let v = match kind {
                Kind::Persistent | Kind::Held { .. } => {
                    w.next().expect("packed particle too short")
                }
                Kind::History if !halo => w.next().expect("packed particle too short"),
                kind => arrival(kind),
            };
            get(self).push(v);
        }
        self.nc.push(0);
    }

    /// The fields that carry state from one step to the next (everything
    /// else is recomputed each step), in packing order: what migration
    /// moves, and without the integrator's history (`dx`, `dy`, `dz`,
    /// `du_prev` and, stirred under block steps, the kept stirring
    /// acceleration: set and read for owned particles only) what a halo
    /// carries.
    fn carried(&self, history: bool) -> impl Iterator<Item = &Vec<f64>> + '_ {
        fields::sent(self.fields, history).filter_map(|f| f.f64(self))
    }

    /// Bytes held per particle by the particle arrays (not counting
    /// neighbour lists or the tree).
    pub fn bytes_per_particle(&self) -> usize {
        fields::held(self.fields).map(|f| f.bytes()).sum()
    }

    /// Reorders every field by `perm` (`field[i] <- field[perm[i]]`),
    /// using one scratch buffer (kept by the caller between steps, so
    /// nothing is allocated once it has grown).
    pub fn reorder(&mut self, perm: &[u32], scratch: &mut Vec<u64>) {
        assert_eq!(perm.len(), self.len(), "permutation length");
        for get in self.f64_arrays() {
            apply_permutation_f64(perm, get(self), scratch);
        }
        apply_permutation(perm, &mut self.id, scratch);
        // nc is recomputed by the next search.
        self.nc.resize(perm.len(), 0);
    }

    /// As [`reorder`](Self::reorder) for the fields that carry state
    /// between steps and the ids; the fields every step recomputes before
    /// reading them get the values an arriving particle gets (what the
    /// domain's sort needs: 13 to 17 gathers instead of up to 33).
    pub fn reorder_carried(&mut self, perm: &[u32], scratch: &mut Vec<u64>) {
        assert_eq!(perm.len(), self.len(), "permutation length");
        let held_recomputed = self.held_recomputed;
        for (name, get, kind) in fields::f64_fields_named(self.fields) {
            match kind {
                Kind::Derived { fill } => get(self).fill(fill),
                // The density rate reads the density of the last step.
                Kind::Held { fill } if held_recomputed && name != "rho" => get(self).fill(fill),
                _ => apply_permutation_f64(perm, get(self), scratch),
            }
        }
        apply_permutation(perm, &mut self.id, scratch);
        self.nc.resize(perm.len(), 0);
    }

    /// Keeps only the particles in `range`, in order.
    pub fn keep(&mut self, range: Range<usize>) {
        fn cut<T>(v: &mut Vec<T>, range: &Range<usize>) {
            v.truncate(range.end);
            v.drain(..range.start.min(v.len()));
        }
        for get in self.f64_arrays() {
            cut(get(self), &range);
        }
        cut(&mut self.id, &range);
        cut(&mut self.nc, &range);
    }

    /// Makes room for `additional` more particles in every array, growing
    /// each to the new length plus 1/32 (so that the next steps' halo
    /// counts, which vary by a few percent, fit without reallocating)
    /// instead of doubling it as repeated pushes would. Arrays that already
    /// have room are left alone.
    pub fn reserve(&mut self, additional: usize) {
        fn grow<T>(v: &mut Vec<T>, want: usize) {
            if v.capacity() < want {
                v.reserve_exact(want + want / 32 - v.len());
            }
        }
        let want = self.len() + additional;
        for get in self.f64_arrays() {
            grow(get(self), want);
        }
        grow(&mut self.id, want);
        grow(&mut self.nc, want);
    }

    /// Returns the memory of arrays that hold more than their particles
    /// (e.g. after [`keep`](Self::keep) of a share of a larger set).
    pub fn shrink_to_fit(&mut self) {
        for get in self.f64_arrays() {
            get(self).shrink_to_fit();
        }
        self.id.shrink_to_fit();
        self.nc.shrink_to_fit();
    }

    /// Checks that every held array has one entry per particle, that the
    /// arrays not held are empty, and that the optional fields `needed`
    /// are held.
    ///
    /// # Errors
    /// [`CoreError::Invalid`](crate::CoreError::Invalid) naming the first
    /// array of the wrong length, or the missing field.
    pub fn check(&self, needed: FieldSet) -> Result<(), crate::CoreError> {
        let n = self.len();
        let all = self.fields.union(needed);
        for f in FIELDS {
            let (held, len) = (all.holds(f.needs), f.len(self));
            let want = if held { n } else { 0 };
            if len != want {
                let why = if !self.fields.holds(f.needs) && held {
                    format!(
                        "the run needs it ({:?}) but the particles were built without it",
                        f.needs
                    )
                } else if !held {
                    "the particles' FieldSet does not hold it".to_owned()
                } else {
                    format!("x has {n}")
                };
                return Err(crate::CoreError::Invalid(format!(
                    "field {} ({}) has {len} entries for {n} particles: {why}; build the particles with the run's FieldSet (HydroConfig::fields)",
                    f.name, f.doc
                )));
            }
        }
        Ok(())
    }
}

/// The value a derived field starts with on an arriving particle (the
/// sent fields are overwritten from the message).
fn arrival(kind: Kind) -> f64 {
    match kind {
        Kind::Derived { fill } | Kind::Held { fill } => fill,
        _ => 0.0,
    }
}

/// One field of [`ParticleFields::place_halos`]: the halos (from
/// `n_owned` on) gathered in `order` into `scratch`, the owned block
/// shifted by `n_low`, the halos written around it.
fn place_tail<T: Copy>(
    v: &mut [T],
    n_owned: usize,
    order: &[u32],
    n_low: usize,
    scratch: &mut Vec<u64>,
    bits: fn(T) -> u64,
    value: fn(u64) -> T,
) {
    scratch.clear();
    scratch.extend(order.iter().map(|&k| bits(v[n_owned + k as usize])));
    if n_low > 0 {
        v.copy_within(0..n_owned, n_low);
    }
    let (low, high) = scratch.split_at(n_low);
    for (d, &s) in v[..n_low].iter_mut().zip(low) {
        *d = value(s);
    }
    for (d, &s) in v[n_low + n_owned..].iter_mut().zip(high) {
        *d = value(s);
    }
}

impl ParticleFields for Particles {
    fn len(&self) -> usize {
        self.x.len()
    }

    fn ids(&self) -> &[u64] {
        &self.id
    }

    fn positions(&self) -> [&[f64]; 3] {
        [&self.x, &self.y, &self.z]
    }

    fn smoothing_lengths(&self) -> &[f64] {
        &self.h
    }

    fn packed_words(&self) -> usize {
        1 + fields::sent(self.fields, true).count()
    }

    fn pack(&self, i: usize, out: &mut Vec<u64>) {
        out.push(self.id[i]);
        out.extend(self.carried(true).map(|f| f[i].to_bits()));
    }

    fn push_packed(&mut self, words: &[u64]) {
        self.push_words(words, false);
    }

    fn halo_words(&self) -> usize {
        1 + fields::sent(self.fields, false).count()
    }

    fn pack_halo(&self, i: usize, out: &mut Vec<u64>) {
        out.push(self.id[i]);
        out.extend(self.carried(false).map(|f| f[i].to_bits()));
    }

    fn pack_halos(&self, idx: &[u32], out: &mut Vec<u64>) {
        let sent: Vec<&[f64]> = self.carried(false).map(Vec::as_slice).collect();
        out.reserve(idx.len() * (1 + sent.len()));
        for &i in idx {
            let i = i as usize;
            out.push(self.id[i]);
            out.extend(sent.iter().map(|f| f[i].to_bits()));
        }
    }

    fn push_halo(&mut self, words: &[u64]) {
        self.push_words(words, true);
    }

    fn push_halos(&mut self, packed: &[u64]) {
        let words = self.halo_words();
        assert_eq!(packed.len() % words, 0, "packed halos of {words} words");
        let n = self.len() + packed.len() / words;
        let rows = || packed.chunks_exact(words);
        self.id.extend(rows().map(|r| r[0]));
        let mut word = 1;
        for (get, kind) in fields::f64_fields(self.fields) {
            let f = get(self);
            if matches!(kind, Kind::Persistent | Kind::Held { .. }) {
                f.extend(rows().map(|r| f64::from_bits(r[word])));
                word += 1;
            } else {
                f.resize(n, arrival(kind));
            }
        }
        self.nc.resize(n, 0);
    }

    fn keep(&mut self, range: Range<usize>) {
        Particles::keep(self, range);
    }

    fn reserve(&mut self, additional: usize) {
        Particles::reserve(self, additional);
    }

    fn reorder(&mut self, perm: &[u32], scratch: &mut Vec<u64>) {
        Particles::reorder(self, perm, scratch);
    }

    fn reorder_carried(&mut self, perm: &[u32], scratch: &mut Vec<u64>) {
        Particles::reorder_carried(self, perm, scratch);
    }

    fn place_halos(&mut self, n_owned: usize, order: &[u32], n_low: usize, scratch: &mut Vec<u64>) {
        let n = self.len();
        assert_eq!(order.len() + n_owned, n, "halo order length");
        for get in self.f64_arrays() {
            place_tail(
                get(self),
                n_owned,
                order,
                n_low,
                scratch,
                f64::to_bits,
                f64::from_bits,
            );
        }
        place_tail(&mut self.id, n_owned, order, n_low, scratch, |v| v, |v| v);
        // nc is recomputed by the next search.
        self.nc.resize(n, 0);
    }
}

#[cfg(test)]
mod held_tests {
    use super::*;

    /// A sort at a sub-step where every particle recomputes its held
    /// fields resets them (but the density, which the density rate reads)
    /// and moves everything else; any other sort moves them.
    #[test]
    fn a_sort_resets_the_held_fields_only_where_they_are_recomputed() {
        let set = FieldSet {
            block: true,
            ..FieldSet::default()
        };
        let fill = |p: &mut Particles| {
            for i in 0..p.len() {
                let v = i as f64 + 1.0;
                (p.x[i], p.rho[i], p.p[i], p.ax[i], p.du[i]) =
                    (v, 10.0 * v, 20.0 * v, 30.0 * v, 40.0 * v);
            }
        };
        let perm = [2u32, 0, 1];
        let mut scratch = Vec::new();
        let mut moved = Particles::new(3, set);
        fill(&mut moved);
        moved.reorder_carried(&perm, &mut scratch);
        assert_eq!(moved.p, [60.0, 20.0, 40.0]);
        let mut reset = Particles::new(3, set);
        fill(&mut reset);
        reset.held_recomputed = true;
        reset.reorder_carried(&perm, &mut scratch);
        assert_eq!(reset.x, [3.0, 1.0, 2.0]);
        assert_eq!(reset.rho, [30.0, 10.0, 20.0]);
        for held in [&reset.p, &reset.ax, &reset.du] {
            assert_eq!(held, &[0.0; 3]);
        }
    }
}
