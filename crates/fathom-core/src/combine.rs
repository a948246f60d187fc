//! Combine operators: how a child's value joins its parent's, on the edge between them.
//!
//! `a` is the parent's accumulated value, `b` the child's. Hard combines keep the winner's
//! material; smooth combines (polynomial smooth min/max with blend radius `k`) blend materials.

use crate::value::Value;

const BIG: f64 = 1e6;

crate::declare_family! {
    /// A combine operator on the edge from a child to its parent.
    family Combine, noun "combine operator", table COMBINES;
    fn combine(a: Value<S>, b: Value<S>) -> Value<S>;

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
    SmoothUnion [Bound] (k: Scalar = 0.25, [1e-6, BIG], "blend radius") => {
        let h = (S::splat(0.5) + S::splat(0.5) * (b.d - a.d) / k).clamp(S::zero(), S::one());
        let d = S::lerp(b.d, a.d, h) - k * h * (S::one() - h);
        Value::blend(d, a, b, h)
    };

    /// Smooth subtraction with blend radius `k`: the child carved out of the parent.
    SmoothSubtract [Bound] (k: Scalar = 0.25, [1e-6, BIG], "blend radius") => {
        let h = (S::splat(0.5) - S::splat(0.5) * (a.d + b.d) / k).clamp(S::zero(), S::one());
        let d = S::lerp(a.d, -b.d, h) + k * h * (S::one() - h);
        Value::blend(d, b, a, h)
    };

    /// Smooth intersection with blend radius `k`.
    SmoothIntersect [Bound] (k: Scalar = 0.25, [1e-6, BIG], "blend radius") => {
        let h = (S::splat(0.5) - S::splat(0.5) * (b.d - a.d) / k).clamp(S::zero(), S::one());
        let d = S::lerp(b.d, a.d, h) + k * h * (S::one() - h);
        Value::blend(d, a, b, h)
    };
}
