//! Sod's shock tube (doubled, periodic, gamma = 5/3) to t = 0.2 at side 40
//! (40 dense particles per unit length, 11,523 particles from an 8^3 glass
//! block), with the case's scheme, against the exact Riemann solution.
//!
//! The case's scheme is `gas` since 2026-12-06 (issue 42): L1 rho / P /
//! v_x 0.0173 / 0.0178 / 0.0381 at side 40 and 0.0115 / 0.0122 / 0.0256
//! at 80 (2 threads, global steps). The bounds were set on the scheme
//! before it, the paper's with kernel gradients, as follows.
//!
//! Measured from glass at side 40 and 80 (2 threads): L1 rho 0.0163 /
//! 0.0094, P 0.0182 / 0.0109, v_x 0.0322 / 0.0187 (the error falls as
//! N^(-0.26) with N = 8x); shock at |x| = 0.8780 / 0.8761 (exact 0.8689:
//! +1.0% / +0.8%); contact at 0.6645 / 0.6668 (exact 0.6682: -0.6% /
//! -0.2%). The L1 bounds are the side-40 figures plus 20% (machine and
//! thread-count rounding move them by far less); the positions must be
//! within 2% of the exact ones. The same tube on cubic lattices
//! (`--lattice`) gives 0.0301 / 0.0416 / 0.0525 at side 40 and barely
//! improves at 80 (0.0298 / 0.0379 / 0.0459: the expanded dense gas
//! settles 20% too dense there), so these bounds also fail the lattice.
//!
//! Null solution: the untouched initial state, compared with the t = 0.2
//! solution, must fail every L1 bound and the shock position (checked in
//! the test, from the same particles).

use sph_apps::cases::Reference;
use sph_apps::simulation::Stop;

const SIDE: usize = 40;
const T_END: f64 = 0.2;
/// L1 bounds: rho, P, v_x.
const L1_MAX: [f64; 3] = [0.020, 0.022, 0.039];

/// The outermost `|x|` where the profile's density falls through `level`
/// (from `profile.csv`, rows `r,count,rho,...`), interpolated.
fn front(profile: &str, level: f64) -> f64 {
    let rows: Vec<(f64, f64)> = profile
        .lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let count: usize = f[1].parse().ok()?;
            (count > 0).then(|| (f[0].parse().unwrap(), f[2].parse().unwrap()))
        })
        .collect();
    let k = rows
        .iter()
        .rposition(|&(_, rho)| rho >= level)
        .expect("some bin above the level");
    let ((ra, da), (rb, db)) = (rows[k], rows[k + 1]);
    ra + (da - level) / (da - db) * (rb - ra)
}

/// The tube's L1 bounds and the shock within 2% of the exact position
/// (returned).
fn check_l1_and_shock(s: &sph_apps::Summary, tube: &sph_apps::cases::Tube) -> f64 {
    let l1 = s.l1.expect("L1 against the exact solution");
    let got = [l1.rho, l1.p, l1.v];
    for k in 0..3 {
        assert!(got[k] < L1_MAX[k], "L1 {got:?} against bounds {L1_MAX:?}");
    }
    let shock_ref = tube.shock_position(T_END);
    let shock = s.shock_radius.expect("measured shock");
    assert!(
        (shock / shock_ref - 1.0).abs() < 0.02,
        "shock at {shock}, exact {shock_ref}"
    );
    shock_ref
}

#[test]
fn sod_tube_matches_the_exact_riemann_solution() {
    let scene = sph_validation::scene("sod", SIDE);
    let Some(Reference::Tube(tube)) = scene.reference.clone() else {
        panic!("sod has a tube reference");
    };
    let reference = scene.reference.clone().unwrap();

    // Null solution: the initial state, held still, against the solution.
    let p0 = &scene.particles;
    let n = p0.len() as f64;
    let mut null = [0.0f64; 3];
    for i in 0..p0.len() {
        let s = reference.coordinate([p0.x[i], p0.y[i], p0.z[i]]);
        let (now, then) = (reference.state(s, 0.0), reference.state(s, T_END));
        null[0] += (now.rho - then.rho).abs() / n;
        null[1] += (now.p - then.p).abs() / n;
        null[2] += (now.v - then.v).abs() / n;
    }
    for k in 0..3 {
        assert!(null[k] > 2.0 * L1_MAX[k], "null {null:?} passes bound {k}");
    }

    let out = sph_validation::scratch("sod40");
    let s = sph_validation::run(scene, Stop::Time(T_END), &out);
    let shock_ref = check_l1_and_shock(&s, &tube);
    assert!(
        (tube.interface / shock_ref - 1.0).abs() > 0.02,
        "the initial interface would pass"
    );

    let (rho_l, rho_r) = tube.riemann.rho_star();
    let profile = std::fs::read_to_string(out.join("profile.csv")).unwrap();
    let contact = front(&profile, 0.5 * (rho_l + rho_r));
    let contact_ref = tube.contact_position(T_END);
    assert!(
        (contact / contact_ref - 1.0).abs() < 0.02,
        "contact at {contact}, exact {contact_ref}"
    );

    assert!(s.energy_rel_drift.abs() < 1e-3, "{}", s.energy_rel_drift);
    assert!(s.momentum_rel_drift < 1e-12, "{}", s.momentum_rel_drift);
}

/// Block time steps (issue 41) keep the tube's bounds; momentum is not
/// kept to round-off under them (a pair's two forces are evaluated at
/// different times), so its bound is stated from two resolutions, with the
/// limiter. Measured (2026-12-04): side 40 L1 rho / P / v_x 0.0160 /
/// 0.0178 / 0.0314 (global 0.0163 / 0.0182 / 0.0322); momentum drift
/// 1.1e-5 at side 20 and 5.0e-6 at side 40 (global 2e-18); energy drift
/// 9.1e-7 and 7.6e-6.
#[test]
fn block_steps_keep_the_tube_with_momentum_within_1e_4() {
    for side in [20, SIDE] {
        let mut scene = sph_validation::scene("sod", side);
        scene.config.time_steps = sph_core::TimeSteps::Block;
        let Some(Reference::Tube(tube)) = scene.reference.clone() else {
            panic!("sod has a tube reference");
        };
        let out = sph_validation::scratch(&format!("sod{side}-block"));
        let s = sph_validation::run(scene, Stop::Time(T_END), &out);
        assert!(
            s.particle_updates < s.steps * s.particles as u64,
            "side {side}: some particle skipped a sub-step"
        );
        assert!(
            s.momentum_rel_drift < 1e-4,
            "side {side}: {}",
            s.momentum_rel_drift
        );
        assert!(
            s.energy_rel_drift.abs() < 1e-3,
            "side {side}: {}",
            s.energy_rel_drift
        );
        if side == SIDE {
            check_l1_and_shock(&s, &tube);
        }
    }
}
