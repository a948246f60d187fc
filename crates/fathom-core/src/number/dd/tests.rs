//! Tests of double-double arithmetic: the error-free transforms against exact integer
//! arithmetic, every operation against an exact floating-point expansion, the exact
//! comparisons and roundings, DD evaluation of every registry entry and preset against f64, and
//! the Menger sponge's self-similarity at its corner 31 levels down (where f64 fails).

use super::*;
use crate::fractals::Fractal;
use crate::modifiers::Modifier;
use crate::presets::{PRESETS, load};
use crate::primitives::Primitive;
use crate::scene::{Node, Scene};
use crate::tape::Tape;
use crate::transforms::Transform;
use crate::{Evaluator, scenes};

/// The tests' deterministic generator.
use crate::testing::SplitMix64 as Rng;

/// A signed integer mantissa of 1 to 53 bits.
fn mantissa(rng: &mut Rng) -> i64 {
    let bits = rng.int(1, 53);
    let m = (rng.next_u64() >> (64 - bits)) as i64 | 1;
    if rng.next_u64() & 1 == 1 { -m } else { m }
}

/// A random double-double of magnitude about `2^e` with a random trailing part.
fn random_dd(rng: &mut Rng, e: i32) -> Dd {
    let hi = rng.range(0.5, 1.0) * 2f64.powi(e) * if rng.next_u64() & 1 == 1 { -1.0 } else { 1.0 };
    let lo = rng.range(-0.5, 0.5) * f64::EPSILON * hi.abs();
    Dd::new(hi, lo)
}

/// `m 2^e` as an f64 (exact for |m| < 2^53 and e in the normal range).
fn ldexp(m: i64, e: i32) -> f64 {
    m as f64 * 2f64.powi(e)
}

/// `x / 2^e` as an integer, asserting that it is one.
fn scaled_int(x: f64, e: i32) -> i128 {
    let s = x * 2f64.powi(-e);
    assert_eq!(s.fract(), 0.0, "{x} is not a multiple of 2^{e}");
    assert!(s.abs() < 2f64.powi(126));
    s as i128
}

#[test]
fn two_sum_and_quick_two_sum_are_exact_against_integers() {
    let mut rng = Rng(1);
    for _ in 0..100_000 {
        // a = ma 2^ea, b = mb 2^eb with exponent gaps up to 70 (past the 53 where b is all
        // rounding error): both are integers at scale 2^min(ea, eb), which fit in i128.
        let (ma, mb) = (mantissa(&mut rng), mantissa(&mut rng));
        let ea = rng.int(-300, 300);
        let eb = ea + rng.int(-70, 70);
        let (a, b) = (ldexp(ma, ea), ldexp(mb, eb));
        let e0 = ea.min(eb);
        let exact = ((ma as i128) << (ea - e0)) + ((mb as i128) << (eb - e0));
        let (s, e) = two_sum(a, b);
        assert_eq!(s, a + b);
        assert_eq!(
            scaled_int(s, e0) + scaled_int(e, e0),
            exact,
            "two_sum({a:e}, {b:e})"
        );
        let (big, small) = if a.abs() >= b.abs() { (a, b) } else { (b, a) };
        let (s, e) = quick_two_sum(big, small);
        assert_eq!(
            scaled_int(s, e0) + scaled_int(e, e0),
            exact,
            "quick_two_sum({big:e}, {small:e})"
        );
    }
}

#[test]
fn two_prod_is_exact_against_integers() {
    let mut rng = Rng(2);
    for _ in 0..100_000 {
        let (ma, mb) = (mantissa(&mut rng), mantissa(&mut rng));
        let (ea, eb) = (rng.int(-400, 400), rng.int(-400, 400));
        let (a, b) = (ldexp(ma, ea), ldexp(mb, eb));
        let (p, e) = two_prod(a, b);
        assert_eq!(p, a * b);
        assert_eq!(
            scaled_int(p, ea + eb) + scaled_int(e, ea + eb),
            ma as i128 * mb as i128,
            "two_prod({a:e}, {b:e})"
        );
    }
    // Without the fused multiply-add the error term is lost: a plain product misses it.
    let a = 1.0 + f64::EPSILON;
    let (p, e) = two_prod(a, a);
    assert_eq!(p, 1.0 + 2.0 * f64::EPSILON);
    assert_eq!(e, f64::EPSILON * f64::EPSILON);
}

/// The exact sum of `terms` rounded to f64: Shewchuk's grow-expansion (every step an exact
/// [`two_sum`], checked above), then the non-overlapping components summed smallest first.
fn exact_sum(terms: &[f64]) -> f64 {
    let mut comps: Vec<f64> = Vec::new();
    for &t in terms {
        let mut q = t;
        let mut next = Vec::with_capacity(comps.len() + 1);
        for &c in &comps {
            let (s, e) = two_sum(q, c);
            if e != 0.0 {
                next.push(e);
            }
            q = s;
        }
        next.push(q);
        comps = next;
    }
    comps.iter().fold(0.0, |acc, &c| acc + c)
}

/// The exact terms of `a b` (four exact products, eight terms).
fn prod_terms(a: Dd, b: Dd) -> Vec<f64> {
    let mut t = Vec::new();
    for (x, y) in [(a.hi, b.hi), (a.hi, b.lo), (a.lo, b.hi), (a.lo, b.lo)] {
        let (p, e) = two_prod(x, y);
        t.extend([p, e]);
    }
    t
}

fn neg(t: Vec<f64>) -> Vec<f64> {
    t.into_iter().map(|x| -x).collect()
}

/// Is `x` normalised: `hi` is `hi + lo` rounded to nearest?
fn normalised(x: Dd) -> bool {
    x.hi + x.lo == x.hi || x.lo.abs() <= 0.5 * (x.hi.abs() * f64::EPSILON)
}

#[test]
fn arithmetic_is_accurate_to_double_double_precision() {
    let mut rng = Rng(3);
    // Worst residual / |result| seen per operation.
    let mut worst = [0.0f64; 5];
    for _ in 0..20_000 {
        let (ea, eb) = (rng.int(-20, 20), rng.int(-20, 20));
        let (a, b) = (random_dd(&mut rng, ea), random_dd(&mut rng, eb));
        let rel = |r: f64, scale: f64| r.abs() / scale.abs();
        // (a + b) - result, exactly.
        let s = a + b;
        let r = exact_sum(&[a.hi, a.lo, b.hi, b.lo, -s.hi, -s.lo]);
        worst[0] = worst[0].max(rel(r, a.hi.abs().max(b.hi.abs())));
        let d = a - b;
        let r = exact_sum(&[a.hi, a.lo, -b.hi, -b.lo, -d.hi, -d.lo]);
        worst[1] = worst[1].max(rel(r, a.hi.abs().max(b.hi.abs())));
        // a b - result.
        let p = a * b;
        let mut t = prod_terms(a, b);
        t.extend([-p.hi, -p.lo]);
        worst[2] = worst[2].max(rel(exact_sum(&t), p.hi));
        // a - (a / b) b, relative to a.
        let q = a / b;
        let mut t = neg(prod_terms(q, b));
        t.extend([a.hi, a.lo]);
        worst[3] = worst[3].max(rel(exact_sum(&t), a.hi));
        // |a| - sqrt(|a|)^2, relative to |a|.
        let aa = a.abs();
        let root = aa.sqrt();
        let mut t = neg(prod_terms(root, root));
        t.extend([aa.hi, aa.lo]);
        worst[4] = worst[4].max(rel(exact_sum(&t), aa.hi));
        for x in [s, d, p, q, root] {
            assert!(normalised(x), "{x:?} not normalised");
        }
    }
    eprintln!(
        "worst relative residuals: add {:.2e}, sub {:.2e}, mul {:.2e}, div {:.2e}, sqrt {:.2e}",
        worst[0], worst[1], worst[2], worst[3], worst[4]
    );
    // 2^-104 = 4.9e-32; the QD algorithms are within a few units of it.
    for (name, w) in ["add", "sub", "mul", "div", "sqrt"].iter().zip(worst) {
        assert!(w < 1e-30, "{name}: relative residual {w:e}");
    }
    // The oracle can tell f64 from double-double: the f64 quotient's residual is ~1e-17.
    let (a, b) = (Dd::from(1.0), Dd::from(3.0));
    let f = Dd::from(1.0 / 3.0);
    let mut t = neg(prod_terms(f, b));
    t.push(1.0);
    assert!(exact_sum(&t).abs() > 1e-17);
    let q = a / b;
    let mut t = neg(prod_terms(q, b));
    t.push(1.0);
    assert!(exact_sum(&t).abs() < 1e-32, "{}", exact_sum(&t));
}

#[test]
fn mixed_operations_with_f64_match_the_double_double_ones() {
    let mut rng = Rng(4);
    for _ in 0..10_000 {
        let e = rng.int(-10, 10);
        let a = random_dd(&mut rng, e);
        let b = rng.range(-4.0, 4.0);
        let close = |x: Dd, y: Dd| ((x - y).hi).abs() <= 1e-30 * x.hi.abs().max(1e-300);
        assert!(close(a + b, a + Dd::from(b)));
        assert!(close(a - b, a - Dd::from(b)));
        assert!(close(a * b, a * Dd::from(b)));
        assert!(close(a / b, a / Dd::from(b)), "{a:?} / {b}");
        let mut c = a;
        c += b;
        c *= Dd::from(2.0);
        c -= a;
        c /= 3.0;
        assert!(close(c, ((a + b) * 2.0 - a) / 3.0));
    }
    // Normalising constructor: any split of the same value gives the same number.
    assert_eq!(Dd::new(1.0, 1.0), Dd::from(2.0));
    assert_eq!(Dd::new(1e-20, 1.0), Dd::new(1.0, 1e-20));
    assert_eq!(Dd::new(1.0, 1e-20).to_f64(), 1.0);
}

#[test]
fn comparisons_and_roundings_see_the_trailing_part() {
    let one = Dd::from(1.0);
    let above = Dd::new(1.0, 1e-20);
    let below = Dd::new(1.0, -1e-20);
    assert!(above > one && one > below && above > below);
    assert!(above.gt(one) && below.lt(one) && one.le(one) && one.ge(one));
    assert!(!one.lt(one) && !above.le(one));
    assert!(-above < -one);
    assert_eq!(Real::min(above, below), below);
    assert_eq!(Real::max(above, below), above);
    assert_eq!(Real::min(one, Dd::from(f64::NAN)), one);
    assert_eq!(Real::max(Dd::from(f64::NAN), one), one);
    assert_eq!(Real::abs(-above), above);
    // A value a hair below 3 floors to 2 (f64's floor of `hi` would say 3).
    let x = Dd::new(3.0, -1e-20);
    assert_eq!(Real::floor(x), Dd::from(2.0));
    assert_eq!(Real::floor(Dd::new(3.0, 1e-20)), Dd::from(3.0));
    assert_eq!(Real::floor(Dd::new(-3.0, 1e-20)), Dd::from(-3.0));
    assert_eq!(Real::floor(Dd::new(-3.0, -1e-20)), Dd::from(-4.0));
    assert_eq!(Real::floor(Dd::from(2.5)), Dd::from(2.0));
    // Half away from zero, and the trailing part decides near the half.
    assert_eq!(Real::round(Dd::from(2.5)), Dd::from(3.0));
    assert_eq!(Real::round(Dd::from(-2.5)), Dd::from(-3.0));
    assert_eq!(Real::round(Dd::new(2.5, -1e-20)), Dd::from(2.0));
    assert_eq!(Real::round(Dd::new(-2.5, 1e-20)), Dd::from(-2.0));
    assert_eq!(Real::round(Dd::new(7.0, -1e-20)), Dd::from(7.0));
    assert_eq!(Real::signum(below), one);
    assert_eq!(Real::signum(-below), -one);
    assert_eq!(Dd::select(true, above, below), above);
    assert_eq!(Dd::select(false, above, below), below);
    // An integer beyond 2^53 with a fractional trailing part: floor keeps it exact.
    let big = Dd::new(2f64.powi(60), 0.75);
    assert_eq!(Real::floor(big), Dd::from(2f64.powi(60)));
    assert_eq!(Real::round(big), Dd::new(2f64.powi(60), 1.0));
}

#[test]
fn non_finite_values_behave_as_in_f64() {
    let zero = Dd::ZERO;
    assert_eq!((Dd::ONE / zero).hi, f64::INFINITY);
    assert_eq!((-Dd::ONE / zero).hi, f64::NEG_INFINITY);
    assert!((zero / zero).hi.is_nan());
    assert!(Real::sqrt(Dd::from(-1.0)).hi.is_nan());
    assert_eq!(Real::sqrt(zero), zero);
    assert_eq!((Dd::from(f64::INFINITY) + Dd::ONE).hi, f64::INFINITY);
    assert_eq!((Dd::from(1e300) * Dd::from(1e300)).hi, f64::INFINITY);
    assert_eq!(Real::min(Dd::from(f64::INFINITY), Dd::ONE), Dd::ONE);
    assert!(!Real::is_finite(Dd::from(f64::INFINITY)));
    assert!(Real::is_finite(Dd::ONE));
    assert_eq!(Real::ln(zero).hi, f64::NEG_INFINITY);
    assert_eq!(Real::sqrt(Dd::from(f64::INFINITY)).hi, f64::INFINITY);
}

#[test]
fn transcendental_functions_are_f64_accurate_with_a_first_order_tail() {
    let mut rng = Rng(5);
    for _ in 0..1000 {
        let e = rng.int(-3, 1);
        let x = random_dd(&mut rng, e);
        let h = x.hi;
        // Within two f64 ulps (of 1 for small results: the tail moves ln(1 + e) by e).
        let near =
            |got: Dd, want: f64| (got.to_f64() - want).abs() <= 4.5e-16 * want.abs().max(1.0);
        assert!(near(Real::sin(x), h.sin()) && near(Real::cos(x), h.cos()));
        let (s, c) = Real::sin_cos(x);
        assert_eq!((s, c), (Real::sin(x), Real::cos(x)));
        assert!(near(Real::exp(x), h.exp()));
        assert!(near(Real::atan2(x, Dd::from(0.7)), h.atan2(0.7)));
        let u = Dd::from(h.abs().min(0.9));
        assert!(near(Real::acos(u), u.hi.acos()) && near(Real::asin(u), u.hi.asin()));
        let a = x.abs();
        assert!(near(Real::ln(a), a.hi.ln()));
        assert!(near(Real::powf(a, Dd::from(3.5)), a.hi.powf(3.5)));
    }
    // The tail carries the first-order change below an f64 ulp: ln(1 + 1e-20) = 1e-20, and
    // exp and sin move by their derivatives.
    let tiny = Dd::new(1.0, 1e-20);
    assert!((Real::ln(tiny).to_f64() - 1e-20).abs() < 1e-35);
    let e = Real::exp(tiny) - Dd::from(1f64.exp());
    assert!((e.to_f64() / 1e-20 - 1f64.exp()).abs() < 1e-6, "{e:?}");
    let s = Real::sin(tiny) - Real::sin(Dd::ONE);
    assert!((s.to_f64() / 1e-20 - 1f64.cos()).abs() < 1e-6);
    let p = Real::powf(tiny, Dd::from(8.0)) - Dd::ONE;
    assert!((p.to_f64() / 8e-20 - 1.0).abs() < 1e-6, "{p:?}");
}

#[test]
fn point_helpers_keep_small_offsets_exact() {
    let target = DVec3::new(1.0, -0.3, 0.7);
    let off = DVec3::new(1e-20, -3e-25, 2.5e-18);
    let eye = add_offset(dd3(target), off);
    // f64 cannot hold the offset at all; double-double gives it back exactly.
    assert_eq!(target + off, target);
    assert_eq!(to_dvec3(eye), target);
    let back = sub_to_f64(eye, dd3(target));
    assert!((back - off).abs().max_element() <= 1e-16 * off.abs().max_element());
    assert_eq!(sub_to_f64(dd3(target), dd3(target)), DVec3::ZERO);
}

/// Scenes covering the registry: every primitive and fractal at its defaults, every transform
/// and modifier on a box at its defaults, the hundred-node scene (every combine), and every
/// preset.
fn registry_scenes() -> Vec<(String, Scene)> {
    let mut out = Vec::new();
    for &p in Primitive::ALL {
        out.push((format!("primitive {p:?}"), Scene::new(Node::new(p))));
    }
    for &f in Fractal::ALL {
        out.push((format!("fractal {f:?}"), Scene::new(Node::new(f))));
    }
    for &t in Transform::ALL {
        out.push((
            format!("transform {t:?}"),
            Scene::new(Node::new(Primitive::Box).op(t)),
        ));
    }
    for &m in Modifier::ALL {
        out.push((
            format!("modifier {m:?}"),
            Scene::new(Node::new(Primitive::Box).op(m)),
        ));
    }
    out.push(("hundred-node".into(), scenes::hundred_node_scene()));
    for p in PRESETS {
        out.push((format!("preset {}", p.name), load(p.name).unwrap()));
    }
    out
}

#[test]
fn dd_evaluation_matches_f64_on_every_registry_entry_and_preset() {
    let mut rng = Rng(6);
    let mut ev64 = Evaluator::<f64>::new();
    let mut evdd = Evaluator::<Dd>::new();
    let mut checked = 0;
    for (name, scene) in registry_scenes() {
        let tape = Tape::compile(&scene).unwrap();
        let mut worst = 0.0f64;
        for _ in 0..300 {
            let q = DVec3::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
            );
            let want = ev64.eval(&tape, q.into());
            let got = evdd.eval(&tape, dd3(q));
            let err = (got.d.to_f64() - want.d).abs() / want.d.abs().max(1e-6);
            worst = worst.max(err);
            assert!(
                err <= 1e-9,
                "{name} at {q:?}: f64 {} dd {:?} (relative {err:e})",
                want.d,
                got.d
            );
            assert_eq!(got.id.hi, want.id, "{name}: material at {q:?}");
            checked += 1;
        }
        if worst > 1e-13 {
            eprintln!("{name}: worst relative difference {worst:.1e}");
        }
    }
    assert!(checked > 300 * 50, "{checked}");
}

/// `(1, 1, 1) - v 3^-k` in double-double.
fn corner_point_dd(v: DVec3, k: i32) -> V3<Dd> {
    let s = Dd::from(3.0).powi(k); // exact: 3^66 < 2^106
    let c = |x: f64| Dd::ONE - Dd::from(x) / s;
    V3::new(c(v.x), c(v.y), c(v.z))
}

#[test]
fn menger_corner_self_similarity_holds_in_dd_and_fails_in_f64() {
    // The corner (1,1,1) is the fixed point of the sponge's map p -> 3 p - 2 (after the abs
    // and sort folds, which leave points near the corner alone), so k iterations take
    // (1,1,1) - 3^-k v to (1,1,1) - sort(v) exactly, and the estimate with N iterations there
    // is 3^-k times the estimate with N - k iterations at (1,1,1) - v. An identity in exact
    // arithmetic: any difference is rounding. k = 60 (3^60 = 4e28) shows the corner's special
    // case: the target is exact, so the whole offset sits in `lo` with f64 relative precision.
    const LEVELS: u32 = 9;
    // Offsets inside and outside the corner (components up to 2 keep the identity exact: the
    // middle cut `|z + 1| - 1` leaves z >= -1 alone).
    let mut rng = Rng(7);
    let vs: Vec<DVec3> = (0..12)
        .map(|_| {
            DVec3::new(
                rng.range(-0.5, 1.5),
                rng.range(-0.5, 1.5),
                rng.range(-0.5, 1.5),
            )
        })
        .collect();
    let shallow = Tape::compile(&scenes::menger(LEVELS)).unwrap();
    let mut evdd = Evaluator::<Dd>::new();
    let mut ev64 = Evaluator::<f64>::new();
    for k in [25, 31, 60] {
        let deep = Tape::compile(&scenes::menger(LEVELS + k as u32)).unwrap();
        let s_dd = Dd::from(3.0).powi(k);
        let s = s_dd.hi;
        let (mut f64_worst, mut dd_worst) = (0.0f64, 0.0f64);
        let mut compared = 0;
        for &v in &vs {
            let want = ev64.distance(&shallow, (DVec3::ONE - v).into());
            if want.abs() < 1e-3 {
                continue; // on the surface: relative differences mean nothing
            }
            compared += 1;
            let got = (evdd.distance(&deep, corner_point_dd(v, k)) * s_dd).to_f64();
            let err = (got - want).abs() / want.abs();
            dd_worst = dd_worst.max(err);
            assert!(
                err <= 1e-9,
                "k {k}, v {v:?}: dd {got} against {want} (relative {err:e})"
            );
            // The same in f64: the point itself is rounded to an ulp of 1 (1.1e-16), which is
            // 3^-k v's 1e-4 (k = 25) or 7 % (k = 31); at k = 60 it is 1 itself.
            let p64 = DVec3::ONE - v / s;
            let got64 = ev64.distance(&deep, p64.into()) * s;
            f64_worst = f64_worst.max((got64 - want).abs() / want.abs());
        }
        assert!(
            compared >= 6,
            "only {compared} points away from the surface"
        );
        eprintln!(
            "menger corner 3^-{k}: {compared} points; worst relative error dd {dd_worst:.1e}, f64 {f64_worst:.2e}"
        );
        assert!(
            f64_worst > 1e-6,
            "k {k}: f64 passes the self-similarity check ({f64_worst:e}); the test proves nothing"
        );
        if k == 31 {
            assert!(f64_worst > 1e-2, "k 31: f64 error only {f64_worst:e}");
        }
    }
}
