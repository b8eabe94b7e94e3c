//! Slab writes and reads (one step shared by several writers or readers):
//! a file written by N writers is byte for byte the file one process writes,
//! and M readers get back every row, whatever N and M; a corrupted value is
//! found by the combined checksums.

mod common;

use std::path::Path;

use proptest::prelude::*;
use sph_io::slab::{self, SlabSummary};
use sph_io::{
    Field, FieldData, H5Part, IoError, Selection, Snapshot, SnapshotReader, SnapshotWriter,
};

/// Rows `lo..hi` of every field of `snap`.
fn rows(snap: &Snapshot, lo: usize, hi: usize) -> Snapshot {
    let mut s = snap.clone();
    for f in &mut s.fields {
        f.data = match &f.data {
            FieldData::F64(v) => FieldData::F64(v[lo..hi].to_vec()),
            FieldData::U64(v) => FieldData::U64(v[lo..hi].to_vec()),
        };
    }
    s
}

/// Writes `snap` as `writers` slabs of near-equal size (the steps each
/// rank of a distributed write takes, run one after the other).
fn write_in_slabs(path: &Path, snap: &Snapshot, writers: usize) -> Result<(), IoError> {
    let n = snap.len();
    let parts: Vec<Snapshot> = (0..writers)
        .map(|r| rows(snap, n * r / writers, n * (r + 1) / writers))
        .collect();
    let summaries = parts
        .iter()
        .map(|p| SlabSummary::of(p, &Selection::All))
        .collect::<Result<Vec<_>, _>>()?;
    let offsets = slab::create_layout(path, snap, &summaries)?;
    let mut first = 0;
    for p in &parts {
        slab::write_slab(path, &offsets, first, p, &Selection::All)?;
        first += p.len() as u64;
    }
    slab::commit(path)
}

/// Reads `path` as `readers` row ranges, verifies the combined checksums
/// and glues the rows back together.
fn read_in_slabs(path: &Path, readers: usize) -> Result<Snapshot, IoError> {
    let (_, n, _) = slab::read_rows(path, 0, &Selection::All, 0..0)?;
    let mut whole: Option<Snapshot> = None;
    let mut checks = Vec::new();
    for r in 0..readers as u64 {
        let range = n * r / readers as u64..n * (r + 1) / readers as u64;
        let (part, total, c) = slab::read_rows(path, 0, &Selection::All, range)?;
        assert_eq!(total, n);
        checks.push(c);
        match whole.as_mut() {
            None => whole = Some(part),
            Some(w) => {
                for (f, g) in w.fields.iter_mut().zip(part.fields) {
                    match (&mut f.data, g.data) {
                        (FieldData::F64(a), FieldData::F64(b)) => a.extend(b),
                        (FieldData::U64(a), FieldData::U64(b)) => a.extend(b),
                        _ => panic!("types differ between readers"),
                    }
                }
            }
        }
    }
    slab::verify(path, 0, &checks)?;
    Ok(whole.expect("at least one reader"))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn slabs_write_the_one_process_file_and_read_back_on_any_count(
        snap in common::snapshot(5, 60),
        writers in 1usize..5,
        readers in 1usize..5,
    ) {
        let d = common::scratch_dir();
        let one = d.path().join("one.h5");
        let many = d.path().join("many.h5");
        H5Part.write(&one, &snap, &Selection::All).unwrap();
        write_in_slabs(&many, &snap, writers).unwrap();
        prop_assert!(std::fs::read(&one).unwrap() == std::fs::read(&many).unwrap(),
            "{writers} writers: the file differs from the one-process file");
        let back = read_in_slabs(&many, readers).unwrap();
        prop_assert!(back.bits_eq(&snap), "{readers} readers");
    }
}

#[test]
fn a_changed_value_in_any_slab_fails_the_combined_checksum() {
    let d = common::scratch_dir();
    let path = d.path().join("c.h5");
    let mut snap = Snapshot::default();
    snap.set_field(
        "x",
        FieldData::F64((0..1000).map(|i| i as f64 * 0.5).collect()),
    )
    .set_field("id", FieldData::U64((0..1000).collect()));
    write_in_slabs(&path, &snap, 3).unwrap();
    // Flip one bit of x[700] (a value of the third writer's slab): find it
    // by its bytes, independently of the layout code.
    let mut bytes = std::fs::read(&path).unwrap();
    let needle = 350.0f64.to_le_bytes();
    let at = bytes
        .windows(8)
        .position(|w| w == needle)
        .expect("x[700] is in the file");
    bytes[at] ^= 1;
    std::fs::write(&path, &bytes).unwrap();
    for readers in 1..=4 {
        match read_in_slabs(&path, readers) {
            Err(IoError::Checksum { field, step, .. }) => {
                assert_eq!((field.as_str(), step.as_str()), ("x", "Step#0"))
            }
            other => panic!("{readers} readers: {other:?}"),
        }
    }
    // The whole-file reader agrees.
    assert!(matches!(
        H5Part.read_step(&path, 0, &Selection::All),
        Err(IoError::Checksum { .. })
    ));
}

#[test]
fn slabs_that_disagree_on_the_fields_are_refused_and_leave_no_file() {
    let d = common::scratch_dir();
    let path = d.path().join("d.h5");
    let mut a = Snapshot::default();
    a.set_field("x", FieldData::F64(vec![1.0, 2.0]));
    let mut b = Snapshot::default();
    b.fields.push(Field {
        name: "y".into(),
        data: FieldData::F64(vec![3.0]),
    });
    let s = [
        SlabSummary::of(&a, &Selection::All).unwrap(),
        SlabSummary::of(&b, &Selection::All).unwrap(),
    ];
    let e = slab::create_layout(&path, &a, &s).unwrap_err();
    assert!(e.to_string().contains("slab 1"), "{e}");
    assert!(!path.exists());
    assert!(!d.path().join("d.h5.tmp").exists());
}

#[test]
fn an_uncommitted_write_leaves_the_old_file() {
    let d = common::scratch_dir();
    let path = d.path().join("u.h5");
    let mut old = Snapshot::default();
    old.set_field("x", FieldData::F64(vec![1.0; 10]));
    H5Part.write(&path, &old, &Selection::All).unwrap();
    let mut new = Snapshot::default();
    new.set_field("x", FieldData::F64(vec![2.0; 10]));
    let s = [SlabSummary::of(&new, &Selection::All).unwrap()];
    let offsets = slab::create_layout(&path, &new, &s).unwrap();
    slab::write_slab(&path, &offsets, 0, &new, &Selection::All).unwrap();
    // No commit (the process died): the old file is what reads back.
    let back = H5Part.read_step(&path, 0, &Selection::All).unwrap();
    assert!(back.bits_eq(&old));
}
