//! fathom-gpu: the GPU renderer. One WGSL program interprets the same tape the CPU runs
//! (`docs/tape.md`), so a scene never needs a new shader: parameter edits are buffer writes,
//! structure edits upload a new instruction stream, and the pipelines are built once per run.
//!
//! - [`shader`]: the WGSL source, with the registry dispatch generated from the registry tables,
//!   and its naga validation;
//! - [`device`]: adapter and device set-up, headless or for a surface, with clear errors;
//! - [`renderer`]: buffers, pipelines, the render passes and the readback into a `Frame`;
//! - [`path`]: the path tracer (fathom-pathtrace's integrator in WGSL), accumulating samples
//!   on the device;
//! - [`denoise`]: the path tracer's à-trous denoiser on the device;
//! - [`precision`]: where f32 positions stop being enough and the CPU's f64 path must take over.

#![warn(missing_docs)]

pub mod denoise;
pub mod device;
pub mod error;
mod passes;
pub mod path;
mod path_state;
pub mod precision;
pub mod renderer;
pub mod shader;

pub use device::Gpu;
pub use error::GpuError;
pub use passes::{RenderOptions, RenderStats};
pub use renderer::{GpuValue, Projection, Renderer};
