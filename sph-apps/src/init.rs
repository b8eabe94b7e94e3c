//! Initial conditions from a snapshot file (`sphexa run --init FILE[:K]`):
//! ours, an H5Part file of SPH-EXA, or a SWIFT/GADGET file (initial
//! conditions or snapshot, `PartType0`), each rank taking its share of the
//! particles in place of the case's.

use crate::output::snapshot as snapfile;
use crate::{checkpoint, AppError};
use sph_comm::Communicator;

/// The particles of snapshot `spec` (`FILE[:K]`, ours, SPH-EXA's or a
/// SWIFT/GADGET file) as this rank's share of the initial conditions of a
/// run with `fields`; the total and, if the file has one, its box (with
/// the boundary kinds of `case_box` unless the file records them).
///
/// A SWIFT/GADGET file's box `[0, BoxSize)` is placed with its centre on
/// `case_box`'s (positions shifted alike), and its smoothing lengths are
/// converted to this code's convention for the file's kernel (SWIFT's cubic
/// spline where the file names none): see [`sph_io::swift`]. Values are
/// taken in the file's units; its time is not kept (runs start at 0).
///
/// # Errors
/// An unreadable file or step, a missing required field (`x`, `y`, `z`,
/// `h`, `m`, `u`), a SWIFT file with what [`sph_io::swift::read_swift`]
/// refuses, a file in neither layout, or a bad box.
pub fn load<C: Communicator>(
    comm: &C,
    spec: &str,
    fields: sph_core::FieldSet,
    case_box: &sph_tree::BoundingBox,
) -> Result<(sph_core::Particles, usize, Option<sph_tree::BoundingBox>), AppError> {
    use sph_io::foreign;
    let boundary = case_box.boundary();
    let (path, k) = checkpoint::split_spec(spec)?;
    if sph_io::swift::looks_like_swift(&path) {
        return load_swift(comm, &path, k, fields, case_box);
    }
    let index = step_index(&path, k)?;
    let required = ["x", "y", "z", "h", "m", "u"];
    let optional = ["vx", "vy", "vz", "id"];
    let head = foreign::read_foreign_rows(&path, index, &required, &[], 0..0)?;
    let total = head.total;
    let (r, size) = (comm.rank() as u64, comm.size() as u64);
    let rows = total * r / size..total * (r + 1) / size;
    // Our own files: read through the checksummed reader.
    let ours = sph_io::SnapshotReader::read_step(
        &sph_io::H5Part,
        &path,
        index,
        &sph_io::Selection::Names(Vec::new()),
    )
    .is_ok();
    let mut values: Vec<(String, Vec<f64>)> = Vec::new();
    let mut ids: Option<Vec<u64>> = None;
    let mut periodic = None;
    if ours {
        let present: Vec<&str> = required
            .iter()
            .chain(&optional)
            .copied()
            .filter(|n| head.datasets.iter().any(|d| d == n))
            .collect();
        let (snap, _) =
            snapfile::read_share(comm, &path, index, &sph_io::Selection::names(&present))?;
        periodic = Some(snap.bbox.periodic);
        for f in snap.fields {
            match f.data {
                sph_io::FieldData::F64(v) => values.push((f.name, v)),
                sph_io::FieldData::U64(v) if f.name == "id" => ids = Some(v),
                sph_io::FieldData::U64(v) => {
                    values.push((f.name, v.into_iter().map(|x| x as f64).collect()))
                }
            }
        }
        for n in required {
            if !values.iter().any(|(m, _)| m == n) {
                return Err(AppError::Usage(format!(
                    "--init {}: Step#{index} has no field '{n}'; initial conditions need {}",
                    path.display(),
                    required.join(", ")
                )));
            }
        }
    } else {
        let st = foreign::read_foreign_rows(&path, index, &required, &optional, rows.clone())?;
        for (name, v) in st.fields {
            if name == "id" {
                ids = Some(v.iter().map(|&x| x as u64).collect());
            } else {
                values.push((name, v));
            }
        }
    }
    let n = (rows.end - rows.start) as usize;
    let mut p = sph_core::Particles::new(n, fields);
    p.id = ids.unwrap_or_else(|| rows.clone().collect());
    for (name, v) in values {
        // Only the initial state's fields: the rest start from the case.
        if !required.contains(&name.as_str()) && !optional.contains(&name.as_str()) {
            continue;
        }
        if let Some(dst) = sph_core::fields::find(&name).and_then(|f| f.f64_mut(&mut p)) {
            dst.copy_from_slice(&v);
        }
    }
    let bbox = match head.bbox {
        Some(b) => {
            let kinds = match periodic {
                Some(per) => per.map(|q| {
                    if q {
                        sph_tree::Boundary::Periodic
                    } else {
                        sph_tree::Boundary::Open
                    }
                }),
                None => boundary,
            };
            Some(sph_tree::BoundingBox::new(
                [b[0], b[2], b[4]],
                [b[1], b[3], b[5]],
                kinds,
            )?)
        }
        None => None,
    };
    let total = usize::try_from(total)
        .map_err(|_| AppError::Usage(format!("--init {}: {total} particles", path.display())))?;
    Ok((p, total, bbox))
}

/// What snapshot `spec` (`FILE[:K]`) says of its physics, for a scene of
/// the user's own ([`crate::cases::scene`]): the attributes of its step
/// group, or of a SWIFT/GADGET file its box `[0, BoxSize)` alone.
///
/// # Errors
/// An unreadable file or step, or an attribute of the wrong shape.
pub fn attributes(spec: &str) -> Result<crate::cases::scene::FileAttrs, AppError> {
    use crate::cases::scene::FileAttrs;
    let (path, k) = checkpoint::split_spec(spec)?;
    if sph_io::swift::looks_like_swift(&path) {
        let l = sph_io::swift::read_swift(&path)?.particles.box_size;
        return Ok(FileAttrs {
            bbox: Some([0.0, l[0], 0.0, l[1], 0.0, l[2]]),
            ..FileAttrs::default()
        });
    }
    let index = step_index(&path, k)?;
    let head = sph_io::foreign::read_foreign_rows(&path, index, &[], &[], 0..0)?;
    FileAttrs::of(&path.display().to_string(), &head)
}

/// The step group `k` of H5Part file `path`, or its last.
fn step_index(path: &std::path::Path, k: Option<u64>) -> Result<usize, AppError> {
    let count = sph_io::foreign::step_count(path).map_err(|e| {
        AppError::Usage(format!(
            "--init {}: neither an H5Part file ({e}) nor a SWIFT/GADGET file (no group 'Header')",
            path.display()
        ))
    })?;
    Ok(k.map_or(count.saturating_sub(1), |k| k as usize))
}

/// [`load`] of a SWIFT/GADGET file.
fn load_swift<C: Communicator>(
    comm: &C,
    path: &std::path::Path,
    step: Option<u64>,
    fields: sph_core::FieldSet,
    case_box: &sph_tree::BoundingBox,
) -> Result<(sph_core::Particles, usize, Option<sph_tree::BoundingBox>), AppError> {
    use sph_io::swift::{self, SwiftKernel};
    let file = swift::read_swift(path)?;
    if let Some(k) = step {
        return Err(AppError::Usage(format!(
            "--init {}:{k}: a SWIFT/GADGET file holds one step; give the file alone",
            path.display()
        )));
    }
    let mut gas = file.particles;
    let factor = file
        .header
        .kernel
        .unwrap_or(SwiftKernel::CubicSpline)
        .to_sph_exa_h();
    gas.scale_h(factor);
    let (lo, hi) = (case_box.lo(), case_box.hi());
    let centre: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let lo: [f64; 3] = std::array::from_fn(|k| centre[k] - 0.5 * gas.box_size[k]);
    gas.shift(lo);
    let hi: [f64; 3] = std::array::from_fn(|k| lo[k] + gas.box_size[k]);
    let bbox = sph_tree::BoundingBox::new(lo, hi, case_box.boundary())?;
    let total = gas.len();
    let (r, size) = (comm.rank(), comm.size());
    let rows = total * r / size..total * (r + 1) / size;
    let mut p = sph_core::Particles::new(rows.len(), fields);
    p.id = gas.id[rows.clone()].to_vec();
    let columns = [
        ("x", &gas.x),
        ("y", &gas.y),
        ("z", &gas.z),
        ("vx", &gas.vx),
        ("vy", &gas.vy),
        ("vz", &gas.vz),
        ("h", &gas.h),
        ("m", &gas.m),
        ("u", &gas.u),
    ];
    for (name, v) in columns {
        if let Some(dst) = sph_core::fields::find(name).and_then(|f| f.f64_mut(&mut p)) {
            dst.copy_from_slice(&v[rows.clone()]);
        }
    }
    Ok((p, total, Some(bbox)))
}
