//! Initial conditions from a snapshot file (`sphexa run --init FILE[:K]`):
//! ours, or an H5Part file of SPH-EXA, each rank reading its share of the
//! particles in place of the case's.

use crate::output::snapshot as snapfile;
use crate::{checkpoint, AppError};
use sph_comm::Communicator;

/// The particles of snapshot `spec` (`FILE[:K]`, ours or SPH-EXA's) as
/// this rank's share of the initial conditions of a run with `fields`;
/// the total and, if the file has one, its box (with `boundary` kinds
/// unless the file records them).
///
/// # Errors
/// An unreadable file or step, a missing required field (`x`, `y`, `z`,
/// `h`, `m`, `u`), or a bad box.
pub fn load<C: Communicator>(
    comm: &C,
    spec: &str,
    fields: sph_core::FieldSet,
    boundary: [sph_tree::Boundary; 3],
) -> Result<(sph_core::Particles, usize, Option<sph_tree::BoundingBox>), AppError> {
    use sph_io::foreign;
    let (path, k) = checkpoint::split_spec(spec)?;
    let count = foreign::step_count(&path)?;
    let index = match k {
        Some(k) => k as usize,
        None => count.saturating_sub(1),
    };
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
