//! The crate's error type: every failure names the file, parameter or value that caused it,
//! what was expected, and the valid range or choices.

use std::path::PathBuf;
use thiserror::Error;

/// Why a grid could not be read, written or built, or why a parameter was refused.
#[derive(Debug, Error)]
pub enum VolumeError {
    /// The file could not be opened, read or written.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file's bytes are not what its format says; `offset` is the byte where it went wrong.
    #[error("{}: byte {offset}: {msg}", path.display())]
    Format {
        path: PathBuf,
        offset: u64,
        msg: String,
    },
    /// A voxel holds a value a density cannot have (NaN, infinite or negative).
    #[error("{origin}: voxel ({x}, {y}, {z}) holds {value}; densities must be finite and >= 0")]
    BadDensity {
        origin: String,
        x: u32,
        y: u32,
        z: u32,
        value: f32,
    },
    /// A grid would need more memory than allowed; nothing was allocated.
    #[error(
        "{what}: {res_x}x{res_y}x{res_z} voxels need {bytes} bytes, more than the memory limit \
         of {limit} bytes (raise it with --max-memory)"
    )]
    TooLarge {
        what: String,
        res_x: u64,
        res_y: u64,
        res_z: u64,
        bytes: u64,
        limit: u64,
    },
    /// A parameter is outside its range.
    #[error("{name} = {value} is out of range: {range}")]
    Param {
        name: &'static str,
        value: String,
        range: String,
    },
    /// An output could not be written (the old file, if any, is unchanged).
    #[error(transparent)]
    Write(#[from] fathom_core::atomic_file::WriteError),
    /// Something else about the input makes it unusable (empty scene, unknown name).
    #[error("{0}")]
    Invalid(String),
}

impl VolumeError {
    /// A parameter error: `name = value` is outside `range`.
    pub fn param(
        name: &'static str,
        value: impl std::fmt::Display,
        range: impl Into<String>,
    ) -> Self {
        VolumeError::Param {
            name,
            value: value.to_string(),
            range: range.into(),
        }
    }
}

/// Checks that a finite `value` lies in `[lo, hi]`; the error names `name` and the range.
pub fn check_range(name: &'static str, value: f64, lo: f64, hi: f64) -> Result<(), VolumeError> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(VolumeError::param(name, value, format!("[{lo}, {hi}]")))
    }
}
