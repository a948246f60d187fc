//! fathom-pathtrace: a progressive, unbiased path tracer for fathom's distance fields, for
//! pictures worth printing.
//!
//! A renderer backend calls, in order:
//! 1. [`PathTracer::new`]`(&scene, &tape, PathSettings::new(w, h))`: validates everything
//!    and prepares lights, looks and the camera;
//! 2. [`Progressive::new`]`(tracer)`, then [`Progressive::add_samples`]`(n, &Control)` as
//!    often as time allows (cancellable, deterministic for any thread count);
//! 3. [`Progressive::frame`] for colour + albedo + normal + depth + variance, and
//!    [`denoise::denoise`] for a cleaned-up image; [`Progressive::stats`] for paths/s and
//!    dropped non-finite paths.
//!
//! Modules, each with one purpose:
//! - [`shared`]: constants a WGSL port must share;
//! - [`sampler`]: Owen-scrambled Sobol samples per (pixel, index, dimension);
//! - [`sampling`]: frames, warps, the power heuristic;
//! - [`material`]: [`PbrMaterial`], its validation and the mapping of today's materials;
//! - [`microfacet`], [`bsdf`]: GGX with VNDF sampling and energy compensation; the BSDF;
//! - [`colour`]: looks: gradients over orbit traps, position and normal;
//! - [`lights`], [`envmap`], [`distribution`]: directional cones, sphere lights, sky and
//!   environment maps with importance sampling;
//! - [`medium`]: homogeneous and height fog, Henyey-Greenstein;
//! - [`camera`]: the thin lens; [`march`]: sphere tracing and normals;
//! - [`integrator`]: the path tracer; [`progressive`]: accumulation and frames;
//! - [`denoise`]: the à-trous denoiser; [`output`]: tonemapping, PNG, RMSE;
//! - [`settings`]: what to render and the crate's error.
#![warn(missing_docs)]

pub mod bsdf;
pub mod camera;
pub mod colour;
pub mod denoise;
pub mod distribution;
pub mod envmap;
pub mod furnace;
pub mod integrator;
pub mod lights;
pub mod march;
pub mod material;
pub mod medium;
pub mod microfacet;
pub mod output;
pub mod progressive;
pub mod sampler;
pub mod sampling;
pub mod settings;
pub mod shared;

pub use denoise::{DenoiseSettings, denoise};
pub use integrator::PathTracer;
pub use material::PbrMaterial;
pub use progressive::{Control, Frame, Progressive, Stats};
pub use settings::{PathSettings, PathTraceError};
