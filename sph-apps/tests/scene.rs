//! A scene of the user's own: `sphexa run --init FILE` with no case. The
//! physics comes from the options or the file's attributes (SPH-EXA's
//! names), and a scene runs exactly as the case with the same particles,
//! physics and scheme runs; what matters and is left unsaid is an error
//! naming the option to give.

mod common;

use common::{assert_mentions, initial_fields, ok, refused, s, scratch, write_sphexa_file};
use hdf5_pure::AttrValue;
use sph_apps::cases::{self, Layout, SchemeOverrides, Share};
use std::path::{Path, PathBuf};

/// The initial particles of `case` at `side` (lattice) in an SPH-EXA
/// layout file `dir/NAME` (group Step#0, no ids, no checksums) with the
/// step attributes `attrs`.
fn write_case(
    case: &str,
    side: usize,
    dir: &Path,
    name: &str,
    attrs: &[(&str, AttrValue)],
) -> PathBuf {
    let scene = cases::lookup(case)
        .unwrap()
        .setup_share(
            side,
            sph_core::HydroConfig::default(),
            &SchemeOverrides::default(),
            Share::WHOLE,
            &Layout::Lattice,
        )
        .unwrap();
    let p = &scene.particles;
    let file = dir.join(name);
    let fields = initial_fields(p);
    write_sphexa_file(&file, attrs, &fields);
    file
}

fn conserved(dir: &Path) -> String {
    std::fs::read_to_string(dir.join("conserved.csv")).expect("conserved.csv")
}

/// The Sedov blast's particles in a periodic box, written with SPH-EXA's
/// attributes (`box`, `boundaryType` 1, `gamma`, `gravConstant` 0, `minDt`)
/// and again with none, the physics then given as options: both scenes run
/// the bits of the `sedov` case from that file with the scene's scheme and
/// first step, and the scene's config.toml repeats the run.
#[test]
fn a_blast_runs_as_the_case_with_the_same_physics() {
    let dir = scratch("blast");
    let cube = AttrValue::F64Array(vec![-0.5, 0.5, -0.5, 0.5, -0.5, 0.5]);
    let attrs = [
        ("time", AttrValue::F64(0.0)),
        ("minDt", AttrValue::F64(1e-6)),
        ("box", cube),
        ("boundaryType", AttrValue::I8Array(vec![1, 1, 1])),
        ("gamma", AttrValue::F64(5.0 / 3.0)),
        ("gravConstant", AttrValue::F64(0.0)),
    ];
    let with_attrs = write_case("sedov", 10, &dir, "blast.h5", &attrs);
    let bare = write_case("sedov", 10, &dir, "bare.h5", &[]);
    // Global steps: a scene stopped by --steps alone steps globally.
    let steps = ["--steps", "6", "-q", "--time-steps", "global"];
    let run = |out: &Path, args: &[&str]| {
        let mut all = args.to_vec();
        all.extend_from_slice(&steps);
        all.extend_from_slice(&["--out", s(out)]);
        ok(&all);
    };
    let case = dir.join("case");
    run(
        &case,
        &[
            "sedov",
            "--init",
            s(&with_attrs),
            "--scheme",
            "gas",
            "--first-step",
            "criteria",
        ],
    );
    let from_attrs = dir.join("from-attrs");
    run(&from_attrs, &["--init", s(&with_attrs)]);
    let from_options = dir.join("from-options");
    run(
        &from_options,
        &[
            "--init",
            s(&bare),
            "--boundary",
            "periodic",
            "--box",
            "-0.5:0.5",
            "--eos",
            "ideal:1.6666666666666667",
        ],
    );
    let reference = conserved(&case);
    assert_eq!(reference.lines().count(), 7);
    assert_eq!(
        conserved(&from_attrs),
        reference,
        "scene from the attributes"
    );
    assert_eq!(
        conserved(&from_options),
        reference,
        "scene from the options"
    );
    // The blast moved: this is a run, not a copy of the initial state.
    let last: Vec<f64> = reference
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert!(last[3] > 0.0, "E_kin {}", last[3]);

    // config.toml holds no case and the resolved physics; it repeats the run.
    let config = std::fs::read_to_string(from_options.join("config.toml")).unwrap();
    assert!(!config.contains("case"), "{config}");
    for key in [
        "boundary = \"periodic,periodic,periodic\"",
        "box = ",
        "gravity = \"off\"",
        "eos = ",
    ] {
        assert!(config.contains(key), "{key} not in {config}");
    }
    let again = dir.join("again");
    ok(&[
        "--config",
        s(&from_options.join("config.toml")),
        "--out",
        s(&again),
    ]);
    assert_eq!(conserved(&again), reference, "the scene's config.toml");

    // A scene's checkpoint restarts it (its physics from the checkpoint's
    // configuration, not from the file) to the same bits.
    let halves = dir.join("halves");
    let physics = [
        "--boundary",
        "periodic",
        "--box",
        "-0.5:0.5",
        "--eos",
        "ideal:1.6666666666666667",
    ];
    let mut args = vec!["--init", s(&bare), "--checkpoint-every", "3"];
    args.extend_from_slice(&physics);
    run(&halves, &args);
    let ckpt = halves.join("checkpoints/checkpoint_00000003.h5");
    ok(&["--restart", s(&ckpt), "--steps", "6", "-q"]);
    assert_eq!(conserved(&halves), reference, "restarted scene");
}

/// The Evrard sphere's particles in an open box, with `gamma` and no
/// `gravConstant`: the scene needs `--gravity`, and with it runs the bits
/// of the `evrard` case from that file with the same scheme, softening,
/// Courant factor and first step (its gravity on: E_grav < 0; off: 0).
#[test]
fn an_isolated_sphere_runs_with_the_gravity_it_is_given() {
    let dir = scratch("sphere");
    let attrs = [
        ("minDt", AttrValue::F64(1e-4)),
        ("boundaryType", AttrValue::I8Array(vec![0, 0, 0])),
        ("gamma", AttrValue::F64(5.0 / 3.0)),
    ];
    let file = write_case("evrard", 10, &dir, "sphere.h5", &attrs);
    let same = [
        "--courant",
        "0.3",
        "--steps",
        "5",
        "-q",
        "--time-steps",
        "global",
    ];
    let run = |out: &Path, args: &[&str]| {
        let mut all = args.to_vec();
        all.extend_from_slice(&same);
        all.extend_from_slice(&["--out", s(out)]);
        ok(&all);
    };
    let e = refused(&[
        "--init",
        s(&file),
        "--steps",
        "5",
        "-q",
        "--out",
        s(&dir.join("x")),
    ]);
    assert_mentions(&e, &["sphere.h5", "--gravity on", "--gravity off"]);

    let case = dir.join("case");
    run(
        &case,
        &[
            "evrard",
            "--init",
            s(&file),
            "--scheme",
            "gas",
            "--first-step",
            "criteria",
        ],
    );
    let on = dir.join("on");
    run(
        &on,
        &["--init", s(&file), "--gravity", "on", "--softening", "0.25"],
    );
    let reference = conserved(&case);
    assert_eq!(conserved(&on), reference, "scene with gravity");
    let e_grav = |text: &str| -> f64 {
        text.lines()
            .nth(1)
            .unwrap()
            .split(',')
            .nth(5)
            .unwrap()
            .parse()
            .unwrap()
    };
    assert!(e_grav(&reference) < 0.0, "gravity on: {reference}");
    let off = dir.join("off");
    run(&off, &["--init", s(&file), "--gravity", "off"]);
    assert_eq!(e_grav(&conserved(&off)), 0.0);
}

/// What matters and is not said is refused, naming the option; a case
/// refuses the scene's options, a scene `--side`, and a file's attribute
/// of the wrong shape is named.
#[test]
fn unsaid_physics_is_named() {
    let dir = scratch("unsaid");
    let out = dir.join("out");
    let periodic_no_box = write_case(
        "sedov",
        4,
        &dir,
        "no_box.h5",
        &[
            ("boundaryType", AttrValue::I8Array(vec![1, 1, 1])),
            ("gamma", AttrValue::F64(1.4)),
        ],
    );
    let bare = write_case("sedov", 4, &dir, "bare.h5", &[]);
    let fixed = write_case(
        "sedov",
        4,
        &dir,
        "fixed.h5",
        &[("boundaryType", AttrValue::I8Array(vec![2, 2, 2]))],
    );
    let run = |extra: &[&str]| {
        let mut all = extra.to_vec();
        all.extend_from_slice(&["-q", "--out", s(&out)]);
        refused(&all)
    };
    let e = run(&["--init", s(&periodic_no_box), "--steps", "1"]);
    assert_mentions(&e, &["no_box.h5", "--box LO:HI"]);
    let e = run(&["--init", s(&bare), "--steps", "1"]);
    assert_mentions(&e, &["bare.h5", "--boundary periodic"]);
    let e = run(&[
        "--init",
        s(&bare),
        "--steps",
        "1",
        "--boundary",
        "open",
        "--gravity",
        "off",
    ]);
    assert_mentions(&e, &["bare.h5", "--eos"]);
    let e = run(&["--init", s(&periodic_no_box), "--box", "-0.5:0.5"]);
    assert_mentions(&e, &["--end-time T", "--steps N"]);
    let e = run(&[
        "--init",
        s(&periodic_no_box),
        "--box",
        "-0.5:0.5",
        "--steps",
        "1",
        "--gravity",
        "on",
    ]);
    assert_mentions(&e, &["Ewald", "--gravity off"]);
    let e = run(&["--init", s(&fixed), "--steps", "1"]);
    assert_mentions(&e, &["fixed.h5", "boundaryType", "--boundary"]);
    let e = run(&["--init", s(&bare), "-n", "8", "--steps", "1"]);
    assert_mentions(&e, &["--side 8"]);
    let e = run(&["sedov", "--box", "-1:1", "--steps", "1"]);
    assert_mentions(&e, &["--box", "case 'sedov'"]);
    let e = run(&[
        "--init",
        s(&bare),
        "--boundary",
        "periodic,open",
        "--steps",
        "1",
    ]);
    assert_mentions(&e, &["periodic,open", "periodic,periodic,open"]);
    let e = run(&["--init", s(&bare), "--box", "1:0", "--steps", "1"]);
    assert_mentions(&e, &["1:0", "LO < HI"]);
    let e = run(&["--init", s(&bare), "--gravity", "-1", "--steps", "1"]);
    assert_mentions(&e, &["'-1'", "on, off"]);
    let e = run(&["--steps", "1"]);
    assert_mentions(&e, &["no case given", "--init FILE"]);
    // The particles of [-0.5, 0.5) in a periodic box said to be [0, 1).
    let e = run(&[
        "--init",
        s(&periodic_no_box),
        "--box",
        "0:1",
        "--steps",
        "1",
    ]);
    assert_mentions(&e, &["x = -", "outside the periodic box", "--box"]);
}
