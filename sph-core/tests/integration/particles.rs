//! Invariants of the particle container's growth.

use proptest::prelude::*;
use sph_core::{FieldSet, Particles};
use sph_domain::ParticleFields;

proptest! {
    /// `reserve` keeps every value, makes room for the arrivals and does
    /// not double the arrays as repeated pushes would.
    #[test]
    fn reserve_keeps_values_and_grows_to_need(n in 1usize..300, extra in 0usize..600) {
        let mut p = Particles::new(n, FieldSet::default());
        for i in 0..n {
            p.x[i] = i as f64;
            p.id[i] = 7 * i as u64;
        }
        let mut packed = Vec::new();
        p.pack(n - 1, &mut packed);
        p.reserve(extra);
        let want = n + extra;
        for (name, cap) in [("x", p.x.capacity()), ("iad", p.iad[3].capacity()), ("id", p.id.capacity()), ("nc", p.nc.capacity())] {
            prop_assert!(cap >= want, "{name}: capacity {cap} < {want}");
            prop_assert!(cap <= want + want / 32 + 1 || extra == 0, "{name}: capacity {cap} for {want}");
        }
        for _ in 0..extra {
            p.push_packed(&packed);
        }
        prop_assert_eq!(p.len(), want);
        prop_assert!(p.check(FieldSet::default()).is_ok());
        for i in 0..n {
            prop_assert_eq!(p.x[i], i as f64);
            prop_assert_eq!(p.id[i], 7 * i as u64);
        }
        for i in n..want {
            prop_assert_eq!(p.x[i], (n - 1) as f64);
        }
    }
}

proptest! {
    /// A packed particle comes back with every persistent field; a packed
    /// halo with every field but the integrator's history (zeros there),
    /// in fewer words, with and without the optional persistent fields.
    #[test]
    fn halos_travel_without_the_integrator_history(seed in any::<u64>(), switches in any::<bool>()) {
        let fields = FieldSet::default();
        let mut p = Particles::new(1, fields);
        if switches {
            p.enable_alpha(0.0);
        }
        let v = |k: u64| (seed.wrapping_mul(k + 1) % 1000) as f64 + 0.5;
        for (k, f) in [&mut p.x, &mut p.y, &mut p.z, &mut p.vx, &mut p.vy, &mut p.vz, &mut p.dx, &mut p.dy,
                       &mut p.dz, &mut p.h, &mut p.m, &mut p.u, &mut p.du_prev].into_iter().enumerate() {
            f[0] = v(k as u64);
        }
        if switches {
            p.alpha[0] = 0.25;
        }
        p.id[0] = seed;
        let (mut full, mut halo) = (Vec::new(), Vec::new());
        p.pack(0, &mut full);
        p.pack_halo(0, &mut halo);
        prop_assert_eq!(full.len(), p.packed_words());
        prop_assert_eq!(halo.len(), p.halo_words());
        prop_assert_eq!(p.packed_words() - p.halo_words(), 4);
        p.push_packed(&full);
        p.push_halo(&halo);
        prop_assert!(p.check(fields).is_ok());
        for f in [&p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz, &p.h, &p.m, &p.u] {
            prop_assert_eq!(f[1], f[0]);
            prop_assert_eq!(f[2], f[0]);
        }
        for f in [&p.dx, &p.dy, &p.dz, &p.du_prev] {
            prop_assert_eq!(f[1], f[0]);
            prop_assert_eq!(f[2], 0.0);
        }
        prop_assert_eq!(p.id[2], seed);
        if switches {
            prop_assert_eq!(p.alpha[2], 0.25);
        }
    }
}

proptest! {
    /// Placing the halos (moving only them and shifting the owned block)
    /// gives every field exactly what the full reorder by the same
    /// permutation gives.
    #[test]
    fn placing_halos_is_the_reorder_it_stands_for(
        n_owned in 0usize..60,
        keys in proptest::collection::vec(any::<u32>(), 0..40),
        low in 0.0f64..=1.0,
        gravity in any::<bool>(),
    ) {
        let nh = keys.len();
        let n = n_owned + nh;
        let mut fields = FieldSet::default();
        fields.gravity = gravity;
        let mut p = Particles::new(n, fields);
        for i in 0..n {
            p.id[i] = 1000 + i as u64;
            p.x[i] = i as f64;
            p.u[i] = -(i as f64);
            p.iad[2][i] = 0.5 * i as f64;
            p.du_prev[i] = i as f64 + 0.25;
        }
        let mut order: Vec<u32> = (0..nh as u32).collect();
        order.sort_by_key(|&k| (keys[k as usize], k));
        let n_low = (low * nh as f64) as usize;
        let mut perm = Vec::new();
        sph_domain::halo_placement(n_owned, &order, n_low, &mut perm);
        let mut want = p.clone();
        want.reorder(&perm, &mut Vec::new());
        ParticleFields::place_halos(&mut p, n_owned, &order, n_low, &mut Vec::new());
        prop_assert_eq!(&p.id, &want.id);
        prop_assert_eq!(&p.x, &want.x);
        prop_assert_eq!(&p.u, &want.u);
        prop_assert_eq!(&p.iad[2], &want.iad[2]);
        prop_assert_eq!(&p.du_prev, &want.du_prev);
        prop_assert_eq!(p.nc.len(), n);
    }
}

proptest! {
    /// The bulk halo paths give what the one-at-a-time ones give: the same
    /// words packed, every field (zeros for the history and the
    /// recomputed fields, Omega 1) after pushing.
    #[test]
    fn bulk_halo_packing_matches_one_at_a_time(
        n in 1usize..40,
        picks in proptest::collection::vec(any::<prop::sample::Index>(), 0..30),
        switches in any::<bool>(),
        gravity in any::<bool>(),
    ) {
        let mut fields = FieldSet::default();
        fields.gravity = gravity;
        let mut src = Particles::new(n, fields);
        if switches {
            src.enable_alpha(0.5);
        }
        for i in 0..n {
            src.id[i] = 50 + i as u64;
            for (k, f) in [&mut src.x, &mut src.vz, &mut src.h, &mut src.u, &mut src.dx, &mut src.du_prev, &mut src.rho]
                .into_iter()
                .enumerate()
            {
                f[i] = (i * 7 + k) as f64 + 0.5;
            }
        }
        let mut idx: Vec<u32> = picks.iter().map(|p| p.index(n) as u32).collect();
        idx.sort_unstable();
        let (mut bulk, mut single) = (Vec::new(), Vec::new());
        src.pack_halos(&idx, &mut bulk);
        for &i in &idx {
            src.pack_halo(i as usize, &mut single);
        }
        prop_assert_eq!(&bulk, &single);

        let mut a = Particles::new(3, fields);
        if switches {
            a.enable_alpha(0.1);
        }
        let mut b = a.clone();
        a.push_halos(&bulk);
        for chunk in single.chunks_exact(b.halo_words()) {
            b.push_halo(chunk);
        }
        prop_assert_eq!(a.len(), 3 + idx.len());
        prop_assert_eq!(&a.id, &b.id);
        for (fa, fb) in [(&a.x, &b.x), (&a.vz, &b.vz), (&a.h, &b.h), (&a.u, &b.u), (&a.dx, &b.dx),
                         (&a.du_prev, &b.du_prev), (&a.rho, &b.rho), (&a.omega, &b.omega), (&a.alpha, &b.alpha),
                         (&a.phi, &b.phi), (&a.iad[5], &b.iad[5])] {
            prop_assert_eq!(fa, fb);
        }
        prop_assert_eq!(a.nc.len(), b.nc.len());
        prop_assert!(a.check(FieldSet::default()).is_ok());
    }
}

proptest! {
    /// Under block time steps a particle and a halo carry the time bin and
    /// the derived fields inactive particles hold (density, pressure,
    /// sound speed, acceleration, du/dt, Omega, the IAD matrix), a halo
    /// still without the integrator's history; the domain's reorder keeps
    /// them with their particle instead of resetting them.
    #[test]
    fn block_steps_carry_the_held_fields(seed in any::<u64>(), n in 2usize..20) {
        let mut fields = FieldSet::default();
        fields.block = true;
        let mut p = Particles::new(n, fields);
        let v = |i: usize, k: usize| (seed.wrapping_mul((i * 31 + k + 1) as u64) % 1000) as f64 + 0.5;
        for i in 0..n {
            p.id[i] = 100 + i as u64;
            for (k, f) in [&mut p.x, &mut p.u, &mut p.dx, &mut p.du_prev, &mut p.bin, &mut p.rho, &mut p.p,
                           &mut p.c, &mut p.ax, &mut p.az, &mut p.du, &mut p.omega]
                .into_iter()
                .enumerate()
            {
                f[i] = v(i, k);
            }
            p.iad[0][i] = v(i, 20);
            p.iad[5][i] = v(i, 21);
        }
        let (mut full, mut halo) = (Vec::new(), Vec::new());
        p.pack(0, &mut full);
        p.pack_halo(0, &mut halo);
        prop_assert_eq!(p.packed_words() - p.halo_words(), 4);
        let mut q = p.clone();
        q.push_packed(&full);
        q.push_halo(&halo);
        prop_assert!(q.check(fields).is_ok());
        for f in [&q.x, &q.u, &q.bin, &q.rho, &q.p, &q.c, &q.ax, &q.az, &q.du, &q.omega, &q.iad[0], &q.iad[5]] {
            prop_assert_eq!(f[n], f[0]);
            prop_assert_eq!(f[n + 1], f[0]);
        }
        for f in [&q.dx, &q.du_prev] {
            prop_assert_eq!(f[n], f[0]);
            prop_assert_eq!(f[n + 1], 0.0);
        }
        // The domain's reorder: held fields move with their particle.
        let perm: Vec<u32> = (0..n as u32).rev().collect();
        let mut r = p.clone();
        r.reorder_carried(&perm, &mut Vec::new());
        for i in 0..n {
            let j = n - 1 - i;
            prop_assert_eq!(r.id[i], p.id[j]);
            prop_assert_eq!(r.rho[i], p.rho[j]);
            prop_assert_eq!(r.bin[i], p.bin[j]);
            prop_assert_eq!(r.iad[5][i], p.iad[5][j]);
        }
        // Without block steps the same reorder resets them.
        let mut g = Particles::new(n, FieldSet::default());
        g.rho.copy_from_slice(&p.rho);
        g.reorder_carried(&perm, &mut Vec::new());
        prop_assert!(g.rho.iter().all(|&x| x == 0.0));
        prop_assert!(g.bin.is_empty());
    }
}
