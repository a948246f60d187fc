//! Fuzz tests of the scene parser and the tape compiler (house rule: no panics on user input).
//!
//! - mutated preset texts (byte flips, truncations, token insertions and deletions, random
//!   numbers including huge and non-finite ones) must parse to a valid scene that round-trips,
//!   or give an error with a position inside the text (or a node path for rule violations);
//! - random scene trees from the registry tables, valid and wild, must compile or be refused
//!   cleanly; valid ones must compile, evaluate and round-trip through text;
//! - the corpus in `fuzz-corpus/` is replayed, each file stating the outcome it expects.
//!
//! 256 cases per property by default; set `PROPTEST_CASES` for longer runs.

use super::*;
use crate::presets::PRESETS;
use crate::tape::Tape;
use crate::testing::{Mode, arb_scene};
use proptest::prelude::*;

/// Tokens worth inserting: brackets, separators, names from every table, odd numbers.
const TOKENS: &[&str] = &[
    "(",
    ")",
    "[",
    "]",
    "{",
    "}",
    ",",
    ":",
    "\"",
    "/*",
    "//",
    "\n",
    "Some(",
    "None",
    "Node(",
    "shape:",
    "children: [",
    "ops: [",
    "version: 2",
    "Sphere",
    "Box()",
    "Mandelbulb(power: 40)",
    "Rotate(axis: (0, 0, 0), angle: 1)",
    "SmoothUnion(k: 0)",
    "FoldAbs",
    "r#Sphere",
    "0x1F",
    "1e999",
    "-1e999",
    "NaN",
    "inf",
    "-inf",
    "1e-400",
    "99999999999999999999999",
    "-0.0",
    "1_000",
    "_1",
    ".5",
    "5.",
    "+3",
    "'c'",
    "b\"x\"",
    "true",
    "()",
    "é",
    "\u{0}",
    "#![enable(implicit_some)]",
];

/// Numbers to write over existing ones.
const NUMBERS: &[&str] = &[
    "0",
    "-1",
    "1e300",
    "-1e300",
    "1e999",
    "NaN",
    "inf",
    "0.5",
    "4294967296",
    "-0",
    "1e-320",
    "18446744073709551616",
    "3.000000000000001",
    "257",
    "65",
];

#[derive(Clone, Debug)]
enum Mutation {
    Flip { at: usize, byte: u8 },
    Truncate { at: usize },
    Insert { at: usize, token: usize },
    Delete { at: usize, len: usize },
    Number { nth: usize, number: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(at, byte)| Mutation::Flip { at, byte }),
        any::<usize>().prop_map(|at| Mutation::Truncate { at }),
        (any::<usize>(), 0..TOKENS.len()).prop_map(|(at, token)| Mutation::Insert { at, token }),
        (any::<usize>(), 1..12usize).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (any::<usize>(), 0..NUMBERS.len())
            .prop_map(|(nth, number)| Mutation::Number { nth, number }),
    ]
}

/// Applies a mutation to the bytes of a scene text.
fn apply(text: &mut Vec<u8>, m: &Mutation) {
    let n = text.len().max(1);
    match *m {
        Mutation::Flip { at, byte } => {
            if !text.is_empty() {
                text[at % n] = byte;
            }
        }
        Mutation::Truncate { at } => text.truncate(at % n),
        Mutation::Insert { at, token } => {
            let at = at % (text.len() + 1);
            text.splice(at..at, TOKENS[token].bytes());
        }
        Mutation::Delete { at, len } => {
            let at = at % n;
            let end = (at + len).min(text.len());
            text.drain(at.min(end)..end);
        }
        Mutation::Number { nth, number } => {
            // Spans of digits (with their dots), the n-th one (mod count) replaced.
            let mut spans = Vec::new();
            let mut i = 0;
            while i < text.len() {
                if text[i].is_ascii_digit() {
                    let s = i;
                    while i < text.len() && (text[i].is_ascii_digit() || text[i] == b'.') {
                        i += 1;
                    }
                    spans.push(s..i);
                } else {
                    i += 1;
                }
            }
            if !spans.is_empty() {
                let r = spans[nth % spans.len()].clone();
                text.splice(r, NUMBERS[number].bytes());
            }
        }
    }
}

/// The property every input must satisfy: a valid scene that survives a text round trip, or
/// an error that points inside the text (or names the node it is about).
fn check_outcome(text: &str) -> Result<(), TestCaseError> {
    match parse(text, "fuzz") {
        Ok(scene) => {
            prop_assert!(scene.validate().is_ok());
            let again = parse(&to_string(&scene), "again").ok();
            prop_assert_eq!(again, Some(scene), "accepted text does not round-trip");
        }
        Err(SceneFileError::Syntax { line, col, msg, .. }) => {
            let (last_line, _) = lex::end_position(text);
            prop_assert!(
                line >= 1 && col >= 1 && line <= last_line,
                "{line}:{col} {msg}"
            );
            prop_assert!(!msg.is_empty());
        }
        Err(SceneFileError::Invalid { error, .. }) => {
            prop_assert!(!error.to_string().is_empty())
        }
        Err(e) => prop_assert!(false, "unexpected error kind: {e}"),
    }
    Ok(())
}

fn cases(default: u32) -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default);
    ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(cases(256))]

    #[test]
    fn mutated_presets_parse_or_fail_with_a_position(
        preset in 0..PRESETS.len(),
        mutations in prop::collection::vec(mutation(), 1..5),
    ) {
        let mut bytes = PRESETS[preset].text.as_bytes().to_vec();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        let text = String::from_utf8_lossy(&bytes);
        check_outcome(&text)?;
    }

    #[test]
    fn wild_scenes_compile_or_are_refused_cleanly(scene in arb_scene(Mode::Wild)) {
        match Tape::compile(&scene) {
            Ok(tape) => {
                prop_assert!(scene.validate().is_ok());
                // Evaluating a compiled tape must not panic either.
                let _ = tape.eval_f64([0.3, -0.2, 0.7]);
            }
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
        // Whatever the scene, its text form parses back to it or is refused with a message.
        check_outcome(&to_string(&scene))?;
    }

    #[test]
    fn valid_scenes_compile_evaluate_and_round_trip(scene in arb_scene(Mode::Valid)) {
        prop_assert_eq!(scene.validate(), Ok(()));
        let tape = Tape::compile(&scene).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let _ = tape.eval_f64([0.1, 0.2, -0.3]);
        let text = to_string(&scene);
        let back = parse(&text, "random").map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        prop_assert_eq!(back, scene);
    }
}

/// Each corpus file starts with `// expect: ok` or `// expect: error: <text in the message>`.
#[test]
fn corpus_replays_with_the_expected_outcomes() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz-corpus");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    files.sort();
    assert!(files.len() >= 24, "only {} corpus files", files.len());
    let mut failures = Vec::new();
    for path in files {
        let bytes = std::fs::read(&path).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        let name = path.file_name().unwrap().to_string_lossy();
        let expect = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("// expect: "))
            .unwrap_or_else(|| panic!("{name}: first line must be `// expect: ...`"))
            .trim()
            .to_string();
        let result = load(&path);
        if let Err(e) = check_outcome(&text) {
            failures.push(format!("{name}: {e}"));
        }
        match (expect.strip_prefix("error: "), result) {
            (None, Ok(_)) if expect == "ok" => {}
            (Some(want), Err(e)) => {
                let got = e.to_string();
                if !got.contains(want) || !got.starts_with(&format!("{}:", path.display())) {
                    failures.push(format!(
                        "{name}: expected an error containing {want:?}, got {got}"
                    ));
                }
            }
            (_, r) => failures.push(format!(
                "{name}: expected {expect}, got {:?}",
                r.map(|_| "a scene")
            )),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
