//! Particle storage: structure of arrays, `f64`, one `Vec` per field.
//!
//! Only the fields the chosen physics needs hold data: the IAD matrix is
//! empty when plain kernel gradients are used, and the grad-h factor is
//! empty when grad-h terms are off. Arrays are kept in space-filling-curve
//! order by [`Particles::reorder`].

use sph_domain::ParticleFields;
use sph_tree::{apply_permutation, apply_permutation_f64};
use std::ops::Range;

/// Which optional fields a run needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldSet {
    /// The 6 components of the inverse IAD matrix.
    pub iad: bool,
    /// The grad-h factor Omega.
    pub grad_h: bool,
    /// The gravitational potential (self-gravity runs).
    pub gravity: bool,
}

impl Default for FieldSet {
    fn default() -> Self {
        Self {
            iad: true,
            grad_h: true,
            gravity: false,
        }
    }
}

/// All particles of one rank, one array per field.
#[derive(Debug, Clone, Default)]
pub struct Particles {
    /// Unique particle id (stable across sorting and ranks).
    pub id: Vec<u64>,
    /// Position.
    pub x: Vec<f64>,
    /// Position.
    pub y: Vec<f64>,
    /// Position.
    pub z: Vec<f64>,
    /// Velocity.
    pub vx: Vec<f64>,
    /// Velocity.
    pub vy: Vec<f64>,
    /// Velocity.
    pub vz: Vec<f64>,
    /// Position change of the last step, `x_n - x_{n-1}` (Press integrator).
    pub dx: Vec<f64>,
    /// Position change of the last step.
    pub dy: Vec<f64>,
    /// Position change of the last step.
    pub dz: Vec<f64>,
    /// Smoothing length.
    pub h: Vec<f64>,
    /// Mass.
    pub m: Vec<f64>,
    /// Specific internal energy.
    pub u: Vec<f64>,
    /// Density.
    pub rho: Vec<f64>,
    /// Pressure.
    pub p: Vec<f64>,
    /// Sound speed.
    pub c: Vec<f64>,
    /// grad-h factor Omega (empty when grad-h is off).
    pub omega: Vec<f64>,
    /// Inverse IAD matrix, components xx, xy, xz, yy, yz, zz (empty for
    /// plain kernel gradients).
    pub iad: [Vec<f64>; 6],
    /// Acceleration.
    pub ax: Vec<f64>,
    /// Acceleration.
    pub ay: Vec<f64>,
    /// Acceleration.
    pub az: Vec<f64>,
    /// du/dt of this step.
    pub du: Vec<f64>,
    /// du/dt of the previous step (Adams-Bashforth).
    pub du_prev: Vec<f64>,
    /// Gravitational potential per unit mass (empty without self-gravity).
    pub phi: Vec<f64>,
    /// Per-particle artificial-viscosity strength (empty unless AV switches
    /// are on; see [`Particles::enable_alpha`]).
    pub alpha: Vec<f64>,
    /// Per-particle reference density and pressure of
    /// [`Eos::TaitReferenced`](crate::Eos) (empty otherwise); a zero
    /// density is calibrated from the first density evaluation.
    pub eos_ref: [Vec<f64>; 2],
    /// Neighbour count of the last search (self included), for the h update.
    pub nc: Vec<u32>,
    fields: FieldSet,
    /// Whether `alpha` is a field of every particle (even on a rank that
    /// holds none right now), so it travels with migrating particles.
    alpha_on: bool,
}

impl Particles {
    /// `n` particles at rest at the origin, with the fields of `fields`.
    pub fn new(n: usize, fields: FieldSet) -> Self {
        let z = || vec![0.0; n];
        let mut p = Self {
            id: (0..n as u64).collect(),
            x: z(),
            y: z(),
            z: z(),
            vx: z(),
            vy: z(),
            vz: z(),
            dx: z(),
            dy: z(),
            dz: z(),
            h: z(),
            m: z(),
            u: z(),
            rho: z(),
            p: z(),
            c: z(),
            omega: Vec::new(),
            phi: Vec::new(),
            alpha: Vec::new(),
            iad: Default::default(),
            ax: z(),
            ay: z(),
            az: z(),
            du: z(),
            du_prev: z(),
            eos_ref: Default::default(),
            nc: vec![0; n],
            fields,
            alpha_on: false,
        };
        if fields.grad_h {
            p.omega = vec![1.0; n];
        }
        if fields.iad {
            p.iad = std::array::from_fn(|_| vec![0.0; n]);
        }
        if fields.gravity {
            p.phi = vec![0.0; n];
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

    fn f64_fields_mut(&mut self) -> Vec<&mut Vec<f64>> {
        let FieldsByKind {
            mut halo,
            history,
            recomputed,
        } = self.fields_by_kind_mut();
        halo.extend(history);
        halo.extend(recomputed.into_iter().map(|(f, _)| f));
        halo
    }

    /// The held f64 fields by kind: what a halo carries (in its packing
    /// order, see [`carried`](Self::carried)), the integrator's history
    /// (carried by migrating particles only), and the fields every step
    /// recomputes before reading them, each with the value an arriving
    /// particle gets (Omega: 1, else 0).
    fn fields_by_kind_mut(&mut self) -> FieldsByKind<'_> {
        let mut halo: Vec<&mut Vec<f64>> = vec![
            &mut self.x,
            &mut self.y,
            &mut self.z,
            &mut self.vx,
            &mut self.vy,
            &mut self.vz,
            &mut self.h,
            &mut self.m,
            &mut self.u,
        ];
        halo.extend(self.eos_ref.iter_mut().filter(|c| !c.is_empty()));
        if self.alpha_on {
            halo.push(&mut self.alpha);
        }
        let history = vec![&mut self.dx, &mut self.dy, &mut self.dz, &mut self.du_prev];
        let mut recomputed: Vec<(&mut Vec<f64>, f64)> = [
            &mut self.rho,
            &mut self.p,
            &mut self.c,
            &mut self.ax,
            &mut self.ay,
            &mut self.az,
            &mut self.du,
        ]
        .into_iter()
        .map(|f| (f, 0.0))
        .collect();
        if self.fields.grad_h {
            recomputed.push((&mut self.omega, 1.0));
        }
        if self.fields.gravity {
            recomputed.push((&mut self.phi, 0.0));
        }
        if self.fields.iad {
            recomputed.extend(self.iad.iter_mut().map(|c| (c, 0.0)));
        }
        FieldsByKind {
            halo,
            history,
            recomputed,
        }
    }

    /// Appends one packed particle; a `halo` comes without the integrator
    /// history (zeros there).
    fn push_words(&mut self, words: &[u64], halo: bool) {
        let with_ref = !self.eos_ref[0].is_empty();
        self.id.push(words[0]);
        let mut w = words[1..].iter().map(|&b| f64::from_bits(b));
        let mut next = || w.next().expect("packed particle too short");
        for f in [
            &mut self.x,
            &mut self.y,
            &mut self.z,
            &mut self.vx,
            &mut self.vy,
            &mut self.vz,
        ] {
            f.push(next());
        }
        for f in [&mut self.dx, &mut self.dy, &mut self.dz] {
            f.push(if halo { 0.0 } else { next() });
        }
        for f in [&mut self.h, &mut self.m, &mut self.u] {
            f.push(next());
        }
        self.du_prev.push(if halo { 0.0 } else { next() });
        self.push_rest(&mut w, with_ref);
    }

    /// The optional persistent fields from the rest of a packed particle,
    /// and zeros (Omega: 1) in every recomputed field.
    fn push_rest(&mut self, w: &mut impl Iterator<Item = f64>, with_ref: bool) {
        if with_ref {
            for f in self.eos_ref.iter_mut() {
                f.push(w.next().expect("packed particle too short"));
            }
        }
        if self.alpha_on {
            self.alpha
                .push(w.next().expect("packed particle too short"));
        }
        // Recomputed every step before use.
        for f in [
            &mut self.rho,
            &mut self.p,
            &mut self.c,
            &mut self.ax,
            &mut self.ay,
            &mut self.az,
            &mut self.du,
        ] {
            f.push(0.0);
        }
        if self.fields.grad_h {
            self.omega.push(1.0);
        }
        if self.fields.gravity {
            self.phi.push(0.0);
        }
        if self.fields.iad {
            for f in self.iad.iter_mut() {
                f.push(0.0);
            }
        }
        self.nc.push(0);
    }

    /// The fields that carry state from one step to the next (everything
    /// else is recomputed each step), in packing order: what migration
    /// moves, and without the integrator's history (`dx`, `dy`, `dz`,
    /// `du_prev`: set and read for owned particles only) what a halo
    /// carries ([`HISTORY_FIELDS`] words fewer).
    fn carried(&self, history: bool) -> impl Iterator<Item = &Vec<f64>> + '_ {
        let with_history = move |_: &&Vec<f64>| history;
        [&self.x, &self.y, &self.z, &self.vx, &self.vy, &self.vz]
            .into_iter()
            .chain(
                [&self.dx, &self.dy, &self.dz]
                    .into_iter()
                    .filter(with_history),
            )
            .chain([&self.h, &self.m, &self.u])
            .chain(std::iter::once(&self.du_prev).filter(with_history))
            .chain(self.eos_ref.iter().filter(|f| !f.is_empty()))
            .chain(std::iter::once(&self.alpha).filter(|_| self.alpha_on))
    }

    /// Bytes held per particle by the particle arrays (not counting
    /// neighbour lists or the tree).
    pub fn bytes_per_particle(&self) -> usize {
        let optional = [&self.omega, &self.phi, &self.alpha]
            .into_iter()
            .chain(self.iad.iter())
            .chain(self.eos_ref.iter())
            .filter(|v| !v.is_empty())
            .count();
        let n_f64 = 20 + optional;
        n_f64 * 8 + 8 /* id */ + 4 /* nc */
    }

    /// Reorders every field by `perm` (`field[i] <- field[perm[i]]`),
    /// using one scratch buffer (kept by the caller between steps, so
    /// nothing is allocated once it has grown).
    pub fn reorder(&mut self, perm: &[u32], scratch: &mut Vec<u64>) {
        assert_eq!(perm.len(), self.len(), "permutation length");
        for f in self.f64_fields_mut() {
            apply_permutation_f64(perm, f, scratch);
        }
        apply_permutation(perm, &mut self.id, scratch);
        // nc is recomputed by the next search.
        self.nc.resize(perm.len(), 0);
    }

    /// As [`reorder`](Self::reorder) for the fields that carry state
    /// between steps and the ids; the fields every step recomputes before
    /// reading them get the values an arriving particle gets (what the
    /// domain's sort needs: 13 to 15 gathers instead of up to 30).
    pub fn reorder_carried(&mut self, perm: &[u32], scratch: &mut Vec<u64>) {
        assert_eq!(perm.len(), self.len(), "permutation length");
        let FieldsByKind {
            halo,
            history,
            recomputed,
        } = self.fields_by_kind_mut();
        for f in halo.into_iter().chain(history) {
            apply_permutation_f64(perm, f, scratch);
        }
        for (f, fill) in recomputed {
            f.fill(fill);
        }
        apply_permutation(perm, &mut self.id, scratch);
        self.nc.resize(perm.len(), 0);
    }

    /// Gives every particle its own viscosity strength, starting at
    /// `alpha0` (a persistent field: it migrates with the particle).
    pub fn enable_alpha(&mut self, alpha0: f64) {
        self.alpha_on = true;
        self.alpha = vec![alpha0; self.len()];
    }

    /// Keeps only the particles in `range`, in order.
    pub fn keep(&mut self, range: Range<usize>) {
        let cut = |v: &mut Vec<f64>| {
            v.truncate(range.end);
            v.drain(..range.start);
        };
        for f in self.f64_fields_mut() {
            cut(f);
        }
        self.id.truncate(range.end);
        self.id.drain(..range.start);
        self.nc.truncate(range.end);
        self.nc.drain(..range.start.min(self.nc.len()));
    }

    /// Makes room for `additional` more particles in every array, growing
    /// each to the new length plus 1/32 (so that the next steps' halo
    /// counts, which vary by a few percent, fit without reallocating)
    /// instead of doubling it as repeated pushes would. Arrays that already
    /// have room are left alone.
    pub fn reserve(&mut self, additional: usize) {
        let want = self.len() + additional;
        let room = |cap: usize, len: usize| (cap < want).then(|| want + want / 32 - len);
        for f in self.f64_fields_mut() {
            if let Some(extra) = room(f.capacity(), f.len()) {
                f.reserve_exact(extra);
            }
        }
        if let Some(extra) = room(self.id.capacity(), self.id.len()) {
            self.id.reserve_exact(extra);
        }
        if let Some(extra) = room(self.nc.capacity(), self.nc.len()) {
            self.nc.reserve_exact(extra);
        }
    }

    /// Returns the memory of arrays that hold more than their particles
    /// (e.g. after [`keep`](Self::keep) of a share of a larger set).
    pub fn shrink_to_fit(&mut self) {
        for f in self.f64_fields_mut() {
            f.shrink_to_fit();
        }
        self.id.shrink_to_fit();
        self.nc.shrink_to_fit();
    }

    /// Checks that every array holds one entry per particle and that the
    /// optional fields `needed` are present.
    ///
    /// # Errors
    /// [`CoreError::Invalid`](crate::CoreError::Invalid) naming the first
    /// array of the wrong length, or the missing field.
    pub fn check(&self, needed: FieldSet) -> Result<(), crate::CoreError> {
        let n = self.len();
        let mut lens = vec![
            ("id", self.id.len()),
            ("y", self.y.len()),
            ("z", self.z.len()),
            ("vx", self.vx.len()),
            ("vy", self.vy.len()),
            ("vz", self.vz.len()),
            ("dx", self.dx.len()),
            ("dy", self.dy.len()),
            ("dz", self.dz.len()),
            ("h", self.h.len()),
            ("m", self.m.len()),
            ("u", self.u.len()),
            ("rho", self.rho.len()),
            ("p", self.p.len()),
            ("c", self.c.len()),
            ("ax", self.ax.len()),
            ("ay", self.ay.len()),
            ("az", self.az.len()),
            ("du", self.du.len()),
            ("du_prev", self.du_prev.len()),
            ("nc", self.nc.len()),
        ];
        let optional = [
            ("omega (grad-h)", &self.omega, needed.grad_h),
            ("phi (self-gravity)", &self.phi, needed.gravity),
            ("alpha (viscosity switches)", &self.alpha, self.alpha_on),
        ];
        for (name, v, on) in optional {
            if on || !v.is_empty() {
                lens.push((name, v.len()));
            }
        }
        for (k, c) in self.iad.iter().enumerate() {
            if needed.iad || !c.is_empty() {
                lens.push((
                    ["iad xx", "iad xy", "iad xz", "iad yy", "iad yz", "iad zz"][k],
                    c.len(),
                ));
            }
        }
        for (name, l) in lens {
            if l != n {
                return Err(crate::CoreError::Invalid(format!(
                    "field {name} has {l} entries for {n} particles (x has {n}); build the particles with the run's FieldSet"
                )));
            }
        }
        Ok(())
    }
}

/// Fields of the integrator's history (see `Particles::history`).
const HISTORY_FIELDS: usize = 4;

/// The f64 fields of [`Particles::fields_by_kind_mut`].
struct FieldsByKind<'a> {
    halo: Vec<&'a mut Vec<f64>>,
    history: Vec<&'a mut Vec<f64>>,
    recomputed: Vec<(&'a mut Vec<f64>, f64)>,
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
        1 + self.carried(true).count()
    }

    fn pack(&self, i: usize, out: &mut Vec<u64>) {
        out.push(self.id[i]);
        out.extend(self.carried(true).map(|f| f[i].to_bits()));
    }

    fn push_packed(&mut self, words: &[u64]) {
        self.push_words(words, false);
    }

    fn halo_words(&self) -> usize {
        self.packed_words() - HISTORY_FIELDS
    }

    fn pack_halo(&self, i: usize, out: &mut Vec<u64>) {
        out.push(self.id[i]);
        out.extend(self.carried(false).map(|f| f[i].to_bits()));
    }

    fn pack_halos(&self, idx: &[u32], out: &mut Vec<u64>) {
        let fields: Vec<&[f64]> = self.carried(false).map(Vec::as_slice).collect();
        out.reserve(idx.len() * (1 + fields.len()));
        for &i in idx {
            let i = i as usize;
            out.push(self.id[i]);
            out.extend(fields.iter().map(|f| f[i].to_bits()));
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
        let FieldsByKind {
            halo,
            history,
            recomputed,
        } = self.fields_by_kind_mut();
        for (k, f) in halo.into_iter().enumerate() {
            f.extend(rows().map(|r| f64::from_bits(r[1 + k])));
        }
        for f in history {
            f.resize(n, 0.0);
        }
        for (f, fill) in recomputed {
            f.resize(n, fill);
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
        for f in self.f64_fields_mut() {
            place_tail(
                f,
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
