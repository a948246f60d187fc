//! Scene files: the versioned, human-readable text form of a [`Scene`] (RON), with errors that
//! name file:line:column, what was expected, and for unknown names the valid choices.
//!
//! Reading goes in three passes, each refusing bad input before the next allocates for it:
//! the size limit; a light lexer ([`lex`]) that refuses non-finite numbers (`NaN`, `inf`,
//! `1e999`) with their position; a probe of `version` so a file from another format version
//! says so instead of failing on some later field; then the RON parse proper (with a recursion
//! limit, so absurd nesting is an error and not a stack overflow) and [`Scene::validate`].

use crate::limits;
use crate::scene::{SCENE_VERSION, Scene};
use crate::validate::SceneError;
use std::path::Path;
use thiserror::Error;

pub mod fract;
mod lex;

/// Why a scene file could not be read or written.
#[derive(Debug, Error)]
pub enum SceneFileError {
    /// The text is not a valid scene (bad syntax, or a rule broken at a place in the text);
    /// `line`/`col` are 1-based (columns count characters).
    #[error("{origin}:{line}:{col}: {msg}")]
    Syntax {
        /// Where the text came from (a path, `<preset mandelbulb>`, ...).
        origin: String,
        /// 1-based line.
        line: usize,
        /// 1-based column, in characters.
        col: usize,
        /// What is wrong.
        msg: String,
    },
    /// The scene parsed but breaks a limit or rule that has no single place in the text (the
    /// tree is too deep, too many lights), or at a place left to its default.
    #[error("{origin}: {error}")]
    Invalid {
        /// Where the text came from.
        origin: String,
        /// The rule broken.
        error: SceneError,
    },
    /// The file could not be read or written.
    #[error("{origin}: {source}")]
    Io {
        /// The path.
        origin: String,
        /// The error from the operating system.
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than [`limits::MAX_SCENE_FILE_BYTES`]; it was not read.
    #[error("{origin}: the file is {size} bytes; scene files are limited to {max} bytes", max = limits::MAX_SCENE_FILE_BYTES)]
    TooLarge {
        /// The path.
        origin: String,
        /// The file's size, bytes.
        size: u64,
    },
    /// The path is not a regular file (a directory, FIFO or device); it was not opened.
    #[error(transparent)]
    Read(crate::input_file::ReadError),
    /// The file could not be written (the old one, if any, is left as it was).
    #[error(transparent)]
    Write(#[from] crate::atomic_file::WriteError),
}

impl SceneFileError {
    /// The 1-based (line, column) the error points at, if it has one.
    pub fn position(&self) -> Option<(usize, usize)> {
        match self {
            SceneFileError::Syntax { line, col, .. } => Some((*line, *col)),
            _ => None,
        }
    }
}

/// RON nesting allowed while parsing: each tree level costs a few levels of brackets (the node,
/// its children list, its calls), plus the scene's own few.
const RECURSION_LIMIT: usize = 4 * limits::MAX_TREE_DEPTH + 16;

/// Parses scene text. `origin` names the source in error messages (a path, or `<preset:NAME>`).
pub fn parse(text: &str, origin: &str) -> Result<Scene, SceneFileError> {
    if text.len() as u64 > limits::MAX_SCENE_FILE_BYTES {
        return Err(SceneFileError::TooLarge {
            origin: origin.into(),
            size: text.len() as u64,
        });
    }
    let syntax = |(line, col): (usize, usize), msg: String| SceneFileError::Syntax {
        origin: origin.into(),
        line,
        col,
        msg,
    };
    let tokens = lex::scan(text).map_err(|e| syntax(e.pos, e.msg))?;
    check_version(&tokens).map_err(|(pos, msg)| syntax(pos, msg))?;
    let opts = ron::Options::default().with_recursion_limit(RECURSION_LIMIT);
    let scene: Scene = opts.from_str(text).map_err(|e| {
        let pos = (e.span.start.line, e.span.start.col);
        let mut msg = describe(&e.code);
        // RON often reports a truncated file as a missing comma; say what really happened.
        let at_end = (e.span.end.line, e.span.end.col) >= lex::end_position(text.trim_end());
        if at_end && !matches!(e.code, ron::Error::Eof) {
            msg = format!("unexpected end of file ({msg}); a closing bracket is probably missing");
        }
        syntax(pos, msg)
    })?;
    // Rule violations name a node path; point at it in the text when it is written there.
    scene
        .validate()
        .and_then(|()| scene.validate_animation())
        .map_err(|error| {
            let msg = error.to_string();
            match lex::locate_path(&tokens, &msg) {
                Some(pos) => syntax(pos, msg),
                None => SceneFileError::Invalid {
                    origin: origin.into(),
                    error,
                },
            }
        })?;
    Ok(scene)
}

/// Checks the top-level `version` field from the tokens alone, before the full parse, so that
/// a file written for another format version says so instead of failing on some later field.
fn check_version(tokens: &[lex::Token]) -> Result<(), ((usize, usize), String)> {
    let Some((pos, value)) = lex::top_level_number(tokens, "version") else {
        return Ok(()); // a missing or malformed version is reported by the full parse
    };
    if value.parse::<u64>().ok() == Some(SCENE_VERSION as u64) {
        return Ok(());
    }
    Err((
        pos,
        format!(
            "scene format version {value} is not supported; this build of fathom reads \
             version {SCENE_VERSION} only (supported versions: {SCENE_VERSION})"
        ),
    ))
}

/// A readable message for each RON error, saying what was expected.
fn describe(code: &ron::Error) -> String {
    use ron::Error as E;
    match code {
        E::Message(s) => s.clone(),
        E::Eof => "unexpected end of file: a closing `)` or `]` is probably missing".into(),
        E::ExpectedComma => {
            "expected `,` between items, or a closing `)` or `]` after the last one".into()
        }
        E::ExpectedStructLike => "expected `(` opening a structure; write `Name()` to take \
                                  every default"
            .into(),
        E::ExpectedNamedStructLike("") => "expected `(` opening a structure".into(),
        E::ExpectedNamedStructLike(name) => format!("expected `{name}(...)` here"),
        E::ExpectedStructLikeEnd => {
            "expected `)` closing the structure, or a `,` before the next field".into()
        }
        E::ExpectedArray => "expected a list `[ ... ]`".into(),
        E::ExpectedArrayEnd => "expected `]` closing the list, or a `,` between items".into(),
        E::ExpectedFloat => "expected a number".into(),
        E::ExpectedInteger => "expected a whole number".into(),
        E::FloatUnderscore | E::UnderscoreAtBeginning => {
            "a number may not start with or contain `_` here".into()
        }
        E::IntegerOutOfBounds => "whole number out of range for this field".into(),
        E::InvalidIntegerDigit { digit, base } => {
            format!("invalid digit `{digit}` in a base-{base} number")
        }
        E::ExpectedBoolean => "expected `true` or `false`".into(),
        E::ExpectedOption => "expected `None` or `Some(...)`".into(),
        E::ExpectedOptionEnd => "expected `)` closing `Some(...)`".into(),
        E::ExpectedMapColon => "expected `:` after the field name".into(),
        E::ExpectedIdentifier => "expected a name".into(),
        E::ExpectedUnit => "expected `()`".into(),
        E::UnexpectedChar(c) => format!("unexpected character `{}`", c.escape_default()),
        E::TrailingCharacters => {
            "unexpected text after the end of the scene (a file holds one `Scene(...)`)".into()
        }
        E::UnclosedBlockComment => "a `/*` comment is never closed".into(),
        E::ExpectedDifferentStructName { expected, found } => {
            format!("expected `{expected}(...)` here, found `{found}`")
        }
        E::ExpectedStructName(name) => format!("expected `{name}(...)` here"),
        E::InvalidValueForType { expected, found } => format!("expected {expected}, found {found}"),
        E::ExpectedDifferentLength { expected, found } => {
            format!("expected {expected}, found {found} element(s)")
        }
        E::NoSuchEnumVariant {
            expected, found, ..
        } => crate::call_serde::unknown_name("choice", found, expected.iter().copied()),
        E::NoSuchStructField {
            expected,
            found,
            outer,
        } => {
            let noun = match outer {
                Some(o) => format!("field of `{o}`"),
                None => "field".into(),
            };
            crate::call_serde::unknown_name(&noun, found, expected.iter().copied())
        }
        E::MissingStructField { field, outer } => match outer {
            Some(o) => format!("`{o}` is missing its required field `{field}`"),
            None => format!("missing required field `{field}`"),
        },
        E::DuplicateStructField { field, outer } => match outer {
            Some(o) => format!("field `{field}` of `{o}` is given twice"),
            None => format!("field `{field}` is given twice"),
        },
        E::ExceededRecursionLimit => format!(
            "the text is nested too deeply (more than {RECURSION_LIMIT} levels of brackets); \
             scene trees are limited to {} levels",
            limits::MAX_TREE_DEPTH
        ),
        E::Utf8Error(e) => format!("the file is not valid UTF-8: {e}"),
        other => {
            let s = other.to_string();
            let mut c = s.chars();
            match c.next() {
                Some(f) => f.to_lowercase().chain(c).collect(),
                None => s,
            }
        }
    }
}

/// Reads and parses a scene file, refusing oversized files before reading them. A `.fract`
/// file is read as Mandelbulber2 settings ([`fract`]); what it could not carry over is listed
/// on standard error as warnings (use [`fract::load`] to get them instead).
pub fn load(path: &Path) -> Result<Scene, SceneFileError> {
    if fract::is_fract(path) {
        let imported = fract::load(path)?;
        for w in &imported.warnings {
            eprintln!("fathom: warning: {w}");
        }
        return Ok(imported.scene);
    }
    let text = read_text(path)?;
    parse(&text, &path.display().to_string())
}

/// Reads a text file, refusing oversized files before reading them and reporting where the
/// text stops being UTF-8.
fn read_text(path: &Path) -> Result<String, SceneFileError> {
    let origin = path.display().to_string();
    let io = |source| SceneFileError::Io {
        origin: origin.clone(),
        source,
    };
    use crate::input_file::{self, ReadError};
    let bytes = input_file::read(path, limits::MAX_SCENE_FILE_BYTES).map_err(|e| match e {
        ReadError::TooLarge { size, .. } => SceneFileError::TooLarge {
            origin: origin.clone(),
            size,
        },
        ReadError::Io { source, .. } => io(source),
        e @ ReadError::NotAFile { .. } => SceneFileError::Read(e),
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let valid = String::from_utf8_lossy(valid);
        let (line, col) = lex::end_position(&valid);
        SceneFileError::Syntax {
            origin: origin.clone(),
            line,
            col,
            msg: "the file is not valid UTF-8 text".into(),
        }
    })?;
    Ok(text)
}

/// The scene as scene-file text.
pub fn to_string(scene: &Scene) -> String {
    let cfg = ron::ser::PrettyConfig::new()
        .indentor("    ".to_string())
        .struct_names(true);
    ron::Options::default()
        .to_string_pretty(scene, cfg)
        .expect("a scene always serialises")
}

/// Writes a scene file (atomically: the old file stays until the new one is whole).
pub fn save(path: &Path, scene: &Scene) -> Result<(), SceneFileError> {
    Ok(crate::atomic_file::write(path, to_string(scene))?)
}

#[cfg(test)]
mod fuzz;
#[cfg(test)]
mod tests;
