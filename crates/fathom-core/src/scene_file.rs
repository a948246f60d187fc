//! Scene files: the versioned, human-readable text form of a [`Scene`] (RON), with errors that
//! name file:line:column, what was expected, and for unknown names the valid choices.

use crate::limits;
use crate::scene::Scene;
use std::path::Path;
use thiserror::Error;

/// Why a scene file could not be read or written.
#[derive(Debug, Error)]
pub enum SceneFileError {
    /// The text is not a valid scene; `line`/`col` are 1-based.
    #[error("{origin}:{line}:{col}: {msg}")]
    Syntax {
        origin: String,
        line: usize,
        col: usize,
        msg: String,
    },
    /// The scene parsed but breaks a limit or rule (the message names the node path).
    #[error("{origin}: {msg}")]
    Invalid { origin: String, msg: String },
    #[error("{origin}: {source}")]
    Io {
        origin: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{origin}: the file is {size} bytes; scene files are limited to {max} bytes", max = limits::MAX_SCENE_FILE_BYTES)]
    TooLarge { origin: String, size: u64 },
}

/// Parses scene text. `origin` names the source in error messages (a path, or `<preset:NAME>`).
pub fn parse(text: &str, origin: &str) -> Result<Scene, SceneFileError> {
    if text.len() as u64 > limits::MAX_SCENE_FILE_BYTES {
        return Err(SceneFileError::TooLarge {
            origin: origin.into(),
            size: text.len() as u64,
        });
    }
    let opts = ron::Options::default().with_recursion_limit(4 * limits::MAX_TREE_DEPTH + 16);
    let scene: Scene = opts.from_str(text).map_err(|e| SceneFileError::Syntax {
        origin: origin.into(),
        line: e.span.start.line,
        col: e.span.start.col,
        msg: e.code.to_string(),
    })?;
    scene.validate().map_err(|msg| SceneFileError::Invalid {
        origin: origin.into(),
        msg,
    })?;
    Ok(scene)
}

/// Reads and parses a scene file, refusing oversized files before reading them.
pub fn load(path: &Path) -> Result<Scene, SceneFileError> {
    let origin = path.display().to_string();
    let io = |source| SceneFileError::Io {
        origin: origin.clone(),
        source,
    };
    let size = std::fs::metadata(path).map_err(io)?.len();
    if size > limits::MAX_SCENE_FILE_BYTES {
        return Err(SceneFileError::TooLarge { origin, size });
    }
    let text = std::fs::read_to_string(path).map_err(io)?;
    parse(&text, &origin)
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

/// Writes a scene file.
pub fn save(path: &Path, scene: &Scene) -> Result<(), SceneFileError> {
    std::fs::write(path, to_string(scene)).map_err(|source| SceneFileError::Io {
        origin: path.display().to_string(),
        source,
    })
}
