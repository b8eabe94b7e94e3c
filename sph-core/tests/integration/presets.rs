//! Every scheme preset (and the Balsara limiter on the paper's and the
//! `ve` scheme) through `Hydro::step` on a small periodic blast: linear
//! momentum kept to round-off, total energy to integrator accuracy, and
//! the same bits with 1 and 2 threads.

use sph_core::{Hydro, HydroConfig, Particles, Scheme, PRESETS};
use sph_kernels::{Sinc, Tabulated};
use sph_tree::{Boundary, BoundingBox};

/// A 12^3 lattice in a periodic unit box, hot in the middle (a small
/// Sedov blast), run for `steps` steps of `scheme`: the final particles
/// and the largest momentum and relative energy drifts.
fn blast(scheme: Scheme, steps: usize) -> (Particles, f64, f64) {
    let n = 12;
    let config = HydroConfig::with_scheme(scheme);
    let mut p = Particles::new(n * n * n, config.fields());
    for i in 0..p.len() {
        let c = [i % n, i / n % n, i / (n * n)].map(|k| (k as f64 + 0.5) / n as f64 - 0.5);
        (p.x[i], p.y[i], p.z[i]) = (c[0], c[1], c[2]);
        p.m[i] = 1.0 / p.len() as f64;
        p.h[i] = 1.9 / n as f64;
        p.u[i] = 1e-4 + (-(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / 0.01).exp();
    }
    let mut bbox = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
    let kernel = Tabulated::new(&Sinc::new(6.0).unwrap(), Tabulated::DEFAULT_POINTS).unwrap();
    let mut hydro = Hydro::new(kernel, config, 0.0, 1e-4).unwrap();
    hydro.prepare(&mut p);
    let first = hydro.step(&mut p, &mut bbox).unwrap().conserved;
    let (mut mom, mut de) = (0.0f64, 0.0f64);
    for _ in 1..steps {
        let c = hydro.step(&mut p, &mut bbox).unwrap().conserved;
        // Momentum relative to the total |momentum| scale sum m |v|.
        let scale: f64 = (0..p.len())
            .map(|i| p.m[i] * (p.vx[i].abs() + p.vy[i].abs() + p.vz[i].abs()))
            .sum();
        for k in 0..3 {
            mom = mom.max(c.momentum[k].abs() / scale);
        }
        de = de.max(((c.e_tot() - first.e_tot()) / first.e_tot()).abs());
    }
    (p, mom, de)
}

fn with_balsara(mut s: Scheme) -> Scheme {
    s.balsara = true;
    s
}

fn schemes() -> Vec<(String, Scheme)> {
    let mut v: Vec<(String, Scheme)> = PRESETS.iter().map(|p| (p.0.to_string(), p.1)).collect();
    for (name, s) in [("paper", Scheme::PAPER), ("ve", Scheme::VE)] {
        v.push((format!("{name}+balsara"), with_balsara(s)));
    }
    v
}

#[test]
fn every_preset_conserves_momentum_and_energy_and_ignores_threads() {
    for (name, scheme) in schemes() {
        let pool = |t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
        };
        let (p1, mom, de) = pool(1).install(|| blast(scheme, 12));
        let (p2, _, _) = pool(2).install(|| blast(scheme, 12));
        assert!(mom < 1e-13, "{name}: momentum drift {mom:e}");
        assert!(de < 1e-3, "{name}: energy drift {de:e}");
        assert!(p1.vx.iter().any(|&v| v != 0.0), "{name}: nothing moved");
        for (a, b) in [
            (&p1.x, &p2.x),
            (&p1.vx, &p2.vx),
            (&p1.u, &p2.u),
            (&p1.rho, &p2.rho),
        ] {
            assert!(
                a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "{name}: 1 and 2 threads differ"
            );
        }
    }
}

#[test]
fn balsara_changes_the_solution_and_ve_differs_from_paper() {
    let (plain, _, _) = blast(Scheme::PAPER, 6);
    let (limited, _, _) = blast(with_balsara(Scheme::PAPER), 6);
    assert_ne!(plain.u, limited.u);
    let (ve, _, _) = blast(Scheme::VE, 6);
    assert_ne!(plain.rho, ve.rho);
}
