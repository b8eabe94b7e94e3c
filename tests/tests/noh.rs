//! Noh implosion to t = 0.3 with the case's scheme (kernel gradients,
//! viscosity switches up to alpha = 0.7), at two resolutions: spheres cut
//! from 30^3 and 37^3 lattices (14,328 and 26,745 particles).
//!
//! VALIDATION.md asks for the post-shock plateau within 10% of 64 rho0
//! (rho0 the particle set's own density), away from the centre: the mean
//! density between 0.3 and 0.8 shock radii is measured (the centre has the
//! wall-heating dip, the outer part the smeared shock).
//!
//! Measured (2 threads), 30^3 / 37^3 cut: plateau 57.3 / 65.7 rho0; L1 rho
//! 18.93 / 16.73, P 8.88 / 8.69, |v| 0.238 / 0.215 (absolute units; rho0 =
//! 1.91, so 64 rho0 = 122); shock (half-way density between the inflow and
//! the shocked gas) at 0.1068 / 0.0957 against 0.1 (+6.8% / -4.3%). With
//! the paper's constant alpha = 1 the plateau stays near 21 rho0.
//!
//! Checks: the plateau at 37^3 within 10%; every L1 lower at 37^3 than at
//! 30^3; L1 bounds at 37^3 (its figures + 10%); the shock within 10% at
//! both.
//!
//! Null solution: the untouched initial state has no shock and no plateau
//! (rho0 everywhere), so it fails those two checks. It does not fail the
//! L1 bounds: L1 sampled at the particles' initial positions scores
//! 5.8 / 0.31 / 0.0076 (computed in the test), because there almost every
//! particle is in the unshocked inflow, which the reference describes
//! exactly, while after the run half of them are shocked. The L1 figures
//! here are checked for convergence and against regressions, not as a
//! proof that the implosion happened.

use sph_apps::cases;
use sph_apps::simulation::Stop;
use sph_apps::Summary;
use sph_core::HydroConfig;

const T_END: f64 = 0.3;
/// L1 bounds at the 37^3 cut: rho, P, |v|.
const L1_MAX: [f64; 3] = [18.4, 9.6, 0.24];

fn run(side: usize) -> Summary {
    let scene = cases::lookup("noh")
        .unwrap()
        .setup(side, HydroConfig::default())
        .unwrap();
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("noh{side}"));
    sph_validation::run(scene, Stop::Time(T_END), &out)
}

/// L1 rho / P / |v| of the initial state of the `side^3` cut, held still.
fn null_solution(side: usize) -> [f64; 3] {
    let scene = cases::lookup("noh")
        .unwrap()
        .setup(side, HydroConfig::default())
        .unwrap();
    let reference = scene.reference.clone().unwrap();
    let rho0 = scene.particles.m[0] * (side * side * side) as f64;
    let p = &scene.particles;
    let n = p.len() as f64;
    let mut l1 = [0.0; 3];
    for i in 0..p.len() {
        let r = reference.coordinate([p.x[i], p.y[i], p.z[i]]);
        let s = reference.state(r, T_END);
        let speed = (p.vx[i].powi(2) + p.vy[i].powi(2) + p.vz[i].powi(2)).sqrt();
        l1[0] += (rho0 - s.rho).abs() / n;
        l1[1] += s.p.abs() / n;
        l1[2] += (speed - s.v.abs()).abs() / n;
    }
    l1
}

#[test]
fn noh_reaches_the_plateau_and_converges() {
    let coarse = run(30);
    let fine = run(37);

    let target = fine.plateau_density_ref.unwrap();
    let plateau = fine.plateau_density.unwrap();
    let rho0 = target / 64.0;
    assert!(
        (plateau / target - 1.0).abs() < 0.1,
        "plateau {plateau} = {} rho0, target 64 rho0",
        plateau / rho0
    );

    for s in [&coarse, &fine] {
        let (r, r_ref) = (s.shock_radius.unwrap(), s.shock_radius_ref.unwrap());
        assert!(
            (r_ref - 0.1).abs() < 1e-12,
            "reference shock radius {r_ref}"
        );
        assert!(
            (r / r_ref - 1.0).abs() < 0.1,
            "{} particles: shock at {r}, reference {r_ref}",
            s.particles
        );
        assert!(
            s.energy_rel_drift.abs() < 1e-3,
            "energy drift {:e}",
            s.energy_rel_drift
        );
        assert!(
            s.momentum_rel_drift < 1e-12,
            "momentum drift {:e}",
            s.momentum_rel_drift
        );
    }

    let (c, f) = (coarse.l1.unwrap(), fine.l1.unwrap());
    let (c, f) = ([c.rho, c.p, c.v], [f.rho, f.p, f.v]);
    for k in 0..3 {
        assert!(
            f[k] < c[k],
            "L1 does not fall: {c:?} at 30^3, {f:?} at 37^3"
        );
        assert!(f[k] < L1_MAX[k], "L1 {f:?} against bounds {L1_MAX:?}");
    }
    // The initial state: rho0 in the plateau shell, no shock at all, and
    // its L1 (see above) below the run's.
    let null = null_solution(37);
    assert!((rho0 / target - 1.0).abs() > 0.1);
    assert!(null.iter().zip(&f).all(|(n, r)| n < r), "{null:?} {f:?}");
}
