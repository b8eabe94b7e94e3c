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

/// Lookup3 (`hashlittle`, initial value 0): the checksum of HDF5's
/// version-2 object headers, to re-seal a header after patching it.
fn lookup3(data: &[u8]) -> u32 {
    let word = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    let mut a = 0xdead_beef_u32.wrapping_add(data.len() as u32);
    let (mut b, mut c) = (a, a);
    let mut rest = data;
    while rest.len() > 12 {
        a = a.wrapping_add(word(&rest[0..]));
        b = b.wrapping_add(word(&rest[4..]));
        c = c.wrapping_add(word(&rest[8..]));
        // mix(a, b, c)
        a = a.wrapping_sub(c) ^ c.rotate_left(4);
        c = c.wrapping_add(b);
        b = b.wrapping_sub(a) ^ a.rotate_left(6);
        a = a.wrapping_add(c);
        c = c.wrapping_sub(b) ^ b.rotate_left(8);
        b = b.wrapping_add(a);
        a = a.wrapping_sub(c) ^ c.rotate_left(16);
        c = c.wrapping_add(b);
        b = b.wrapping_sub(a) ^ a.rotate_left(19);
        a = a.wrapping_add(c);
        c = c.wrapping_sub(b) ^ b.rotate_left(4);
        b = b.wrapping_add(a);
        rest = &rest[12..];
    }
    if rest.is_empty() {
        return c;
    }
    let mut tail = [0u8; 12];
    tail[..rest.len()].copy_from_slice(rest);
    a = a.wrapping_add(word(&tail[0..]));
    b = b.wrapping_add(word(&tail[4..]));
    c = c.wrapping_add(word(&tail[8..]));
    // final(a, b, c)
    c = (c ^ b).wrapping_sub(b.rotate_left(14));
    a = (a ^ c).wrapping_sub(c.rotate_left(11));
    b = (b ^ a).wrapping_sub(a.rotate_left(25));
    c = (c ^ b).wrapping_sub(b.rotate_left(16));
    a = (a ^ c).wrapping_sub(c.rotate_left(4));
    b = (b ^ a).wrapping_sub(a.rotate_left(14));
    c = (c ^ b).wrapping_sub(b.rotate_left(24));
    c
}

/// The one position of `needle` in `hay`.
fn find_unique(hay: &[u8], needle: &[u8]) -> usize {
    let hits: Vec<usize> = (0..=hay.len() - needle.len())
        .filter(|&i| hay[i..].starts_with(needle))
        .collect();
    assert_eq!(hits.len(), 1, "{needle:?} at {hits:?}");
    hits[0]
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
    // Dataspace message (version 2): version, rank 1, flags 0, simple, dims[0] = 7.
    let mut space = vec![2, 1, 0, 1];
    space.extend(7u64.to_le_bytes());
    let dims = find_unique(&f, &space) + 4;
    // Layout message (version 3 or 4), contiguous: address, then size 56.
    let layouts: Vec<usize> = (0..f.len() - 18)
        .filter(|&i| {
            matches!(f[i], 3 | 4) && f[i + 1] == 1 && f[i + 10..i + 18] == 56u64.to_le_bytes()
        })
        .collect();
    assert_eq!(layouts.len(), 1, "layout messages at {layouts:?}");
    let layout = layouts[0];
    // The object header holding them: "OHDR", version, flags, optional
    // times (flag 0x20) and attribute thresholds (0x10), the size of chunk 0
    // in 1 << (flags & 3) bytes, the messages, then the checksum.
    let start = (0..dims)
        .rev()
        .find(|&i| f[i..].starts_with(b"OHDR"))
        .unwrap();
    let flags = f[start + 5];
    let mut at = start + 6;
    at += if flags & 0x20 != 0 { 16 } else { 0 };
    at += if flags & 0x10 != 0 { 4 } else { 0 };
    let width = 1usize << (flags & 3);
    let mut size = [0u8; 8];
    size[..width].copy_from_slice(&f[at..at + width]);
    let end = at + width + u64::from_le_bytes(size) as usize;
    assert!(layout < end, "layout outside the header");
    let stored = |f: &[u8]| u32::from_le_bytes(f[end..end + 4].try_into().unwrap());
    assert_eq!(
        lookup3(&f[start..end]),
        stored(&f),
        "lookup3 over the header as parsed is not its stored checksum"
    );
    f[dims..dims + 8].copy_from_slice(&count.to_le_bytes());
    f[layout + 2..layout + 10].fill(0xff); // undefined address: never allocated
    f[layout + 10..layout + 18].copy_from_slice(&count.wrapping_mul(8).to_le_bytes());
    let sum = lookup3(&f[start..end]);
    f[end..end + 4].copy_from_slice(&sum.to_le_bytes());
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
