//! The softened point-point (P2P) interaction, written once for the tree's
//! leaf kernel ([`traversal`](crate::traversal)), the remote particles of
//! the distributed evaluation ([`distributed`](crate::distributed)) and
//! the direct sum ([`direct`](crate::direct)).

/// The field, without the factor `G`, of a source of mass `m` at separation
/// `d = x_source - x_target`, softened within `eps` (the pair's softening
/// length; `SOFT = false` means none and ignores `eps`):
///
/// ```text
/// r_eff^2 = max(r^2, eps^2)
/// a       =  m d / r_eff^3
/// phi     = -m / r_eff * (3/2 - r^2 / (2 r_eff^2))
/// ```
///
/// (the potential of a uniform sphere of radius `eps` inside it, whose
/// gradient is the softened force, and `-m / r` outside). Returns
/// `(a, phi)`; both are zero when `live` is false (the self pair) or
/// `r_eff = 0` (coincident particles without softening), so a caller may
/// add them unconditionally: an accumulator that starts at `+0.0` keeps
/// its bits when a zero is added.
///
/// The operations and their order are part of the contract: every caller
/// gets the same bits for the same pair, and the tree's results stay
/// reproducible across versions.
#[inline(always)]
pub(crate) fn softened_p2p<const SOFT: bool>(
    d: [f64; 3],
    m: f64,
    eps: f64,
    live: bool,
) -> ([f64; 3], f64) {
    let r2_true = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let r2 = if SOFT {
        r2_true.max(eps * eps)
    } else {
        r2_true
    };
    let inv_r = if r2 > 0.0 && live {
        1.0 / r2.sqrt()
    } else {
        0.0
    };
    let mr = m * inv_r;
    let inv_r2 = inv_r * inv_r;
    let mr3 = mr * inv_r2;
    // Inside the softening length the potential of a uniform sphere, whose
    // gradient is the softened force (1 outside).
    let phi = -(mr * (1.5 - 0.5 * r2_true * inv_r2));
    ([mr3 * d[0], mr3 * d[1], mr3 * d[2]], phi)
}

#[cfg(test)]
mod tests {
    use super::softened_p2p;

    #[test]
    fn outside_the_softening_is_newton() {
        // r = 2, m = 8: a = 8 d / 8 = d, phi = -8 / 2.
        let (a, phi) = softened_p2p::<true>([0.0, 2.0, 0.0], 8.0, 1.0, true);
        assert_eq!(a, [0.0, 2.0, 0.0]);
        assert_eq!(phi, -4.0);
        assert_eq!(
            softened_p2p::<false>([0.0, 2.0, 0.0], 8.0, 123.0, true),
            (a, phi)
        );
    }

    #[test]
    fn inside_the_softening_is_a_uniform_sphere() {
        // r = 1, eps = 2, m = 8: a = 8 d / 8, phi = -8 / 2 * (3/2 - 1/8).
        let (a, phi) = softened_p2p::<true>([-1.0, 0.0, 0.0], 8.0, 2.0, true);
        assert_eq!(a, [-1.0, 0.0, 0.0]);
        assert_eq!(phi, -5.5);
        // At the centre: no force, the sphere's central potential -3m/(2 eps).
        assert_eq!(
            softened_p2p::<true>([0.0; 3], 8.0, 2.0, true),
            ([0.0; 3], -6.0)
        );
    }

    #[test]
    fn self_pairs_and_unsoftened_coincident_pairs_add_nothing() {
        for (d, eps, live) in [([1.0, 0.0, 0.0], 0.5, false), ([0.0; 3], 0.0, true)] {
            let (a, phi) = softened_p2p::<true>(d, 3.0, eps, live);
            let mut acc = [0.0f64; 4];
            for (s, v) in acc.iter_mut().zip([a[0], a[1], a[2], phi]) {
                *s += v;
            }
            assert!(
                acc.iter().all(|v| v.to_bits() == 0.0f64.to_bits()),
                "{acc:?}"
            );
        }
    }
}
