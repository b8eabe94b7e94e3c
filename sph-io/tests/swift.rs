//! The SWIFT/GADGET layout (`sph_io::swift`): an h5py-written IC file
//! (tests/data, made by make_swift_ics.py) read to its known values; write
//! then read exact, by hand and over random particle sets; snapshots in
//! several files; every refusal by its own error, and no panic on corrupt
//! bytes.

mod common;

use std::path::{Path, PathBuf};

use hdf5_pure::{AttrValue, FileBuilder};
use proptest::prelude::*;
use sph_io::swift::{
    read_swift, swift_h_per_h, write_swift, SwiftKernel, SwiftParticles, SwiftUnits,
    GADGET_TO_SPH_EXA_H, UNIT_NAMES,
};
use sph_io::IoError;

// ---------------------------------------------------------------------------
// A file built attribute by attribute, to break one thing at a time.

/// A dataset of `PartType0`.
#[derive(Clone)]
enum Data {
    F32(Vec<f32>, Vec<u64>),
    F64(Vec<f64>, Vec<u64>),
    U32(Vec<u32>),
    I64(Vec<i64>),
}

/// The groups of a SWIFT/GADGET file: attributes by group, datasets of
/// `PartType0`, and extra groups.
#[derive(Clone)]
struct Spec {
    header: Vec<(String, AttrValue)>,
    units: Option<Vec<(String, AttrValue)>>,
    gas: Option<Vec<(String, Data)>>,
    extra_groups: Vec<(String, Vec<(String, AttrValue)>)>,
}

impl Spec {
    /// `n` valid gas particles, IC names, masses in the datasets, ids
    /// `first_id..`; header for one file of `n`.
    fn ics(n: usize, first_id: u32) -> Spec {
        let nn = n as u64;
        let col = |f: &dyn Fn(usize) -> f64| (0..n).map(f).collect::<Vec<f64>>();
        let vec3 = |f: &dyn Fn(usize, usize) -> f64| {
            let mut v = Vec::with_capacity(3 * n);
            for i in 0..n {
                for k in 0..3 {
                    v.push(f(i, k));
                }
            }
            Data::F64(v, vec![nn, 3])
        };
        let header = vec![
            ("BoxSize".into(), AttrValue::F64(2.0)),
            (
                "NumPart_ThisFile".into(),
                AttrValue::I64Array(vec![n as i64, 0, 0, 0, 0, 0]),
            ),
            (
                "NumPart_Total".into(),
                AttrValue::U32Array(vec![n as u32, 0, 0, 0, 0, 0]),
            ),
            (
                "NumPart_Total_HighWord".into(),
                AttrValue::U32Array(vec![0; 6]),
            ),
            ("MassTable".into(), AttrValue::F64Array(vec![0.0; 6])),
            ("Time".into(), AttrValue::F64(0.5)),
            ("Flag_Entropy_ICs".into(), AttrValue::I32(0)),
            ("NumFilesPerSnapshot".into(), AttrValue::I32(1)),
            ("Dimension".into(), AttrValue::I32(3)),
        ];
        let first = first_id as usize;
        let gas = vec![
            (
                "Coordinates".into(),
                vec3(&|i, k| (i + first) as f64 / 64.0 + k as f64 / 4.0),
            ),
            ("Velocities".into(), vec3(&|i, k| i as f64 - k as f64)),
            (
                "Masses".into(),
                Data::F64(col(&|i| 1.0 + i as f64), vec![nn]),
            ),
            (
                "SmoothingLength".into(),
                Data::F64(col(&|_| 0.25), vec![nn]),
            ),
            (
                "InternalEnergy".into(),
                Data::F64(col(&|i| 2.0 + i as f64 / 8.0), vec![nn]),
            ),
            (
                "ParticleIDs".into(),
                Data::U32((0..n as u32).map(|i| first_id + i).collect()),
            ),
        ];
        Spec {
            header,
            units: None,
            gas: Some(gas),
            extra_groups: Vec::new(),
        }
    }

    fn set_header(mut self, name: &str, value: AttrValue) -> Spec {
        self.header.retain(|(n, _)| n != name);
        self.header.push((name.into(), value));
        self
    }

    fn drop_header(mut self, name: &str) -> Spec {
        self.header.retain(|(n, _)| n != name);
        self
    }

    fn set_gas(mut self, name: &str, data: Data) -> Spec {
        let gas = self.gas.as_mut().unwrap();
        gas.retain(|(n, _)| n != name);
        gas.push((name.into(), data));
        self
    }

    fn drop_gas(mut self, name: &str) -> Spec {
        self.gas.as_mut().unwrap().retain(|(n, _)| n != name);
        self
    }

    fn group(mut self, name: &str, attrs: Vec<(&str, AttrValue)>) -> Spec {
        self.extra_groups.push((
            name.into(),
            attrs.into_iter().map(|(n, v)| (n.into(), v)).collect(),
        ));
        self
    }

    fn bytes(&self) -> Vec<u8> {
        let mut b = FileBuilder::new();
        let mut attr_group = |name: &str, attrs: &[(String, AttrValue)]| {
            let mut g = b.create_group(name);
            for (n, v) in attrs {
                g.set_attr(n, v.clone());
            }
            b.add_group(g.finish());
        };
        attr_group("Header", &self.header);
        if let Some(u) = &self.units {
            attr_group("Units", u);
        }
        for (name, attrs) in &self.extra_groups {
            attr_group(name, attrs);
        }
        if let Some(gas) = &self.gas {
            let mut g = b.create_group("PartType0");
            for (name, data) in gas {
                let ds = g.create_dataset(name);
                match data {
                    Data::F32(v, shape) => ds.with_f32_data(v).with_shape(shape),
                    Data::F64(v, shape) => ds.with_f64_data(v).with_shape(shape),
                    Data::U32(v) => ds.with_u32_data(v),
                    Data::I64(v) => ds.with_i64_data(v),
                };
            }
            b.add_group(g.finish());
        }
        b.finish().unwrap()
    }

    fn write(&self, path: &Path) -> PathBuf {
        std::fs::write(path, self.bytes()).unwrap();
        path.to_owned()
    }
}

/// Reads `spec` written to a scratch file: the error (a success fails).
fn refused(spec: &Spec) -> IoError {
    let dir = common::scratch_dir();
    let path = spec.write(&dir.path().join("ics.hdf5"));
    let e = read_swift(&path).expect_err("the file must be refused");
    let msg = e.to_string();
    assert!(msg.contains("ics.hdf5"), "the error names the file: {msg}");
    e
}

// ---------------------------------------------------------------------------
// The h5py fixture.

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/swift_ics_64.hdf5")
}

#[test]
fn h5py_ics_fixture_reads_to_the_values_its_script_wrote() {
    let f = read_swift(&fixture()).unwrap();
    let p = &f.particles;
    assert_eq!(p.len(), 64);
    assert_eq!(p.box_size, [1.0; 3], "scalar BoxSize is a cube");
    assert_eq!(p.time, 0.25);
    for i in 0..64 {
        let (ix, iy, iz) = (i / 16, (i / 4) % 4, i % 4);
        let fi = i as f64;
        assert_eq!(
            [p.x[i], p.y[i], p.z[i]],
            [ix, iy, iz].map(|c| (c as f64 + 0.5) / 4.0),
            "row {i}"
        );
        assert_eq!(
            [p.vx[i], p.vy[i], p.vz[i]],
            [
                ((i % 7) as f64 - 3.0) / 8.0,
                ((i % 5) as f64 - 2.0) / 4.0,
                -fi / 64.0
            ]
        );
        // f32 0.3 widened exactly, not 0.3.
        assert_eq!(p.h[i], f64::from(0.3f32));
        assert_eq!(p.u[i], 1.5 + fi / 64.0);
        assert_eq!(p.m[i], 1.0 / 64.0, "from MassTable[0]");
        assert_eq!(p.id[i], 1000 + i as u64);
    }
    assert_eq!((p.rho.as_ref(), p.p.as_ref()), (None, None));
    assert_eq!(
        p.units,
        Some(SwiftUnits {
            length: 3.08567758e24,
            mass: 1.98848e43,
            time: 3.08567758e19,
            current: 1.0,
            temperature: 1.0,
        })
    );
    let h = &f.header;
    assert_eq!(h.num_part_total, vec![64, 0, 0, 0, 0, 0]);
    assert_eq!((h.num_files, h.num_part_per_file.clone()), (1, vec![64]));
    assert_eq!(h.files, vec![fixture()]);
    assert!(h.masses_from_table);
    assert_eq!(h.mass_table[0], 1.0 / 64.0);
    assert_eq!(
        (h.h_dataset, h.u_dataset),
        ("SmoothingLength", "InternalEnergy")
    );
    assert_eq!(
        (h.dimension, h.redshift, h.scale_factor),
        (Some(3), None, None)
    );
    assert_eq!((h.kernel, h.kernel_name.as_deref()), (None, None));
}

#[test]
fn fixture_rewritten_by_write_swift_reads_back_the_same() {
    let dir = common::scratch_dir();
    let path = dir.path().join("again.hdf5");
    let a = read_swift(&fixture()).unwrap();
    write_swift(&path, &a.particles).unwrap();
    let b = read_swift(&path).unwrap();
    assert_eq!(a.particles, b.particles);
    assert_eq!(
        (b.header.h_dataset, b.header.u_dataset),
        ("SmoothingLengths", "InternalEnergies")
    );
    assert!(!b.header.masses_from_table);
    assert_eq!(b.header.mass_table, vec![0.0; 6]);
    assert_eq!(
        (b.header.dimension, b.header.redshift, b.header.scale_factor),
        (Some(3), Some(0.0), Some(1.0))
    );
}

// ---------------------------------------------------------------------------
// Write then read.

fn sample(n: usize) -> SwiftParticles {
    let f = |k: f64| (0..n).map(|i| k * (i as f64 + 1.0)).collect::<Vec<_>>();
    SwiftParticles {
        x: f(0.01),
        y: f(0.02),
        z: f(0.03),
        vx: f(-1.0),
        vy: f(1e-300),
        vz: f(1e300),
        m: f(0.1),
        h: f(0.7),
        u: f(3.0),
        id: (0..n as u64).map(|i| u64::MAX - i).collect(),
        rho: Some(f(5.0)),
        p: Some(f(7.0)),
        box_size: [1.0, 2.0, 3.5],
        time: 0.125,
        units: Some(SwiftUnits {
            length: 3.085e21,
            mass: 1.989e33,
            time: 3.156e13,
            current: 1.0,
            temperature: 1.0,
        }),
    }
}

/// Every value compared by its bits.
fn bits_eq(a: &SwiftParticles, b: &SwiftParticles) -> bool {
    let f = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let cols = |p: &SwiftParticles| {
        [&p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz, &p.m, &p.h, &p.u]
            .map(|v| f(v))
            .to_vec()
    };
    cols(a) == cols(b)
        && a.id == b.id
        && a.rho.as_deref().map(f) == b.rho.as_deref().map(f)
        && a.p.as_deref().map(f) == b.p.as_deref().map(f)
        && a.box_size.map(f64::to_bits) == b.box_size.map(f64::to_bits)
        && a.time.to_bits() == b.time.to_bits()
        && a.units.unwrap_or_default() == b.units.unwrap_or_default()
}

#[test]
fn write_then_read_is_exact_and_atomic() {
    let dir = common::scratch_dir();
    let path = dir.path().join("snap_0000.hdf5");
    let gas = sample(10);
    write_swift(&path, &gas).unwrap();
    assert!(!dir.path().join("snap_0000.hdf5.tmp").exists());
    let back = read_swift(&path).unwrap();
    assert!(bits_eq(&back.particles, &gas));
    assert_eq!(back.particles, gas);
    let h = &back.header;
    assert_eq!(h.num_part_total, vec![10, 0, 0, 0, 0, 0]);
    assert_eq!(h.num_files, 1);
    // Without densities and pressures, and without units: ONES are written.
    let mut bare = sample(3);
    (bare.rho, bare.p, bare.units) = (None, None, None);
    write_swift(&path, &bare).unwrap();
    let back = read_swift(&path).unwrap().particles;
    assert_eq!((back.rho, back.p), (None, None));
    assert_eq!(back.units, Some(SwiftUnits::ONES));
    // No particles at all.
    let empty = SwiftParticles {
        box_size: [1.0; 3],
        ..SwiftParticles::default()
    };
    write_swift(&path, &empty).unwrap();
    let back = read_swift(&path).unwrap();
    assert!(back.particles.is_empty());
    assert_eq!(back.header.num_part_total[0], 0);
}

#[test]
fn the_writer_refuses_what_no_reader_should_get() {
    let dir = common::scratch_dir();
    let path = dir.path().join("w.hdf5");
    let mut short = sample(4);
    short.u.pop();
    assert!(matches!(
        write_swift(&path, &short),
        Err(IoError::LengthMismatch { ref field, expected: 4, found: 3 }) if field == "u"
    ));
    let mut rho = sample(4);
    rho.rho.as_mut().unwrap().push(1.0);
    assert!(matches!(
        write_swift(&path, &rho),
        Err(IoError::LengthMismatch { ref field, .. }) if field == "rho"
    ));
    let mut nan = sample(4);
    nan.vy[2] = f64::NAN;
    match write_swift(&path, &nan) {
        Err(IoError::NonFinite { field, index, .. }) => {
            assert_eq!((field.as_str(), index), ("PartType0/Velocities", 7))
        }
        other => panic!("{other:?}"),
    }
    let mut flat = sample(4);
    flat.box_size[1] = 0.0;
    assert!(matches!(
        write_swift(&path, &flat),
        Err(IoError::SwiftLayout { .. })
    ));
    let mut t = sample(4);
    t.time = f64::INFINITY;
    assert!(matches!(
        write_swift(&path, &t),
        Err(IoError::NonFinite { ref field, .. }) if field == "Header/Time"
    ));
    assert!(!path.exists(), "nothing written");
}

fn particles(max: usize) -> impl Strategy<Value = SwiftParticles> {
    let finite = prop_oneof![
        -1e6..1e6f64,
        any::<f64>().prop_filter("finite", |x| x.is_finite())
    ];
    (0..max)
        .prop_flat_map(move |n| {
            let col = prop::collection::vec(finite.clone(), n);
            (
                prop::collection::vec(col.clone(), 9),
                prop::collection::vec(any::<u64>(), n),
                prop::option::of(col.clone()),
                prop::option::of(col),
                prop::array::uniform3(1e-3..1e9f64),
                -1e3..1e3f64,
                prop::option::of(prop::array::uniform5(1e-30..1e30f64)),
            )
        })
        .prop_map(|(mut c, id, rho, p, box_size, time, units)| {
            let mut take = || c.remove(0);
            SwiftParticles {
                x: take(),
                y: take(),
                z: take(),
                vx: take(),
                vy: take(),
                vz: take(),
                m: take(),
                h: take(),
                u: take(),
                id,
                rho,
                p,
                box_size,
                time,
                units: units.map(|u| SwiftUnits {
                    length: u[0],
                    mass: u[1],
                    time: u[2],
                    current: u[3],
                    temperature: u[4],
                }),
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn random_particle_sets_round_trip_bitwise(gas in particles(40)) {
        let dir = common::scratch_dir();
        let path = dir.path().join("r.hdf5");
        write_swift(&path, &gas).unwrap();
        let back = read_swift(&path).unwrap();
        prop_assert!(bits_eq(&back.particles, &gas), "wrote {:?}\nread {:?}", gas, back.particles);
        prop_assert_eq!(back.particles.units, Some(gas.units.unwrap_or(SwiftUnits::ONES)));
        prop_assert_eq!(back.header.num_part_total[0], gas.len() as u64);
    }
}

// ---------------------------------------------------------------------------
// Snapshots in several files.

/// Pieces `snap.K.hdf5` of 3 files with 4, 0 and 5 particles.
fn pieces(dir: &Path, edit: impl Fn(usize, Spec) -> Spec) -> Vec<PathBuf> {
    let counts = [4usize, 0, 5];
    let mut first = 1;
    counts
        .iter()
        .enumerate()
        .map(|(k, &n)| {
            let spec = Spec::ics(n, first)
                .set_header("NumFilesPerSnapshot", AttrValue::I32(3))
                .set_header("NumPart_Total", AttrValue::U32Array(vec![9, 0, 0, 0, 0, 0]));
            first += n as u32;
            edit(k, spec).write(&dir.join(format!("snap.{k}.hdf5")))
        })
        .collect()
}

#[test]
fn a_snapshot_in_several_files_reads_as_one_from_any_piece() {
    let dir = common::scratch_dir();
    let paths = pieces(dir.path(), |_, s| s);
    let whole = read_swift(&paths[1]).unwrap();
    assert_eq!(whole.header.files, paths);
    assert_eq!(whole.header.num_part_per_file, vec![4, 0, 5]);
    assert_eq!(whole.header.num_files, 3);
    let p = &whole.particles;
    assert_eq!(p.id, (1..=9).collect::<Vec<u64>>());
    assert_eq!(p.x[4], 5.0 / 64.0, "the third piece's first particle");
    assert_eq!(p.m, vec![1., 2., 3., 4., 1., 2., 3., 4., 5.]);
    assert_eq!(read_swift(&paths[0]).unwrap(), whole);
}

#[test]
fn pieces_that_do_not_fit_together_are_refused() {
    let multi = |e: IoError, what: &str| match e {
        IoError::SwiftMultiFile { found, .. } => assert!(found.contains(what), "{found}"),
        other => panic!("{what}: {other:?}"),
    };
    let dir = common::scratch_dir();
    let paths = pieces(dir.path(), |_, s| s);
    std::fs::remove_file(&paths[2]).unwrap();
    multi(read_swift(&paths[0]).unwrap_err(), "missing");

    let dir = common::scratch_dir();
    let paths = pieces(dir.path(), |k, s| {
        if k == 2 {
            s.set_header("Time", AttrValue::F64(0.75))
        } else {
            s
        }
    });
    multi(read_swift(&paths[0]).unwrap_err(), "Time");

    let dir = common::scratch_dir();
    let paths = pieces(dir.path(), |k, s| {
        if k == 0 {
            s.set_gas("Densities", Data::F64(vec![1.0; 4], vec![4]))
        } else {
            s
        }
    });
    multi(read_swift(&paths[0]).unwrap_err(), "Densities");

    let dir = common::scratch_dir();
    let paths = pieces(dir.path(), |_, s| {
        s.set_header(
            "NumPart_Total",
            AttrValue::U32Array(vec![10, 0, 0, 0, 0, 0]),
        )
    });
    multi(read_swift(&paths[0]).unwrap_err(), "NumPart_Total[0] = 10");

    // A forged piece count ends at the first missing piece.
    let dir = common::scratch_dir();
    let path = Spec::ics(4, 1)
        .set_header("NumFilesPerSnapshot", AttrValue::I64(i64::MAX))
        .write(&dir.path().join("snap.0.hdf5"));
    multi(read_swift(&path).unwrap_err(), "snap.1.hdf5");

    // A name without the piece index.
    let e = refused(&Spec::ics(4, 1).set_header("NumFilesPerSnapshot", AttrValue::I32(2)));
    multi(e, "NAME.I.EXT");
}

// ---------------------------------------------------------------------------
// Every refusal by name.

#[test]
fn other_particle_types_are_refused() {
    for e in [
        refused(
            &Spec::ics(4, 1)
                .set_header("NumPart_Total", AttrValue::U32Array(vec![4, 8, 0, 0, 0, 0])),
        ),
        refused(&Spec::ics(4, 1).set_header(
            "NumPart_ThisFile",
            AttrValue::I64Array(vec![4, 0, 0, 0, 2, 0, 0]),
        )),
        refused(&Spec::ics(4, 1).group("PartType1", vec![])),
        refused(&Spec::ics(4, 1).group("PartType5", vec![])),
    ] {
        assert!(matches!(e, IoError::SwiftOtherTypes { .. }), "{e:?}");
        assert!(e.to_string().contains("gas only"), "{e}");
    }
}

#[test]
fn cosmological_files_are_refused() {
    for (spec, what) in [
        (
            Spec::ics(4, 1).group(
                "Cosmology",
                vec![("Cosmological run", AttrValue::I32Array(vec![1]))],
            ),
            "Cosmological run",
        ),
        (
            Spec::ics(4, 1).set_header("Redshift", AttrValue::F64Array(vec![2.0])),
            "Redshift = 2",
        ),
        (
            Spec::ics(4, 1).set_header("Scale-factor", AttrValue::F64(0.5)),
            "Scale-factor = 0.5",
        ),
    ] {
        match refused(&spec) {
            IoError::SwiftCosmological { found, .. } => assert!(found.contains(what), "{found}"),
            other => panic!("{other:?}"),
        }
    }
    // A non-cosmological SWIFT file says so and reads.
    let dir = common::scratch_dir();
    let path = Spec::ics(4, 1)
        .group(
            "Cosmology",
            vec![("Cosmological run", AttrValue::I32Array(vec![0]))],
        )
        .set_header("Redshift", AttrValue::F64Array(vec![0.0]))
        .set_header("Scale-factor", AttrValue::F64Array(vec![1.0]))
        .write(&dir.path().join("c.hdf5"));
    assert_eq!(read_swift(&path).unwrap().particles.len(), 4);
}

#[test]
fn entropy_ics_are_refused() {
    for flag in [
        AttrValue::I32(1),
        AttrValue::I32Array(vec![1, 0, 0, 0, 0, 0]),
    ] {
        let e = refused(&Spec::ics(4, 1).set_header("Flag_Entropy_ICs", flag));
        assert!(matches!(e, IoError::SwiftEntropy { .. }), "{e:?}");
        assert!(e.to_string().contains("entropy"), "{e}");
    }
}

#[test]
fn missing_header_attributes_and_datasets_are_named() {
    for attr in ["BoxSize", "NumPart_ThisFile", "NumPart_Total"] {
        match refused(&Spec::ics(4, 1).drop_header(attr)) {
            IoError::BadAttribute { step, attr: a, .. } => {
                assert_eq!((step.as_str(), a.as_str()), ("Header", attr))
            }
            other => panic!("{attr}: {other:?}"),
        }
    }
    for name in [
        "Coordinates",
        "Velocities",
        "ParticleIDs",
        "SmoothingLength",
        "InternalEnergy",
    ] {
        match refused(&Spec::ics(4, 1).drop_gas(name)) {
            IoError::MissingField { step, field, .. } => {
                assert_eq!(step, "PartType0");
                assert!(field.contains(name), "{field}");
            }
            other => panic!("{name}: {other:?}"),
        }
    }
    // Masses: from MassTable[0] when positive, refused when not.
    let e = refused(&Spec::ics(4, 1).drop_gas("Masses"));
    assert!(
        matches!(&e, IoError::SwiftLayout { found, .. } if found.contains("MassTable[0] = 0")),
        "{e:?}"
    );
    let dir = common::scratch_dir();
    let path = Spec::ics(4, 1)
        .drop_gas("Masses")
        .set_header(
            "MassTable",
            AttrValue::F64Array(vec![0.5, 0., 0., 0., 0., 0.]),
        )
        .write(&dir.path().join("mt.hdf5"));
    let f = read_swift(&path).unwrap();
    assert_eq!(f.particles.m, vec![0.5; 4]);
    assert!(f.header.masses_from_table);
    // No Header, no PartType0 with particles, not HDF5.
    let mut no_header = Spec::ics(4, 1);
    no_header.header.clear();
    let dir = common::scratch_dir();
    let bytes = {
        let mut b = FileBuilder::new();
        let g = b.create_group("PartType0");
        b.add_group(g.finish());
        b.finish().unwrap()
    };
    let path = dir.path().join("nh.hdf5");
    std::fs::write(&path, bytes).unwrap();
    assert!(
        matches!(read_swift(&path), Err(IoError::SwiftLayout { found, .. }) if found.contains("Header"))
    );
    let mut no_gas = Spec::ics(4, 1);
    no_gas.gas = None;
    assert!(
        matches!(refused(&no_gas), IoError::SwiftLayout { found, .. } if found.contains("PartType0"))
    );
    std::fs::write(&path, b"not an HDF5 file at all").unwrap();
    assert!(matches!(read_swift(&path), Err(IoError::NotHdf5 { .. })));
}

#[test]
fn lengths_shapes_types_and_counts_are_checked() {
    match refused(&Spec::ics(4, 1).set_gas("Masses", Data::F64(vec![1.0; 3], vec![3]))) {
        IoError::WrongLength {
            field,
            expected: 4,
            found: 3,
            ..
        } => assert_eq!(field, "Masses"),
        other => panic!("{other:?}"),
    }
    match refused(&Spec::ics(4, 1).set_gas("Coordinates", Data::F64(vec![0.5; 15], vec![5, 3]))) {
        IoError::WrongLength {
            field,
            expected: 4,
            found: 5,
            ..
        } => assert_eq!(field, "Coordinates"),
        other => panic!("{other:?}"),
    }
    for (spec, what) in [
        (
            Spec::ics(4, 1).set_gas("Coordinates", Data::F64(vec![0.5; 4], vec![4])),
            "shape [4]",
        ),
        (
            Spec::ics(4, 1).set_gas("Velocities", Data::F64(vec![0.5; 8], vec![4, 2])),
            "shape [4, 2]",
        ),
        (
            Spec::ics(4, 1).set_gas("Masses", Data::U32(vec![1; 4])),
            "Masses of type",
        ),
        (
            Spec::ics(4, 1).set_gas("ParticleIDs", Data::F64(vec![1.0; 4], vec![4])),
            "ParticleIDs of type",
        ),
        (
            Spec::ics(4, 1).set_gas("ParticleIDs", Data::I64(vec![1, 2, -3, 4])),
            "row 2 = -3",
        ),
        (
            Spec::ics(4, 1).set_header("Dimension", AttrValue::I32(2)),
            "Dimension = 2",
        ),
        (
            Spec::ics(4, 1)
                .set_header("NumPart_Total", AttrValue::U32Array(vec![5, 0, 0, 0, 0, 0])),
            "NumPart_Total[0] = 5",
        ),
    ] {
        match refused(&spec) {
            IoError::SwiftLayout { found, .. } => assert!(found.contains(what), "{what}: {found}"),
            other => panic!("{what}: {other:?}"),
        }
    }
    // Signed and narrower ids, f32 values and both name sets read.
    let dir = common::scratch_dir();
    let path = Spec::ics(2, 1)
        .set_gas("ParticleIDs", Data::I64(vec![7, 0]))
        .set_gas("Masses", Data::F32(vec![0.5, 0.25], vec![2]))
        .drop_gas("SmoothingLength")
        .set_gas("SmoothingLengths", Data::F64(vec![0.1, 0.2], vec![2]))
        .set_header("BoxSize", AttrValue::F32Array(vec![1.0, 2.0, 4.0]))
        .set_header("NumPart_Total_HighWord", AttrValue::U32Array(vec![0; 7]))
        .write(&dir.path().join("ok.hdf5"));
    let f = read_swift(&path).unwrap();
    assert_eq!(f.particles.id, vec![7, 0]);
    assert_eq!(f.particles.m, vec![0.5, 0.25]);
    assert_eq!(f.particles.h, vec![0.1, 0.2]);
    assert_eq!(f.particles.box_size, [1.0, 2.0, 4.0]);
    assert_eq!(
        (f.header.h_dataset, f.header.u_dataset),
        ("SmoothingLengths", "InternalEnergy")
    );
}

#[test]
fn non_finite_values_are_refused_by_place() {
    let mut xyz = vec![0.5; 12];
    xyz[7] = f64::NAN;
    for (spec, field, index) in [
        (
            Spec::ics(4, 1).set_gas("Coordinates", Data::F64(xyz, vec![4, 3])),
            "PartType0/Coordinates",
            7,
        ),
        (
            Spec::ics(4, 1).set_gas(
                "InternalEnergy",
                Data::F32(vec![1.0, 1.0, 1.0, f32::INFINITY], vec![4]),
            ),
            "PartType0/InternalEnergy",
            3,
        ),
        (
            Spec::ics(4, 1).set_header("BoxSize", AttrValue::F64(f64::NAN)),
            "Header/BoxSize",
            0,
        ),
        (
            Spec::ics(4, 1).set_header("Time", AttrValue::F64(f64::NEG_INFINITY)),
            "Header/Time",
            0,
        ),
        (
            Spec::ics(4, 1).drop_gas("Masses").set_header(
                "MassTable",
                AttrValue::F64Array(vec![f64::NAN, 0., 0., 0., 0., 0.]),
            ),
            "Header/MassTable",
            0,
        ),
    ] {
        match refused(&spec) {
            IoError::NonFinite {
                field: f, index: i, ..
            } => assert_eq!((f.as_str(), i), (field, index)),
            other => panic!("{field}: {other:?}"),
        }
    }
}

#[test]
fn units_are_read_where_present_and_checked() {
    let units = |v: [f64; 5]| {
        let mut s = Spec::ics(2, 1);
        s.units = Some(
            UNIT_NAMES
                .iter()
                .zip(v)
                .map(|(n, x)| ((*n).to_owned(), AttrValue::F64Array(vec![x])))
                .collect(),
        );
        s
    };
    let dir = common::scratch_dir();
    let path = units([2.0, 3.0, 5.0, 7.0, 11.0]).write(&dir.path().join("u.hdf5"));
    assert_eq!(
        read_swift(&path).unwrap().particles.units,
        Some(SwiftUnits {
            length: 2.0,
            mass: 3.0,
            time: 5.0,
            current: 7.0,
            temperature: 11.0
        })
    );
    assert!(matches!(
        refused(&units([1.0, -1.0, 1.0, 1.0, 1.0])),
        IoError::SwiftLayout { .. }
    ));
    assert!(matches!(
        refused(&units([1.0, 1.0, f64::NAN, 1.0, 1.0])),
        IoError::NonFinite { .. }
    ));
    let mut missing = units([1.0; 5]);
    missing.units.as_mut().unwrap().pop();
    match refused(&missing) {
        IoError::BadAttribute { step, attr, .. } => {
            assert_eq!((step.as_str(), attr.as_str()), ("Units", UNIT_NAMES[4]))
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn the_kernel_of_a_snapshot_is_named() {
    let dir = common::scratch_dir();
    let path = Spec::ics(2, 1)
        .group(
            "HydroScheme",
            vec![("Kernel function", AttrValue::String("Wendland C2".into()))],
        )
        .write(&dir.path().join("k.hdf5"));
    let h = read_swift(&path).unwrap().header;
    assert_eq!(h.kernel, Some(SwiftKernel::WendlandC2));
    assert_eq!(h.kernel_name.as_deref(), Some("Wendland C2"));
    for k in SwiftKernel::ALL {
        assert_eq!(SwiftKernel::from_swift_name(k.swift_name()), Some(k));
    }
}

// ---------------------------------------------------------------------------
// The smoothing-length convention.

/// The shapes of SWIFT's kernels in this code's convention (support `v < 2`,
/// unnormalised), written from their definitions (Dehnen & Aly 2012, table
/// 1), not from SWIFT's coefficient tables.
fn shape(k: SwiftKernel, v: f64) -> f64 {
    let q = v / 2.0;
    let p = |x: f64| x.max(0.0);
    match k {
        SwiftKernel::CubicSpline => p(1.0 - q).powi(3) - 4.0 * p(0.5 - q).powi(3),
        SwiftKernel::QuarticSpline => {
            let x = 2.5 * q;
            p(2.5 - x).powi(4) - 5.0 * p(1.5 - x).powi(4) + 10.0 * p(0.5 - x).powi(4)
        }
        SwiftKernel::QuinticSpline => {
            let x = 3.0 * q;
            p(3.0 - x).powi(5) - 6.0 * p(2.0 - x).powi(5) + 15.0 * p(1.0 - x).powi(5)
        }
        SwiftKernel::WendlandC2 => p(1.0 - q).powi(4) * (1.0 + 4.0 * q),
        SwiftKernel::WendlandC4 => p(1.0 - q).powi(6) * (1.0 + 6.0 * q + 35.0 / 3.0 * q * q),
        SwiftKernel::WendlandC6 => {
            p(1.0 - q).powi(8) * (1.0 + 8.0 * q + 25.0 * q * q + 32.0 * q * q * q)
        }
    }
}

/// SWIFT's `kernel_gamma` (support over `h`) is, for each of its kernels,
/// support over twice the standard deviation: recomputed from the shapes,
/// it matches the table to SWIFT's printed digits, and `swift_h_per_h` is
/// `2 / gamma`.
#[test]
fn swift_gammas_are_the_support_over_twice_the_standard_deviation() {
    for k in SwiftKernel::ALL {
        let per_h = swift_h_per_h(|v| shape(k, v));
        let gamma = 2.0 / per_h;
        assert!(
            (gamma - k.gamma()).abs() < 1e-6,
            "{k:?}: {gamma} against {}",
            k.gamma()
        );
        assert!((k.to_sph_exa_h() * per_h - 1.0).abs() < 1e-6, "{k:?}");
    }
    assert!((SwiftKernel::CubicSpline.to_sph_exa_h() - 0.912871).abs() < 1e-6);
    assert_eq!(GADGET_TO_SPH_EXA_H, 0.5);
    // Our M4 as sph-kernels writes it (1 - 1.5 v^2 + 0.75 v^3, 0.25 (2 - v)^3)
    // is SWIFT's cubic spline.
    let m4 = |v: f64| {
        if v < 1.0 {
            1.0 - 1.5 * v * v + 0.75 * v * v * v
        } else if v < 2.0 {
            0.25 * (2.0 - v).powi(3)
        } else {
            0.0
        }
    };
    assert!((2.0 / swift_h_per_h(m4) - SwiftKernel::CubicSpline.gamma()).abs() < 1e-6);
}

#[test]
fn centring_and_h_scaling_undo_each_other() {
    let mut p = sample(5);
    let before = p.clone();
    p.uncentre();
    assert_eq!(p.x[0], before.x[0] + 0.5);
    assert_eq!(p.z[0], before.z[0] + 1.75);
    p.centre();
    // Exact for the h scaling (powers of 2); to rounding for the shifts.
    p.scale_h(2.0);
    p.scale_h(0.5);
    assert_eq!(p.h, before.h);
    for (a, b) in [(&p.x, &before.x), (&p.y, &before.y), (&p.z, &before.z)] {
        for (u, v) in a.iter().zip(b.iter()) {
            assert!((u - v).abs() <= 1e-15, "{u} {v}");
        }
    }
}

// ---------------------------------------------------------------------------
// Corrupt bytes: never a panic.

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    /// Bit flips and truncations of a written snapshot give a read or an
    /// error naming the file; never a panic.
    #[test]
    fn corrupt_files_give_errors_not_panics(flips in prop::collection::vec((any::<prop::sample::Index>(), 0u8..8), 1..6), cut in any::<prop::sample::Index>(), truncate in any::<bool>()) {
        let dir = common::scratch_dir();
        let path = dir.path().join("c.hdf5");
        write_swift(&path, &sample(6)).unwrap();
        let mut bytes = std::fs::read(&path).unwrap();
        for (at, bit) in flips {
            let i = at.index(bytes.len());
            bytes[i] ^= 1 << bit;
        }
        if truncate {
            bytes.truncate(cut.index(bytes.len()));
        }
        std::fs::write(&path, &bytes).unwrap();
        match read_swift(&path) {
            Ok(f) => {
                let p = &f.particles;
                let n = p.len();
                for v in [&p.y, &p.z, &p.vx, &p.vy, &p.vz, &p.m, &p.h, &p.u] {
                    prop_assert_eq!(v.len(), n);
                }
                prop_assert_eq!(p.id.len(), n);
            }
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(msg.contains("c.hdf5"), "{}", msg);
            }
        }
    }
}
