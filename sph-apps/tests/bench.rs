//! `sphexa bench` end to end (CI-sized): three Sedov resolutions with the
//! `std` preset and the C++ reference points write bench.csv with every
//! column, bench.json with the fitted orders, and a PNG that is a real
//! plot.

mod common;

use common::sphexa_command;
use std::path::PathBuf;

#[test]
fn bench_writes_csv_json_and_a_real_plot() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench-sedov");
    std::fs::remove_dir_all(&out).ok();
    let reference = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sphexa_cpp_sedov.csv");
    let o = sphexa_command()
        .args(["bench", "sedov", "--sizes", "16,20,24", "--schemes", "std"])
        .args(["--threads", "1", "--reference", reference, "-q", "--out"])
        .arg(&out)
        .output()
        .expect("sphexa runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");

    // CSV: the header is the documented column list, one row per size with
    // the particle counts of the lattices and finite, positive figures.
    let csv = std::fs::read_to_string(out.join("bench.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for col in [
        "case",
        "scheme",
        "kernel",
        "N",
        "ranks",
        "threads",
        "steps",
        "wall_s",
        "particle_steps_per_s",
        "peak_rss_bytes",
        "bytes_per_particle",
        "l1_rho",
        "l1_p",
        "l1_v",
        "energy_drift",
        "momentum_drift",
        "repeat",
    ] {
        assert!(header.contains(&col), "no column {col}: {header:?}");
    }
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 3);
    let ns: Vec<u64> = rows.iter().map(|r| r[col("N")].parse().unwrap()).collect();
    assert_eq!(ns, vec![16 * 16 * 16, 20 * 20 * 20, 24 * 24 * 24]);
    for r in &rows {
        assert_eq!(r[col("case")], "sedov");
        assert_eq!(r[col("scheme")], "std");
        assert_eq!(r[col("threads")], "1");
        for name in ["wall_s", "particle_steps_per_s", "l1_rho", "l1_p", "l1_v"] {
            let v: f64 = r[col(name)].parse().unwrap();
            assert!(v.is_finite() && v > 0.0, "{name} = {v}");
        }
        let rss: u64 = r[col("peak_rss_bytes")].parse().unwrap();
        assert!(rss > 1_000_000, "peak RSS {rss}");
    }

    // JSON: an order per L1 field of the one series, over the three sizes.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    let orders = json["orders"].as_array().unwrap();
    assert_eq!(orders.len(), 3, "{orders:?}");
    for o in orders {
        assert!(o["order"].as_f64().unwrap().is_finite());
        assert_eq!(o["sizes"].as_array().unwrap().len(), 3);
    }
    assert_eq!(json["reference"].as_array().unwrap().len(), 6);

    // PNG: the documented size, and drawn: many colours (lines, markers,
    // text antialiasing) and a good share of non-white pixels.
    let decoder = png::Decoder::new(std::fs::File::open(out.join("error_vs_time.png")).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (1800, 640));
    let channels = info.line_size / info.width as usize;
    assert!(channels >= 3);
    let pixels: Vec<&[u8]> = buf[..info.buffer_size()].chunks(channels).collect();
    let colours: std::collections::HashSet<[u8; 3]> =
        pixels.iter().map(|p| [p[0], p[1], p[2]]).collect();
    let non_white = pixels.iter().filter(|p| p[..3] != [255, 255, 255]).count();
    assert!(colours.len() > 50, "{} colours", colours.len());
    let share = non_white as f64 / pixels.len() as f64;
    assert!(share > 0.02, "non-white share {share}");
    // The series colours are there: ours in the first colour, the second
    // reference series in olive (the first is black, like the axes).
    for c in [[31u8, 119, 180], [188, 189, 34]] {
        assert!(colours.contains(&c), "colour {c:?} missing");
    }
}

/// `--time-steps global,block`: each combination both ways; bench.csv
/// names the mode and counts the particle updates (every particle every
/// step in the global run, fewer per sub-step under block steps), and the
/// block runs form their own series.
#[test]
fn bench_sweeps_the_time_step_modes() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench-modes");
    std::fs::remove_dir_all(&out).ok();
    let o = sphexa_command()
        .args([
            "bench",
            "sedov",
            "--sizes",
            "12",
            "--time-steps",
            "global,block",
        ])
        .args(["--threads", "1", "-q", "--out"])
        .arg(&out)
        .output()
        .expect("sphexa runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("bench.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let modes: Vec<&str> = rows.iter().map(|r| r[col("time_steps")]).collect();
    assert_eq!(modes, ["global", "block"]);
    let num = |r: &Vec<&str>, c: &str| r[col(c)].parse::<u64>().unwrap();
    let (g, b) = (&rows[0], &rows[1]);
    assert_eq!(num(g, "particle_updates"), num(g, "steps") * num(g, "N"));
    assert!(num(b, "particle_updates") < num(b, "steps") * num(b, "N"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    let text = json.to_string();
    assert!(text.contains("sedov case sinc:6 block"), "{text}");
    let e = sphexa_command()
        .args([
            "bench",
            "sedov",
            "--sizes",
            "12",
            "--time-steps",
            "adaptive",
        ])
        .output()
        .expect("sphexa runs");
    let stderr = String::from_utf8_lossy(&e.stderr);
    assert!(
        !e.status.success() && stderr.contains("adaptive") && stderr.contains("block"),
        "{stderr}"
    );
}
