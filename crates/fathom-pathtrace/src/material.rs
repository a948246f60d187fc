//! The physically based material a surface point has, its validation, and how today's
//! Blinn-Phong [`fathom_core::Material`] maps onto it.
//!
//! The parameters follow the "principled" convention of Burley 2012 ("Physically Based Shading
//! at Disney") as glTF and Blender use it: a base colour that is the diffuse albedo of a
//! dielectric or the reflectance (F0) of a metal, a metallic mix, a perceptual roughness
//! (GGX alpha = roughness^2), a specular level whose 0.5 is a 4 % dielectric F0, a specular
//! tint towards the base colour, emission (colour x strength), and transmission through the
//! shape's interior with an index of refraction and Beer-Lambert absorption.
//!
//! **Today's files keep their meaning** ([`PbrMaterial::from_legacy`]):
//! - `albedo` is the base colour; `metallic`, `emission` (x `emission_strength`),
//!   `transmission` and `ior` carry over as they are (their defaults: an opaque, non-emissive
//!   dielectric of IOR 1.5, what files without them always meant);
//! - the Blinn-Phong exponent `n` becomes a GGX alpha by Walter et al.'s correspondence
//!   ("Microfacet Models for Refraction through Rough Surfaces", EGSR 2007)
//!   `alpha = sqrt(2 / (n + 2))`, so roughness = `alpha^(1/2)` (n = 32: 0.49; n = 128: 0.35);
//! - `specular` (the highlight's strength, [0, 1]) is the specular level: dielectric
//!   F0 = 0.08 x specular, so the default 0.3 gives F0 = 2.4 % and 0.5 the usual 4 %;
//! - `trap_colour` is not a material property but a colouring rule; [`crate::colour`] keeps it.

use glam::DVec3;

/// Why a material was refused: the field, its value and the accepted range.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MaterialError {
    /// A value outside its range, or not finite.
    #[error("material.{field} = {value} is out of range [{min}, {max}]")]
    OutOfRange {
        /// The field's name (`base_colour[1]` for a component).
        field: String,
        /// The value given.
        value: f64,
        /// Smallest accepted value.
        min: f64,
        /// Largest accepted value.
        max: f64,
    },
}

/// Largest emission strength (radiance multiplier).
pub const MAX_EMISSION_STRENGTH: f64 = 1e6;
/// Smallest index of refraction.
pub const MIN_IOR: f64 = 1.0;
/// Largest index of refraction (diamond is 2.42; a few crystals reach 3).
pub const MAX_IOR: f64 = 4.0;
/// Largest absorption coefficient per world unit.
pub const MAX_ABSORPTION: f64 = 1e6;

/// A physically based surface (and, with transmission, interior).
#[derive(Clone, Debug, PartialEq)]
pub struct PbrMaterial {
    /// Diffuse albedo of the dielectric part, F0 of the metallic part; linear RGB in [0, 1].
    pub base_colour: [f64; 3],
    /// 0 dielectric, 1 metal, [0, 1].
    pub metallic: f64,
    /// Perceptual roughness; GGX alpha = roughness^2, [0, 1].
    pub roughness: f64,
    /// Dielectric specular level: F0 = 0.08 x specular, [0, 1].
    pub specular: f64,
    /// How far the dielectric specular colour moves from white to the base colour, [0, 1].
    pub specular_tint: f64,
    /// Emitted colour, linear RGB in [0, 1].
    pub emission: [f64; 3],
    /// Emitted radiance = emission x emission_strength, [0, MAX_EMISSION_STRENGTH].
    pub emission_strength: f64,
    /// Fraction of the dielectric part that is a smooth refracting interface, [0, 1].
    pub transmission: f64,
    /// Index of refraction of the interior, [MIN_IOR, MAX_IOR].
    pub ior: f64,
    /// Beer-Lambert absorption coefficient of the interior per world unit and channel,
    /// [0, MAX_ABSORPTION].
    pub absorption: [f64; 3],
}

impl Default for PbrMaterial {
    fn default() -> Self {
        PbrMaterial::from_legacy(&fathom_core::Material::default())
    }
}

impl PbrMaterial {
    /// A white diffuse material of the given albedo (no specular, no emission).
    pub fn diffuse(albedo: [f64; 3]) -> Self {
        PbrMaterial {
            base_colour: albedo,
            metallic: 0.0,
            roughness: 1.0,
            specular: 0.0,
            specular_tint: 0.0,
            emission: [0.0; 3],
            emission_strength: 0.0,
            transmission: 0.0,
            ior: 1.5,
            absorption: [0.0; 3],
        }
    }

    /// The material today's Blinn-Phong parameters mean (see the module docs).
    pub fn from_legacy(m: &fathom_core::Material) -> Self {
        let alpha = (2.0 / (m.shininess.max(0.0) + 2.0)).sqrt();
        PbrMaterial {
            base_colour: m.albedo.map(|c| c.clamp(0.0, 1.0)),
            roughness: alpha.sqrt().clamp(0.0, 1.0),
            specular: m.specular.clamp(0.0, 1.0),
            metallic: m.metallic.clamp(0.0, 1.0),
            emission: m.emission.map(|c| c.clamp(0.0, 1.0)),
            emission_strength: m.emission_strength.clamp(0.0, MAX_EMISSION_STRENGTH),
            transmission: m.transmission.clamp(0.0, 1.0),
            ior: m.ior,
            ..PbrMaterial::diffuse([0.0; 3])
        }
    }

    /// GGX alpha of this roughness (floored at [`crate::shared::MIN_ALPHA`]).
    pub fn alpha(&self) -> f64 {
        (self.roughness * self.roughness).max(crate::shared::MIN_ALPHA)
    }

    /// Emitted radiance.
    pub fn emitted(&self) -> DVec3 {
        DVec3::from(self.emission) * self.emission_strength
    }

    /// Checks every field against its range.
    pub fn validate(&self) -> Result<(), MaterialError> {
        let unit = |field: String, v: f64| check(field, v, 0.0, 1.0);
        for (i, &c) in self.base_colour.iter().enumerate() {
            unit(format!("base_colour[{i}]"), c)?;
        }
        for (i, &c) in self.emission.iter().enumerate() {
            unit(format!("emission[{i}]"), c)?;
        }
        for (i, &c) in self.absorption.iter().enumerate() {
            check(format!("absorption[{i}]"), c, 0.0, MAX_ABSORPTION)?;
        }
        unit("metallic".into(), self.metallic)?;
        unit("roughness".into(), self.roughness)?;
        unit("specular".into(), self.specular)?;
        unit("specular_tint".into(), self.specular_tint)?;
        unit("transmission".into(), self.transmission)?;
        check(
            "emission_strength".into(),
            self.emission_strength,
            0.0,
            MAX_EMISSION_STRENGTH,
        )?;
        check("ior".into(), self.ior, MIN_IOR, MAX_IOR)?;
        Ok(())
    }

    /// `self` and `other` mixed with weight `w` of `other` (smooth combines blend materials).
    pub fn lerp(&self, other: &PbrMaterial, w: f64) -> PbrMaterial {
        let l = |a: f64, b: f64| a + (b - a) * w;
        let l3 = |a: [f64; 3], b: [f64; 3]| [l(a[0], b[0]), l(a[1], b[1]), l(a[2], b[2])];
        PbrMaterial {
            base_colour: l3(self.base_colour, other.base_colour),
            metallic: l(self.metallic, other.metallic),
            roughness: l(self.roughness, other.roughness),
            specular: l(self.specular, other.specular),
            specular_tint: l(self.specular_tint, other.specular_tint),
            emission: l3(self.emission, other.emission),
            emission_strength: l(self.emission_strength, other.emission_strength),
            transmission: l(self.transmission, other.transmission),
            ior: l(self.ior, other.ior),
            absorption: l3(self.absorption, other.absorption),
        }
    }
}

fn check(field: String, value: f64, min: f64, max: f64) -> Result<(), MaterialError> {
    if value.is_finite() && (min..=max).contains(&value) {
        Ok(())
    } else {
        Err(MaterialError::OutOfRange {
            field,
            value,
            min,
            max,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legacy_materials_map_as_documented() {
        let m = PbrMaterial::from_legacy(&fathom_core::Material {
            albedo: [0.2, 0.4, 0.6],
            specular: 0.5,
            shininess: 32.0,
            trap_colour: 0.0,
            ..Default::default()
        });
        assert_eq!(m.base_colour, [0.2, 0.4, 0.6]);
        assert!((m.alpha() - (2.0f64 / 34.0).sqrt()).abs() < 1e-12);
        assert_eq!(m.specular, 0.5);
        assert_eq!(m.metallic, 0.0);
        m.validate().unwrap();
        // The scene's physically based fields carry over.
        let glass = PbrMaterial::from_legacy(&fathom_core::Material {
            metallic: 0.25,
            emission: [1.0, 0.5, 0.0],
            emission_strength: 3.0,
            transmission: 1.0,
            ior: 1.33,
            ..Default::default()
        });
        assert_eq!(
            (glass.metallic, glass.transmission, glass.ior),
            (0.25, 1.0, 1.33)
        );
        assert_eq!(glass.emitted(), DVec3::new(3.0, 1.5, 0.0));
        glass.validate().unwrap();
        // Sharper highlights are smoother surfaces.
        let sharp = PbrMaterial::from_legacy(&fathom_core::Material {
            shininess: 1024.0,
            ..Default::default()
        });
        assert!(sharp.roughness < m.roughness);
    }

    #[test]
    fn bad_values_name_the_field_and_range() {
        let cases: Vec<(PbrMaterial, &str)> = vec![
            (
                PbrMaterial {
                    roughness: f64::NAN,
                    ..Default::default()
                },
                "material.roughness = NaN is out of range [0, 1]",
            ),
            (
                PbrMaterial {
                    ior: 0.5,
                    ..Default::default()
                },
                "material.ior = 0.5 is out of range [1, 4]",
            ),
            (
                PbrMaterial {
                    emission_strength: f64::INFINITY,
                    ..Default::default()
                },
                "material.emission_strength = inf is out of range [0, 1000000]",
            ),
            (
                PbrMaterial {
                    base_colour: [0.5, 1.5, 0.5],
                    ..Default::default()
                },
                "material.base_colour[1] = 1.5 is out of range [0, 1]",
            ),
            (
                PbrMaterial {
                    absorption: [0.0, 0.0, -1.0],
                    ..Default::default()
                },
                "material.absorption[2] = -1 is out of range [0, 1000000]",
            ),
        ];
        for (m, want) in cases {
            assert_eq!(m.validate().unwrap_err().to_string(), want);
        }
    }
}
