//! Error messages and round trips of scene files.

use super::*;
use crate::presets::PRESETS;

const BASE: &str = "Scene(
    version: 1,
    root: Node(
        shape: Sphere(radius: 1.0),
    ),
)
";

/// The error for `text`, as (line, col, message); panics if it parses or has no position.
fn err(text: &str) -> (usize, usize, String) {
    match parse(text, "t.ron") {
        Ok(_) => panic!("parsed:\n{text}"),
        Err(SceneFileError::Syntax { line, col, msg, .. }) => (line, col, msg),
        Err(e) => panic!("no position: {e}"),
    }
}

fn with_shape(shape: &str) -> String {
    BASE.replace("Sphere(radius: 1.0)", shape)
}

#[test]
fn base_parses() {
    let s = parse(BASE, "t.ron").unwrap();
    assert_eq!(s.root.shape.params, vec![1.0]);
}

#[test]
fn unknown_shape_lists_nearest_first_with_position() {
    let (line, col, msg) = err(&with_shape("Spere(radius: 1.0)"));
    assert_eq!(line, 4, "{msg}");
    assert!(col >= 16, "{col} {msg}");
    assert!(msg.contains("unknown shape `Spere`"), "{msg}");
    assert!(msg.contains("did you mean `Sphere`"), "{msg}");
    assert!(
        msg.contains("valid choices (nearest first): Sphere,"),
        "{msg}"
    );
}

#[test]
fn unknown_parameter_lists_the_valid_ones() {
    let (line, _, msg) = err(&with_shape("Torus(major: 1.0, minr: 0.2)"));
    assert_eq!(line, 4);
    assert!(msg.contains("`Torus` has no parameter `minr`"), "{msg}");
    assert!(msg.contains("did you mean `minor`"), "{msg}");
}

#[test]
fn unknown_struct_field_lists_the_valid_ones() {
    let text = BASE.replace("shape:", "shap:");
    let (line, col, msg) = err(&text);
    assert_eq!((line, col), (4, 9), "{msg}");
    assert!(msg.contains("unknown field of `Node` `shap`"), "{msg}");
    assert!(msg.contains("did you mean `shape`"), "{msg}");
}

#[test]
fn unknown_combine_and_operator_are_named() {
    let text = BASE.replace(
        "shape: Sphere(radius: 1.0),",
        "shape: Sphere(radius: 1.0), ops: [Translat(offset: (1, 0, 0))],",
    );
    let (_, _, msg) = err(&text);
    assert!(msg.contains("unknown domain operator `Translat`"), "{msg}");
    assert!(msg.contains("did you mean `Translate`"), "{msg}");
    let text = BASE.replace(
        "shape: Sphere(radius: 1.0),",
        "shape: Sphere(radius: 1.0), children: [Node(combine: Unoin, shape: Sphere())],",
    );
    let (_, _, msg) = err(&text);
    assert!(msg.contains("unknown combine operator `Unoin`"), "{msg}");
    assert!(msg.contains("did you mean `Union`"), "{msg}");
}

#[test]
fn out_of_range_parameter_names_its_range() {
    let (line, _, msg) = err(&with_shape("Sphere(radius: -2.0)"));
    assert_eq!(line, 4);
    assert!(msg.contains("out of range [0, 1e6]"), "{msg}");
    assert!(msg.contains("radius"), "{msg}");
}

#[test]
fn non_finite_numbers_are_refused_with_position() {
    for (lit, col) in [("NaN", 31), ("inf", 31), ("-inf", 32), ("1e400", 31)] {
        let (line, c, msg) = err(&with_shape(&format!("Sphere(radius: {lit})")));
        assert_eq!((line, c), (4, col), "{lit}: {msg}");
        assert!(msg.contains("finite"), "{msg}");
    }
    // Also outside registry calls (camera, lights) where serde would take them silently.
    let text = BASE.replace(
        "version: 1,",
        "version: 1, camera: Camera(eye: (0, NaN, 4)),",
    );
    let (line, col, _) = err(&text);
    assert_eq!((line, col), (2, 41));
}

#[test]
fn wrong_version_says_which_are_supported() {
    let text = BASE.replace("version: 1", "version: 7");
    let (line, col, msg) = err(&text);
    assert_eq!((line, col), (2, 14), "{msg}");
    assert!(msg.contains("version 7 is not supported"), "{msg}");
    assert!(msg.contains("supported versions: 1"), "{msg}");
    let (_, _, msg) = err(&BASE.replace("version: 1,", ""));
    assert!(
        msg.contains("missing its required field `version`"),
        "{msg}"
    );
}

#[test]
fn bare_name_takes_all_defaults() {
    let s = parse(&with_shape("Torus"), "t.ron").unwrap();
    assert_eq!(s.root.shape.params, vec![1.0, 0.25]);
    let s = parse(&with_shape("Torus()"), "t.ron").unwrap();
    assert_eq!(s.root.shape.params, vec![1.0, 0.25]);
    // Bare names inside lists, followed by more items.
    let text = BASE.replace(
        "shape: Sphere(radius: 1.0),",
        "shape: Sphere, ops: [Rotate, FoldAbs, Scale], children: [Node(combine: SmoothUnion, shape: Box)],",
    );
    let s = parse(&text, "t.ron").unwrap();
    assert_eq!(s.root.ops.len(), 3);
    assert_eq!(s.root.children[0].combine.params, vec![0.25]);
}

#[test]
fn wrong_value_shapes_name_the_parameter() {
    let (_, _, msg) = err(&with_shape("Box(size: 1.0)"));
    assert!(
        msg.contains("parameter `size` of `Box` takes a vector"),
        "{msg}"
    );
    let (_, _, msg) = err(&with_shape("Sphere(radius: (1, 2, 3))"));
    assert!(
        msg.contains("parameter `radius` of `Sphere` takes a number"),
        "{msg}"
    );
    let (_, _, msg) = err(&with_shape("Box(size: (1, 2))"));
    assert!(msg.contains("three components"), "{msg}");
    let (_, _, msg) = err(&with_shape("Torus(major: 1.0, major: 2.0)"));
    assert!(msg.contains("given twice"), "{msg}");
}

#[test]
fn syntax_errors_say_what_was_expected() {
    let (line, _, msg) = err(&BASE.replace("version: 1,", "version: 1"));
    assert_eq!(line, 3, "{msg}");
    assert!(msg.contains("expected `,`"), "{msg}");
    let cut = &BASE[..BASE.len() - 4];
    let (l, c, msg) = err(cut);
    assert!(msg.contains("end of file"), "{l}:{c} {msg:?} {cut:?}");
    let (_, _, msg) = err(&format!("{BASE} Scene()"));
    assert!(msg.contains("after the end of the scene"), "{msg}");
    let (l, c, msg) = err(&BASE.replace("Node(", "Nod("));
    assert!(msg.contains("Node"), "{l}:{c}: {msg}");
    let (_, _, msg) = err(&BASE.replace("version: 1,", "version: 1, lights: [Light(shadows: 1)],"));
    assert!(msg.contains("true"), "{msg}");
}

#[test]
fn invalid_scenes_name_the_node_path() {
    let text = BASE.replace(
        "shape: Sphere(radius: 1.0),",
        "shape: Sphere, children: [Node(shape: Sphere, material: Material(specular: 3.0))],",
    );
    let e = parse(&text, "t.ron").unwrap_err().to_string();
    assert!(
        e.starts_with("t.ron:4:74: root.children[0].material.specular = 3 is out of range [0, 1]"),
        "{e}"
    );
    // Rules with no place in the text keep the file name only.
    let lights = BASE.replace(
        "version: 1,",
        &format!("version: 1, lights: [{}],", "Light(),".repeat(9)),
    );
    let e = parse(&lights, "t.ron").unwrap_err().to_string();
    assert!(e.starts_with("t.ron: 9 lights; the limit is 8"), "{e}");
}

#[test]
fn path_tracer_materials_load_name_their_range_and_stay_out_of_files_that_do_not_use_them() {
    let glass = BASE.replace(
        "shape: Sphere(radius: 1.0),",
        "shape: Sphere, material: Material(transmission: 1.0, ior: 1.33, metallic: 0.5, \
         emission: (1.0, 0.5, 0.25), emission_strength: 4.0),",
    );
    let s = parse(&glass, "t.ron").unwrap();
    let m = &s.root.material;
    assert_eq!((m.transmission, m.ior, m.metallic), (1.0, 1.33, 0.5));
    assert_eq!((m.emission, m.emission_strength), ([1.0, 0.5, 0.25], 4.0));
    // Saved and read back, the fields are kept.
    let again = parse(&to_string(&s), "t.ron").unwrap();
    assert_eq!(again.root.material, *m);
    // A field out of range is named with its range and its place.
    let bad = glass.replace("ior: 1.33", "ior: 7.0");
    let e = parse(&bad, "t.ron").unwrap_err().to_string();
    assert!(
        e.contains("root.material.ior = 7 is out of range [1, 3]") && e.starts_with("t.ron:"),
        "{e}"
    );
    // Scenes that do not use them are written as before.
    for p in PRESETS {
        let text = to_string(&crate::presets::load(p.name).unwrap());
        for field in ["metallic", "emission", "transmission", "ior"] {
            assert!(!text.contains(field), "{}: {field} written", p.name);
        }
    }
}

#[test]
fn deep_nesting_is_a_clean_error() {
    let n = 10_000;
    let mut text = String::from("Scene(version: 1, root: ");
    for _ in 0..n {
        text.push_str("Node(shape: Sphere, children: [");
    }
    for _ in 0..n {
        text.push_str("]), ");
    }
    text.push(')');
    let (_, _, msg) = err(&text);
    assert!(msg.contains("nested too deeply"), "{msg}");
    // Deeper than the tree limit but within the bracket limit: the limit is named.
    let d = limits::MAX_TREE_DEPTH + 1;
    let mut text = String::from("Scene(version: 1, root: ");
    for _ in 0..d {
        text.push_str("Node(shape: Sphere, children: [");
    }
    for _ in 0..d {
        text.push_str("]), ");
    }
    text.push(')');
    let e = parse(&text, "t.ron");
    let msg = e.unwrap_err().to_string();
    assert!(
        msg.contains(&format!("limit is {}", limits::MAX_TREE_DEPTH)) || msg.contains("nested"),
        "{msg}"
    );
}

#[test]
fn oversized_text_is_refused_before_parsing() {
    let text = " ".repeat(limits::MAX_SCENE_FILE_BYTES as usize + 1);
    assert!(matches!(
        parse(&text, "big"),
        Err(SceneFileError::TooLarge { .. })
    ));
}

#[test]
fn load_and_save_round_trip_through_a_file() {
    let dir = std::env::temp_dir().join(format!("fathom-scene-file-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("s.ron");
    for p in PRESETS {
        let s = crate::presets::load(p.name).unwrap();
        save(&path, &s).unwrap();
        assert_eq!(load(&path).unwrap(), s, "{}", p.name);
    }
    std::fs::write(&path, b"Scene(version: 1, \xff)").unwrap();
    let e = load(&path).unwrap_err();
    assert_eq!(e.position(), Some((1, 19)), "{e}");
    assert!(e.to_string().contains("UTF-8"), "{e}");
    let missing = load(&dir.join("missing.ron")).unwrap_err();
    assert!(matches!(missing, SceneFileError::Io { .. }));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_worked_example_in_the_format_guide_parses_and_compiles() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md");
    let md = std::fs::read_to_string(&path).unwrap();
    let start = md.find("```ron\n").expect("a ron block") + "```ron\n".len();
    let end = start + md[start..].find("```").unwrap();
    let scene = parse(&md[start..end], "scene-format.md").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.root.children.len(), 2);
    crate::tape::Tape::compile(&scene).unwrap();
}
