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
