//! Small geometric helpers every estimator uses: a local shading frame, the standard warps of
//! the unit square onto the hemisphere, a cone and the sphere with their densities, the power
//! heuristic, luminance. Formulas as in pbrt-v4 (Pharr, Jakob, Humphreys), chapters 3 and A.5.

use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// An orthonormal frame whose z axis is a given unit vector (Duff et al. 2017, "Building an
/// Orthonormal Basis, Revisited": branchless and continuous except at z = -1 exactly).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent.
    pub s: DVec3,
    /// Second tangent.
    pub t: DVec3,
    /// The normal.
    pub n: DVec3,
}

impl Frame {
    /// The frame around unit vector `n`.
    pub fn new(n: DVec3) -> Frame {
        let sign = 1f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            s: DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            t: DVec3::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }
    /// World to local.
    pub fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
    /// Local to world.
    pub fn to_world(&self, v: DVec3) -> DVec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// Cosine-weighted direction on the upper hemisphere (Malley's method); density cos / pi.
pub fn cosine_hemisphere(u: [f64; 2]) -> DVec3 {
    let r = u[0].sqrt();
    let phi = TAU * u[1];
    DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u[0]).max(0.0).sqrt())
}

/// Uniform direction on the unit sphere; density 1 / (4 pi).
pub fn uniform_sphere(u: [f64; 2]) -> DVec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = TAU * u[1];
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone around +z whose `1 - cos(half-angle)` is `one_minus_cos`
/// (passed so tiny cones keep their precision); density [`cone_pdf`].
pub fn uniform_cone(u: [f64; 2], one_minus_cos: f64) -> DVec3 {
    let omc = u[0] * one_minus_cos;
    let z = 1.0 - omc;
    // sin^2 = 1 - z^2 = omc (2 - omc), exact for tiny cones.
    let r = (omc * (2.0 - omc)).max(0.0).sqrt();
    let phi = TAU * u[1];
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density (per steradian) of [`uniform_cone`].
pub fn cone_pdf(one_minus_cos: f64) -> f64 {
    1.0 / (TAU * one_minus_cos)
}

/// `1 - cos(asin(sqrt(sin2)))`, precise for small angles.
pub fn one_minus_cos_from_sin2(sin2: f64) -> f64 {
    let sin2 = sin2.clamp(0.0, 1.0);
    sin2 / (1.0 + (1.0 - sin2).sqrt())
}

/// The power heuristic (beta = 2) of Veach and Guibas 1995 for one sample of strategy `a`
/// against one of strategy `b`.
pub fn power_heuristic(pdf_a: f64, pdf_b: f64) -> f64 {
    if pdf_a.is_infinite() {
        return 1.0;
    }
    let (a, b) = (pdf_a * pdf_a, pdf_b * pdf_b);
    if a + b > 0.0 { a / (a + b) } else { 0.0 }
}

/// Rec. 709 luminance of linear RGB.
pub fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Mirror of `w` about +z.
pub fn reflect_z(w: DVec3) -> DVec3 {
    DVec3::new(-w.x, -w.y, w.z)
}

/// `PI` for the modules that think in solid angles.
pub const INV_PI: f64 = 1.0 / PI;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(0.3, -0.5, 0.8).normalize(),
            DVec3::new(1e-9, 0.0, -1.0).normalize(),
        ] {
            let f = Frame::new(n);
            for (a, b) in [(f.s, f.t), (f.s, f.n), (f.t, f.n)] {
                assert!(a.dot(b).abs() < 1e-12);
            }
            for v in [f.s, f.t, f.n] {
                assert!((v.length() - 1.0).abs() < 1e-12);
            }
            let v = DVec3::new(0.1, 0.2, 0.3);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-12);
        }
    }

    #[test]
    fn cones_stay_inside_and_tiny_cones_keep_precision() {
        let omc = one_minus_cos_from_sin2(1e-12);
        assert!((omc - 5e-13).abs() < 1e-20);
        for u in [[0.0, 0.0], [0.999, 0.5], [0.5, 0.25]] {
            let w = uniform_cone(u, 0.1);
            assert!(w.z >= 0.9 - 1e-12 && (w.length() - 1.0).abs() < 1e-12);
        }
    }
}
