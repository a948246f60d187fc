//! Primitive shapes: signed distance functions after Inigo Quilez's catalogue
//! (iquilezles.org/articles/distfunctions), each declared once with its parameters.
//!
//! Every primitive is centred at the origin in its local frame; placement comes from the node's
//! domain operators. `Exact` entries are true Euclidean distances, `Bound` entries are
//! conservative (never larger than the true distance).

use crate::vec3::V3;

const BIG: f64 = 1e6;

crate::declare_family! {
    /// A signed-distance primitive.
    family Primitive, noun "primitive", table PRIMITIVES;
    fn distance(p: V3<S>) -> S;

    /// Nothing: infinitely far everywhere. A group node whose children carry the shape.
    Empty [Exact] () => S::splat(1e20);

    /// A sphere of the given radius.
    Sphere [Exact] (radius: Scalar = 1.0, [0.0, BIG], "radius")
        => p.length() - radius;

    /// An axis-aligned box; `size` holds the half-extents.
    Box [Exact] (size: Vec3 = [1.0, 1.0, 1.0], [0.0, BIG], "half-extents along x, y, z")
        => {
            let q = p.abs() - size;
            q.maxs(S::zero()).length() + q.max_elem().min(S::zero())
        };

    /// A torus in the xz plane.
    Torus [Exact] (
        major: Scalar = 1.0, [0.0, BIG], "radius of the ring",
        minor: Scalar = 0.25, [0.0, BIG], "radius of the tube",
    ) => {
        let qx = (p.x * p.x + p.z * p.z).sqrt() - major;
        (qx * qx + p.y * p.y).sqrt() - minor
    };

    /// An infinite plane through the origin with the given normal (need not be unit length).
    Plane [Exact] (normal: Vec3 = [0.0, 1.0, 0.0], [-BIG, BIG], "normal direction")
        => p.dot(normal.normalize());
}
