//! The `.fract` importer: mapping, warnings, located errors, a fuzz pass and a replayed corpus.

use super::*;
use crate::tape::Tape;
use proptest::prelude::*;

const BULB: &str = "# Mandelbulber settings file
# version 2.13
# only modified parameters
[main_parameters]
camera -0,15 -1,18 0,16;
target -0,60 0,47 0,62;
camera_top 0,0669 -0,25 0,9659;
camera_rotation 15 15 0;
fov 1,1;
image_height 1080;
image_width 1920;
N 20;
main_light_alpha -10;
[fractal_1]
power 8;
[fractal_2]
power 3;
[keyframes]
frame;main_camera_x
0;1,1
";

#[test]
fn a_mandelbulb_file_maps_camera_formula_and_warns_about_the_rest() {
    let im = parse(BULB, "b.fract").unwrap();
    assert_eq!(im.image_size, (1920, 1080));
    let c = &im.scene.camera;
    assert!(
        (c.eye - DVec3::new(-0.15, 0.16, 1.18)).length() < 1e-12,
        "{:?}",
        c.eye
    );
    assert!((c.fov - (2.0 * 0.55f64.atan()).to_degrees()).abs() < 1e-9);
    let shape = &im.scene.root.shape;
    assert_eq!(shape.get("power"), Some(&[8.0][..]));
    assert_eq!(shape.get("iterations"), Some(&[20.0][..]));
    // 90 (1 - 8) / 8 = -78.75, taken modulo 45 into (-22.5, 22.5]: 11.25.
    assert_eq!(shape.get("polar_offset"), Some(&[11.25][..]));
    let w = im.warnings.join("\n");
    assert!(w.contains("main_light_alpha (line 13)"), "{w}");
    assert!(
        w.contains("[fractal_2]") && w.contains("[keyframes]"),
        "{w}"
    );
    assert!(
        !w.contains("camera_rotation"),
        "redundant keys are not reported: {w}"
    );
    Tape::compile(&im.scene).unwrap();
}

/// fathom's bulb with the mapped polar offset is Mandelbulber's asin-form bulb: one iteration
/// of each, written out here from Mandelbulber's formula, agree.
#[test]
fn the_polar_offset_reproduces_mandelbulbers_latitude_form() {
    for p in [8.0f64, 9.0, 3.0] {
        let beta = 7.0f64;
        let alpha = 12.0f64;
        let polar = (90.0 * (1.0 - p) / p - beta).to_radians();
        let z = DVec3::new(0.3, -0.4, 0.5);
        let r = z.length();
        // Mandelbulber: th = (asin(z/r) + beta) p, ph = (atan2 + alpha) p.
        let th = ((z.z / r).asin() + beta.to_radians()) * p;
        let ph = (z.y.atan2(z.x) + alpha.to_radians()) * p;
        let mb = DVec3::new(th.cos() * ph.cos(), th.cos() * ph.sin(), th.sin()) * r.powf(p);
        // fathom: theta = (acos(z/r) + polar) p.
        let t = ((z.z / r).acos() + polar) * p;
        let ours = DVec3::new(t.sin() * ph.cos(), t.sin() * ph.sin(), t.cos()) * r.powf(p);
        assert!((mb - ours).length() < 1e-12, "p {p}: {mb:?} vs {ours:?}");
    }
}

#[test]
fn malformed_and_unsupported_input_names_file_line_and_column() {
    let cases: &[(&str, &str, (usize, usize))] = &[
        (
            "# Mandelbulber settings file\n[main_parameters]\ncamera 1 2;\n",
            "three numbers",
            (3, 8),
        ),
        (
            "# Mandelbulber settings file\n[main_parameters]\nfov 1,5\n",
            "expected `;`",
            (3, 8),
        ),
        (
            "# Mandelbulber settings file\n[main_parameters]\nfov ;\n",
            "no value",
            (3, 5),
        ),
        (
            "# Mandelbulber settings file\n[main_parameters]\nfov x;\n",
            "not a number",
            (3, 5),
        ),
        (
            "# Mandelbulber settings file\n[main_parameters]\nformula_1 10;\n",
            "not supported",
            (3, 11),
        ),
        (
            "# Mandelbulber settings file\n[main_parameters]\nN 1.5;\n",
            "whole number",
            (3, 3),
        ),
        (
            "# Mandelbulber settings file\n[main_parameters]\nN 5;\nN 6;\n",
            "twice",
            (4, 1),
        ),
        ("hello\n", "not a Mandelbulber settings file", (1, 1)),
        (
            "# Mandelbulber settings file\ncamera 1 2 3;\n",
            "before any section",
            (2, 1),
        ),
        (
            "# Mandelbulber settings file\n[main_parameters\n",
            "[section]",
            (2, 1),
        ),
        (
            "# Mandelbulber settings file\n[main_parameters]\n[fractal_1]\npower 64;\n",
            "range",
            (4, 7),
        ),
    ];
    for (text, want, pos) in cases {
        let e = parse(text, "x.fract").unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(want), "{text:?}: {msg}");
        assert_eq!(e.position(), Some(*pos), "{text:?}: {msg}");
        assert!(msg.starts_with("x.fract:"), "{msg}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]
    /// Arbitrary text and arbitrary edits of a valid file never panic; success always yields a
    /// scene that compiles.
    #[test]
    fn fuzzed_text_never_panics(text in "\\PC{0,300}") {
        if let Ok(im) = parse(&text, "fuzz") {
            prop_assert!(Tape::compile(&im.scene).is_ok());
        }
    }

    #[test]
    fn edited_files_never_panic(at in 0usize..BULB.len(), cut in 0usize..20, insert in "[ ;,.#\\[\\]a-z0-9\\-e]{0,12}") {
        let at = (0..=at).rev().find(|&i| BULB.is_char_boundary(i)).unwrap_or(0);
        let end = (at + cut).min(BULB.len());
        let end = (end..=BULB.len()).find(|&i| BULB.is_char_boundary(i)).unwrap();
        let text = format!("{}{}{}", &BULB[..at], insert, &BULB[end..]);
        if let Ok(im) = parse(&text, "fuzz") {
            prop_assert!(Tape::compile(&im.scene).is_ok());
        }
    }
}

/// The checked-in corpus (`fuzz-corpus-fract/`): `ok-*` files import, `err-*` files fail with
/// a position.
#[test]
fn the_fract_corpus_replays() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz-corpus-fract");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let path = e.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let r = load(&path);
        if name.starts_with("ok-") {
            let im = r.unwrap_or_else(|e| panic!("{name}: {e}"));
            Tape::compile(&im.scene).unwrap();
        } else {
            let e = r.err().unwrap_or_else(|| panic!("{name} should fail"));
            assert!(
                e.position().is_some() || matches!(e, SceneFileError::TooLarge { .. }),
                "{name}: {e}"
            );
        }
        n += 1;
    }
    assert!(n >= 10, "corpus has {n} files");
}

#[test]
fn a_byte_order_mark_is_not_part_of_the_header() {
    let im = parse(&format!("\u{feff}{BULB}"), "bom.fract").unwrap();
    assert_eq!(im.image_size, (1920, 1080));
}

#[test]
fn values_fathom_changes_are_warned_with_their_line() {
    for (setting, key, line, clamped) in [
        ("DE_factor 0;", "DE_factor", 5, "clamped to 0.01"),
        ("DE_factor -1;", "DE_factor", 5, "clamped to 0.01"),
        ("DE_factor 1e6;", "DE_factor", 5, "clamped to 1"),
        ("bailout 0;", "bailout", 5, "clamped to 1"),
        ("bailout -5;", "bailout", 5, "clamped to 1"),
        ("bailout 1e300;", "bailout", 5, "clamped to 1000"),
    ] {
        let text = format!(
            "# Mandelbulber settings file\n[main_parameters]\nformula_1 2;\n\
             use_default_bailout false;\n{setting}\n[fractal_1]\npower 8;\n"
        );
        let im = parse(&text, "w.fract").unwrap();
        let w = im.warnings.join("\n");
        let want = format!("w.fract:{line}: `{key}`");
        assert!(w.contains(&want) && w.contains(clamped), "{setting}: {w}");
    }
    // In range: no warning.
    let im = parse(
        "# Mandelbulber settings file\n[main_parameters]\nDE_factor 0.5;\n",
        "ok.fract",
    )
    .unwrap();
    assert!(!im.warnings.join("\n").contains("DE_factor"));
}

/// Mandelbulber's own example files (from its Debian package, which scripts/setup.sh
/// installs), each mutated a few ways from a fixed seed: every outcome is a scene that
/// compiles or an error with a position (or a size refusal), never a panic.
#[test]
fn mutated_shipped_examples_import_or_fail_with_a_position() {
    let dir = std::path::Path::new("/usr/share/mandelbulber2/examples");
    let Ok(entries) = std::fs::read_dir(dir) else {
        panic!("{} is missing: run scripts/setup.sh", dir.display());
    };
    let mut files: Vec<_> = entries
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| is_fract(p))
        .collect();
    files.sort();
    assert!(files.len() >= 10, "{} examples", files.len());
    // A small deterministic generator (xorshift): the same mutations on every run.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    const PIECES: &[&str] = &[
        ";",
        " ",
        "\n",
        "[",
        "]",
        "1e308",
        "-1e308",
        "nan",
        "inf",
        "0",
        "-0",
        ",",
        "#",
        "\u{feff}",
        "DE_factor 0;\n",
        "bailout 1e300;\n",
        "N 0;\n",
        "fov -1;\n",
        "formula_1 8;\n",
        "camera 0 0 0;\n",
        "image_width 0;\n",
        "power 1e9;\n",
    ];
    let mut cases = 0;
    for path in files.iter().take(60) {
        let text = std::fs::read_to_string(path).unwrap();
        let name = path.display().to_string();
        for _ in 0..8 {
            let mut t = text.clone().into_bytes();
            for _ in 0..(1 + next() % 4) {
                let at = (next() % (t.len() as u64 + 1)) as usize;
                match next() % 4 {
                    0 => {
                        let p = PIECES[(next() % PIECES.len() as u64) as usize];
                        t.splice(at..at, p.bytes());
                    }
                    1 => {
                        let end = (at + (next() % 40) as usize).min(t.len());
                        t.drain(at..end);
                    }
                    2 => t.truncate(at),
                    _ => {
                        if at < t.len() {
                            t[at] = next() as u8;
                        }
                    }
                }
            }
            let t = String::from_utf8_lossy(&t);
            match parse(&t, &name) {
                Ok(im) => {
                    Tape::compile(&im.scene).unwrap_or_else(|e| panic!("{name}: {e}"));
                }
                Err(e) => assert!(
                    e.position().is_some()
                        || matches!(e, SceneFileError::TooLarge { .. })
                        || matches!(e, SceneFileError::Invalid { .. }),
                    "{name}: {e}"
                ),
            }
            cases += 1;
        }
    }
    assert!(cases >= 80);
}
