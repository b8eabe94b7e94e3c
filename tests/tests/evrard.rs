//! Evrard collapse (30^3 lattice cut to the unit sphere: 14328 particles,
//! self-gravity) to t = 2.0, with the case's scheme and Courant factor,
//! against the energies of the 1-D Lagrangian reference in VALIDATION.md
//! (quoted there as good to 2%): E_kin, E_int and E_grav within 10% at
//! t = 0.8 (infall) and t = 2.0 (after the bounce); at t = 1.0 (the
//! bounce) E_int and E_grav within 10% and E_kin within 30%; total energy
//! (including E_grav) conserved to 1e-2 through the bounce (t <= 1.5).
//!
//! Measured: t = 0.8 -1.9% / -7.6% / -3.3%, t = 1.0 +23.5% / -7.8% /
//! -2.6%, t = 2.0 -9.1% / -1.3% / -2.3%, drift 3.4e-4; at 20^3 E_kin is
//! 19% low at t = 2.0, so 30^3 is the smallest resolution that meets the
//! 10% bounds. E_kin at the bounce is the known gap: the collapse lags the
//! reference's bounce at 20^3, 30^3 and 40^3 (+18%, +23.5%, +21%), the
//! 30% bound holds it there (~1 minute on 2 cores).

use sph_apps::cases;
use sph_apps::simulation::Stop;
use sph_core::HydroConfig;

#[test]
fn evrard_30_energies_match_reference() {
    let scene = cases::lookup("evrard")
        .unwrap()
        .setup(30, HydroConfig::default())
        .unwrap();
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("evrard30");
    let s = sph_validation::run(scene, Stop::Time(2.0), &out);

    for (t, kin_bound) in [(0.8, 0.10), (1.0, 0.30), (2.0, 0.10)] {
        let e = s
            .energies
            .iter()
            .find(|e| (e.t - t).abs() < 1e-12)
            .unwrap_or_else(|| panic!("no energies at t = {t}"));
        for (name, got, want, bound) in [
            ("E_kin", e.e_kin, e.e_kin_ref, kin_bound),
            ("E_int", e.e_int, e.e_int_ref, 0.10),
            ("E_grav", e.e_grav, e.e_grav_ref, 0.10),
        ] {
            let rel = (got - want) / want;
            println!(
                "t = {t}: {name} {got:.4} vs {want:.4} ({:+.1}%)",
                100.0 * rel
            );
            assert!(
                rel.abs() < bound,
                "t = {t}: {name} = {got}, reference {want}"
            );
        }
    }

    // Total energy through the bounce, from conserved.csv.
    let text = std::fs::read_to_string(out.join("conserved.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (ct, ce) = (col("t"), col("E_tot"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let e0 = rows[0][ce];
    let drift = rows
        .iter()
        .filter(|r| r[ct] <= 1.5)
        .map(|r| ((r[ce] - e0) / e0).abs())
        .fold(0.0, f64::max);
    println!("largest |E_tot drift| through t = 1.5: {drift:.2e}");
    assert!(drift < 1e-2, "energy drift {drift:e}");
}
