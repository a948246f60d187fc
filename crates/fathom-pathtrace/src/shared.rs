//! Constants the CPU path tracer and a future WGSL port must agree on, defined once here.
//!
//! Every number that changes what an image converges to (offsets, table sizes, bounce limits,
//! the denoiser's kernel) lives here, so a shader generated from this list cannot drift from
//! the CPU reference the tests check. [`WGSL_CONSTANTS`] lists them in the same shape as
//! `fathom_core::shared::WGSL_CONSTANTS`.

pub use fathom_core::shared::{WgslConstant, WgslType};

/// A new ray leaves a surface this many hit epsilons along the normal (on the side it goes
/// to). The tracer stops within one epsilon of the surface and fractal estimates undershoot
/// near it; 4 is what fathom-trace lifts its shadow rays by (`SHADOW_LIFT`), and the
/// no-self-shadowing test in `integrator` fails with 0 (acne on a plane at grazing angles)
/// and passes with 1 and 4; 4 keeps a margin for fractal estimates.
pub const SURFACE_LIFT: f64 = 4.0;
/// Smallest hit epsilon in world units (the floor under the pixel-footprint epsilon).
pub const MIN_EPSILON: f64 = 1e-9;
/// Sample tiles are this many pixels on a side.
pub const TILE: u32 = 16;
/// Bounces after which Russian roulette may end a path.
pub const RR_START: u32 = 3;
/// Russian roulette never survives with probability above this (keeps loops in closed
/// white scenes finite) ...
pub const RR_MAX_SURVIVAL: f64 = 0.95;
/// ... and never below this (keeps the variance of survivors bounded).
pub const RR_MIN_SURVIVAL: f64 = 0.05;
/// Resolution of the GGX directional-albedo tables along cos(theta) and along alpha.
pub const ALBEDO_TABLE: usize = 32;
/// Smallest GGX alpha: below it a lobe is treated as this rough (keeps D finite).
pub const MIN_ALPHA: f64 = 1e-3;
/// À-trous passes of the denoiser (step widths 1, 2, 4, ...).
pub const ATROUS_PASSES: u32 = 3;
/// Default normal-weight exponent of the denoiser (SVGF's sigma_n).
pub const DENOISE_SIGMA_NORMAL: f64 = 128.0;
/// Default depth-weight scale of the denoiser (SVGF's sigma_z).
pub const DENOISE_SIGMA_DEPTH: f64 = 1.0;
/// Default luminance-weight scale of the denoiser (SVGF's sigma_l).
pub const DENOISE_SIGMA_LUMINANCE: f64 = 4.0;

/// The denoiser divides colour by the first-hit albedo floored at this (black surfaces keep
/// their colour undivided).
pub const DENOISE_MIN_ALBEDO: f64 = 1e-3;

const fn f(name: &'static str, value: f64) -> WgslConstant {
    WgslConstant::f32(name, value)
}

const fn u(name: &'static str, value: u32) -> WgslConstant {
    WgslConstant::u32(name, value)
}

/// Every constant a WGSL port of the path tracer shares with this crate.
pub const WGSL_CONSTANTS: &[WgslConstant] = &[
    f("PT_SURFACE_LIFT", SURFACE_LIFT),
    f("PT_MIN_EPSILON", MIN_EPSILON),
    u("PT_TILE", TILE),
    u("PT_RR_START", RR_START),
    f("PT_RR_MAX_SURVIVAL", RR_MAX_SURVIVAL),
    f("PT_RR_MIN_SURVIVAL", RR_MIN_SURVIVAL),
    u("PT_ALBEDO_TABLE", ALBEDO_TABLE as u32),
    f("PT_MIN_ALPHA", MIN_ALPHA),
    u("PT_ATROUS_PASSES", ATROUS_PASSES),
    f("PT_DENOISE_SIGMA_NORMAL", DENOISE_SIGMA_NORMAL),
    f("PT_DENOISE_SIGMA_DEPTH", DENOISE_SIGMA_DEPTH),
    f("PT_DENOISE_SIGMA_LUMINANCE", DENOISE_SIGMA_LUMINANCE),
    f("PT_DENOISE_MIN_ALBEDO", DENOISE_MIN_ALBEDO),
];

/// [`WGSL_CONSTANTS`] as WGSL `const` declarations, for a shader to include ahead of its code.
pub fn wgsl_declarations() -> String {
    fathom_core::shared::declarations("fathom_pathtrace::shared", WGSL_CONSTANTS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_u32s_exact() {
        for (i, a) in WGSL_CONSTANTS.iter().enumerate() {
            assert!(WGSL_CONSTANTS[i + 1..].iter().all(|b| b.name != a.name));
            if a.ty == WgslType::U32 {
                assert_eq!(a.value.fract(), 0.0, "{}", a.name);
            }
        }
    }
}
