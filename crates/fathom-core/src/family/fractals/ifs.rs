//! Kaleidoscopic IFS fractals (Knighty, fractalforums 2010, as in Fragmentarium): each iteration
//! folds space onto a fundamental domain of a symmetry group, optionally rotates, and scales
//! about `offset` by `scale`, so the copies of the whole sit at `offset`'s images. The estimate
//! is a distance bound of a base solid at the final point divided by `scale^n`.
//!
//! All folds here are continuous and 1-Lipschitz (abs, sorting networks of min/max, and
//! `p -= 2 min(p.n, 0) n` mirrors), which is what makes every estimate a bound for any
//! parameter values (see the module doc of [`super`]).

use crate::real::{Mask, Real};
use crate::vec3::V3;

/// Squared radius beyond which a lane stops iterating (its point only grows from there).
use crate::shared::IFS_BAIL2 as BAIL2;

/// `1 / sqrt(3)`.
const INV_SQRT3: f64 = 0.577_350_269_189_625_8;

/// The shared escape loop: runs `step` until `iterations` or until every lane left radius
/// 1e4, then returns `last(z) / scale^k` (k = iterations a lane ran) and the orbit trap
/// (smallest `|z|`, starting point included).
#[inline(always)]
pub(super) fn ifs_loop<S: Real>(
    p: V3<S>,
    iterations: usize,
    scale: S,
    step: impl Fn(V3<S>) -> V3<S>,
    last: impl Fn(V3<S>) -> S,
) -> (S, S) {
    let bail2 = S::splat(BAIL2);
    let inv = S::one() / scale;
    let mut z = p;
    let mut k = S::one();
    let mut r2 = z.length2();
    let mut trap = r2;
    let mut active = r2.lt(bail2);
    for _ in 0..iterations {
        if !active.any() {
            break;
        }
        let nz = step(z);
        z = V3::select(active, nz, z);
        k = S::select(active, k * inv, k);
        r2 = z.length2();
        trap = S::select(active, trap.min(r2), trap);
        active = active & r2.lt(bail2);
    }
    (last(z) * k, trap.sqrt())
}

/// `p * scale - offset * (scale - 1)`: the contraction towards `offset`, inverted.
#[inline(always)]
fn scale_about<S: Real>(p: V3<S>, scale: S, offset: V3<S>) -> V3<S> {
    p * scale - offset * (scale - S::one())
}

/// Sorts the components so that `x >= y >= z` (a three-comparator network of min/max).
#[inline(always)]
fn sort_desc<S: Real>(p: V3<S>) -> V3<S> {
    let (x, y) = (p.x.max(p.y), p.x.min(p.y));
    let (x, z) = (x.max(p.z), x.min(p.z));
    let (y, z) = (y.max(z), y.min(z));
    V3::new(x, y, z)
}

/// Exact signed distance to the box `[-1, 1]^3`.
#[inline(always)]
fn unit_box<S: Real>(p: V3<S>) -> S {
    let q = p.abs() - V3::splat(S::one());
    q.maxs(S::zero()).length() + q.max_elem().min(S::zero())
}

/// The Menger sponge: abs + sort folds, scale about `offset`, then the middle cut along z
/// (Knighty's `if z < -c: z += 2c`, `c = offset.z (scale - 1) / 2`, written as the
/// equivalent mirror `z = |z + c| - c`, which is continuous). Base solid: the cube `[-1,1]^3`.
#[inline(always)]
pub(super) fn menger<S: Real>(p: V3<S>, iterations: usize, scale: S, offset: V3<S>) -> (S, S) {
    let cut = S::splat(0.5) * offset.z * (scale - S::one());
    ifs_loop(
        p,
        iterations,
        scale,
        |z| {
            let mut q = scale_about(sort_desc(z.abs()), scale, offset);
            q.z = (q.z + cut).abs() - cut;
            q
        },
        unit_box,
    )
}

/// The tetrahedron with vertices (1,1,1), (-1,-1,1), (1,-1,-1), (-1,1,-1): the largest of its
/// four face-plane distances (exact inside and facing a face, a bound near edges and corners).
#[inline(always)]
fn tetrahedron<S: Real>(p: V3<S>) -> S {
    let a = (p.x + p.y - p.z).max(p.x - p.y + p.z);
    let b = (p.y + p.z - p.x).max(-(p.x + p.y + p.z));
    (a.max(b) - S::one()) * S::splat(INV_SQRT3)
}

/// Mirrors `(a, b)` to `(-b, -a)` where `a + b < 0`: the fold across the plane `a + b = 0`.
#[inline(always)]
fn fold_sum<S: Real>(a: S, b: S) -> (S, S) {
    let m = (a + b).lt(S::zero());
    (S::select(m, -b, a), S::select(m, -a, b))
}

/// The Sierpinski tetrahedron: the three plane folds `x+y<0`, `x+z<0`, `y+z<0` bring every
/// point into the region nearest the vertex (1,1,1) (checked in the tests), then scale about
/// `offset`. Base solid: the tetrahedron of [`tetrahedron`].
#[inline(always)]
pub(super) fn sierpinski<S: Real>(p: V3<S>, iterations: usize, scale: S, offset: V3<S>) -> (S, S) {
    ifs_loop(
        p,
        iterations,
        scale,
        |z| {
            let (x, y) = fold_sum(z.x, z.y);
            let (x, zz) = fold_sum(x, z.z);
            let (y, zz) = fold_sum(y, zz);
            scale_about(V3::new(x, y, zz), scale, offset)
        },
        tetrahedron,
    )
}

/// User parameters (iterations, scale, offset, rotation in degrees) to the buffer layout
/// (iterations, scale, offset, then the three rows of `Rz Ry Rx`).
pub(super) fn bake_kifs(user: &[f64], out: &mut Vec<f64>) {
    out.extend_from_slice(&user[..5]);
    let [ax, ay, az] = [user[5], user[6], user[7]].map(f64::to_radians);
    let m = glam::DMat3::from_rotation_z(az)
        * glam::DMat3::from_rotation_y(ay)
        * glam::DMat3::from_rotation_x(ax);
    for i in 0..3 {
        out.extend_from_slice(&m.row(i).to_array());
    }
}

/// Applies the baked rotation (rows) unless it is the identity (checked once per call).
#[inline(always)]
fn rotator<S: Real>(rows: [V3<S>; 3]) -> impl Fn(V3<S>) -> V3<S> {
    let identity = rows[0].x.lane(0) == 1.0 && rows[1].y.lane(0) == 1.0 && rows[2].z.lane(0) == 1.0;
    move |p| {
        if identity {
            p
        } else {
            V3::new(rows[0].dot(p), rows[1].dot(p), rows[2].dot(p))
        }
    }
}

/// Octahedral KIFS: abs + sort folds (the 48 symmetries of the cube), rotation, scale about
/// `offset`. Base solid: the octahedron `|x| + |y| + |z| <= 1`.
#[inline(always)]
pub(super) fn kifs_octahedron<S: Real>(
    p: V3<S>,
    iterations: usize,
    scale: S,
    offset: V3<S>,
    rot: [V3<S>; 3],
) -> (S, S) {
    let rotate = rotator(rot);
    ifs_loop(
        p,
        iterations,
        scale,
        |z| scale_about(rotate(sort_desc(z.abs())), scale, offset),
        |z| {
            let a = z.abs();
            (a.x + a.y + a.z - S::one()) * S::splat(INV_SQRT3)
        },
    )
}

/// Knighty's icosahedral-group fold: rounds of abs(x), abs(y), abs(z) (the coordinate planes
/// are mirrors of the group in this orientation) and the mirror with normal
/// `(-1/2, -cos(pi/5), sqrt(3/4 - cos^2(pi/5)))`. It maps every point into the fundamental
/// triangle spanned by a 2-fold axis (0,0,1), the 5-fold axis [`ICO_VERTEX`] and the 3-fold
/// axis [`DODECA_VERTEX`]. With abs(z) included three rounds suffice (without it, five);
/// checked on random points in the tests.
#[inline(always)]
fn fold_icosahedral<S: Real>(mut p: V3<S>) -> V3<S> {
    let n = V3::c(-0.5, -0.809_016_994_374_947_5, 0.309_016_994_374_947_4);
    for _ in 0..3 {
        p = p.abs();
        let t = p.dot(n).min(S::zero());
        p -= n * (t + t);
    }
    p
}

/// The unit 5-fold axis in the fundamental triangle: an icosahedron vertex, a dodecahedron face
/// normal.
pub(super) const ICO_VERTEX: [f64; 3] = [0.525_731_112_119_133_6, 0.0, 0.850_650_808_352_039_9];
/// The unit 3-fold axis in the fundamental triangle: a dodecahedron vertex, an icosahedron face
/// normal.
pub(super) const DODECA_VERTEX: [f64; 3] = [0.0, 0.356_822_089_773_089_9, 0.934_172_358_962_715_7];
/// Inradius of the icosahedron and of the dodecahedron of circumradius 1 (the cosine of the
/// angle between adjacent 5-fold and 3-fold axes).
const ICO_INRADIUS: f64 = ICO_VERTEX[0] * DODECA_VERTEX[0]
    + ICO_VERTEX[1] * DODECA_VERTEX[1]
    + ICO_VERTEX[2] * DODECA_VERTEX[2];

/// Distance bound of a convex polyhedron with icosahedral symmetry, circumradius 1, whose face
/// normals are the orbit of `face`: fold into the fundamental triangle, where the nearest face
/// plane is the one with normal `face`.
#[inline(always)]
fn icosahedral_solid<S: Real>(p: V3<S>, face: [f64; 3]) -> S {
    fold_icosahedral(p).dot(V3::c(face[0], face[1], face[2])) - S::splat(ICO_INRADIUS)
}

/// Icosahedral KIFS over a base solid with icosahedral symmetry whose face normals are the
/// orbit of `face`: `ICO_VERTEX` gives the dodecahedron (faces along the 5-fold axes),
/// `DODECA_VERTEX` the icosahedron (faces along the 3-fold axes).
#[inline(always)]
pub(super) fn kifs_icosahedral<S: Real>(
    p: V3<S>,
    iterations: usize,
    scale: S,
    offset: V3<S>,
    rot: [V3<S>; 3],
    face: [f64; 3],
) -> (S, S) {
    let rotate = rotator(rot);
    ifs_loop(
        p,
        iterations,
        scale,
        |z| scale_about(rotate(fold_icosahedral(z)), scale, offset),
        |z| icosahedral_solid(z, face),
    )
}

/// Test access to the folds.
#[cfg(test)]
pub(super) mod for_test {
    use super::*;
    pub fn sierpinski_fold(z: V3<f64>) -> V3<f64> {
        let (x, y) = fold_sum(z.x, z.y);
        let (x, zz) = fold_sum(x, z.z);
        let (y, zz) = fold_sum(y, zz);
        V3::new(x, y, zz)
    }
    pub fn icosahedral_fold(z: V3<f64>) -> V3<f64> {
        fold_icosahedral(z)
    }
    pub const INRADIUS: f64 = ICO_INRADIUS;
}
