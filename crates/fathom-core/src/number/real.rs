//! The scalar abstraction every distance function is written against.
//!
//! Each primitive, operator and fractal is written once, generic over [`Real`]. Five types
//! implement it: `f64` (the exact scalar path used as the reference), [`F32x8`] (eight `f32`
//! lanes evaluated together by AVX2, the throughput path), [`F64x4`] (four `f64` lanes, within
//! a few ulps of `f64`: the octree's voxel colouring), [`crate::dd::Dd`] (double-double,
//! one lane, for zooms past f64 precision) and [`crate::dd4::Dd4`] (four double-double lanes,
//! the octree's deep frames). Control flow
//! that depends on a value (a fold, a bailout) is written with masks and [`Real::select`], so the
//! same source is branch-free on the packet path and an ordinary `if` on the scalar path.

use std::fmt::Debug;
use std::ops::{
    Add, AddAssign, BitAnd, BitOr, Div, DivAssign, Mul, MulAssign, Neg, Not, Sub, SubAssign,
};

/// A per-lane boolean: `bool` for scalars, a lane mask for packets.
pub trait Mask:
    Copy + Debug + BitAnd<Output = Self> + BitOr<Output = Self> + Not<Output = Self>
{
    /// True when any lane is set.
    fn any(self) -> bool;
    /// True when every lane is set.
    fn all(self) -> bool;
}

impl Mask for bool {
    #[inline(always)]
    fn any(self) -> bool {
        self
    }
    #[inline(always)]
    fn all(self) -> bool {
        self
    }
}

/// A real number, or a packet of them evaluated in lockstep.
pub trait Real:
    Copy
    + Debug
    + Send
    + Sync
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + 'static
{
    /// The lane mask produced by comparisons.
    type Mask: Mask;
    /// Number of lanes (1 for scalars).
    const LANES: usize;

    /// The same value in every lane.
    fn splat(v: f64) -> Self;
    /// Lane `i` as an `f64`.
    fn lane(self, i: usize) -> f64;
    /// Build from per-lane values (missing lanes repeat the last given value).
    fn from_lanes(v: &[f64]) -> Self;

    /// Square root, per lane.
    fn sqrt(self) -> Self;
    /// Absolute value, per lane.
    fn abs(self) -> Self;
    /// The smaller of the two, per lane.
    fn min(self, o: Self) -> Self;
    /// The larger of the two, per lane.
    fn max(self, o: Self) -> Self;
    /// Largest whole number not above, per lane.
    fn floor(self) -> Self;
    /// Round half away from zero.
    fn round(self) -> Self;
    /// Sine (radians), per lane.
    fn sin(self) -> Self;
    /// Cosine (radians), per lane.
    fn cos(self) -> Self;
    /// Sine and cosine at once, per lane.
    fn sin_cos(self) -> (Self, Self);
    /// Arc cosine, radians in [0, pi], per lane.
    fn acos(self) -> Self;
    /// Arc sine, radians in [-pi/2, pi/2], per lane.
    fn asin(self) -> Self;
    /// `self.atan2(x)` is the angle of the point `(x, self)`.
    fn atan2(self, x: Self) -> Self;
    /// Natural logarithm, per lane.
    fn ln(self) -> Self;
    /// `e` raised to `self`, per lane.
    fn exp(self) -> Self;
    /// `self` raised to `e`, for `self > 0`.
    fn powf(self, e: Self) -> Self;
    /// -1, 0 or +1 (0 maps to +1 on some paths: use only where the sign of 0 does not matter).
    fn signum(self) -> Self;

    /// Per lane: `self < o`.
    fn lt(self, o: Self) -> Self::Mask;
    /// Per lane: `self <= o`.
    fn le(self, o: Self) -> Self::Mask;
    /// Per lane: `self > o`.
    fn gt(self, o: Self) -> Self::Mask;
    /// Per lane: `self >= o`.
    fn ge(self, o: Self) -> Self::Mask;
    /// Lanes that are neither NaN nor infinite.
    fn is_finite(self) -> Self::Mask;
    /// Per lane: `m ? a : b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;

    /// Per lane: `self` clamped to `[lo, hi]`.
    #[inline(always)]
    fn clamp(self, lo: Self, hi: Self) -> Self {
        self.max(lo).min(hi)
    }
    /// Zero in every lane.
    #[inline(always)]
    fn zero() -> Self {
        Self::splat(0.0)
    }
    /// One in every lane.
    #[inline(always)]
    fn one() -> Self {
        Self::splat(1.0)
    }
    /// Linear interpolation, exact at both ends: `a (1 - t) + b t`. (The shorter
    /// `a + (b - a) t` cancels catastrophically in f32 when `|a - b|` dwarfs `b`, e.g. a smooth
    /// union of a near shape with one a billion units away.)
    #[inline(always)]
    fn lerp(a: Self, b: Self, t: Self) -> Self {
        a * (Self::one() - t) + b * t
    }
}

impl Real for f64 {
    type Mask = bool;
    const LANES: usize = 1;

    #[inline(always)]
    fn splat(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn lane(self, _i: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn from_lanes(v: &[f64]) -> Self {
        v[0]
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        f64::min(self, o)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        f64::max(self, o)
    }
    #[inline(always)]
    fn floor(self) -> Self {
        f64::floor(self)
    }
    #[inline(always)]
    fn round(self) -> Self {
        f64::round(self)
    }
    #[inline(always)]
    fn sin(self) -> Self {
        f64::sin(self)
    }
    #[inline(always)]
    fn cos(self) -> Self {
        f64::cos(self)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        f64::sin_cos(self)
    }
    #[inline(always)]
    fn acos(self) -> Self {
        f64::acos(self)
    }
    #[inline(always)]
    fn asin(self) -> Self {
        f64::asin(self)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        f64::atan2(self, x)
    }
    #[inline(always)]
    fn ln(self) -> Self {
        f64::ln(self)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        f64::exp(self)
    }
    #[inline(always)]
    fn powf(self, e: Self) -> Self {
        f64::powf(self, e)
    }
    #[inline(always)]
    fn signum(self) -> Self {
        f64::signum(self)
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
        f64::is_finite(self)
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m { a } else { b }
    }
}

/// The mask type and the [`Real`] implementation of a `wide` packet type `$w` of `$n` lanes
/// (`$narrow` converts an `f64` to a lane), declared once for every packet width.
macro_rules! packet_real {
    ($name:ident, $w:ty, $mask:ident, $n:literal, $narrow:path) => {
        #[doc = concat!("Lane mask of [`", stringify!($name), "`]: all-ones bits in set lanes.")]
        #[derive(Clone, Copy, Debug)]
        pub struct $mask(pub $w);

        impl BitAnd for $mask {
            type Output = Self;
            #[inline(always)]
            fn bitand(self, o: Self) -> Self {
                $mask(self.0 & o.0)
            }
        }
        impl BitOr for $mask {
            type Output = Self;
            #[inline(always)]
            fn bitor(self, o: Self) -> Self {
                $mask(self.0 | o.0)
            }
        }
        impl Not for $mask {
            type Output = Self;
            #[inline(always)]
            fn not(self) -> Self {
                $mask(!self.0)
            }
        }
        impl Mask for $mask {
            #[inline(always)]
            fn any(self) -> bool {
                self.0.any()
            }
            #[inline(always)]
            fn all(self) -> bool {
                self.0.all()
            }
        }

        impl Real for $name {
            type Mask = $mask;
            const LANES: usize = $n;

            #[inline(always)]
            fn splat(v: f64) -> Self {
                <$w>::splat($narrow(v))
            }
            #[inline(always)]
            fn lane(self, i: usize) -> f64 {
                f64::from(self.as_array()[i])
            }
            #[inline(always)]
            fn from_lanes(v: &[f64]) -> Self {
                let mut a = [$narrow(0.0); $n];
                for (i, x) in a.iter_mut().enumerate() {
                    *x = $narrow(v[i.min(v.len() - 1)]);
                }
                <$w>::new(a)
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$w>::sqrt(self)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$w>::abs(self)
            }
            #[inline(always)]
            fn min(self, o: Self) -> Self {
                <$w>::fast_min(self, o)
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                <$w>::fast_max(self, o)
            }
            #[inline(always)]
            fn floor(self) -> Self {
                <$w>::floor(self)
            }
            #[inline(always)]
            fn round(self) -> Self {
                // wide rounds half to even; match f64::round (half away from zero).
                let t = <$w>::trunc(self);
                let frac = self - t;
                let half = <$w>::splat(0.5);
                let up = frac.abs().simd_ge(half);
                up.select(t + self.signum(), t)
            }
            #[inline(always)]
            fn sin(self) -> Self {
                <$w>::sin(self)
            }
            #[inline(always)]
            fn cos(self) -> Self {
                <$w>::cos(self)
            }
            #[inline(always)]
            fn sin_cos(self) -> (Self, Self) {
                <$w>::sin_cos(self)
            }
            #[inline(always)]
            fn acos(self) -> Self {
                <$w>::acos(self)
            }
            #[inline(always)]
            fn asin(self) -> Self {
                <$w>::asin(self)
            }
            #[inline(always)]
            fn atan2(self, x: Self) -> Self {
                <$w>::atan2(self, x)
            }
            #[inline(always)]
            fn ln(self) -> Self {
                <$w>::ln(self)
            }
            #[inline(always)]
            fn exp(self) -> Self {
                <$w>::exp(self)
            }
            #[inline(always)]
            fn powf(self, e: Self) -> Self {
                (<$w>::ln(self) * e).exp()
            }
            #[inline(always)]
            fn signum(self) -> Self {
                <$w>::signum(self)
            }
            #[inline(always)]
            fn lt(self, o: Self) -> $mask {
                $mask(self.simd_lt(o))
            }
            #[inline(always)]
            fn le(self, o: Self) -> $mask {
                $mask(self.simd_le(o))
            }
            #[inline(always)]
            fn gt(self, o: Self) -> $mask {
                $mask(self.simd_gt(o))
            }
            #[inline(always)]
            fn ge(self, o: Self) -> $mask {
                $mask(self.simd_ge(o))
            }
            #[inline(always)]
            fn is_finite(self) -> $mask {
                $mask(<$w>::is_finite(self))
            }
            #[inline(always)]
            fn select(m: $mask, a: Self, b: Self) -> Self {
                m.0.select(a, b)
            }
        }
    };
}

/// `f64` to `f32`, rounding (the f32 packet's lane conversion).
#[inline(always)]
fn narrow_f32(x: f64) -> f32 {
    x as f32
}

/// Eight `f32` lanes (AVX2 on x86-64-v3), the packet type of the throughput path.
pub type F32x8 = wide::f32x8;
packet_real!(F32x8, wide::f32x8, Mask8, 8, narrow_f32);

/// Four `f64` lanes (AVX2). Its transcendental functions are `wide`'s, within a few ulps of
/// libm's (tested below), so results are close to the `f64` path but not bit-identical.
pub type F64x4 = wide::f64x4;
packet_real!(F64x4, wide::f64x4, Mask4, 4, std::convert::identity);

#[cfg(test)]
mod tests {
    use super::*;

    fn check_lanes(f: impl Fn(F32x8) -> F32x8, g: impl Fn(f64) -> f64, xs: [f64; 8], tol: f64) {
        let v = f(F32x8::from_lanes(&xs));
        for (i, &x) in xs.iter().enumerate() {
            let want = g(x);
            let got = v.lane(i);
            assert!(
                (want - got).abs() <= tol * (1.0 + want.abs()),
                "lane {i}: x={x} want {want} got {got}"
            );
        }
    }

    #[test]
    fn packet_functions_match_f64() {
        let xs = [-2.5, -1.5, -0.5, 0.0, 0.3, 0.5, 1.5, 2.49];
        check_lanes(<F32x8 as Real>::round, f64::round, xs, 1e-7);
        check_lanes(<F32x8 as Real>::floor, f64::floor, xs, 1e-7);
        check_lanes(<F32x8 as Real>::abs, f64::abs, xs, 1e-7);
        check_lanes(<F32x8 as Real>::sin, f64::sin, xs, 1e-6);
        check_lanes(<F32x8 as Real>::cos, f64::cos, xs, 1e-6);
        let unit = [-1.0, -0.9, -0.5, 0.0, 0.1, 0.5, 0.99, 1.0];
        check_lanes(<F32x8 as Real>::acos, f64::acos, unit, 1e-6);
        let pos = [1e-3, 0.1, 0.5, 1.0, 2.0, 7.5, 100.0, 1e4];
        check_lanes(<F32x8 as Real>::ln, f64::ln, pos, 1e-6);
        check_lanes(<F32x8 as Real>::sqrt, f64::sqrt, pos, 1e-7);
        check_lanes(
            |v| Real::powf(v, F32x8::splat(8.0)),
            |x| x.powf(8.0),
            pos,
            1e-5,
        );
        check_lanes(
            |v| Real::atan2(v, F32x8::splat(-0.7)),
            |y| y.atan2(-0.7),
            xs,
            1e-6,
        );
    }

    fn check_lanes4(f: impl Fn(F64x4) -> F64x4, g: impl Fn(f64) -> f64, xs: [f64; 4], tol: f64) {
        let v = f(F64x4::from_lanes(&xs));
        for (i, &x) in xs.iter().enumerate() {
            let want = g(x);
            let got = v.lane(i);
            assert!(
                (want - got).abs() <= tol * (1.0 + want.abs()),
                "lane {i}: x={x} want {want} got {got}"
            );
        }
    }

    #[test]
    fn f64_packet_functions_match_f64_to_a_few_ulps() {
        for xs in [[-2.5, -1.5, -0.5, 0.0], [0.3, 0.5, 1.5, 2.49]] {
            check_lanes4(<F64x4 as Real>::round, f64::round, xs, 0.0);
            check_lanes4(<F64x4 as Real>::floor, f64::floor, xs, 0.0);
            check_lanes4(<F64x4 as Real>::abs, f64::abs, xs, 0.0);
            check_lanes4(<F64x4 as Real>::sin, f64::sin, xs, 1e-15);
            check_lanes4(<F64x4 as Real>::cos, f64::cos, xs, 1e-15);
            check_lanes4(
                |v| Real::atan2(v, F64x4::splat(-0.7)),
                |y| y.atan2(-0.7),
                xs,
                1e-15,
            );
        }
        for unit in [[-1.0, -0.9, -0.5, 0.0], [0.1, 0.5, 0.99, 1.0]] {
            check_lanes4(<F64x4 as Real>::acos, f64::acos, unit, 1e-15);
        }
        for pos in [[1e-3, 0.1, 0.5, 1.0], [2.0, 7.5, 100.0, 1e4]] {
            check_lanes4(<F64x4 as Real>::ln, f64::ln, pos, 1e-15);
            check_lanes4(<F64x4 as Real>::sqrt, f64::sqrt, pos, 0.0);
            check_lanes4(
                |v| Real::powf(v, F64x4::splat(8.0)),
                |x| x.powf(8.0),
                pos,
                2e-14,
            );
        }
    }

    #[test]
    fn select_and_masks() {
        let a = F32x8::from_lanes(&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        let m = Real::lt(a, F32x8::splat(3.5));
        assert!(m.any() && !m.all());
        let s = <F32x8 as Real>::select(m, F32x8::splat(1.0), F32x8::splat(-1.0));
        assert_eq!(s.lane(3), 1.0);
        assert_eq!(s.lane(4), -1.0);
        assert!(1.0f64.lt(2.0).all());
    }
}
