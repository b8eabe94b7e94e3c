//! Write then read: every bit of every field and attribute comes back.

mod common;

use proptest::prelude::*;
use sph_io::{FieldData, H5Part, Selection, Snapshot, SnapshotReader, SnapshotWriter};

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn one_step_round_trips_bitwise(snap in common::snapshot(5, 40)) {
        let dir = common::scratch_dir();
        let path = dir.path().join("s.h5");
        H5Part.write(&path, &snap, &Selection::All).unwrap();
        prop_assert_eq!(H5Part.step_count(&path).unwrap(), 1);
        let back = H5Part.read_step(&path, 0, &Selection::All).unwrap();
        prop_assert!(back.bits_eq(&snap), "wrote {:?}\nread {:?}", snap, back);
        // No temporary file is left behind.
        prop_assert!(!dir.path().join("s.h5.tmp").exists());
    }

    #[test]
    fn several_steps_round_trip_bitwise(snaps in prop::collection::vec(common::snapshot(3, 20), 1..4)) {
        let dir = common::scratch_dir();
        let path = dir.path().join("s.h5");
        let refs: Vec<&Snapshot> = snaps.iter().collect();
        H5Part.write_steps(&path, &refs, &Selection::All).unwrap();
        let back = H5Part.read_all(&path, &Selection::All).unwrap();
        prop_assert_eq!(back.len(), snaps.len());
        for (a, b) in snaps.iter().zip(&back) {
            prop_assert!(a.bits_eq(b));
        }
    }

    /// Writing a subset writes exactly those fields in that order; reading a
    /// subset returns exactly those, in the order asked.
    #[test]
    fn selections_write_and_read_by_name(snap in common::snapshot(5, 10), pick in any::<u64>(), rev in any::<bool>()) {
        let dir = common::scratch_dir();
        let path = dir.path().join("s.h5");
        let mut names: Vec<String> = snap
            .fields
            .iter()
            .enumerate()
            .filter(|(i, _)| pick >> (i % 64) & 1 == 1)
            .map(|(_, f)| f.name.clone())
            .collect();
        if rev {
            names.reverse();
        }
        H5Part.write(&path, &snap, &Selection::Names(names.clone())).unwrap();
        let all = H5Part.read_step(&path, 0, &Selection::All).unwrap();
        prop_assert_eq!(all.fields.iter().map(|f| f.name.clone()).collect::<Vec<_>>(), names.clone());
        for f in &all.fields {
            prop_assert!(snap.field(&f.name).unwrap().bits_eq(&f.data));
        }
        let mut back_names = names.clone();
        back_names.reverse();
        let some = H5Part.read_step(&path, 0, &Selection::Names(back_names.clone())).unwrap();
        prop_assert_eq!(some.fields.iter().map(|f| f.name.clone()).collect::<Vec<_>>(), back_names);
    }
}

#[test]
fn extreme_values_round_trip() {
    let dir = common::scratch_dir();
    let path = dir.path().join("s.h5");
    let mut s = common::sample(0);
    let specials = vec![
        f64::NAN,
        f64::from_bits(0x7ff0_0000_0000_0001),
        f64::from_bits(0xfff8_dead_beef_0000),
        f64::INFINITY,
        f64::NEG_INFINITY,
        -0.0,
        f64::MIN_POSITIVE / 2.0,
        f64::MAX,
    ];
    let n = specials.len();
    s.fields.clear();
    s.set_field("f", FieldData::F64(specials)).set_field(
        "u",
        FieldData::U64(vec![0, 1, u64::MAX, u64::MAX - 1, 1 << 63, 2, 3, 4]),
    );
    s.time = f64::NAN;
    s.step = u64::MAX;
    assert_eq!(s.len(), n);
    H5Part.write(&path, &s, &Selection::All).unwrap();
    assert!(H5Part
        .read_step(&path, 0, &Selection::All)
        .unwrap()
        .bits_eq(&s));
}

#[test]
fn overwrite_replaces_the_file() {
    let dir = common::scratch_dir();
    let path = dir.path().join("s.h5");
    let a = common::sample(10);
    let mut b = common::sample(3);
    b.step = 7;
    H5Part.write(&path, &a, &Selection::All).unwrap();
    H5Part.write(&path, &b, &Selection::All).unwrap();
    assert!(H5Part
        .read_step(&path, 0, &Selection::All)
        .unwrap()
        .bits_eq(&b));
}

/// Fields longer than one read window (65536 rows) come back whole, and a
/// changed byte in a later window is still caught.
#[test]
fn fields_longer_than_a_read_window_round_trip() {
    let dir = common::scratch_dir();
    let path = dir.path().join("big.h5");
    let s = common::sample(150_001);
    H5Part.write(&path, &s, &Selection::All).unwrap();
    assert!(H5Part
        .read_step(&path, 0, &Selection::All)
        .unwrap()
        .bits_eq(&s));

    let mut bytes = std::fs::read(&path).unwrap();
    let last_id = s.field("id").unwrap().as_u64().unwrap()[150_000].to_le_bytes();
    let at = bytes.windows(8).rposition(|w| w == last_id).unwrap();
    bytes[at + 3] ^= 0x10;
    std::fs::write(&path, &bytes).unwrap();
    let e = H5Part
        .read_step(&path, 0, &Selection::names(&["id"]))
        .unwrap_err();
    assert!(
        matches!(&e, sph_io::IoError::Checksum { field, .. } if field == "id"),
        "{e}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    /// Appending steps one at a time gives the same snapshots as writing
    /// them together.
    #[test]
    fn appended_steps_round_trip_bitwise(snaps in prop::collection::vec(common::snapshot(3, 20), 1..5)) {
        let dir = common::scratch_dir();
        let path = dir.path().join("run.h5");
        for (k, s) in snaps.iter().enumerate() {
            prop_assert_eq!(H5Part.append(&path, s, &Selection::All).unwrap(), k);
        }
        let back = H5Part.read_all(&path, &Selection::All).unwrap();
        prop_assert_eq!(back.len(), snaps.len());
        for (a, b) in snaps.iter().zip(&back) {
            prop_assert!(a.bits_eq(b));
        }
        prop_assert!(!dir.path().join("run.h5.tmp").exists());
    }
}

/// Many steps in one file (past the 8 links a compact group holds), each
/// with more than 8 attributes, appended to a file written whole.
#[test]
fn many_appended_steps() {
    let dir = common::scratch_dir();
    let path = dir.path().join("run.h5");
    let mut all: Vec<Snapshot> = (0..3)
        .map(|k| {
            let mut s = common::sample(10 + k);
            s.step = k as u64;
            s
        })
        .collect();
    H5Part
        .write_steps(&path, &all.iter().collect::<Vec<_>>(), &Selection::All)
        .unwrap();
    for k in 3..20 {
        let mut s = common::sample(5 + k);
        s.step = k as u64;
        s.time = k as f64 * 0.01;
        for a in 0..6 {
            s.set_attr(&format!("setting{a}"), sph_io::Attr::F64(a as f64));
        }
        assert_eq!(
            H5Part
                .append(&path, &s, &Selection::names(&["id", "x"]))
                .unwrap(),
            k
        );
        let mut kept = s.clone();
        kept.fields.retain(|f| f.name != "y");
        kept.fields.reverse();
        all.push(kept);
    }
    let back = H5Part.read_all(&path, &Selection::All).unwrap();
    assert_eq!(back.len(), 20);
    for (a, b) in all.iter().zip(&back) {
        assert!(a.bits_eq(b), "step {}", a.step);
    }
    // An invalid snapshot leaves the file as it was.
    let mut bad = common::sample(4);
    bad.set_field("short", FieldData::U64(vec![1]));
    assert!(H5Part.append(&path, &bad, &Selection::All).is_err());
    assert_eq!(H5Part.step_count(&path).unwrap(), 20);
    assert!(!dir.path().join("run.h5.tmp").exists());
}
