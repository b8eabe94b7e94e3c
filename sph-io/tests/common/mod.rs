//! Shared helpers and proptest strategies.
#![allow(dead_code)]

use hdf5_pure::{AttrValue, FileBuilder};
use proptest::prelude::*;
use sph_io::{Attr, BoxSpec, Field, FieldData, Snapshot};

/// A file in SPH-EXA's H5Part layout (no checksums, no field table, `f32`
/// fields, integer ids, attributes named as SPH-EXA names them), built with
/// the HDF5 encoder directly: steps 0 and 1 of `n` particles with fields
/// `x` (f64), `h` (f32) and `id` (u64).
pub fn sphexa_bytes(n: usize) -> Vec<u8> {
    let mut b = FileBuilder::new();
    b.set_attr("numParticlesGlobal", AttrValue::U64(n as u64));
    for k in 0..2 {
        let mut g = b.create_group(&format!("Step#{k}"));
        g.set_attr("time", AttrValue::F64(0.25 + k as f64));
        g.set_attr("iteration", AttrValue::I64(10 + k as i64));
        g.set_attr("minDt", AttrValue::F64(1e-3));
        g.set_attr("boundaryType", AttrValue::I8Array(vec![1, 0, 1]));
        g.set_attr("gamma", AttrValue::F32(1.5));
        g.set_attr("kernelChoice", AttrValue::String("sinc".into()));
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
    b.finish().unwrap()
}

/// `name` in a directory of this crate's tests under the target directory.
pub fn scratch_path(name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("sph-io-tests");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A fresh empty directory under the target directory, removed with its
/// contents when dropped: what these tests write into instead of the
/// system temp dir (`cargo test` writes nothing outside the clone and its
/// target directory, wherever HOME and TMPDIR point).
pub struct ScratchDir(std::path::PathBuf);

impl ScratchDir {
    /// The directory.
    pub fn path(&self) -> &std::path::Path {
        &self.0
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A new [`ScratchDir`], `sph-io-tests/TEST-PID-K` under
/// `CARGO_TARGET_TMPDIR` (unique among the tests of this process, which run
/// on several threads; one left by a killed run whose process id comes
/// round again is emptied first).
pub fn scratch_dir() -> ScratchDir {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let k = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("sph-io-tests")
        .join(format!(
            "{}-{}-{k}",
            env!("CARGO_CRATE_NAME"),
            std::process::id()
        ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    ScratchDir(dir)
}

/// Lookup3 (`hashlittle`, initial value 0): the checksum of HDF5's
/// version-2 object headers, to re-seal a header after patching it.
pub fn lookup3(data: &[u8]) -> u32 {
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
pub fn find_unique(hay: &[u8], needle: &[u8]) -> usize {
    let hits: Vec<usize> = (0..=hay.len() - needle.len())
        .filter(|&i| hay[i..].starts_with(needle))
        .collect();
    assert_eq!(hits.len(), 1, "{needle:?} at {hits:?}");
    hits[0]
}

/// Makes the one 1-D dataset of `values` 8-byte values in `f` (an HDF5
/// file from hdf5-pure's encoder) claim `count` values with no storage
/// allocated, as libhdf5 writes a dataset never written to: a reader that
/// trusts the count fills `8 * count` bytes with the fill value. Patches
/// its dataspace and layout messages and re-seals its object header's
/// checksum, so the file is valid HDF5.
pub fn claim_count(f: &mut [u8], values: u64, count: u64) {
    // Dataspace message (version 2): version, rank 1, flags 0, simple, dims[0].
    let mut space = vec![2, 1, 0, 1];
    space.extend(values.to_le_bytes());
    let dims = find_unique(f, &space) + 4;
    // Layout message (version 3 or 4), contiguous: address, then size.
    let layouts: Vec<usize> = (0..f.len() - 18)
        .filter(|&i| {
            matches!(f[i], 3 | 4)
                && f[i + 1] == 1
                && f[i + 10..i + 18] == (8 * values).to_le_bytes()
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
        stored(f),
        "lookup3 over the header as parsed is not its stored checksum"
    );
    f[dims..dims + 8].copy_from_slice(&count.to_le_bytes());
    f[layout + 2..layout + 10].fill(0xff); // undefined address: never allocated
    f[layout + 10..layout + 18].copy_from_slice(&count.wrapping_mul(8).to_le_bytes());
    let sum = lookup3(&f[start..end]);
    f[end..end + 4].copy_from_slice(&sum.to_le_bytes());
}

/// Any `f64` bit pattern (NaNs with payloads, infinities, -0.0, subnormals).
pub fn any_f64() -> impl Strategy<Value = f64> {
    any::<u64>().prop_map(f64::from_bits)
}

pub fn attr_value() -> impl Strategy<Value = Attr> {
    prop_oneof![
        any_f64().prop_map(Attr::F64),
        any::<i64>().prop_map(Attr::I64),
        "[^\u{0}]{0,24}".prop_map(Attr::Str),
        prop::collection::vec(any_f64(), 0..8).prop_map(Attr::F64Array),
    ]
}

pub fn bbox() -> impl Strategy<Value = BoxSpec> {
    (
        prop::array::uniform3(any_f64()),
        prop::array::uniform3(any_f64()),
        prop::array::uniform3(any::<bool>()),
    )
        .prop_map(|(lo, hi, periodic)| BoxSpec { lo, hi, periodic })
}

/// A snapshot with up to `max_fields` fields of `0..max_len` particles and up
/// to 6 attributes of every kind; names unique and not reserved.
pub fn snapshot(max_fields: usize, max_len: usize) -> impl Strategy<Value = Snapshot> {
    let names = prop::collection::btree_set("[a-z][a-z0-9_]{0,7}", 0..=max_fields + 6);
    (
        any::<u64>(),
        any_f64(),
        any_f64(),
        bbox(),
        names,
        0..max_len,
        any::<u64>(),
    )
        .prop_flat_map(move |(step, time, dt, bbox, names, n, _)| {
            let names: Vec<String> = names
                .into_iter()
                .filter(|s| !sph_io::h5part::RESERVED_ATTRS.contains(&s.as_str()))
                .collect();
            let nf = names.len().min(max_fields);
            let (fnames, anames) = names.split_at(nf);
            let fnames = fnames.to_vec();
            let anames = anames.to_vec();
            let fields = fnames
                .into_iter()
                .map(move |name| {
                    prop_oneof![
                        prop::collection::vec(any_f64(), n).prop_map(FieldData::F64),
                        prop::collection::vec(any::<u64>(), n).prop_map(FieldData::U64),
                    ]
                    .prop_map(move |data| Field {
                        name: name.clone(),
                        data,
                    })
                })
                .collect::<Vec<_>>();
            let attrs = anames
                .into_iter()
                .map(|name| attr_value().prop_map(move |v| (name.clone(), v)))
                .collect::<Vec<_>>();
            (fields, attrs).prop_map(move |(fields, attrs)| Snapshot {
                step,
                time,
                dt,
                bbox,
                attrs,
                fields,
            })
        })
}

/// A fixed snapshot: `n` particles, fields x, y (f64) and id (u64), two
/// attributes.
pub fn sample(n: usize) -> Snapshot {
    let bbox = BoxSpec {
        lo: [-1.0, -2.0, -3.0],
        hi: [1.0, 2.0, 3.0],
        periodic: [true, false, true],
    };
    let mut s = Snapshot::new(42, 0.125, 1e-3, bbox);
    s.set_attr("scheme", Attr::Str("std".into()))
        .set_attr("ng0", Attr::I64(100))
        .set_field(
            "x",
            FieldData::F64((0..n).map(|i| (i as f64 * 0.37).sin()).collect()),
        )
        .set_field(
            "y",
            FieldData::F64((0..n).map(|i| (i as f64 * 1.91).cos() + 2.0).collect()),
        )
        .set_field(
            "id",
            FieldData::U64(
                (0..n as u64)
                    .map(|i| i.wrapping_mul(0x9E37_79B9_7F4A_7C15))
                    .collect(),
            ),
        );
    s
}
