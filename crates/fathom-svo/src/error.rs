//! What can go wrong setting up an octree view, each naming the setting and its range.

use fathom_core::tape::CompileError;

/// Why an octree view could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OctreeError {
    /// The image size (`width` x `height` pixels) is 0 or above 16384 on a side.
    #[error("image size {width}x{height} is out of range (1..=16384 per side)")]
    Size {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
    },
    /// `fidelity`, pixels a voxel may cover, is outside [0.25, 16].
    #[error("fidelity {0} is out of range [0.25, 16] (pixels per voxel)")]
    Fidelity(f64),
    /// The worker thread count is 0 or above 256.
    #[error("threads {0} is out of range 1..=256")]
    Threads(usize),
    /// The brick period (levels between bricks) is 0 or above 16.
    #[error("brick period must be in 1..=16 levels")]
    BrickPeriod(u8),
    /// `unify_every` is 0 frames.
    #[error("unify-every must be at least 1 frame")]
    UnifyEvery,
    /// The memory budget (bytes) is below 1 MiB.
    #[error("max memory {0} bytes is below the minimum of 1 MiB")]
    Memory(usize),
    /// The full test's relative margin is outside [0, 1].
    #[error("margin {0} is out of range [0, 1]")]
    Margin(f64),
    /// The subdivision time per frame (ms) is negative or not finite.
    #[error("subdivision budget must be a non-negative number of ms")]
    SubdivideMs(f64),
    /// The frame rate to hold is outside [0, 1000].
    #[error("target frame rate {0} is out of range 0..=1000 fps (0: a fixed subdivision time)")]
    TargetFps(f64),
    /// An explicit root cube is not finite or has no positive side.
    #[error("the root cube must be finite with a positive side")]
    Root,
    /// The tile side of the start walks is above 256 pixels.
    #[error("beam (tile side) {0} is out of range 0..=256 pixels (0: no beams)")]
    Beam(u32),
    /// The finest tile side is 0 or above 256 pixels.
    #[error("beam-min (finest beam tile side) {0} is out of range 1..=256 pixels")]
    BeamMin(u32),
    /// The fovea weight is outside [0, 64].
    #[error("fovea {0} is out of range [0, 64] (0: requests served by size on screen alone)")]
    Fovea(f64),
    /// `fill_px` is neither 0 nor in [2, 64] pixels.
    #[error("fill-px {0} is out of range 0 or [2, 64] pixels (0: every pixel casts its ray)")]
    FillPx(f64),
    /// The scene did not compile to a tape.
    #[error(transparent)]
    Compile(#[from] CompileError),
    /// The worker thread pool could not start (`threads` threads; the pool's `message`).
    #[error("cannot start {threads} threads: {message}")]
    Pool {
        /// Threads asked for.
        threads: usize,
        /// Why the pool failed.
        message: String,
    },
}
