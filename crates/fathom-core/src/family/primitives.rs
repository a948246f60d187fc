//! Primitive shapes: signed distance functions after Inigo Quilez's catalogue
//! (iquilezles.org/articles/distfunctions), each declared once with its parameters.
//!
//! Every primitive is centred at the origin in its local frame (y is up: cylinders, cones,
//! capsules and prisms run along y); placement comes from the node's domain operators.
//! `Exact` entries are the true Euclidean signed distance for every parameter value in range;
//! `Bound` entries are 1-Lipschitz and never larger in magnitude than the true distance (most of
//! them are exact outside, or exact for part of their parameter range, as their docs say).
//!
//! The code is branch-free (masks and `select`) so the same source runs on the f64 and the
//! f32x8 packet path. Parameter-only work that would need a square root or trigonometry on
//! every evaluation (angles, normalisations) is done once by a bake function; the baked slot
//! layout is named after `baked(...)` in each declaration.

use crate::real::Real;
use crate::vec3::V3;

const BIG: f64 = 1e6;
/// Guards divisions by parameter-derived lengths that may be zero.
use crate::shared::TINY;

crate::declare_family! {
    /// A signed-distance primitive.
    family Primitive, noun "primitive", table PRIMITIVES;
    fn distance(p: V3<S>) -> S;

    /// Nothing: infinitely far everywhere. A group node whose children carry the shape.
    Empty [Exact] () => S::splat(1e20);

    /// A sphere of the given radius.
    Sphere [Exact] (radius: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "radius")
        => p.length() - radius;

    /// An axis-aligned box; `size` holds the half-extents.
    Box [Exact] (size: Vec3 = [1.0, 1.0, 1.0], [0.0, BIG], soft [0.0, 4.0], "half-extents along x, y, z")
        => box3(p, size);

    /// A box with rounded edges: half-extents `size` (the outer extent), edges rounded by
    /// `radius`. A radius larger than a half-extent makes that extent equal to the radius.
    RoundBox [Exact] (
        size: Vec3 = [1.0, 1.0, 1.0], [0.0, BIG], soft [0.0, 4.0], "outer half-extents along x, y, z",
        radius: Scalar = 0.1, [0.0, BIG], soft [0.0, 1.0], "edge rounding radius",
    ) => box3(p, (size - V3::splat(radius)).maxs(S::zero())) - radius;

    /// The twelve edges of a box as square bars: outer half-extents `size`, bars `thickness`
    /// wide. Exact outside; inside, where bars overlap at the corners, a bound.
    BoxFrame [Bound] (
        size: Vec3 = [1.0, 1.0, 1.0], [0.0, BIG], soft [0.0, 4.0], "outer half-extents along x, y, z",
        thickness: Scalar = 0.1, [0.0, BIG], soft [0.0, 1.0], "width of each bar",
    ) => {
        let e = thickness * S::splat(0.5);
        let p = p.abs() - size;
        let q = (p + V3::splat(e)).abs() - V3::splat(e);
        box_q(p.x, q.y, q.z).min(box_q(q.x, p.y, q.z)).min(box_q(q.x, q.y, p.z))
    };

    /// A torus in the xz plane. Exact for `minor <= major` (a ring torus); for a self-
    /// intersecting spindle torus it is exact outside and a bound inside.
    Torus [Bound] (
        major: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "radius of the ring",
        minor: Scalar = 0.25, [0.0, BIG], soft [0.0, 1.0], "radius of the tube",
    ) => len2(len2(p.x, p.z) - major, p.y) - minor;

    /// A torus cut to an arc in the xy plane, symmetric about +y: the ring spans `angle`
    /// degrees either side of +y. Exact outside; inside exact while `minor` is small against
    /// `major` and the gap of the arc, a bound otherwise.
    CappedTorus [Bound] (
        angle: Scalar = 120.0, [0.0, 180.0], soft [0.0, 180.0], "half-aperture of the arc in degrees, from +y",
        major: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "radius of the ring",
        minor: Scalar = 0.2, [0.0, BIG], soft [0.0, 1.0], "radius of the tube",
    ) baked(bake_sin_cos_first) (sin_a: Scalar, cos_a: Scalar, major: Scalar, minor: Scalar)
        => {
            let px = p.x.abs();
            let beyond = (cos_a * px).gt(sin_a * p.y);
            let kk = S::select(beyond, px * sin_a + p.y * cos_a, len2(px, p.y));
            (p.length2() + major * major - S::splat(2.0) * major * kk).max(S::zero()).sqrt() - minor
        };

    /// A chain link: two half-tori of ring radius `major` joined by straight tubes, elongated
    /// along y by `half_length` either side. Exact for `minor <= major`, else a bound inside.
    Link [Bound] (
        half_length: Scalar = 0.5, [0.0, BIG], soft [0.0, 2.0], "half-length of the straight parts (along y)",
        major: Scalar = 0.5, [0.0, BIG], soft [0.0, 2.0], "radius of the ring",
        minor: Scalar = 0.15, [0.0, BIG], soft [0.0, 1.0], "radius of the tube",
    ) => {
        let qy = (p.y.abs() - half_length).max(S::zero());
        len2(len2(p.x, qy) - major, p.z) - minor
    };

    /// An infinite cylinder along y.
    Cylinder [Exact] (radius: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "radius")
        => len2(p.x, p.z) - radius;

    /// A cylinder along y capped at `y = ±half_height`.
    CappedCylinder [Exact] (
        radius: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "radius",
        half_height: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "half of the height (along y)",
    ) => box_q2(len2(p.x, p.z) - radius, p.y.abs() - half_height);

    /// A capped cylinder along y with edges rounded by `rounding` (outer radius and
    /// half-height as given).
    RoundedCylinder [Exact] (
        radius: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "outer radius",
        half_height: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "outer half-height (along y)",
        rounding: Scalar = 0.1, [0.0, BIG], soft [0.0, 1.0], "edge rounding radius",
    ) => box_q2(
        len2(p.x, p.z) - (radius - rounding).max(S::zero()),
        p.y.abs() - (half_height - rounding).max(S::zero()),
    ) - rounding;

    /// A cone along y: base disc of `radius` at `y = -half_height`, tip at `y = +half_height`.
    Cone [Exact] (
        radius: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "radius of the base",
        half_height: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "half of the height (along y)",
    ) => capped_cone(p, half_height, radius, S::zero());

    /// A frustum along y: radius `bottom` at `y = -half_height`, `top` at `y = +half_height`.
    CappedCone [Exact] (
        half_height: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "half of the height (along y)",
        bottom: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "radius at the bottom",
        top: Scalar = 0.5, [0.0, BIG], soft [0.0, 2.0], "radius at the top",
    ) => capped_cone(p, half_height, bottom, top);

    /// The convex hull of two spheres on the y axis: radius `bottom` centred at
    /// `y = -half_height`, radius `top` at `y = +half_height`.
    RoundCone [Exact] (
        bottom: Scalar = 0.5, [0.0, BIG], soft [0.0, 2.0], "radius of the bottom sphere",
        top: Scalar = 0.25, [0.0, BIG], soft [0.0, 1.0], "radius of the top sphere",
        half_height: Scalar = 0.5, [0.0, BIG], soft [0.0, 2.0], "half the distance between the sphere centres",
    ) => {
        let h = half_height * S::splat(2.0);
        let b = ((bottom - top) / h.max(S::splat(TINY))).clamp(-S::one(), S::one());
        let a = (S::one() - b * b).max(S::zero()).sqrt();
        let qx = len2(p.x, p.z);
        let qy = p.y + half_height;
        let kk = a * qy - b * qx;
        let d1 = len2(qx, qy) - bottom;
        let d2 = len2(qx, qy - h) - top;
        let dm = qx * a + qy * b - bottom;
        let hull = S::select(kk.lt(S::zero()), d1, S::select(kk.gt(a * h), d2, dm));
        // One sphere inside the other: the hull is the larger sphere.
        S::select((bottom - top).abs().ge(h), d1.min(d2), hull)
    };

    /// An infinite plane through the origin with the given normal (need not be unit length;
    /// zero means +y).
    Plane [Exact] (normal: Vec3 = [0.0, 1.0, 0.0], [-BIG, BIG], soft [-1.0, 1.0], "normal direction")
        baked(bake_unit_normal) (unit: Vec3)
        => p.dot(unit);

    /// A hexagonal prism along y: `radius` is the inradius of the hexagon (centre to flat
    /// side), which has two flat sides facing ±z.
    HexPrism [Exact] (
        radius: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "inradius of the hexagon",
        half_height: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "half of the height (along y)",
    ) => {
        let (kx, ky, kz) = (S::splat(-0.866_025_403_784_438_6), S::splat(0.5), S::splat(0.577_350_269_189_625_8));
        let (mut ax, mut az) = (p.x.abs(), p.z.abs());
        let t = S::splat(2.0) * (kx * ax + ky * az).min(S::zero());
        ax -= t * kx;
        az -= t * ky;
        let cx = ax.clamp(-kz * radius, kz * radius);
        let l = len2(ax - cx, az - radius);
        box_q2(S::select(az.lt(radius), -l, l), p.y.abs() - half_height)
    };

    /// A triangular prism along y: an equilateral triangle of side `2 * half_side` in the xz
    /// plane (centroid at the origin, one vertex towards +z), extruded by `half_height`.
    TriPrism [Exact] (
        half_side: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "half of the side length of the triangle",
        half_height: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "half of the height (along y)",
    ) => box_q2(equilateral_triangle(p.x, p.z, half_side), p.y.abs() - half_height);

    /// A capsule along y: the segment from `y = -half_height` to `+half_height`, thickened
    /// by `radius`.
    Capsule [Exact] (
        radius: Scalar = 0.5, [0.0, BIG], soft [0.0, 2.0], "radius",
        half_height: Scalar = 0.5, [0.0, BIG], soft [0.0, 2.0], "half-length of the axis segment",
    ) => {
        let qy = p.y - p.y.clamp(-half_height, half_height);
        V3::new(p.x, qy, p.z).length() - radius
    };

    /// A capsule around the segment from `a` to `b`.
    CapsuleSegment [Exact] (
        a: Vec3 = [-0.5, 0.0, 0.0], [-BIG, BIG], soft [-2.0, 2.0], "first end of the segment",
        b: Vec3 = [0.5, 0.0, 0.0], [-BIG, BIG], soft [-2.0, 2.0], "second end of the segment",
        radius: Scalar = 0.25, [0.0, BIG], soft [0.0, 1.0], "radius",
    ) => segment_dist2(p, a, b).sqrt() - radius;

    /// A spherical sector (an ice-cream cone): the part of a sphere of `radius` within
    /// `angle` degrees of +y, tip at the origin.
    SolidAngle [Exact] (
        angle: Scalar = 30.0, [0.0, 180.0], soft [0.0, 180.0], "half-aperture in degrees, from +y",
        radius: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "radius of the sphere",
    ) baked(bake_sin_cos_first) (sin_a: Scalar, cos_a: Scalar, radius: Scalar)
        => {
            let qx = len2(p.x, p.z);
            let qy = p.y;
            let l = len2(qx, qy) - radius;
            let t = (qx * sin_a + qy * cos_a).clamp(S::zero(), radius);
            let m = len2(qx - sin_a * t, qy - cos_a * t);
            let s = cos_a * qx - sin_a * qy;
            l.max(S::select(s.lt(S::zero()), -m, m))
        };

    /// The part of a sphere above the plane `y = cut` (a flat bottom; `cut <= -radius` keeps
    /// the whole sphere, `cut >= radius` leaves a point).
    CutSphere [Exact] (
        radius: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "radius of the sphere",
        cut: Scalar = 0.5, [-BIG, BIG], soft [-2.0, 2.0], "height of the cutting plane",
    ) baked(bake_cut_sphere) (radius: Scalar, h: Scalar, w: Scalar)
        => {
            let qx = len2(p.x, p.z);
            let qy = p.y;
            let s = ((h - radius) * qx * qx + w * w * (h + radius - S::splat(2.0) * qy))
                .max(h * qx - w * qy);
            let ds = len2(qx, qy) - radius;
            let cut_d = S::select(qx.lt(w), h - qy, len2(qx - w, qy - h));
            let d = S::select(s.lt(S::zero()), ds, cut_d);
            S::select(h.le(-radius), ds, d)
        };

    /// A spherical shell of `radius` and half-thickness `thickness`, with the cap above
    /// `y = cut` removed (an open bowl; `cut >= radius` keeps the whole shell). Exact outside;
    /// a bound inside when the shell is thick against the opening.
    CutHollowSphere [Bound] (
        radius: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "radius of the sphere",
        cut: Scalar = 0.5, [-BIG, BIG], soft [-2.0, 2.0], "height of the cutting plane",
        thickness: Scalar = 0.05, [0.0, BIG], soft [0.0, 1.0], "half-thickness of the shell",
    ) baked(bake_cut_hollow_sphere) (radius: Scalar, h: Scalar, w: Scalar, thickness: Scalar)
        => {
            let qx = len2(p.x, p.z);
            let qy = p.y;
            let rim = (h * qx).lt(w * qy);
            S::select(rim, len2(qx - w, qy - h), (len2(qx, qy) - radius).abs()) - thickness
        };

    /// A sphere of `radius` with a bite: the sphere of `cut_radius` centred at
    /// `(offset, 0, 0)` is carved out. Exact when the spheres' surfaces intersect, otherwise
    /// a bound.
    DeathStar [Bound] (
        radius: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "radius of the main sphere",
        cut_radius: Scalar = 0.8, [0.0, BIG], soft [0.0, 4.0], "radius of the carved-out sphere",
        offset: Scalar = 1.2, [0.0, BIG], soft [0.0, 5.0], "distance of the carved sphere's centre along +x",
    ) baked(bake_death_star) (radius: Scalar, cut_radius: Scalar, offset: Scalar, ca: Scalar, cb: Scalar)
        => {
            let qx = p.x;
            let qy = len2(p.y, p.z);
            let rim = (qx * cb - qy * ca).gt(offset * (cb - qy).max(S::zero()));
            let carved = (len2(qx, qy) - radius).max(cut_radius - len2(qx - offset, qy));
            S::select(rim, len2(qx - ca, qy - cb), carved)
        };

    /// An axis-aligned ellipsoid with semi-axes `radii`, by the larger of two provable bounds:
    /// `(|p / radii| - 1) * min(radii)` and `|p| - max(radii)`. (iq's sharper
    /// `k0 (k0 - 1) / k1` is not 1-Lipschitz: the tests found slopes above 1.03.) Exact on the
    /// longest and shortest axes' ends for a sphere; an underestimate elsewhere.
    Ellipsoid [Bound] (radii: Vec3 = [1.0, 0.5, 0.75], [0.0, BIG], soft [0.0, 4.0], "semi-axes along x, y, z")
        baked(bake_ellipsoid) (inv_r: Vec3, min_r: Scalar, max_r: Scalar)
        => (((p * inv_r).length() - S::one()) * min_r).max(p.length() - max_r);

    /// A rhombus slab: half-diagonals `half_x` and `half_z` in the xz plane, half-thickness
    /// `half_height` along y, the outline grown by `radius` (rounded corners).
    Rhombus [Exact] (
        half_x: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "half-diagonal along x",
        half_z: Scalar = 0.5, [0.0, BIG], soft [0.0, 2.0], "half-diagonal along z",
        half_height: Scalar = 0.1, [0.0, BIG], soft [0.0, 1.0], "half-thickness along y",
        radius: Scalar = 0.05, [0.0, BIG], soft [0.0, 1.0], "rounding of the outline",
    ) => {
        let (ax, ay, az) = (p.x.abs(), p.y.abs(), p.z.abs());
        let bb = (half_x * half_x + half_z * half_z).max(S::splat(TINY));
        let nd = half_x * (half_x - S::splat(2.0) * ax) - half_z * (half_z - S::splat(2.0) * az);
        let f = (nd / bb).clamp(-S::one(), S::one());
        let h = S::splat(0.5);
        let l = len2(ax - h * half_x * (S::one() - f), az - h * half_z * (S::one() + f));
        let s = ax * half_z + az * half_x - half_x * half_z;
        box_q2(S::select(s.lt(S::zero()), -l, l) - radius, ay - half_height)
    };

    /// A regular octahedron with vertices at distance `size` on the axes.
    Octahedron [Exact] (size: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "centre-to-vertex distance") => {
        let a = p.abs();
        let m = a.x + a.y + a.z - size;
        let three = S::splat(3.0);
        let c1 = (three * a.x).lt(m);
        let c2 = (three * a.y).lt(m);
        let c3 = (three * a.z).lt(m);
        let q = V3::select(c1, a, V3::select(c2, V3::new(a.y, a.z, a.x), V3::new(a.z, a.x, a.y)));
        let kk = (S::splat(0.5) * (q.z - q.y + size)).clamp(S::zero(), size);
        let edge = V3::new(q.x, q.y - size + kk, q.z - kk).length();
        S::select(c1 | c2 | c3, edge, m * S::splat(0.577_350_269_189_625_8))
    };

    /// A regular octahedron like `Octahedron`, by the cheap plane bound (exact on the faces'
    /// normal cones, an underestimate near edges and vertices).
    OctahedronBound [Bound] (size: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "centre-to-vertex distance")
        => (p.x.abs() + p.y.abs() + p.z.abs() - size) * S::splat(0.577_350_269_189_625_8);

    /// A square pyramid: base of side `base` in the plane `y = -height / 2`, apex at
    /// `y = +height / 2`.
    Pyramid [Exact] (
        base: Scalar = 1.0, [1e-6, BIG], soft [0.01, 4.0], "side length of the square base",
        height: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "height (along y)",
    ) => {
        let inv = S::one() / base;
        let h = height * inv;
        let half = S::splat(0.5);
        let m2 = h * h + S::splat(0.25);
        let (ax, az) = (p.x.abs() * inv, p.z.abs() * inv);
        let py = (p.y * inv) + h * half;
        let sw = az.gt(ax);
        let px = S::select(sw, az, ax) - half;
        let pz = S::select(sw, ax, az) - half;
        let qx = pz;
        let qy = h * py - half * px;
        let qz = h * px + half * py;
        let s = (-qx).max(S::zero());
        let t = ((qy - half * pz) / (m2 + S::splat(0.25))).clamp(S::zero(), S::one());
        let a = m2 * (qx + s) * (qx + s) + qy * qy;
        let bq = qx + half * t;
        let by = qy - m2 * t;
        let b = m2 * bq * bq + by * by;
        let d2 = S::select(qy.min(-qx * m2 - qy * half).gt(S::zero()), S::zero(), a.min(b));
        // iq's formula measures the slanted faces only; the base is added here: below the
        // base plane the nearest point is on the base square, inside the depth is at most
        // the height above the base.
        let lateral = ((d2 + qz * qz) / m2).sqrt();
        let inside = qz.max(-py).lt(S::zero());
        let (bx, bz) = ((ax - half).max(S::zero()), (az - half).max(S::zero()));
        let below = (bx * bx + bz * bz + py * py).sqrt();
        let d = S::select(py.lt(S::zero()), below, S::select(inside, (-lateral).max(-py), lateral));
        d * base
    };

    /// A flat triangle with corners `a`, `b`, `c` (unsigned distance: it has no inside).
    Triangle [Exact] (
        a: Vec3 = [0.0, 1.0, 0.0], [-BIG, BIG], soft [-4.0, 4.0], "first corner",
        b: Vec3 = [-0.866_025_403_784_438_6, -0.5, 0.0], [-BIG, BIG], soft [-4.0, 4.0], "second corner",
        c: Vec3 = [0.866_025_403_784_438_6, -0.5, 0.0], [-BIG, BIG], soft [-4.0, 4.0], "third corner",
    ) => triangle_dist2(p, a, b, c).sqrt();

    /// A flat quadrilateral with corners `a`, `b`, `c`, `d` in order, made of the triangles
    /// `abc` and `acd` (so a non-planar quad is a folded pair of triangles); unsigned.
    Quad [Exact] (
        a: Vec3 = [-1.0, 0.0, -1.0], [-BIG, BIG], soft [-4.0, 4.0], "first corner",
        b: Vec3 = [1.0, 0.0, -1.0], [-BIG, BIG], soft [-4.0, 4.0], "second corner",
        c: Vec3 = [1.0, 0.0, 1.0], [-BIG, BIG], soft [-4.0, 4.0], "third corner",
        d: Vec3 = [-1.0, 0.0, 1.0], [-BIG, BIG], soft [-4.0, 4.0], "fourth corner",
    ) => triangle_dist2(p, a, b, c).min(triangle_dist2(p, a, c, d)).sqrt();

    /// A lens (vesica) revolved about y: tips at `y = ±half_height`, widest (`half_width`) at
    /// `y = 0`. `half_width` is clamped to [half_height / 1000, half_height] (a lens of two
    /// equal arcs is never wider than tall).
    Vesica [Exact] (
        half_width: Scalar = 0.5, [0.0, BIG], soft [0.0, 2.0], "radius at the equator",
        half_height: Scalar = 1.0, [0.0, BIG], soft [0.0, 4.0], "distance from the centre to each tip",
    ) baked(bake_vesica) (arc_radius: Scalar, arc_offset: Scalar, tip: Scalar)
        => {
            let qx = len2(p.x, p.z);
            let qy = p.y.abs();
            let to_tip = ((qy - tip) * arc_offset).gt(qx * tip);
            S::select(to_tip, len2(qx, qy - tip), len2(qx + arc_offset, qy) - arc_radius)
        };

    /// An infinite cone with its tip at the origin, opening towards +y with half-aperture
    /// `angle` degrees.
    InfiniteCone [Exact] (angle: Scalar = 30.0, [0.0, 90.0], soft [0.0, 90.0], "half-aperture in degrees, from +y")
        baked(bake_sin_cos_first) (sin_a: Scalar, cos_a: Scalar)
        => {
            let qx = len2(p.x, p.z);
            let qy = p.y;
            let t = (qx * sin_a + qy * cos_a).max(S::zero());
            let d = len2(qx - sin_a * t, qy - cos_a * t);
            S::select((qx * cos_a - qy * sin_a).lt(S::zero()), -d, d)
        };

    /// An infinite slab `|y| <= half_thickness`.
    Slab [Exact] (half_thickness: Scalar = 0.5, [0.0, BIG], soft [0.0, 2.0], "half of the thickness (along y)")
        => p.y.abs() - half_thickness;
}

/// `sqrt(x^2 + y^2)`.
#[inline(always)]
fn len2<S: Real>(x: S, y: S) -> S {
    (x * x + y * y).sqrt()
}

/// The box distance from per-axis signed offsets `(x, y, z)` (positive outside each slab).
#[inline(always)]
fn box_q<S: Real>(x: S, y: S, z: S) -> S {
    let z0 = S::zero();
    V3::new(x.max(z0), y.max(z0), z.max(z0)).length() + x.max(y).max(z).min(z0)
}

/// The 2D box distance from two signed offsets; also the exact extrusion of a 2D distance `x`
/// by a slab offset `y`.
#[inline(always)]
fn box_q2<S: Real>(x: S, y: S) -> S {
    let z0 = S::zero();
    len2(x.max(z0), y.max(z0)) + x.max(y).min(z0)
}

/// Exact box with half-extents `size`.
#[inline(always)]
fn box3<S: Real>(p: V3<S>, size: V3<S>) -> S {
    let q = p.abs() - size;
    box_q(q.x, q.y, q.z)
}

/// Exact frustum along y: radius `r1` at `y = -h`, `r2` at `y = +h` (iq's sdCappedCone).
#[inline(always)]
fn capped_cone<S: Real>(p: V3<S>, h: S, r1: S, r2: S) -> S {
    let qx = len2(p.x, p.z);
    let qy = p.y;
    let (k2x, k2y) = (r2 - r1, S::splat(2.0) * h);
    let ca_x = qx - qx.min(S::select(qy.lt(S::zero()), r1, r2));
    let ca_y = qy.abs() - h;
    let k2k2 = (k2x * k2x + k2y * k2y).max(S::splat(TINY));
    let t = (((r2 - qx) * k2x + (h - qy) * k2y) / k2k2).clamp(S::zero(), S::one());
    let cb_x = qx - r2 + k2x * t;
    let cb_y = qy - h + k2y * t;
    let inside = cb_x.lt(S::zero()) & ca_y.lt(S::zero());
    let d = (ca_x * ca_x + ca_y * ca_y)
        .min(cb_x * cb_x + cb_y * cb_y)
        .sqrt();
    S::select(inside, -d, d)
}

/// Exact 2D distance to an equilateral triangle of side `2 r`, centroid at the origin, one
/// vertex towards +y (iq's sdEquilateralTriangle).
#[inline(always)]
fn equilateral_triangle<S: Real>(x: S, y: S, r: S) -> S {
    let k = S::splat(1.732_050_807_568_877_2);
    let half = S::splat(0.5);
    let x = x.abs() - r;
    let y = y + r / k;
    let flip = (x + k * y).gt(S::zero());
    let (x, y) = (
        S::select(flip, (x - k * y) * half, x),
        S::select(flip, (-k * x - y) * half, y),
    );
    let x = x - x.clamp(-S::splat(2.0) * r, S::zero());
    let l = len2(x, y);
    S::select(y.gt(S::zero()), -l, l)
}

/// Squared distance from `p` to the segment `ab`.
#[inline(always)]
fn segment_dist2<S: Real>(p: V3<S>, a: V3<S>, b: V3<S>) -> S {
    let pa = p - a;
    let ba = b - a;
    let h = (pa.dot(ba) / ba.length2().max(S::splat(TINY))).clamp(S::zero(), S::one());
    (pa - ba * h).length2()
}

/// Squared distance from `p` to the triangle `abc` (iq's udTriangle); degenerate triangles
/// fall back to the edges.
#[inline(always)]
fn triangle_dist2<S: Real>(p: V3<S>, a: V3<S>, b: V3<S>, c: V3<S>) -> S {
    let ba = b - a;
    let cb = c - b;
    let ac = a - c;
    let pa = p - a;
    let pb = p - b;
    let pc = p - c;
    let nor = ba.cross(ac);
    let z0 = S::zero();
    let inside =
        ba.cross(nor).dot(pa).gt(z0) & cb.cross(nor).dot(pb).gt(z0) & ac.cross(nor).dot(pc).gt(z0);
    let edge = |e: V3<S>, q: V3<S>| {
        let t = (e.dot(q) / e.length2().max(S::splat(TINY))).clamp(z0, S::one());
        (e * t - q).length2()
    };
    let edges = edge(ba, pa).min(edge(cb, pb)).min(edge(ac, pc));
    let np = nor.dot(pa);
    let face = np * np / nor.length2().max(S::splat(TINY));
    S::select(inside, face, edges)
}

/// `[angle_degrees, rest...]` -> `[sin, cos, rest...]`.
fn bake_sin_cos_first(user: &[f64], out: &mut Vec<f64>) {
    let (s, c) = user[0].to_radians().sin_cos();
    out.extend_from_slice(&[s, c]);
    out.extend_from_slice(&user[1..]);
}

/// A normal direction to a unit vector (zero becomes +y).
fn bake_unit_normal(user: &[f64], out: &mut Vec<f64>) {
    let n = glam::DVec3::new(user[0], user[1], user[2]);
    let u = if n.length_squared() > 0.0 {
        n.normalize()
    } else {
        glam::DVec3::Y
    };
    out.extend_from_slice(&[u.x, u.y, u.z]);
}

/// `[radius, cut]` -> `[radius, h, w]` with `h` clamped to `[-radius, radius]` and `w` the
/// radius of the cut disc.
fn bake_cut_sphere(user: &[f64], out: &mut Vec<f64>) {
    let r = user[0];
    let h = user[1].clamp(-r, r);
    // Exactly at `-r` the formula's axis case is wrong; the code selects the sphere there.
    out.extend_from_slice(&[r, h, (r * r - h * h).max(0.0).sqrt()]);
}

/// `[radius, cut, thickness]` -> `[radius, h, w, thickness]`.
fn bake_cut_hollow_sphere(user: &[f64], out: &mut Vec<f64>) {
    bake_cut_sphere(&user[..2], out);
    out.push(user[2]);
}

/// `[ra, rb, d]` -> `[ra, rb, d, a, b]`: `(a, b)` is the rim where the spheres meet (in the
/// meridian plane).
fn bake_death_star(user: &[f64], out: &mut Vec<f64>) {
    let (ra, rb) = (user[0], user[1]);
    let d = user[2].max(1e-9);
    let a = (ra * ra - rb * rb + d * d) / (2.0 * d);
    let b = (ra * ra - a * a).max(0.0).sqrt();
    out.extend_from_slice(&[ra, rb, d, a, b]);
}

/// Semi-axes -> their reciprocals, the smallest and the largest (zero axes become 1e-9).
fn bake_ellipsoid(user: &[f64], out: &mut Vec<f64>) {
    let r: Vec<f64> = user.iter().map(|&v| v.max(1e-9)).collect();
    out.extend(r.iter().map(|v| 1.0 / v));
    out.push(r.iter().copied().fold(f64::INFINITY, f64::min));
    out.push(r.iter().copied().fold(0.0, f64::max));
}

/// `[half_width, half_height]` -> `[arc radius, arc centre offset, tip height]`.
fn bake_vesica(user: &[f64], out: &mut Vec<f64>) {
    let b = user[1];
    let w = user[0].clamp(1e-3 * b, b);
    if b <= 0.0 {
        out.extend_from_slice(&[0.0, 0.0, 0.0]);
        return;
    }
    let r = (b * b + w * w) / (2.0 * w);
    out.extend_from_slice(&[r, r - w, b]);
}

#[cfg(test)]
pub(crate) mod testkit;
#[cfg(test)]
mod tests;
