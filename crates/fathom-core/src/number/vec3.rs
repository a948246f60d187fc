//! A three-component vector generic over [`Real`], so distance functions read like the maths on
//! both the scalar and the packet path. (glam covers the fixed `f32`/`f64` types elsewhere; it has
//! no vector of SIMD lanes.)

use crate::real::Real;
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// A point or direction; each component is a [`Real`] (a number or a packet of lanes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<S> {
    /// The x component.
    pub x: S,
    /// The y component.
    pub y: S,
    /// The z component.
    pub z: S,
}

impl<S: Real> V3<S> {
    /// A vector from its components.
    #[inline(always)]
    pub fn new(x: S, y: S, z: S) -> Self {
        V3 { x, y, z }
    }
    /// The same value in every component.
    #[inline(always)]
    pub fn splat(v: S) -> Self {
        V3 { x: v, y: v, z: v }
    }
    /// A constant vector broadcast to every lane.
    #[inline(always)]
    pub fn c(x: f64, y: f64, z: f64) -> Self {
        V3::new(S::splat(x), S::splat(y), S::splat(z))
    }
    /// The zero vector.
    #[inline(always)]
    pub fn zero() -> Self {
        V3::splat(S::zero())
    }
    /// The dot product.
    #[inline(always)]
    pub fn dot(self, o: Self) -> S {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// The cross product (right-handed).
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    /// The squared length (no square root).
    #[inline(always)]
    pub fn length2(self) -> S {
        self.dot(self)
    }
    /// The Euclidean length.
    #[inline(always)]
    pub fn length(self) -> S {
        self.dot(self).sqrt()
    }
    /// Componentwise absolute value.
    #[inline(always)]
    pub fn abs(self) -> Self {
        V3::new(self.x.abs(), self.y.abs(), self.z.abs())
    }
    /// Componentwise minimum.
    #[inline(always)]
    pub fn min(self, o: Self) -> Self {
        V3::new(self.x.min(o.x), self.y.min(o.y), self.z.min(o.z))
    }
    /// Componentwise maximum.
    #[inline(always)]
    pub fn max(self, o: Self) -> Self {
        V3::new(self.x.max(o.x), self.y.max(o.y), self.z.max(o.z))
    }
    /// Each component's maximum with the scalar `s`.
    #[inline(always)]
    pub fn maxs(self, s: S) -> Self {
        V3::new(self.x.max(s), self.y.max(s), self.z.max(s))
    }
    /// The largest component.
    #[inline(always)]
    pub fn max_elem(self) -> S {
        self.x.max(self.y).max(self.z)
    }
    /// The smallest component.
    #[inline(always)]
    pub fn min_elem(self) -> S {
        self.x.min(self.y).min(self.z)
    }
    /// Each component clamped to `[lo, hi]` componentwise.
    #[inline(always)]
    pub fn clamp(self, lo: Self, hi: Self) -> Self {
        self.max(lo).min(hi)
    }
    /// `f` applied to each component.
    #[inline(always)]
    pub fn map(self, f: impl Fn(S) -> S) -> Self {
        V3::new(f(self.x), f(self.y), f(self.z))
    }
    /// The vector scaled to unit length (not finite for the zero vector).
    #[inline(always)]
    pub fn normalize(self) -> Self {
        self * (S::one() / self.length())
    }
    /// Per lane: `m ? a : b`, for all three components.
    #[inline(always)]
    pub fn select(m: S::Mask, a: Self, b: Self) -> Self {
        V3::new(
            S::select(m, a.x, b.x),
            S::select(m, a.y, b.y),
            S::select(m, a.z, b.z),
        )
    }
    /// Lane `i` as a plain `f64` vector.
    pub fn lane(self, i: usize) -> [f64; 3] {
        [self.x.lane(i), self.y.lane(i), self.z.lane(i)]
    }
}

impl<S: Real> Add for V3<S> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl<S: Real> Sub for V3<S> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl<S: Real> AddAssign for V3<S> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<S: Real> SubAssign for V3<S> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}
impl<S: Real> Mul<S> for V3<S> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: S) -> Self {
        V3::new(self.x * s, self.y * s, self.z * s)
    }
}
/// Component-wise product.
impl<S: Real> Mul for V3<S> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        V3::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
}
impl<S: Real> Div<S> for V3<S> {
    type Output = Self;
    #[inline(always)]
    fn div(self, s: S) -> Self {
        let inv = S::one() / s;
        V3::new(self.x * inv, self.y * inv, self.z * inv)
    }
}
impl<S: Real> Neg for V3<S> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        V3::new(-self.x, -self.y, -self.z)
    }
}

impl From<glam::DVec3> for V3<f64> {
    fn from(v: glam::DVec3) -> Self {
        V3::new(v.x, v.y, v.z)
    }
}
impl From<V3<f64>> for glam::DVec3 {
    fn from(v: V3<f64>) -> Self {
        glam::DVec3::new(v.x, v.y, v.z)
    }
}
