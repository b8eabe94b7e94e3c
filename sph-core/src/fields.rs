//! The particle field table: every per-particle array of
//! [`Particles`] declared once, with what it is.
//!
//! Each [`Field`] says its name in snapshots and checkpoints, its type, its
//! [`Kind`] (what migration, halos, the space-filling-curve reordering and
//! checkpoints do with it) and the condition ([`Needs`]) under which a run
//! holds it. Storage, migration and halo packing, reordering, bytes per
//! particle, the length check, and the checkpoint and snapshot field lists
//! are all derived from [`FIELDS`]: declaring a new persistent field is one
//! `Vec` in [`Particles`] and one entry in the table, both in this file.
//!
//! ```
//! use sph_core::fields::{self, Kind, Needs};
//! use sph_core::{FieldSet, Particles};
//!
//! // What a checkpoint stores: the id, the persistent state and the
//! // integrator's history, where the run holds them.
//! let p = Particles::new(3, FieldSet::default());
//! let names: Vec<&str> = fields::checkpointed(p.fields()).map(|f| f.name).collect();
//! assert_eq!(&names[..4], &["id", "x", "y", "z"]);
//! assert!(names.contains(&"du_prev") && !names.contains(&"alpha"));
//!
//! // Each field once, found by its name.
//! let rho = fields::find("rho").unwrap();
//! assert!(matches!(rho.kind, Kind::Derived { .. }) && rho.needs == Needs::Always);
//! assert_eq!(rho.f64(&p).unwrap().len(), 3);
//! ```

/// What a field is, which decides where it travels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// The particle's identity (`id`): migrates, travels with halos,
    /// checkpointed, reordered with the particle.
    Identity,
    /// State carried from one step to the next: migrates, travels with
    /// halos, checkpointed.
    Persistent,
    /// The integrator's history, set and read for owned particles only:
    /// migrates and is checkpointed, but halos arrive with zeros.
    History,
    /// Recomputed every step before it is read: neither sent nor
    /// checkpointed; a particle that arrives (or is reordered by the
    /// domain's sort) gets `fill`.
    Derived {
        /// The value of an arriving particle.
        fill: f64,
    },
    /// Under block time steps, a derived field that inactive particles
    /// keep until their own step recomputes it, because active neighbours
    /// read it: it travels and is checkpointed as [`Kind::Persistent`]
    /// state. A field is `Held` only where its run holds
    /// [`FieldSet::block`] ([`kind`] resolves it).
    Held {
        /// The value of a new particle.
        fill: f64,
    },
}

/// The condition under which a run holds a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Needs {
    /// Every run.
    Always,
    /// IAD gradients (the inverse IAD matrix).
    Iad,
    /// Grad-h terms (the Omega factor).
    GradH,
    /// Self-gravity (the potential).
    Gravity,
    /// Artificial-viscosity switches (the per-particle strength alpha).
    Switches,
    /// An equation of state with a per-particle reference state
    /// ([`Eos::TaitReferenced`](crate::Eos)).
    ReferencedEos,
    /// Block (individual) time steps: the particle's time bin.
    BlockSteps,
    /// Block time steps with viscosity switches: the velocity divergence
    /// inactive neighbours hold.
    BlockSwitches,
    /// Block time steps with generalised or pressure-energy volumes: the
    /// volume elements inactive neighbours hold.
    BlockVolumes,
    /// Block time steps with the Balsara limiter: the limited viscosity
    /// strength inactive neighbours hold.
    BlockBalsara,
    /// Block time steps with viscosity cleaning: the velocity gradients
    /// inactive neighbours hold.
    BlockCleaning,
    /// Block time steps with turbulence driving: the stirring
    /// acceleration each particle keeps over its step (its work accrues
    /// as the particle drifts).
    BlockStirring,
}

/// Which optional fields a run holds (one flag per [`Needs`] condition
/// other than [`Needs::Always`]). It grows with the table: build one from
/// `Default` (or [`Scheme::fields`](crate::Scheme::fields)) and set flags.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub struct FieldSet {
    /// The 6 components of the inverse IAD matrix.
    pub iad: bool,
    /// The grad-h factor Omega.
    pub grad_h: bool,
    /// The gravitational potential (self-gravity runs).
    pub gravity: bool,
    /// The per-particle viscosity strength (AV switches).
    pub alpha: bool,
    /// The reference density and pressure of a referenced EOS.
    pub eos_ref: bool,
    /// Block time steps: the time bin, and the derived fields inactive
    /// particles hold ([`Kind::Held`]).
    pub block: bool,
    /// Volume elements other than `m / rho` (generalised or
    /// pressure-energy volumes): held fields under block time steps.
    pub volumes: bool,
    /// The Balsara limiter: its strengths are held under block time steps.
    pub balsara: bool,
    /// Viscosity cleaning: its velocity gradients are held under block
    /// time steps.
    pub cleaning: bool,
    /// Turbulence driving: each particle's stirring acceleration is kept
    /// over its step under block time steps.
    pub stirring: bool,
}

impl FieldSet {
    /// No optional field: plain kernel gradients, no grad-h, nothing else.
    pub const NONE: FieldSet = FieldSet {
        iad: false,
        grad_h: false,
        gravity: false,
        alpha: false,
        eos_ref: false,
        block: false,
        volumes: false,
        balsara: false,
        cleaning: false,
        stirring: false,
    };
}

impl Default for FieldSet {
    /// IAD and grad-h on (the paper's scheme), nothing else.
    fn default() -> Self {
        Self {
            iad: true,
            grad_h: true,
            gravity: false,
            alpha: false,
            eos_ref: false,
            block: false,
            volumes: false,
            balsara: false,
            cleaning: false,
            stirring: false,
        }
    }
}

impl FieldSet {
    /// Whether a run with these flags holds fields that need `needs`.
    pub fn holds(&self, needs: Needs) -> bool {
        match needs {
            Needs::Always => true,
            Needs::Iad => self.iad,
            Needs::GradH => self.grad_h,
            Needs::Gravity => self.gravity,
            Needs::Switches => self.alpha,
            Needs::ReferencedEos => self.eos_ref,
            Needs::BlockSteps => self.block,
            Needs::BlockSwitches => self.block && self.alpha,
            Needs::BlockVolumes => self.block && self.volumes,
            Needs::BlockBalsara => self.block && self.balsara,
            Needs::BlockCleaning => self.block && self.cleaning,
            Needs::BlockStirring => self.block && self.stirring,
        }
    }

    /// The union of two sets (a field held by either).
    pub fn union(self, other: FieldSet) -> FieldSet {
        FieldSet {
            iad: self.iad || other.iad,
            grad_h: self.grad_h || other.grad_h,
            gravity: self.gravity || other.gravity,
            alpha: self.alpha || other.alpha,
            eos_ref: self.eos_ref || other.eos_ref,
            block: self.block || other.block,
            volumes: self.volumes || other.volumes,
            balsara: self.balsara || other.balsara,
            cleaning: self.cleaning || other.cleaning,
            stirring: self.stirring || other.stirring,
        }
    }
}

/// Read access to a field's array.
pub type Get<T> = fn(&Particles) -> &Vec<T>;
/// Write access to a field's array.
pub type GetMut<T> = fn(&mut Particles) -> &mut Vec<T>;

/// A field's array and its element type.
#[derive(Debug, Clone, Copy)]
pub enum Column {
    /// 64-bit floats (every physical quantity).
    F64(Get<f64>, GetMut<f64>),
    /// 64-bit unsigned integers (the id).
    U64(Get<u64>, GetMut<u64>),
    /// 32-bit unsigned integers (the neighbour count).
    U32(Get<u32>, GetMut<u32>),
}

/// One per-particle field.
#[derive(Debug, Clone, Copy)]
pub struct Field {
    /// Name in snapshots, checkpoints and `--snapshot-fields`.
    pub name: &'static str,
    /// The SWIFT/GADGET-layout dataset (`PartType0/...`) and component
    /// that holds the same quantity, where there is one (names only: unit
    /// and convention differences are the reader's and writer's business).
    pub swift: Option<(&'static str, u8)>,
    /// What the field is.
    pub kind: Kind,
    /// When a run holds it.
    pub needs: Needs,
    /// Its array.
    pub column: Column,
    /// One line for listings.
    pub doc: &'static str,
    /// A derived field that block time steps hold for inactive particles
    /// ([`Kind::Held`]).
    pub held_when_block: bool,
}

impl Field {
    /// The field's `f64` array, `None` for the integer fields.
    pub fn f64<'a>(&self, p: &'a Particles) -> Option<&'a Vec<f64>> {
        match self.column {
            Column::F64(get, _) => Some(get(p)),
            _ => None,
        }
    }

    /// The field's `f64` array for writing, `None` for the integer fields.
    pub fn f64_mut<'a>(&self, p: &'a mut Particles) -> Option<&'a mut Vec<f64>> {
        match self.column {
            Column::F64(_, get) => Some(get(p)),
            _ => None,
        }
    }

    /// The number of entries the field's array holds.
    pub fn len(&self, p: &Particles) -> usize {
        match self.column {
            Column::F64(get, _) => get(p).len(),
            Column::U64(get, _) => get(p).len(),
            Column::U32(get, _) => get(p).len(),
        }
    }

    /// Bytes per particle of the field's array.
    pub fn bytes(&self) -> usize {
        match self.column {
            Column::F64(..) | Column::U64(..) => 8,
            Column::U32(..) => 4,
        }
    }

    /// Whether the field is stored in checkpoints of a run with `set`
    /// (identity, persistent state, integrator history and, under block
    /// time steps, the held fields: what a restart needs to continue to
    /// the bit).
    pub fn checkpointed(&self, set: FieldSet) -> bool {
        matches!(
            kind(self, set),
            Kind::Identity | Kind::Persistent | Kind::History | Kind::Held { .. }
        )
    }
}

/// What `field` is in a run with `set`: its declared kind, except that a
/// derived field marked `held_when_block` is [`Kind::Held`] under block
/// time steps.
pub fn kind(field: &Field, set: FieldSet) -> Kind {
    match field.kind {
        Kind::Derived { fill } if set.block && field.held_when_block => Kind::Held { fill },
        k => k,
    }
}

macro_rules! field {
    ($name:literal, $swift:expr, $kind:expr, $needs:expr, $ty:ident, $($path:tt)+) => {
        Field {
            name: $name,
            swift: $swift,
            kind: $kind,
            needs: $needs,
            column: Column::$ty(|p| &p.$($path)+, |p| &mut p.$($path)+),
            doc: "",
            held_when_block: false,
        }
    };
}

const fn doc(mut f: Field, doc: &'static str) -> Field {
    f.doc = doc;
    f
}

/// Marks a derived field that inactive particles hold under block time
/// steps (their active neighbours read it).
const fn kept_by_blocks(mut f: Field) -> Field {
    f.held_when_block = true;
    f
}

use Kind::{History, Identity, Persistent};
use Needs::{
    Always, BlockBalsara, BlockCleaning, BlockSteps, BlockStirring, BlockSwitches, BlockVolumes,
    GradH, Gravity, Iad, ReferencedEos, Switches,
};

const DERIVED: Kind = Kind::Derived { fill: 0.0 };

/// All particles of one rank, one array per field: the storage of the
/// table below ([`FIELDS`]), whose entries reach these arrays; its
/// operations are in `particles.rs`.
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
    /// are on: [`FieldSet::alpha`]).
    pub alpha: Vec<f64>,
    /// Per-particle reference density and pressure of
    /// [`Eos::TaitReferenced`](crate::Eos) (empty otherwise); a zero
    /// density is calibrated from the first density evaluation.
    pub eos_ref: [Vec<f64>; 2],
    /// Neighbour count of the last search (self included), for the h update.
    pub nc: Vec<u32>,
    /// Time bin of the particle's current step under block time steps
    /// (an exact small integer; empty in global runs).
    pub bin: Vec<f64>,
    /// `d ln rho / dt` over the particle's last step under block time
    /// steps, which predicts its density while it is inactive (empty in
    /// global runs).
    pub dlnrho: Vec<f64>,
    /// Velocity divergence, held for inactive neighbours (block time
    /// steps with viscosity switches; global runs keep it in the
    /// pipeline's step buffers).
    pub div_v: Vec<f64>,
    /// Volume element `X` and its normalisation `k`, held for inactive
    /// neighbours (block time steps with generalised or pressure-energy
    /// volumes; global runs keep them in the step buffers).
    pub xm: Vec<f64>,
    /// The normalisation `k` of the volume elements (as `xm`).
    pub kx: Vec<f64>,
    /// The Balsara-limited viscosity strength, held for inactive
    /// neighbours (block time steps with the limiter; global runs keep it
    /// in the step buffers).
    pub alpha_eff: Vec<f64>,
    /// The symmetric velocity gradient `G_xx, G_xy, G_xz, G_yy, G_yz,
    /// G_zz` of viscosity cleaning, held for inactive neighbours (block
    /// time steps with cleaning; global runs keep it in the step buffers).
    pub grad_v: [Vec<f64>; 6],
    /// The stirring acceleration the particle got at the start of its
    /// step, kept over the step (block time steps with turbulence
    /// driving; global runs keep it in the step buffers).
    pub stir_a: [Vec<f64>; 3],
    /// The optional fields held (on every rank alike, even one that holds
    /// no particles right now, so that messages agree).
    pub(crate) fields: FieldSet,
    /// Block time steps: the next sort may reset the held fields (all but
    /// `rho`) instead of moving them, because every particle recomputes
    /// them before they are read (a sub-step where all are active).
    pub(crate) held_recomputed: bool,
}

/// Every per-particle field, in the order of snapshot listings; migration
/// and halo messages pack the sent fields in this order too, checkpoints
/// store theirs in it.
#[rustfmt::skip]
pub const FIELDS: &[Field] = &[
    doc(field!("id", Some(("ParticleIDs", 0)), Identity, Always, U64, id), "unique particle id"),
    doc(field!("x", Some(("Coordinates", 0)), Persistent, Always, F64, x), "position"),
    doc(field!("y", Some(("Coordinates", 1)), Persistent, Always, F64, y), "position"),
    doc(field!("z", Some(("Coordinates", 2)), Persistent, Always, F64, z), "position"),
    doc(field!("vx", Some(("Velocities", 0)), Persistent, Always, F64, vx), "velocity"),
    doc(field!("vy", Some(("Velocities", 1)), Persistent, Always, F64, vy), "velocity"),
    doc(field!("vz", Some(("Velocities", 2)), Persistent, Always, F64, vz), "velocity"),
    doc(field!("h", Some(("SmoothingLengths", 0)), Persistent, Always, F64, h), "smoothing length"),
    doc(field!("m", Some(("Masses", 0)), Persistent, Always, F64, m), "mass"),
    doc(field!("u", Some(("InternalEnergies", 0)), Persistent, Always, F64, u), "specific internal energy"),
    doc(field!("dx", None, History, Always, F64, dx), "position change of the last step"),
    doc(field!("dy", None, History, Always, F64, dy), "position change of the last step"),
    doc(field!("dz", None, History, Always, F64, dz), "position change of the last step"),
    doc(field!("du_prev", None, History, Always, F64, du_prev), "du/dt of the previous step"),
    doc(field!("alpha", Some(("ViscosityParameters", 0)), Persistent, Switches, F64, alpha), "artificial-viscosity strength"),
    doc(field!("rho0", None, Persistent, ReferencedEos, F64, eos_ref[0]), "reference density of the referenced EOS (0: from the first density)"),
    doc(field!("p0", None, Persistent, ReferencedEos, F64, eos_ref[1]), "reference pressure of the referenced EOS"),
    doc(field!("bin", None, Persistent, BlockSteps, F64, bin), "time bin of the particle's step (block time steps)"),
    doc(field!("dlnrho", None, Persistent, BlockSteps, F64, dlnrho), "d ln rho / dt over the particle's last step (block time steps)"),
    doc(field!("stir_ax", None, History, BlockStirring, F64, stir_a[0]), "stirring acceleration over the particle's step, x (block time steps, driving)"),
    doc(field!("stir_ay", None, History, BlockStirring, F64, stir_a[1]), "stirring acceleration over the particle's step, y (block time steps, driving)"),
    doc(field!("stir_az", None, History, BlockStirring, F64, stir_a[2]), "stirring acceleration over the particle's step, z (block time steps, driving)"),
    kept_by_blocks(doc(field!("div_v", None, DERIVED, BlockSwitches, F64, div_v), "velocity divergence (block time steps with switches)")),
    kept_by_blocks(doc(field!("xm", None, DERIVED, BlockVolumes, F64, xm), "volume element X (block time steps, generalised volumes)")),
    kept_by_blocks(doc(field!("kx", None, DERIVED, BlockVolumes, F64, kx), "volume normalisation k (block time steps, generalised volumes)")),
    kept_by_blocks(doc(field!("alpha_eff", None, DERIVED, BlockBalsara, F64, alpha_eff), "Balsara-limited viscosity strength (block time steps)")),
    kept_by_blocks(doc(field!("gv_xx", None, DERIVED, BlockCleaning, F64, grad_v[0]), "velocity gradient, xx (block time steps, viscosity cleaning)")),
    kept_by_blocks(doc(field!("gv_xy", None, DERIVED, BlockCleaning, F64, grad_v[1]), "velocity gradient, symmetric xy (block time steps, viscosity cleaning)")),
    kept_by_blocks(doc(field!("gv_xz", None, DERIVED, BlockCleaning, F64, grad_v[2]), "velocity gradient, symmetric xz (block time steps, viscosity cleaning)")),
    kept_by_blocks(doc(field!("gv_yy", None, DERIVED, BlockCleaning, F64, grad_v[3]), "velocity gradient, yy (block time steps, viscosity cleaning)")),
    kept_by_blocks(doc(field!("gv_yz", None, DERIVED, BlockCleaning, F64, grad_v[4]), "velocity gradient, symmetric yz (block time steps, viscosity cleaning)")),
    kept_by_blocks(doc(field!("gv_zz", None, DERIVED, BlockCleaning, F64, grad_v[5]), "velocity gradient, zz (block time steps, viscosity cleaning)")),
    kept_by_blocks(doc(field!("rho", Some(("Densities", 0)), DERIVED, Always, F64, rho), "density")),
    kept_by_blocks(doc(field!("p", Some(("Pressures", 0)), DERIVED, Always, F64, p), "pressure")),
    kept_by_blocks(doc(field!("c", Some(("SoundSpeeds", 0)), DERIVED, Always, F64, c), "sound speed")),
    kept_by_blocks(doc(field!("ax", Some(("Accelerations", 0)), DERIVED, Always, F64, ax), "acceleration")),
    kept_by_blocks(doc(field!("ay", Some(("Accelerations", 1)), DERIVED, Always, F64, ay), "acceleration")),
    kept_by_blocks(doc(field!("az", Some(("Accelerations", 2)), DERIVED, Always, F64, az), "acceleration")),
    kept_by_blocks(doc(field!("du", None, DERIVED, Always, F64, du), "du/dt of this step")),
    doc(field!("nc", None, DERIVED, Always, U32, nc), "neighbour count of the last search (self included)"),
    kept_by_blocks(doc(field!("omega", None, Kind::Derived { fill: 1.0 }, GradH, F64, omega), "grad-h factor")),
    kept_by_blocks(doc(field!("phi", Some(("Potentials", 0)), DERIVED, Gravity, F64, phi), "gravitational potential per unit mass")),
    kept_by_blocks(doc(field!("c11", None, DERIVED, Iad, F64, iad[0]), "inverse IAD matrix, xx")),
    kept_by_blocks(doc(field!("c12", None, DERIVED, Iad, F64, iad[1]), "inverse IAD matrix, xy")),
    kept_by_blocks(doc(field!("c13", None, DERIVED, Iad, F64, iad[2]), "inverse IAD matrix, xz")),
    kept_by_blocks(doc(field!("c22", None, DERIVED, Iad, F64, iad[3]), "inverse IAD matrix, yy")),
    kept_by_blocks(doc(field!("c23", None, DERIVED, Iad, F64, iad[4]), "inverse IAD matrix, yz")),
    kept_by_blocks(doc(field!("c33", None, DERIVED, Iad, F64, iad[5]), "inverse IAD matrix, zz")),
];

/// The field called `name`.
pub fn find(name: &str) -> Option<&'static Field> {
    FIELDS.iter().find(|f| f.name == name)
}

/// The fields a run with `set` holds.
pub fn held(set: FieldSet) -> impl Iterator<Item = &'static Field> {
    FIELDS.iter().filter(move |f| set.holds(f.needs))
}

/// The fields a checkpoint of a run with `set` stores.
pub fn checkpointed(set: FieldSet) -> impl Iterator<Item = &'static Field> {
    held(set).filter(move |f| f.checkpointed(set))
}

/// The held `f64` fields a migrating particle carries (`history: true`)
/// or a halo carries (`false`: without the integrator's history), in
/// packing order.
pub(crate) fn sent(set: FieldSet, history: bool) -> impl Iterator<Item = &'static Field> {
    held(set).filter(move |f| {
        matches!(f.column, Column::F64(..))
            && match kind(f, set) {
                Persistent | Kind::Held { .. } => true,
                History => history,
                _ => false,
            }
    })
}

/// The held `f64` fields with the value an arriving particle gets: `None`
/// for the sent ones (taken from the message; a halo's history is 0),
/// `Some(fill)` for the derived ones.
pub(crate) fn f64_fields(set: FieldSet) -> impl Iterator<Item = (GetMut<f64>, Kind)> {
    f64_fields_named(set).map(|(_, get, kind)| (get, kind))
}

/// As [`f64_fields`], with each field's name.
pub(crate) fn f64_fields_named(
    set: FieldSet,
) -> impl Iterator<Item = (&'static str, GetMut<f64>, Kind)> {
    held(set).filter_map(move |f| match f.column {
        Column::F64(_, get) => Some((f.name, get, kind(f, set))),
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_is_unique_and_every_accessor_its_own_array() {
        let mut p = Particles::new(
            2,
            FieldSet {
                iad: true,
                grad_h: true,
                gravity: true,
                alpha: true,
                eos_ref: true,
                block: true,
                volumes: true,
                balsara: true,
                cleaning: true,
                stirring: true,
            },
        );
        for (k, f) in FIELDS.iter().enumerate() {
            assert!(
                FIELDS[k + 1..].iter().all(|g| g.name != f.name),
                "{} twice",
                f.name
            );
            assert_eq!(f.len(&p), 2, "{}", f.name);
            // Mark this field's array and check no other field sees it.
            if let Some(v) = f.f64_mut(&mut p) {
                v[1] = 1000.0 + k as f64;
            }
        }
        for (k, f) in FIELDS.iter().enumerate() {
            if let Some(v) = f.f64(&p) {
                assert_eq!(v[1], 1000.0 + k as f64, "{}", f.name);
            }
        }
    }

    #[test]
    fn the_table_covers_every_array_of_particles() {
        // Each `Vec` is 24 bytes; Particles adds the FieldSet (its flags,
        // padded to 8 bytes). A new array without a table entry fails here.
        let arrays = FIELDS.len();
        let flags = std::mem::size_of::<FieldSet>().next_multiple_of(8);
        assert_eq!(
            std::mem::size_of::<Particles>(),
            arrays * std::mem::size_of::<Vec<f64>>() + flags,
            "Particles has an array the field table does not list"
        );
    }

    #[test]
    fn a_set_holds_exactly_its_conditions() {
        let none = FieldSet::NONE;
        assert!(held(none).all(|f| f.needs == Needs::Always));
        let names: Vec<_> = held(FieldSet {
            alpha: true,
            ..none
        })
        .filter(|f| f.needs != Needs::Always)
        .map(|f| f.name)
        .collect();
        assert_eq!(names, ["alpha"]);
        let block: Vec<_> = held(FieldSet {
            block: true,
            ..none
        })
        .filter(|f| f.needs != Needs::Always)
        .map(|f| f.name)
        .collect();
        assert_eq!(block, ["bin", "dlnrho"]);
        // The stirring acceleration is kept only under block steps.
        for (block, kept) in [
            (false, &[][..]),
            (true, &["stir_ax", "stir_ay", "stir_az"][..]),
        ] {
            let stirred: Vec<_> = held(FieldSet {
                block,
                stirring: true,
                ..none
            })
            .filter(|f| !matches!(f.needs, Needs::Always | Needs::BlockSteps))
            .map(|f| f.name)
            .collect();
            assert_eq!(stirred, kept);
        }
        // A halo carries 4 words fewer than a migrating particle.
        let block = FieldSet {
            block: true,
            ..FieldSet::default()
        };
        for set in [none, FieldSet::default(), block] {
            assert_eq!(sent(set, true).count() - sent(set, false).count(), 4);
        }
    }

    fn names(fields: impl Iterator<Item = &'static Field>) -> Vec<&'static str> {
        fields.map(|f| f.name).collect()
    }

    /// Global runs send and checkpoint what they did before block time
    /// steps existed; block runs add the time bin and hold the derived
    /// fields active neighbours read.
    #[test]
    fn block_steps_hold_the_derived_fields_global_runs_recompute() {
        let global = FieldSet::default();
        let carried = ["x", "y", "z", "vx", "vy", "vz", "h", "m", "u"];
        let history = ["dx", "dy", "dz", "du_prev"];
        assert_eq!(names(sent(global, false)), carried);
        assert_eq!(
            names(sent(global, true)),
            [&carried[..], &history[..]].concat()
        );
        assert_eq!(
            names(checkpointed(global)),
            [&["id"][..], &carried[..], &history[..]].concat()
        );
        assert!(held(global).all(|f| kind(f, global) == f.kind));

        let block = FieldSet {
            block: true,
            ..global
        };
        let kept = [
            "rho", "p", "c", "ax", "ay", "az", "du", "omega", "c11", "c12", "c13", "c22", "c23",
            "c33",
        ];
        let halo = names(sent(block, false));
        assert_eq!(halo, [&carried[..], &["bin", "dlnrho"], &kept[..]].concat());
        for f in held(block) {
            let k = kind(f, block);
            assert_eq!(
                matches!(k, Kind::Held { .. }),
                kept.contains(&f.name),
                "{}",
                f.name
            );
            assert_eq!(f.checkpointed(block), f.name != "nc", "{}", f.name);
        }
        // Omega keeps its fill for a new particle.
        let omega = find("omega").unwrap();
        assert_eq!(kind(omega, block), Kind::Held { fill: 1.0 });
        // 16 words more per halo (bin, dlnrho and 14 held), 16 bytes
        // more per particle (bin, dlnrho).
        assert_eq!(sent(block, false).count(), sent(global, false).count() + 16);
        let bytes = |set| held(set).map(|f| f.bytes()).sum::<usize>();
        assert_eq!(bytes(block), bytes(global) + 16);
    }
}
