//! fathom-core: what a scene is and how it is evaluated.
//!
//! The modules are grouped in folders: [`number`] (numbers and vectors), [`family`] (the
//! registry and the families it declares), [`model`] (the scene and its files), [`program`]
//! (tape and evaluation), [`animation`] (flight paths, camera paths, parameter paths,
//! bindings) and [`files`] (atomic output, cleanup, bounded input); each module is also
//! reachable at the crate root by its own name, as listed here:
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
//!
//! A first use: read a scene from its text, compile it to a [`Tape`] and ask for the distance
//! from a point to the surface.
//!
//! ```
//! use fathom_core::{Evaluator, Tape, V3, presets, scene_file};
//!
//! let text = "Scene(version: 1, root: Node(shape: Sphere(radius: 1.0)))";
//! let scene = scene_file::parse(text, "<doc>")?;
//! let tape = Tape::compile(&scene)?;
//! let d = Evaluator::<f64>::new().distance(&tape, V3::new(3.0, 0.0, 0.0));
//! assert!((d - 2.0).abs() < 1e-9);
//!
//! // The built-in presets are scenes too.
//! let bulb = Tape::compile(&presets::load("mandelbulb")?)?;
//! assert!(bulb.eval_f64([0.0, 0.0, 10.0]).d > 0.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

pub mod animation;
pub mod family;
pub mod files;
pub mod frame;
pub mod limits;
pub mod model;
pub mod number;
pub mod program;
#[cfg(any(test, feature = "testing"))]
pub mod testing;

// Every module keeps its path at the crate root (`fathom_core::scene`, `crate::tape`, ...), so
// the folders above group the code without renaming what other crates use.
pub use animation::{binding, camera_path, flight, flight_path, param_path, param_resolve};
pub use family::{
    call, call_serde, combine, docgen, fractals, modifiers, primitives, registry, transforms,
};
pub use files::{atomic_file, cleanup, input_file};
pub use model::{camera, presets, scene, scene_file, scenes, validate};
pub use number::{dd, dd4, real, rng, value, vec3};
pub use program::{eval, reference, shared, tape};

pub use camera::{Camera, CameraFrame, Projection};
pub use dd::Dd;
pub use eval::Evaluator;
pub use real::{F32x8, F64x4, Real};
pub use scene::{Call, Material, Node, Scene};
pub use tape::Tape;
pub use value::Value;
pub use vec3::V3;
