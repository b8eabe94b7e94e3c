//! The crate's error type.

use std::path::PathBuf;

use crate::field_type::FieldType;

/// Everything that can go wrong writing or reading a snapshot. Errors about a
/// file name the file and, where they apply, the step group and the field.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    /// An operating-system error on `path`.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is not an HDF5 file (another format, or a header destroyed).
    #[error("{}: not an HDF5 file", path.display())]
    NotHdf5 {
        /// The file.
        path: PathBuf,
    },
    /// The file is HDF5 but its structure could not be decoded (torn,
    /// truncated or corrupted), or the HDF5 encoder refused the data.
    #[error("{}: {}{what}", path.display(), at(step, field))]
    Format {
        /// The file.
        path: PathBuf,
        /// Step group, when the failure is inside one.
        step: Option<String>,
        /// Field, when the failure is inside one.
        field: Option<String>,
        /// What failed.
        what: String,
    },
    /// The file has no step group of this index.
    #[error("{}: no step group {step} (the file has {count})", path.display())]
    MissingStep {
        /// The file.
        path: PathBuf,
        /// The step group asked for, `Step#k`.
        step: String,
        /// How many step groups the file has.
        count: usize,
    },
    /// A field asked for (or listed in the step's field table) is absent.
    #[error("{}: {step}: missing field '{field}'", path.display())]
    MissingField {
        /// The file.
        path: PathBuf,
        /// The step group.
        step: String,
        /// The field.
        field: String,
    },
    /// A field is not of the length of the step's particle count.
    #[error("{}: {step}: field '{field}' has {found} values, expected {expected}", path.display())]
    WrongLength {
        /// The file.
        path: PathBuf,
        /// The step group.
        step: String,
        /// The field.
        field: String,
        /// The step's particle count.
        expected: u64,
        /// The field's length on disk.
        found: u64,
    },
    /// A dataset claims more values than the file has bytes for: a corrupt
    /// or hostile count, refused before anything is allocated for it.
    #[error(
        "{}: {step}: field '{field}' claims {count} values of {size} bytes, more than the file's {file_len} bytes",
        path.display()
    )]
    BeyondFile {
        /// The file.
        path: PathBuf,
        /// The step group.
        step: String,
        /// The field.
        field: String,
        /// The number of values the dataset's shape claims.
        count: u64,
        /// Bytes per value on disk.
        size: u32,
        /// The file's length in bytes.
        file_len: u64,
    },
    /// A field's element type on disk is not the one recorded for it (or not
    /// one this crate reads).
    #[error("{}: {step}: field '{field}' is of type {found}, expected {expected}", path.display())]
    WrongType {
        /// The file.
        path: PathBuf,
        /// The step group.
        step: String,
        /// The field.
        field: String,
        /// The expected type.
        expected: FieldType,
        /// What the file holds, as text.
        found: String,
    },
    /// A field's values do not match their stored checksum.
    #[error(
        "{}: {step}: field '{field}' fails its checksum (stored crc32 {stored:#010x}, computed {computed:#010x})",
        path.display()
    )]
    Checksum {
        /// The file.
        path: PathBuf,
        /// The step group.
        step: String,
        /// The field, or `<metadata>` for the step's metadata checksum.
        field: String,
        /// The stored checksum.
        stored: u32,
        /// The checksum of what was read.
        computed: u32,
    },
    /// A required step attribute is absent or of the wrong type/shape.
    #[error("{}: {step}: attribute '{attr}': {what}", path.display())]
    BadAttribute {
        /// The file.
        path: PathBuf,
        /// The step group.
        step: String,
        /// The attribute.
        attr: String,
        /// What is wrong with it.
        what: String,
    },
    /// A snapshot to write has fields of different lengths.
    #[error(
        "field '{field}' has {found} values, expected {expected} (the length of the first field)"
    )]
    LengthMismatch {
        /// The field.
        field: String,
        /// Length of the first field.
        expected: usize,
        /// Length of this one.
        found: usize,
    },
    /// A name is used twice among a snapshot's fields or attributes.
    #[error("duplicate name '{name}'")]
    DuplicateName {
        /// The name.
        name: String,
    },
    /// A name is empty or contains `/` or NUL.
    #[error("bad name '{name}': names must be non-empty, without '/' or NUL")]
    BadName {
        /// The name.
        name: String,
    },
    /// A user attribute uses a name the format reserves.
    #[error("attribute name '{name}' is reserved by the file format")]
    ReservedName {
        /// The name.
        name: String,
    },
    /// A field selected for writing is not in the snapshot.
    #[error("selected field '{field}' is not in the snapshot")]
    UnknownField {
        /// The field.
        field: String,
    },
    /// A value read or to be written is NaN or infinite.
    #[error("{}: {field}: element {index} is {value}; values must be finite", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// The dataset or attribute, as `GROUP/NAME` (`PartType0/Masses`,
        /// `Header/BoxSize`).
        field: String,
        /// Index of the first non-finite value, in file order (row-major
        /// for `N x 3` datasets: row `index / 3`, column `index % 3`).
        index: u64,
        /// The value.
        value: f64,
    },
    /// A SWIFT/GADGET file ([`crate::swift`]) whose structure this crate
    /// does not read: no `Header`, a dataset of another shape or type, a
    /// `Dimension` other than 3, negative ids, inconsistent counts, masses
    /// neither stored nor in `MassTable`.
    #[error("{}: {found}; sph-io reads {allowed}", path.display())]
    SwiftLayout {
        /// The file.
        path: PathBuf,
        /// What the file holds.
        found: String,
        /// What is allowed instead.
        allowed: String,
    },
    /// A SWIFT/GADGET file with particles of another type than gas.
    #[error(
        "{}: {found}: particles other than gas; sph-io reads gas only (PartType0; NumPart_ThisFile and NumPart_Total zero beyond entry 0, no other PartType group)",
        path.display()
    )]
    SwiftOtherTypes {
        /// The file.
        path: PathBuf,
        /// What shows the other types (a count or a group).
        found: String,
    },
    /// A cosmological SWIFT/GADGET file (comoving coordinates, an expansion
    /// factor other than 1).
    #[error(
        "{}: {found}: a cosmological file; sph-io reads non-cosmological files only ('Cosmology/Cosmological run' 0 or absent, Header 'Redshift' 0 and 'Scale-factor' 1 where present)",
        path.display()
    )]
    SwiftCosmological {
        /// The file.
        path: PathBuf,
        /// The attribute that shows it, with its value.
        found: String,
    },
    /// A snapshot in several files (`NumFilesPerSnapshot > 1`) whose pieces
    /// cannot be found or do not agree.
    #[error(
        "{}: {found}; sph-io reads a snapshot of K files as NAME.0.hdf5 .. NAME.(K-1).hdf5, all present, with the same NumFilesPerSnapshot, NumPart_Total, BoxSize, Time and MassTable, and NumPart_ThisFile adding up to NumPart_Total",
        path.display()
    )]
    SwiftMultiFile {
        /// The file named by the caller.
        path: PathBuf,
        /// What is wrong.
        found: String,
    },
    /// A SWIFT/GADGET file whose thermal variable is entropy.
    #[error(
        "{}: Header/Flag_Entropy_ICs = {found}: the file holds entropy, not internal energy; sph-io reads files with Flag_Entropy_ICs 0 (InternalEnergy / InternalEnergies)",
        path.display()
    )]
    SwiftEntropy {
        /// The file.
        path: PathBuf,
        /// The flag's value(s) as found.
        found: String,
    },
}

fn at(step: &Option<String>, field: &Option<String>) -> String {
    match (step, field) {
        (Some(s), Some(f)) => format!("{s}: field '{f}': "),
        (Some(s), None) => format!("{s}: "),
        (None, Some(f)) => format!("field '{f}': "),
        (None, None) => String::new(),
    }
}
