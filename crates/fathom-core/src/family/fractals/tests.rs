//! Tests of the fractal estimators: known inside/outside points, the Lipschitz bound on random
//! pairs, packet (f32x8) against scalar (f64) agreement, and the power-8 fast path of the
//! Mandelbulb against the trig form. Every family-wide test loops over [`Fractal::ALL`], so a
//! new fractal cannot be added untested.

use super::*;
use crate::real::{F32x8, Real};
use crate::registry::Family;

/// The tests' deterministic generator.
use crate::testing::SplitMix64 as Rng;

/// The parameter buffer of `f` with its defaults, with `set` overriding named parameters.
fn params(f: Fractal, set: &[(&str, &[f64])]) -> Vec<f64> {
    let def = f.def();
    let mut user = def.defaults();
    for (name, v) in set {
        let (off, spec) = def
            .param(name)
            .unwrap_or_else(|| panic!("{}: no `{name}`", def.name));
        user[off..off + spec.kind.width()].copy_from_slice(v);
    }
    def.check(&user).unwrap();
    let mut buf = Vec::new();
    def.bake_into(&user, &mut buf);
    buf
}

fn est(f: Fractal, a: &[f64], p: [f64; 3]) -> (f64, f64) {
    f.estimate::<f64>(V3::new(p[0], p[1], p[2]), a)
}

fn d(f: Fractal, a: &[f64], p: [f64; 3]) -> f64 {
    est(f, a, p).0
}

/// Half-width of a box that holds each fractal at its defaults, for sampling.
fn extent(f: Fractal) -> f64 {
    match f {
        Fractal::Mandelbulb => 1.3,
        Fractal::Mandelbox => 2.4,
        Fractal::Koch => 1.3,
        _ => 1.2,
    }
}

#[test]
fn every_fractal_has_finite_estimates_everywhere() {
    let mut rng = Rng(1);
    for &f in Fractal::ALL {
        let a = params(f, &[]);
        for _ in 0..2000 {
            let p = rng.point(3.0 * extent(f));
            let (dist, trap) = est(f, &a, p);
            assert!(
                dist.is_finite() && trap.is_finite(),
                "{f:?} at {p:?}: {dist} {trap}"
            );
            assert!(trap >= 0.0);
        }
        // Far away, the estimate must be positive and grow.
        let far = d(f, &a, [50.0, 20.0, -30.0]);
        assert!(far > 10.0, "{f:?}: far estimate {far}");
    }
}

/// Worst `|f(a) - f(b)| / |a - b|` over random pairs near the fractal, at the given parameters,
/// where it was found, and how many pairs exceeded `1 + 1e-6`.
fn lipschitz_stats(f: Fractal, a: &[f64], seed: u64, pairs: usize) -> (f64, [f64; 3], usize) {
    let mut rng = Rng(seed);
    let r = extent(f) * 1.2;
    let mut worst = (0.0, [0.0; 3]);
    let mut over = 0;
    for _ in 0..pairs {
        let p = rng.point(r);
        let u = rng.dir();
        // Separations from 1e-4 to 0.3, log-uniform, so both fine detail and large steps count.
        let h = 10f64.powf(rng.range(-4.0, -0.5));
        let q = [p[0] + u[0] * h, p[1] + u[1] * h, p[2] + u[2] * h];
        let ratio = (d(f, a, p) - d(f, a, q)).abs() / h;
        if ratio > worst.0 {
            worst = (ratio, p);
        }
        over += usize::from(ratio > 1.0 + 1e-6);
    }
    (worst.0, worst.1, over)
}

/// `Bound` entries must satisfy `|f(a) - f(b)| <= |a - b| (1 + 1e-6)` on every sampled pair.
/// `Safety` entries (the escape-time estimators, whose overestimate is heavy-tailed) must do so
/// on all but 5e-4 of the pairs at their default `safety`; their worst ratio is reported.
#[test]
fn lipschitz_on_random_pairs() {
    use crate::registry::Quality;
    const PAIRS: usize = 20_000;
    for &f in Fractal::ALL {
        let a = params(f, &[]);
        let (worst, at, over) = lipschitz_stats(f, &a, 7 + f.index() as u64, PAIRS);
        eprintln!(
            "{f:?}: worst ratio {worst:.6} at {at:?}; {over} of {PAIRS} pairs above 1 + 1e-6"
        );
        match f.def().quality {
            Quality::Exact | Quality::Bound => {
                assert_eq!(over, 0, "{f:?}: worst ratio {worst} at {at:?}")
            }
            Quality::Safety => assert!(
                over as f64 <= 5e-4 * PAIRS as f64,
                "{f:?}: {over} pairs above 1, worst {worst} at {at:?}"
            ),
        }
    }
}

/// The folding fractals stay 1-Lipschitz away from their defaults too (random offsets,
/// scales and rotations), as the continuity argument of the module doc says.
#[test]
fn folding_fractals_are_lipschitz_at_random_parameters() {
    let mut rng = Rng(21);
    for &f in Fractal::ALL {
        if matches!(f.def().quality, crate::registry::Quality::Safety) {
            continue;
        }
        for trial in 0..4 {
            let def = f.def();
            let mut user = def.defaults();
            for spec in def.params {
                let (off, _) = def.param(spec.name).unwrap();
                for v in &mut user[off..off + spec.kind.width()] {
                    *v = match spec.name {
                        "iterations" => rng.range(1.0, 8.0).floor(),
                        "scale" => rng.range(1.2, 3.5),
                        "offset" => rng.range(-1.2, 1.2),
                        "rotation" | "twist" => rng.range(-60.0, 60.0),
                        _ => *v,
                    };
                }
            }
            def.check(&user).unwrap();
            let mut a = Vec::new();
            def.bake_into(&user, &mut a);
            let (worst, at, over) = lipschitz_stats(f, &a, 100 + trial, 3000);
            assert_eq!(over, 0, "{f:?} {user:?}: worst {worst} at {at:?}");
        }
    }
}

#[test]
fn packet_agrees_with_scalar() {
    let mut rng = Rng(3);
    for &f in Fractal::ALL {
        let a = params(f, &[]);
        let mut worst = 0.0f64;
        for _ in 0..300 {
            let pts: Vec<[f64; 3]> = (0..8).map(|_| rng.point(extent(f) * 1.5)).collect();
            let v = V3::new(
                F32x8::from_lanes(&pts.iter().map(|p| p[0]).collect::<Vec<_>>()),
                F32x8::from_lanes(&pts.iter().map(|p| p[1]).collect::<Vec<_>>()),
                F32x8::from_lanes(&pts.iter().map(|p| p[2]).collect::<Vec<_>>()),
            );
            let (dx, _) = f.estimate::<F32x8>(v, &a);
            for (i, p) in pts.iter().enumerate() {
                // Compare against f64 evaluated at the f32-rounded point.
                let p32 = p.map(|c| c as f32 as f64);
                let want = d(f, &a, p32);
                let got = dx.lane(i);
                let err = (got - want).abs() / (1e-3 * want.abs() + 1e-4);
                worst = worst.max(err);
            }
        }
        eprintln!("{f:?}: worst packet error / tolerance = {worst:.3}");
        assert!(worst <= 1.0, "{f:?}: packet error {worst} x tolerance");
    }
}

#[test]
fn sierpinski_folds_reach_the_cell_of_vertex_one_one_one() {
    let mut rng = Rng(11);
    for _ in 0..100_000 {
        let p = rng.point(3.0);
        let q = ifs::for_test::sierpinski_fold(V3::new(p[0], p[1], p[2]));
        assert!(
            q.x + q.y >= -1e-12 && q.x + q.z >= -1e-12 && q.y + q.z >= -1e-12,
            "{p:?} -> {q:?}"
        );
        assert!((q.length() - V3::new(p[0], p[1], p[2]).length()).abs() < 1e-12);
    }
}

/// A mirror of the icosahedral group, given the oblique normal.
type Mirror = fn(V3<f64>, V3<f64>) -> V3<f64>;

/// The orbit of `v` under the group generated by the mirrors x = 0, y = 0 and the oblique one.
fn icosahedral_orbit(v: [f64; 3]) -> Vec<V3<f64>> {
    let n = V3::new(-0.5, -0.809_016_994_374_947_5, 0.309_016_994_374_947_4);
    let gens: [Mirror; 3] = [
        |p, _| V3::new(-p.x, p.y, p.z),
        |p, _| V3::new(p.x, -p.y, p.z),
        |p, n| p - n * (2.0 * p.dot(n)),
    ];
    let mut orbit = vec![V3::new(v[0], v[1], v[2])];
    let mut i = 0;
    while i < orbit.len() {
        for g in gens {
            let w = g(orbit[i], n);
            if orbit.iter().all(|o| (*o - w).length() > 1e-9) {
                orbit.push(w);
            }
        }
        i += 1;
        assert!(orbit.len() <= 120, "the group is not finite");
    }
    orbit
}

#[test]
fn icosahedral_fold_gives_the_polyhedra() {
    // 12 vertices of the icosahedron (= dodecahedron faces), 20 of the dodecahedron.
    let ico = icosahedral_orbit(ifs::ICO_VERTEX);
    let dod = icosahedral_orbit(ifs::DODECA_VERTEX);
    assert_eq!(ico.len(), 12);
    assert_eq!(dod.len(), 20);
    let mut rng = Rng(12);
    for _ in 0..200_000 {
        let p = rng.point(2.0);
        let v = V3::new(p[0], p[1], p[2]);
        let q = ifs::for_test::icosahedral_fold(v);
        let n = V3::new(-0.5, -0.809_016_994_374_947_5, 0.309_016_994_374_947_4);
        assert!(
            q.x >= 0.0 && q.y >= 0.0 && q.dot(n) >= -1e-12,
            "{p:?} -> {q:?}"
        );
        assert!((q.length() - v.length()).abs() < 1e-12);
        // Folded single-plane bound == max over all face planes of the polyhedron.
        let r = ifs::for_test::INRADIUS;
        let want_ico = dod.iter().map(|f| f.dot(v)).fold(f64::MIN, f64::max) - r;
        let want_dod = ico.iter().map(|f| f.dot(v)).fold(f64::MIN, f64::max) - r;
        let got_ico = q.dot(V3::new(
            ifs::DODECA_VERTEX[0],
            ifs::DODECA_VERTEX[1],
            ifs::DODECA_VERTEX[2],
        )) - r;
        let got_dod = q.dot(V3::new(
            ifs::ICO_VERTEX[0],
            ifs::ICO_VERTEX[1],
            ifs::ICO_VERTEX[2],
        )) - r;
        assert!((want_ico - got_ico).abs() < 1e-12 && (want_dod - got_dod).abs() < 1e-12);
    }
}

#[test]
fn mandelbulb_power8_fast_path_matches_trig_form() {
    let mut rng = Rng(13);
    // One step, anywhere (including near the z axis and at the origin).
    let mut worst = 0.0f64;
    for i in 0..100_000 {
        let mut z = rng.point(1.5);
        if i % 10 == 0 {
            z[0] *= 1e-9;
            z[1] *= 1e-9;
        }
        let c = rng.point(1.5);
        let (t, f) =
            mandelbulb::steps_for_test(V3::new(z[0], z[1], z[2]), V3::new(c[0], c[1], c[2]));
        let scale = V3::new(z[0], z[1], z[2]).length().powi(8) + V3::new(c[0], c[1], c[2]).length();
        worst = worst.max((t - f).length() / scale);
    }
    eprintln!("power-8 step: worst relative difference {worst:e}");
    // Near the z axis acos(z/r) loses precision (its slope is infinite at 1), so the trig
    // form is the less accurate one there; elsewhere the two agree to ~1e-15.
    assert!(worst < 1e-7, "{worst}");
    let (t, f) = mandelbulb::steps_for_test(V3::zero(), V3::new(0.1, 0.2, 0.3));
    assert_eq!((t, f), (V3::new(0.1, 0.2, 0.3), V3::new(0.1, 0.2, 0.3)));
    // Whole estimates: the same to 1e-6 relative.
    let a = params(Fractal::Mandelbulb, &[("safety", &[0.8])]);
    let mut worst = 0.0f64;
    for _ in 0..20_000 {
        let p = rng.point(1.5);
        let fast = d(Fractal::Mandelbulb, &a, p) / 0.8;
        let (trig, _) = mandelbulb::mandelbulb_trig_for_test(V3::new(p[0], p[1], p[2]), 12, 4.0);
        worst = worst.max((fast - trig).abs() / trig.abs().max(1e-3));
    }
    eprintln!("power-8 estimate: worst relative difference {worst:e}");
    assert!(worst < 1e-6, "{worst}");
}

/// The parameters of `f` with `iterations` set.
fn at_depth(f: Fractal, n: usize) -> Vec<f64> {
    params(f, &[("iterations", &[n as f64])])
}

#[test]
fn menger_holes_tunnels_and_corners() {
    let f = Fractal::Menger;
    // Depth 0 is the cube [-1, 1]^3 itself.
    let a0 = at_depth(f, 0);
    assert!((d(f, &a0, [2.0, 0.0, 0.0]) - 1.0).abs() < 1e-12);
    assert!((d(f, &a0, [0.0, 0.0, 0.0]) + 1.0).abs() < 1e-12);
    for n in 1..=6 {
        let a = at_depth(f, n);
        // The centre is removed; the nearest solid is an edge cube's edge at (1/3, 1/3, 0).
        let c = d(f, &a, [0.0, 0.0, 0.0]);
        assert!(
            (c - 2f64.sqrt() / 3.0).abs() < 1e-12,
            "depth {n}: centre {c}"
        );
        // The three first-level tunnels run right through: every point whose two other
        // coordinates are within 1/3 of the axis is outside, including each face centre.
        let mut rng = Rng(40 + n as u64);
        for axis in 0..3 {
            for _ in 0..500 {
                let mut p = [rng.range(-0.32, 0.32), rng.range(-0.32, 0.32), 0.0];
                p.rotate_right(axis);
                p[axis] = rng.range(-1.5, 1.5);
                assert!(
                    d(f, &a, p) > 0.0,
                    "depth {n}: tunnel point {p:?} is not outside"
                );
            }
            let mut face = [0.0; 3];
            face[axis] = 1.0;
            assert!(d(f, &a, face) > 0.3, "depth {n}: face centre {face:?}");
        }
        // The corners are fixed points of the IFS: on the surface at every depth, and a point
        // just inside a corner is inside.
        for s in 0..8 {
            let sg = [s & 1, s & 2, s & 4].map(|b| if b == 0 { 1.0 } else { -1.0 });
            assert!(d(f, &a, sg).abs() < 1e-12, "depth {n}: corner {sg:?}");
            let inside = sg.map(|c| c * (1.0 - 1e-3 / 3f64.powi(n as i32)));
            assert!(d(f, &a, inside) <= 0.0, "depth {n}: {inside:?}");
        }
        // The centre of a corner sub-cube is solid at depth 1 and a hole from depth 2 on.
        let sub = d(f, &a, [2.0 / 3.0; 3]);
        assert!(
            if n == 1 { sub < 0.0 } else { sub > 0.0 },
            "depth {n}: sub-cube centre {sub}"
        );
    }
}

#[test]
fn sierpinski_vertices_edges_and_removed_octahedron() {
    let f = Fractal::Sierpinski;
    let verts = [
        [1.0, 1.0, 1.0],
        [-1.0, -1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
    ];
    for n in 0..=12 {
        let a = at_depth(f, n);
        // Tolerance shrinking like scale^-n: the surface detail at depth n.
        let tol = 1e-9 * 2f64.powi(-(n as i32));
        for v in verts {
            assert!(
                d(f, &a, v).abs() <= tol,
                "depth {n}: vertex {v:?}: {}",
                d(f, &a, v)
            );
        }
        // Edge midpoints are vertices of the depth-1 copies, so on the surface too.
        for m in [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]] {
            assert!(d(f, &a, m).abs() <= tol, "depth {n}: edge midpoint {m:?}");
        }
        let c = d(f, &a, [0.0, 0.0, 0.0]);
        if n == 0 {
            // The solid tetrahedron: the centre is 1/sqrt 3 deep.
            assert!((c + 1.0 / 3f64.sqrt()).abs() < 1e-12);
        } else {
            // The centre of the removed octahedron |x|+|y|+|z| <= 1, 1/sqrt 3 from its faces.
            assert!(
                (c - 1.0 / 3f64.sqrt()).abs() < 1e-12,
                "depth {n}: centre {c}"
            );
        }
    }
}

#[test]
fn mandelbulb_inside_on_axes_and_outside_far() {
    let f = Fractal::Mandelbulb;
    let a = params(f, &[]);
    for p in [
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 0.3],
        [0.0, 0.0, -0.3],
        [0.3, 0.0, 0.0],
        [0.0, -0.3, 0.0],
    ] {
        assert!(
            d(f, &a, p) <= 0.0,
            "{p:?} should be inside: {}",
            d(f, &a, p)
        );
    }
    for p in [[3.0, 0.0, 0.0], [0.0, 0.0, 5.0], [2.0, 2.0, -2.0]] {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let v = d(f, &a, p);
        // The bulb lies within radius 1.2, so the true distance is at least r - 1.2.
        assert!(v > 0.0 && v <= r - 1.0, "{p:?}: {v}");
    }
}

/// Far below the old estimate's floor (~7e-7 outside the set, 0 inside), the Mandelbulb's
/// surface is a smooth level set with a signed, first-order estimate: on lines through 40
/// surface points found by bisection, stepping along the normal, the estimate changes sign
/// at the surface, grows linearly with the offset (doubling when it doubles) and the
/// gradient's direction is the same whether taken 1e-11 or 1e-12 wide. Its size against the
/// offset is the running derivative's: 0.13-2.3x on 37 of the 40 lines, a heavy tail where
/// `dr` underestimates the map's stretch (near the poles: 13, 86 and 478 times on the other
/// 3). The old estimate failed the sign, doubling and size checks at every offset here (it
/// read 7e-7 or 0).
#[test]
fn mandelbulb_surface_is_smooth_and_signed_far_below_the_old_floor() {
    let f = Fractal::Mandelbulb;
    let a = params(f, &[]);
    let mut rng = Rng(404);
    let at = |p: [f64; 3], u: [f64; 3], s: f64| [p[0] + u[0] * s, p[1] + u[1] * s, p[2] + u[2] * s];
    let grad = |p: [f64; 3], h: f64| -> [f64; 3] {
        let g: [f64; 3] = std::array::from_fn(|i| {
            let mut q = p;
            let mut r = p;
            q[i] += h;
            r[i] -= h;
            d(f, &a, q) - d(f, &a, r)
        });
        let n = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        g.map(|x| x / n)
    };
    let mut sizes = Vec::new();
    while sizes.len() < 40 {
        // A line from outside (radius 1.5) toward the origin (inside), bisected to the surface.
        let u = rng.dir();
        let (mut lo, mut hi) = (0.0, 1.5);
        if d(f, &a, at([0.0; 3], u, lo)) >= 0.0 || d(f, &a, at([0.0; 3], u, hi)) <= 0.0 {
            continue;
        }
        for _ in 0..80 {
            let m = 0.5 * (lo + hi);
            if d(f, &a, at([0.0; 3], u, m)) < 0.0 {
                lo = m;
            } else {
                hi = m;
            }
        }
        let p0 = at([0.0; 3], u, 0.5 * (lo + hi));
        let n = grad(p0, 1e-11);
        for e in [1e-11, 1e-10, 1e-9] {
            let (out, out2, inside) = (
                d(f, &a, at(p0, n, e)),
                d(f, &a, at(p0, n, 2.0 * e)),
                d(f, &a, at(p0, n, -e)),
            );
            assert!(
                out > 0.0 && inside < 0.0,
                "{p0:?} offset {e}: {out} {inside}"
            );
            let ratio = out2 / out;
            assert!(
                (1.8..=2.2).contains(&ratio),
                "{p0:?} offset {e}: doubling gave {ratio}"
            );
            let sym = -inside / out;
            assert!(
                (0.9..=1.1).contains(&sym),
                "{p0:?} offset {e}: inside/outside {sym}"
            );
        }
        sizes.push(d(f, &a, at(p0, n, 1e-10)) / 1e-10);
        let g2 = grad(p0, 1e-12);
        let cos = n[0] * g2[0] + n[1] * g2[1] + n[2] * g2[2];
        assert!(
            cos > 0.999,
            "{p0:?}: normals 1e-11 and 1e-12 wide differ (cos {cos})"
        );
    }
    sizes.sort_by(f64::total_cmp);
    eprintln!("estimate / offset on 40 lines: {sizes:.3?}");
    let within = sizes.iter().filter(|&&s| s <= 2.5).count();
    assert!(
        within >= 36,
        "only {within} of 40 lines at most 2.5x the offset: {sizes:?}"
    );
    assert!(
        sizes[0] > 0.1,
        "an estimate far below the offset: {sizes:?}"
    );
}

#[test]
fn mandelbox_origin_inside_and_far_point_escapes() {
    let f = Fractal::Mandelbox;
    for scale in [-1.5, 2.0] {
        let a = params(f, &[("scale", &[scale])]);
        // The origin is a fixed point of every fold and of z -> scale z + 0.
        assert_eq!(est(f, &a, [0.0; 3]), (0.0, 0.0));
        // Far away the first iteration already escapes: z = scale * fold(p) + p.
        let v = d(f, &a, [200.0, 0.0, 0.0]);
        assert!(v > 20.0 && v < 200.0, "scale {scale}: {v}");
    }
    // The default box fits in |x|, |y|, |z| < 2.2: points beyond are outside.
    let a = params(f, &[]);
    let mut rng = Rng(50);
    for _ in 0..2000 {
        let mut p = rng.point(3.0);
        p[rng.next_u64() as usize % 3] = 2.2 * rng.range(1.0, 1.3).copysign(rng.range(-1.0, 1.0));
        assert!(d(f, &a, p) > 0.0, "{p:?}");
    }
}

#[test]
fn koch_vertices_peaks_and_centre() {
    let f = Fractal::Koch;
    let h0 = 1.0 / 3f64.sqrt();
    for n in 0..=7 {
        for twist in [0.0, 90.0] {
            let a = params(f, &[("iterations", &[n as f64]), ("twist", &[twist])]);
            let radius = 0.15 / 3f64.powi(n);
            // The triangle's corners are on the curve at every depth.
            for ang in [30f64, 150.0, 270.0] {
                let r = 2.0 / 3f64.sqrt();
                let (s, c) = ang.to_radians().sin_cos();
                let v = d(f, &a, [r * c, r * s, 0.0]);
                assert!(
                    (v + radius).abs() < 1e-12,
                    "depth {n} twist {twist}: corner {ang}: {v}"
                );
            }
            if n >= 1 {
                // The peak of the first bump on each edge, and the inner vertices.
                assert!((d(f, &a, [0.0, 2.0 * h0, 0.0]) + radius).abs() < 1e-12);
                assert!((d(f, &a, [1.0 / 3.0, h0, 0.0]) + radius).abs() < 1e-12);
                // From the centre the nearest curve points are the inner vertices (1/3, h0).
                if twist == 0.0 {
                    let c = d(f, &a, [0.0; 3]) + radius;
                    assert!((c - 2.0 / 3.0).abs() < 1e-12, "depth {n}: centre {c}");
                }
            }
        }
    }
}

#[test]
fn kifs_polyhedra_vertices_and_centres() {
    for (f, origin_outside) in [
        (Fractal::KifsOctahedron, false),
        (Fractal::KifsIcosahedron, true),
        (Fractal::KifsDodecahedron, true),
    ] {
        let def = f.def();
        let (off, _) = def.param("offset").unwrap();
        let vertex = &def.defaults()[off..off + 3];
        for n in 0..=6 {
            let a = at_depth(f, n);
            // The offset is a fixed point of the IFS and a vertex of the base solid.
            let v = d(f, &a, [vertex[0], vertex[1], vertex[2]]);
            assert!(v.abs() < 1e-9, "{f:?} depth {n}: vertex {v}");
            let o = d(f, &a, [0.0; 3]);
            if n == 0 {
                assert!(o < 0.0, "{f:?}: the solid's centre is inside");
            } else if origin_outside {
                assert!(o > 0.0, "{f:?} depth {n}: centre {o}");
            } else {
                // The six octahedra of the flake meet at the centre.
                assert!(o.abs() < 1e-9, "{f:?} depth {n}: centre {o}");
            }
        }
    }
}

/// Points within about `spread` of the surface: sphere-trace random rays aimed at the fractal
/// until the estimate drops below 1e-5 (the surface as a renderer sees it; the Mandelbox
/// estimate is never negative), then jitter.
fn near_surface(f: Fractal, a: &[f64], rng: &mut Rng, count: usize, spread: f64) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    let r = extent(f);
    for _ in 0..1000 * count {
        if out.len() == count {
            return out;
        }
        let o = rng.dir().map(|c| c * 2.0 * r);
        let t = rng.point(0.7 * r);
        let dir = [0, 1, 2].map(|i| t[i] - o[i]);
        let len = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
        let mut s = 0.0;
        for _ in 0..300 {
            let p = [0, 1, 2].map(|i| o[i] + dir[i] / len * s);
            let v = d(f, a, p);
            if v < 1e-5 {
                let u = rng.dir();
                let j = rng.range(-spread, spread);
                out.push([0, 1, 2].map(|i| p[i] + u[i] * j));
                break;
            }
            s += v;
            if s > 4.0 * r {
                break;
            }
        }
    }
    panic!("{f:?}: found only {} surface points", out.len());
}

/// Near the surface is where f32 hurts: an escape-time orbit that grazes the bailout can escape
/// one iteration earlier or later, and fold decisions can flip. The reference is f64 at the
/// f32-rounded point (so input rounding is not counted) and the tolerance is relative 1e-3 +
/// absolute 1e-4, far above f32 round-off (~1e-7 per operation) yet far below the step sizes
/// that matter to a sphere tracer. Measured worst: under 1% of the tolerance.
#[test]
fn packet_agrees_with_scalar_near_the_surface() {
    let mut rng = Rng(60);
    for &f in Fractal::ALL {
        let a = params(f, &[]);
        let pts = near_surface(f, &a, &mut rng, 320, 1e-2);
        let mut worst = 0.0f64;
        let mut errs = Vec::new();
        for chunk in pts.chunks(8) {
            let lane =
                |i: usize| F32x8::from_lanes(&chunk.iter().map(|p| p[i]).collect::<Vec<_>>());
            let (dx, _) = f.estimate::<F32x8>(V3::new(lane(0), lane(1), lane(2)), &a);
            for (i, p) in chunk.iter().enumerate() {
                let want = d(f, &a, p.map(|c| c as f32 as f64));
                let e = (dx.lane(i) - want).abs() / (1e-3 * want.abs() + 1e-4);
                errs.push(e);
                worst = worst.max(e);
            }
        }
        errs.sort_by(f64::total_cmp);
        eprintln!(
            "{f:?}: near surface, error / tolerance: median {:.4}, 99% {:.4}, worst {worst:.4}",
            errs[errs.len() / 2],
            errs[errs.len() * 99 / 100]
        );
        assert!(
            worst <= 1.0,
            "{f:?}: packet error {worst} x tolerance near the surface"
        );
    }
}

/// The depth-n Koch snowflake as an explicit polyline (counter-clockwise, bumps outward).
fn koch_polyline(n: usize) -> Vec<[f64; 2]> {
    let h0 = 1.0 / 3f64.sqrt();
    let mut pts = vec![[1.0, h0], [-1.0, h0], [0.0, -2.0 * h0], [1.0, h0]];
    let (s, c) = (-60f64).to_radians().sin_cos();
    for _ in 0..n {
        let mut next = vec![pts[0]];
        for w in pts.windows(2) {
            let (a, b) = (w[0], w[1]);
            let t = [(b[0] - a[0]) / 3.0, (b[1] - a[1]) / 3.0];
            let p1 = [a[0] + t[0], a[1] + t[1]];
            let peak = [p1[0] + c * t[0] - s * t[1], p1[1] + s * t[0] + c * t[1]];
            next.extend([p1, peak, [a[0] + 2.0 * t[0], a[1] + 2.0 * t[1]], b]);
        }
        pts = next;
    }
    pts
}

/// At twist 0 the Koch estimate is the exact distance to the explicit polyline, minus the
/// tube radius.
#[test]
fn koch_matches_the_explicit_polyline() {
    let f = Fractal::Koch;
    let mut rng = Rng(70);
    for n in 0..=4 {
        let a = at_depth(f, n);
        let line = koch_polyline(n);
        assert_eq!(line.len(), 3 * 4usize.pow(n as u32) + 1);
        let radius = 0.15 / 3f64.powi(n as i32);
        for _ in 0..400 {
            let p = rng.point(1.4);
            let mut best = f64::MAX;
            for w in line.windows(2) {
                let (a0, b0) = (w[0], w[1]);
                let ab = [b0[0] - a0[0], b0[1] - a0[1]];
                let ap = [p[0] - a0[0], p[1] - a0[1]];
                let t = ((ap[0] * ab[0] + ap[1] * ab[1]) / (ab[0] * ab[0] + ab[1] * ab[1]))
                    .clamp(0.0, 1.0);
                let dx = ap[0] - t * ab[0];
                let dy = ap[1] - t * ab[1];
                best = best.min((dx * dx + dy * dy + p[2] * p[2]).sqrt());
            }
            let got = d(f, &a, p);
            assert!(
                (got - (best - radius)).abs() < 1e-9,
                "depth {n} at {p:?}: {got} vs {}",
                best - radius
            );
        }
    }
}
