//! `sphexa bench --ranks 1,2` (built only with `--features mpi`; run by
//! `cargo test -p sph-apps --features mpi --test mpi_bench`): the runs on
//! two ranks are started through the launcher, land in bench.csv with
//! their rank count, and give the one-rank run's L1 errors to the bit (the
//! solver's results do not depend on the decomposition).

mod common;

use common::sphexa_command;
use std::path::PathBuf;

#[test]
fn bench_runs_each_size_on_one_and_two_ranks() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mpi-bench");
    std::fs::remove_dir_all(&out).ok();
    let mpi = sph_comm::launch::Launcher::detect().unwrap_or_else(|e| panic!("{e}"));
    let o = sphexa_command()
        .args(["bench", "sedov", "--sizes", "10,12", "--schemes", "std,ve"])
        .args(["--ranks", "1,2", "--threads", "1", "--end-time", "0.01"])
        .args(["--mpirun", &mpi.words().join(" "), "-q", "--out"])
        .arg(&out)
        .envs(mpi.env().iter().copied())
        .output()
        .expect("sphexa bench runs");
    assert!(
        o.status.success(),
        "sphexa bench failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let csv = std::fs::read_to_string(out.join("bench.csv")).expect("bench.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 8, "2 sizes x 2 schemes x 2 rank counts");
    for r in &rows {
        if r[col("ranks")] != "2" {
            continue;
        }
        let twin = rows
            .iter()
            .find(|s| {
                s[col("ranks")] == "1"
                    && s[col("scheme")] == r[col("scheme")]
                    && s[col("side")] == r[col("side")]
            })
            .expect("the one-rank run of the same scheme and size");
        for name in ["N", "steps", "l1_rho", "l1_p", "l1_v", "t_end"] {
            assert_eq!(r[col(name)], twin[col(name)], "{name} differs on 2 ranks");
        }
        let rss: f64 = r[col("peak_rss_bytes")].parse().expect("a number");
        assert!(rss > 1e6, "peak RSS {rss} of a 2-rank run");
    }
    let twos = rows.iter().filter(|r| r[col("ranks")] == "2").count();
    assert_eq!(twos, 4);
}
