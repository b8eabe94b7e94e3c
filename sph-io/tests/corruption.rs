//! Random damage to a written file: a read either fails with an error (never
//! a panic) or returns exactly what was written; damage to any field's
//! values always fails.

mod common;

use std::path::Path;
use std::sync::OnceLock;

use proptest::prelude::*;
use sph_io::{FieldData, H5Part, IoError, Selection, Snapshot, SnapshotReader, SnapshotWriter};

struct Fixture {
    snaps: Vec<Snapshot>,
    bytes: Vec<u8>,
    /// Byte ranges of the field values in the file.
    payload: Vec<std::ops::Range<usize>>,
}

fn le_bytes(d: &FieldData) -> Vec<u8> {
    match d {
        FieldData::F64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        FieldData::U64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
    }
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let a = common::sample(50);
        let mut b = common::sample(20);
        b.step = 43;
        // Values unlike step 0's, so each field's bytes occur once in the file.
        b.set_field(
            "x",
            FieldData::F64((0..20).map(|i| i as f64 + 0.5).collect()),
        )
        .set_field(
            "y",
            FieldData::F64((0..20).map(|i| -(i as f64) - 0.25).collect()),
        )
        .set_field("id", FieldData::U64((1000..1020).collect()));
        let dir = common::scratch_dir();
        let path = dir.path().join("s.h5");
        // Step 1 is appended (an in-place edit of a copy), so damage to
        // both file shapes is exercised.
        H5Part.write(&path, &a, &Selection::All).unwrap();
        H5Part.append(&path, &b, &Selection::All).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let mut payload = Vec::new();
        for s in [&a, &b] {
            for f in &s.fields {
                let needle = le_bytes(&f.data);
                let mut hits = bytes
                    .windows(needle.len())
                    .enumerate()
                    .filter(|(_, w)| *w == needle);
                let (at, _) = hits.next().expect("field bytes in the file");
                assert!(hits.next().is_none(), "field bytes occur once");
                payload.push(at..at + needle.len());
            }
        }
        Fixture {
            snaps: vec![a, b],
            bytes,
            payload,
        }
    })
}

fn read_back(path: &Path) -> Result<Vec<Snapshot>, IoError> {
    H5Part.read_all(path, &Selection::All)
}

fn identical(read: &[Snapshot], snaps: &[Snapshot]) -> bool {
    read.len() == snaps.len() && read.iter().zip(snaps).all(|(a, b)| a.bits_eq(b))
}

#[test]
fn the_fixture_reads_back() {
    let fx = fixture();
    let dir = common::scratch_dir();
    let path = dir.path().join("s.h5");
    std::fs::write(&path, &fx.bytes).unwrap();
    assert!(identical(&read_back(&path).unwrap(), &fx.snaps));
    assert_eq!(fx.payload.len(), 6);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// One byte anywhere changed: an error or an identical read.
    #[test]
    fn a_changed_byte_is_detected_or_harmless(pos in any::<prop::sample::Index>(), mask in 1u8..=255) {
        let fx = fixture();
        let mut bytes = fx.bytes.clone();
        let i = pos.index(bytes.len());
        bytes[i] ^= mask;
        let dir = common::scratch_dir();
        let path = dir.path().join("s.h5");
        std::fs::write(&path, &bytes).unwrap();
        match read_back(&path) {
            Ok(read) => {
                prop_assert!(identical(&read, &fx.snaps), "byte {} ^ {:#x} read back different data", i, mask);
                prop_assert!(!fx.payload.iter().any(|r| r.contains(&i)), "payload byte {} ^ {:#x} undetected", i, mask);
            }
            Err(e) => prop_assert!(e.to_string().contains("s.h5"), "{}", e),
        }
    }

    /// One byte of field values changed: always a checksum error naming the
    /// field.
    #[test]
    fn a_changed_value_byte_is_always_detected(which in 0usize..6, off in any::<prop::sample::Index>(), mask in 1u8..=255) {
        let fx = fixture();
        let r = fx.payload[which].clone();
        let i = r.start + off.index(r.len());
        let mut bytes = fx.bytes.clone();
        bytes[i] ^= mask;
        let dir = common::scratch_dir();
        let path = dir.path().join("s.h5");
        std::fs::write(&path, &bytes).unwrap();
        let e = read_back(&path).unwrap_err();
        let field = &fx.snaps[which / 3].fields[which % 3].name;
        let step = format!("Step#{}", which / 3);
        prop_assert!(
            matches!(&e, IoError::Checksum { field: f, step: s, .. } if f == field && *s == step),
            "{}", e
        );
    }

    /// A burst of up to 16 random bytes written anywhere: an error or an
    /// identical read.
    #[test]
    fn a_scribbled_run_is_detected_or_harmless(pos in any::<prop::sample::Index>(), junk in prop::collection::vec(any::<u8>(), 1..16)) {
        let fx = fixture();
        let mut bytes = fx.bytes.clone();
        let i = pos.index(bytes.len());
        let end = (i + junk.len()).min(bytes.len());
        bytes[i..end].copy_from_slice(&junk[..end - i]);
        let dir = common::scratch_dir();
        let path = dir.path().join("s.h5");
        std::fs::write(&path, &bytes).unwrap();
        if let Ok(read) = read_back(&path) {
            prop_assert!(identical(&read, &fx.snaps));
        }
    }

    /// Any truncation (a torn write) is an error.
    #[test]
    fn a_truncated_file_is_an_error(keep in any::<prop::sample::Index>()) {
        let fx = fixture();
        let n = keep.index(fx.bytes.len());
        let dir = common::scratch_dir();
        let path = dir.path().join("s.h5");
        std::fs::write(&path, &fx.bytes[..n]).unwrap();
        let e = read_back(&path).unwrap_err();
        prop_assert!(e.to_string().contains("s.h5"), "{}", e);
    }
}
