//! fathom-core: what a scene is and how it is evaluated.
//!
//! - [`registry`]: how each primitive, fractal and operator is declared once;
//! - [`primitives`], [`fractals`], [`transforms`], [`modifiers`], [`combine`]: the declarations;
//! - [`scene`]: the scene tree, camera, lights, render settings; [`scenes`]: code-built ones;
//! - [`camera`]: the camera and its projections; [`camera_path`]: zooms and tours over frames;
//! - [`flight`]: named flight paths (keyframes, splines, scale-aware timing);
//!   [`binding`]: parameters driven by LFOs or OSC; [`param_path`]: a number of a scene by path;
//! - [`tape`]: the flat program a scene compiles to (see `docs/tape.md`);
//! - [`eval`]: the CPU interpreter (f64 scalar and f32x8 packet paths) and normals;
//! - [`dd`]: double-double numbers ([`Dd`], ~1e-32 relative) for zooms past f64 precision;
//! - [`reference`]: a direct tree walk that defines what the tape must compute;
//! - [`shared`]: constants the CPU renderers and the WGSL program share, defined once;
//! - [`atomic_file`]: every output written under a temporary name and renamed once whole;
//!   [`cleanup`]: temporary files removed on every exit path, Ctrl-C included;
//!   [`input_file`]: inputs read only when regular files under a size limit.

pub mod atomic_file;
pub mod binding;
pub mod call_serde;
pub mod camera;
pub mod camera_path;
pub mod cleanup;
pub mod combine;
pub mod dd;
pub mod dd4;
pub mod docgen;
pub mod eval;
pub mod flight;
pub mod fractals;
pub mod frame;
pub mod input_file;
pub mod limits;
pub mod modifiers;
pub mod param_path;
pub mod presets;
pub mod primitives;
pub mod real;
pub mod reference;
pub mod registry;
pub mod scene;
pub mod scene_file;
pub mod scenes;
pub mod shared;
pub mod tape;
#[cfg(test)]
mod tape_props;
#[cfg(any(test, feature = "testing"))]
pub mod testing;
pub mod transforms;
pub mod value;
pub mod vec3;

pub use camera::{Camera, CameraFrame, Projection};
pub use dd::Dd;
pub use eval::Evaluator;
pub use real::{F32x8, F64x4, Real};
pub use scene::{Call, Material, Node, Scene};
pub use tape::Tape;
pub use value::Value;
pub use vec3::V3;
