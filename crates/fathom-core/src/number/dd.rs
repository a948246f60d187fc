//! Double-double arithmetic: a number carried as the unevaluated sum of two `f64`s, giving
//! about 106 significant bits (relative precision ~1e-32) for zooms past what `f64` resolves
//! (a coordinate near 1 has an ulp of 2.2e-16, so an f64 zoom stops near 1e15).
//!
//! [`Dd`] implements [`Real`] with one lane, so the tape interpreter ([`crate::Evaluator`]),
//! every primitive, operator and fractal, and anything else written against `Real` can be
//! evaluated in double-double unchanged ([`crate::Tape::eval_dd`]).
//!
//! What is exact to double-double precision (~1e-32 relative per operation) and what is not:
//!
//! - `+ - * /`, `sqrt` (one Newton correction), `abs`, `min`, `max`, `floor`, `round`,
//!   `signum`, comparisons (on `hi`, then `lo`) and `select` carry the full precision;
//! - `sin`, `cos`, `sin_cos`, `acos`, `asin`, `atan2`, `ln`, `exp`, `powf` are only
//!   **f64-accurate**: the f64 function of `hi` plus a first-order correction from `lo`
//!   (`f(hi) + f'(hi) lo`). The correction keeps them smooth and monotone below an f64 ulp
//!   (a point moved by 1e-25 moves the result by about `f' 1e-25`), but their absolute error is
//!   that of the f64 function, ~1e-16 relative.
//!
//! Consequently these estimators are exact in double-double, because per point they use only
//! `+ - * / sqrt abs min max` and folds: the power-8 Mandelbulb kernel (`step_pow8`, trig-free;
//! the final `0.5 ln(r) r / dr` is f64-accurate, which only scales the distance, it does not
//! move the set boundary), the Mandelbox, the IFS fractals (Menger, Sierpinski, the KIFS
//! flakes, the Koch wire) and the primitives; angles given as parameters (rotations, the Koch
//! twist, capped shapes) are baked into f64 sines and cosines once, which are then exact
//! constants of the shape. Per-point trigonometry is only f64-accurate: the trig-form
//! Mandelbulb (any power other than 8, or non-zero angle offsets) and the `Twist` and `Bend`
//! transforms, which therefore blur at ~1e-16 relative like f64.
//!
//! Algorithms: Dekker/Knuth error-free transforms ([`two_sum`], [`quick_two_sum`],
//! [`two_prod`] with a fused multiply-add), and the "accurate" addition and division of the QD
//! library (Hida, Li and Bailey 2001). Non-finite results (overflow, division by zero) fall
//! back to the plain f64 result with `lo = 0`, so infinities propagate as they do in f64
//! instead of turning into NaN.

use crate::real::Real;
use crate::vec3::V3;
use glam::DVec3;
use std::cmp::Ordering;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

#[cfg(test)]
mod tests;

/// A double-double number `hi + lo`, normalised: `hi` is `hi + lo` rounded to f64, so
/// `|lo| <= ulp(hi) / 2`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dd {
    /// The leading part: the value rounded to f64.
    pub hi: f64,
    /// The trailing part: what `hi` misses.
    pub lo: f64,
}

/// `a + b` exactly, as `(s, e)` with `s = fl(a + b)` and `e` the rounding error (Knuth).
#[inline(always)]
pub fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    (s, e)
}

/// `a + b` exactly when `|a| >= |b|` (or `a == 0`), as `(s, e)` (Dekker). Cheaper than
/// [`two_sum`].
#[inline(always)]
pub fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let e = b - (s - a);
    (s, e)
}

/// `a * b` exactly, as `(p, e)` with `p = fl(a b)` and `e = a b - p` from one fused
/// multiply-add (exact unless the product underflows).
#[inline(always)]
pub fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let e = a.mul_add(b, -p);
    (p, e)
}

impl Dd {
    /// Zero.
    pub const ZERO: Dd = Dd { hi: 0.0, lo: 0.0 };
    /// One.
    pub const ONE: Dd = Dd { hi: 1.0, lo: 0.0 };

    /// The double-double `hi + lo` (normalised, so any split of a value is accepted).
    #[inline(always)]
    pub fn new(hi: f64, lo: f64) -> Dd {
        let (h, l) = two_sum(hi, lo);
        if !h.is_finite() {
            return Dd { hi: h, lo: 0.0 };
        }
        Dd { hi: h, lo: l }
    }

    /// The value rounded to f64 (`hi`, up to a tie).
    #[inline(always)]
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }

    /// True when neither part is NaN or infinite.
    #[inline(always)]
    pub fn is_finite(self) -> bool {
        self.hi.is_finite() && self.lo.is_finite()
    }

    /// True when the value is NaN.
    #[inline(always)]
    pub fn is_nan(self) -> bool {
        self.hi.is_nan()
    }

    /// `(s, e)` from an exact sum, renormalised; non-finite `s` drops `e`.
    #[inline(always)]
    fn renorm(s: f64, e: f64) -> Dd {
        if !s.is_finite() {
            return Dd { hi: s, lo: 0.0 };
        }
        let (hi, lo) = quick_two_sum(s, e);
        Dd { hi, lo }
    }

    /// `self + b` for an f64 `b`, to double-double precision.
    #[inline(always)]
    pub fn add_f64(self, b: f64) -> Dd {
        let (s, e) = two_sum(self.hi, b);
        Dd::renorm(s, e + self.lo)
    }

    /// `self * b` for an f64 `b`, to double-double precision.
    #[inline(always)]
    pub fn mul_f64(self, b: f64) -> Dd {
        let (p, e) = two_prod(self.hi, b);
        Dd::renorm(p, e + self.lo * b)
    }

    /// `self / b` for an f64 `b`, to double-double precision.
    #[inline(always)]
    pub fn div_f64(self, b: f64) -> Dd {
        let q1 = self.hi / b;
        if !q1.is_finite() {
            return Dd { hi: q1, lo: 0.0 };
        }
        // r = self - q1 b, exactly enough: two_prod gives q1 b as (p, e).
        let (p, e) = two_prod(q1, b);
        let (s, f) = two_sum(self.hi, -p);
        let r = s + (f - e + self.lo);
        let q2 = r / b;
        Dd::renorm(q1, q2)
    }

    /// `self^2`, a little cheaper than `self * self`.
    #[inline(always)]
    pub fn sqr(self) -> Dd {
        let (p, e) = two_prod(self.hi, self.hi);
        Dd::renorm(p, e + 2.0 * self.hi * self.lo)
    }

    /// `self^n` for an integer `n` (repeated squaring; negative `n` divides).
    pub fn powi(self, n: i32) -> Dd {
        let mut base = self;
        let mut e = n.unsigned_abs();
        let mut acc = Dd::ONE;
        while e > 0 {
            if e & 1 == 1 {
                acc *= base;
            }
            base = base.sqr();
            e >>= 1;
        }
        if n < 0 { Dd::ONE / acc } else { acc }
    }

    /// The total order of normalised values (`hi` first, then `lo`); `None` with a NaN.
    #[inline(always)]
    fn cmp_dd(self, o: Dd) -> Option<Ordering> {
        match self.hi.partial_cmp(&o.hi)? {
            Ordering::Equal => self.lo.partial_cmp(&o.lo),
            ord => Some(ord),
        }
    }
}

impl From<f64> for Dd {
    #[inline(always)]
    fn from(x: f64) -> Dd {
        Dd { hi: x, lo: 0.0 }
    }
}

impl PartialOrd for Dd {
    #[inline(always)]
    fn partial_cmp(&self, o: &Dd) -> Option<Ordering> {
        self.cmp_dd(*o)
    }
}

impl Neg for Dd {
    type Output = Dd;
    #[inline(always)]
    fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
}

impl Add for Dd {
    type Output = Dd;
    /// QD's accurate ("IEEE") addition: both parts summed error-free, so cancellation of the
    /// leading parts keeps the full precision of the trailing ones.
    #[inline(always)]
    fn add(self, b: Dd) -> Dd {
        let (s1, s2) = two_sum(self.hi, b.hi);
        if !s1.is_finite() {
            return Dd { hi: s1, lo: 0.0 };
        }
        let (t1, t2) = two_sum(self.lo, b.lo);
        let (s1, s2) = quick_two_sum(s1, s2 + t1);
        let (hi, lo) = quick_two_sum(s1, s2 + t2);
        Dd { hi, lo }
    }
}

impl Sub for Dd {
    type Output = Dd;
    #[inline(always)]
    fn sub(self, b: Dd) -> Dd {
        self + -b
    }
}

impl Mul for Dd {
    type Output = Dd;
    #[inline(always)]
    fn mul(self, b: Dd) -> Dd {
        let (p, e) = two_prod(self.hi, b.hi);
        Dd::renorm(p, e + (self.hi * b.lo + self.lo * b.hi))
    }
}

impl Div for Dd {
    type Output = Dd;
    /// QD's accurate division: three quotient digits, each from the remainder of the last.
    #[inline(always)]
    fn div(self, b: Dd) -> Dd {
        let q1 = self.hi / b.hi;
        if !q1.is_finite() {
            return Dd { hi: q1, lo: 0.0 };
        }
        let r = self - b.mul_f64(q1);
        let q2 = r.hi / b.hi;
        let r = r - b.mul_f64(q2);
        let q3 = r.hi / b.hi;
        let (q1, q2) = quick_two_sum(q1, q2);
        Dd { hi: q1, lo: q2 }.add_f64(q3)
    }
}

impl Add<f64> for Dd {
    type Output = Dd;
    #[inline(always)]
    fn add(self, b: f64) -> Dd {
        self.add_f64(b)
    }
}

impl Sub<f64> for Dd {
    type Output = Dd;
    #[inline(always)]
    fn sub(self, b: f64) -> Dd {
        self.add_f64(-b)
    }
}

impl Mul<f64> for Dd {
    type Output = Dd;
    #[inline(always)]
    fn mul(self, b: f64) -> Dd {
        self.mul_f64(b)
    }
}

impl Div<f64> for Dd {
    type Output = Dd;
    #[inline(always)]
    fn div(self, b: f64) -> Dd {
        self.div_f64(b)
    }
}

macro_rules! assign_ops {
    ($($tr:ident $f:ident $op:tt),*) => {$(
        impl $tr for Dd {
            #[inline(always)]
            fn $f(&mut self, o: Dd) {
                *self = *self $op o;
            }
        }
        impl $tr<f64> for Dd {
            #[inline(always)]
            fn $f(&mut self, o: f64) {
                *self = *self $op o;
            }
        }
    )*};
}
assign_ops!(AddAssign add_assign +, SubAssign sub_assign -, MulAssign mul_assign *, DivAssign div_assign /);

/// `f(hi) + d lo` for an f64 function value `f` at `hi` and its derivative `d` there: the
/// first-order correction that keeps an f64-accurate function smooth below an f64 ulp.
#[inline(always)]
fn corrected(f: f64, d: f64, lo: f64) -> Dd {
    let c = d * lo;
    if c.is_finite() {
        Dd::new(f, c)
    } else {
        Dd::from(f)
    }
}

impl Real for Dd {
    type Mask = bool;
    const LANES: usize = 1;

    #[inline(always)]
    fn splat(v: f64) -> Self {
        Dd::from(v)
    }
    #[inline(always)]
    fn lane(self, _i: usize) -> f64 {
        self.hi
    }
    #[inline(always)]
    fn from_lanes(v: &[f64]) -> Self {
        Dd::from(v[0])
    }
    /// One Newton step from the f64 root (QD's `sqrt`): `x + (a - x^2) / (2x)`, full precision.
    #[inline(always)]
    fn sqrt(self) -> Self {
        if self.hi <= 0.0 {
            // 0 (either sign) stays 0; negatives give NaN as in f64.
            return Dd::from(self.hi.sqrt());
        }
        if !self.hi.is_finite() {
            return Dd::from(self.hi.sqrt());
        }
        let x = self.hi.sqrt();
        let r = self - Dd::from(x).sqr();
        Dd::from(x).add_f64(r.hi * (0.5 / x))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        if self.hi.is_sign_negative() {
            -self
        } else {
            self
        }
    }
    /// As `f64::min`: a NaN operand yields the other one.
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        if self.is_nan() || o < self { o } else { self }
    }
    /// As `f64::max`: a NaN operand yields the other one.
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        if self.is_nan() || o > self { o } else { self }
    }
    /// Exact: when `hi` is a whole number the fractional part is in `lo`.
    #[inline(always)]
    fn floor(self) -> Self {
        let h = self.hi.floor();
        if h == self.hi {
            let (hi, lo) = quick_two_sum(h, self.lo.floor());
            Dd { hi, lo }
        } else {
            Dd::from(h)
        }
    }
    /// Half away from zero, exactly (`floor`, then the exact fractional part against 1/2).
    #[inline(always)]
    fn round(self) -> Self {
        let a = self.abs();
        let f = a.floor();
        let r = if a - f >= Dd::from(0.5) { f + 1.0 } else { f };
        if self.hi.is_sign_negative() { -r } else { r }
    }
    #[inline(always)]
    fn sin(self) -> Self {
        let (s, c) = self.hi.sin_cos();
        corrected(s, c, self.lo)
    }
    #[inline(always)]
    fn cos(self) -> Self {
        let (s, c) = self.hi.sin_cos();
        corrected(c, -s, self.lo)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.hi.sin_cos();
        (corrected(s, c, self.lo), corrected(c, -s, self.lo))
    }
    #[inline(always)]
    fn acos(self) -> Self {
        let h = self.hi;
        corrected(h.acos(), -1.0 / (1.0 - h * h).sqrt(), self.lo)
    }
    #[inline(always)]
    fn asin(self) -> Self {
        let h = self.hi;
        corrected(h.asin(), 1.0 / (1.0 - h * h).sqrt(), self.lo)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        let (y0, x0) = (self.hi, x.hi);
        let a = y0.atan2(x0);
        let r2 = x0 * x0 + y0 * y0;
        let c = (x0 * self.lo - y0 * x.lo) / r2;
        if c.is_finite() {
            Dd::new(a, c)
        } else {
            Dd::from(a)
        }
    }
    #[inline(always)]
    fn ln(self) -> Self {
        corrected(self.hi.ln(), 1.0 / self.hi, self.lo)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        let e = self.hi.exp();
        corrected(e, e, self.lo)
    }
    /// `hi^e` with the first-order corrections from both trailing parts.
    #[inline(always)]
    fn powf(self, e: Self) -> Self {
        let p = self.hi.powf(e.hi);
        let c = p * (e.hi * self.lo / self.hi + e.lo * self.hi.ln());
        if c.is_finite() {
            Dd::new(p, c)
        } else {
            Dd::from(p)
        }
    }
    #[inline(always)]
    fn signum(self) -> Self {
        Dd::from(self.hi.signum())
    }
    #[inline(always)]
    fn lt(self, o: Self) -> bool {
        self < o
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
    }
    #[inline(always)]
    fn ge(self, o: Self) -> bool {
        self >= o
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        Dd::is_finite(self)
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m { a } else { b }
    }
}

/// An f64 point as a double-double point (exact).
#[inline]
pub fn dd3(p: DVec3) -> V3<Dd> {
    V3::new(Dd::from(p.x), Dd::from(p.y), Dd::from(p.z))
}

/// `p + off` per component, to double-double precision (exact whenever the sum has at most
/// 106 significant bits, e.g. an eye offset of 1e-20 from a target near 1).
#[inline]
pub fn add_offset(p: V3<Dd>, off: DVec3) -> V3<Dd> {
    V3::new(p.x.add_f64(off.x), p.y.add_f64(off.y), p.z.add_f64(off.z))
}

/// `a - b` per component, computed in double-double and rounded once to f64: a small
/// difference of two nearby deep points keeps its full f64 relative precision.
#[inline]
pub fn sub_to_f64(a: V3<Dd>, b: V3<Dd>) -> DVec3 {
    DVec3::new(
        (a.x - b.x).to_f64(),
        (a.y - b.y).to_f64(),
        (a.z - b.z).to_f64(),
    )
}

/// A double-double point rounded to f64.
#[inline]
pub fn to_dvec3(p: V3<Dd>) -> DVec3 {
    DVec3::new(p.x.to_f64(), p.y.to_f64(), p.z.to_f64())
}
