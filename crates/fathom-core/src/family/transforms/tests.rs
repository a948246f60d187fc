//! Tests of every domain operator: hand-computed images, the Lipschitz bound of the composed
//! distance (with the `k` scale applied as the tape does), symmetry of the folds, and the
//! f32x8 packet path. All iterate over `Transform::ALL`.

use super::*;
use crate::primitives::testkit::{Rng, baked, dist, lane, pack, param_sets, v3, wide_params};
use crate::real::F32x8;
use crate::registry::{Family, Quality};

fn apply(t: Transform, a: &[f64], p: [f64; 3]) -> ([f64; 3], f64) {
    let mut q = v3(p);
    let mut k = 1.0;
    t.apply::<f64>(&mut q, &mut k, a);
    ([q.x, q.y, q.z], k)
}

/// A named local-frame distance function.
type Shape = (&'static str, fn(V3<f64>) -> f64);

/// Unit sphere and unit box: the shapes the operators are composed with.
fn shapes() -> [Shape; 2] {
    [
        ("unit sphere", |p| p.length() - 1.0),
        ("unit box", |p| {
            let q = p.abs() - V3::splat(1.0);
            q.maxs(0.0).length() + q.max_elem().min(0.0)
        }),
    ]
}

/// Hand-computed images `(params, p, p', k')` (by geometry, not by running the code).
#[allow(clippy::type_complexity)]
fn hand_cases(name: &str) -> Option<Vec<(Vec<f64>, [f64; 3], [f64; 3], f64)>> {
    use std::f64::consts::FRAC_PI_2;
    Some(match name {
        "Translate" => vec![(vec![1.0, 2.0, 3.0], [1.0, 1.0, 1.0], [0.0, -1.0, -2.0], 1.0)],
        // Rotating by 90° about z maps x to y, so the world point (0, 1, 0) is the local x.
        "Rotate" => vec![(
            vec![0.0, 0.0, 1.0, 90.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            1.0,
        )],
        "Scale" => vec![(vec![2.0], [2.0, 4.0, -6.0], [1.0, 2.0, -3.0], 2.0)],
        "FoldAbs" => vec![(vec![], [-1.0, 3.0, -2.0], [1.0, 3.0, 2.0], 1.0)],
        "FoldMenger" => vec![(vec![], [-1.0, 3.0, -2.0], [3.0, 2.0, 1.0], 1.0)],
        "ScaleAbout" => vec![
            (
                vec![2.0, 1.0, 1.0, 1.0],
                [1.0, 1.0, 1.0],
                [1.0, 1.0, 1.0],
                0.5,
            ),
            (
                vec![3.0, 1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [-2.0, 3.0, 0.0],
                1.0 / 3.0,
            ),
        ],
        "Mirror" => vec![
            (
                vec![1.0, 0.0, 0.0],
                [-1.0, -2.0, -3.0],
                [1.0, -2.0, -3.0],
                1.0,
            ),
            (
                vec![0.0, -5.0, 1.0],
                [-1.0, -2.0, -3.0],
                [-1.0, 2.0, 3.0],
                1.0,
            ),
        ],
        "Repeat" => vec![(vec![2.0, 0.0, 2.0], [2.9, 5.0, -3.2], [0.9, 5.0, 0.8], 1.0)],
        "RepeatLimited" => vec![
            (
                vec![2.0, 2.0, 2.0, 1.0, 1.0, 1.0],
                [7.0, 0.5, -2.5],
                [5.0, 0.5, -0.5],
                1.0,
            ),
            (
                vec![2.0, 0.0, 2.0, 2.0, 2.0, 0.0],
                [3.5, 9.0, 3.5],
                [-0.5, 9.0, 3.5],
                1.0,
            ),
        ],
        // Quarter turn at y = 1: (x, z) = (1, 0) -> (0, 1).
        "Twist" => vec![(vec![FRAC_PI_2, 0.5], [1.0, 1.0, 0.0], [0.0, 1.0, 1.0], 0.5)],
        // Quarter turn at x = 1: (x, y) = (1, 0) -> (0, 1).
        "Bend" => vec![(
            vec![FRAC_PI_2, 0.25],
            [1.0, 0.0, 3.0],
            [0.0, 1.0, 3.0],
            0.25,
        )],
        "Elongate" => vec![
            (vec![0.5, 0.0, 0.0], [2.0, 1.0, 0.0], [1.5, 1.0, 0.0], 1.0),
            (vec![0.5, 0.0, 0.0], [0.2, 1.0, 0.0], [0.0, 1.0, 0.0], 1.0),
        ],
        "FoldPlane" => vec![
            (
                vec![2.0, 0.0, 0.0, 1.0],
                [0.0, 1.0, 2.0],
                [2.0, 1.0, 2.0],
                1.0,
            ),
            (
                vec![2.0, 0.0, 0.0, 1.0],
                [1.5, 1.0, 2.0],
                [1.5, 1.0, 2.0],
                1.0,
            ),
            (
                vec![0.0, 0.0, 0.0, 1.0],
                [-4.0, 1.0, 2.0],
                [-4.0, 1.0, 2.0],
                1.0,
            ),
        ],
        // x + y < 0: (x, y) -> (-y, -x) = (2, 1); then already sorted.
        "FoldOctahedral" => vec![(vec![], [-1.0, -2.0, 0.5], [2.0, 1.0, 0.5], 1.0)],
        // abs gives (1, 1, 0), already in the kept wedge: n1 . p = -1 / 2 and
        // n2 . p = (1 - phi) / (2 phi), both negative.
        "FoldIcosahedral" => vec![(vec![], [-1.0, 1.0, 0.0], [1.0, 1.0, 0.0], 1.0)],
        _ => return None,
    })
}

#[test]
fn every_transform_matches_hand_computed_images() {
    let mut missing = Vec::new();
    for &t in Transform::ALL {
        let def = t.def();
        let Some(cases) = hand_cases(def.name) else {
            missing.push(def.name);
            continue;
        };
        for (user, p, want, want_k) in cases {
            def.check(&user).unwrap();
            let (got, k) = apply(t, &baked(def, &user), p);
            assert!(
                dist(got, want) < 1e-12 && (k - want_k).abs() < 1e-12,
                "{} {user:?} at {p:?}: want {want:?} k={want_k}, got {got:?} k={k}",
                def.name
            );
        }
    }
    assert!(
        missing.is_empty(),
        "transforms without hand cases: {missing:?}"
    );
}

/// The region a `Safety` operator's doc promises the bound in, for its parameters.
fn safe_region(name: &str, user: &[f64]) -> Option<Box<dyn Fn([f64; 3]) -> bool>> {
    let rate_safety = || (user[0].abs(), user[1]);
    match name {
        "Twist" => {
            let (rate, safety) = rate_safety();
            let r = (1.0 / safety - safety) / rate;
            Some(Box::new(move |p| p[0].hypot(p[2]) <= r))
        }
        "Bend" => {
            let (rate, safety) = rate_safety();
            let r = (1.0 / safety - 1.0) / rate;
            Some(Box::new(move |p| p[0].hypot(p[1]) <= r))
        }
        _ => None,
    }
}

/// `d(p) = shape(T(p)) * k` is 1-Lipschitz for every operator and shape (Safety operators
/// inside their documented region), and the safety factor is not looser than needed by more
/// than the documented estimate (the region is tight enough to be violated just outside).
#[test]
fn every_transform_composed_with_a_shape_is_1_lipschitz() {
    let mut rng = Rng::new(21);
    for &t in Transform::ALL {
        let def = t.def();
        let mut sets = param_sets(def, &mut rng, 3);
        sets.extend((0..4).map(|_| wide_params(def, &mut rng)));
        for user in sets {
            let a = baked(def, &user);
            let region = safe_region(def.name, &user);
            if def.quality == Quality::Safety {
                assert!(
                    region.is_some(),
                    "{}: Safety operator without a region",
                    def.name
                );
            }
            let inside = |p: [f64; 3]| region.as_ref().is_none_or(|r| r(p));
            for (sname, g) in shapes() {
                let f = |p: [f64; 3]| {
                    let (q, k) = apply(t, &a, p);
                    g(v3(q)) * k
                };
                let mut n = 0;
                // A tiny safe region (fast twist, safety near 1) rejects most samples.
                let mut tries = 0;
                while n < 3000 && tries < 200_000 {
                    tries += 1;
                    let p = rng.cube(2.5);
                    let len = if n % 2 == 0 { 0.05 } else { 1.5 };
                    let r = rng.range(0.0, len);
                    let o = rng.dir(r);
                    let q = [p[0] + o[0], p[1] + o[1], p[2] + o[2]];
                    if !inside(p) || !inside(q) {
                        continue;
                    }
                    n += 1;
                    let (fp, fq) = (f(p), f(q));
                    let l = dist(p, q);
                    assert!(
                        (fp - fq).abs() <= l * (1.0 + 1e-6) + 1e-9,
                        "{} {user:?} on {sname}: f({p:?}) = {fp}, f({q:?}) = {fq}, |p - q| = {l}",
                        def.name
                    );
                }
            }
        }
    }
}

/// The folds make the composed field invariant under the mirrors of their symmetry group,
/// even for an asymmetric shape (distance to an off-centre point).
#[test]
fn folds_are_invariant_under_their_mirrors() {
    type M = fn([f64; 3]) -> [f64; 3];
    let coord: [M; 3] = [
        |p| [-p[0], p[1], p[2]],
        |p| [p[0], -p[1], p[2]],
        |p| [p[0], p[1], -p[2]],
    ];
    let swaps: [M; 3] = [
        |p| [p[1], p[0], p[2]],
        |p| [p[2], p[1], p[0]],
        |p| [p[0], p[2], p[1]],
    ];
    let sums: [M; 3] = [
        |p| [-p[1], -p[0], p[2]],
        |p| [-p[2], p[1], -p[0]],
        |p| [p[0], -p[2], -p[1]],
    ];
    fn reflect(p: [f64; 3], n: [f64; 3]) -> [f64; 3] {
        let t = p[0] * n[0] + p[1] * n[1] + p[2] * n[2];
        [0, 1, 2].map(|i| p[i] - 2.0 * t * n[i])
    }
    let ico: [M; 2] = [|p| reflect(p, ICO_N1), |p| reflect(p, ICO_N2)];
    let cases: Vec<(Transform, Vec<M>)> = vec![
        (Transform::FoldAbs, coord.to_vec()),
        (Transform::FoldMenger, [coord, swaps].concat()),
        (Transform::FoldOctahedral, [swaps, sums].concat()),
        (
            Transform::FoldIcosahedral,
            [coord.as_slice(), &ico].concat(),
        ),
    ];
    let c = [0.31, 0.17, 0.07];
    let mut rng = Rng::new(9);
    for (t, mirrors) in cases {
        let f = |p: [f64; 3]| dist(apply(t, &[], p).0, c);
        for _ in 0..2000 {
            let p = rng.cube(2.0);
            for (i, m) in mirrors.iter().enumerate() {
                let (a, b) = (f(p), f(m(p)));
                assert!(
                    (a - b).abs() < 1e-9,
                    "{t:?}: mirror {i} changes the field at {p:?}: {a} vs {b}"
                );
            }
        }
    }
}

/// The f32x8 packet path agrees with f64: compared through the composed distance to a unit
/// sphere and box (which is continuous across the cell walls of the repetitions, where the
/// f32 and f64 paths may pick different cells).
#[test]
fn every_transform_packet_path_matches_f64() {
    let mut rng = Rng::new(13);
    for &t in Transform::ALL {
        let def = t.def();
        for user in param_sets(def, &mut rng, 2) {
            let a = baked(def, &user);
            for _ in 0..200 {
                let ps: [[f64; 3]; 8] = std::array::from_fn(|_| rng.cube(2.5));
                let ps = ps.map(|p| p.map(|c| c as f32 as f64));
                let mut q8 = pack(&ps);
                let mut k8 = F32x8::splat(1.0);
                t.apply::<F32x8>(&mut q8, &mut k8, &a);
                let d8 = [q8.length() - F32x8::splat(1.0), {
                    let q = q8.abs() - V3::splat(F32x8::splat(1.0));
                    q.maxs(F32x8::splat(0.0)).length() + q.max_elem().min(F32x8::splat(0.0))
                }];
                for (i, p) in ps.iter().enumerate() {
                    let (q, k) = apply(t, &a, *p);
                    assert!(
                        (lane(k8, i) - k).abs() <= 1e-5 * k.abs(),
                        "{} {user:?}: k f64 {k}, f32x8 {}",
                        def.name,
                        lane(k8, i)
                    );
                    for ((_, g), d8) in shapes().iter().zip(d8) {
                        let want = g(v3(q));
                        let got = lane(d8, i);
                        assert!(
                            (got - want).abs() <= 1e-4 * want.abs().max(1.0),
                            "{} {user:?} at {p:?}: f64 {want}, f32x8 {got}",
                            def.name
                        );
                    }
                }
            }
        }
    }
}
