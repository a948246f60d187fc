//! Tests of every primitive against hand-computed values, a brute-force surface sampling, the
//! eikonal property, the Lipschitz bound, and the f32x8 packet path. All iterate over
//! `Primitive::ALL`, so a new primitive cannot be added untested.

use super::testkit::{Rng, baked, dist, lane, pack, param_sets, v3, wide_params};
use super::*;
use crate::real::F32x8;
use crate::registry::{Family, Quality};

fn eval(k: Primitive, a: &[f64], p: [f64; 3]) -> f64 {
    k.distance::<f64>(v3(p), a)
}

/// Hand-computed distances at the default parameters (by geometry, not by running the code).
fn hand_values(name: &str) -> Option<Vec<([f64; 3], f64)>> {
    let s2 = 2f64.sqrt();
    let s3 = 3f64.sqrt();
    Some(match name {
        "Empty" => vec![([0.0, 0.0, 0.0], 1e20), ([5.0, -3.0, 2.0], 1e20)],
        "Sphere" => vec![
            ([2.0, 0.0, 0.0], 1.0),
            ([0.0, 0.0, 0.0], -1.0),
            ([0.0, 0.5, 0.0], -0.5),
        ],
        "Box" => vec![
            ([2.0, 0.0, 0.0], 1.0),
            ([2.0, 2.0, 0.0], s2),
            ([2.0, 2.0, 2.0], s3),
            ([0.0, 0.0, 0.0], -1.0),
        ],
        "RoundBox" => vec![
            ([2.0, 0.0, 0.0], 1.0),
            ([0.0, 0.0, 0.0], -1.0),
            ([2.0, 2.0, 2.0], 1.1 * s3 - 0.1),
        ],
        // Bars 0.1 wide: the nearest bar point to (2,0,0) is (1, 0, 0.9).
        "BoxFrame" => vec![
            ([2.0, 0.0, 0.0], 1.81f64.sqrt()),
            ([0.0, 0.0, 0.0], 0.9 * s2),
            ([0.95, 0.95, 0.0], -0.05),
        ],
        "Torus" => vec![
            ([2.0, 0.0, 0.0], 0.75),
            ([1.0, 0.0, 0.0], -0.25),
            ([0.0, 0.0, 0.0], 0.75),
            ([0.0, 1.0, 0.0], s2 - 0.25),
        ],
        // Arc ±120° from +y, ends at (±sin 120°, cos 120°) = (±0.866, -0.5).
        "CappedTorus" => vec![
            ([0.0, 1.0, 0.0], -0.2),
            ([0.0, -1.0, 0.0], 0.8),
            ([0.0, 0.0, 0.0], 0.8),
            ([0.0, 0.0, 1.0], s2 - 0.2),
        ],
        "Link" => vec![
            ([0.5, 0.0, 0.0], -0.15),
            ([0.0, 1.0, 0.0], -0.15),
            ([0.0, 0.0, 0.0], 0.35),
            ([0.5, 0.0, 1.0], 0.85),
        ],
        "Cylinder" => vec![([3.0, 5.0, 4.0], 4.0), ([0.0, 7.0, 0.0], -1.0)],
        "CappedCylinder" => vec![
            ([0.0, 3.0, 0.0], 2.0),
            ([3.0, 0.0, 0.0], 2.0),
            ([2.0, 2.0, 0.0], s2),
            ([0.5, 0.8, 0.0], -0.2),
        ],
        "RoundedCylinder" => vec![
            ([0.0, 3.0, 0.0], 2.0),
            ([2.0, 2.0, 0.0], 1.1 * s2 - 0.1),
            ([0.0, 0.0, 0.0], -1.0),
        ],
        // Side line from (1, -1) to (0, 1) in (rho, y): distance from the origin 1/sqrt(5).
        "Cone" => vec![
            ([0.0, 2.0, 0.0], 1.0),
            ([0.0, -2.0, 0.0], 1.0),
            ([0.0, 0.0, 0.0], -1.0 / 5f64.sqrt()),
        ],
        // Side from (1, -1) to (0.5, 1): normal (2, 0.5) / sqrt(4.25).
        "CappedCone" => vec![
            ([0.0, 2.0, 0.0], 1.0),
            ([0.0, -3.0, 0.0], 2.0),
            ([0.0, 0.0, 0.0], -1.5 / 4.25f64.sqrt()),
        ],
        "RoundCone" => vec![
            ([0.0, -2.0, 0.0], 1.0),
            ([0.0, 2.0, 0.0], 1.25),
            ([0.5, -0.5, 0.0], 0.0),
            ([0.0, 0.0, 0.0], -0.375),
        ],
        "Plane" => vec![([1.0, 2.0, 3.0], 2.0), ([0.0, -0.5, 9.0], -0.5)],
        // Inradius 1 (flat sides at z = ±1), circumradius 2/sqrt(3) along x.
        "HexPrism" => vec![
            ([0.0, 0.0, 2.0], 1.0),
            ([0.0, 3.0, 0.0], 2.0),
            ([0.0, 0.0, 0.0], -1.0),
            ([2.0, 0.0, 0.0], 2.0 - 2.0 / s3),
        ],
        // Side 2: inradius 1/sqrt(3), vertex at z = 2/sqrt(3).
        "TriPrism" => vec![
            ([0.0, 0.0, -2.0], 2.0 - 1.0 / s3),
            ([0.0, 0.0, 2.0], 2.0 - 2.0 / s3),
            ([0.0, 0.0, 0.0], -1.0 / s3),
            ([0.0, 3.0, 0.0], 2.0),
        ],
        "Capsule" => vec![
            ([0.0, 2.0, 0.0], 1.0),
            ([2.0, 0.0, 0.0], 1.5),
            ([0.0, 0.0, 0.0], -0.5),
        ],
        "CapsuleSegment" => vec![([2.0, 0.0, 0.0], 1.25), ([0.0, 1.0, 0.0], 0.75)],
        "SolidAngle" => vec![
            ([0.0, 0.5, 0.0], -0.25),
            ([0.0, 2.0, 0.0], 1.0),
            ([0.0, -1.0, 0.0], 1.0),
            ([1.0, 0.0, 0.0], 0.75f64.sqrt()),
        ],
        // Keeps y >= 0.5; the rim is the circle (rho, y) = (sqrt(0.75), 0.5).
        "CutSphere" => vec![
            ([0.0, -2.0, 0.0], 2.5),
            ([0.0, 2.0, 0.0], 1.0),
            ([0.0, 0.75, 0.0], -0.25),
            (
                [2.0, 0.0, 0.0],
                ((2.0 - 0.75f64.sqrt()).powi(2) + 0.25).sqrt(),
            ),
        ],
        "CutHollowSphere" => vec![
            ([0.0, 2.0, 0.0], 3f64.sqrt() - 0.05),
            ([0.0, -2.0, 0.0], 0.95),
            ([0.0, 0.0, 0.0], 0.95),
        ],
        // Rim at (a, b) = (0.75, sqrt(0.4375)) in (x, |yz|).
        "DeathStar" => vec![
            ([-2.0, 0.0, 0.0], 1.0),
            ([0.0, 0.0, 0.0], -0.4),
            ([2.0, 0.0, 0.0], s2),
        ],
        // max((|p / r| - 1) * 0.5, |p| - 1).
        "Ellipsoid" => vec![
            ([2.0, 0.0, 0.0], 1.0),
            ([0.0, 1.0, 0.0], 0.5),
            ([0.0, 0.0, 1.5], 0.5),
            ([0.0, 0.0, 0.0], -0.5),
        ],
        "Rhombus" => vec![
            ([0.0, 2.0, 0.0], 1.9),
            ([3.0, 0.0, 0.0], 1.95),
            ([0.0, 0.0, 0.0], -0.1),
        ],
        "Octahedron" => vec![
            ([0.0, 0.0, 0.0], -1.0 / s3),
            ([2.0, 0.0, 0.0], 1.0),
            ([1.0, 1.0, 1.0], 2.0 / s3),
        ],
        "OctahedronBound" => vec![
            ([0.0, 0.0, 0.0], -1.0 / s3),
            ([2.0, 0.0, 0.0], 1.0 / s3),
            ([1.0, 1.0, 1.0], 2.0 / s3),
        ],
        // Face through (0.5, -0.5) and (0, 0.5) in the xy slice: normal (1, 0.5)/sqrt(1.25).
        "Pyramid" => vec![
            ([0.0, 1.5, 0.0], 1.0),
            ([0.0, -1.5, 0.0], 1.0),
            ([0.0, 0.0, 0.0], -0.25 / 1.25f64.sqrt()),
            ([0.0, -0.7, 0.0], 0.2),
        ],
        "Triangle" => vec![([0.0, 0.0, 1.0], 1.0), ([0.0, 2.0, 0.0], 1.0)],
        "Quad" => vec![
            ([0.0, 1.0, 0.0], 1.0),
            ([2.0, 0.0, 0.0], 1.0),
            ([2.0, 0.0, 2.0], s2),
        ],
        "Vesica" => vec![
            ([0.0, 2.0, 0.0], 1.0),
            ([1.0, 0.0, 0.0], 0.5),
            ([0.0, 0.0, 0.0], -0.5),
        ],
        "InfiniteCone" => vec![
            ([0.0, 1.0, 0.0], -0.5),
            ([0.0, -1.0, 0.0], 1.0),
            ([1.0, 0.0, 0.0], 0.75f64.sqrt()),
        ],
        "Slab" => vec![([0.0, 2.0, 0.0], 1.5), ([5.0, 0.0, 0.0], -0.5)],
        _ => return None,
    })
}

#[test]
fn every_primitive_matches_hand_computed_values() {
    let mut missing = Vec::new();
    for &k in Primitive::ALL {
        let def = k.def();
        let Some(cases) = hand_values(def.name) else {
            missing.push(def.name);
            continue;
        };
        let a = baked(def, &def.defaults());
        for (p, want) in cases {
            let got = eval(k, &a, p);
            assert!(
                (got - want).abs() <= 1e-9 * (1.0 + want.abs()),
                "{} at {p:?}: want {want}, got {got}",
                def.name
            );
        }
    }
    assert!(
        missing.is_empty(),
        "primitives without hand values: {missing:?}"
    );
}

/// Shapes whose distance is unsigned (no inside, so no sign change to find): their surface is
/// sampled directly from the parameters instead.
fn unsigned_surface(name: &str, user: &[f64], step: f64) -> Option<Vec<[f64; 3]>> {
    let corner = |i: usize| [user[3 * i], user[3 * i + 1], user[3 * i + 2]];
    let tris = match name {
        "Triangle" => vec![[corner(0), corner(1), corner(2)]],
        "Quad" => vec![
            [corner(0), corner(1), corner(2)],
            [corner(0), corner(2), corner(3)],
        ],
        _ => return None,
    };
    let mut out = Vec::new();
    for [a, b, c] in tris {
        let n = ((dist(a, b).max(dist(b, c)).max(dist(c, a))) / step).ceil() as usize + 1;
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let w = 1.0 - u - v;
                out.push([0, 1, 2].map(|t| a[t] * w + b[t] * u + c[t] * v));
            }
        }
    }
    Some(out)
}

/// Half-size of the sampling box and grid resolution of the brute-force reference.
const BOX: f64 = 2.4;
const GRID: usize = 81;

/// Surface samples: zero crossings of `f` along the edges of a grid over [-BOX, BOX]^3, placed
/// by linear interpolation.
fn zero_set(f: &dyn Fn([f64; 3]) -> f64) -> Vec<[f64; 3]> {
    let h = 2.0 * BOX / (GRID - 1) as f64;
    let at = |i: usize| -BOX + h * i as f64;
    let mut vals = vec![0.0; GRID * GRID * GRID];
    let idx = |i: usize, j: usize, k: usize| (i * GRID + j) * GRID + k;
    for i in 0..GRID {
        for j in 0..GRID {
            for k in 0..GRID {
                vals[idx(i, j, k)] = f([at(i), at(j), at(k)]);
            }
        }
    }
    let mut out = Vec::new();
    for i in 0..GRID {
        for j in 0..GRID {
            for k in 0..GRID {
                let v0 = vals[idx(i, j, k)];
                for (di, dj, dk) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                    let (i1, j1, k1) = (i + di, j + dj, k + dk);
                    if i1 >= GRID || j1 >= GRID || k1 >= GRID {
                        continue;
                    }
                    let v1 = vals[idx(i1, j1, k1)];
                    if (di, v0.abs() < 1.5 * h) == (1, true) {
                        // Also project near-surface nodes onto the zero set (Newton steps
                        // along the gradient), which fills in sharp edges and corners the
                        // grid crossings miss.
                        let mut q = [at(i), at(j), at(k)];
                        for _ in 0..6 {
                            let g = grad(f, q, 1e-7);
                            let g2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
                            if g2 < 1e-12 {
                                break;
                            }
                            let fq = f(q);
                            q = [0, 1, 2].map(|c| q[c] - fq * g[c] / g2);
                        }
                        if f(q).abs() < 1e-7 {
                            out.push(q);
                        }
                    }
                    if (v0 < 0.0) != (v1 < 0.0) {
                        let t = v0 / (v0 - v1);
                        let p0 = [at(i), at(j), at(k)];
                        let p1 = [at(i1), at(j1), at(k1)];
                        out.push([0, 1, 2].map(|c| p0[c] + (p1[c] - p0[c]) * t));
                    }
                }
            }
        }
    }
    out
}

/// Compares each primitive (defaults and two random parameter sets) with the distance to a
/// dense sampling of its zero set: `Exact` entries must match within the sampling error,
/// `Bound` entries must not exceed it.
#[test]
fn every_primitive_agrees_with_brute_force_surface_distance() {
    let h = 2.0 * BOX / (GRID - 1) as f64;
    let tol = h;
    let mut rng = Rng::new(7);
    let mut failures = Vec::new();
    for &k in Primitive::ALL {
        let def = k.def();
        if def.name == "Empty" {
            // No surface at all: covered by the hand values (1e20 everywhere).
            continue;
        }
        let mut sets = param_sets(def, &mut rng, 2);
        sets.extend((0..2).map(|_| wide_params(def, &mut rng)));
        for user in sets {
            let a = baked(def, &user);
            let f = |p: [f64; 3]| eval(k, &a, p);
            let samples =
                unsigned_surface(def.name, &user, h * 0.5).unwrap_or_else(|| zero_set(&f));
            assert!(
                !samples.is_empty(),
                "{} {user:?}: no surface found",
                def.name
            );
            // Only shapes that reach the walls of the sampled box (infinite ones) can have
            // their nearest point outside it.
            let clipped = samples
                .iter()
                .any(|s| s.iter().any(|c| c.abs() > BOX - 2.0 * h));
            let mut checked = 0;
            for _ in 0..80 {
                let p = rng.cube(1.6);
                let reference = samples
                    .iter()
                    .map(|&s| dist(p, s))
                    .fold(f64::INFINITY, f64::min);
                let to_wall = BOX - p.iter().fold(0.0f64, |m, c| m.max(c.abs()));
                if clipped && reference >= to_wall - h {
                    continue; // the nearest surface point may lie outside the sampled box
                }
                checked += 1;
                let d = f(p);
                let bad = match def.quality {
                    Quality::Exact => (d.abs() - reference).abs() > tol,
                    _ => d.abs() > reference + tol,
                };
                if bad {
                    failures.push(format!(
                        "{} ({}) params {user:?} at {p:?}: f = {d}, brute force = {reference}",
                        def.name, def.quality
                    ));
                    checked = usize::MAX;
                    break;
                }
            }
            assert!(
                checked >= 20,
                "{}: only {checked} points checked ({} samples)",
                def.name,
                samples.len()
            );
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn grad(f: &dyn Fn([f64; 3]) -> f64, p: [f64; 3], e: f64) -> [f64; 3] {
    let mut g = [0.0; 3];
    for (i, gi) in g.iter_mut().enumerate() {
        let (mut a, mut b) = (p, p);
        a[i] += e;
        b[i] -= e;
        *gi = (f(a) - f(b)) / (2.0 * e);
    }
    g
}

/// For exact primitives: `|grad f| = 1` away from the medial axis, and stepping `-f grad f`
/// lands on the surface.
#[test]
fn exact_primitives_are_eikonal_and_project_onto_the_surface() {
    let mut rng = Rng::new(11);
    for &k in Primitive::ALL {
        let def = k.def();
        if def.quality != Quality::Exact || def.name == "Empty" {
            continue;
        }
        let mut sets = param_sets(def, &mut rng, 6);
        sets.extend((0..6).map(|_| wide_params(def, &mut rng)));
        for user in sets {
            let a = baked(def, &user);
            let f = |p: [f64; 3]| eval(k, &a, p);
            let mut smooth = 0;
            for _ in 0..200 {
                let p = rng.cube(2.0);
                let g = grad(&f, p, 1e-6);
                // Skip points near a crease (the medial axis), where the gradient jumps.
                let q = {
                    let o = rng.dir(1e-3);
                    [p[0] + o[0], p[1] + o[1], p[2] + o[2]]
                };
                let gq = grad(&f, q, 1e-6);
                if dist(g, gq) > 0.05 {
                    continue;
                }
                smooth += 1;
                let len = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
                assert!(
                    (len - 1.0).abs() < 1e-4,
                    "{} {user:?} at {p:?}: |grad| = {len}",
                    def.name
                );
                let d = f(p);
                let proj = [0, 1, 2].map(|i| p[i] - d * g[i]);
                let dp = f(proj);
                assert!(
                    dp.abs() < 1e-5 * (1.0 + d.abs()),
                    "{} {user:?}: projecting {p:?} (f = {d}) gives f = {dp}",
                    def.name
                );
            }
            assert!(smooth >= 100, "{}: only {smooth} smooth points", def.name);
        }
    }
}

/// Every primitive is 1-Lipschitz: `|f(a) - f(b)| <= |a - b|`.
#[test]
fn every_primitive_is_1_lipschitz() {
    let mut rng = Rng::new(3);
    for &k in Primitive::ALL {
        let def = k.def();
        for user in param_sets(def, &mut rng, 3) {
            let a = baked(def, &user);
            for i in 0..3000 {
                let p = rng.cube(2.5);
                let len = if i % 2 == 0 { 0.05 } else { 1.5 };
                let r = rng.range(0.0, len);
                let o = rng.dir(r);
                let q = [p[0] + o[0], p[1] + o[1], p[2] + o[2]];
                let (fp, fq) = (eval(k, &a, p), eval(k, &a, q));
                let l = dist(p, q);
                assert!(
                    (fp - fq).abs() <= l * (1.0 + 1e-6) + 1e-9,
                    "{} {user:?}: f({p:?}) = {fp}, f({q:?}) = {fq}, |p - q| = {l}",
                    def.name
                );
            }
        }
    }
}

/// The f32x8 packet path computes the same distances as the f64 path.
#[test]
fn every_primitive_packet_path_matches_f64() {
    let mut rng = Rng::new(5);
    for &k in Primitive::ALL {
        let def = k.def();
        let mut sets = param_sets(def, &mut rng, 2);
        sets.extend((0..4).map(|_| wide_params(def, &mut rng)));
        for user in sets {
            let a = baked(def, &user);
            for _ in 0..200 {
                let ps: [[f64; 3]; 8] = std::array::from_fn(|_| rng.cube(2.5));
                // Round the points to f32 so both paths see the same inputs.
                let ps = ps.map(|p| p.map(|c| c as f32 as f64));
                let d8 = k.distance::<F32x8>(pack(&ps), &a);
                for (i, p) in ps.iter().enumerate() {
                    let want = eval(k, &a, *p);
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

/// Degenerate parameters (each parameter in turn, and all of them, at 0 or its smallest allowed
/// value) give finite, 1-Lipschitz fields on both paths: no NaN from a zero radius or
/// collinear corners.
#[test]
fn degenerate_parameters_give_finite_lipschitz_fields() {
    let mut rng = Rng::new(17);
    for &k in Primitive::ALL {
        let def = k.def();
        let defaults = def.defaults();
        let lowest: Vec<f64> = def
            .params
            .iter()
            .flat_map(|s| s.default_values().iter().map(move |_| s.min.max(0.0)))
            .collect();
        let mut sets = vec![lowest.clone()];
        for i in 0..defaults.len() {
            let mut v = defaults.clone();
            v[i] = lowest[i];
            sets.push(v);
        }
        for user in sets {
            def.check(&user).unwrap();
            let a = baked(def, &user);
            for _ in 0..300 {
                let p = rng.cube(2.0);
                let o = rng.dir(0.1);
                let q = [p[0] + o[0], p[1] + o[1], p[2] + o[2]];
                let (fp, fq) = (eval(k, &a, p), eval(k, &a, q));
                assert!(fp.is_finite(), "{} {user:?} at {p:?}: {fp}", def.name);
                assert!(
                    (fp - fq).abs() <= 0.1 * (1.0 + 1e-6) + 1e-9,
                    "{} {user:?}: f({p:?}) = {fp}, f({q:?}) = {fq}",
                    def.name
                );
                let ps: [[f64; 3]; 8] = std::array::from_fn(|_| rng.cube(2.0));
                let d8 = k.distance::<F32x8>(pack(&ps), &a);
                for (i, p) in ps.iter().enumerate() {
                    assert!(
                        lane(d8, i).is_finite(),
                        "{} {user:?} f32x8 at {p:?}",
                        def.name
                    );
                }
            }
        }
    }
}

/// Parameters drawn over a wide box (sizes in [0, 2], signed values in [-2, 2], angles over
/// their whole range), unrelated to the defaults: every field stays finite and 1-Lipschitz,
/// including the odd configurations (a carving sphere that misses, one sphere inside another).
#[test]
fn wide_random_parameters_give_finite_lipschitz_fields() {
    let mut rng = Rng::new(23);
    for &k in Primitive::ALL {
        let def = k.def();
        for _ in 0..40 {
            let user = wide_params(def, &mut rng);
            let a = baked(def, &user);
            for i in 0..400 {
                let p = rng.cube(3.0);
                let r = rng.range(0.0, if i % 2 == 0 { 0.05 } else { 1.5 });
                let o = rng.dir(r);
                let q = [p[0] + o[0], p[1] + o[1], p[2] + o[2]];
                let (fp, fq) = (eval(k, &a, p), eval(k, &a, q));
                assert!(fp.is_finite(), "{} {user:?} at {p:?}: {fp}", def.name);
                assert!(
                    (fp - fq).abs() <= dist(p, q) * (1.0 + 1e-6) + 1e-9,
                    "{} {user:?}: f({p:?}) = {fp}, f({q:?}) = {fq}, |p - q| = {}",
                    def.name,
                    dist(p, q)
                );
            }
        }
    }
}
