//! Internal energy under the barotropic equations of state (isothermal,
//! polytropic): the first step sets `u = e(rho)`, the compression energy
//! from density 1, so that `E_kin + E_int` is conserved and `u - e(rho)` is
//! the heat made (issue 43).

use sph_core::scheme::Viscosity;
use sph_core::{Eos, Hydro, HydroConfig, Particles, Scheme, StepReport};
use sph_kernels::{Sinc, Tabulated};
use sph_tree::{Boundary, BoundingBox};

const N: usize = 16;
/// Mean density 2: `e(2)` is far from 0, so a run that kept the given `u`
/// (0 here) instead of `e(rho)` fails the heat check below.
const RHO: f64 = 2.0;

/// An `N^3` lattice of density [`RHO`] in a periodic unit box, sound speed
/// about 1, with the velocity `vx = amplitude sin(2 pi x)` (a standing
/// sound wave, period about 1), run for `steps` steps of the paper's scheme
/// with viscosity 0.1 (`steps`, or more until `t_end`): the particles and
/// the reports.
fn wave(
    eos: Eos,
    amplitude: f64,
    h: f64,
    steps: usize,
    t_end: f64,
) -> (Particles, Vec<StepReport>) {
    let mut config = HydroConfig::with_scheme(Scheme::PAPER);
    config.eos = eos;
    config.scheme.viscosity = Viscosity::Constant { alpha: 0.1 };
    config.neighbors.ng0 = 60;
    config.neighbors.ngmax = 90;
    let mut p = Particles::new(N * N * N, config.fields());
    for i in 0..p.len() {
        let c = [i % N, i / N % N, i / (N * N)].map(|k| (k as f64 + 0.5) / N as f64 - 0.5);
        (p.x[i], p.y[i], p.z[i]) = (c[0], c[1], c[2]);
        p.vx[i] = amplitude * (2.0 * std::f64::consts::PI * c[0]).sin();
        p.m[i] = RHO / p.len() as f64;
        p.h[i] = h;
        p.u[i] = 0.0;
    }
    let mut bbox = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
    let kernel = Tabulated::new(&Sinc::new(6.0).unwrap(), Tabulated::DEFAULT_POINTS).unwrap();
    let mut hydro = Hydro::new(kernel, config, 0.0, 1e-3).unwrap();
    hydro.prepare(&mut p);
    let mut reports: Vec<StepReport> = Vec::new();
    while reports.len() < steps || reports.last().is_none_or(|r| r.t < t_end) {
        reports.push(hydro.step(&mut p, &mut bbox).unwrap());
    }
    (p, reports)
}

/// The lattice's smoothing length after the neighbour count has settled,
/// at rest: a wave started with it sees the density change by its motion
/// only, not by `h` relaxing (which changes the estimate by ~1% here).
fn settled_h(eos: Eos) -> f64 {
    let (p, _) = wave(eos, 0.0, 1.3 / N as f64, 20, 0.0);
    p.h[0]
}

/// Isothermal with `c = 1`, and polytropic with `c = 1` at density 2.
fn barotropic() -> [Eos; 2] {
    let gamma = 5.0 / 3.0;
    [
        Eos::Isothermal { c0: 1.0 },
        Eos::Polytropic {
            k: RHO.powf(1.0 - gamma) / gamma,
            gamma,
        },
    ]
}

#[test]
fn gas_at_rest_holds_the_compression_energy_of_its_density() {
    for eos in barotropic() {
        let (p, reports) = wave(eos, 0.0, 1.3 / N as f64, 1, 0.0);
        for i in 0..p.len() {
            assert_eq!(p.u[i], eos.energy(p.rho[i]).unwrap(), "{eos}: particle {i}");
        }
        let e_int = reports[0].conserved.e_int;
        let expected = eos.energy(RHO).unwrap() * RHO;
        assert!(
            (e_int - expected).abs() < 1e-2 * expected.abs(),
            "{eos}: E_int {e_int} against {expected}"
        );
    }
    // An EOS that reads u keeps the particles' own.
    let (p, _) = wave(Eos::IdealGas { gamma: 1.4 }, 0.0, 1.3 / N as f64, 1, 0.0);
    assert!(p.u.iter().all(|&u| u == 0.0));
}

#[test]
fn a_sound_wave_trades_kinetic_for_compression_energy_and_conserves_the_sum() {
    let amplitude = 1e-2;
    for eos in barotropic() {
        // A quarter period at c = 1 in a unit box.
        let (p, reports) = wave(eos, amplitude, settled_h(eos), 1, 0.3);
        let t_quarter = reports
            .iter()
            .position(|r| r.t >= 0.25)
            .expect("reached t = 0.25");
        let first = &reports[0].conserved;
        let quarter = &reports[t_quarter].conserved;
        let wave_energy = first.e_kin;
        // Not frozen: most of the kinetic energy went into compression.
        assert!(
            quarter.e_kin < 0.2 * wave_energy,
            "{eos}: E_kin {} of {wave_energy} at t = {}",
            quarter.e_kin,
            reports[t_quarter].t
        );
        let drift = reports
            .iter()
            .map(|r| (r.conserved.e_tot() - first.e_tot()).abs())
            .fold(0.0, f64::max);
        // Measured 0.14 (isothermal) and 0.07 (polytropic) of the wave
        // energy at t = 0.3, rising steadily from t = 0: the integrator's
        // error at ~135 steps a period on a 16^3 lattice, which an ideal
        // gas (gamma 5/3, c = 1) in the same set-up shows too (0.05). An
        // E_int that did not count the compression would miss by the whole
        // wave energy.
        assert!(
            drift < 0.2 * wave_energy,
            "{eos}: E_kin + E_int drifts by {drift:e} of a wave energy {wave_energy:e}"
        );
        // u follows e(rho) particle by particle: the mean |u - e(rho)| is
        // measured at 0.20 of the mean |e(rho) - e(2)| (the summation
        // density and the integrated energy equation differ at this
        // resolution; the viscous heat is ~1e-5 of it). A u that did not
        // take the compression work, or started from 0, would be at 1 or
        // at e(2) / swing ~ 70.
        let mean_of = |f: &dyn Fn(usize) -> f64| (0..p.len()).map(f).sum::<f64>() / p.len() as f64;
        let e = |i: usize| eos.energy(p.rho[i]).unwrap();
        let heat = mean_of(&|i| (p.u[i] - e(i)).abs());
        let swing = mean_of(&|i| (e(i) - eos.energy(RHO).unwrap()).abs());
        assert!(
            heat < 0.4 * swing,
            "{eos}: mean |u - e(rho)| {heat:e} against a swing {swing:e}"
        );
    }
}
