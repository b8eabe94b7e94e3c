//! Invariants of the particle container's growth.

use proptest::prelude::*;
use sph_core::{FieldSet, Particles};
use sph_domain::ParticleFields;

proptest! {
    /// `reserve` keeps every value, makes room for the arrivals and does
    /// not double the arrays as repeated pushes would.
    #[test]
    fn reserve_keeps_values_and_grows_to_need(n in 1usize..300, extra in 0usize..600) {
        let mut p = Particles::new(n, FieldSet { grad_h: true, iad: true, ..FieldSet::default() });
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
