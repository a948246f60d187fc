//! The backends with state of their own, behind [`crate::Session`], and what they share: the
//! finished frame ([`Rendered`]) and the session's work counters ([`Counters`]).
//!
//! - [`gpu`]: the wgpu tracer's renderer and device, created on first use;
//! - [`octree`]: the octree explorer, rebuilt when the scene or its settings change;
//! - [`volume`]: the density grid sampled from the scene and the volume path tracer;
//! - [`path`]: the path tracer's accumulator, which refines a still view across renders.
//!
//! The CPU sphere tracer keeps no state between frames and is called by the session directly.

use crate::control::Control;
use crate::stats::Stats;
use fathom_core::frame::Frame;
use serde::Serialize;

pub mod gpu;
pub mod octree;
pub mod path;
pub mod volume;

/// How often the session compiled or updated its tape (the proof that slider edits compile
/// nothing).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Counters {
    /// Full compilations of the tape (the first one included).
    pub compiles: u64,
    /// Parameter-buffer updates without compilation.
    pub param_updates: u64,
    /// Tape uploads to the GPU (a parameter edit rewrites only the parameter buffer).
    pub gpu_uploads: u64,
    /// Octree explorers built (each scene or octree-setting change builds one).
    pub octrees_built: u64,
    /// Density grids sampled for the volume backend (each scene or volume-setting change).
    pub volumes_sampled: u64,
    /// Path-tracing accumulators started (each change of view, scene or path settings).
    pub path_accumulators: u64,
}

/// A finished frame and what it cost.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image and its G-buffer.
    pub frame: Frame,
    /// What the frame cost and found.
    pub stats: Stats,
}

/// A progress report for backends that render in one piece: done.
pub(crate) fn report_done(control: &Control) {
    control.report(1, 1);
}
