//! Gas particles in the SWIFT / GADGET HDF5 layout: [`read_swift`] reads
//! initial-condition files and snapshots that SWIFT, GADGET, swiftsimio or
//! h5py wrote; [`write_swift`] writes SWIFT's snapshot layout, which SWIFT
//! reads as initial conditions and swiftsimio loads.
//!
//! # Layout
//!
//! | group / dataset | read | written |
//! | --- | --- | --- |
//! | `Header` attrs `BoxSize` | scalar (cube) or 3 numbers, finite, > 0 | 3 f64 |
//! | `NumPart_ThisFile`, `NumPart_Total`, `NumPart_Total_HighWord` | integers per type (6, or 7 in newer SWIFT); HighWord optional | i64 x 6, u32 x 6 (low words), u32 x 6 |
//! | `MassTable` | optional; entry 0 gives the masses when `Masses` is absent | 6 zeros |
//! | `Time` | optional (0 when absent) | 1 f64 |
//! | `Flag_Entropy_ICs` | optional; must be 0 | 1 i32, 0 |
//! | `NumFilesPerSnapshot` | optional (1 when absent); above 1 the pieces are read | 1 i32, 1 |
//! | `Dimension` | optional (3 when absent); must be 3 | 1 i32, 3 |
//! | `Redshift`, `Scale-factor` | optional; must be 0 and 1 | 1 f64 each, 0 and 1 |
//! | `Units` attrs `Unit length / mass / time / current / temperature in cgs (U_L / U_M / U_t / U_I / U_T)` | optional, all five if the group is there | all five, 1 f64 each |
//! | `PartType0/Coordinates`, `Velocities` | N x 3, f32 or f64 | N x 3 f64 |
//! | `PartType0/Masses` | N, f32 or f64; or `MassTable[0]` | N f64 |
//! | `PartType0/SmoothingLengths` (snapshots) or `SmoothingLength` (ICs) | N, f32 or f64 | `SmoothingLengths`, N f64 |
//! | `PartType0/InternalEnergies` (snapshots) or `InternalEnergy` (ICs) | N, f32 or f64 | `InternalEnergies`, N f64 |
//! | `PartType0/ParticleIDs` | N, any integer type, none negative | N u64 |
//! | `PartType0/Densities`, `Pressures` | optional, N, f32 or f64 | N f64 where the particles have them |
//!
//! Every dataset written carries SWIFT's unit attributes (`U_M exponent`,
//! `U_L exponent`, `U_t exponent`, `U_I exponent`, `U_T exponent`,
//! `a-scale exponent`, `h-scale exponent`), so swiftsimio attaches units to
//! what it loads. Scalars are written as 1-element arrays, as SWIFT writes
//! them: swiftsimio reads `Time`, `Dimension` and every `Units` attribute as
//! `value[0]`, and fails on a true scalar. swiftsimio also requires the
//! `Units` group to hold exactly those five attributes, so the writer adds
//! none of its own there. Where both names of a quantity are present the
//! snapshot name is read; [`SwiftHeader`] says which was.
//!
//! Checked by hand (not in the tests, which need only Rust): a written
//! file loads in swiftsimio 12.4.0 with its time, box, units and every
//! dataset with its units, and in h5py 3.7 (libhdf5 1.10.8). An IC file
//! written the way SWIFT's example scripts write them (scalar attributes,
//! like `tests/data/swift_ics_64.hdf5`) reads here and in SWIFT, but not in
//! swiftsimio, which indexes `Time` and the units as arrays.
//!
//! # Conventions a caller converts
//!
//! **Smoothing length.** `h` is read and written *as stored*, in the
//! convention of the file. SWIFT's `h` (Dehnen & Aly 2012; `kernel_hydro.h`)
//! is twice the kernel's standard deviation, `h = 2 sigma` with `sigma^2 =
//! <r^2> / 3` under the kernel, and its compact support is at `H =
//! kernel_gamma * h`, `kernel_gamma` depending on the kernel
//! ([`SwiftKernel::gamma`]: 1.825742 for SWIFT's cubic spline in 3-D; the
//! tests recompute every `kernel_gamma` from the kernel's shape). This
//! code's kernels (`sph-kernels`) have their support at `2h`. The same
//! kernel function (same support) therefore has
//!
//! ```text
//! h_ours = h_swift * kernel_gamma / 2      (SwiftKernel::to_sph_exa_h)
//! h_swift = h_ours * 2 / kernel_gamma
//! ```
//!
//! (0.912871 for the cubic spline). SWIFT's M4, M5, M6 and Wendland kernels
//! have the shapes of ours of the same name, so this is the exact
//! conversion for them. For a kernel SWIFT has not (our sinc family),
//! [`swift_h_per_h`] gives `2 sigma / h` of any shape of ours by
//! quadrature, `h_swift = h_ours * swift_h_per_h(shape)`: that keeps the
//! kernel's width (its standard deviation) rather than its support; for the
//! kernels SWIFT has, both agree (`swift_h_per_h = 2 / kernel_gamma`).
//! A snapshot names its kernel in `HydroScheme/Kernel function`
//! ([`SwiftHeader::kernel`]); an IC file does not, and SWIFT's default is
//! the cubic spline. GADGET-2 stores the support radius itself as its
//! `SmoothingLength`: `h_ours = h_gadget / 2` ([`GADGET_TO_SPH_EXA_H`]).
//! SWIFT iterates every `h` to its neighbour target on its first step, so a
//! wrong factor in an IC file costs iterations, not accuracy; in a snapshot
//! read for analysis it matters.
//!
//! **Box.** SWIFT and GADGET boxes are `[0, BoxSize)` on each axis; this
//! code's cases mostly use centred boxes `[-L/2, L/2)`. Positions are read
//! and written as given, not wrapped or checked against the box: shift
//! them with [`SwiftParticles::shift`] (or [`SwiftParticles::centre`] /
//! [`SwiftParticles::uncentre`] for the centred convention) before writing
//! and after reading. Periodicity is not in the layout (SWIFT takes it from
//! its parameter file).
//!
//! **Units.** Values are in the file's units and are not converted; the
//! `Units` group (cgs value of each base unit) is returned where present,
//! and written as 1.0 each (code units = cgs, as SWIFT's readers expect to
//! find the group) unless the particles carry their own.
//!
//! # What is refused
//!
//! Each by its own [`IoError`] variant, naming the file, what was found and
//! what is read instead; never a panic:
//!
//! * particles of other types: `NumPart_ThisFile` or `NumPart_Total` non-zero
//!   beyond entry 0, or any `PartTypeK` group with `K != 0`
//!   ([`IoError::SwiftOtherTypes`]);
//! * cosmological files: a `Cosmology` group whose `Cosmological run` is
//!   non-zero, or a `Header` `Redshift` other than 0 or `Scale-factor`
//!   other than 1 ([`IoError::SwiftCosmological`]). Comoving positions,
//!   peculiar velocities and `a`-scaled energies would need the expansion
//!   history to convert; a non-cosmological GADGET file without `Redshift`
//!   reads;
//! * `Flag_Entropy_ICs` non-zero: entropy instead of internal energy
//!   ([`IoError::SwiftEntropy`]);
//! * a snapshot in `K > 1` files whose pieces `NAME.0.hdf5` ..
//!   `NAME.(K-1).hdf5` are not all there, or disagree
//!   ([`IoError::SwiftMultiFile`]); when they are, they are read in order and
//!   concatenated;
//! * a missing `Header` attribute ([`IoError::BadAttribute`]) or dataset
//!   ([`IoError::MissingField`], step `PartType0`), a dataset of another
//!   length than `NumPart_ThisFile[0]` ([`IoError::WrongLength`]), a dataset
//!   claiming more bytes than the file has ([`IoError::BeyondFile`]);
//! * other shapes or types, `Dimension` other than 3, negative ids, counts
//!   that do not add up ([`IoError::SwiftLayout`]);
//! * NaN or infinite values in any dataset read or in `BoxSize`, `Time`,
//!   `MassTable[0]` or `Units` ([`IoError::NonFinite`]).
//!
//! Not checked: ids for uniqueness, positions against the box. Datasets
//! stored with compression filters (gzip, SWIFT's lossy filters) are not
//! read: the crate's HDF5 decoder is built without filters (`h5repack -f
//! NONE` removes them).
//!
//! # Example
//!
//! ```
//! use sph_io::swift::{read_swift, write_swift, SwiftKernel, SwiftParticles};
//!
//! # let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../target/tmp"))
//! #     .join(format!("sph-io-swift-doc-{}", std::process::id()));
//! # std::fs::create_dir_all(&dir)?;
//! let path = dir.join("gas.hdf5");
//!
//! // Two particles of a case in a centred box [-0.5, 0.5)^3, our h.
//! let mut gas = SwiftParticles {
//!     x: vec![-0.25, 0.25], y: vec![0.0, 0.1], z: vec![0.0, -0.1],
//!     vx: vec![0.0; 2], vy: vec![0.0; 2], vz: vec![1.0, -1.0],
//!     m: vec![0.5; 2], h: vec![0.1; 2], u: vec![1.5; 2], id: vec![1, 2],
//!     box_size: [1.0; 3],
//!     ..SwiftParticles::default()
//! };
//! // To SWIFT's conventions: box [0, 1), SWIFT's h for its cubic spline.
//! let k = SwiftKernel::CubicSpline;
//! gas.uncentre();
//! gas.scale_h(1.0 / k.to_sph_exa_h());
//! write_swift(&path, &gas)?;
//!
//! let back = read_swift(&path)?;
//! assert_eq!(back.particles.x, vec![0.25, 0.75]);
//! assert_eq!(back.header.h_dataset, "SmoothingLengths");
//! assert_eq!(back.header.num_part_total[0], 2);
//! // And back to ours.
//! let mut ours = back.particles;
//! ours.centre();
//! ours.scale_h(k.to_sph_exa_h());
//! assert_eq!(ours.x, vec![-0.25, 0.25]);
//! assert!((ours.h[0] - 0.1).abs() < 1e-15);
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use hdf5_pure::{AttrValue, DType, FileBuilder, Group};

use crate::error::IoError;
use crate::h5part;

/// The header group.
pub const HEADER: &str = "Header";
/// The units group.
pub const UNITS: &str = "Units";
/// The gas group.
pub const GAS: &str = "PartType0";

/// Names of the five `Units` attributes, in the order of [`SwiftUnits`]'
/// fields: length, mass, time, current, temperature.
pub const UNIT_NAMES: [&str; 5] = [
    "Unit length in cgs (U_L)",
    "Unit mass in cgs (U_M)",
    "Unit time in cgs (U_t)",
    "Unit current in cgs (U_I)",
    "Unit temperature in cgs (U_T)",
];

/// `h_ours = h_gadget * GADGET_TO_SPH_EXA_H`: GADGET-2's `SmoothingLength` is
/// its kernel's support radius, ours is at `2h`.
pub const GADGET_TO_SPH_EXA_H: f64 = 0.5;

/// SWIFT's SPH kernels (`src/kernel_hydro.h`), for the smoothing-length
/// conversion (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SwiftKernel {
    /// Cubic spline (M4), SWIFT's default.
    CubicSpline,
    /// Quartic spline (M5).
    QuarticSpline,
    /// Quintic spline (M6).
    QuinticSpline,
    /// Wendland C2.
    WendlandC2,
    /// Wendland C4.
    WendlandC4,
    /// Wendland C6.
    WendlandC6,
}

impl SwiftKernel {
    /// Every kernel.
    pub const ALL: [SwiftKernel; 6] = [
        SwiftKernel::CubicSpline,
        SwiftKernel::QuarticSpline,
        SwiftKernel::QuinticSpline,
        SwiftKernel::WendlandC2,
        SwiftKernel::WendlandC4,
        SwiftKernel::WendlandC6,
    ];

    /// SWIFT's `kernel_gamma` in 3-D: the kernel's support over SWIFT's `h`,
    /// `H / h` (the values of `kernel_hydro.h`, which SWIFT rounds to f32).
    pub const fn gamma(self) -> f64 {
        match self {
            SwiftKernel::CubicSpline => 1.825742,
            SwiftKernel::QuarticSpline => 2.018932,
            SwiftKernel::QuinticSpline => 2.195775,
            SwiftKernel::WendlandC2 => 1.936492,
            SwiftKernel::WendlandC4 => 2.207940,
            SwiftKernel::WendlandC6 => 2.449490,
        }
    }

    /// `h_ours = h_swift * to_sph_exa_h()`: `gamma / 2`, the factor that keeps
    /// the kernel's support (ours is at `2h`, SWIFT's at `gamma * h`).
    /// Divide by it to go back.
    pub const fn to_sph_exa_h(self) -> f64 {
        self.gamma() / 2.0
    }

    /// SWIFT's name of the kernel, as in a snapshot's
    /// `HydroScheme/Kernel function`.
    pub const fn swift_name(self) -> &'static str {
        match self {
            SwiftKernel::CubicSpline => "Cubic spline (M4)",
            SwiftKernel::QuarticSpline => "Quartic spline (M5)",
            SwiftKernel::QuinticSpline => "Quintic spline (M6)",
            SwiftKernel::WendlandC2 => "Wendland C2",
            SwiftKernel::WendlandC4 => "Wendland C4",
            SwiftKernel::WendlandC6 => "Wendland C6",
        }
    }

    /// The kernel SWIFT names `name` ([`swift_name`](Self::swift_name);
    /// surrounding blanks ignored).
    pub fn from_swift_name(name: &str) -> Option<SwiftKernel> {
        let name = name.trim_matches(|c: char| c.is_whitespace() || c == '\0');
        Self::ALL.into_iter().find(|k| k.swift_name() == name)
    }
}

/// SWIFT's `h` for a kernel of this code with `h = 1`: twice the kernel's
/// standard deviation, `2 sigma` with `sigma^2 = (1/3) * integral of r^2 W
/// d^3r`, for the dimensionless shape `shape(v)`, `v = r / h`, of support
/// `v < 2` (`sph_kernels::Kernel::shape`; the normalisation cancels).
/// `h_swift = h_ours * swift_h_per_h(shape)`; for a kernel SWIFT has this
/// is `2 / kernel_gamma` ([`SwiftKernel::to_sph_exa_h`] is its inverse).
///
/// Composite Simpson quadrature over 4096 intervals: relative error below
/// 1e-9 for the built-in kernels.
pub fn swift_h_per_h(shape: impl Fn(f64) -> f64) -> f64 {
    const STEPS: usize = 4096;
    let dv = 2.0 / STEPS as f64;
    let (mut m0, mut m2) = (0.0, 0.0);
    for i in 0..=STEPS {
        let v = i as f64 * dv;
        let weight = if i == 0 || i == STEPS {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let w = weight * shape(v) * v * v;
        m0 += w;
        m2 += w * v * v;
    }
    2.0 * (m2 / m0 / 3.0).sqrt()
}

/// The cgs value of each base unit of a file (its `Units` group).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwiftUnits {
    /// `Unit length in cgs (U_L)`.
    pub length: f64,
    /// `Unit mass in cgs (U_M)`.
    pub mass: f64,
    /// `Unit time in cgs (U_t)`.
    pub time: f64,
    /// `Unit current in cgs (U_I)`.
    pub current: f64,
    /// `Unit temperature in cgs (U_T)`.
    pub temperature: f64,
}

impl SwiftUnits {
    /// Every unit 1.0 (code units are cgs): what [`write_swift`] writes for
    /// particles without units.
    pub const ONES: SwiftUnits = SwiftUnits {
        length: 1.0,
        mass: 1.0,
        time: 1.0,
        current: 1.0,
        temperature: 1.0,
    };

    fn values(&self) -> [f64; 5] {
        [
            self.length,
            self.mass,
            self.time,
            self.current,
            self.temperature,
        ]
    }
}

impl Default for SwiftUnits {
    fn default() -> Self {
        SwiftUnits::ONES
    }
}

/// Gas particles as structure of arrays, with the box, the time and the
/// units: what [`write_swift`] writes and [`read_swift`] returns. Values are
/// in the file's conventions (see the [module docs](self)).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SwiftParticles {
    /// Positions (`Coordinates`).
    pub x: Vec<f64>,
    /// Positions.
    pub y: Vec<f64>,
    /// Positions.
    pub z: Vec<f64>,
    /// Velocities (`Velocities`).
    pub vx: Vec<f64>,
    /// Velocities.
    pub vy: Vec<f64>,
    /// Velocities.
    pub vz: Vec<f64>,
    /// Masses (`Masses`, or `MassTable[0]` on read).
    pub m: Vec<f64>,
    /// Smoothing lengths in the file's convention (`SmoothingLengths` or
    /// `SmoothingLength`).
    pub h: Vec<f64>,
    /// Specific internal energies (`InternalEnergies` or `InternalEnergy`).
    pub u: Vec<f64>,
    /// Ids (`ParticleIDs`).
    pub id: Vec<u64>,
    /// Densities (`Densities`), where present.
    pub rho: Option<Vec<f64>>,
    /// Pressures (`Pressures`), where present.
    pub p: Option<Vec<f64>>,
    /// The box `[0, box_size[k])` on each axis (`Header/BoxSize`).
    pub box_size: [f64; 3],
    /// The time (`Header/Time`).
    pub time: f64,
    /// The `Units` group, where present (written as [`SwiftUnits::ONES`]
    /// when `None`).
    pub units: Option<SwiftUnits>,
}

impl SwiftParticles {
    /// Number of particles (the length of `x`).
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Adds `by` to every position.
    pub fn shift(&mut self, by: [f64; 3]) {
        for (v, d) in [&mut self.x, &mut self.y, &mut self.z].into_iter().zip(by) {
            v.iter_mut().for_each(|a| *a += d);
        }
    }

    /// From SWIFT's `[0, L)` to the centred `[-L/2, L/2)`: shifts every
    /// position by `-box_size / 2`.
    pub fn centre(&mut self) {
        self.shift(self.box_size.map(|l| -0.5 * l));
    }

    /// From the centred `[-L/2, L/2)` to SWIFT's `[0, L)`: shifts every
    /// position by `+box_size / 2`.
    pub fn uncentre(&mut self) {
        self.shift(self.box_size.map(|l| 0.5 * l));
    }

    /// Multiplies every smoothing length by `factor` (for the conventions,
    /// [`SwiftKernel::to_sph_exa_h`], [`GADGET_TO_SPH_EXA_H`]).
    pub fn scale_h(&mut self, factor: f64) {
        self.h.iter_mut().for_each(|h| *h *= factor);
    }

    /// The float arrays with the datasets they are written to and their
    /// lengths checked against `x`.
    fn checked_columns(&self, path: &Path) -> Result<(), IoError> {
        let n = self.x.len();
        let lens = [
            ("y", self.y.len()),
            ("z", self.z.len()),
            ("vx", self.vx.len()),
            ("vy", self.vy.len()),
            ("vz", self.vz.len()),
            ("m", self.m.len()),
            ("h", self.h.len()),
            ("u", self.u.len()),
            ("id", self.id.len()),
            ("rho", self.rho.as_ref().map_or(n, Vec::len)),
            ("p", self.p.as_ref().map_or(n, Vec::len)),
        ];
        for (field, found) in lens {
            if found != n {
                return Err(IoError::LengthMismatch {
                    field: field.to_owned(),
                    expected: n,
                    found,
                });
            }
        }
        let columns: [(&str, &[f64]); 11] = [
            ("Coordinates", &self.x),
            ("Coordinates", &self.y),
            ("Coordinates", &self.z),
            ("Velocities", &self.vx),
            ("Velocities", &self.vy),
            ("Velocities", &self.vz),
            ("Masses", &self.m),
            ("SmoothingLengths", &self.h),
            ("InternalEnergies", &self.u),
            ("Densities", self.rho.as_deref().unwrap_or(&[])),
            ("Pressures", self.p.as_deref().unwrap_or(&[])),
        ];
        for (k, (name, v)) in columns.iter().enumerate() {
            // Row-major index in the N x 3 datasets.
            let (stride, col) = if k < 6 { (3, k as u64 % 3) } else { (1, 0) };
            finite(path, &format!("{GAS}/{name}"), v.iter().copied(), |i| {
                i * stride + col
            })?;
        }
        let b = self.box_size;
        finite(path, "Header/BoxSize", b.iter().copied(), |i| i)?;
        if b.iter().any(|&l| l <= 0.0) {
            return Err(IoError::SwiftLayout {
                path: path.to_owned(),
                found: format!("BoxSize {b:?}"),
                allowed: "a positive box size on every axis".to_owned(),
            });
        }
        finite(path, "Header/Time", [self.time], |i| i)?;
        if let Some(u) = &self.units {
            check_units(path, u)?;
        }
        Ok(())
    }
}

/// What the header of a file said, beyond what [`SwiftParticles`] holds.
#[derive(Debug, Clone, PartialEq)]
pub struct SwiftHeader {
    /// `NumPart_Total` with `NumPart_Total_HighWord` (`low + high << 32`),
    /// per type: entry 0 is the gas particle count, the others are 0.
    pub num_part_total: Vec<u64>,
    /// `NumFilesPerSnapshot` (1 where absent).
    pub num_files: u64,
    /// The files read, in order (one unless `num_files > 1`).
    pub files: Vec<PathBuf>,
    /// Gas particles in each file read (`NumPart_ThisFile[0]`), in order.
    pub num_part_per_file: Vec<u64>,
    /// `MassTable` (empty where absent).
    pub mass_table: Vec<f64>,
    /// Whether the masses came from `MassTable[0]` (no `Masses` dataset).
    pub masses_from_table: bool,
    /// `Dimension`, where present (always 3: others are refused).
    pub dimension: Option<u64>,
    /// `Redshift`, where present (always 0: others are refused).
    pub redshift: Option<f64>,
    /// `Scale-factor`, where present (always 1: others are refused).
    pub scale_factor: Option<f64>,
    /// The smoothing-length dataset read: `SmoothingLengths` or
    /// `SmoothingLength` (empty without gas).
    pub h_dataset: &'static str,
    /// The internal-energy dataset read: `InternalEnergies` or
    /// `InternalEnergy` (empty without gas).
    pub u_dataset: &'static str,
    /// `HydroScheme/Kernel function` as written, where present (snapshots).
    pub kernel_name: Option<String>,
    /// The kernel it names, where it is one of SWIFT's.
    pub kernel: Option<SwiftKernel>,
}

/// A file (or a snapshot of several files) read by [`read_swift`].
#[derive(Debug, Clone, PartialEq)]
pub struct SwiftFile {
    /// The gas particles, box, time and units.
    pub particles: SwiftParticles,
    /// The header's other facts.
    pub header: SwiftHeader,
}

/// Whether `path` is an HDF5 file with a `Header` group: a SWIFT/GADGET
/// file, to tell a caller trying several layouts whose error to report.
/// False for anything unreadable.
pub fn looks_like_swift(path: &Path) -> bool {
    h5part::open(path)
        .ok()
        .and_then(|file| h5part::guard(path, None, None, || file.root().groups()).ok())
        .is_some_and(|groups| groups.iter().any(|g| g == HEADER))
}

/// Reads the gas particles of a SWIFT/GADGET file at `path` (IC or snapshot
/// names, any float type, any integer id type). A snapshot in `K > 1`
/// files is read from `NAME.0.hdf5` .. `NAME.(K-1).hdf5` (`path` is any one
/// of them) and concatenated in that order.
///
/// # Errors
/// Everything the [module docs](self#what-is-refused) list, each naming the
/// file; an unreadable or non-HDF5 file as for the other readers.
pub fn read_swift(path: &Path) -> Result<SwiftFile, IoError> {
    let first = read_piece(path)?;
    let k = first.num_files;
    if k <= 1 {
        let this = first.this_file_gas;
        if first.total[0] != this {
            return Err(IoError::SwiftLayout {
                path: path.to_owned(),
                found: format!(
                    "NumPart_Total[0] = {} but NumPart_ThisFile[0] = {this} in a snapshot of one file",
                    first.total[0]
                ),
                allowed: "NumPart_Total[0] equal to NumPart_ThisFile[0] when NumFilesPerSnapshot is 1".to_owned(),
            });
        }
        return Ok(first.into_file(vec![path.to_owned()], vec![this]));
    }
    let multi = |found: String| IoError::SwiftMultiFile {
        path: path.to_owned(),
        found,
    };
    let pieces = piece_paths(path, k).ok_or_else(|| {
        multi(format!(
            "NumFilesPerSnapshot = {k} but the name is not of the form NAME.I.EXT"
        ))
    })?;
    // The first piece's arrays move into the result when its turn comes;
    // what stays is its header, compared with every piece's.
    let mut first = first;
    let meta_only = SwiftParticles {
        box_size: first.p.box_size,
        time: first.p.time,
        units: first.p.units,
        ..SwiftParticles::default()
    };
    let mut first_particles = Some(std::mem::replace(&mut first.p, meta_only));
    let mut out = first.clone();
    let (mut rho, mut pressure) = (Vec::new(), Vec::new());
    let (mut with_rho, mut with_p) = (None::<bool>, None::<bool>);
    let mut per_file = Vec::new();
    let mut files = Vec::new();
    let mut gas = 0u64;
    for piece_path in pieces {
        let piece_path = &piece_path;
        let mut piece = if piece_path == path && first_particles.is_some() {
            let mut piece = first.clone();
            piece.p = first_particles.take().unwrap_or_default();
            piece
        } else {
            if !piece_path.exists() {
                return Err(multi(format!(
                    "piece {} of {k} is missing",
                    piece_path.display()
                )));
            }
            read_piece(piece_path)?
        };
        let disagree = |what: &str| {
            multi(format!(
                "piece {} differs from {} in {what}",
                piece_path.display(),
                path.display()
            ))
        };
        if piece.num_files != k {
            return Err(disagree("NumFilesPerSnapshot"));
        }
        if piece.total != first.total {
            return Err(disagree("NumPart_Total"));
        }
        if piece.p.box_size.map(f64::to_bits) != first.p.box_size.map(f64::to_bits) {
            return Err(disagree("BoxSize"));
        }
        if piece.p.time.to_bits() != first.p.time.to_bits() {
            return Err(disagree("Time"));
        }
        if piece
            .mass_table
            .iter()
            .map(|m| m.to_bits())
            .ne(first.mass_table.iter().map(|m| m.to_bits()))
        {
            return Err(disagree("MassTable"));
        }
        per_file.push(piece.this_file_gas);
        files.push(piece_path.clone());
        gas = gas.saturating_add(piece.this_file_gas);
        if piece.this_file_gas > 0 {
            out.masses_from_table |= piece.masses_from_table;
            out.h_name = piece.h_name;
            out.u_name = piece.u_name;
            for (all, has, mine, name) in [
                (&mut rho, &mut with_rho, piece.p.rho.take(), "Densities"),
                (&mut pressure, &mut with_p, piece.p.p.take(), "Pressures"),
            ] {
                if *has.get_or_insert(mine.is_some()) != mine.is_some() {
                    return Err(multi(format!(
                        "{name} in some pieces only (not in {})",
                        piece_path.display()
                    )));
                }
                all.extend(mine.unwrap_or_default());
            }
        }
        let o = &mut out.p;
        let q = piece.p;
        o.x.extend(q.x);
        o.y.extend(q.y);
        o.z.extend(q.z);
        o.vx.extend(q.vx);
        o.vy.extend(q.vy);
        o.vz.extend(q.vz);
        o.m.extend(q.m);
        o.h.extend(q.h);
        o.u.extend(q.u);
        o.id.extend(q.id);
    }
    if gas != first.total[0] {
        return Err(multi(format!(
            "the pieces hold {gas} gas particles (NumPart_ThisFile[0] per piece: {per_file:?}) but NumPart_Total[0] = {}",
            first.total[0]
        )));
    }
    out.p.rho = with_rho.unwrap_or(false).then_some(rho);
    out.p.p = with_p.unwrap_or(false).then_some(pressure);
    Ok(out.into_file(files, per_file))
}

/// Writes `gas` as a SWIFT snapshot (one file, layout in the
/// [module docs](self)) to `path`, through `NAME.tmp` renamed once complete.
///
/// # Errors
/// Arrays of different lengths ([`IoError::LengthMismatch`]), a NaN or
/// infinite value ([`IoError::NonFinite`]), a box size not positive or
/// units not positive ([`IoError::SwiftLayout`]), and I/O errors.
pub fn write_swift(path: &Path, gas: &SwiftParticles) -> Result<(), IoError> {
    gas.checked_columns(path)?;
    let n = gas.len();
    let n64 = n as u64;
    let mut b = FileBuilder::new();

    let mut hd = b.create_group(HEADER);
    let mut counts = [0u64; 6];
    counts[0] = n64;
    let one_f = |x: f64| AttrValue::F64Array(vec![x]);
    let one_i = |x: i32| AttrValue::I32Array(vec![x]);
    hd.set_attr("BoxSize", AttrValue::F64Array(gas.box_size.to_vec()));
    hd.set_attr(
        "NumPart_ThisFile",
        AttrValue::I64Array(counts.iter().map(|&c| c as i64).collect()),
    );
    hd.set_attr(
        "NumPart_Total",
        AttrValue::U32Array(counts.iter().map(|&c| c as u32).collect()),
    );
    hd.set_attr(
        "NumPart_Total_HighWord",
        AttrValue::U32Array(counts.iter().map(|&c| (c >> 32) as u32).collect()),
    );
    hd.set_attr("MassTable", AttrValue::F64Array(vec![0.0; 6]));
    hd.set_attr("Time", one_f(gas.time));
    hd.set_attr("Redshift", one_f(0.0));
    hd.set_attr("Scale-factor", one_f(1.0));
    hd.set_attr("Dimension", one_i(3));
    hd.set_attr("NumFilesPerSnapshot", one_i(1));
    hd.set_attr("Flag_Entropy_ICs", one_i(0));
    b.add_group(hd.finish());

    let mut ug = b.create_group(UNITS);
    for (name, v) in UNIT_NAMES
        .iter()
        .zip(gas.units.unwrap_or(SwiftUnits::ONES).values())
    {
        ug.set_attr(name, one_f(v));
    }
    b.add_group(ug.finish());

    let mut g = b.create_group(GAS);
    let interleave = |a: &[f64], b: &[f64], c: &[f64]| {
        let mut v = Vec::with_capacity(3 * n);
        for i in 0..n {
            v.extend_from_slice(&[a[i], b[i], c[i]]);
        }
        v
    };
    // (name, data, [U_M, U_L, U_t] exponents, a-scale exponent), as SWIFT
    // writes them.
    let vectors: [(&str, Vec<f64>, [f32; 3], f32); 2] = [
        (
            "Coordinates",
            interleave(&gas.x, &gas.y, &gas.z),
            [0., 1., 0.],
            1.,
        ),
        (
            "Velocities",
            interleave(&gas.vx, &gas.vy, &gas.vz),
            [0., 1., -1.],
            0.,
        ),
    ];
    for (name, data, dims, a) in &vectors {
        let ds = g.create_dataset(name);
        ds.with_f64_data(data).with_shape(&[n64, 3]);
        unit_attrs(ds, *dims, *a);
    }
    // (name, data, [U_M, U_L, U_t] exponents, a-scale exponent).
    let scalars = [
        ("Masses", Some(&gas.m[..]), [1., 0., 0.], 0.),
        ("SmoothingLengths", Some(&gas.h[..]), [0., 1., 0.], 1.),
        ("InternalEnergies", Some(&gas.u[..]), [0., 2., -2.], -2.),
        ("Densities", gas.rho.as_deref(), [1., -3., 0.], -3.),
        ("Pressures", gas.p.as_deref(), [1., -1., -2.], -5.),
    ];
    for (name, data, dims, a) in scalars {
        if let Some(data) = data {
            let ds = g.create_dataset(name);
            ds.with_f64_data(data);
            unit_attrs(ds, dims, a);
        }
    }
    let ds = g.create_dataset("ParticleIDs");
    ds.with_u64_data(&gas.id);
    unit_attrs(ds, [0.; 3], 0.);
    b.add_group(g.finish());

    h5part::write_atomic(path, None, |file| {
        let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
        b.finish_to(&mut w)
            .map_err(|e| h5part::encoder_error(path, e))?;
        w.flush().map_err(|source| IoError::Io {
            path: h5part::tmp_path(path),
            source,
        })
    })
}

/// SWIFT's unit attributes of a dataset: base-unit exponents (mass, length,
/// time; current and temperature 0) and the expansion-factor exponent.
fn unit_attrs(ds: &mut hdf5_pure::DatasetBuilder, [m, l, t]: [f32; 3], a: f32) {
    let one = |x: f32| AttrValue::F32Array(vec![x]);
    ds.set_attr("U_M exponent", one(m))
        .set_attr("U_L exponent", one(l))
        .set_attr("U_t exponent", one(t))
        .set_attr("U_I exponent", one(0.0))
        .set_attr("U_T exponent", one(0.0))
        .set_attr("a-scale exponent", one(a))
        .set_attr("h-scale exponent", one(0.0));
}

/// One file of a snapshot.
#[derive(Clone)]
struct Piece {
    p: SwiftParticles,
    num_files: u64,
    total: Vec<u64>,
    this_file_gas: u64,
    mass_table: Vec<f64>,
    masses_from_table: bool,
    dimension: Option<u64>,
    redshift: Option<f64>,
    scale_factor: Option<f64>,
    h_name: &'static str,
    u_name: &'static str,
    kernel_name: Option<String>,
}

impl Piece {
    fn into_file(self, files: Vec<PathBuf>, per_file: Vec<u64>) -> SwiftFile {
        SwiftFile {
            particles: self.p,
            header: SwiftHeader {
                num_part_total: self.total,
                num_files: self.num_files.max(1),
                files,
                num_part_per_file: per_file,
                mass_table: self.mass_table,
                masses_from_table: self.masses_from_table,
                dimension: self.dimension,
                redshift: self.redshift,
                scale_factor: self.scale_factor,
                h_dataset: self.h_name,
                u_dataset: self.u_name,
                kernel: self
                    .kernel_name
                    .as_deref()
                    .and_then(SwiftKernel::from_swift_name),
                kernel_name: self.kernel_name,
            },
        }
    }
}

/// `NAME.0.EXT` .. `NAME.(k-1).EXT` for a `path` named `NAME.I.EXT`, `None`
/// for another name.
fn piece_paths(path: &Path, k: u64) -> Option<impl Iterator<Item = PathBuf> + '_> {
    let name = path.file_name()?.to_str()?;
    let (rest, ext) = name.rsplit_once('.')?;
    let (stem, index) = rest.rsplit_once('.')?;
    if stem.is_empty() || index.is_empty() || !index.bytes().all(|c| c.is_ascii_digit()) {
        return None;
    }
    // Lazily: a forged count ends at the first missing piece, having
    // allocated nothing for the pieces it claims.
    Some((0..k).map(move |i| path.with_file_name(format!("{stem}.{i}.{ext}"))))
}

/// Refuses the first non-finite value of `values` (the attribute or dataset
/// `field`; `index` maps a position in `values` to the file's order).
fn finite(
    path: &Path,
    field: &str,
    values: impl IntoIterator<Item = f64>,
    index: impl Fn(u64) -> u64,
) -> Result<(), IoError> {
    match values.into_iter().enumerate().find(|(_, v)| !v.is_finite()) {
        None => Ok(()),
        Some((i, value)) => Err(IoError::NonFinite {
            path: path.to_owned(),
            field: field.to_owned(),
            index: index(i as u64),
            value,
        }),
    }
}

fn check_units(path: &Path, u: &SwiftUnits) -> Result<(), IoError> {
    for (name, v) in UNIT_NAMES.iter().zip(u.values()) {
        finite(path, &format!("{UNITS}/{name}"), [v], |i| i)?;
        if v <= 0.0 {
            return Err(IoError::SwiftLayout {
                path: path.to_owned(),
                found: format!("{UNITS}/{name} = {v}"),
                allowed: "positive unit values".to_owned(),
            });
        }
    }
    Ok(())
}

/// Numbers of an attribute (floats, or integers converted).
fn numbers(v: &AttrValue) -> Option<Vec<f64>> {
    v.to_f64s()
        .or_else(|| {
            v.to_i64s()
                .map(|v| v.into_iter().map(|x| x as f64).collect())
        })
        .or_else(|| {
            v.to_u64s()
                .map(|v| v.into_iter().map(|x| x as f64).collect())
        })
}

/// Attribute access for one group, with errors naming it.
struct Attrs<'a> {
    path: &'a Path,
    group: &'static str,
    map: HashMap<String, AttrValue>,
}

impl Attrs<'_> {
    fn bad(&self, attr: &str, what: &str) -> IoError {
        IoError::BadAttribute {
            path: self.path.to_owned(),
            step: self.group.to_owned(),
            attr: attr.to_owned(),
            what: what.to_owned(),
        }
    }

    /// Non-negative integers (scalar or array), `None` when absent.
    fn ints(&self, name: &str) -> Result<Option<Vec<u64>>, IoError> {
        match self.map.get(name) {
            None => Ok(None),
            Some(v) => match v.to_u64s() {
                Some(v) if !v.is_empty() => Ok(Some(v)),
                _ => Err(self.bad(
                    name,
                    &format!("not non-negative integers ({})", v.type_name()),
                )),
            },
        }
    }

    /// Finite numbers (scalar or array), `None` when absent.
    fn floats(&self, name: &str) -> Result<Option<Vec<f64>>, IoError> {
        match self.map.get(name) {
            None => Ok(None),
            Some(v) => match numbers(v) {
                Some(x) if !x.is_empty() => {
                    finite(
                        self.path,
                        &format!("{}/{name}", self.group),
                        x.iter().copied(),
                        |i| i,
                    )?;
                    Ok(Some(x))
                }
                _ => Err(self.bad(name, &format!("not numbers ({})", v.type_name()))),
            },
        }
    }

    /// One finite number (scalar or 1-element array), `None` when absent.
    fn float(&self, name: &str) -> Result<Option<f64>, IoError> {
        match self.floats(name)? {
            None => Ok(None),
            Some(v) if v.len() == 1 => Ok(Some(v[0])),
            Some(v) => Err(self.bad(name, &format!("{} values, expected 1", v.len()))),
        }
    }

    /// One non-negative integer (scalar or 1-element array), `None` when absent.
    fn int(&self, name: &str) -> Result<Option<u64>, IoError> {
        match self.ints(name)? {
            None => Ok(None),
            Some(v) if v.len() == 1 => Ok(Some(v[0])),
            Some(v) => Err(self.bad(name, &format!("{} values, expected 1", v.len()))),
        }
    }
}

fn group_attrs<'a>(
    path: &'a Path,
    file: &hdf5_pure::File,
    group: &'static str,
) -> Result<Attrs<'a>, IoError> {
    let g = h5part::guard(path, Some(group), None, || file.group(group))?;
    let map = h5part::guard(path, Some(group), None, || g.attrs())?;
    Ok(Attrs { path, group, map })
}

/// Reads one file: header checks, then the gas datasets.
fn read_piece(path: &Path) -> Result<Piece, IoError> {
    let file = h5part::open(path)?;
    let file_len = h5part::file_len(path)?;
    let groups = h5part::guard(path, None, None, || file.root().groups())?;
    let layout = |found: String, allowed: &str| IoError::SwiftLayout {
        path: path.to_owned(),
        found,
        allowed: allowed.to_owned(),
    };
    if !groups.iter().any(|g| g == HEADER) {
        return Err(layout(
            "no group 'Header'".to_owned(),
            "SWIFT/GADGET files (groups Header and PartType0)",
        ));
    }
    // Cosmology first: a cosmological file is refused as that, whatever
    // else it holds.
    if groups.iter().any(|g| g == "Cosmology") {
        let c = group_attrs(path, &file, "Cosmology")?;
        if let Some(v) = c.map.get("Cosmological run") {
            match numbers(v) {
                Some(x) if x.iter().all(|&f| f == 0.0) => {}
                _ => {
                    return Err(IoError::SwiftCosmological {
                        path: path.to_owned(),
                        found: format!("Cosmology/Cosmological run = {v:?}"),
                    })
                }
            }
        }
    }
    let h = group_attrs(path, &file, HEADER)?;
    let redshift = h.float("Redshift")?;
    let scale_factor = h.float("Scale-factor")?;
    for (name, v, ok) in [
        ("Redshift", redshift, 0.0),
        ("Scale-factor", scale_factor, 1.0),
    ] {
        if let Some(v) = v.filter(|&v| v != ok) {
            return Err(IoError::SwiftCosmological {
                path: path.to_owned(),
                found: format!("Header/{name} = {v}"),
            });
        }
    }
    let required = |v: Option<Vec<u64>>, name: &str| v.ok_or_else(|| h.bad(name, "missing"));
    let this_file = required(h.ints("NumPart_ThisFile")?, "NumPart_ThisFile")?;
    let low = required(h.ints("NumPart_Total")?, "NumPart_Total")?;
    let high = h.ints("NumPart_Total_HighWord")?.unwrap_or_default();
    let mut total = Vec::with_capacity(low.len());
    for (k, &lo) in low.iter().enumerate() {
        let hi = high.get(k).copied().unwrap_or(0);
        let t = (hi < (1 << 32))
            .then(|| lo.checked_add(hi << 32))
            .flatten()
            .ok_or_else(|| h.bad("NumPart_Total_HighWord", "count beyond 64 bits"))?;
        total.push(t);
    }
    for (name, counts) in [("NumPart_ThisFile", &this_file), ("NumPart_Total", &total)] {
        if let Some(k) = counts.iter().skip(1).position(|&c| c != 0) {
            return Err(IoError::SwiftOtherTypes {
                path: path.to_owned(),
                found: format!(
                    "Header/{name} = {counts:?} ({} of type {})",
                    counts[k + 1],
                    k + 1
                ),
            });
        }
    }
    if let Some(g) = groups
        .iter()
        .find(|g| g.starts_with("PartType") && g.as_str() != GAS)
    {
        return Err(IoError::SwiftOtherTypes {
            path: path.to_owned(),
            found: format!("group '{g}'"),
        });
    }
    if let Some(flags) = h.ints("Flag_Entropy_ICs")? {
        if flags.iter().any(|&f| f != 0) {
            return Err(IoError::SwiftEntropy {
                path: path.to_owned(),
                found: if flags.len() == 1 {
                    flags[0].to_string()
                } else {
                    format!("{flags:?}")
                },
            });
        }
    }
    let dimension = h.int("Dimension")?;
    if let Some(d) = dimension.filter(|&d| d != 3) {
        return Err(layout(
            format!("Header/Dimension = {d}"),
            "3-D files only (Dimension 3)",
        ));
    }
    let num_files = h.int("NumFilesPerSnapshot")?.unwrap_or(1);
    let bs = h
        .floats("BoxSize")?
        .ok_or_else(|| h.bad("BoxSize", "missing"))?;
    let box_size = match bs.as_slice() {
        [l] => [*l; 3],
        [a, b, c] => [*a, *b, *c],
        _ => return Err(h.bad("BoxSize", &format!("{} values, expected 1 or 3", bs.len()))),
    };
    if box_size.iter().any(|&l| l <= 0.0) {
        return Err(h.bad("BoxSize", &format!("{box_size:?} not positive")));
    }
    let time = h.float("Time")?.unwrap_or(0.0);
    let mass_table = h.floats("MassTable")?.unwrap_or_default();
    let table_mass = mass_table.first().copied().unwrap_or(0.0);

    let units = if groups.iter().any(|g| g == UNITS) {
        let u = group_attrs(path, &file, UNITS)?;
        let mut v = [0.0; 5];
        for (slot, name) in v.iter_mut().zip(UNIT_NAMES) {
            *slot = u.float(name)?.ok_or_else(|| u.bad(name, "missing"))?;
        }
        let units = SwiftUnits {
            length: v[0],
            mass: v[1],
            time: v[2],
            current: v[3],
            temperature: v[4],
        };
        check_units(path, &units)?;
        Some(units)
    } else {
        None
    };
    let kernel_name = if groups.iter().any(|g| g == "HydroScheme") {
        group_attrs(path, &file, "HydroScheme")?
            .map
            .get("Kernel function")
            .and_then(|v| v.as_str().map(|s| s.trim_end_matches('\0').to_owned()))
    } else {
        None
    };

    let n = this_file[0];
    let mut piece = Piece {
        p: SwiftParticles {
            box_size,
            time,
            units,
            ..SwiftParticles::default()
        },
        num_files,
        total,
        this_file_gas: n,
        mass_table,
        masses_from_table: false,
        dimension,
        redshift,
        scale_factor,
        h_name: "",
        u_name: "",
        kernel_name,
    };
    if !groups.iter().any(|g| g == GAS) {
        if n == 0 {
            return Ok(piece);
        }
        return Err(layout(
            format!("NumPart_ThisFile[0] = {n} but no group '{GAS}'"),
            "the gas particles in group PartType0",
        ));
    }
    let g = h5part::guard(path, Some(GAS), None, || file.group(GAS))?;
    let names = h5part::guard(path, Some(GAS), None, || g.datasets())?;
    let has = |name: &str| names.iter().any(|d| d == name);
    let pick = |a: &'static str, b: &'static str| {
        [a, b]
            .into_iter()
            .find(|d| has(d))
            .ok_or_else(|| IoError::MissingField {
                path: path.to_owned(),
                step: GAS.to_owned(),
                field: format!("{a}' (or '{b}"),
            })
    };
    let rd = Reader {
        path,
        g: &g,
        names: &names,
        n,
        file_len,
    };
    let p = &mut piece.p;
    let xyz = rd.floats("Coordinates", 3)?;
    let v = rd.floats("Velocities", 3)?;
    [p.x, p.y, p.z] = split3(&xyz);
    drop(xyz);
    [p.vx, p.vy, p.vz] = split3(&v);
    drop(v);
    if has("Masses") {
        p.m = rd.floats("Masses", 1)?;
    } else {
        let m = table_mass;
        if m <= 0.0 && n > 0 {
            return Err(layout(
                format!("no dataset '{GAS}/Masses' and MassTable[0] = {m}"),
                "masses from a Masses dataset or a positive MassTable[0]",
            ));
        }
        p.m = vec![m; p.x.len()];
        piece.masses_from_table = true;
    }
    piece.h_name = pick("SmoothingLengths", "SmoothingLength")?;
    piece.u_name = pick("InternalEnergies", "InternalEnergy")?;
    p.h = rd.floats(piece.h_name, 1)?;
    p.u = rd.floats(piece.u_name, 1)?;
    p.id = rd.ids("ParticleIDs")?;
    p.rho = if has("Densities") {
        Some(rd.floats("Densities", 1)?)
    } else {
        None
    };
    p.p = if has("Pressures") {
        Some(rd.floats("Pressures", 1)?)
    } else {
        None
    };
    Ok(piece)
}

fn split3(v: &[f64]) -> [Vec<f64>; 3] {
    let n = v.len() / 3;
    let mut out = [
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    ];
    for row in v.chunks_exact(3) {
        for (o, &x) in out.iter_mut().zip(row) {
            o.push(x);
        }
    }
    out
}

/// Reads the datasets of one `PartType0` group, of `n` rows each.
struct Reader<'a> {
    path: &'a Path,
    g: &'a Group,
    names: &'a [String],
    n: u64,
    file_len: u64,
}

impl Reader<'_> {
    /// The dataset `name` after checks of presence, shape (`n` rows of
    /// `cols`; `cols` 1 is a 1-D dataset) and size against the file.
    fn open(&self, name: &str, cols: u64) -> Result<(hdf5_pure::Dataset, DType), IoError> {
        let path = self.path;
        if !self.names.iter().any(|d| d == name) {
            return Err(IoError::MissingField {
                path: path.to_owned(),
                step: GAS.to_owned(),
                field: name.to_owned(),
            });
        }
        let at = (Some(GAS), Some(name));
        let ds = h5part::guard(path, at.0, at.1, || self.g.dataset(name))?;
        let shape = h5part::guard(path, at.0, at.1, || ds.shape())?;
        let want: &[u64] = if cols == 1 {
            &[self.n]
        } else {
            &[self.n, cols]
        };
        let shape_ok = shape.len() == want.len() && shape[1..] == want[1..];
        if !shape_ok {
            let dims = if cols == 1 { "N" } else { "N x 3" };
            return Err(IoError::SwiftLayout {
                path: path.to_owned(),
                found: format!("{GAS}/{name} of shape {shape:?}"),
                allowed: format!("{name} as {dims}"),
            });
        }
        if shape[0] != self.n {
            return Err(IoError::WrongLength {
                path: path.to_owned(),
                step: GAS.to_owned(),
                field: name.to_owned(),
                expected: self.n,
                found: shape[0],
            });
        }
        let size = h5part::guard(path, at.0, at.1, || ds.element_size())?;
        let count = self.n.saturating_mul(cols);
        let size32 = u32::try_from(size).unwrap_or(u32::MAX);
        h5part::check_claim(path, GAS, name, count, size32, self.file_len)?;
        let dtype = h5part::guard(path, at.0, at.1, || ds.dtype())?;
        Ok((ds, dtype))
    }

    /// `n x cols` f32/f64 values as f64 (row-major), all finite.
    fn floats(&self, name: &str, cols: u64) -> Result<Vec<f64>, IoError> {
        let (ds, dtype) = self.open(name, cols)?;
        if !matches!(dtype, DType::F32 | DType::F64) {
            return Err(IoError::SwiftLayout {
                path: self.path.to_owned(),
                found: format!("{GAS}/{name} of type {dtype}"),
                allowed: format!("{name} as f32 or f64"),
            });
        }
        let v = h5part::guard(self.path, Some(GAS), Some(name), || ds.read_f64())?;
        self.check_len(name, v.len() as u64, cols)?;
        finite(
            self.path,
            &format!("{GAS}/{name}"),
            v.iter().copied(),
            |i| i,
        )?;
        Ok(v)
    }

    /// `n` non-negative integers of any integer type.
    fn ids(&self, name: &str) -> Result<Vec<u64>, IoError> {
        let (ds, dtype) = self.open(name, 1)?;
        let at = (Some(GAS), Some(name));
        let v = match dtype {
            DType::U8 | DType::U16 | DType::U32 | DType::U64 => {
                h5part::guard(self.path, at.0, at.1, || ds.read_u64())?
            }
            DType::I8 | DType::I16 | DType::I32 | DType::I64 => {
                let v = h5part::guard(self.path, at.0, at.1, || ds.read_i64())?;
                if let Some((row, x)) = v.iter().enumerate().find(|(_, x)| **x < 0) {
                    return Err(IoError::SwiftLayout {
                        path: self.path.to_owned(),
                        found: format!("{GAS}/{name} row {row} = {x}"),
                        allowed: "non-negative ids".to_owned(),
                    });
                }
                v.into_iter().map(|x| x as u64).collect()
            }
            other => {
                return Err(IoError::SwiftLayout {
                    path: self.path.to_owned(),
                    found: format!("{GAS}/{name} of type {other}"),
                    allowed: format!("{name} as integers"),
                })
            }
        };
        self.check_len(name, v.len() as u64, 1)?;
        Ok(v)
    }

    fn check_len(&self, name: &str, values: u64, cols: u64) -> Result<(), IoError> {
        if values != self.n * cols {
            return Err(IoError::WrongLength {
                path: self.path.to_owned(),
                step: GAS.to_owned(),
                field: name.to_owned(),
                expected: self.n,
                found: values / cols,
            });
        }
        Ok(())
    }
}
