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
