//! [`RenderError`]: everything a session can refuse or fail at, each variant carrying the typed
//! error of the layer that found it (the request, the scene and the node path, the tape, the
//! camera, a renderer), so a window can point at the bad field and a command line can print it.

use crate::request::RequestError;
use fathom_core::camera::CameraError;
use fathom_core::tape::CompileError;
use fathom_core::validate::SceneError;
use fathom_gpu::GpuError;
use fathom_svo::OctreeError;
use fathom_trace::TraceError;

/// Why a session could not render a frame or take a scene.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The request breaks a limit or asks for something the backend cannot do.
    #[error(transparent)]
    Request(#[from] RequestError),
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The scene did not compile to a tape.
    #[error(transparent)]
    Compile(#[from] CompileError),
    /// The camera cannot form an image.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// The CPU tracer refused or failed.
    #[error(transparent)]
    Trace(TraceError),
    /// The GPU renderer refused or failed (no adapter, out of memory, ...).
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The octree renderer refused or failed.
    #[error(transparent)]
    Octree(#[from] OctreeError),
    /// The volume renderer refused or failed.
    #[error(transparent)]
    Volume(#[from] fathom_volume::VolumeError),
    /// The path tracer refused or failed.
    #[error(transparent)]
    Path(fathom_pathtrace::PathTraceError),
    /// The frame was abandoned through its [`crate::CancelToken`]; the session is unchanged.
    #[error("the render was cancelled")]
    Cancelled,
    /// The worker thread pool could not be started.
    #[error("cannot start {threads} worker threads: {message}")]
    Threads {
        /// Threads asked for.
        threads: usize,
        /// The pool builder's error.
        message: String,
    },
    /// A deep eye's trailing part is NaN or infinite, or its view scale is not positive.
    #[error(
        "a deep eye needs a finite trailing part and a positive scale; got ({x}, {y}, {z}) and scale {scale}"
    )]
    DeepEye {
        /// The trailing part's x.
        x: f64,
        /// The trailing part's y.
        y: f64,
        /// The trailing part's z.
        z: f64,
        /// The view scale given.
        scale: f64,
    },
}

impl From<fathom_pathtrace::PathTraceError> for RenderError {
    fn from(e: fathom_pathtrace::PathTraceError) -> RenderError {
        match e {
            fathom_pathtrace::PathTraceError::Cancelled => RenderError::Cancelled,
            e => RenderError::Path(e),
        }
    }
}

impl From<TraceError> for RenderError {
    fn from(e: TraceError) -> RenderError {
        match e {
            TraceError::Cancelled => RenderError::Cancelled,
            e => RenderError::Trace(e),
        }
    }
}
