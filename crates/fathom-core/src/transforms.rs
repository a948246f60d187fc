//! Domain operators: maps applied to the evaluation point before a node's shape (and its whole
//! subtree) is evaluated, and the folds, rotations and scalings of IFS loops.
//!
//! Each operator transforms the point in place and multiplies the distance scale `k` (the
//! factor that turns a distance measured in the transformed frame back into world units): a
//! uniform scale by `s` divides the point by `s` and multiplies `k` by `s`. Operators that
//! stretch space non-uniformly (twist, bend) are tagged `Safety` and multiply `k` by their
//! `safety` parameter.

use crate::vec3::V3;

const BIG: f64 = 1e6;

crate::declare_family! {
    /// A domain (point) operator.
    family Transform, noun "domain operator", table TRANSFORMS;
    fn apply(p: &mut V3<S>, k: &mut S) -> ();

    /// Moves the subtree by `offset`.
    Translate [Exact] (offset: Vec3 = [0.0, 0.0, 0.0], [-BIG, BIG], "translation")
        => { *p -= offset; };

    /// Rotates the subtree by `angle` degrees about `axis` (right-handed).
    Rotate [Exact] (
        axis: Vec3 = [0.0, 1.0, 0.0], [-BIG, BIG], "rotation axis (normalised; zero means none)",
        angle: Scalar = 0.0, [-36000.0, 36000.0], "angle in degrees",
    ) baked(bake_rotation) (r0: Vec3, r1: Vec3, r2: Vec3)
        => { *p = V3::new(r0.dot(*p), r1.dot(*p), r2.dot(*p)); };

    /// Scales the subtree uniformly by `factor` about the origin.
    Scale [Exact] (factor: Scalar = 1.0, [1e-6, BIG], "scale factor")
        => { *p = *p / factor; *k *= factor; };

    /// Folds space with `abs` on each axis: mirrors the negative half onto the positive.
    FoldAbs [Exact] () => { *p = p.abs(); };

    /// The Menger sort fold: abs, then sorts the coordinates so that x >= y >= z.
    FoldMenger [Exact] () => {
        let mut q = p.abs();
        let m = q.x.lt(q.y);
        let (a, b) = (S::select(m, q.y, q.x), S::select(m, q.x, q.y));
        q.x = a; q.y = b;
        let m = q.x.lt(q.z);
        let (a, b) = (S::select(m, q.z, q.x), S::select(m, q.x, q.z));
        q.x = a; q.z = b;
        let m = q.y.lt(q.z);
        let (a, b) = (S::select(m, q.z, q.y), S::select(m, q.y, q.z));
        q.y = a; q.z = b;
        *p = q;
    };

    /// Scales by `factor` about `centre`: `p = factor * p - centre * (factor - 1)`, the
    /// contraction step of an IFS. Divides the distance by the accumulated scale.
    ScaleAbout [Exact] (
        factor: Scalar = 2.0, [1e-6, BIG], "scale factor",
        centre: Vec3 = [1.0, 1.0, 1.0], [-BIG, BIG], "fixed point of the scaling",
    ) => {
        *p = *p * factor - centre * (factor - S::one());
        *k /= factor;
    };
}

/// Axis-angle (degrees) to the rows of the inverse rotation matrix (it maps world points into
/// the rotated frame).
fn bake_rotation(user: &[f64], out: &mut Vec<f64>) {
    let axis = glam::DVec3::new(user[0], user[1], user[2]);
    let m = if axis.length_squared() > 0.0 {
        glam::DMat3::from_axis_angle(axis.normalize(), user[3].to_radians())
    } else {
        glam::DMat3::IDENTITY
    };
    // Row i of the inverse (= transpose) is column i of m.
    for c in [m.x_axis, m.y_axis, m.z_axis] {
        out.extend_from_slice(&[c.x, c.y, c.z]);
    }
}
