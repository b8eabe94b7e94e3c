//! Each way a write or a read can fail gives its own error, naming the file,
//! the step group and the field.

mod common;

use std::path::{Path, PathBuf};

use hdf5_pure::{AttrValue, File};
use sph_io::{Attr, FieldData, H5Part, IoError, Selection, SnapshotReader, SnapshotWriter};

fn written(dir: &Path) -> PathBuf {
    let path = dir.join("snap.h5");
    H5Part
        .write(&path, &common::sample(16), &Selection::All)
        .unwrap();
    path
}

fn read(path: &Path) -> Result<sph_io::Snapshot, IoError> {
    H5Part.read_step(path, 0, &Selection::All)
}

/// Applies one in-place edit to step group 0 of a written file.
fn edit(path: &Path, f: impl FnOnce(&File)) {
    let file = File::open_rw(path).unwrap();
    f(&file);
    file.commit().unwrap();
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let dir = common::scratch_dir();
    let path = dir.path().join("nope.h5");
    let e = read(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::Io { path: p, .. } if *p == path),
        "{e}"
    );
    assert!(e.to_string().contains("nope.h5"));
}

#[test]
fn other_formats_are_not_hdf5() {
    let dir = common::scratch_dir();
    for (name, bytes) in [
        ("empty.h5", &b""[..]),
        ("text.h5", &b"x,y,z\n1,2,3\n"[..]),
        ("png.h5", &b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR"[..]),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let e = read(&path).unwrap_err();
        assert!(
            matches!(&e, IoError::NotHdf5 { path: p } if *p == path),
            "{e}"
        );
        assert!(e.to_string().contains(name));
    }
}

#[test]
fn truncated_file_is_an_error() {
    let dir = common::scratch_dir();
    let path = written(dir.path());
    let bytes = std::fs::read(&path).unwrap();
    for keep in [bytes.len() - 1, bytes.len() / 2, 600, 100, 8] {
        std::fs::write(&path, &bytes[..keep]).unwrap();
        let e = read(&path).unwrap_err();
        assert!(e.to_string().contains("snap.h5"), "{e}");
    }
}

#[test]
fn missing_step_names_the_count() {
    let dir = common::scratch_dir();
    let path = written(dir.path());
    let e = H5Part.read_step(&path, 3, &Selection::All).unwrap_err();
    assert!(
        matches!(&e, IoError::MissingStep { step, count: 1, .. } if step == "Step#3"),
        "{e}"
    );
}

#[test]
fn reading_an_unknown_field_names_it() {
    let dir = common::scratch_dir();
    let path = written(dir.path());
    let e = H5Part
        .read_step(&path, 0, &Selection::names(&["x", "rho"]))
        .unwrap_err();
    assert!(
        matches!(&e, IoError::MissingField { step, field, .. } if step == "Step#0" && field == "rho"),
        "{e}"
    );
    assert_eq!(
        e.to_string(),
        format!("{}: Step#0: missing field 'rho'", path.display())
    );
}

#[test]
fn a_field_listed_but_absent_is_missing() {
    let dir = common::scratch_dir();
    let path = written(dir.path());
    edit(&path, |f| f.group("Step#0").unwrap().delete("y").unwrap());
    let e = read(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::MissingField { step, field, .. } if step == "Step#0" && field == "y"),
        "{e}"
    );
    // The other fields still read.
    let s = H5Part
        .read_step(&path, 0, &Selection::names(&["x", "id"]))
        .unwrap();
    assert_eq!(s.len(), 16);
}

#[test]
fn a_field_of_the_wrong_length_is_reported() {
    let dir = common::scratch_dir();
    let path = written(dir.path());
    let short = FieldData::F64(vec![1.0; 15]);
    let crc = short.crc32();
    edit(&path, |f| {
        let g = f.group("Step#0").unwrap();
        g.delete("y").unwrap();
        g.create_dataset("y", |b| {
            b.with_f64_data(&[1.0; 15])
                .set_attr("crc32", AttrValue::U32(crc));
        })
        .unwrap();
    });
    let e = read(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::WrongLength { step, field, expected: 16, found: 15, .. }
            if step == "Step#0" && field == "y"),
        "{e}"
    );
}

#[test]
fn a_field_of_the_wrong_type_is_reported() {
    let dir = common::scratch_dir();
    let path = written(dir.path());
    edit(&path, |f| {
        let g = f.group("Step#0").unwrap();
        g.delete("x").unwrap();
        g.create_dataset("x", |b| {
            b.with_i32_data(&[1; 16])
                .set_attr("crc32", AttrValue::U32(0));
        })
        .unwrap();
    });
    let e = read(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::WrongType { step, field, .. } if step == "Step#0" && field == "x"),
        "{e}"
    );
    assert!(e.to_string().contains("expected f64"), "{e}");
}

#[test]
fn changed_values_fail_the_field_checksum() {
    let dir = common::scratch_dir();
    let path = written(dir.path());
    edit(&path, |f| {
        let mut ds = f.dataset("Step#0/id").unwrap();
        ds.write(&[5u64; 16]).unwrap();
    });
    let e = read(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::Checksum { step, field, .. } if step == "Step#0" && field == "id"),
        "{e}"
    );
    assert!(e.to_string().contains("snap.h5"));
}

#[test]
fn changed_metadata_fails_the_step_checksum() {
    let dir = common::scratch_dir();
    let edits: [(&str, AttrValue); 4] = [
        ("time", AttrValue::F64(0.5)),
        ("iteration", AttrValue::U64(43)),
        ("scheme", AttrValue::String("ve".into())),
        ("numParticles", AttrValue::U64(16)), // same value: must still read
    ];
    for (attr, value) in edits {
        let path = written(dir.path());
        let same = attr == "numParticles";
        edit(&path, |f| {
            f.group("Step#0").unwrap().set_attr(attr, value).unwrap()
        });
        match read(&path) {
            Ok(s) => assert!(same && s.bits_eq(&common::sample(16))),
            Err(e) => {
                assert!(!same, "{e}");
                assert!(
                    matches!(&e, IoError::Checksum { field, .. } if field == "<metadata>"),
                    "{attr}: {e}"
                );
            }
        }
    }
}

#[test]
fn missing_or_mistyped_step_attributes_are_named() {
    let dir = common::scratch_dir();
    let path = written(dir.path());
    edit(&path, |f| {
        f.group("Step#0").unwrap().remove_attr("minDt").unwrap()
    });
    let e = read(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::BadAttribute { attr, .. } if attr == "minDt"),
        "{e}"
    );

    let path = written(dir.path());
    edit(&path, |f| {
        f.group("Step#0")
            .unwrap()
            .set_attr("box", AttrValue::F64Array(vec![0.0; 5]))
            .unwrap()
    });
    let e = read(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::BadAttribute { attr, .. } if attr == "box"),
        "{e}"
    );

    let path = written(dir.path());
    edit(&path, |f| {
        f.dataset("Step#0/x").unwrap().remove_attr("crc32").unwrap()
    });
    let e = read(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::BadAttribute { attr, .. } if attr == "x/crc32"),
        "{e}"
    );
}

#[test]
fn invalid_snapshots_are_refused_and_leave_no_file() {
    let dir = common::scratch_dir();
    let path = dir.path().join("bad.h5");
    let write = |s: &sph_io::Snapshot, sel: &Selection| {
        let r = H5Part.write(&path, s, sel);
        assert!(!path.exists() && !dir.path().join("bad.h5.tmp").exists());
        r.unwrap_err()
    };

    let mut s = common::sample(4);
    s.set_field("short", FieldData::U64(vec![1, 2]));
    assert!(
        matches!(write(&s, &Selection::All), IoError::LengthMismatch { field, expected: 4, found: 2 } if field == "short")
    );

    let mut s = common::sample(4);
    s.fields.push(s.fields[0].clone());
    assert!(matches!(write(&s, &Selection::All), IoError::DuplicateName { name } if name == "x"));

    let mut s = common::sample(4);
    s.set_field("a/b", FieldData::U64(vec![0; 4]));
    assert!(matches!(
        write(&s, &Selection::All),
        IoError::BadName { .. }
    ));

    let mut s = common::sample(4);
    s.set_attr("time", Attr::F64(1.0));
    assert!(matches!(write(&s, &Selection::All), IoError::ReservedName { name } if name == "time"));

    let s = common::sample(4);
    assert!(
        matches!(write(&s, &Selection::names(&["x", "rho"])), IoError::UnknownField { field } if field == "rho")
    );
}

#[test]
fn a_failed_write_keeps_the_old_file() {
    let dir = common::scratch_dir();
    let path = written(dir.path());
    let mut bad = common::sample(4);
    bad.set_field("short", FieldData::U64(vec![1]));
    assert!(H5Part.write(&path, &bad, &Selection::All).is_err());
    assert!(read(&path).unwrap().bits_eq(&common::sample(16)));
}

#[test]
fn a_leftover_tmp_file_does_not_matter() {
    let dir = common::scratch_dir();
    let path = written(dir.path());
    // A crash mid-write leaves a torn NAME.tmp beside an intact NAME.
    std::fs::write(dir.path().join("snap.h5.tmp"), b"\x89HDF\r\n\x1a\ntorn").unwrap();
    assert!(read(&path).unwrap().bits_eq(&common::sample(16)));
    H5Part
        .write(&path, &common::sample(3), &Selection::All)
        .unwrap();
    assert_eq!(read(&path).unwrap().len(), 3);
    assert!(!dir.path().join("snap.h5.tmp").exists());
}
