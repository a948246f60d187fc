//! Four double-double numbers evaluated in lockstep ([`Dd4`]): the [`Dd`] arithmetic on
//! [`F64x4`] lanes, so deep octree frames (past what f64 resolves) get the packet speedup
//! that [`F64x4`] gives shallow ones.
//!
//! Every lane computes exactly what [`Dd`] computes for it: the same error-free transforms
//! (Knuth's two-sum, Dekker's quick two-sum, a fused multiply-add for the exact product), the
//! same QD "accurate" addition and division, the same non-finite fallbacks (`lo = 0`), with
//! the scalar type's branches turned into lane selects. Only the f64 functions of the leading
//! parts differ: `sin`, `cos`, `acos`, `asin`, `atan2`, `ln`, `exp` and `powf` take
//! [`F64x4`]'s (`wide`'s, within a few ulps of libm's), then the same first-order correction
//! from the trailing part. So `+ - * / sqrt` and the folds agree with [`Dd`] bit for bit, and
//! the trig-free estimators (the power-8 Mandelbulb kernel, the Mandelbox, the IFS fractals)
//! agree to the few ulps of their final f64-accurate step (tested below).
//!
//! Our own code rather than a crate: the double-double crates on crates.io (`twofloat`,
//! `qd`, `double-double`) are scalar; this is [`Dd`] with `f64x4` lanes, and must stay the
//! same algorithm lane for lane.

use crate::dd::Dd;
use crate::real::{F64x4, Mask4, Real};
use crate::vec3::V3;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// Four double-double numbers: lane `i` is `hi[i] + lo[i]`, normalised as [`Dd`] is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dd4 {
    /// The leading parts.
    pub hi: F64x4,
    /// The trailing parts.
    pub lo: F64x4,
}

/// [`crate::dd::two_sum`] per lane.
#[inline(always)]
fn two_sum(a: F64x4, b: F64x4) -> (F64x4, F64x4) {
    let s = a + b;
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    (s, e)
}

/// [`crate::dd::quick_two_sum`] per lane.
#[inline(always)]
fn quick_two_sum(a: F64x4, b: F64x4) -> (F64x4, F64x4) {
    let s = a + b;
    let e = b - (s - a);
    (s, e)
}

/// [`crate::dd::two_prod`] per lane: one fused multiply-add (the x86-64-v3 baseline of
/// `.cargo/config.toml`).
#[cfg(target_feature = "fma")]
#[inline(always)]
fn two_prod(a: F64x4, b: F64x4) -> (F64x4, F64x4) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

/// [`crate::dd::two_prod`] per lane without a fused multiply-add (builds below x86-64-v3):
/// Dekker's product of the halves of each factor split at 27 bits, exact as the fused one.
#[cfg(not(target_feature = "fma"))]
#[inline(always)]
fn two_prod(a: F64x4, b: F64x4) -> (F64x4, F64x4) {
    let split = |x: F64x4| {
        let t = x * F64x4::splat(134217729.0);
        let h = t - (t - x);
        (h, x - h)
    };
    let p = a * b;
    let ((ah, al), (bh, bl)) = (split(a), split(b));
    (p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
}

/// Per lane `m ? a : b` on plain lanes.
#[inline(always)]
fn pick(m: F64x4, a: F64x4, b: F64x4) -> F64x4 {
    m.select(a, b)
}

impl Dd4 {
    /// Packs four double-doubles.
    #[inline]
    pub fn from_dd(v: [Dd; 4]) -> Dd4 {
        Dd4 {
            hi: F64x4::from(v.map(|x| x.hi)),
            lo: F64x4::from(v.map(|x| x.lo)),
        }
    }

    /// Four double-double points as one point of packets (lane `k` is point `k`).
    #[inline]
    pub fn pack(p: &[V3<Dd>; 4]) -> V3<Dd4> {
        let lanes = |f: fn(&V3<Dd>) -> Dd| Dd4::from_dd(p.each_ref().map(f));
        V3::new(lanes(|v| v.x), lanes(|v| v.y), lanes(|v| v.z))
    }

    /// Lane `i` as a double-double.
    #[inline]
    pub fn dd(self, i: usize) -> Dd {
        Dd {
            hi: self.hi.as_array()[i],
            lo: self.lo.as_array()[i],
        }
    }

    /// Plain lanes with a zero trailing part.
    #[inline(always)]
    fn exact(hi: F64x4) -> Dd4 {
        Dd4 {
            hi,
            lo: F64x4::ZERO,
        }
    }

    /// `(ok ? a : b)` per lane, both parts.
    #[inline(always)]
    fn pick(ok: F64x4, a: Dd4, b: Dd4) -> Dd4 {
        Dd4 {
            hi: pick(ok, a.hi, b.hi),
            lo: pick(ok, a.lo, b.lo),
        }
    }

    /// [`Dd::new`] per lane: `two_sum`, non-finite leading parts keep `lo = 0`.
    #[inline(always)]
    fn new(hi: F64x4, lo: F64x4) -> Dd4 {
        let (h, l) = two_sum(hi, lo);
        Dd4::pick(h.is_finite(), Dd4 { hi: h, lo: l }, Dd4::exact(h))
    }

    /// [`Dd`]'s renormalisation of an exact sum `(s, e)`; non-finite `s` drops `e`.
    #[inline(always)]
    fn renorm(s: F64x4, e: F64x4) -> Dd4 {
        let (hi, lo) = quick_two_sum(s, e);
        Dd4::pick(s.is_finite(), Dd4 { hi, lo }, Dd4::exact(s))
    }

    /// `self + b` for plain lanes `b`.
    #[inline(always)]
    fn add_f64(self, b: F64x4) -> Dd4 {
        let (s, e) = two_sum(self.hi, b);
        Dd4::renorm(s, e + self.lo)
    }

    /// `self * b` for plain lanes `b`.
    #[inline(always)]
    fn mul_f64(self, b: F64x4) -> Dd4 {
        let (p, e) = two_prod(self.hi, b);
        Dd4::renorm(p, e + self.lo * b)
    }

    /// `self^2`.
    #[inline(always)]
    fn sqr(self) -> Dd4 {
        let (p, e) = two_prod(self.hi, self.hi);
        Dd4::renorm(p, e + F64x4::splat(2.0) * self.hi * self.lo)
    }

    /// [`Dd`]'s first-order correction `f(hi) + d lo` of an f64 function value `f` with
    /// derivative `d`; a non-finite correction is dropped.
    #[inline(always)]
    fn corrected(f: F64x4, d: F64x4, lo: F64x4) -> Dd4 {
        let c = d * lo;
        Dd4::pick(c.is_finite(), Dd4::new(f, c), Dd4::exact(f))
    }

    /// Lanes whose value is negative (sign of the leading part, so -0 counts).
    #[inline(always)]
    fn negative(self) -> F64x4 {
        self.hi.is_sign_negative()
    }
}

impl Neg for Dd4 {
    type Output = Dd4;
    #[inline(always)]
    fn neg(self) -> Dd4 {
        Dd4 {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
}

impl Add for Dd4 {
    type Output = Dd4;
    /// [`Dd`]'s accurate addition per lane.
    #[inline(always)]
    fn add(self, b: Dd4) -> Dd4 {
        let (s1, s2) = two_sum(self.hi, b.hi);
        let (t1, t2) = two_sum(self.lo, b.lo);
        let (s1b, s2b) = quick_two_sum(s1, s2 + t1);
        let (hi, lo) = quick_two_sum(s1b, s2b + t2);
        Dd4::pick(s1.is_finite(), Dd4 { hi, lo }, Dd4::exact(s1))
    }
}

impl Sub for Dd4 {
    type Output = Dd4;
    #[inline(always)]
    fn sub(self, b: Dd4) -> Dd4 {
        self + -b
    }
}

impl Mul for Dd4 {
    type Output = Dd4;
    #[inline(always)]
    fn mul(self, b: Dd4) -> Dd4 {
        let (p, e) = two_prod(self.hi, b.hi);
        Dd4::renorm(p, e + (self.hi * b.lo + self.lo * b.hi))
    }
}

impl Div for Dd4 {
    type Output = Dd4;
    /// [`Dd`]'s accurate division per lane: three quotient digits.
    #[inline(always)]
    fn div(self, b: Dd4) -> Dd4 {
        let q1 = self.hi / b.hi;
        let r = self - b.mul_f64(q1);
        let q2 = r.hi / b.hi;
        let r = r - b.mul_f64(q2);
        let q3 = r.hi / b.hi;
        let (h, l) = quick_two_sum(q1, q2);
        let q = Dd4 { hi: h, lo: l }.add_f64(q3);
        Dd4::pick(q1.is_finite(), q, Dd4::exact(q1))
    }
}

macro_rules! assign_ops {
    ($($tr:ident $f:ident $op:tt),*) => {$(
        impl $tr for Dd4 {
            #[inline(always)]
            fn $f(&mut self, o: Dd4) {
                *self = *self $op o;
            }
        }
    )*};
}
assign_ops!(AddAssign add_assign +, SubAssign sub_assign -, MulAssign mul_assign *, DivAssign div_assign /);

impl Real for Dd4 {
    type Mask = Mask4;
    const LANES: usize = 4;

    #[inline(always)]
    fn splat(v: f64) -> Self {
        Dd4::exact(F64x4::splat(v))
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f64 {
        self.hi.as_array()[i]
    }
    #[inline(always)]
    fn from_lanes(v: &[f64]) -> Self {
        Dd4::exact(<F64x4 as Real>::from_lanes(v))
    }
    /// [`Dd`]'s one Newton step from the f64 root; zero, negative and non-finite lanes give
    /// the f64 root.
    #[inline(always)]
    fn sqrt(self) -> Self {
        let x = self.hi.sqrt();
        let r = self - Dd4::exact(x).sqr();
        let y = Dd4::exact(x).add_f64(r.hi * (F64x4::splat(0.5) / x));
        let ok = self.hi.simd_gt(F64x4::ZERO) & self.hi.is_finite();
        Dd4::pick(ok, y, Dd4::exact(x))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Dd4::pick(self.negative(), -self, self)
    }
    /// As `f64::min`: a NaN operand yields the other one.
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Dd4::pick(self.hi.is_nan() | o.lt(self).0, o, self)
    }
    /// As `f64::max`: a NaN operand yields the other one.
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Dd4::pick(self.hi.is_nan() | o.gt(self).0, o, self)
    }
    #[inline(always)]
    fn floor(self) -> Self {
        let h = self.hi.floor();
        let (hi, lo) = quick_two_sum(h, self.lo.floor());
        Dd4::pick(h.simd_eq(self.hi), Dd4 { hi, lo }, Dd4::exact(h))
    }
    #[inline(always)]
    fn round(self) -> Self {
        let a = self.abs();
        let f = a.floor();
        let up = (a - f).ge(Dd4::splat(0.5)).0;
        let r = Dd4::pick(up, f.add_f64(F64x4::ONE), f);
        Dd4::pick(self.negative(), -r, r)
    }
    #[inline(always)]
    fn sin(self) -> Self {
        let (s, c) = <F64x4 as Real>::sin_cos(self.hi);
        Dd4::corrected(s, c, self.lo)
    }
    #[inline(always)]
    fn cos(self) -> Self {
        let (s, c) = <F64x4 as Real>::sin_cos(self.hi);
        Dd4::corrected(c, -s, self.lo)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = <F64x4 as Real>::sin_cos(self.hi);
        (
            Dd4::corrected(s, c, self.lo),
            Dd4::corrected(c, -s, self.lo),
        )
    }
    #[inline(always)]
    fn acos(self) -> Self {
        let h = self.hi;
        let d = -(F64x4::ONE / (F64x4::ONE - h * h).sqrt());
        Dd4::corrected(<F64x4 as Real>::acos(h), d, self.lo)
    }
    #[inline(always)]
    fn asin(self) -> Self {
        let h = self.hi;
        let d = F64x4::ONE / (F64x4::ONE - h * h).sqrt();
        Dd4::corrected(<F64x4 as Real>::asin(h), d, self.lo)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        let (y0, x0) = (self.hi, x.hi);
        let a = <F64x4 as Real>::atan2(y0, x0);
        let c = (x0 * self.lo - y0 * x.lo) / (x0 * x0 + y0 * y0);
        Dd4::pick(c.is_finite(), Dd4::new(a, c), Dd4::exact(a))
    }
    #[inline(always)]
    fn ln(self) -> Self {
        Dd4::corrected(<F64x4 as Real>::ln(self.hi), F64x4::ONE / self.hi, self.lo)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        let e = <F64x4 as Real>::exp(self.hi);
        Dd4::corrected(e, e, self.lo)
    }
    #[inline(always)]
    fn powf(self, e: Self) -> Self {
        let p = <F64x4 as Real>::powf(self.hi, e.hi);
        let c = p * (e.hi * self.lo / self.hi + e.lo * <F64x4 as Real>::ln(self.hi));
        Dd4::pick(c.is_finite(), Dd4::new(p, c), Dd4::exact(p))
    }
    #[inline(always)]
    fn signum(self) -> Self {
        Dd4::exact(<F64x4 as Real>::signum(self.hi))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Mask4 {
        Mask4(self.hi.simd_lt(o.hi) | (self.hi.simd_eq(o.hi) & self.lo.simd_lt(o.lo)))
    }
    #[inline(always)]
    fn le(self, o: Self) -> Mask4 {
        Mask4(self.hi.simd_lt(o.hi) | (self.hi.simd_eq(o.hi) & self.lo.simd_le(o.lo)))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Mask4 {
        o.lt(self)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Mask4 {
        o.le(self)
    }
    #[inline(always)]
    fn is_finite(self) -> Mask4 {
        Mask4(self.hi.is_finite() & self.lo.is_finite())
    }
    #[inline(always)]
    fn select(m: Mask4, a: Self, b: Self) -> Self {
        Dd4::pick(m.0, a, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::Evaluator;
    use crate::tape::Tape;

    /// Awkward double-doubles: tiny and huge, signs, exact integers with fractional trailing
    /// parts, zeros of both signs, an infinity and a NaN.
    fn samples() -> Vec<Dd> {
        let mut v = vec![
            Dd::new(1.0, 1e-17),
            Dd::new(-3.0, 2e-16),
            Dd::new(2.0, -1e-17),
            Dd::new(0.1, 5e-18),
            Dd::new(-0.7, -3e-18),
            Dd::new(1e-300, 0.0),
            Dd::new(1e300, 1e283),
            Dd::new(4.0, 0.3e-15),
            Dd::new(-4.0, -0.3e-15),
            Dd::new(2.5, 0.0),
            Dd::new(-2.5, 0.0),
            Dd::new(0.0, 0.0),
            Dd::new(-0.0, 0.0),
            Dd::from(f64::INFINITY),
            Dd::from(f64::NAN),
            Dd::new(0.999999, 4e-23),
        ];
        for k in 0..16 {
            let x = (k as f64 * 0.37).sin() * 3.0;
            v.push(Dd::new(x, x * 1e-17 * (k as f64 - 7.5)));
        }
        v
    }

    fn same(a: Dd, b: Dd) -> bool {
        (a.hi.to_bits() == b.hi.to_bits() && a.lo.to_bits() == b.lo.to_bits())
            || (a.hi.is_nan() && b.hi.is_nan())
    }

    fn close(a: Dd, b: Dd, rel: f64) -> bool {
        same(a, b)
            || (a.hi - b.hi).abs() <= rel * a.hi.abs().max(1e-300)
            || (a.hi.is_nan() && b.hi.is_nan())
    }

    #[test]
    fn lanes_compute_what_the_scalar_double_double_computes() {
        let s = samples();
        // Every pair of samples through every lane position.
        for &a in &s {
            for j in 0..s.len() {
                let bs: [Dd; 4] = std::array::from_fn(|k| s[(j + k * 5) % s.len()]);
                let x = Dd4::from_dd([a; 4]);
                let y = Dd4::from_dd(bs);
                for (k, &b) in bs.iter().enumerate() {
                    let exact: [(&str, Dd4, Dd); 10] = [
                        ("+", x + y, a + b),
                        ("-", x - y, a - b),
                        ("*", x * y, a * b),
                        ("/", x / y, a / b),
                        ("min", x.min(y), a.min(b)),
                        ("max", x.max(y), a.max(b)),
                        ("sqrt", x.sqrt(), a.sqrt()),
                        ("abs", x.abs(), a.abs()),
                        ("floor", x.floor(), a.floor()),
                        ("round", x.round(), a.round()),
                    ];
                    for (op, got, want) in exact {
                        assert!(
                            same(got.dd(k), want),
                            "{a:?} {op} {b:?}: {:?} against {want:?}",
                            got.dd(k)
                        );
                    }
                    assert_eq!(x.lt(y).0.as_array()[k] != 0.0, a < b, "{a:?} < {b:?}");
                    assert_eq!(x.le(y).0.as_array()[k] != 0.0, a <= b, "{a:?} <= {b:?}");
                    assert_eq!(x.ge(y).0.as_array()[k] != 0.0, a >= b, "{a:?} >= {b:?}");
                }
            }
            // The f64-accurate functions: within a few ulps of the scalar ones, where an f64
            // function means something (not at 1e300 or infinity).
            if a.hi.is_nan() || a.hi.abs() >= 100.0 {
                continue;
            }
            let x = Dd4::from_dd([a; 4]);
            let f: [(&str, Dd4, Dd); 6] = [
                ("sin", x.sin(), Real::sin(a)),
                ("cos", x.cos(), Real::cos(a)),
                ("atan2", x.atan2(Dd4::splat(0.3)), a.atan2(Dd::from(0.3))),
                ("ln", x.abs().ln(), a.abs().ln()),
                (
                    "exp",
                    (x * Dd4::splat(1e-3)).exp(),
                    (a * Dd::from(1e-3)).exp(),
                ),
                (
                    "powf",
                    x.abs().powf(Dd4::splat(8.0)),
                    a.abs().powf(Dd::from(8.0)),
                ),
            ];
            for (op, got, want) in f {
                assert!(
                    close(got.dd(0), want, 1e-14),
                    "{op}({a:?}): {:?} against {want:?}",
                    got.dd(0)
                );
            }
        }
    }

    #[test]
    fn deep_distances_match_the_scalar_double_double_tape() {
        // Four points spread 1e-20 apart near the zoom targets (below an f64 ulp of the
        // coordinates): the packet gives each lane the scalar double-double's distance.
        for name in ["mandelbulb", "menger", "mandelbox", "sierpinski"] {
            let scene = crate::presets::load(name).unwrap();
            let tape = Tape::compile(&scene).unwrap();
            let (mut e1, mut e4) = (Evaluator::<Dd>::new(), Evaluator::<Dd4>::new());
            for base in [[0.3, 0.71, -0.42], [1.0 / 3.0, 0.2, 0.9], [-0.5, 0.05, 0.6]] {
                let p: [V3<Dd>; 4] = std::array::from_fn(|k| {
                    let t = Dd::new(0.0, 1e-20 * k as f64);
                    V3::new(
                        Dd::from(base[0]) + t,
                        Dd::from(base[1]) - t,
                        Dd::from(base[2]) + t * 2.0,
                    )
                });
                let d4 = e4.distance(&tape, Dd4::pack(&p));
                for (k, p) in p.into_iter().enumerate() {
                    let d1 = e1.distance(&tape, p);
                    assert!(
                        close(d4.dd(k), d1, 1e-13),
                        "{name} lane {k} at {base:?}: {:?} against {d1:?}",
                        d4.dd(k)
                    );
                }
            }
        }
    }
}
