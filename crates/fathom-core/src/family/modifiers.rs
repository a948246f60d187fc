//! Distance modifiers: operators on a node's list that act on the distance after the node's
//! subtree is evaluated (rounding, onion shells), rather than on the point.
//!
//! `k` is the distance scale at the node (see `transforms`), so lengths given in the node's
//! frame stay in that frame.

const BIG: f64 = 1e6;

crate::declare_family! {
    /// An operator on the distance value.
    family Modifier, noun "distance modifier", table MODIFIERS;
    fn modify(d: S, k: S) -> S;

    /// Rounds edges by `radius` (grows the shape by that much).
    Round [Bound] (radius: Scalar = 0.1, [0.0, BIG], soft [0.0, 1.0], "rounding radius") => d - radius * k;

    /// Turns the solid into a shell of the given thickness around its surface.
    Onion [Bound] (thickness: Scalar = 0.05, [0.0, BIG], soft [0.0, 1.0], "shell half-thickness")
        => d.abs() - thickness * k;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitives::testkit::{Rng, baked, dist, param_sets, v3};
    use crate::real::{F32x8, Real};
    use crate::registry::Family;

    /// A world-space field: a box of half-extents (1, 0.5, 0.75) seen through a scale by `k`.
    fn field(p: [f64; 3], k: f64) -> f64 {
        let q = (v3(p) / k).abs() - crate::vec3::V3::new(1.0, 0.5, 0.75);
        (q.maxs(0.0).length() + q.max_elem().min(0.0)) * k
    }

    #[test]
    fn every_modifier_keeps_the_field_1_lipschitz() {
        let mut rng = Rng::new(31);
        for &m in Modifier::ALL {
            let def = m.def();
            for user in param_sets(def, &mut rng, 3) {
                let a = baked(def, &user);
                for k in [1.0, 0.37, 2.5] {
                    for i in 0..2000 {
                        let p = rng.cube(3.0);
                        let r = rng.range(0.0, if i % 2 == 0 { 0.05 } else { 1.5 });
                        let o = rng.dir(r);
                        let q = [p[0] + o[0], p[1] + o[1], p[2] + o[2]];
                        let fp = m.modify::<f64>(field(p, k), k, &a);
                        let fq = m.modify::<f64>(field(q, k), k, &a);
                        assert!(
                            (fp - fq).abs() <= dist(p, q) * (1.0 + 1e-6) + 1e-9,
                            "{} {user:?} k={k}: {fp} vs {fq} over {}",
                            def.name,
                            dist(p, q)
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn modifiers_hand_values_and_packet_path() {
        // Round grows by radius * k; Onion makes a shell of half-thickness * k.
        let round = baked(Modifier::Round.def(), &[0.1]);
        assert!((Modifier::Round.modify::<f64>(0.5, 2.0, &round) - 0.3).abs() < 1e-12);
        let onion = baked(Modifier::Onion.def(), &[0.05]);
        assert!((Modifier::Onion.modify::<f64>(-0.5, 2.0, &onion) - 0.4).abs() < 1e-12);
        let mut rng = Rng::new(2);
        for &m in Modifier::ALL {
            let def = m.def();
            let a = baked(def, &def.defaults());
            let ds: Vec<f64> = (0..8).map(|_| rng.range(-3.0, 3.0)).collect();
            let got = m.modify::<F32x8>(F32x8::from_lanes(&ds), F32x8::splat(1.5), &a);
            for (i, &d) in ds.iter().enumerate() {
                let want = m.modify::<f64>(d as f32 as f64, 1.5, &a);
                assert!(
                    (<F32x8 as Real>::lane(got, i) - want).abs() < 1e-5,
                    "{}",
                    def.name
                );
            }
        }
    }
}
