//! The white-furnace cases: materials that neither make nor lose energy, so an object of any
//! of them inside a uniform environment of radiance 1 converges to 1 everywhere. The CPU
//! integrator's tests and the GPU port's tests check the same list.

use crate::material::PbrMaterial;

/// One case: a name for messages, the material, and the relative tolerance its mean must
/// meet (the rough lobes carry the albedo tables' interpolation error, see the BSDF tests).
pub type FurnaceCase = (&'static str, PbrMaterial, f64);

/// Diffuse albedo 1, rough metal with F0 1, a smooth dielectric of IOR 1.5 and white plastic.
pub fn furnace_cases() -> Vec<FurnaceCase> {
    vec![
        ("diffuse, albedo 1", PbrMaterial::diffuse([1.0; 3]), 0.01),
        (
            "rough metal, F0 1",
            PbrMaterial {
                metallic: 1.0,
                roughness: 0.8,
                ..PbrMaterial::diffuse([1.0; 3])
            },
            0.015,
        ),
        (
            "smooth dielectric, ior 1.5",
            PbrMaterial {
                transmission: 1.0,
                ior: 1.5,
                roughness: 0.0,
                ..PbrMaterial::diffuse([1.0; 3])
            },
            0.01,
        ),
        (
            "white plastic",
            PbrMaterial {
                roughness: 0.5,
                specular: 1.0,
                ..PbrMaterial::diffuse([1.0; 3])
            },
            0.015,
        ),
    ]
}
