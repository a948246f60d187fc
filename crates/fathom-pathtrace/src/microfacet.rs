//! The GGX (Trowbridge-Reitz) microfacet distribution, its height-correlated Smith masking,
//! sampling of its visible normals, and the directional-albedo tables that energy
//! compensation needs.
//!
//! - D, Lambda, G1 and the height-correlated G2: Heitz 2014, "Understanding the
//!   Masking-Shadowing Function in Microfacet-Based BRDFs".
//! - Visible-normal (VNDF) sampling: Heitz 2018, "Sampling the GGX Distribution of Visible
//!   Normals" (JCGT 7(4)): a reflected direction's estimator weight is then G2 / G1(wo), which
//!   keeps the variance low at grazing angles.
//! - A single-scattering microfacet BRDF loses the energy of light that bounces more than once
//!   between microfacets (up to ~60 % for rough metals). Kulla and Conty 2017 ("Revisiting
//!   Physically Based Shading at Imageworks") add a reciprocal lobe that returns exactly that
//!   energy; it needs E(mu, alpha), the directional albedo of the lobe with F = 1, and its
//!   cosine-weighted average. [`AlbedoTables`] computes those once per process by integrating
//!   the VNDF estimator over an Owen-scrambled Sobol set (deterministic, no file to ship);
//!   W(mu, alpha) is the part weighted by Schlick's (1 - cos)^5, so the albedo of the lobe
//!   with Schlick's Fresnel is F0 (E - W) + W exactly.
//!
//! All vectors are in the local shading frame (normal = +z).

use crate::sampler::{owen_scramble, sobol0, sobol1, to_unit};
use crate::shared::{ALBEDO_TABLE, MIN_ALPHA};
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::OnceLock;

/// The normal distribution D(h).
pub fn d(h: DVec3, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let c2 = h.z * h.z;
    let k = c2 * (a2 - 1.0) + 1.0;
    a2 / (PI * k * k)
}

/// Smith's Lambda(w).
pub fn lambda(w: DVec3, alpha: f64) -> f64 {
    let c2 = w.z * w.z;
    if c2 <= 0.0 {
        return f64::INFINITY;
    }
    let t2 = (1.0 - c2).max(0.0) / c2;
    0.5 * ((1.0 + alpha * alpha * t2).sqrt() - 1.0)
}

/// Masking G1(w).
pub fn g1(w: DVec3, alpha: f64) -> f64 {
    1.0 / (1.0 + lambda(w, alpha))
}

/// Height-correlated masking-shadowing G2(wo, wi).
pub fn g2(wo: DVec3, wi: DVec3, alpha: f64) -> f64 {
    1.0 / (1.0 + lambda(wo, alpha) + lambda(wi, alpha))
}

/// A visible normal for view `wo` (wo.z > 0), from two uniforms.
pub fn sample_vndf(wo: DVec3, alpha: f64, u: [f64; 2]) -> DVec3 {
    // Stretch the view to the unit-roughness configuration.
    let v = DVec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let len2 = v.x * v.x + v.y * v.y;
    let t1 = if len2 > 0.0 {
        DVec3::new(-v.y, v.x, 0.0) / len2.sqrt()
    } else {
        DVec3::X
    };
    let t2 = v.cross(t1);
    // A point on the projected hemisphere: a disk, half of it squashed by the view's slope.
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    let p1 = r * phi.cos();
    let mut p2 = r * phi.sin();
    let s = 0.5 * (1.0 + v.z);
    p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    let nh = t1 * p1 + t2 * p2 + v * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    // Unstretch.
    DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-12)).normalize()
}

/// Density of [`sample_vndf`]'s normal `h` for view `wo`: G1(wo) max(0, wo.h) D(h) / wo.z.
pub fn vndf_pdf(wo: DVec3, h: DVec3, alpha: f64) -> f64 {
    if wo.z <= 0.0 {
        return 0.0;
    }
    g1(wo, alpha) * wo.dot(h).max(0.0) * d(h, alpha) / wo.z
}

/// Density of the reflected direction `wi` when `h` is drawn by [`sample_vndf`].
pub fn reflect_pdf(wo: DVec3, wi: DVec3, alpha: f64) -> f64 {
    let h = (wo + wi).normalize();
    let oh = wo.dot(h);
    if oh <= 0.0 || !h.is_finite() {
        return 0.0;
    }
    vndf_pdf(wo, h, alpha) / (4.0 * oh)
}

/// Directional albedos of the GGX lobe, tabulated over cos(theta) (cell centres) and
/// roughness = sqrt(alpha) (grid points from 0 to 1), with bilinear lookups.
pub struct AlbedoTables {
    /// E(mu, alpha): albedo with F = 1.
    e: Vec<f64>,
    /// W(mu, alpha): the part weighted by (1 - wo.h)^5.
    w: Vec<f64>,
    /// Cosine-weighted hemispherical averages 2 int E mu dmu, per roughness.
    e_avg: Vec<f64>,
    /// The same for W.
    w_avg: Vec<f64>,
}

/// Samples per table entry.
const TABLE_SAMPLES: u32 = 1024;

impl AlbedoTables {
    /// The process-wide tables (computed on first use, about 10 ms).
    pub fn get() -> &'static AlbedoTables {
        static T: OnceLock<AlbedoTables> = OnceLock::new();
        T.get_or_init(AlbedoTables::compute)
    }

    fn compute() -> AlbedoTables {
        let n = ALBEDO_TABLE;
        let mut e = vec![0.0; n * n];
        let mut w = vec![0.0; n * n];
        for j in 0..n {
            let alpha = alpha_at(j);
            for i in 0..n {
                let mu = (i as f64 + 0.5) / n as f64;
                let wo = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                let (mut se, mut sw) = (0.0, 0.0);
                let seed = (j * n + i) as u32;
                for k in 0..TABLE_SAMPLES {
                    let u = [
                        to_unit(owen_scramble(sobol0(k), seed.wrapping_mul(0x9e37_79b9))),
                        to_unit(owen_scramble(sobol1(k), seed ^ 0x5bd1_e995)),
                    ];
                    let h = sample_vndf(wo, alpha, u);
                    let wi = 2.0 * wo.dot(h) * h - wo;
                    if wi.z <= 0.0 {
                        continue;
                    }
                    let weight = g2(wo, wi, alpha) / g1(wo, alpha);
                    se += weight;
                    sw += weight * (1.0 - wo.dot(h)).max(0.0).powi(5);
                }
                e[j * n + i] = (se / TABLE_SAMPLES as f64).min(1.0);
                w[j * n + i] = sw / TABLE_SAMPLES as f64;
            }
        }
        let mut t = AlbedoTables {
            e,
            w,
            e_avg: vec![0.0; n],
            w_avg: vec![0.0; n],
        };
        // Averages of the interpolated functions, so the lobes built on them integrate
        // consistently.
        const M: usize = 512;
        for j in 0..n {
            let r = j as f64 / (n - 1) as f64;
            let (mut ea, mut wa) = (0.0, 0.0);
            for k in 0..M {
                let mu = (k as f64 + 0.5) / M as f64;
                let (ev, wv) = t.lookup(mu, r);
                ea += ev * mu;
                wa += wv * mu;
            }
            t.e_avg[j] = 2.0 * ea / M as f64;
            t.w_avg[j] = 2.0 * wa / M as f64;
        }
        t
    }

    /// The raw tables, for upload to a shader: (E, W) row-major with cos(theta) across
    /// ([`ALBEDO_TABLE`] x [`ALBEDO_TABLE`], rows by roughness), then (E_avg, W_avg) per row.
    /// [`AlbedoTables::lookup`] and [`AlbedoTables::averages`] are how they are read.
    pub fn raw(&self) -> [&[f64]; 4] {
        [&self.e, &self.w, &self.e_avg, &self.w_avg]
    }

    /// (E, W) at cos(theta) `mu` and roughness `r` = sqrt(alpha).
    pub fn lookup(&self, mu: f64, r: f64) -> (f64, f64) {
        let n = ALBEDO_TABLE;
        let x = (mu * n as f64 - 0.5).clamp(0.0, (n - 1) as f64);
        let y = (r * (n - 1) as f64).clamp(0.0, (n - 1) as f64);
        let (i0, j0) = (x.floor() as usize, y.floor() as usize);
        let (i1, j1) = ((i0 + 1).min(n - 1), (j0 + 1).min(n - 1));
        let (fx, fy) = (x - i0 as f64, y - j0 as f64);
        let bil = |t: &[f64]| {
            let a = t[j0 * n + i0] * (1.0 - fx) + t[j0 * n + i1] * fx;
            let b = t[j1 * n + i0] * (1.0 - fx) + t[j1 * n + i1] * fx;
            a * (1.0 - fy) + b * fy
        };
        (bil(&self.e), bil(&self.w))
    }

    /// (E_avg, W_avg) at roughness `r` = sqrt(alpha).
    pub fn averages(&self, r: f64) -> (f64, f64) {
        let n = ALBEDO_TABLE;
        let y = (r * (n - 1) as f64).clamp(0.0, (n - 1) as f64);
        let j0 = y.floor() as usize;
        let j1 = (j0 + 1).min(n - 1);
        let fy = y - j0 as f64;
        (
            self.e_avg[j0] * (1.0 - fy) + self.e_avg[j1] * fy,
            self.w_avg[j0] * (1.0 - fy) + self.w_avg[j1] * fy,
        )
    }
}

/// Alpha of table row `j`.
fn alpha_at(j: usize) -> f64 {
    let r = j as f64 / (ALBEDO_TABLE - 1) as f64;
    (r * r).max(MIN_ALPHA)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn d_is_normalised_over_projected_area() {
        // int D(h) h.z dh = 1, by a midpoint rule in (cos theta, phi) (D is isotropic).
        for alpha in [0.05, 0.3, 1.0] {
            let n = 20000;
            let mut s = 0.0;
            for k in 0..n {
                let c = (k as f64 + 0.5) / n as f64;
                let h = DVec3::new((1.0 - c * c).sqrt(), 0.0, c);
                s += d(h, alpha) * c * 2.0 * PI / n as f64;
            }
            assert!((s - 1.0).abs() < 2e-3, "alpha {alpha}: {s}");
        }
    }

    #[test]
    fn smooth_lobes_reflect_everything_and_rough_ones_lose_energy() {
        let t = AlbedoTables::get();
        let (e_smooth, _) = t.lookup(0.7, 0.0);
        assert!((e_smooth - 1.0).abs() < 1e-3, "{e_smooth}");
        let (e_rough, _) = t.lookup(0.7, 1.0);
        // Kulla and Conty: a single-scattering GGX lobe of alpha 1 loses up to 60 %.
        assert!(e_rough > 0.3 && e_rough < 0.5, "{e_rough}");
        let (avg, _) = t.averages(1.0);
        assert!(avg > 0.3 && avg < 0.5, "{avg}");
    }

    #[test]
    fn tables_match_brute_force_quadrature() {
        // int D G2 / (4 mu_o mu_i) mu_i dwi by a midpoint rule in (cos theta, phi).
        for (mu, alpha) in [(0.7, 1.0), (0.7, 0.25), (0.2, 0.5), (0.9, 0.09)] {
            let wo = DVec3::new((1.0f64 - mu * mu).sqrt(), 0.0, mu);
            let n = 600;
            let mut s = 0.0;
            for a in 0..n {
                for b in 0..n {
                    let c = (a as f64 + 0.5) / n as f64;
                    let p = (b as f64 + 0.5) / n as f64 * 2.0 * PI;
                    let sn = (1.0 - c * c).sqrt();
                    let wi = DVec3::new(sn * p.cos(), sn * p.sin(), c);
                    let h = (wo + wi).normalize();
                    s += d(h, alpha) * g2(wo, wi, alpha) / (4.0 * wo.z * wi.z) * c;
                }
            }
            s *= 2.0 * PI / (n * n) as f64;
            let t = AlbedoTables::get().lookup(mu, alpha.sqrt()).0;
            assert!(
                (s - t).abs() < 3e-3,
                "mu {mu} alpha {alpha}: quadrature {s}, table {t}"
            );
        }
    }
}
