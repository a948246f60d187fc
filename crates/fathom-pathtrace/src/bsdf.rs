//! The BSDF of a [`PbrMaterial`] at one point: evaluation, sampling and density, in the local
//! frame (normal = +z, `wo` the direction back towards where the light goes).
//!
//! Lobes, mixed by metallic `m` and transmission `t`:
//! - `(1 - m)(1 - t)` **dielectric over diffuse**: a GGX reflection with Schlick's Fresnel
//!   (F0 = 0.08 specular, tinted; F90 = min(1, 50 F0) so specular 0 is pure Lambert), its Kulla-Conty multiple-scattering lobe, and under it a
//!   Lambertian base scaled by `(1 - Es(mu_o)) (1 - Es(mu_i)) / (1 - Es_avg)` where `Es` is the
//!   specular layer's directional albedo: the energy the coat does not reflect goes to the
//!   base, reciprocally (the coupling of Kulla and Conty 2017, section 5.1). An albedo-1
//!   base therefore reflects everything at every angle (white furnace);
//! - `m` **metal**: the same GGX lobe with F0 = base colour, plus Kulla-Conty's lobe with
//!   their average-Fresnel colour factor; with F0 = 1 it is white in the furnace;
//! - `(1 - m) t` **smooth glass**: a delta interface that reflects with the exact dielectric
//!   Fresnel term and refracts otherwise (pbrt-v4's `DielectricBxDF` at roughness 0). Inside
//!   an object the integrator asks for [`Bsdf::interior`], the same interface seen from the
//!   dense side. Radiance is not scaled by eta^2 on crossing: a path that enters an object
//!   leaves it again before it reaches a light or the sky, and the two factors cancel.
//!
//! Sampling is a one-sample mixture: visible-normal GGX, cosine hemisphere, or the delta
//! interface, chosen with probabilities proportional to each part's albedo for this `wo`; the
//! density is the mixture's, so MIS with lights sees the true density of every direction.

use crate::material::PbrMaterial;
use crate::microfacet::{self, AlbedoTables};
use crate::sampling::{INV_PI, cosine_hemisphere, luminance, reflect_z};
use glam::DVec3;

/// A direction drawn from a BSDF.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// The new direction (local frame).
    pub wi: DVec3,
    /// f cos / pdf (for delta lobes: the lobe's weight / its selection probability).
    pub weight: DVec3,
    /// Density of `wi` (the continuous part's; 0 for a delta sample).
    pub pdf: f64,
    /// Whether `wi` came from a delta lobe (no light sampling can produce it).
    pub delta: bool,
    /// Whether `wi` crosses the surface (refraction).
    pub transmitted: bool,
}

/// The BSDF at one point.
#[derive(Clone, Debug)]
pub struct Bsdf {
    alpha: f64,
    rough: f64,
    base: DVec3,
    f0_diel: DVec3,
    f0_metal: DVec3,
    w_diel: f64,
    w_metal: f64,
    w_glass: f64,
    /// Relative index of refraction across the interface, inside over outside as seen from `wo`.
    eta: f64,
    e_avg: f64,
    w_avg: f64,
}

/// The grazing reflectance paired with `f0`: 1 for any real material, falling to 0 as F0
/// does below 2 % (Filament's "specular occlusion" F90 = saturate(50 F0)), so a material
/// with specular 0 is purely Lambertian and a black metal stays black.
fn f90(f0: DVec3) -> DVec3 {
    (f0 * 50.0).min(DVec3::ONE)
}

/// Schlick's Fresnel with a grazing reflectance [`f90`].
fn schlick(f0: DVec3, c: f64) -> DVec3 {
    let w = (1.0 - c).clamp(0.0, 1.0).powi(5);
    f0 + (f90(f0) - f0) * w
}

/// The exact Fresnel reflectance of a smooth dielectric interface for cos(theta_i) `ci` >= 0
/// and relative index `eta` = n_transmitted / n_incident.
pub fn fresnel_dielectric(ci: f64, eta: f64) -> f64 {
    let ci = ci.clamp(0.0, 1.0);
    let s2t = (1.0 - ci * ci) / (eta * eta);
    if s2t >= 1.0 {
        return 1.0;
    }
    let ct = (1.0 - s2t).sqrt();
    let rs = (ci - eta * ct) / (ci + eta * ct);
    let rp = (eta * ci - ct) / (eta * ci + ct);
    0.5 * (rs * rs + rp * rp)
}

/// Kulla and Conty's colour factor of the multiple-scattering lobe: the average Fresnel
/// F_avg (for Schlick, F0 + (F90 - F0) / 21) compounded over the inter-reflections.
fn f_ms(f0: DVec3, e_avg: f64) -> DVec3 {
    let favg = f0 + (f90(f0) - f0) / 21.0;
    favg * favg * e_avg / (DVec3::ONE - favg * (1.0 - e_avg))
}

impl Bsdf {
    /// The BSDF of material `m` seen from outside.
    pub fn new(m: &PbrMaterial) -> Bsdf {
        let base = DVec3::from(m.base_colour);
        let lum = luminance(base);
        let tint = if lum > 0.0 { base / lum } else { DVec3::ONE };
        let spec_colour = DVec3::ONE.lerp(tint, m.specular_tint);
        let f0_diel = (0.08 * m.specular * spec_colour).min(DVec3::ONE);
        let alpha = m.alpha();
        let rough = alpha.sqrt();
        let (e_avg, w_avg) = AlbedoTables::get().averages(rough);
        Bsdf {
            alpha,
            rough,
            base,
            f0_diel,
            f0_metal: base,
            w_diel: (1.0 - m.metallic) * (1.0 - m.transmission),
            w_metal: m.metallic,
            w_glass: (1.0 - m.metallic) * m.transmission,
            eta: m.ior,
            e_avg,
            w_avg,
        }
    }

    /// The interface of material `m` seen from its interior (a pure smooth dielectric).
    pub fn interior(m: &PbrMaterial) -> Bsdf {
        Bsdf {
            w_diel: 0.0,
            w_metal: 0.0,
            w_glass: 1.0,
            eta: 1.0 / m.ior,
            ..Bsdf::new(m)
        }
    }

    /// Whether the BSDF has a non-delta part (light sampling can help).
    pub fn has_smooth_part(&self) -> bool {
        self.w_diel + self.w_metal > 0.0
    }

    /// The directional albedo of the specular layer with reflectance `f0` at cos `mu`:
    /// single scattering with Schlick (F0 (E - W) + F90 W) plus the multiple-scattering lobe.
    fn layer_albedo(&self, f0: DVec3, mu: f64) -> DVec3 {
        let (e, w) = AlbedoTables::get().lookup(mu, self.rough);
        f0 * (e - w) + f90(f0) * w + f_ms(f0, self.e_avg) * (1.0 - e)
    }

    /// Its cosine-weighted hemispherical average.
    fn layer_albedo_avg(&self, f0: DVec3) -> DVec3 {
        f0 * (self.e_avg - self.w_avg)
            + f90(f0) * self.w_avg
            + f_ms(f0, self.e_avg) * (1.0 - self.e_avg)
    }

    /// f(wo, wi) of the non-delta lobes (0 unless both are above the surface).
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> DVec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 || !self.has_smooth_part() {
            return DVec3::ZERO;
        }
        let t = AlbedoTables::get();
        let h = (wo + wi).normalize();
        let oh = wo.dot(h).max(0.0);
        let ss =
            microfacet::d(h, self.alpha) * microfacet::g2(wo, wi, self.alpha) / (4.0 * wo.z * wi.z);
        let (eo, _) = t.lookup(wo.z, self.rough);
        let (ei, _) = t.lookup(wi.z, self.rough);
        let ms = if self.e_avg < 1.0 - 1e-6 {
            (1.0 - eo) * (1.0 - ei) * INV_PI / (1.0 - self.e_avg)
        } else {
            0.0
        };
        let spec = |f0: DVec3| schlick(f0, oh) * ss + f_ms(f0, self.e_avg) * ms;
        let mut f = DVec3::ZERO;
        if self.w_diel > 0.0 {
            let eso = self.layer_albedo(self.f0_diel, wo.z);
            let esi = self.layer_albedo(self.f0_diel, wi.z);
            let avg = self.layer_albedo_avg(self.f0_diel);
            let diffuse = self.base * (DVec3::ONE - eso) * (DVec3::ONE - esi) * INV_PI
                / (DVec3::ONE - avg).max(DVec3::splat(1e-9));
            f += self.w_diel * (spec(self.f0_diel) + diffuse);
        }
        if self.w_metal > 0.0 {
            f += self.w_metal * spec(self.f0_metal);
        }
        f
    }

    /// Probabilities of choosing (GGX, cosine, glass) for `wo`.
    fn lobe_probabilities(&self, wo: DVec3) -> [f64; 3] {
        let mu = wo.z.max(1e-6);
        let (e, w) = AlbedoTables::get().lookup(mu, self.rough);
        let single = |f0: DVec3| luminance(f0 * (e - w) + f90(f0) * w);
        let multi = |f0: DVec3| luminance(f_ms(f0, self.e_avg)) * (1.0 - e);
        let mut p_ggx = 0.0;
        let mut p_cos = 0.0;
        if self.w_diel > 0.0 {
            p_ggx += self.w_diel * single(self.f0_diel);
            let es = luminance(self.layer_albedo(self.f0_diel, mu));
            p_cos += self.w_diel * (multi(self.f0_diel) + luminance(self.base) * (1.0 - es));
        }
        if self.w_metal > 0.0 {
            p_ggx += self.w_metal * single(self.f0_metal);
            p_cos += self.w_metal * multi(self.f0_metal);
        }
        let p_glass = self.w_glass;
        let sum = p_ggx + p_cos + p_glass;
        if sum > 0.0 {
            [p_ggx / sum, p_cos / sum, p_glass / sum]
        } else {
            [0.0, 1.0, 0.0]
        }
    }

    /// Density of sampling `wi` from `wo` (the continuous lobes only).
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let [p_ggx, p_cos, _] = self.lobe_probabilities(wo);
        p_ggx * microfacet::reflect_pdf(wo, wi, self.alpha) + p_cos * wi.z * INV_PI
    }

    /// Draws a direction: `u_lobe` picks the lobe (and, for glass, reflection or refraction),
    /// `u` the direction. `None` when the path ends here (no energy).
    pub fn sample(&self, wo: DVec3, u_lobe: f64, u: [f64; 2]) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let [p_ggx, p_cos, p_glass] = self.lobe_probabilities(wo);
        if u_lobe < p_glass {
            // Reuse the rest of u_lobe to choose reflection or refraction.
            let u2 = u_lobe / p_glass;
            let f = fresnel_dielectric(wo.z, self.eta);
            let weight = DVec3::splat(self.w_glass / p_glass);
            if u2 < f {
                return Some(BsdfSample {
                    wi: reflect_z(wo),
                    weight,
                    pdf: 0.0,
                    delta: true,
                    transmitted: false,
                });
            }
            let s2t = (1.0 - wo.z * wo.z) / (self.eta * self.eta);
            let ct = (1.0 - s2t).max(0.0).sqrt();
            let wi = DVec3::new(-wo.x / self.eta, -wo.y / self.eta, -ct).normalize();
            return Some(BsdfSample {
                wi,
                weight,
                pdf: 0.0,
                delta: true,
                transmitted: true,
            });
        }
        let wi = if u_lobe < p_glass + p_ggx {
            let h = microfacet::sample_vndf(wo, self.alpha, u);
            2.0 * wo.dot(h) * h - wo
        } else {
            let _ = p_cos;
            cosine_hemisphere(u)
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let weight = self.eval(wo, wi) * wi.z / pdf;
        Some(BsdfSample {
            wi,
            weight,
            pdf,
            delta: false,
            transmitted: false,
        })
    }

    /// The colour the denoiser divides by: what a white light reflects off this BSDF, roughly
    /// (the base colour for dielectrics and metals, white for glass).
    pub fn albedo(&self) -> DVec3 {
        let s = self.w_diel + self.w_metal + self.w_glass;
        if s <= 0.0 {
            return DVec3::ONE;
        }
        (self.base * (self.w_diel + self.w_metal) + DVec3::splat(self.w_glass)) / s
    }
}

#[cfg(test)]
mod tests;
