//! The one WGSL program: hand-written functions per registry entry (`src/wgsl/*.wgsl`, named
//! `prim_<Name>`, `frac_<Name>`, `xf_<Name>`, `mod_<Name>`, `comb_<Name>`), glued to the tape
//! interpreter by dispatch functions that are GENERATED here from the registry tables. The
//! opcode indices and each entry's parameter layout therefore come from the same tables the CPU
//! uses: an entry without a WGSL function, or with a function whose signature does not match
//! its declared parameters, fails naga validation with an error naming the entry.

use fathom_core::combine::COMBINES;
use fathom_core::fractals::FRACTALS;
use fathom_core::modifiers::MODIFIERS;
use fathom_core::primitives::PRIMITIVES;
use fathom_core::registry::{Def, ParamKind};
use fathom_core::transforms::TRANSFORMS;
use std::fmt::Write;
use wgpu::naga;

/// The hand-written WGSL files, in the order they are concatenated.
pub const COMMON: &str = include_str!("wgsl/common.wgsl");
/// Primitive distance functions.
pub const PRIMITIVES_WGSL: &str = include_str!("wgsl/primitives.wgsl");
/// Fractal distance estimators.
pub const FRACTALS_WGSL: &str = include_str!("wgsl/fractals.wgsl");
/// Domain operators.
pub const TRANSFORMS_WGSL: &str = include_str!("wgsl/transforms.wgsl");
/// Distance modifiers.
pub const MODIFIERS_WGSL: &str = include_str!("wgsl/modifiers.wgsl");
/// Combine operators.
pub const COMBINE_WGSL: &str = include_str!("wgsl/combine.wgsl");
/// The tape interpreter.
pub const INTERP: &str = include_str!("wgsl/interp.wgsl");
/// The point-evaluation entry point.
pub const EVAL_POINTS: &str = include_str!("wgsl/eval_points.wgsl");
/// The render passes (prepass, depth, shade).
pub const TRACE: &str = include_str!("wgsl/trace.wgsl");
/// Display conversions (tonemap, sRGB) shared by the render passes and the path tracer.
pub const POST: &str = include_str!("wgsl/post.wgsl");
/// The path tracer (fathom-pathtrace's integrator in WGSL).
pub const PATH: &str = include_str!("wgsl/path.wgsl");
/// The path tracer's per-pixel running sums, shared by the tracer and the denoiser.
pub const ACCUM: &str = include_str!("wgsl/accum.wgsl");
/// The à-trous denoiser (fathom-pathtrace's denoise.rs in WGSL).
pub const DENOISE: &str = include_str!("wgsl/denoise.wgsl");

/// One registry family as the WGSL side sees it.
pub struct WgslFamily {
    /// Family noun for messages.
    pub noun: &'static str,
    /// Prefix of the WGSL function names.
    pub prefix: &'static str,
    /// The registry table.
    pub defs: &'static [Def],
    /// The WGSL file holding the functions.
    pub source: &'static str,
}

/// Every family with WGSL functions, in tape-family order (1..=5).
pub fn families() -> [WgslFamily; 5] {
    [
        WgslFamily {
            noun: "primitive",
            prefix: "prim_",
            defs: PRIMITIVES,
            source: PRIMITIVES_WGSL,
        },
        WgslFamily {
            noun: "fractal",
            prefix: "frac_",
            defs: FRACTALS,
            source: FRACTALS_WGSL,
        },
        WgslFamily {
            noun: "domain operator",
            prefix: "xf_",
            defs: TRANSFORMS,
            source: TRANSFORMS_WGSL,
        },
        WgslFamily {
            noun: "distance modifier",
            prefix: "mod_",
            defs: MODIFIERS,
            source: MODIFIERS_WGSL,
        },
        WgslFamily {
            noun: "combine operator",
            prefix: "comb_",
            defs: COMBINES,
            source: COMBINE_WGSL,
        },
    ]
}

/// Registry entries with no `fn <prefix><Name>(` in their family's WGSL file, as
/// `"primitive Sphere (fn prim_Sphere)"`.
pub fn missing_functions() -> Vec<String> {
    let mut out = Vec::new();
    for f in families() {
        for d in f.defs {
            let fname = format!("{}{}", f.prefix, d.name);
            if !f.source.contains(&format!("fn {fname}(")) {
                out.push(format!("{} {} (fn {fname})", f.noun, d.name));
            }
        }
    }
    out
}

/// The argument list that reads an entry's operands from the parameter buffer at offset `a`,
/// following the declared layout (or the raw offset for entries with a bake function).
fn param_args(d: &Def) -> String {
    if d.bake.is_some() {
        return ", a".into();
    }
    let mut s = String::new();
    let mut off = 0usize;
    for p in d.params {
        match p.kind {
            ParamKind::Scalar => write!(s, ", params[a + {off}u]").unwrap(),
            ParamKind::Int => write!(s, ", u32(params[a + {off}u])").unwrap(),
            ParamKind::Vec3 => write!(s, ", param_vec3(a + {off}u)").unwrap(),
        }
        off += p.kind.width();
    }
    s
}

/// Generates the five `op_*` dispatch functions from the registry tables.
pub fn dispatch() -> String {
    let fams = families();
    let mut s = String::from("// GENERATED from the fathom-core registry tables by shader.rs.\n\n");
    // (signature, result variable init, call template: {f} = function, {args} = params)
    let shapes: [(&str, &str, &str, &str); 5] = [
        (
            "fn op_prim(i: u32, a: u32, p: vec3f) -> f32",
            "var r = 1e20;",
            "r = {f}(p{args});",
            "return r;",
        ),
        (
            "fn op_frac(i: u32, a: u32, p: vec3f) -> vec2f",
            "var r = vec2f(1e20, NO_TRAP);",
            "r = {f}(p{args});",
            "return r;",
        ),
        (
            "fn op_xf(i: u32, a: u32, p: ptr<function, vec3f>, k: ptr<function, f32>)",
            "",
            "{f}(p, k{args});",
            "",
        ),
        (
            "fn op_mod(i: u32, a: u32, d: f32, k: f32) -> f32",
            "var r = d;",
            "r = {f}(d, k{args});",
            "return r;",
        ),
        (
            "fn op_comb(i: u32, a: u32, va: Val, vb: Val, k: f32) -> Val",
            "var r = va;",
            "r = {f}(va, vb, k{args});",
            "return r;",
        ),
    ];
    for (f, (sig, init, call, ret)) in fams.iter().zip(shapes) {
        writeln!(s, "{sig} {{").unwrap();
        if !init.is_empty() {
            writeln!(s, "    {init}").unwrap();
        }
        writeln!(s, "    switch i {{").unwrap();
        for (idx, d) in f.defs.iter().enumerate() {
            let c = call
                .replace("{f}", &format!("{}{}", f.prefix, d.name))
                .replace("{args}", &param_args(d));
            writeln!(s, "        case {idx}u: {{ {c} }} // {} {}", f.noun, d.name).unwrap();
        }
        writeln!(s, "        default: {{}}\n    }}").unwrap();
        if !ret.is_empty() {
            writeln!(s, "    {ret}").unwrap();
        }
        s += "}\n\n";
    }
    s
}

/// The tape interpreter as a library for other shaders: the constants shared with Rust, the
/// common declarations (the tape's instruction and parameter buffers at `@group(0)
/// @binding(0)` and `@binding(1)`), every family, the generated dispatch and `eval_tape` /
/// `eval_distance`, without this crate's own entry points and bindings. fathom-micro's
/// fragment shader is written on top of it.
pub fn interpreter_source() -> String {
    let mut s = fathom_core::shared::wgsl_declarations();
    for part in [COMMON, PRIMITIVES_WGSL, FRACTALS_WGSL, TRANSFORMS_WGSL] {
        s += part;
        s += "\n";
    }
    for part in [MODIFIERS_WGSL, COMBINE_WGSL] {
        s += part;
        s += "\n";
    }
    s += &dispatch();
    s += INTERP;
    s += "\n";
    s
}

/// The whole WGSL program: the interpreter library and the entry points.
pub fn source() -> String {
    let mut s = interpreter_source();
    for part in [EVAL_POINTS, POST, TRACE] {
        s += part;
        s += "\n";
    }
    s
}

/// The path tracer's WGSL program: the interpreter library, the constants shared with
/// fathom-pathtrace (`fathom_pathtrace::shared`) and with `crate::path`, and `path.wgsl`. A
/// module of its own, built the first time a path is traced, so the preview passes never
/// pay for compiling it.
pub fn path_source() -> String {
    let mut s = interpreter_source();
    s += &fathom_pathtrace::shared::wgsl_declarations();
    s += &crate::path_state::wgsl_declarations();
    for part in [POST, ACCUM, PATH] {
        s += part;
        s += "\n";
    }
    s
}

/// The denoiser's WGSL program (no interpreter: it reads only the accumulation).
pub fn denoise_source() -> String {
    let mut s = fathom_pathtrace::shared::wgsl_declarations();
    for part in [POST, ACCUM, DENOISE] {
        s += part;
        s += "\n";
    }
    s
}

/// Why the WGSL did not validate, with the registry entry (or function) it happened in.
#[derive(Debug, thiserror::Error)]
#[error("WGSL validation failed in {location}: {message}")]
pub struct ShaderError {
    /// "primitive `Sphere` (fn prim_Sphere)" or "fn eval_tape", or "the WGSL source".
    pub location: String,
    /// naga's readable report.
    pub message: String,
}

/// Names the registry entry (or function) that contains byte `offset` of `src`.
fn locate(src: &str, offset: usize) -> String {
    let before = &src[..offset.min(src.len())];
    // A generated dispatch line names its entry in a trailing comment.
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let line_end = src[line_start..]
        .find('\n')
        .map_or(src.len(), |i| line_start + i);
    let line = &src[line_start..line_end];
    if let Some(c) = line.find("} // ") {
        return format!("{} (dispatch)", &line[c + 5..]);
    }
    let Some(fpos) = before.rfind("\nfn ") else {
        return "the WGSL source".into();
    };
    let name: String = src[fpos + 4..]
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    for f in families() {
        if let Some(entry) = name.strip_prefix(f.prefix)
            && f.defs.iter().any(|d| d.name == entry)
        {
            return format!("{} `{entry}` (fn {name})", f.noun);
        }
    }
    format!("fn {name}")
}

/// Parses and validates WGSL with naga; errors name the registry entry they occur in.
pub fn validate(src: &str) -> Result<naga::Module, ShaderError> {
    let module = naga::front::wgsl::parse_str(src).map_err(|e| ShaderError {
        location: e
            .location(src)
            .map(|l| locate(src, l.offset as usize))
            .unwrap_or_else(|| "the WGSL source".into()),
        message: e.emit_to_string(src),
    })?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| ShaderError {
        location: e
            .spans()
            .next()
            .and_then(|(span, _)| span.to_range())
            .map(|r| locate(src, r.start))
            .unwrap_or_else(|| "the WGSL source".into()),
        message: e.emit_to_string(src),
    })?;
    Ok(module)
}

#[cfg(test)]
mod tests;
