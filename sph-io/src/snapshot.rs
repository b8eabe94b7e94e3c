//! The format-independent data model: one [`Snapshot`] is one output step.

use crate::error::IoError;
pub use crate::field_type::FieldType;

/// Simulation box: lower and upper corners and, per axis, whether the
/// boundary is periodic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxSpec {
    /// Lower corner `(x, y, z)`.
    pub lo: [f64; 3],
    /// Upper corner `(x, y, z)`.
    pub hi: [f64; 3],
    /// Periodic flag per axis.
    pub periodic: [bool; 3],
}

impl Default for BoxSpec {
    /// The unit cube, open on every axis.
    fn default() -> Self {
        BoxSpec {
            lo: [0.0; 3],
            hi: [1.0; 3],
            periodic: [false; 3],
        }
    }
}

/// Value of a step attribute (run settings, scheme name, constants).
#[derive(Debug, Clone, PartialEq)]
pub enum Attr {
    /// One `f64`.
    F64(f64),
    /// One `i64`.
    I64(i64),
    /// A UTF-8 string.
    Str(String),
    /// An array of `f64`.
    F64Array(Vec<f64>),
}

impl Attr {
    /// Bitwise equality (`NaN == NaN` when the bits agree, `0.0 != -0.0`).
    pub fn bits_eq(&self, other: &Attr) -> bool {
        match (self, other) {
            (Attr::F64(a), Attr::F64(b)) => a.to_bits() == b.to_bits(),
            (Attr::I64(a), Attr::I64(b)) => a == b,
            (Attr::Str(a), Attr::Str(b)) => a == b,
            (Attr::F64Array(a), Attr::F64Array(b)) => {
                a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
            }
            _ => false,
        }
    }
}

/// Values of one per-particle field.
#[derive(Debug, Clone, PartialEq)]
pub enum FieldData {
    /// `f64` values.
    F64(Vec<f64>),
    /// `u64` values.
    U64(Vec<u64>),
}

impl FieldData {
    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            FieldData::F64(v) => v.len(),
            FieldData::U64(v) => v.len(),
        }
    }

    /// True when the field holds no value.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Element type.
    pub fn field_type(&self) -> FieldType {
        match self {
            FieldData::F64(_) => FieldType::F64,
            FieldData::U64(_) => FieldType::U64,
        }
    }

    /// The `f64` values, if this is an `f64` field.
    pub fn as_f64(&self) -> Option<&[f64]> {
        match self {
            FieldData::F64(v) => Some(v),
            FieldData::U64(_) => None,
        }
    }

    /// The `u64` values, if this is a `u64` field.
    pub fn as_u64(&self) -> Option<&[u64]> {
        match self {
            FieldData::U64(v) => Some(v),
            FieldData::F64(_) => None,
        }
    }

    /// Bitwise equality (`NaN == NaN` when the bits agree).
    pub fn bits_eq(&self, other: &FieldData) -> bool {
        match (self, other) {
            (FieldData::F64(a), FieldData::F64(b)) => {
                a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
            }
            (FieldData::U64(a), FieldData::U64(b)) => a == b,
            _ => false,
        }
    }

    /// CRC32 (IEEE) of the values as little-endian bytes, the checksum every
    /// backend stores with a field.
    pub fn crc32(&self) -> u32 {
        let mut h = crc32fast::Hasher::new();
        let mut buf = [0u8; 8 * 512];
        macro_rules! feed {
            ($v:expr) => {
                for chunk in $v.chunks(512) {
                    for (dst, x) in buf.chunks_exact_mut(8).zip(chunk) {
                        dst.copy_from_slice(&x.to_le_bytes());
                    }
                    h.update(&buf[..8 * chunk.len()]);
                }
            };
        }
        match self {
            FieldData::F64(v) => feed!(v),
            FieldData::U64(v) => feed!(v),
        }
        h.finalize()
    }
}

/// One named per-particle field.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// Field name (`x`, `vx`, `rho`, `id`, ...): the dataset name on disk.
    pub name: String,
    /// The values, one per particle.
    pub data: FieldData,
}

/// One output step: step metadata, attributes and per-particle fields, all
/// of one length.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Snapshot {
    /// Iteration number of the run.
    pub step: u64,
    /// Simulation time.
    pub time: f64,
    /// Time step.
    pub dt: f64,
    /// Simulation box.
    pub bbox: BoxSpec,
    /// Further attributes (scheme, run settings), in order, names unique.
    pub attrs: Vec<(String, Attr)>,
    /// Fields, in order, names unique, all of one length.
    pub fields: Vec<Field>,
}

impl Snapshot {
    /// An empty snapshot (no attribute, no field) at `step`, `time`, `dt`.
    pub fn new(step: u64, time: f64, dt: f64, bbox: BoxSpec) -> Self {
        Snapshot {
            step,
            time,
            dt,
            bbox,
            attrs: Vec::new(),
            fields: Vec::new(),
        }
    }

    /// Adds (or replaces) attribute `name`.
    pub fn set_attr(&mut self, name: &str, value: Attr) -> &mut Self {
        match self.attrs.iter_mut().find(|(n, _)| n == name) {
            Some((_, v)) => *v = value,
            None => self.attrs.push((name.to_owned(), value)),
        }
        self
    }

    /// Adds (or replaces) field `name`; lengths are checked by
    /// [`validate`](Self::validate) and on write.
    pub fn set_field(&mut self, name: &str, data: FieldData) -> &mut Self {
        match self.fields.iter_mut().find(|f| f.name == name) {
            Some(f) => f.data = data,
            None => self.fields.push(Field {
                name: name.to_owned(),
                data,
            }),
        }
        self
    }

    /// Attribute `name`, if present.
    pub fn attr(&self, name: &str) -> Option<&Attr> {
        self.attrs.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }

    /// Field `name`, if present.
    pub fn field(&self, name: &str) -> Option<&FieldData> {
        self.fields.iter().find(|f| f.name == name).map(|f| &f.data)
    }

    /// Number of particles (length of the first field; 0 without fields).
    pub fn len(&self) -> usize {
        self.fields.first().map_or(0, |f| f.data.len())
    }

    /// True when the snapshot holds no particle.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Checks that names are unique and non-empty, contain no `/` and no
    /// NUL, and that every field has the length of the first.
    pub fn validate(&self) -> Result<(), IoError> {
        let n = self.len();
        for (i, f) in self.fields.iter().enumerate() {
            check_name(&f.name)?;
            if self.fields[..i].iter().any(|g| g.name == f.name) {
                return Err(IoError::DuplicateName {
                    name: f.name.clone(),
                });
            }
            if f.data.len() != n {
                return Err(IoError::LengthMismatch {
                    field: f.name.clone(),
                    expected: n,
                    found: f.data.len(),
                });
            }
        }
        for (i, (name, _)) in self.attrs.iter().enumerate() {
            check_name(name)?;
            if self.attrs[..i].iter().any(|(m, _)| m == name) {
                return Err(IoError::DuplicateName { name: name.clone() });
            }
        }
        Ok(())
    }

    /// Bitwise equality of everything (floats compared by their bits).
    pub fn bits_eq(&self, other: &Snapshot) -> bool {
        let box_eq = |a: &BoxSpec, b: &BoxSpec| {
            a.lo.iter()
                .chain(&a.hi)
                .zip(b.lo.iter().chain(&b.hi))
                .all(|(x, y)| x.to_bits() == y.to_bits())
                && a.periodic == b.periodic
        };
        self.step == other.step
            && self.time.to_bits() == other.time.to_bits()
            && self.dt.to_bits() == other.dt.to_bits()
            && box_eq(&self.bbox, &other.bbox)
            && self.attrs.len() == other.attrs.len()
            && self
                .attrs
                .iter()
                .zip(&other.attrs)
                .all(|((n, a), (m, b))| n == m && a.bits_eq(b))
            && self.fields.len() == other.fields.len()
            && self
                .fields
                .iter()
                .zip(&other.fields)
                .all(|(f, g)| f.name == g.name && f.data.bits_eq(&g.data))
    }
}

pub(crate) fn check_name(name: &str) -> Result<(), IoError> {
    if name.is_empty() || name.contains('/') || name.contains('\0') || name == "." {
        return Err(IoError::BadName {
            name: name.to_owned(),
        });
    }
    Ok(())
}

/// Which fields to write or read.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum Selection {
    /// Every field.
    #[default]
    All,
    /// Only these fields, in this order; each must exist.
    Names(Vec<String>),
}

impl Selection {
    /// A selection of the given names.
    pub fn names<S: AsRef<str>>(names: &[S]) -> Self {
        Selection::Names(names.iter().map(|s| s.as_ref().to_owned()).collect())
    }
}
