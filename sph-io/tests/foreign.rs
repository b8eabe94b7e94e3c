//! Files in SPH-EXA's H5Part layout (no checksums, no field table, `f32`
//! fields, integer ids, attributes named as SPH-EXA names them), built by
//! `common::sphexa_bytes` with the HDF5 encoder directly, read by
//! `sph_io::foreign`.

mod common;

use sph_io::foreign::{read_foreign_rows, step_count};
use sph_io::IoError;

#[test]
fn sphexa_layout_reads_with_conversions_and_row_ranges() {
    let path = common::scratch_path("foreign-sphexa.h5");
    std::fs::write(&path, common::sphexa_bytes(10)).unwrap();
    assert_eq!(step_count(&path).unwrap(), 2);
    let s = read_foreign_rows(&path, 1, &["x", "h"], &["id", "vx"], 2..5).unwrap();
    assert_eq!(s.group, "Step#1");
    assert_eq!(
        (s.time, s.iteration, s.dt, s.total),
        (Some(1.25), Some(11), Some(1e-3), 10)
    );
    assert_eq!(s.bbox, Some([-1.0, 1.0, -2.0, 2.0, -3.0, 3.0]));
    // Every numeric attribute, integers and f32 widened exactly, by name;
    // strings are not numbers.
    assert_eq!(s.number("boundaryType"), Some(&[1.0, 0.0, 1.0][..]));
    assert_eq!(s.number("gamma"), Some(&[1.5][..]));
    assert_eq!(s.number("minDt"), Some(&[1e-3][..]));
    assert_eq!(s.number("kernelChoice"), None);
    let names: Vec<&str> = s.numbers.iter().map(|(n, _)| n.as_str()).collect();
    assert!(names.windows(2).all(|w| w[0] < w[1]), "sorted: {names:?}");
    assert_eq!(s.field("x").unwrap(), &[1.2, 1.3, 1.4]);
    // f32 values widen exactly: 0.5 + i/8 is exact in f32.
    assert_eq!(s.field("h").unwrap(), &[0.75, 0.875, 1.0]);
    assert_eq!(s.field("id").unwrap(), &[102.0, 103.0, 104.0]);
    assert!(s.field("vx").is_none(), "optional and absent");
    // A missing required field is named.
    match read_foreign_rows(&path, 0, &["x", "rho"], &[], 0..10) {
        Err(IoError::MissingField { field, step, .. }) => {
            assert_eq!((field.as_str(), step.as_str()), ("rho", "Step#0"))
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        read_foreign_rows(&path, 2, &["x"], &[], 0..1),
        Err(IoError::MissingStep { count: 2, .. })
    ));
}
