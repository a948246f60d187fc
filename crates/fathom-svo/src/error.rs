//! What can go wrong setting up an octree view, each naming the setting and its range.

use fathom_core::tape::CompileError;

/// Why an octree view could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OctreeError {
    #[error("image size {width}x{height} is out of range (1..=16384 per side)")]
    Size { width: u32, height: u32 },
    #[error("fidelity {0} is out of range [0.25, 16] (pixels per voxel)")]
    Fidelity(f64),
    #[error("threads {0} is out of range 1..=256")]
    Threads(usize),
    #[error("brick period must be in 1..=16 levels")]
    BrickPeriod(u8),
    #[error("unify-every must be at least 1 frame")]
    UnifyEvery,
    #[error("max memory {0} bytes is below the minimum of 1 MiB")]
    Memory(usize),
    #[error("margin {0} is out of range [0, 1]")]
    Margin(f64),
    #[error("subdivision budget must be a non-negative number of ms")]
    SubdivideMs(f64),
    #[error("target frame rate {0} is out of range 0..=1000 fps (0: a fixed subdivision time)")]
    TargetFps(f64),
    #[error("the root cube must be finite with a positive side")]
    Root,
    #[error("beam (tile side) {0} is out of range 0..=256 pixels (0: no beams)")]
    Beam(u32),
    #[error("beam-min (finest beam tile side) {0} is out of range 1..=256 pixels")]
    BeamMin(u32),
    #[error("fovea {0} is out of range [0, 64] (0: requests served by size on screen alone)")]
    Fovea(f64),
    #[error("fill-px {0} is out of range 0 or [2, 64] pixels (0: every pixel casts its ray)")]
    FillPx(f64),
    #[error(transparent)]
    Compile(#[from] CompileError),
    #[error("cannot start {threads} threads: {message}")]
    Pool { threads: usize, message: String },
}
