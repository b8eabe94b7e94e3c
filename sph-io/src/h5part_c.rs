//! The same H5Part files as [`H5Part`](crate::H5Part), written and read by
//! the HDF5 C library (libhdf5 through
//! [`hdf5-metno`](https://docs.rs/hdf5-metno)); only with the cargo feature
//! `hdf5-c`.
//!
//! # Layout
//! Byte for byte the files differ (libhdf5 lays out its own object headers,
//! symbol tables and heaps), but the content is the one the
//! [`h5part`](crate::h5part#layout) module describes: groups `Step#k`, one 1-D
//! little-endian `f64`/`u64` dataset per field with its `crc32` attribute
//! (u32), the step attributes of the same names, types and shapes (scalars
//! as scalar dataspaces, arrays as 1-D ones, strings as fixed-width
//! null-padded UTF-8 as narrow as their longest value), and the same metadata
//! checksum, computed by the same code. Each backend reads what the other
//! writes, to the bit (`tests/backends.rs`).
//!
//! The reader decodes the attributes into the pure-Rust crate's `AttrValue`
//! and checks them with the code [`H5Part`](crate::H5Part) uses, so a step
//! either backend accepts has the same metadata. It is more lenient in one
//! respect: a string attribute stored wider than its value, or as a
//! variable-length string (what h5py writes by default), is accepted where
//! the pure-Rust reader refuses it; the metadata checksum still covers its
//! value.
//!
//! # Limits
//! - An attribute (a user attribute, or a field or attribute name table)
//!   over about 64 KiB is refused on write: libhdf5 keeps attributes in the
//!   object header, whose messages are at most 64 KiB in the file format
//!   version it writes by default (readable by every HDF5 since 1.6); a
//!   string attribute longer than 65,536 bytes is refused on read (strings
//!   pass through fixed-width buffers of at most that size). The pure-Rust
//!   backend has neither limit.
//! - libhdf5 is not hardened against crafted or corrupted files: a torn or
//!   truncated file gives an [`IoError`], but a corrupted one may crash the
//!   process inside the C library instead of returning an error (the
//!   pure-Rust reader was given 80,000 random corruptions without a panic).
//!   The CRC32s are checked all the same.
//! - Parallel HDF5 (one file written collectively by MPI ranks) is not used
//!   here; see `docs/architecture.md` for what it would take.
//!
//! Writes go to `NAME.tmp`, are synced to disk and renamed, and
//! [`SnapshotWriter::append`] extends a copy of the file, as with
//! [`H5Part`](crate::H5Part).

use std::collections::HashMap;
use std::path::Path;

use h5::types::{FixedAscii, FixedUnicode, FloatSize, IntSize, TypeDescriptor};
use h5::types::{VarLenAscii, VarLenUnicode};
use hdf5_metno as h5;
use hdf5_pure::AttrValue;

use crate::error::IoError;
use crate::h5part::{self, parse_meta, plan_step, step_group, tmp_path, StepPlan, A_CRC};
use crate::snapshot::{Field, FieldData, FieldType, Selection, Snapshot};
use crate::{SnapshotReader, SnapshotWriter};

/// Longest string attribute (bytes) the backend writes or reads.
pub const MAX_STRING_BYTES: usize = 1 << 16;

/// The H5Part backend on libhdf5 (stateless; see the [module docs](self)).
#[derive(Debug, Clone, Copy, Default)]
pub struct H5PartC;

/// An [`IoError::Format`] from a libhdf5 error.
fn c_error(path: &Path, step: Option<&str>, field: Option<&str>, e: h5::Error) -> IoError {
    IoError::Format {
        path: path.to_owned(),
        step: step.map(str::to_owned),
        field: field.map(str::to_owned),
        what: format!("libhdf5: {e}"),
    }
}

impl SnapshotWriter for H5PartC {
    fn write_steps(
        &self,
        path: &Path,
        steps: &[&Snapshot],
        select: &Selection,
    ) -> Result<(), IoError> {
        let plans = steps
            .iter()
            .map(|snap| plan_step(snap, select))
            .collect::<Result<Vec<_>, _>>()?;
        h5part::write_atomic(path, None, |_| {
            let tmp = tmp_path(path);
            let file = h5::File::create(&tmp).map_err(|e| c_error(path, None, None, e))?;
            for (k, plan) in plans.iter().enumerate() {
                write_group(path, &file, &step_group(k), plan)?;
            }
            file.close().map_err(|e| c_error(path, None, None, e))
        })
    }

    fn append(&self, path: &Path, snap: &Snapshot, select: &Selection) -> Result<usize, IoError> {
        if !path.exists() {
            self.write(path, snap, select)?;
            return Ok(0);
        }
        let plan = plan_step(snap, select)?;
        let k = self.step_count(path)?;
        h5part::write_atomic(path, Some(path), |_| {
            let tmp = tmp_path(path);
            let file = h5::File::open_rw(&tmp).map_err(|e| c_error(path, None, None, e))?;
            write_group(path, &file, &step_group(k), &plan)?;
            file.close().map_err(|e| c_error(path, None, None, e))
        })?;
        Ok(k)
    }
}

/// Writes step group `gname`: its attributes, then its fields, each with
/// its checksum.
fn write_group(
    path: &Path,
    file: &h5::File,
    gname: &str,
    plan: &StepPlan<'_>,
) -> Result<(), IoError> {
    let g = file
        .create_group(gname)
        .map_err(|e| c_error(path, Some(gname), None, e))?;
    for (name, value) in &plan.attrs {
        write_attr(&g, name, value).map_err(|e| {
            c_error(
                path,
                Some(gname),
                None,
                format!("attribute '{name}': {e}").into(),
            )
        })?;
    }
    for (f, crc) in &plan.fields {
        write_field(&g, f, *crc).map_err(|e| c_error(path, Some(gname), Some(&f.name), e))?;
    }
    Ok(())
}

fn write_field(g: &h5::Group, f: &Field, crc: u32) -> h5::Result<()> {
    let builder = g.new_dataset_builder();
    let ds = match &f.data {
        FieldData::F64(v) => builder.with_data(v.as_slice()).create(f.name.as_str())?,
        FieldData::U64(v) => builder.with_data(v.as_slice()).create(f.name.as_str())?,
    };
    ds.new_attr::<u32>().create(A_CRC)?.write_scalar(&crc)
}

/// Writes one attribute in the encoding `hdf5-pure` gives `value`.
fn write_attr(loc: &h5::Location, name: &str, value: &AttrValue) -> h5::Result<()> {
    match value {
        AttrValue::F64(x) => loc.new_attr::<f64>().create(name)?.write_scalar(x),
        AttrValue::I64(x) => loc.new_attr::<i64>().create(name)?.write_scalar(x),
        AttrValue::U64(x) => loc.new_attr::<u64>().create(name)?.write_scalar(x),
        AttrValue::U32(x) => loc.new_attr::<u32>().create(name)?.write_scalar(x),
        AttrValue::F64Array(v) => array_attr(loc, name, v),
        AttrValue::U8Array(v) => array_attr(loc, name, v),
        AttrValue::String(s) => string_attr(loc, name, std::slice::from_ref(s), true),
        AttrValue::StringArray(v) => string_attr(loc, name, v, false),
        other => Err(format!("no encoding for {other:?}").into()),
    }
}

fn array_attr<T: h5::H5Type>(loc: &h5::Location, name: &str, v: &[T]) -> h5::Result<()> {
    loc.new_attr_builder().with_data(v).create(name).map(drop)
}

/// A fixed-width, null-padded UTF-8 string attribute (scalar, or 1-D over
/// `values`) as wide as the longest value, at least 1 byte: what
/// `hdf5-pure` writes for `AttrValue::String`/`StringArray`.
fn string_attr(loc: &h5::Location, name: &str, values: &[String], scalar: bool) -> h5::Result<()> {
    let width = values.iter().map(String::len).max().unwrap_or(0).max(1);
    let file_type = TypeDescriptor::FixedUnicode(width);
    fn write<const N: usize>(
        loc: &h5::Location,
        name: &str,
        values: &[String],
        scalar: bool,
        file_type: TypeDescriptor,
    ) -> h5::Result<()> {
        let fixed = values
            .iter()
            .map(|s| s.parse::<FixedUnicode<N>>())
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| h5::Error::from(e.to_string()))?;
        // The values are converted (by libhdf5) from N-byte buffers to the
        // narrower file type.
        if scalar {
            let attr = loc.new_attr_builder().empty_as(file_type).create(name)?;
            attr.as_writer().write_scalar(&fixed[0])
        } else {
            loc.new_attr_builder()
                .with_data_as(fixed.as_slice(), file_type)
                .create(name)
                .map(drop)
        }
    }
    match width {
        0..=64 => write::<64>(loc, name, values, scalar, file_type),
        65..=1024 => write::<1024>(loc, name, values, scalar, file_type),
        1025..=16384 => write::<16384>(loc, name, values, scalar, file_type),
        16385..=MAX_STRING_BYTES => write::<MAX_STRING_BYTES>(loc, name, values, scalar, file_type),
        _ => Err(format!(
            "a string of {width} bytes, more than the {MAX_STRING_BYTES} this backend handles"
        )
        .into()),
    }
}

impl SnapshotReader for H5PartC {
    fn step_count(&self, path: &Path) -> Result<usize, IoError> {
        let file = open(path)?;
        Ok(count_steps(&file))
    }

    fn read_step(
        &self,
        path: &Path,
        index: usize,
        select: &Selection,
    ) -> Result<Snapshot, IoError> {
        let file = open(path)?;
        read_group(path, &file, index, select)
    }

    fn read_all(&self, path: &Path, select: &Selection) -> Result<Vec<Snapshot>, IoError> {
        let file = open(path)?;
        (0..count_steps(&file))
            .map(|k| read_group(path, &file, k, select))
            .collect()
    }
}

/// Opens `path` read-only; a missing file is an [`IoError::Io`], a file
/// without the HDF5 signature [`IoError::NotHdf5`] (the same checks as the
/// pure-Rust reader).
fn open(path: &Path) -> Result<h5::File, IoError> {
    let is_hdf5 = hdf5_pure::is_hdf5(path).map_err(|source| IoError::Io {
        path: path.to_owned(),
        source,
    })?;
    if !is_hdf5 {
        return Err(IoError::NotHdf5 {
            path: path.to_owned(),
        });
    }
    h5::File::open(path).map_err(|e| c_error(path, None, None, e))
}

/// Number of groups `Step#0, Step#1, ...` in a row.
fn count_steps(file: &h5::File) -> usize {
    let mut count = 0;
    while file.link_exists(&step_group(count)) && file.group(&step_group(count)).is_ok() {
        count += 1;
    }
    count
}

fn read_group(
    path: &Path,
    file: &h5::File,
    k: usize,
    select: &Selection,
) -> Result<Snapshot, IoError> {
    let gname = step_group(k);
    let count = count_steps(file);
    if k >= count {
        return Err(IoError::MissingStep {
            path: path.to_owned(),
            step: gname,
            count,
        });
    }
    let g = file
        .group(&gname)
        .map_err(|e| c_error(path, Some(&gname), None, e))?;
    let attrs = read_attrs(&g).map_err(|e| c_error(path, Some(&gname), None, e))?;
    let meta = parse_meta(path, gname, g, attrs)?;
    let wanted = meta.wanted(path, select)?;
    let mut snap = meta.snapshot();
    snap.fields.reserve(wanted.len());
    for (name, t) in wanted {
        let data = read_field(path, &meta.gname, &meta.group, &name, t, meta.n)?;
        snap.fields.push(Field { name, data });
    }
    Ok(snap)
}

/// Reads field `name` (of type `t`, `n` values) of step group `g` and checks
/// it against its stored CRC32; a field claiming more values than the file
/// has bytes for is refused ([`IoError::BeyondFile`]) before anything is
/// allocated for it.
fn read_field(
    path: &Path,
    gname: &str,
    g: &h5::Group,
    name: &str,
    t: FieldType,
    n: u64,
) -> Result<FieldData, IoError> {
    let err = |e: h5::Error| c_error(path, Some(gname), Some(name), e);
    if !g.link_exists(name) {
        return Err(IoError::MissingField {
            path: path.to_owned(),
            step: gname.to_owned(),
            field: name.to_owned(),
        });
    }
    let ds = g.dataset(name).map_err(err)?;
    let desc = ds.dtype().and_then(|d| d.to_descriptor()).map_err(err)?;
    let found_t = match desc {
        TypeDescriptor::Float(FloatSize::U8) => Some(FieldType::F64),
        TypeDescriptor::Unsigned(IntSize::U8) => Some(FieldType::U64),
        _ => None,
    };
    if found_t != Some(t) {
        return Err(IoError::WrongType {
            path: path.to_owned(),
            step: gname.to_owned(),
            field: name.to_owned(),
            expected: t,
            found: format!("{desc:?}"),
        });
    }
    let shape = ds.shape();
    if shape.len() != 1 || shape[0] as u64 != n {
        return Err(IoError::WrongLength {
            path: path.to_owned(),
            step: gname.to_owned(),
            field: name.to_owned(),
            expected: n,
            found: shape.iter().product::<usize>() as u64,
        });
    }
    // `read_raw` allocates for the whole shape before libhdf5 reads a byte:
    // a count beyond the file (values of 8 bytes, the types just checked)
    // is refused first.
    h5part::check_claim(path, gname, name, n, 8, h5part::file_len(path)?)?;
    let stored = match ds.attr(A_CRC).and_then(|a| {
        let d = a.dtype()?.to_descriptor()?;
        if d == TypeDescriptor::Unsigned(IntSize::U4) && a.is_scalar() {
            a.read_scalar::<u32>().map(Some)
        } else {
            Ok(None)
        }
    }) {
        Ok(Some(c)) => c,
        _ => {
            return Err(IoError::BadAttribute {
                path: path.to_owned(),
                step: gname.to_owned(),
                attr: format!("{name}/{A_CRC}"),
                what: "missing or not a u32".to_owned(),
            })
        }
    };
    let data = match t {
        FieldType::F64 => FieldData::F64(ds.read_raw::<f64>().map_err(err)?),
        FieldType::U64 => FieldData::U64(ds.read_raw::<u64>().map_err(err)?),
    };
    let computed = data.crc32();
    if computed != stored {
        return Err(IoError::Checksum {
            path: path.to_owned(),
            step: gname.to_owned(),
            field: name.to_owned(),
            stored,
            computed,
        });
    }
    Ok(data)
}

/// The attributes of `loc` as `hdf5-pure` decodes them (numbers at their
/// stored width, scalar or 1-D); attributes of other types are left out,
/// as `hdf5-pure` leaves out those it cannot decode.
fn read_attrs(loc: &h5::Location) -> h5::Result<HashMap<String, AttrValue>> {
    let mut out = HashMap::new();
    for name in loc.attr_names()? {
        let a = loc.attr(&name)?;
        let Ok(desc) = a.dtype().and_then(|d| d.to_descriptor()) else {
            continue;
        };
        let scalar = a.is_scalar();
        macro_rules! num {
            ($t:ty, $one:ident, $many:ident) => {
                if scalar {
                    AttrValue::$one(a.read_scalar::<$t>()?)
                } else {
                    AttrValue::$many(a.read_raw::<$t>()?)
                }
            };
        }
        let value = match desc {
            TypeDescriptor::Float(FloatSize::U8) => num!(f64, F64, F64Array),
            TypeDescriptor::Float(FloatSize::U4) => num!(f32, F32, F32Array),
            TypeDescriptor::Integer(IntSize::U1) => num!(i8, I8, I8Array),
            TypeDescriptor::Integer(IntSize::U2) => num!(i16, I16, I16Array),
            TypeDescriptor::Integer(IntSize::U4) => num!(i32, I32, I32Array),
            TypeDescriptor::Integer(IntSize::U8) => num!(i64, I64, I64Array),
            TypeDescriptor::Unsigned(IntSize::U1) => num!(u8, U8, U8Array),
            TypeDescriptor::Unsigned(IntSize::U2) => num!(u16, U16, U16Array),
            TypeDescriptor::Unsigned(IntSize::U4) => num!(u32, U32, U32Array),
            TypeDescriptor::Unsigned(IntSize::U8) => num!(u64, U64, U64Array),
            TypeDescriptor::FixedUnicode(w) | TypeDescriptor::FixedAscii(w) => {
                let ascii = matches!(desc, TypeDescriptor::FixedAscii(_));
                strings_value(read_fixed_strings(&a, &name, w, ascii)?, scalar)
            }
            TypeDescriptor::VarLenUnicode => {
                let v = a.read_raw::<VarLenUnicode>()?;
                strings_value(v.iter().map(|s| s.as_str().to_owned()).collect(), scalar)
            }
            TypeDescriptor::VarLenAscii => {
                let v = a.read_raw::<VarLenAscii>()?;
                strings_value(v.iter().map(|s| s.as_str().to_owned()).collect(), scalar)
            }
            _ => continue,
        };
        out.insert(name, value);
    }
    Ok(out)
}

fn strings_value(mut v: Vec<String>, scalar: bool) -> AttrValue {
    if scalar {
        AttrValue::String(v.pop().unwrap_or_default())
    } else {
        AttrValue::StringArray(v)
    }
}

/// The values of a fixed-width string attribute of `width` bytes, read
/// through buffers of the next size up.
fn read_fixed_strings(
    a: &h5::Attribute,
    name: &str,
    width: usize,
    ascii: bool,
) -> h5::Result<Vec<String>> {
    fn read<const N: usize>(a: &h5::Attribute, ascii: bool) -> h5::Result<Vec<String>> {
        let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
        Ok(if ascii {
            let v = a.read_raw::<FixedAscii<N>>()?;
            v.iter().map(|s| text(s.as_bytes())).collect()
        } else {
            let v = a.read_raw::<FixedUnicode<N>>()?;
            v.iter().map(|s| text(s.as_bytes())).collect()
        })
    }
    match width {
        0..=64 => read::<64>(a, ascii),
        65..=1024 => read::<1024>(a, ascii),
        1025..=16384 => read::<16384>(a, ascii),
        16385..=MAX_STRING_BYTES => read::<MAX_STRING_BYTES>(a, ascii),
        _ => Err(format!(
            "attribute '{name}': a string of {width} bytes, more than the {MAX_STRING_BYTES} this backend handles"
        )
        .into()),
    }
}
