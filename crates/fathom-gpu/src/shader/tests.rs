//! Checks of the WGSL program that need no device: coverage of the registry, naga validation,
//! the generated dispatch, and errors that name the entry they are in.

use super::*;

#[test]
fn every_registry_entry_has_a_wgsl_function() {
    let missing = missing_functions();
    assert!(
        missing.is_empty(),
        "registry entries without WGSL (add them to crates/fathom-gpu/src/wgsl/):\n  {}",
        missing.join("\n  ")
    );
}

#[test]
fn the_whole_program_validates_with_naga() {
    let src = source();
    if let Err(e) = validate(&src) {
        panic!("{e}");
    }
}

#[test]
fn dispatch_cases_follow_the_registry_tables() {
    let d = dispatch();
    for f in families() {
        for (i, def) in f.defs.iter().enumerate() {
            let want = format!("case {i}u: {{");
            let line = d
                .lines()
                .find(|l| l.contains(&want) && l.ends_with(&format!("// {} {}", f.noun, def.name)))
                .unwrap_or_else(|| panic!("no dispatch case {i} for {} {}", f.noun, def.name));
            assert!(
                line.contains(&format!("{}{}(", f.prefix, def.name)),
                "{line}"
            );
        }
    }
}

#[test]
fn parameter_layout_follows_the_declaration() {
    // Torus: two scalars; Box: one Vec3; Mandelbulb: Scalar, Int, Scalar, Scalar, Scalar, Scalar; Rotate:
    // baked.
    let d = dispatch();
    assert!(
        d.contains("prim_Torus(p, params[a + 0u], params[a + 1u])"),
        "{d}"
    );
    assert!(d.contains("prim_Box(p, param_vec3(a + 0u))"));
    assert!(d.contains(
        "frac_Mandelbulb(p, params[a + 0u], u32(params[a + 1u]), params[a + 2u], params[a + 3u], params[a + 4u], params[a + 5u])"
    ));
    assert!(d.contains("xf_Rotate(p, k, a)"));
}

#[test]
fn a_broken_entry_is_named_in_the_error() {
    let src = source().replace(
        "return length(p) - radius;",
        "return length(p) - radius + not_declared;",
    );
    let e = validate(&src).expect_err("an undeclared name must not validate");
    assert!(
        e.location.contains("primitive `Sphere`"),
        "location: {}",
        e.location
    );
}

#[test]
fn a_missing_function_is_named_by_its_dispatch_case() {
    let src = source().replace("fn prim_Torus(", "fn prim_Torus_gone(");
    let e = validate(&src).expect_err("a missing function must not validate");
    assert!(
        e.to_string().contains("Torus"),
        "error does not name the entry: {e}"
    );
}

#[test]
fn a_type_mismatch_is_named() {
    // A primitive whose WGSL takes a different parameter type than the registry declares.
    let src = source().replace(
        "fn prim_Sphere(p: vec3f, radius: f32)",
        "fn prim_Sphere(p: vec3f, radius: vec3f)",
    );
    let e = validate(&src).expect_err("a mistyped parameter must not validate");
    assert!(e.to_string().contains("Sphere"), "{e}");
}

#[test]
fn rust_mirrors_of_the_wgsl_structs_have_the_same_layout() {
    // The uniform block and G-buffer pixel are declared in trace.wgsl and mirrored in
    // passes.rs: every field's name and offset, and the struct size, must agree with naga's
    // layout of the WGSL declaration.
    let module = validate(&source()).unwrap();
    check_layouts(&module, crate::passes::rust_layouts());
}

#[test]
fn the_path_tracer_validates_and_its_rust_mirrors_have_the_same_layout() {
    let module = validate(&path_source()).unwrap();
    check_layouts(&module, crate::path::rust_layouts());
}

#[test]
fn the_denoiser_validates_and_its_rust_mirrors_have_the_same_layout() {
    let module = validate(&denoise_source()).unwrap();
    check_layouts(&module, crate::denoise::rust_layouts());
}

fn check_layouts(module: &naga::Module, layouts: Vec<crate::passes::Layout>) {
    for (rust_name, size, fields) in layouts {
        let wgsl_name = rust_name.strip_prefix("Gpu").unwrap_or(rust_name);
        let (members, span) = module
            .types
            .iter()
            .find_map(|(_, t)| match &t.inner {
                naga::TypeInner::Struct { members, span }
                    if t.name.as_deref() == Some(wgsl_name) =>
                {
                    Some((members, *span))
                }
                _ => None,
            })
            .unwrap_or_else(|| panic!("no struct {wgsl_name} in the WGSL"));
        let wgsl: Vec<(String, u32)> = members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
            .collect();
        let rust: Vec<(String, u32)> = fields
            .iter()
            .map(|(n, o, _)| (n.to_string(), *o as u32))
            .collect();
        assert_eq!(
            rust, wgsl,
            "{rust_name} vs WGSL {wgsl_name}: fields and offsets"
        );
        assert_eq!(size as u32, span, "{rust_name} vs WGSL {wgsl_name}: size");
        // Each field fills the space up to the next (no hidden padding on either side).
        for (k, (n, o, s)) in fields.iter().enumerate() {
            let next = fields.get(k + 1).map_or(size, |f| f.1);
            assert_eq!(o + s, next, "{rust_name}.{n} leaves a gap");
        }
    }
}

#[test]
fn shared_constants_are_generated_not_typed_into_wgsl_files() {
    // A constant of fathom_core::shared written into a .wgsl file by hand could drift from
    // Rust; it must come only from the generated declarations.
    for name in fathom_core::shared::WGSL_CONSTANTS
        .iter()
        .map(|c| c.name)
        .chain(
            fathom_pathtrace::shared::WGSL_CONSTANTS
                .iter()
                .map(|c| c.name),
        )
        .chain(["PT_MATERIAL_VEC4S", "PT_MAX_EVALUATIONS"])
    {
        for f in families() {
            assert!(
                !f.source.contains(&format!("const {}:", name)),
                "{} declared in the {} WGSL",
                name,
                f.noun
            );
        }
        for (file, src) in [
            ("common", COMMON),
            ("interp", INTERP),
            ("trace", TRACE),
            ("eval_points", EVAL_POINTS),
            ("post", POST),
            ("path", PATH),
            ("accum", ACCUM),
            ("denoise", DENOISE),
        ] {
            assert!(
                !src.contains(&format!("const {}:", name)),
                "{} declared in {file}.wgsl",
                name
            );
        }
    }
}
