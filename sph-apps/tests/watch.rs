//! Every run watches itself: runs made to fail exit non-zero with the
//! quantity or the particle and the step in the message under `--strict`,
//! and warn and record the same in summary.json without it.

mod common;

use common::{s, scratch, sphexa, write_sphexa_file};
use hdf5_pure::AttrValue;
use std::path::{Path, PathBuf};
use std::process::Output;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// Column `name` of `conserved.csv` in `dir`, every row.
fn column(dir: &Path, name: &str) -> Vec<f64> {
    let csv = std::fs::read_to_string(dir.join("conserved.csv")).expect("conserved.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let k = header.iter().position(|h| *h == name).expect(name);
    lines
        .map(|l| {
            l.split(',')
                .nth(k)
                .expect("a value")
                .parse()
                .expect("a number")
        })
        .collect()
}

fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("JSON")
}

/// The Sedov initial state at 8^3 as an SPH-EXA-layout file (no ids: a
/// particle's id is its row), with `edit` applied to (m, u) of row `row`.
fn sedov_file(dir: &Path, row: usize, m: f64, u: f64) -> PathBuf {
    let scene = sph_apps::cases::lookup("sedov")
        .unwrap()
        .setup(8, sph_core::HydroConfig::default())
        .unwrap();
    let p = &scene.particles;
    let (mut mass, mut energy) = (p.m.clone(), p.u.clone());
    mass[row] = m;
    energy[row] = u;
    let file = dir.join(format!("sedov_{row}_{m}_{u}.h5"));
    let attrs = [
        ("time", AttrValue::F64(0.0)),
        (
            "box",
            AttrValue::F64Array(vec![-0.5, 0.5, -0.5, 0.5, -0.5, 0.5]),
        ),
    ];
    let fields: [(&str, &[f64]); 6] = [
        ("x", &p.x),
        ("y", &p.y),
        ("z", &p.z),
        ("h", &p.h),
        ("m", &mass),
        ("u", &energy),
    ];
    write_sphexa_file(&file, &attrs, &fields);
    file
}

/// A zero-mass particle under `m / rho` volumes (the paper's scheme):
/// warned about and recorded (step 0, its id and position) without
/// --strict; an error naming it with --strict. Sedov's own scheme
/// (generalised volume elements, `X = m / rho0`) refuses it by id.
#[test]
fn a_zero_mass_particle_is_named() {
    let dir = scratch("zero-mass");
    let file = sedov_file(&dir, 137, 0.0, 1e-8);
    let refused = dir.join("refused");
    let o = sphexa(&[
        "run",
        "sedov",
        "--init",
        s(&file),
        "--steps",
        "2",
        "-q",
        "--out",
        s(&refused),
    ]);
    let e = stderr(&o);
    assert!(!o.status.success(), "volume elements took a zero mass: {e}");
    assert!(e.contains("m > 0") && e.contains("id 137"), "{e}");
    let lax = dir.join("lax");
    let args = |out: &Path| {
        vec![
            "run".to_string(),
            "sedov".into(),
            "--scheme".into(),
            "paper".into(),
            "--init".into(),
            s(&file).into(),
            "--steps".into(),
            "2".into(),
            "-q".into(),
            "--threads".into(),
            "1".into(),
            "--out".into(),
            s(out).into(),
        ]
    };
    let a = args(&lax);
    let o = sphexa(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("warning") && e.contains("particle mass") && e.contains("id 137"),
        "{e}"
    );
    let v = &summary(&lax)["watch"]["violations"];
    assert_eq!(v[0]["quantity"], "particle mass", "{v}");
    assert_eq!(v[0]["step"], 0);
    assert_eq!(v[0]["particle"]["id"], 137);
    let strict = dir.join("strict");
    let mut a = args(&strict);
    a.push("--strict".into());
    let o = sphexa(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let e = stderr(&o);
    assert!(!o.status.success(), "--strict accepted a zero mass: {e}");
    assert!(
        e.contains("step 0") && e.contains("particle mass") && e.contains("id 137"),
        "{e}"
    );
    assert!(!e.contains("panicked"), "{e}");
}

/// A negative internal energy in the input is refused with the particle
/// and what is allowed, strict or not.
#[test]
fn a_negative_internal_energy_is_refused() {
    let dir = scratch("negative-u");
    let file = sedov_file(&dir, 42, 1.0 / 512.0, -1.0);
    let o = sphexa(&[
        "run",
        "sedov",
        "--init",
        s(&file),
        "--steps",
        "1",
        "-q",
        "--out",
        s(&dir.join("out")),
    ]);
    let e = stderr(&o);
    assert!(!o.status.success(), "{e}");
    assert!(e.contains("id 42") && e.contains("u >= 0"), "{e}");
}

/// The rotating square patch with the paper's scheme at Courant factor 1
/// loses energy conservation (the case's own scheme holds it there):
/// with --strict it stops at the first step past the energy bound, naming
/// the quantity, the step and a particle; without it the run finishes, warns
/// once and records that same step.
#[test]
fn square_patch_at_courant_1_is_caught() {
    let dir = scratch("courant");
    let run = |out: &Path, strict: bool| {
        let mut a = vec![
            "run",
            "square-patch",
            "--scheme",
            "paper",
            "-n",
            "12",
            "--courant",
            "1",
            "--steps",
            "120",
            "-q",
            "--threads",
            "1",
            "--out",
            s(out),
        ];
        if strict {
            a.push("--strict");
        }
        sphexa(&a)
    };
    let lax = dir.join("lax");
    let o = run(&lax, false);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert_eq!(e.matches("warning").count(), 1, "{e}");
    let v = summary(&lax)["watch"]["violations"].clone();
    let first = v
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["quantity"] == "energy")
        .unwrap_or_else(|| panic!("no energy violation recorded: {v}"))
        .clone();
    let step = first["step"].as_u64().unwrap();
    assert!(first["value"].as_f64().unwrap() > 1e-2, "{first}");
    // The recorded drift is the one conserved.csv shows at that step.
    let csv = std::fs::read_to_string(lax.join("conserved.csv")).unwrap();
    let e_tot = |k: u64| -> f64 {
        let line = csv.lines().nth(k as usize).unwrap();
        line.split(',').nth(6).unwrap().parse().unwrap()
    };
    let drift = |k: u64| (e_tot(k) - e_tot(1)).abs() / e_tot(1).abs();
    assert!(drift(step) > 1e-2 && drift(step - 1) <= 1e-2, "step {step}");

    let o = run(&dir.join("strict"), true);
    let e = stderr(&o);
    assert!(!o.status.success(), "{e}");
    assert!(
        e.contains(&format!("step {step}:")) && e.contains("energy drift"),
        "{e}"
    );
    assert!(e.contains("particle id") && e.contains("--strict"), "{e}");
}

/// An invalid option combination is explained in the options' terms.
#[test]
fn alpha_below_the_switch_floor_names_the_options() {
    let dir = scratch("alpha");
    let o = sphexa(&[
        "run",
        "noh",
        "--alpha",
        "0",
        "--steps",
        "1",
        "-q",
        "--out",
        s(&dir),
    ]);
    let e = stderr(&o);
    assert!(!o.status.success());
    assert!(
        e.contains("--alpha 0") && e.contains("0.05") && e.contains("--av-switches off"),
        "{e}"
    );
    assert!(!e.contains("AvSwitchParams"), "{e}");
    // With the switches off, alpha 0 is allowed.
    let o = sphexa(&[
        "run",
        "noh",
        "-n",
        "10",
        "--alpha",
        "0",
        "--av-switches",
        "off",
        "--steps",
        "1",
        "-q",
        "--out",
        s(&dir),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A driven run gains energy through the stirring: the watch counts the
/// work (`W_ext`), so `--strict` runs turbulence through; the plain
/// drift, `(E - E_0) / |E_0|`, is far past the bound in the same run.
#[test]
fn a_driven_run_is_checked_against_its_work() {
    let dir = scratch("driven");
    let out = dir.join("turbulence");
    let o = sphexa(&[
        "run",
        "turbulence",
        "-n",
        "12",
        "--end-time",
        "1.5",
        "--strict",
        "-q",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (e_tot, w_ext) = (column(&out, "E_tot"), column(&out, "W_ext"));
    let (e0, e, w) = (e_tot[0], e_tot[e_tot.len() - 1], w_ext[w_ext.len() - 1]);
    assert!(w > 0.0, "no work done: {w}");
    assert!(
        (e - e0).abs() / e0.abs() > 1.0,
        "E {e0} -> {e}: the driving did little"
    );
    let closure = (e - e0 - w).abs() / (e0.abs() + w);
    assert!(
        closure < 1e-2,
        "E - E0 - W = {closure} of the energy through the run"
    );
    let v = summary(&out);
    assert!(v["injected_work"].as_f64().unwrap() > 0.0, "{v}");
    assert!(v["energy_rel_drift"].as_f64().unwrap().abs() < 1e-2, "{v}");
}

/// An isothermal gas has `u = c^2 ln rho`, an internal energy with an
/// arbitrary zero (0 at rho = 1): the glass at rest, undriven, has a tiny
/// `E_0` (its density noise), against which its own relaxation drifts by
/// over 1%. The watch measures the drift against the gas's thermal energy
/// `sum m c^2` instead, so `--strict` runs it through, and summary.json
/// reports the drift on that scale.
#[test]
fn an_isothermal_gas_at_rest_is_checked_against_its_thermal_energy() {
    let dir = scratch("isothermal");
    let out = dir.join("turbulence");
    let o = sphexa(&[
        "run",
        "turbulence",
        "-n",
        "12",
        "--stir",
        "off",
        "--end-time",
        "1",
        "--strict",
        "-q",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = column(&out, "E_tot");
    let (e0, e1) = (e[0], e[e.len() - 1]);
    // Measured 1.5e-2: |E_0| is no scale here.
    assert!(
        (e1 - e0).abs() / e0.abs() > 1e-2,
        "E {e0} -> {e1}: the plain drift is within the bound"
    );
    // M c^2 = 1: measured 1.1e-5.
    let drift = summary(&out)["energy_rel_drift"].as_f64().unwrap();
    assert!(drift.abs() < 1e-3, "energy_rel_drift {drift}");
}
