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
    #[error(transparent)]
    Request(#[from] RequestError),
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Compile(#[from] CompileError),
    #[error(transparent)]
    Camera(#[from] CameraError),
    #[error(transparent)]
    Trace(TraceError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Octree(#[from] OctreeError),
    #[error(transparent)]
    Volume(#[from] fathom_volume::VolumeError),
    #[error(transparent)]
    Path(fathom_pathtrace::PathTraceError),
    /// The frame was abandoned through its [`crate::CancelToken`]; the session is unchanged.
    #[error("the render was cancelled")]
    Cancelled,
    #[error("cannot start {threads} worker threads: {message}")]
    Threads { threads: usize, message: String },
    /// A deep eye's trailing part is NaN or infinite, or its view scale is not positive.
    #[error(
        "a deep eye needs a finite trailing part and a positive scale; got ({x}, {y}, {z}) and scale {scale}"
    )]
    DeepEye { x: f64, y: f64, z: f64, scale: f64 },
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
