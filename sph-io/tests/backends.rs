//! The two backends (feature `hdf5-c`): what the libhdf5 one writes the
//! pure-Rust one reads and the other way round, every bit of every field
//! and attribute; the libhdf5 reader's errors are the pure-Rust reader's.
#![cfg(feature = "hdf5-c")]

mod common;

use std::path::{Path, PathBuf};

use hdf5_pure::{AttrValue, File};
use proptest::prelude::*;
use sph_io::{
    Attr, FieldData, H5Part, H5PartC, IoError, Selection, Snapshot, SnapshotReader, SnapshotWriter,
};

fn write(backend: &str, path: &Path, snaps: &[&Snapshot]) {
    match backend {
        "c" => H5PartC.write_steps(path, snaps, &Selection::All).unwrap(),
        _ => H5Part.write_steps(path, snaps, &Selection::All).unwrap(),
    }
}

fn read_all(backend: &str, path: &Path) -> Vec<Snapshot> {
    match backend {
        "c" => H5PartC.read_all(path, &Selection::All).unwrap(),
        _ => H5Part.read_all(path, &Selection::All).unwrap(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Random snapshots (any f64 bit pattern, u64 fields, every attribute
    /// kind, 0..40 particles) written by each backend, read by both.
    #[test]
    fn each_backend_reads_the_other_bitwise(
        snaps in prop::collection::vec(common::snapshot(5, 40), 1..3),
    ) {
        let dir = common::scratch_dir();
        let refs: Vec<&Snapshot> = snaps.iter().collect();
        for writer in ["c", "pure"] {
            let path = dir.path().join(format!("{writer}.h5"));
            write(writer, &path, &refs);
            let tmp = dir.path().join(format!("{writer}.h5.tmp"));
            prop_assert!(!tmp.exists());
            for reader in ["c", "pure"] {
                let back = read_all(reader, &path);
                prop_assert_eq!(back.len(), snaps.len());
                for (a, b) in snaps.iter().zip(&back) {
                    prop_assert!(a.bits_eq(b), "{} -> {}: wrote {:?}\nread {:?}", writer, reader, a, b);
                }
            }
        }
    }

    /// Appends alternate between the backends on one file.
    #[test]
    fn appends_mix_backends(snaps in prop::collection::vec(common::snapshot(3, 20), 1..5)) {
        let dir = common::scratch_dir();
        let path = dir.path().join("mixed.h5");
        for (k, s) in snaps.iter().enumerate() {
            let got = if k % 2 == 0 {
                H5PartC.append(&path, s, &Selection::All).unwrap()
            } else {
                H5Part.append(&path, s, &Selection::All).unwrap()
            };
            prop_assert_eq!(got, k);
        }
        for reader in ["c", "pure"] {
            let back = read_all(reader, &path);
            prop_assert_eq!(back.len(), snaps.len());
            for (a, b) in snaps.iter().zip(&back) {
                prop_assert!(a.bits_eq(b), "read by {}", reader);
            }
        }
    }
}

#[test]
fn selections_and_step_counts_agree() {
    let dir = common::scratch_dir();
    let path = dir.path().join("s.h5");
    let (a, b) = (common::sample(100), common::sample(7));
    H5PartC
        .write(&path, &a, &Selection::names(&["id", "x"]))
        .unwrap();
    assert_eq!(H5PartC.append(&path, &b, &Selection::All).unwrap(), 1);
    assert_eq!(H5Part.step_count(&path).unwrap(), 2);
    assert_eq!(H5PartC.step_count(&path).unwrap(), 2);
    let sel = Selection::names(&["x", "id"]);
    for s in [
        H5Part.read_step(&path, 0, &sel).unwrap(),
        H5PartC.read_step(&path, 0, &sel).unwrap(),
    ] {
        let names: Vec<&str> = s.fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["x", "id"]);
        assert!(s.field("x").unwrap().bits_eq(a.field("x").unwrap()));
    }
    assert!(H5Part
        .read_step(&path, 1, &Selection::All)
        .unwrap()
        .bits_eq(&b));
}

/// String attributes of every width the libhdf5 backend passes through its
/// fixed-size buffers (1 byte to 60,000 bytes), both ways; one over 64 KiB
/// is refused with an error naming it on write (libhdf5's object header
/// limit) and on read, no file left behind.
#[test]
fn long_string_attributes() {
    let dir = common::scratch_dir();
    let path = dir.path().join("s.h5");
    let mut s = common::sample(3);
    for (i, len) in [0usize, 1, 64, 65, 1024, 1025, 5000, 16385, 60000]
        .into_iter()
        .enumerate()
    {
        let text: String = (0..len)
            .map(|j| (b'a' + ((i + j) % 26) as u8) as char)
            .collect();
        s.set_attr(&format!("s{len}"), Attr::Str(text));
    }
    s.set_attr("utf8", Attr::Str("ρ ≥ 0, ħ/2".into()));
    for writer in ["c", "pure"] {
        write(writer, &path, &[&s]);
        for reader in ["c", "pure"] {
            assert!(
                read_all(reader, &path)[0].bits_eq(&s),
                "{writer} -> {reader}"
            );
        }
    }

    s.set_attr("too_long", Attr::Str("x".repeat(65537)));
    let e = H5PartC.write(&path, &s, &Selection::All).unwrap_err();
    assert!(matches!(&e, IoError::Format { .. }), "{e}");
    assert!(e.to_string().contains("too_long"), "{e}");
    assert!(!dir.path().join("s.h5.tmp").exists());
    // The file of before is untouched.
    assert_eq!(H5PartC.step_count(&path).unwrap(), 1);
    H5Part.write(&path, &s, &Selection::All).unwrap();
    let e = H5PartC.read_step(&path, 0, &Selection::All).unwrap_err();
    assert!(e.to_string().contains("too_long"), "{e}");
}

// The libhdf5 reader's errors, on the files `errors.rs` builds for the
// pure-Rust reader.

fn written(dir: &Path, by_c: bool) -> PathBuf {
    let path = dir.join("snap.h5");
    let s = common::sample(16);
    if by_c {
        H5PartC.write(&path, &s, &Selection::All).unwrap();
    } else {
        H5Part.write(&path, &s, &Selection::All).unwrap();
    }
    path
}

fn read_c(path: &Path) -> Result<Snapshot, IoError> {
    H5PartC.read_step(path, 0, &Selection::All)
}

fn edit(path: &Path, f: impl FnOnce(&File)) {
    let file = File::open_rw(path).unwrap();
    f(&file);
    file.commit().unwrap();
}

#[test]
fn c_reader_missing_file_and_other_formats() {
    let dir = common::scratch_dir();
    let path = dir.path().join("nope.h5");
    let e = read_c(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::Io { path: p, .. } if *p == path),
        "{e}"
    );
    assert!(H5PartC.step_count(&path).is_err());
    for (name, bytes) in [("empty.h5", &b""[..]), ("text.h5", &b"x,y,z\n1,2,3\n"[..])] {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let e = read_c(&path).unwrap_err();
        assert!(
            matches!(&e, IoError::NotHdf5 { path: p } if *p == path),
            "{e}"
        );
    }
}

#[test]
fn c_reader_truncated_file_is_an_error() {
    let dir = common::scratch_dir();
    for by_c in [true, false] {
        let path = written(dir.path(), by_c);
        let bytes = std::fs::read(&path).unwrap();
        for keep in [bytes.len() - 1, bytes.len() / 2, 600, 100, 8] {
            std::fs::write(&path, &bytes[..keep]).unwrap();
            let e = read_c(&path).unwrap_err();
            assert!(e.to_string().contains("snap.h5"), "{e}");
        }
    }
}

#[test]
fn c_reader_missing_step_and_field() {
    let dir = common::scratch_dir();
    for by_c in [true, false] {
        let path = written(dir.path(), by_c);
        let e = H5PartC.read_step(&path, 3, &Selection::All).unwrap_err();
        assert!(
            matches!(&e, IoError::MissingStep { step, count: 1, .. } if step == "Step#3"),
            "{e}"
        );
        let e = H5PartC
            .read_step(&path, 0, &Selection::names(&["x", "rho"]))
            .unwrap_err();
        assert!(
            matches!(&e, IoError::MissingField { step, field, .. } if step == "Step#0" && field == "rho"),
            "{e}"
        );
    }
    // A field listed in the step's table but absent from the group.
    let path = written(dir.path(), false);
    edit(&path, |f| f.group("Step#0").unwrap().delete("y").unwrap());
    let e = read_c(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::MissingField { field, .. } if field == "y"),
        "{e}"
    );
    let s = H5PartC
        .read_step(&path, 0, &Selection::names(&["x", "id"]))
        .unwrap();
    assert_eq!(s.len(), 16);
}

#[test]
fn c_reader_wrong_length_type_and_checksums() {
    let dir = common::scratch_dir();

    let path = written(dir.path(), false);
    let crc = FieldData::F64(vec![1.0; 15]).crc32();
    edit(&path, |f| {
        let g = f.group("Step#0").unwrap();
        g.delete("y").unwrap();
        g.create_dataset("y", |b| {
            b.with_f64_data(&[1.0; 15])
                .set_attr("crc32", AttrValue::U32(crc));
        })
        .unwrap();
    });
    let e = read_c(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::WrongLength { field, expected: 16, found: 15, .. } if field == "y"),
        "{e}"
    );

    let path = written(dir.path(), false);
    edit(&path, |f| {
        let g = f.group("Step#0").unwrap();
        g.delete("x").unwrap();
        g.create_dataset("x", |b| {
            b.with_i32_data(&[1; 16])
                .set_attr("crc32", AttrValue::U32(0));
        })
        .unwrap();
    });
    let e = read_c(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::WrongType { field, .. } if field == "x"),
        "{e}"
    );

    let path = written(dir.path(), false);
    edit(&path, |f| {
        f.dataset("Step#0/id").unwrap().write(&[5u64; 16]).unwrap();
    });
    let e = read_c(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::Checksum { field, .. } if field == "id"),
        "{e}"
    );

    let path = written(dir.path(), false);
    edit(&path, |f| {
        f.group("Step#0")
            .unwrap()
            .set_attr("time", AttrValue::F64(0.5))
            .unwrap()
    });
    let e = read_c(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::Checksum { field, .. } if field == "<metadata>"),
        "{e}"
    );

    let path = written(dir.path(), false);
    edit(&path, |f| {
        f.dataset("Step#0/x").unwrap().remove_attr("crc32").unwrap()
    });
    let e = read_c(&path).unwrap_err();
    assert!(
        matches!(&e, IoError::BadAttribute { attr, .. } if attr == "x/crc32"),
        "{e}"
    );
}

/// A byte of field data flipped in a file the C library wrote: the pure-Rust
/// reader and the C reader both report the field's checksum.
#[test]
fn flipped_value_byte_in_a_c_file_fails_the_checksum() {
    let dir = common::scratch_dir();
    let path = dir.path().join("snap.h5");
    let mut s = Snapshot::new(1, 0.0, 0.0, Default::default());
    s.set_field("x", FieldData::F64(vec![0.125; 4096]));
    H5PartC.write(&path, &s, &Selection::All).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    let needle = 0.125f64.to_le_bytes().repeat(8);
    let at = bytes
        .windows(needle.len())
        .position(|w| w == needle)
        .unwrap();
    bytes[at + 3] ^= 0x10;
    std::fs::write(&path, &bytes).unwrap();
    for e in [
        H5PartC.read_step(&path, 0, &Selection::All).unwrap_err(),
        H5Part.read_step(&path, 0, &Selection::All).unwrap_err(),
    ] {
        assert!(
            matches!(&e, IoError::Checksum { field, .. } if field == "x"),
            "{e}"
        );
    }
}

#[test]
fn c_writer_refuses_invalid_snapshots_and_leaves_no_file() {
    let dir = common::scratch_dir();
    let path = dir.path().join("bad.h5");
    let mut s = common::sample(4);
    s.set_field("short", FieldData::U64(vec![1, 2]));
    assert!(matches!(
        H5PartC.write(&path, &s, &Selection::All),
        Err(IoError::LengthMismatch { .. })
    ));
    let s = common::sample(4);
    assert!(matches!(
        H5PartC.write(&path, &s, &Selection::names(&["rho"])),
        Err(IoError::UnknownField { .. })
    ));
    let mut s = common::sample(4);
    s.set_attr("time", Attr::F64(1.0));
    assert!(matches!(
        H5PartC.write(&path, &s, &Selection::All),
        Err(IoError::ReservedName { .. })
    ));
    assert!(!path.exists() && !dir.path().join("bad.h5.tmp").exists());
    // Writing into a directory that does not exist is an error, not a panic.
    let e = H5PartC
        .write(
            &dir.path().join("no/such/dir.h5"),
            &common::sample(2),
            &Selection::All,
        )
        .unwrap_err();
    assert!(e.to_string().contains("dir.h5"), "{e}");
}
