//! Hostile input for the SPH-EXA-layout reader (`sph_io::foreign`): random
//! bytes, every truncation and bit flips of a valid file never panic (an
//! `Ok` or an error naming the file), and a dataset whose count claims more
//! than the file holds is refused by name before anything is allocated.

mod common;

use std::path::Path;

use hdf5_pure::FileBuilder;
use proptest::prelude::*;
use sph_io::foreign::{read_foreign_rows, step_count, ForeignStep};
use sph_io::IoError;

/// Everything the reader offers: the step count, then every step with all
/// its rows (required `x`, `h`; optional `id`, `vx`).
fn read_all(path: &Path) -> Result<Vec<ForeignStep>, IoError> {
    let n = step_count(path)?;
    (0..n)
        .map(|k| read_foreign_rows(path, k, &["x", "h"], &["id", "vx"], 0..u64::MAX))
        .collect()
}

/// The fixture: two steps of 10 particles.
fn fixture() -> Vec<u8> {
    common::sphexa_bytes(10)
}

/// What a read gave: the steps, or the error's message.
type Outcome = Result<Vec<ForeignStep>, String>;

/// Writes `bytes` to `name`, reads it (a panic fails the test), and checks
/// what any input must give: an error whose message names the file and
/// says more, or steps whose fields each hold `total` values.
fn read_hostile(name: &str, bytes: &[u8]) -> Result<Outcome, TestCaseError> {
    let path = common::scratch_path(name);
    std::fs::write(&path, bytes).unwrap();
    match read_all(&path) {
        Ok(steps) => {
            for s in &steps {
                for (f, v) in &s.fields {
                    prop_assert_eq!(v.len() as u64, s.total, "{} {}", s.group, f);
                }
            }
            Ok(Ok(steps))
        }
        Err(e) => {
            let msg = e.to_string();
            let p = path.display().to_string();
            prop_assert!(msg.starts_with(&p) && msg.len() > p.len() + 2, "{}", msg);
            Ok(Err(msg))
        }
    }
}

#[test]
fn the_fixture_reads() {
    let steps = read_hostile("hostile-fixture.h5", &fixture())
        .unwrap()
        .unwrap();
    assert_eq!(steps.len(), 2);
    assert_eq!(steps[1].total, 10);
    assert_eq!(steps[1].field("h").unwrap()[2], 0.75);
}

/// Every truncation (a torn copy; the last bytes are field values) is an
/// error naming the file.
#[test]
fn every_truncation_is_an_error() {
    let bytes = fixture();
    for len in 0..bytes.len() {
        match read_hostile("hostile-trunc.h5", &bytes[..len]) {
            Ok(Ok(steps)) => panic!("truncated to {len} bytes: read {steps:?}"),
            Ok(Err(_)) => {}
            Err(e) => panic!("truncated to {len} bytes: {e}"),
        }
    }
}

/// Every single-bit flip of the file: no panic, an error naming the file
/// or consistent steps.
#[test]
fn every_bit_flip_is_an_error_or_consistent() {
    let bytes = fixture();
    for i in 0..bytes.len() {
        for bit in 0..8 {
            let mut b = bytes.clone();
            b[i] ^= 1 << bit;
            if let Err(e) = read_hostile("hostile-flip.h5", &b) {
                panic!("byte {i} bit {bit}: {e}");
            }
        }
    }
}

/// A valid HDF5 file whose dataset `Step#0/x` (f64) claims `count` values
/// with no storage allocated, as libhdf5 writes a dataset never written to:
/// a reader that trusts the count fills `8 * count` bytes with the fill
/// value. Made from a 7-value file by patching the dataspace and layout
/// messages and re-sealing the object header's checksum.
fn claims_values(count: u64) -> Vec<u8> {
    let mut b = FileBuilder::new();
    let mut g = b.create_group("Step#0");
    g.create_dataset("x").with_f64_data(&[0.5; 7]);
    b.add_group(g.finish());
    let mut f = b.finish().unwrap();
    common::claim_count(&mut f, 7, count);
    f
}

/// A count beyond the file is refused by name, before the decoder fills
/// 8 TiB (2^40 values: without the check the process aborts on the
/// allocation) or a caller sizes arrays by `total` (the row window 0..0);
/// the largest count the file could hold still reads (as fill values).
#[test]
fn a_count_beyond_the_file_is_refused_by_name() {
    let path = common::scratch_path("hostile-count.h5");
    // Padded to whole values, so that the largest count fills it exactly.
    let len = claims_values(7).len().next_multiple_of(8) as u64;
    // 2^40 values (8 TiB), a count whose byte size overflows u64, one value
    // too many, and exactly as many as the file could hold.
    for (count, refused) in [
        (1u64 << 40, true),
        (u64::MAX / 4, true),
        (len / 8 + 1, true),
        (len / 8, false),
    ] {
        let mut bytes = claims_values(count);
        bytes.resize(len as usize, 0);
        std::fs::write(&path, bytes).unwrap();
        assert_eq!(step_count(&path).unwrap(), 1);
        for rows in [0..u64::MAX, 0..0] {
            let r = read_foreign_rows(&path, 0, &["x"], &[], rows.clone());
            match (refused, r) {
                (true, Err(e)) => {
                    let msg = e.to_string();
                    assert!(
                        matches!(&e, IoError::BeyondFile { step, field, count: c, size: 8, file_len, .. }
                            if step == "Step#0" && field == "x" && *c == count && *file_len == len),
                        "{msg}"
                    );
                    assert_eq!(
                        msg,
                        format!(
                            "{}: Step#0: field 'x' claims {count} values of 8 bytes, more than the file's {len} bytes",
                            path.display()
                        )
                    );
                }
                (false, Ok(st)) => {
                    assert_eq!(st.total, count);
                    assert_eq!(st.field("x").unwrap().len() as u64, count.min(rows.end));
                }
                (_, r) => panic!("count {count}, rows {rows:?}: {r:?}"),
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// Random bytes: after nothing, after the HDF5 signature, or after a
    /// prefix of the valid file (so parsing gets past the superblock).
    #[test]
    fn random_bytes_never_panic(keep in 0usize..3, cut in any::<prop::sample::Index>(), junk in prop::collection::vec(any::<u8>(), 0..2048)) {
        let mut bytes = match keep {
            0 => Vec::new(),
            1 => fixture()[..8].to_vec(),
            _ => {
                let f = fixture();
                f[..cut.index(f.len())].to_vec()
            }
        };
        bytes.extend(junk);
        // Steps or an error: either is fine once read_hostile's checks pass.
        let _ = read_hostile("hostile-random.h5", &bytes)?;
    }

    /// A burst of up to 16 random bytes written anywhere into the valid file.
    #[test]
    fn a_scribbled_run_never_panics(pos in any::<prop::sample::Index>(), junk in prop::collection::vec(any::<u8>(), 1..16)) {
        let mut bytes = fixture();
        let i = pos.index(bytes.len());
        let end = (i + junk.len()).min(bytes.len());
        bytes[i..end].copy_from_slice(&junk[..end - i]);
        // Steps or an error: either is fine once read_hostile's checks pass.
        let _ = read_hostile("hostile-scribble.h5", &bytes)?;
    }
}
