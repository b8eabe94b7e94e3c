//! Hostile files given to `sphexa run`: random, truncated and bit-flipped
//! checkpoints (`--restart FILE`: `checkpoint::load`, then
//! `checkpoint::particles`) and configuration files (`--config FILE`:
//! `config::read`, then `config::table`) are refused with an error that
//! names the file, never a panic, or read back as they were written (damage
//! to bytes the reader does not use); a checkpoint whose particle count
//! needs more bytes than the file holds is refused by name before anything
//! is allocated for it. The library functions are called directly, so the
//! properties run hundreds of cases in seconds; two checks run the binary
//! to see that the message reaches the user.

mod common;

use common::{assert_mentions, refused, s, scratch};
use proptest::prelude::*;
use sph_apps::checkpoint;
use sph_apps::config::{self, OptionKey};
use sph_apps::output::snapshot as snapfile;
use sph_comm::SerialComm;
use sph_core::{HydroConfig, RunState};
use sph_io::{Attr, FieldData, Snapshot};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// A folder for the damaged copies (each test writes its own file names,
/// overwritten case by case).
fn files() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| scratch("files"))
}

// ------------------------------------------------------------ checkpoints

struct Fixture {
    /// The checkpoint file's bytes.
    bytes: Vec<u8>,
    /// What it holds.
    state: RunState,
    rows: Snapshot,
    /// Byte ranges of the field values in the file.
    payload: Vec<std::ops::Range<usize>>,
    fields: sph_core::FieldSet,
}

/// Sedov's 6^3 particles with every checkpoint field set to values that
/// occur once in the file (so damage to any is a change), written as a
/// checkpoint by the writer runs use.
fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let scene = sph_apps::cases::lookup("sedov")
            .unwrap()
            .setup(6, HydroConfig::default())
            .unwrap();
        let mut p = scene.particles;
        let n = p.len();
        for (k, v) in [&mut p.dx, &mut p.dy, &mut p.dz, &mut p.du_prev]
            .into_iter()
            .enumerate()
        {
            for (i, x) in v.iter_mut().enumerate() {
                *x = 1e-3 * (i as f64 + 0.25 * k as f64 + 1.0);
            }
        }
        let state = RunState {
            step: 7,
            t: 0.0125,
            dt_prev: 1.5e-4,
            h_next_max: Some(0.21),
            external_work: 0.0,
            block: None,
        };
        let attrs = [
            (
                "config".to_string(),
                Attr::Str("case = \"sedov\"\nside = 6\n".into()),
            ),
            ("case".to_string(), Attr::Str("sedov".into())),
        ];
        let snap = checkpoint::snapshot(&p, 0..n, state, &scene.bbox, &attrs);
        let path = files().join("fixture.h5");
        snapfile::write(&SerialComm::new(), &path, &snap).expect("checkpoint written");
        let bytes = std::fs::read(&path).unwrap();
        let mut payload = Vec::new();
        for f in &snap.fields {
            let needle: Vec<u8> = match &f.data {
                FieldData::F64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
                FieldData::U64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            };
            let at = bytes
                .windows(needle.len())
                .position(|w| w == needle)
                .unwrap_or_else(|| panic!("field {} in the file", f.name));
            payload.push(at..at + needle.len());
        }
        let fields = scene.config.fields();
        let rows = checkpoint::load(&SerialComm::new(), s(&path))
            .expect("the fixture loads")
            .rows;
        Fixture {
            bytes,
            state,
            rows,
            payload,
            fields,
        }
    })
}

/// What `--restart FILE` does with the file: load it and build the
/// particles. The error's text, or the state and rows.
fn restart(path: &Path) -> Result<(RunState, Snapshot), String> {
    let fx = fixture();
    let l = checkpoint::load(&SerialComm::new(), s(path)).map_err(|e| e.to_string())?;
    checkpoint::particles(&l.rows, fx.fields, &l.path).map_err(|e| e.to_string())?;
    Ok((l.state, l.rows))
}

/// `bytes` as file `name`; what a restart from it gives.
fn restart_from(name: &str, bytes: &[u8]) -> Result<(RunState, Snapshot), String> {
    let path = files().join(name);
    std::fs::write(&path, bytes).unwrap();
    restart(&path)
}

fn unchanged(got: &(RunState, Snapshot)) -> bool {
    let fx = fixture();
    got.0 == fx.state && got.1.bits_eq(&fx.rows)
}

#[test]
fn the_fixture_restarts() {
    let fx = fixture();
    let got = restart_from("intact.h5", &fx.bytes).expect("restarts");
    assert!(unchanged(&got));
    assert_eq!(fx.payload.len(), fx.rows.fields.len());
    assert!(fx.payload.len() >= 14);
}

/// A checkpoint cut after its first value, the step group's metadata
/// (which the encoder puts before the values) intact: the particle count
/// asks for more bytes than the file holds, and the reader says so before
/// it allocates anything for the values.
#[test]
fn a_count_larger_than_the_file_is_refused_by_name() {
    let fx = fixture();
    let first = fx.payload.iter().map(|r| r.start).min().unwrap();
    let cut = first + 8;
    let e = restart_from("cut-values.h5", &fx.bytes[..cut]).unwrap_err();
    assert!(
        e.contains("cut-values.h5")
            && e.contains("claims 216 particles")
            && e.contains(&format!("holds {cut} bytes")),
        "{e}"
    );
}

/// Values no run writes, in a file whose checksums hold: refused by name.
#[test]
fn impossible_run_states_are_refused_by_name() {
    let fx = fixture();
    let write = |name: &str, edit: &dyn Fn(&mut Snapshot)| {
        let mut snap = fx.rows.clone();
        edit(&mut snap);
        let path = files().join(name);
        snapfile::write(&SerialComm::new(), &path, &snap).expect("written");
        restart(&path).unwrap_err()
    };
    let e = write("nan-time.h5", &|s| s.time = f64::NAN);
    assert!(
        e.contains("nan-time.h5") && e.contains("time is NaN"),
        "{e}"
    );
    let e = write("zero-dt.h5", &|s| s.dt = 0.0);
    assert!(e.contains("zero-dt.h5") && e.contains("minDt"), "{e}");
    let e = write("bad-h.h5", &|s| {
        s.set_attr("h_next_max", Attr::F64(-1.0));
    });
    assert!(e.contains("bad-h.h5") && e.contains("h_next_max"), "{e}");
    let e = write("flat-box.h5", &|s| s.bbox.hi[1] = s.bbox.lo[1]);
    assert!(e.contains("flat-box.h5") && e.contains("box"), "{e}");
    let e = write("snapshot.h5", &|s| {
        s.set_attr("sphexa_kind", Attr::Str("snapshot".into()));
    });
    assert!(
        e.contains("snapshot.h5") && e.contains("not a checkpoint"),
        "{e}"
    );
    let e = write("no-u.h5", &|s| s.fields.retain(|f| f.name != "u"));
    assert!(e.contains("no-u.h5") && e.contains("'u'"), "{e}");
}

/// An HDF5 file's first bytes: random bytes after them get past the
/// signature check into the decoder.
const HDF5_SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// One byte anywhere changed: refused by name, or the same restart
    /// (and never unnoticed in the particles' values).
    #[test]
    fn a_changed_byte_is_refused_by_name_or_harmless(pos in any::<prop::sample::Index>(), mask in 1u8..=255) {
        let fx = fixture();
        let mut bytes = fx.bytes.clone();
        let i = pos.index(bytes.len());
        bytes[i] ^= mask;
        match restart_from("flipped.h5", &bytes) {
            Ok(got) => {
                prop_assert!(unchanged(&got), "byte {} ^ {:#x}: a different restart", i, mask);
                prop_assert!(!fx.payload.iter().any(|r| r.contains(&i)), "value byte {} ^ {:#x} unnoticed", i, mask);
            }
            Err(e) => prop_assert!(e.contains("flipped.h5"), "{}", e),
        }
    }

    /// Up to 16 random bytes written anywhere: refused by name, or the
    /// same restart.
    #[test]
    fn a_scribbled_run_is_refused_by_name_or_harmless(pos in any::<prop::sample::Index>(), junk in prop::collection::vec(any::<u8>(), 1..16)) {
        let fx = fixture();
        let mut bytes = fx.bytes.clone();
        let i = pos.index(bytes.len());
        let end = (i + junk.len()).min(bytes.len());
        bytes[i..end].copy_from_slice(&junk[..end - i]);
        match restart_from("scribbled.h5", &bytes) {
            Ok(got) => prop_assert!(unchanged(&got), "junk at {}: a different restart", i),
            Err(e) => prop_assert!(e.contains("scribbled.h5"), "{}", e),
        }
    }

    /// Any truncation (a torn copy) is refused by name.
    #[test]
    fn a_truncated_checkpoint_is_refused_by_name(keep in any::<prop::sample::Index>()) {
        let fx = fixture();
        let n = keep.index(fx.bytes.len());
        let e = restart_from("truncated.h5", &fx.bytes[..n]).unwrap_err();
        prop_assert!(e.contains("truncated.h5"), "{}", e);
    }

    /// Random bytes, with and without the HDF5 signature: refused by name.
    #[test]
    fn random_bytes_are_refused_by_name(signed in any::<bool>(), junk in prop::collection::vec(any::<u8>(), 0..4096)) {
        let mut bytes = if signed { HDF5_SIGNATURE.to_vec() } else { Vec::new() };
        bytes.extend(junk);
        let e = restart_from("random.h5", &bytes).unwrap_err();
        prop_assert!(e.contains("random.h5"), "{}", e);
    }
}

// ---------------------------------------------------- configuration files

/// Options of `sphexa run` of every kind: the case (positional), values,
/// flags, lists.
fn keys() -> Vec<OptionKey> {
    vec![
        OptionKey::positional("case"),
        OptionKey::value("side"),
        OptionKey::value("steps"),
        OptionKey::value("alpha"),
        OptionKey::value("snapshot-at"),
        OptionKey::value("out"),
        OptionKey::flag("quiet"),
        OptionKey::value("config"),
    ]
}

/// A command line's check of one key's tokens, as strict as the driver's:
/// numbers in range, the known cases.
fn check(tokens: &[String]) -> Result<(), String> {
    let Some(t) = tokens.first() else {
        return Ok(());
    };
    let (key, value) = match t.split_once('=') {
        Some(kv) if t.starts_with("--") => kv,
        // A flag.
        None if t.starts_with("--") => return Ok(()),
        _ => ("case", t.as_str()),
    };
    let fine = match key {
        "--side" => value
            .parse::<usize>()
            .is_ok_and(|n| (4..=1000).contains(&n)),
        "--steps" => value.parse::<u64>().is_ok_and(|n| n >= 1),
        "--alpha" => value.parse::<f64>().is_ok_and(|a| a >= 0.0),
        "--snapshot-at" => value.split(',').all(|x| x.parse::<f64>().is_ok()),
        "--out" => !value.is_empty(),
        "case" => ["sedov", "noh"].contains(&value),
        _ => true,
    };
    if fine {
        Ok(())
    } else {
        Err(format!("invalid value '{value}' for '{key}'"))
    }
}

/// A run's configuration as `sphexa run` writes it.
const CONFIG: &str = "case = \"sedov\"\nside = 8\nsteps = 5\nalpha = 0.5\nsnapshot-at = [0.0, 0.25]\nout = \"out/sedov\"\nquiet = true\n";

/// What `--config FILE` does with `bytes` as file `name`.
fn configure(name: &str, bytes: &[u8]) -> Result<toml::Table, String> {
    let path = files().join(name);
    std::fs::write(&path, bytes).unwrap();
    let text = config::read(&path).map_err(|e| e.to_string())?;
    config::table(&text, s(&path), &keys(), check).map_err(|e| e.to_string())
}

#[test]
fn the_configuration_fixture_is_read() {
    let t = configure("intact.toml", CONFIG.as_bytes()).expect("a valid configuration");
    assert_eq!(t.len(), 7);
    let e = configure("config-key.toml", b"config = \"other.toml\"\n").unwrap_err();
    assert!(
        e.contains("config-key.toml") && e.contains("unknown key 'config'"),
        "{e}"
    );
}

/// A file too large to be a configuration is refused by name after
/// reading no more than the limit.
#[test]
fn a_huge_configuration_is_refused_by_name() {
    let mut big = CONFIG.as_bytes().to_vec();
    big.resize(config::MAX_BYTES as usize + 1, b'\n');
    let e = configure("huge.toml", &big).unwrap_err();
    assert!(e.contains("huge.toml") && e.contains("larger than"), "{e}");
    // At the limit it is read (and is the fixture).
    big.pop();
    assert_eq!(configure("at-limit.toml", &big).unwrap().len(), 7);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// One byte of a valid configuration changed: refused by name, or read.
    #[test]
    fn a_changed_configuration_byte_is_refused_by_name_or_read(pos in any::<prop::sample::Index>(), mask in 1u8..=255) {
        let mut bytes = CONFIG.as_bytes().to_vec();
        let i = pos.index(bytes.len());
        bytes[i] ^= mask;
        if let Err(e) = configure("flipped.toml", &bytes) {
            prop_assert!(e.contains("flipped.toml"), "{}", e);
        }
    }

    /// A truncated configuration: refused by name, or a table of the keys
    /// before the cut.
    #[test]
    fn a_truncated_configuration_is_refused_by_name_or_read(keep in any::<prop::sample::Index>()) {
        let n = keep.index(CONFIG.len() + 1);
        match configure("truncated.toml", &CONFIG.as_bytes()[..n]) {
            Ok(t) => prop_assert!(t.len() <= CONFIG[..n].lines().count()),
            Err(e) => prop_assert!(e.contains("truncated.toml"), "{}", e),
        }
    }

    /// Random bytes, and random text of TOML's characters: refused by
    /// name, or read.
    #[test]
    fn random_configurations_are_refused_by_name_or_read(
        junk in prop::collection::vec(any::<u8>(), 0..512),
        text in "[a-z0-9 =\"'\\[\\]{}.,#\n_+-]{0,256}",
    ) {
        for (name, bytes) in [("random.toml", junk.as_slice()), ("text.toml", text.as_bytes())] {
            if let Err(e) = configure(name, bytes) {
                prop_assert!(e.contains(name), "{}", e);
            }
        }
    }
}

// ---------------------------------------------------------- the binary

/// The messages reach the user of `sphexa run`.
#[test]
fn sphexa_names_a_damaged_checkpoint_and_a_binary_configuration() {
    let fx = fixture();
    let dir = scratch("binary");
    let torn = dir.join("torn.h5");
    std::fs::write(&torn, &fx.bytes[..fx.bytes.len() / 2]).unwrap();
    let e = refused(&["--restart", s(&torn), "-q", "--out", s(&dir.join("o"))]);
    assert_mentions(&e, &["torn.h5"]);
    let junk = dir.join("junk.toml");
    std::fs::write(&junk, [0xff, 0xfe, 0x00, 0x41, 0x80]).unwrap();
    let e = refused(&["--config", s(&junk)]);
    assert_mentions(&e, &["junk.toml", "not UTF-8"]);
}
