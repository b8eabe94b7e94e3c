//! A forged file of this crate's own H5Part layout: a step whose particle
//! count (`numParticles`, with the metadata checksum over it recomputed)
//! and whose field's shape claim more values than the file holds is
//! refused by name before anything is allocated for them.

mod common;

use std::path::Path;

use hdf5_pure::{AttrValue, FileBuilder};
use sph_io::{slab, FieldData, H5Part, IoError, Selection, SnapshotReader};

const STEP: u64 = 3;
const TIME: f64 = 0.5;
const DT: f64 = 1e-3;
const BOX: [f64; 6] = [-1.0, 1.0, -2.0, 2.0, -3.0, 3.0];
const PERIODIC: [u8; 3] = [1, 0, 1];

/// The metadata checksum of a step with the constants above, `n`
/// particles, one `f64` field `x` and no user attributes, computed here
/// from the layout's definition (CRC32 over the little-endian step, time,
/// dt, box, periodic flags, count, then the field table and the user
/// attributes, each list led by its length, each name by its length) as a
/// forger would.
fn meta_crc(n: u64) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(&STEP.to_le_bytes());
    h.update(&TIME.to_le_bytes());
    h.update(&DT.to_le_bytes());
    for x in BOX {
        h.update(&x.to_le_bytes());
    }
    h.update(&PERIODIC);
    h.update(&n.to_le_bytes());
    h.update(&1u64.to_le_bytes()); // one field:
    h.update(&1u64.to_le_bytes()); // its name's length,
    h.update(b"x"); // its name,
    h.update(&[0]); // its type (FieldType::F64).
    h.update(&0u64.to_le_bytes()); // no user attributes
    h.finalize()
}

/// A valid HDF5 file of this crate's layout: one step of `count` particles
/// (its metadata checksum recomputed for that count) with one field `x`
/// whose stored CRC32 is `crc`. Written with 7 values of 0.5; for any other
/// count the dataset is patched to claim `count` values with no storage
/// allocated (`common::claim_count`, the object header re-sealed).
fn forged(count: u64, crc: u32) -> Vec<u8> {
    let mut b = FileBuilder::new();
    let mut g = b.create_group("Step#0");
    g.set_attr("time", AttrValue::F64(TIME));
    g.set_attr("iteration", AttrValue::U64(STEP));
    g.set_attr("minDt", AttrValue::F64(DT));
    g.set_attr("box", AttrValue::F64Array(BOX.to_vec()));
    g.set_attr("periodic", AttrValue::U8Array(PERIODIC.to_vec()));
    g.set_attr("numParticles", AttrValue::U64(count));
    g.set_attr("sph_io_fields", AttrValue::StringArray(vec!["x".into()]));
    g.set_attr("sph_io_types", AttrValue::StringArray(vec!["f64".into()]));
    g.set_attr("sph_io_meta_crc32", AttrValue::U32(meta_crc(count)));
    g.create_dataset("x")
        .with_f64_data(&[0.5; 7])
        .set_attr("crc32", AttrValue::U32(crc));
    b.add_group(g.finish());
    let mut f = b.finish().unwrap();
    if count != 7 {
        common::claim_count(&mut f, 7, count);
    }
    f
}

/// One way of reading and what it gave: field `x`'s values and the step's
/// total row count.
type Read = (&'static str, Result<(Vec<f64>, u64), IoError>);

/// Every way to read step 0's field `x`.
fn reads(path: &Path) -> Vec<Read> {
    let x = |s: &sph_io::Snapshot| s.field("x").and_then(FieldData::as_f64).unwrap().to_vec();
    #[cfg_attr(not(feature = "hdf5-c"), allow(unused_mut))]
    let mut reads = vec![
        (
            "read_step",
            H5Part
                .read_step(path, 0, &Selection::All)
                .map(|s| (x(&s), s.len() as u64)),
        ),
        (
            "read_all",
            H5Part
                .read_all(path, &Selection::names(&["x"]))
                .map(|s| (x(&s[0]), s[0].len() as u64)),
        ),
        // The head read that a distributed read sizes its shares by.
        (
            "slab rows 0..0",
            slab::read_rows(path, 0, &Selection::All, 0..0).map(|(s, n, _)| (x(&s), n)),
        ),
        (
            "slab rows 0..",
            slab::read_rows(path, 0, &Selection::All, 0..u64::MAX).and_then(|(s, n, checks)| {
                slab::verify(path, 0, &[checks])?;
                Ok((x(&s), n))
            }),
        ),
    ];
    #[cfg(feature = "hdf5-c")]
    reads.push((
        "H5PartC read_step",
        sph_io::H5PartC
            .read_step(path, 0, &Selection::All)
            .map(|s| (x(&s), s.len() as u64)),
    ));
    reads
}

/// The forger's file as written (7 values) reads back: the recomputed
/// metadata checksum is the one the reader computes, so a refusal below
/// is the count's, not a checksum's.
#[test]
fn the_forgers_checksum_is_the_readers() {
    let dir = common::scratch_dir();
    let path = dir.path().join("forged-7.h5");
    let crc = FieldData::F64(vec![0.5; 7]).crc32();
    std::fs::write(&path, forged(7, crc)).unwrap();
    for (how, r) in reads(&path) {
        let (x, total) = r.unwrap_or_else(|e| panic!("{how}: {e}"));
        assert_eq!(total, 7, "{how}");
        let rows = if how == "slab rows 0..0" { 0 } else { 7 };
        assert_eq!(x, vec![0.5; rows], "{how}");
    }
    // And a count the checksum does not cover is still caught by it.
    let mut bytes = forged(7, crc);
    let at = common::find_unique(&bytes, &meta_crc(7).to_le_bytes());
    bytes[at] ^= 1;
    std::fs::write(&path, bytes).unwrap();
    assert!(matches!(
        H5Part.read_step(&path, 0, &Selection::All),
        Err(IoError::Checksum { field, .. }) if field == "<metadata>"
    ));
}

/// Counts whose values cannot all be in the file (2^40 values: 8 TiB, on
/// which the reader's allocation aborted the process before the check; a
/// count whose byte size overflows u64; one value more than the file could
/// hold) are refused with `BeyondFile` naming the file, step, field and
/// claim, by every read including the metadata-only head read. The largest
/// count the file could hold passes the check and reads as fill values.
#[test]
fn a_count_beyond_the_file_is_refused_by_name() {
    let dir = common::scratch_dir();
    let path = dir.path().join("forged.h5");
    // Padded to whole values, so that the largest count fills it exactly.
    let len = forged(7, 0).len().next_multiple_of(8) as u64;
    for (count, refused) in [
        (1u64 << 40, true),
        (u64::MAX / 4, true),
        (len / 8 + 1, true),
        (len / 8, false),
    ] {
        // For the count that fits, the CRC32 of its fill values (zeros), so
        // that it reads through.
        let fill = if refused { 0 } else { count as usize };
        let mut bytes = forged(count, FieldData::F64(vec![0.0; fill]).crc32());
        bytes.resize(len as usize, 0);
        std::fs::write(&path, bytes).unwrap();
        assert_eq!(H5Part.step_count(&path).unwrap(), 1);
        for (how, r) in reads(&path) {
            match (refused, r) {
                (true, Err(e)) => {
                    let msg = e.to_string();
                    assert!(
                        matches!(&e, IoError::BeyondFile { path: p, step, field, count: c, size: 8, file_len }
                            if p == &path && step == "Step#0" && field == "x" && *c == count && *file_len == len),
                        "{how}: {msg}"
                    );
                    assert_eq!(
                        msg,
                        format!(
                            "{}: Step#0: field 'x' claims {count} values of 8 bytes, more than the file's {len} bytes",
                            path.display()
                        ),
                        "{how}"
                    );
                }
                (false, Ok((x, total))) => {
                    assert_eq!(total, count, "{how}");
                    let rows = if how == "slab rows 0..0" { 0 } else { fill };
                    assert_eq!(x, vec![0.0; rows], "{how}");
                }
                (_, r) => panic!("count {count}, {how}: {r:?}"),
            }
        }
    }
}
