//! Light sources: the scene's directional lights as small cones (soft shadows), spherical
//! area lights, and the environment (the scene's sky gradient, a uniform radiance, or an
//! equirectangular map).
//!
//! Every light can be sampled (a direction, the radiance along it, the density in solid
//! angle) and, unless it is a delta light, report the density of a direction a BSDF chose, so
//! the integrator can weigh the two strategies by the power heuristic (Veach 1997, ch. 9).
//!
//! **Units.** Today's Blinn-Phong shader lights a white surface facing a light of intensity
//! I to brightness I (no 1/pi). A Lambertian BRDF is albedo/pi, so a legacy light becomes a
//! cone of normal irradiance pi x I x colour: the same surface gets the same brightness. The
//! cone's angular radius comes from today's `shadow_softness` k, the Aaltonen/Quilez penumbra
//! factor: a penumbra k h / t < 1 spans the angle atan(1/k), so radius = atan(1/k) (k = 16:
//! 3.6 degrees) keeps the shadows as soft as they were. Lights with `shadows: false` light
//! without a visibility test, as they did, and are invisible to BSDF rays.
//!
//! Sphere lights are sampled uniformly inside the cone they subtend (pbrt-v4's `Sphere`
//! sampling from outside), which is exact in solid angle and never wastes a sample.

use crate::envmap::EnvMap;
use crate::sampling::{Frame, cone_pdf, one_minus_cos_from_sin2, uniform_cone, uniform_sphere};
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::Arc;

/// A light sample towards a shading point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the point towards the light.
    pub wi: DVec3,
    /// Radiance arriving along `wi` (before occlusion).
    pub radiance: DVec3,
    /// Density in solid angle; infinite for a delta light.
    pub pdf: f64,
    /// Distance to the light along `wi` (infinite for distant lights).
    pub distance: f64,
    /// Whether occlusion must be tested.
    pub shadows: bool,
}

/// A directional light with an angular radius.
#[derive(Clone, Debug)]
pub struct ConeLight {
    /// Unit direction towards the light.
    pub direction: DVec3,
    /// Radiance inside the cone (or, for a delta light, the irradiance it brings).
    pub radiance: DVec3,
    /// 1 - cos(angular radius); 0 for a delta light.
    pub one_minus_cos: f64,
    /// Whether it casts shadows (and can be seen by BSDF rays).
    pub shadows: bool,
}

impl ConeLight {
    /// A legacy light with angular radius `radius` (radians, >= 0).
    pub fn from_legacy(l: &fathom_core::scene::Light, radius: f64) -> ConeLight {
        // A light without shadows is a pure direction: no cone to see or to sample.
        let radius = if l.shadows { radius } else { 0.0 };
        let irradiance = DVec3::from(l.colour) * l.intensity * PI;
        let direction = l.direction.normalize();
        let s = radius.sin();
        let omc = one_minus_cos_from_sin2(s * s);
        let radiance = if omc > 0.0 {
            // Normal irradiance of a uniform cone: L pi sin^2(radius).
            irradiance / (PI * s * s)
        } else {
            irradiance
        };
        ConeLight {
            direction,
            radiance,
            one_minus_cos: if radius > 0.0 { omc } else { 0.0 },
            shadows: l.shadows,
        }
    }

    /// Whether this light is a delta (no area; only light sampling finds it).
    pub fn is_delta(&self) -> bool {
        self.one_minus_cos <= 0.0 || !self.shadows
    }

    /// A direction towards the light.
    pub fn sample(&self, u: [f64; 2]) -> LightSample {
        if self.one_minus_cos <= 0.0 {
            return LightSample {
                wi: self.direction,
                radiance: self.radiance,
                pdf: f64::INFINITY,
                distance: f64::INFINITY,
                shadows: self.shadows,
            };
        }
        let wi = Frame::new(self.direction).to_world(uniform_cone(u, self.one_minus_cos));
        LightSample {
            wi,
            radiance: self.radiance,
            pdf: cone_pdf(self.one_minus_cos),
            distance: f64::INFINITY,
            shadows: self.shadows,
        }
    }

    /// Radiance a BSDF ray escaping along `d` sees from this light, with the density light
    /// sampling would have had.
    pub fn seen(&self, d: DVec3) -> Option<(DVec3, f64)> {
        if self.is_delta() || 1.0 - d.dot(self.direction) > self.one_minus_cos {
            return None;
        }
        Some((self.radiance, cone_pdf(self.one_minus_cos)))
    }
}

/// A spherical area light (not part of the distance field; it is intersected analytically).
#[derive(Clone, Debug, PartialEq)]
pub struct SphereLight {
    /// Centre.
    pub centre: DVec3,
    /// Radius, > 0.
    pub radius: f64,
    /// Emitted radiance = colour x strength.
    pub colour: [f64; 3],
    /// Radiance scale.
    pub strength: f64,
}

/// Why a light was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LightError {
    /// A sphere light with a bad field.
    #[error("sphere light {index}: {field} = {value} is out of range {range}")]
    Sphere {
        /// Which light.
        index: usize,
        /// The field.
        field: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range.
        range: &'static str,
    },
}

impl SphereLight {
    /// Checks the fields.
    pub fn validate(&self, index: usize) -> Result<(), LightError> {
        let bad = |field, value, range| {
            Err(LightError::Sphere {
                index,
                field,
                value,
                range,
            })
        };
        for (i, v) in self.centre.to_array().into_iter().enumerate() {
            if !(v.is_finite() && v.abs() <= 1e12) {
                return bad(["centre.x", "centre.y", "centre.z"][i], v, "[-1e12, 1e12]");
            }
        }
        if !(self.radius.is_finite() && self.radius > 0.0 && self.radius <= 1e12) {
            return bad("radius", self.radius, "(0, 1e12]");
        }
        for (i, &c) in self.colour.iter().enumerate() {
            if !(c.is_finite() && (0.0..=1.0).contains(&c)) {
                return bad(["colour.r", "colour.g", "colour.b"][i], c, "[0, 1]");
            }
        }
        if !(self.strength.is_finite() && (0.0..=1e9).contains(&self.strength)) {
            return bad("strength", self.strength, "[0, 1e9]");
        }
        Ok(())
    }

    /// Emitted radiance.
    pub fn radiance(&self) -> DVec3 {
        DVec3::from(self.colour) * self.strength
    }

    /// Distance along unit `d` from `o` to the sphere's near side, if the ray meets it from
    /// outside.
    pub fn intersect(&self, o: DVec3, d: DVec3) -> Option<f64> {
        let oc = self.centre - o;
        let b = oc.dot(d);
        let c = oc.length_squared() - self.radius * self.radius;
        if c <= 0.0 {
            return None;
        }
        let disc = b * b - c;
        if disc < 0.0 || b <= 0.0 {
            return None;
        }
        // Stable near root: c / (b + sqrt(disc)).
        Some(c / (b + disc.sqrt()))
    }

    /// 1 - cos of the half-angle the sphere subtends from `p` (None from inside).
    fn cone(&self, p: DVec3) -> Option<(DVec3, f64, f64)> {
        let oc = self.centre - p;
        let d2 = oc.length_squared();
        let r2 = self.radius * self.radius;
        if d2 <= r2 {
            return None;
        }
        let omc = one_minus_cos_from_sin2(r2 / d2);
        (omc > 0.0).then(|| (oc / d2.sqrt(), omc, d2))
    }

    /// A direction from `p` towards the sphere.
    pub fn sample(&self, p: DVec3, u: [f64; 2]) -> Option<LightSample> {
        let (axis, omc, _) = self.cone(p)?;
        let wi = Frame::new(axis).to_world(uniform_cone(u, omc));
        // Rays inside the cone meet the sphere; grazing ones may miss by rounding.
        let distance = self.intersect(p, wi).unwrap_or_else(|| {
            let oc = self.centre - p;
            oc.dot(wi).max(0.0)
        });
        Some(LightSample {
            wi,
            radiance: self.radiance(),
            pdf: cone_pdf(omc),
            distance,
            shadows: true,
        })
    }

    /// Density of [`SphereLight::sample`] from `p` choosing `wi` (which hits the sphere).
    pub fn pdf(&self, p: DVec3) -> f64 {
        self.cone(p).map_or(0.0, |(_, omc, _)| cone_pdf(omc))
    }
}

/// Radiance arriving from infinitely far away.
#[derive(Clone, Debug)]
pub enum Environment {
    /// The scene's sky: `bottom` at and below the horizon to `top` straight up, blended by
    /// sqrt(max(0, d.y)) as fathom-trace's sky is.
    Sky {
        /// Straight up.
        top: DVec3,
        /// At and below the horizon.
        bottom: DVec3,
    },
    /// The same radiance from every direction (the white furnace).
    Uniform(DVec3),
    /// An equirectangular map, scaled by `strength` and turned by `rotation` (radians, about
    /// +y).
    Map {
        /// The map.
        map: Arc<EnvMap>,
        /// Radiance scale.
        strength: f64,
        /// Turn about +y, radians.
        rotation: f64,
    },
}

impl Environment {
    /// Radiance arriving from direction `d` (unit).
    pub fn radiance(&self, d: DVec3) -> DVec3 {
        match self {
            Environment::Sky { top, bottom } => {
                let u = d.y.clamp(0.0, 1.0).sqrt();
                bottom.lerp(*top, u)
            }
            Environment::Uniform(c) => *c,
            Environment::Map {
                map,
                strength,
                rotation,
            } => map.radiance(rotate_y(d, -rotation)) * *strength,
        }
    }

    /// A direction to the environment: (direction, radiance, density).
    pub fn sample(&self, u: [f64; 2]) -> (DVec3, DVec3, f64) {
        match self {
            Environment::Map {
                map,
                strength,
                rotation,
            } => {
                let (d, l, pdf) = map.sample(u);
                (rotate_y(d, *rotation), l * *strength, pdf)
            }
            _ => {
                let d = uniform_sphere(u);
                (d, self.radiance(d), 1.0 / (4.0 * PI))
            }
        }
    }

    /// Density of [`Environment::sample`] choosing `d`.
    pub fn pdf(&self, d: DVec3) -> f64 {
        match self {
            Environment::Map { map, rotation, .. } => map.pdf(rotate_y(d, -rotation)),
            _ => 1.0 / (4.0 * PI),
        }
    }

    /// Whether it gives no light at all (then it is not sampled).
    pub fn is_black(&self) -> bool {
        match self {
            Environment::Sky { top, bottom } => {
                top.max_element() <= 0.0 && bottom.max_element() <= 0.0
            }
            Environment::Uniform(c) => c.max_element() <= 0.0,
            Environment::Map { strength, .. } => *strength <= 0.0,
        }
    }
}

fn rotate_y(d: DVec3, a: f64) -> DVec3 {
    if a == 0.0 {
        return d;
    }
    let (s, c) = a.sin_cos();
    DVec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legacy_lights_keep_their_irradiance() {
        let l = fathom_core::scene::Light::default();
        for radius in [0.0, 0.01, 0.1] {
            let c = ConeLight::from_legacy(&l, radius);
            // Normal irradiance by integrating the cone's radiance times cos.
            let n = 4000;
            let mut e = DVec3::ZERO;
            for k in 0..n {
                let u = [(k as f64 + 0.5) / n as f64, 0.37];
                let s = c.sample(u);
                let w = if s.pdf.is_infinite() {
                    1.0
                } else {
                    1.0 / s.pdf
                };
                e += s.radiance * s.wi.dot(c.direction) * w;
            }
            e /= n as f64;
            let want = DVec3::from(l.colour) * l.intensity * PI;
            assert!(
                (e - want).abs().max_element() < 1e-3,
                "radius {radius}: {e} vs {want}"
            );
        }
    }

    #[test]
    fn lights_without_shadows_are_directions_with_the_same_irradiance() {
        let l = fathom_core::scene::Light {
            shadows: false,
            ..Default::default()
        };
        let c = ConeLight::from_legacy(&l, 0.1);
        assert!(c.is_delta() && c.one_minus_cos == 0.0);
        let s = c.sample([0.3, 0.6]);
        assert!(s.pdf.is_infinite() && !s.shadows);
        assert_eq!(s.radiance, DVec3::from(l.colour) * l.intensity * PI);
    }

    #[test]
    fn sphere_light_samples_hit_the_sphere_with_the_cone_density() {
        let s = SphereLight {
            centre: DVec3::new(0.0, 3.0, 0.0),
            radius: 0.5,
            colour: [1.0; 3],
            strength: 10.0,
        };
        s.validate(0).unwrap();
        let p = DVec3::ZERO;
        let want_pdf = 1.0 / (2.0 * PI * (1.0 - (1.0 - 0.25f64 / 9.0).sqrt()));
        for k in 0..100 {
            let u = [(k as f64 + 0.5) / 100.0, (k * 37 % 100) as f64 / 100.0];
            let ls = s.sample(p, u).unwrap();
            let t = s.intersect(p, ls.wi).expect("sample misses the sphere");
            assert!((t - ls.distance).abs() < 1e-9);
            assert!(
                (ls.pdf - want_pdf).abs() < 1e-9 * want_pdf
                    && (s.pdf(p) - want_pdf).abs() < 1e-9 * want_pdf
            );
        }
        assert!(s.sample(DVec3::new(0.0, 3.1, 0.0), [0.5, 0.5]).is_none());
        let bad = SphereLight {
            radius: -1.0,
            ..s.clone()
        };
        assert_eq!(
            bad.validate(2).unwrap_err().to_string(),
            "sphere light 2: radius = -1 is out of range (0, 1e12]"
        );
        let bad = SphereLight {
            strength: f64::NAN,
            ..s
        };
        assert!(
            bad.validate(0)
                .unwrap_err()
                .to_string()
                .contains("strength = NaN")
        );
    }

    #[test]
    fn sky_matches_the_blinn_phong_sky() {
        let e = Environment::Sky {
            top: DVec3::new(0.1, 0.2, 0.3),
            bottom: DVec3::new(0.5, 0.5, 0.5),
        };
        assert_eq!(e.radiance(DVec3::Y), DVec3::new(0.1, 0.2, 0.3));
        assert_eq!(e.radiance(-DVec3::Y), DVec3::splat(0.5));
        let d = DVec3::new(0.6, 0.25, 0.0).normalize();
        let u = d.y.sqrt();
        assert!((e.radiance(d).x - (0.5 + (0.1 - 0.5) * u)).abs() < 1e-12);
    }
}
