//! fathom-trace: the CPU sphere tracer.
//!
//! - [`tracer`]: basic and enhanced sphere tracing of a packet of rays (also cones);
//! - [`deep`]: a careful double-double reference tracer for small images at any zoom depth;
//! - [`prepass`]: the multi-resolution cone-marching depth prepass;
//! - [`shade`]: normals, materials, Blinn-Phong, soft shadows, AO, orbit traps, sky;
//! - [`render`]: one frame end to end, tiles over rayon, finished by
//!   [`fathom_image::post::finish_view`] and laid out by [`fathom_image::stereo`].
//!
//! [`output`], [`post`] and [`stereo`] are [`fathom_image`]'s modules, re-exported here so
//! the command line's many `fathom_trace::output` paths keep working; new code uses
//! `fathom_image` directly.
//!
//! A first use: render a small image of a preset on the CPU.
//!
//! ```
//! use fathom_trace::{Options, render};
//!
//! let scene = fathom_core::presets::load("mandelbulb")?;
//! let opts = Options { width: 32, height: 24, ..Options::default() };
//! let (frame, stats) = render(&scene, &opts, &|_done, _total| {})?;
//! assert_eq!((frame.width, frame.height), (32, 24));
//! assert!(stats.hits > 0, "the fractal fills the middle of the view");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

pub mod deep;
pub mod prepass;
pub mod render;
pub mod shade;
pub mod tracer;

pub use fathom_image::{output, post, stereo};

pub use render::{Hooks, Options, OptionsError, Stats, TraceError, render, render_tape};
pub use tracer::Method;

#[cfg(test)]
mod stereo_tests;
#[cfg(test)]
mod tests;
