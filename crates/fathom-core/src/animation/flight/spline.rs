//! The curves a flight path is made of: a centripetal Catmull-Rom segment (Barry-Goldman,
//! alpha = 1/2, written as a cubic Hermite with the equivalent tangents) for positions, squad
//! (Shoemake's spherical quadrangle) for orientations, and a Catmull-Rom Hermite over uneven
//! knots for scalars (field of view, parameter values). Every curve passes through its keys.

use glam::{DQuat, DVec3};

/// One segment of a centripetal Catmull-Rom spline from `p1` to `p2`, with neighbours `p0`
/// and `p3` (`None` at the ends of the path: the missing neighbour is the mirror image of
/// the far end of the segment, so an end segment leaves straight towards its neighbour).
#[derive(Clone, Copy, Debug)]
pub struct CentripetalSegment {
    p1: DVec3,
    p2: DVec3,
    /// Hermite tangents at `p1` and `p2`, in units of the segment's parameter u in [0, 1].
    m1: DVec3,
    m2: DVec3,
}

impl CentripetalSegment {
    /// The segment from `p1` to `p2`, shaped by the neighbours `p0` and `p3` where there are any.
    pub fn new(p0: Option<DVec3>, p1: DVec3, p2: DVec3, p3: Option<DVec3>) -> Self {
        let chord = p2 - p1;
        if chord.length_squared() == 0.0 {
            return CentripetalSegment {
                p1,
                p2,
                m1: DVec3::ZERO,
                m2: DVec3::ZERO,
            };
        }
        // A neighbour that is missing or sits on its key is replaced by the mirror image.
        let p0 = p0.filter(|p| *p != p1).unwrap_or(p1 - chord);
        let p3 = p3.filter(|p| *p != p2).unwrap_or(p2 + chord);
        let knot = |a: DVec3, b: DVec3| (a - b).length().sqrt();
        let (t01, t12, t23) = (knot(p0, p1), knot(p1, p2), knot(p2, p3));
        let m1 = (p1 - p0) / t01 - (p2 - p0) / (t01 + t12) + (p2 - p1) / t12;
        let m2 = (p2 - p1) / t12 - (p3 - p1) / (t12 + t23) + (p3 - p2) / t23;
        CentripetalSegment {
            p1,
            p2,
            m1: m1 * t12,
            m2: m2 * t12,
        }
    }

    /// The point at `u` in [0, 1]: `p1` at 0, `p2` at 1. Evaluated as an offset from the nearer
    /// end, so a segment 1e-12 long near a point 1 from the origin keeps its shape.
    pub fn at(&self, u: f64) -> DVec3 {
        let (u2, u3) = (u * u, u * u * u);
        let h10 = u3 - 2.0 * u2 + u;
        let h11 = u3 - u2;
        if u < 0.5 {
            let h01 = 3.0 * u2 - 2.0 * u3;
            self.p1 + ((self.p2 - self.p1) * h01 + self.m1 * h10 + self.m2 * h11)
        } else {
            let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
            self.p2 + ((self.p1 - self.p2) * h00 + self.m1 * h10 + self.m2 * h11)
        }
    }
}

/// log of a unit quaternion: the rotation vector halved.
fn qlog(q: DQuat) -> DVec3 {
    let v = DVec3::new(q.x, q.y, q.z);
    let s = v.length();
    if s < 1e-12 {
        return v;
    }
    v / s * s.atan2(q.w)
}

/// exp of a pure quaternion (inverse of [`qlog`]).
fn qexp(v: DVec3) -> DQuat {
    let a = v.length();
    if a < 1e-12 {
        return DQuat::from_xyzw(v.x, v.y, v.z, 1.0).normalize();
    }
    let s = a.sin() / a;
    DQuat::from_xyzw(v.x * s, v.y * s, v.z * s, a.cos())
}

/// Makes consecutive quaternions lie in the same hemisphere (q and -q are the same rotation;
/// interpolating between opposite signs would take the long way round).
pub fn align_signs(qs: &mut [DQuat]) {
    for i in 1..qs.len() {
        if qs[i - 1].dot(qs[i]) < 0.0 {
            qs[i] = -qs[i];
        }
    }
}

/// Squad's inner control quaternions, one per key (the ends are their own).
pub fn squad_controls(qs: &[DQuat]) -> Vec<DQuat> {
    let n = qs.len();
    (0..n)
        .map(|i| {
            if i == 0 || i + 1 == n {
                return qs[i];
            }
            let inv = qs[i].inverse();
            let a = qlog(inv * qs[i + 1]);
            let b = qlog(inv * qs[i - 1]);
            (qs[i] * qexp(-(a + b) * 0.25)).normalize()
        })
        .collect()
}

/// Spherical linear interpolation without the shortest-path flip (the signs are aligned
/// beforehand, and squad's control quaternions must not be flipped).
fn slerp_raw(a: DQuat, b: DQuat, t: f64) -> DQuat {
    let d = a.dot(b).clamp(-1.0, 1.0);
    if d.abs() > 1.0 - 1e-12 {
        return (a * (1.0 - t) + b * t).normalize();
    }
    let th = d.acos();
    let s = th.sin();
    (a * (((1.0 - t) * th).sin() / s) + b * ((t * th).sin() / s)).normalize()
}

/// Squad between keys `q1`, `q2` with controls `s1`, `s2` at `u` in [0, 1].
pub fn squad(q1: DQuat, q2: DQuat, s1: DQuat, s2: DQuat, u: f64) -> DQuat {
    slerp_raw(
        slerp_raw(q1, q2, u),
        slerp_raw(s1, s2, u),
        2.0 * u * (1.0 - u),
    )
}

/// The angle (radians) of the rotation from `a` to `b`.
pub fn angle_between(a: DQuat, b: DQuat) -> f64 {
    2.0 * a.dot(b).abs().clamp(0.0, 1.0).acos()
}

/// A cubic Hermite through `(x, v)` knots (x increasing) with Catmull-Rom tangents for uneven
/// spacing; constant before the first knot and after the last.
pub fn scalar_at(knots: &[(f64, f64)], x: f64) -> f64 {
    let n = knots.len();
    if n == 0 {
        return 0.0;
    }
    if x <= knots[0].0 || n == 1 || x.is_nan() {
        return knots[0].1;
    }
    if x >= knots[n - 1].0 {
        return knots[n - 1].1;
    }
    let i = knots.partition_point(|k| k.0 <= x).clamp(1, n - 1) - 1;
    let (x1, v1) = knots[i];
    let (x2, v2) = knots[i + 1];
    let h = x2 - x1;
    let slope = |a: usize, b: usize| (knots[b].1 - knots[a].1) / (knots[b].0 - knots[a].0);
    let tangent = |k: usize| {
        let left = (k > 0).then(|| slope(k - 1, k));
        let right = (k + 1 < n).then(|| slope(k, k + 1));
        match (left, right) {
            (Some(l), Some(r)) => 0.5 * (l + r),
            (Some(s), None) | (None, Some(s)) => s,
            (None, None) => 0.0,
        }
    };
    let (m1, m2) = (tangent(i) * h, tangent(i + 1) * h);
    let u = (x - x1) / h;
    let (u2, u3) = (u * u, u * u * u);
    v1 * (2.0 * u3 - 3.0 * u2 + 1.0)
        + m1 * (u3 - 2.0 * u2 + u)
        + v2 * (3.0 * u2 - 2.0 * u3)
        + m2 * (u3 - u2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_pass_through_their_ends_and_two_keys_fly_straight() {
        let (a, b) = (DVec3::new(1.0, 2.0, 3.0), DVec3::new(-2.0, 0.5, 4.0));
        let s = CentripetalSegment::new(None, a, b, None);
        assert_eq!(s.at(0.0), a);
        assert_eq!(s.at(1.0), b);
        for k in 0..=10 {
            let u = k as f64 / 10.0;
            assert!((s.at(u) - a.lerp(b, u)).length() < 1e-14, "u {u}");
        }
    }

    #[test]
    fn squad_passes_through_its_keys_and_stays_unit() {
        let mut qs = vec![
            DQuat::IDENTITY,
            DQuat::from_rotation_y(1.0),
            -DQuat::from_rotation_x(0.5) * DQuat::from_rotation_y(1.5),
            DQuat::from_rotation_z(2.0),
        ];
        align_signs(&mut qs);
        let s = squad_controls(&qs);
        for i in 0..3 {
            let at0 = squad(qs[i], qs[i + 1], s[i], s[i + 1], 0.0);
            let at1 = squad(qs[i], qs[i + 1], s[i], s[i + 1], 1.0);
            assert!(angle_between(at0, qs[i]) < 1e-7);
            assert!(angle_between(at1, qs[i + 1]) < 1e-7);
            let mid = squad(qs[i], qs[i + 1], s[i], s[i + 1], 0.5);
            assert!((mid.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn scalars_pass_through_uneven_knots() {
        let k = [(0.0, 1.0), (1.0, 3.0), (3.5, -2.0), (4.0, 0.0)];
        for (x, v) in k {
            assert!((scalar_at(&k, x) - v).abs() < 1e-12);
        }
        assert_eq!(scalar_at(&k, -1.0), 1.0);
        assert_eq!(scalar_at(&k, 9.0), 0.0);
    }
}
