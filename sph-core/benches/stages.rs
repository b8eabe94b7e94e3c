//! Hot paths of sph-core on 1e5 particles (a perturbed 46^3 lattice in a
//! periodic box, ~100 neighbours): density + grad-h, IAD, momentum-energy
//! (constant and per-particle viscosity; with the conduction under each
//! contrast weight), AV switches; and the stirring
//! field on 32^3 random points.

// criterion_group! defines a public function without docs.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use sph_core::av_switch::{
    iad_and_velocity_divergence, update_alpha, velocity_divergence, AvSwitchParams, FlowState,
};
use sph_core::conduction::{Conductivity, Contrast};
use sph_core::density::{density, Positions};
use sph_core::iad::iad;
use sph_core::momentum::{
    momentum_energy, momentum_energy_switched, momentum_energy_with, Alpha, Gradients, HydroState,
    MomentumScheme, PairFactors, Rates,
};
use sph_core::stirring::{Mt19937, StirParams, Stirring};
use sph_core::Choice;
use sph_core::{Eos, FieldSet, Particles};
use sph_kernels::{FastKernel, Sinc};
use sph_tree::{
    apply_permutation, compute_keys, Boundary, BoundingBox, CompactNeighborList, Curve, KeySorter,
    NeighborSearch, Octree,
};
use std::hint::black_box;

fn setup() -> (Particles, BoundingBox, CompactNeighborList) {
    let side = 46; // 97,336 particles
    let n = side * side * side;
    let mut p = Particles::new(n, FieldSet::default());
    let bbox = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
    let mut s: u64 = 42;
    let mut rnd = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let dx = 1.0 / side as f64;
    for i in 0..n {
        let c = [i % side, i / side % side, i / (side * side)];
        let q = bbox.wrap(c.map(|k| (k as f64 + 0.5) * dx - 0.5 + 0.3 * dx * rnd()));
        (p.x[i], p.y[i], p.z[i]) = (q[0], q[1], q[2]);
        p.vx[i] = rnd();
        p.vy[i] = rnd();
        p.vz[i] = rnd();
        p.m[i] = 1.0 / n as f64;
        p.u[i] = 1.0 + rnd();
        p.h[i] = 0.5 * (3.0 * 100.0 / (4.0 * std::f64::consts::PI * n as f64)).cbrt();
    }
    let mut keys = Vec::new();
    compute_keys(&bbox, Curve::Hilbert, &p.x, &p.y, &p.z, &mut keys);
    let mut perm = Vec::new();
    KeySorter::new().sort(&keys, None, &mut perm);
    p.reorder(&perm, &mut Vec::new());
    apply_permutation(&perm, &mut keys, &mut Vec::new());
    let tree = Octree::build(&keys, &p.x, &p.y, &p.z, 16).unwrap();
    let mut list = CompactNeighborList::new();
    // Grouped lists, as the solver builds them.
    let search = NeighborSearch {
        grouped: true,
        ..NeighborSearch::default()
    };
    search
        .find_compact(&tree, &bbox, &p.x, &p.y, &p.z, &p.h, 0..n, &mut list)
        .unwrap();
    (p, bbox, list)
}

fn benches(c: &mut Criterion) {
    let (mut p, bbox, list) = setup();
    // The solver's form of sinc:6 (a polynomial in v^2).
    let kernel = FastKernel::new(&Sinc::new(6.0).unwrap()).unwrap();
    let mut g = c.benchmark_group("stages_1e5");
    g.sample_size(10);
    {
        let Particles {
            x,
            y,
            z,
            h,
            m,
            rho,
            omega,
            ..
        } = &mut p;
        let pos = Positions { x, y, z, h, m };
        g.bench_function("density_gradh", |b| {
            b.iter(|| density(&kernel, &bbox, pos, &list, rho, omega))
        });
    }
    {
        let Particles {
            x,
            y,
            z,
            h,
            m,
            rho,
            iad: c6,
            ..
        } = &mut p;
        let pos = Positions { x, y, z, h, m };
        g.bench_function("iad", |b| {
            b.iter(|| black_box(iad(&kernel, &bbox, pos, rho, &list, c6).is_ok()))
        });
    }
    Eos::IdealGas { gamma: 5.0 / 3.0 }.apply(&p.rho, &p.u, None, &mut p.p, &mut p.c);
    for (name, grad) in [
        ("momentum_energy_iad", Gradients::Iad),
        ("momentum_energy_kernel", Gradients::Kernel),
    ] {
        let Particles {
            x,
            y,
            z,
            h,
            m,
            vx,
            vy,
            vz,
            rho,
            p: pr,
            c: cs,
            omega,
            iad: c6,
            ax,
            ay,
            az,
            du,
            u,
            ..
        } = &mut p;
        let state = HydroState {
            pos: Positions { x, y, z, h, m },
            vx,
            vy,
            vz,
            rho,
            p: pr,
            c: cs,
            omega,
            iad: std::array::from_fn(|k| c6[k].as_slice()),
        };
        let mut factors = PairFactors::default();
        factors.fill(&state);
        // The pass's outputs, borrowed anew for each iteration.
        macro_rules! rates {
            () => {
                Rates {
                    ax: &mut *ax,
                    ay: &mut *ay,
                    az: &mut *az,
                    du: &mut *du,
                    criteria: None,
                    impulse: None,
                }
            };
        }
        g.bench_function(name, |b| {
            b.iter(|| {
                let rates = rates!();
                black_box(momentum_energy(
                    &kernel, &bbox, state, &factors, grad, 1.0, &list, rates,
                ))
            })
        });
        // Per-particle alpha in [0.05, 1].
        let alpha: Vec<f64> = (0..rho.len())
            .map(|i| 0.05 + 0.95 * ((i * 7919) % 1000) as f64 / 1000.0)
            .collect();
        g.bench_function(format!("{name}_switched"), |b| {
            b.iter(|| {
                let rates = rates!();
                black_box(momentum_energy_switched(
                    &kernel, &bbox, state, &factors, grad, &alpha, &list, rates,
                ))
            })
        });
        if grad == Gradients::Iad {
            // The conduction inside the momentum pass (alpha_u = 2, as
            // `gas`), with each contrast weight: what `larger`'s two
            // divisions per pair cost against `energy`'s one.
            for contrast in [
                Contrast::Off,
                Contrast::Energy,
                Contrast::Pressure,
                Contrast::Larger,
            ] {
                let scheme = MomentumScheme {
                    conduction: Some(Conductivity {
                        alpha_u: 2.0,
                        p: pr,
                        u,
                        contrast,
                        impulses: None,
                    }),
                    ..MomentumScheme::paper(grad, Alpha::PerParticle(&alpha))
                };
                let name = format!("{name}_conduction_{}", contrast.name());
                g.bench_function(name, |b| {
                    b.iter(|| {
                        let rates = rates!();
                        black_box(momentum_energy_with(
                            &kernel, &bbox, state, &factors, scheme, &list, rates,
                        ))
                    })
                });
            }
            // Both passes of the AV switches (div v, then grad div v and alpha).
            let flow = FlowState::from(state);
            let params = AvSwitchParams::default();
            let mut div_v = vec![0.0; rho.len()];
            let mut alpha = vec![params.alpha_min; rho.len()];
            // IAD and div v in one pass, as the solver runs them with switches.
            let mut c6: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; rho.len()]);
            let mut plain = flow;
            plain.iad = [&[]; 6];
            g.bench_function("iad_divergence_fused", |b| {
                b.iter(|| {
                    black_box(
                        iad_and_velocity_divergence(
                            &kernel,
                            &bbox,
                            plain,
                            [m, rho],
                            &list,
                            &mut c6,
                            &mut div_v,
                            &mut [],
                            &mut [],
                        )
                        .is_ok(),
                    )
                })
            });
            g.bench_function("av_switches_iad", |b| {
                b.iter(|| {
                    velocity_divergence(
                        &kernel,
                        &bbox,
                        flow,
                        grad,
                        &list,
                        &mut div_v,
                        &mut [],
                        &mut [],
                    );
                    update_alpha(
                        &kernel, &bbox, flow, grad, &div_v, &params, 1e-4, &list, &mut alpha,
                    );
                    black_box(alpha[0])
                })
            });
        }
    }
    g.finish();
}

/// The stirring acceleration (112 mode entries) at 32^3 random points.
fn stirring(c: &mut Criterion) {
    let bbox = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
    let mut stir = Stirring::new(StirParams::default(), &bbox).unwrap();
    stir.advance(1e-4);
    let n = 32 * 32 * 32;
    let mut g = Mt19937::new(7);
    let mut coord = || (0..n).map(|_| g.next_canonical() - 0.5).collect::<Vec<_>>();
    let (x, y, z) = (coord(), coord(), coord());
    let (mut ax, mut ay, mut az) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut group = c.benchmark_group("stirring_32c");
    group.sample_size(20);
    group.bench_function("accelerate", |b| {
        b.iter(|| {
            stir.accelerate(&x, &y, &z, &mut ax, &mut ay, &mut az);
            black_box(ax[0])
        })
    });
    group.finish();
}

criterion_group!(stage_benches, benches, stirring);
criterion_main!(stage_benches);
