//! Reading H5Part files that other codes wrote, SPH-EXA's above all: a group
//! `Step#k` per output with one 1-D dataset per field (`x`, `y`, `z`, `vx`,
//! `h`, `m`, `u`, ... as `f64` or `f32`, ids as integers) and the step's
//! `time`, `iteration`, `minDt` and `box` as attributes where present. There
//! are no checksums or field tables to check: values are converted to `f64`
//! and every attribute is optional.

use std::ops::Range;
use std::path::Path;

use hdf5_pure::AttrValue;

use crate::error::IoError;
use crate::h5part::{self, step_group};

/// One step of another code's H5Part file (the rows asked for).
#[derive(Debug, Clone, PartialEq)]
pub struct ForeignStep {
    /// The step group's name, `Step#k`.
    pub group: String,
    /// Attribute `time`, if present and numeric.
    pub time: Option<f64>,
    /// Attribute `iteration`, if present and a non-negative integer.
    pub iteration: Option<u64>,
    /// Attribute `minDt`, if present and numeric.
    pub dt: Option<f64>,
    /// Attribute `box` (`xmin, xmax, ymin, ymax, zmin, zmax`), if present
    /// with 6 numbers.
    pub bbox: Option<[f64; 6]>,
    /// Every attribute of the step group that reads as numbers (a scalar
    /// or a 1-D array: SPH-EXA's `gamma`, `gravConstant`, `boundaryType`,
    /// ours `periodic`, ...), sorted by name.
    pub numbers: Vec<(String, Vec<f64>)>,
    /// Rows of every dataset (the length of the first requested field).
    pub total: u64,
    /// Names of all the step's datasets.
    pub datasets: Vec<String>,
    /// The requested fields (rows asked for), as `f64`, in request order.
    pub fields: Vec<(String, Vec<f64>)>,
}

impl ForeignStep {
    /// The numbers of attribute `name`, if the step has it as numbers.
    pub fn number(&self, name: &str) -> Option<&[f64]> {
        self.numbers
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }

    /// Field `name`, if it was read.
    pub fn field(&self, name: &str) -> Option<&[f64]> {
        self.fields
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// Number of `Step#k` groups of a file (any HDF5 file).
pub fn step_count(path: &Path) -> Result<usize, IoError> {
    let file = h5part::open(path)?;
    h5part::count_steps(path, &file)
}

/// Reads rows `rows` (clamped) of the datasets `required` and, where the
/// step has them, `optional` of step group `index`, converted to `f64`. All
/// fields read must have the same length.
///
/// # Errors
/// A missing step or required field, a field that is not 1-D or not of the
/// first field's length, a field claiming more values than the file has
/// bytes for, or undecodable data, each naming file, step and field.
pub fn read_foreign_rows(
    path: &Path,
    index: usize,
    required: &[&str],
    optional: &[&str],
    rows: Range<u64>,
) -> Result<ForeignStep, IoError> {
    let file = h5part::open(path)?;
    let file_len = h5part::file_len(path)?;
    let count = h5part::count_steps(path, &file)?;
    let gname = step_group(index);
    if index >= count {
        return Err(IoError::MissingStep {
            path: path.to_owned(),
            step: gname,
            count,
        });
    }
    let g = h5part::guard(path, Some(&gname), None, || file.group(&gname))?;
    let attrs = h5part::guard(path, Some(&gname), None, || g.attrs())?;
    let datasets = h5part::guard(path, Some(&gname), None, || g.datasets())?;
    let num = |name: &str| attrs.get(name).and_then(AttrValue::as_f64);
    let bbox = attrs
        .get("box")
        .and_then(AttrValue::to_f64s)
        .filter(|v| v.len() == 6)
        .map(|v| [v[0], v[1], v[2], v[3], v[4], v[5]]);
    let mut numbers: Vec<(String, Vec<f64>)> = attrs
        .iter()
        .filter_map(|(k, v)| {
            // Integers (e.g. SPH-EXA's int8 `boundaryType`) as exact f64s.
            let ints = || Some(v.to_i64s()?.into_iter().map(|i| i as f64).collect());
            Some((k.clone(), v.to_f64s().or_else(ints)?))
        })
        .collect();
    numbers.sort_by(|a, b| a.0.cmp(&b.0));
    let mut step = ForeignStep {
        group: gname.clone(),
        time: num("time"),
        iteration: attrs.get("iteration").and_then(AttrValue::as_u64),
        dt: num("minDt"),
        bbox,
        numbers,
        total: 0,
        datasets: datasets.clone(),
        fields: Vec::new(),
    };
    let mut total: Option<u64> = None;
    let wanted = required
        .iter()
        .map(|n| (*n, true))
        .chain(optional.iter().map(|n| (*n, false)));
    for (name, needed) in wanted {
        if !datasets.iter().any(|d| d == name) {
            if needed {
                return Err(IoError::MissingField {
                    path: path.to_owned(),
                    step: gname,
                    field: name.to_owned(),
                });
            }
            continue;
        }
        let at = (Some(gname.as_str()), Some(name));
        let ds = h5part::guard(path, at.0, at.1, || g.dataset(name))?;
        let shape = h5part::guard(path, at.0, at.1, || ds.shape())?;
        let n = match shape.as_slice() {
            [n] => *n,
            _ => {
                return Err(IoError::Format {
                    path: path.to_owned(),
                    step: Some(gname),
                    field: Some(name.to_owned()),
                    what: format!("not a 1-D dataset (shape {shape:?})"),
                })
            }
        };
        // Every value must be stored somewhere in the file: a count beyond
        // that is refused before the decoder (which fills unallocated
        // storage) or a caller (which sizes arrays by `total`) allocates
        // for it.
        let size = h5part::guard(path, at.0, at.1, || {
            Ok(ds.datatype()?.element_size()?.get())
        })?;
        h5part::check_claim(path, &gname, name, n, size, file_len)?;
        let expected = *total.get_or_insert(n);
        if n != expected {
            return Err(IoError::WrongLength {
                path: path.to_owned(),
                step: gname,
                field: name.to_owned(),
                expected,
                found: n,
            });
        }
        let r = rows.start.min(n)..rows.end.min(n);
        let values = h5part::guard(path, at.0, at.1, || {
            ds.read_f64_rows(r.start, r.end - r.start)
        })?;
        step.fields.push((name.to_owned(), values));
    }
    step.total = total.unwrap_or(0);
    Ok(step)
}
