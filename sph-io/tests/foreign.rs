//! Files in SPH-EXA's H5Part layout (no checksums, no field table, `f32`
//! fields, integer ids, attributes named as SPH-EXA names them), built here
//! with the HDF5 encoder directly, read by `sph_io::foreign`.

use hdf5_pure::{AttrValue, FileBuilder};
use sph_io::foreign::{read_foreign_rows, step_count};
use sph_io::IoError;

fn sphexa_like(path: &std::path::Path, n: usize) {
    let mut b = FileBuilder::new();
    b.set_attr("numParticlesGlobal", AttrValue::U64(n as u64));
    for k in 0..2 {
        let mut g = b.create_group(&format!("Step#{k}"));
        g.set_attr("time", AttrValue::F64(0.25 + k as f64));
        g.set_attr("iteration", AttrValue::I64(10 + k as i64));
        g.set_attr("minDt", AttrValue::F64(1e-3));
        g.set_attr(
            "box",
            AttrValue::F64Array(vec![-1.0, 1.0, -2.0, 2.0, -3.0, 3.0]),
        );
        let x: Vec<f64> = (0..n).map(|i| i as f64 / n as f64 + k as f64).collect();
        g.create_dataset("x").with_f64_data(&x);
        let h: Vec<f32> = (0..n).map(|i| 0.5 + i as f32 / 8.0).collect();
        g.create_dataset("h").with_f32_data(&h);
        let id: Vec<u64> = (0..n as u64).map(|i| 100 + i).collect();
        g.create_dataset("id").with_u64_data(&id);
        b.add_group(g.finish());
    }
    std::fs::write(path, b.finish().unwrap()).unwrap();
}

#[test]
fn sphexa_layout_reads_with_conversions_and_row_ranges() {
    let d = std::env::temp_dir().join(format!("sph-io-foreign-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let path = d.join("sphexa.h5");
    sphexa_like(&path, 10);
    assert_eq!(step_count(&path).unwrap(), 2);
    let s = read_foreign_rows(&path, 1, &["x", "h"], &["id", "vx"], 2..5).unwrap();
    assert_eq!(s.group, "Step#1");
    assert_eq!(
        (s.time, s.iteration, s.dt, s.total),
        (Some(1.25), Some(11), Some(1e-3), 10)
    );
    assert_eq!(s.bbox, Some([-1.0, 1.0, -2.0, 2.0, -3.0, 3.0]));
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
    std::fs::remove_dir_all(&d).ok();
}
