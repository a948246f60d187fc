//! What can go wrong building and rendering microgeometry, each error naming the file,
//! parameter or limit at fault.

use thiserror::Error;

/// Why a mesh could not be read or used.
#[derive(Debug, Error)]
pub enum MeshLoadError {
    /// The file could not be opened or read.
    #[error("{origin}: cannot read the mesh: {source}")]
    Io {
        /// The mesh file or name.
        origin: String,
        /// The error from the operating system.
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than [`crate::limits::MAX_MESH_FILE_BYTES`]; it was not read.
    #[error("{origin}: the file is {size} bytes; mesh files are limited to {max} bytes", max = crate::limits::MAX_MESH_FILE_BYTES)]
    FileTooLarge {
        /// The mesh file.
        origin: String,
        /// Its size, bytes.
        size: u64,
    },
    /// More triangles (or vertices) than [`crate::limits`] allows; refused before allocation.
    #[error("{origin}: the mesh has {count} {what}; the limit is {max}")]
    TooLarge {
        /// The mesh file or name.
        origin: String,
        /// `triangles` or `vertices`.
        what: &'static str,
        /// How many the file declares.
        count: u64,
        /// The limit.
        max: u64,
    },
    /// The text is not valid at a place in the file (1-based line and column).
    #[error("{origin}:{line}:{col}: {msg}")]
    Syntax {
        /// The mesh file.
        origin: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        col: usize,
        /// What is wrong.
        msg: String,
    },
    /// The file parsed but is not a usable mesh (no place in the text to point at).
    #[error("{origin}: {msg}")]
    Invalid {
        /// The mesh file.
        origin: String,
        /// What is wrong.
        msg: String,
    },
    /// The extension names no format we read.
    #[error(
        "{origin}: unknown mesh format `{ext}`; expected one of: obj, gltf, glb (or a built-in mesh: {builtins})"
    )]
    UnknownFormat {
        /// The mesh file or name.
        origin: String,
        /// The extension given.
        ext: String,
        /// The built-in meshes' names.
        builtins: String,
    },
    /// The mesh has no texture coordinates and no projection was chosen.
    #[error(
        "{origin}: the mesh has no UV coordinates; choose a projection (--uv planar, box or spherical)"
    )]
    NoUvs {
        /// The mesh file or name.
        origin: String,
    },
    /// Every triangle was skipped.
    #[error("{origin}: no usable triangles ({report})")]
    Empty {
        /// The mesh file or name.
        origin: String,
        /// What cleaning skipped, and why.
        report: String,
    },
}

/// Why a shell, texture or frame could not be built.
#[derive(Debug, Error)]
pub enum MicroError {
    /// The mesh could not be read or used.
    #[error(transparent)]
    Mesh(#[from] MeshLoadError),
    /// A parameter is outside its documented range.
    #[error("{name} = {value} is out of range {range}")]
    Range {
        /// The parameter's name.
        name: &'static str,
        /// The value given, as text.
        value: String,
        /// The parameter's range, as text.
        range: &'static str,
    },
    /// The shell height is outside its range, which is relative to the mesh's size.
    #[error(
        "shell height = {height} is out of range ({lo:e}, {hi}] for this mesh: from 1e-6 to \
         {rel} times its bounding-box diagonal ({diag})",
        lo = 1e-6 * diag,
        hi = crate::limits::MAX_SHELL_RELATIVE * diag,
        rel = crate::limits::MAX_SHELL_RELATIVE
    )]
    ShellHeight {
        /// The height given, mesh units.
        height: f64,
        /// The mesh's bounding-box diagonal.
        diag: f64,
    },
    /// The texture scene does not compile or its keyframes do not match.
    #[error("texture {origin}: {msg}")]
    Texture {
        /// The texture's file or name.
        origin: String,
        /// What is wrong.
        msg: String,
    },
    /// The image size is empty or too large.
    #[error("{0}")]
    Size(String),
    /// The camera cannot form an image.
    #[error(transparent)]
    Camera(#[from] fathom_core::camera::CameraError),
    /// The GPU path failed.
    #[error(transparent)]
    Gpu(#[from] fathom_gpu::GpuError),
    /// A feature the GPU path does not offer.
    #[error("{0}")]
    Unsupported(String),
}

/// Checks `value` lies in `[lo, hi]` (and is finite).
pub fn check_range(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    range: &'static str,
) -> Result<(), MicroError> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(MicroError::Range {
            name,
            value: value.to_string(),
            range,
        })
    }
}
