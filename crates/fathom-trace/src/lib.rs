//! fathom-trace: the CPU sphere tracer.
//!
//! - [`tracer`]: basic and enhanced sphere tracing of a packet of rays (also cones);
//! - [`deep`]: a careful double-double reference tracer for small images at any zoom depth;
//! - [`prepass`]: the multi-resolution cone-marching depth prepass;
//! - [`shade`]: normals, materials, Blinn-Phong, soft shadows, AO, orbit traps, sky;
//! - [`post`]: effects on a [`fathom_core::frame::Frame`] (fog, SSAO, tonemap, gamma);
//! - [`output`]: PNG, mask, depth EXR and step heat-map files;
//! - [`render`]: one frame end to end, tiles over rayon;
//! - [`stereo`]: the side-by-side and top/bottom layouts of stereo views.

pub mod deep;
pub mod output;
pub mod post;
pub mod prepass;
pub mod render;
pub mod shade;
pub mod stereo;
pub mod tracer;

pub use render::{Hooks, Options, OptionsError, Stats, TraceError, render, render_tape};
pub use tracer::Method;

#[cfg(test)]
mod tests;
