//! Constants the CPU renderers and the WGSL program must agree on, defined once here.
//!
//! fathom-gpu writes every entry of [`WGSL_CONSTANTS`] into the shader as a WGSL `const`
//! (generated, never typed into a `.wgsl` file), and the Rust side reads the same Rust
//! constants, so the tracer's over-relaxation, the shadow and AO sample counts, the prepass
//! levels, the interpreter's stack depth and the fractals' bail-outs cannot drift apart.

use crate::limits;

/// Over-relaxation factor of the enhanced tracer (Keinert et al. suggest 1.2 to 1.6 for
/// distance bounds). Measured on the Mandelbulb at 640x480 (depth evaluations per pixel; basic
/// 25.2): without the prepass 1.2 gives 20.9 and 1.5 gives 26.1; with the prepass (basic 11.6)
/// 1.2 gives 10.2 and 1.5 gives 9.6. Rendering uses the prepass by default, hence 1.5.
pub const OMEGA: f64 = 1.5;
/// Most steps of a shadow ray.
pub const SHADOW_STEPS: u32 = 96;
/// Distance samples of the ambient-occlusion estimate.
pub const AO_SAMPLES: u32 = 5;
/// Block sizes of the cone-marching prepass levels, coarsest first; each level halves the
/// block (the shader computes level `l`'s block as `PREPASS_COARSEST >> l`).
pub const PREPASS_LEVELS: [u32; 3] = [PREPASS_COARSEST, PREPASS_COARSEST / 2, PREPASS_COARSEST / 4];
/// The coarsest prepass block, in pixels.
pub const PREPASS_COARSEST: u32 = 8;
/// Orbit trap of a point no IFS loop has touched.
pub const NO_TRAP: f64 = 1e3;
/// Squared escape radius of the IFS fractals' fold loops.
pub const IFS_BAIL2: f64 = 1e8;
/// How far below zero the Mandelbulb's estimate goes inside its set (fractal units): far
/// above the scales where the inside distance matters (within a few voxels of the surface,
/// below 1e-7 for the preset), far below the steps of a sphere tracer or a Lipschitz check
/// (the preset's pixels are ~1e-3 wide), so the estimate stays 1-Lipschitz in the interior
/// (`fractals/mandelbulb.rs`).
pub const INSIDE_DEPTH: f64 = 1e-6;
/// Guard against division by zero in primitives (denominators are clamped to it).
pub const TINY: f64 = 1e-30;
/// Depth of the interpreter's point and value stacks.
pub const MAX_STACK: usize = limits::MAX_POINT_STACK;
/// Most instructions one evaluation may execute: the longest tape plus the longest IFS loop
/// (every iteration runs a full operator list and its loop bookkeeping), so a corrupt tape
/// cannot hang the device.
pub const MAX_EXECUTED: usize =
    limits::MAX_TAPE_LEN + limits::MAX_IFS_ITERATIONS as usize * (limits::MAX_OPS_PER_LIST + 2);

const _: () = assert!(limits::MAX_POINT_STACK == limits::MAX_VALUE_STACK);
const _: () = assert!(PREPASS_LEVELS[2] * 4 == PREPASS_COARSEST);

/// The WGSL type of a shared constant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WgslType {
    /// A WGSL `f32`.
    F32,
    /// A WGSL `u32`.
    U32,
}

/// One shared constant as the shader declares it.
#[derive(Clone, Copy, Debug)]
pub struct WgslConstant {
    /// The constant's name, the same in Rust and WGSL.
    pub name: &'static str,
    /// Its WGSL type.
    pub ty: WgslType,
    /// Its value (whole for `U32`).
    pub value: f64,
}

impl WgslConstant {
    /// An `f32` constant.
    pub const fn f32(name: &'static str, value: f64) -> WgslConstant {
        WgslConstant {
            name,
            ty: WgslType::F32,
            value,
        }
    }

    /// A `u32` constant.
    pub const fn u32(name: &'static str, value: u32) -> WgslConstant {
        WgslConstant {
            name,
            ty: WgslType::U32,
            value: value as f64,
        }
    }
}

const fn f(name: &'static str, value: f64) -> WgslConstant {
    WgslConstant::f32(name, value)
}

const fn u(name: &'static str, value: u32) -> WgslConstant {
    WgslConstant::u32(name, value)
}

/// Every constant the shader shares with the Rust side.
pub const WGSL_CONSTANTS: &[WgslConstant] = &[
    f("OMEGA", OMEGA),
    u("SHADOW_STEPS", SHADOW_STEPS),
    u("AO_SAMPLES", AO_SAMPLES),
    u("PREPASS_COARSEST", PREPASS_COARSEST),
    u("PREPASS_LEVEL_COUNT", PREPASS_LEVELS.len() as u32),
    f("NO_TRAP", NO_TRAP),
    f("IFS_BAIL2", IFS_BAIL2),
    f("TINY", TINY),
    f("INSIDE_DEPTH", INSIDE_DEPTH),
    u("MAX_STACK", MAX_STACK as u32),
    u("MAX_EXECUTED", MAX_EXECUTED as u32),
];

/// The WGSL declarations of [`WGSL_CONSTANTS`].
pub fn wgsl_declarations() -> String {
    declarations("fathom_core::shared", WGSL_CONSTANTS)
}

/// WGSL `const` declarations of `constants`, headed by a comment naming `source`, the Rust
/// module they are defined in (for a shader to include ahead of its code).
pub fn declarations(source: &str, constants: &[WgslConstant]) -> String {
    let mut s = format!("// GENERATED from {source}: constants shared with Rust.\n");
    for c in constants {
        let v = match c.ty {
            // `{:?}` keeps a decimal point or exponent, as WGSL's f32 literals need.
            WgslType::F32 => format!("{:?}", c.value as f32),
            WgslType::U32 => format!("{}u", c.value as u32),
        };
        let ty = match c.ty {
            WgslType::F32 => "f32",
            WgslType::U32 => "u32",
        };
        s += &format!("const {}: {ty} = {v};\n", c.name);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn declarations_are_exact_for_every_constant() {
        let d = wgsl_declarations();
        for c in WGSL_CONSTANTS {
            let line = d
                .lines()
                .find(|l| l.starts_with(&format!("const {}:", c.name)))
                .unwrap_or_else(|| panic!("{} not declared", c.name));
            let lit = line.split(" = ").nth(1).unwrap().trim_end_matches(';');
            let v: f64 = lit.trim_end_matches('u').parse().unwrap();
            assert_eq!(v as f32, c.value as f32, "{line}");
        }
        assert_eq!(MAX_EXECUTED, 16384 + 256 * 66);
    }
}
