//! Combine operators: how a child's value joins its parent's, on the edge between them.
//!
//! `a` is the parent's accumulated value, `b` the child's. Hard combines keep the winner's
//! material; smooth combines (polynomial smooth min/max with blend radius `k`) blend materials.
//!
//! `scale` is the distance scale at the parent (see `transforms`), as the distance modifiers
//! get it: the blend radius is a length in the node's own frame, like its shapes' sizes, so a
//! tile folded by an IFS loop blends the same at every level. (Applied in world units, a
//! radius of 0.25 on the third level of a scale-3 loop was 27 of the tile's own units: the
//! smooth subtraction's rise of `k / 4` lifted the whole tile off the surface and the scene
//! vanished.)

use crate::value::Value;

const BIG: f64 = 1e6;

crate::declare_family! {
    /// A combine operator on the edge from a child to its parent.
    family Combine, noun "combine operator", table COMBINES;
    fn combine(a: Value<S>, b: Value<S>, scale: S) -> Value<S>;

    /// Union: the nearer of the two.
    Union [Bound] () => Value::select(a.d.le(b.d), a, b);

    /// Subtraction: the parent with the child carved out.
    Subtract [Bound] () => {
        let nb = Value { d: -b.d, ..b };
        Value::select(a.d.ge(nb.d), a, nb)
    };

    /// Intersection: where both are.
    Intersect [Bound] () => Value::select(a.d.ge(b.d), a, b);

    /// Smooth union with blend radius `k`.
    SmoothUnion [Bound] (k: Scalar = 0.25, [1e-6, BIG], soft [0.001, 2.0], "blend radius") => {
        let k = k * scale;
        let h = (S::splat(0.5) + S::splat(0.5) * (b.d - a.d) / k).clamp(S::zero(), S::one());
        let d = S::lerp(b.d, a.d, h) - k * h * (S::one() - h);
        Value::blend(d, a, b, h)
    };

    /// Smooth subtraction with blend radius `k`: the child carved out of the parent.
    SmoothSubtract [Bound] (k: Scalar = 0.25, [1e-6, BIG], soft [0.001, 2.0], "blend radius") => {
        let k = k * scale;
        let h = (S::splat(0.5) - S::splat(0.5) * (a.d + b.d) / k).clamp(S::zero(), S::one());
        let d = S::lerp(a.d, -b.d, h) + k * h * (S::one() - h);
        Value::blend(d, b, a, h)
    };

    /// Smooth intersection with blend radius `k`.
    SmoothIntersect [Bound] (k: Scalar = 0.25, [1e-6, BIG], soft [0.001, 2.0], "blend radius") => {
        let k = k * scale;
        let h = (S::splat(0.5) - S::splat(0.5) * (b.d - a.d) / k).clamp(S::zero(), S::one());
        let d = S::lerp(b.d, a.d, h) + k * h * (S::one() - h);
        Value::blend(d, a, b, h)
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitives::testkit::{Rng, baked, dist, param_sets, v3};
    use crate::real::{F32x8, Real};
    use crate::registry::Family;
    use crate::vec3::V3;

    fn sphere(p: [f64; 3]) -> f64 {
        (v3(p) - V3::new(0.6, 0.0, 0.0)).length() - 1.0
    }
    fn cube(p: [f64; 3]) -> f64 {
        let q = (v3(p) + V3::new(0.5, 0.2, 0.0)).abs() - V3::splat(0.8);
        q.maxs(0.0).length() + q.max_elem().min(0.0)
    }

    fn combined(c: Combine, a: &[f64], p: [f64; 3]) -> Value<f64> {
        c.combine::<f64>(
            Value::solid(sphere(p), 0.0, 1.0),
            Value::solid(cube(p), 1.0, 2.0),
            1.0,
            a,
        )
    }

    /// Blending in a frame scaled by `s` (the distances arriving already multiplied by `s`)
    /// gives `s` times the blend of the unscaled frame: the radius is a length of the node's
    /// own frame, so a tile inside an IFS loop blends alike at every level.
    #[test]
    fn a_smooth_combine_blends_in_the_node_s_own_frame() {
        let v = |d: f64, id: f64| Value::solid(d, id, 0.0);
        let k = [0.25];
        for c in [
            Combine::SmoothUnion,
            Combine::SmoothSubtract,
            Combine::SmoothIntersect,
        ] {
            for (da, db) in [(0.1, 0.05), (-0.2, 0.1), (0.3, -0.1)] {
                let unscaled = c.combine::<f64>(v(da, 0.0), v(db, 1.0), 1.0, &k);
                let s = 1.0 / 27.0;
                let scaled = c.combine::<f64>(v(da * s, 0.0), v(db * s, 1.0), s, &k);
                assert!(
                    (scaled.d - unscaled.d * s).abs() < 1e-12,
                    "{}: {} vs {}",
                    c.def().name,
                    scaled.d,
                    unscaled.d * s
                );
                assert!((scaled.blend - unscaled.blend).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn every_combine_is_1_lipschitz() {
        let mut rng = Rng::new(41);
        for &c in Combine::ALL {
            let def = c.def();
            for user in param_sets(def, &mut rng, 3) {
                let a = baked(def, &user);
                for i in 0..4000 {
                    let p = rng.cube(2.5);
                    let r = rng.range(0.0, if i % 2 == 0 { 0.05 } else { 1.5 });
                    let o = rng.dir(r);
                    let q = [p[0] + o[0], p[1] + o[1], p[2] + o[2]];
                    let (fp, fq) = (combined(c, &a, p).d, combined(c, &a, q).d);
                    assert!(
                        (fp - fq).abs() <= dist(p, q) * (1.0 + 1e-6) + 1e-9,
                        "{} {user:?}: {fp} vs {fq} over {}",
                        def.name,
                        dist(p, q)
                    );
                }
            }
        }
    }

    #[test]
    fn combines_hand_values() {
        let v = |d: f64, id: f64| Value::solid(d, id, 0.0);
        let none: [f64; 0] = [];
        let u = Combine::Union.combine::<f64>(v(1.0, 0.0), v(0.5, 1.0), 1.0, &none);
        assert_eq!((u.d, u.id), (0.5, 1.0));
        let s = Combine::Subtract.combine::<f64>(v(-1.0, 0.0), v(-0.3, 1.0), 1.0, &none);
        assert_eq!((s.d, s.id), (0.3, 1.0));
        let i = Combine::Intersect.combine::<f64>(v(-1.0, 0.0), v(-0.3, 1.0), 1.0, &none);
        assert_eq!((i.d, i.id), (-0.3, 1.0));
        // Equal inputs: the smooth union dips by k/4, the smooth intersection rises by k/4,
        // with an even blend.
        let k = [0.4];
        let su = Combine::SmoothUnion.combine::<f64>(v(1.0, 0.0), v(1.0, 1.0), 1.0, &k);
        assert!((su.d - 0.9).abs() < 1e-12 && (su.blend - 0.5).abs() < 1e-12);
        let si = Combine::SmoothIntersect.combine::<f64>(v(1.0, 0.0), v(1.0, 1.0), 1.0, &k);
        assert!((si.d - 1.1).abs() < 1e-12);
        // a = 1, b = -1: a - (-b) = 0, so the subtraction blends evenly and rises by k/4.
        let ss = Combine::SmoothSubtract.combine::<f64>(v(1.0, 0.0), v(-1.0, 1.0), 1.0, &k);
        assert!((ss.d - 1.1).abs() < 1e-12);
        // Far apart, the smooth ones equal the hard ones.
        let su = Combine::SmoothUnion.combine::<f64>(v(3.0, 0.0), v(1.0, 1.0), 1.0, &k);
        assert_eq!((su.d, su.id, su.blend), (1.0, 1.0, 0.0));
    }

    #[test]
    fn every_combine_packet_path_matches_f64() {
        let mut rng = Rng::new(43);
        for &c in Combine::ALL {
            let def = c.def();
            let a = baked(def, &def.defaults());
            let da: Vec<f64> = (0..8).map(|_| rng.range(-2.0, 2.0) as f32 as f64).collect();
            let db: Vec<f64> = (0..8).map(|_| rng.range(-2.0, 2.0) as f32 as f64).collect();
            let mk = |d: &[f64], id: f64| {
                Value::solid(
                    F32x8::from_lanes(d),
                    <F32x8 as Real>::splat(id),
                    <F32x8 as Real>::splat(id),
                )
            };
            let got =
                c.combine::<F32x8>(mk(&da, 0.0), mk(&db, 1.0), <F32x8 as Real>::splat(0.5), &a);
            for i in 0..8 {
                let want = c.combine::<f64>(
                    Value::solid(da[i], 0.0, 0.0),
                    Value::solid(db[i], 1.0, 1.0),
                    0.5,
                    &a,
                );
                let l = |x: F32x8| <F32x8 as Real>::lane(x, i);
                assert!((l(got.d) - want.d).abs() < 1e-5, "{}: d", def.name);
                assert!(
                    (l(got.blend) - want.blend).abs() < 1e-5,
                    "{}: blend",
                    def.name
                );
                if want.blend < 0.49 {
                    assert_eq!(l(got.id), want.id, "{}: id", def.name);
                }
            }
        }
    }
}
