//! `sphexa stress --quick` (the CI subset of the suite) passes under block
//! and global time steps, and writes stress.json with a verdict and figures
//! for every scenario.

mod common;

use common::sphexa_command;
use std::path::PathBuf;

// Two tests, not one running both: the harness runs them side by side,
// and the suite's serial parts leave a core free for the other.

#[test]
fn the_quick_stress_suite_passes() {
    // Block time steps, the default.
    quick_suite_passes(&[]);
}

#[test]
fn the_quick_stress_suite_passes_under_global_time_steps() {
    quick_suite_passes(&["--time-steps", "global"]);
}

fn quick_suite_passes(extra: &[&str]) {
    let out =
        PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("stress-quick{}", extra.join("")));
    std::fs::remove_dir_all(&out).ok();
    let o = sphexa_command()
        .args(["stress", "--quick", "--threads", "2"])
        .args(extra)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("sphexa runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("stress.json")).unwrap()).unwrap();
    let all = json.as_array().unwrap();
    assert!(all.len() >= 15, "{} scenarios", all.len());
    for s in all {
        assert_eq!(s["pass"], true, "{s}");
        // A run refused at its start (a massless particle under volume
        // elements) has nothing to measure.
        let stopped = s["note"].as_str().unwrap().starts_with("stopped:");
        assert!(
            stopped || !s["figures"].as_object().unwrap().is_empty(),
            "{s}"
        );
    }
    // The table lists every scenario.
    for s in all {
        assert!(stdout.contains(s["name"].as_str().unwrap()), "{stdout}");
    }
    // The zero-mass particle is named, not hidden.
    let zero = all
        .iter()
        .find(|s| s["name"] == "extreme-zero-mass")
        .unwrap();
    assert!(zero["note"].as_str().unwrap().contains("id 100"), "{zero}");
}
