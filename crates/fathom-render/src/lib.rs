//! fathom-render: the render layer between the renderers (fathom-trace, fathom-gpu,
//! fathom-svo) and every front end (the `fathom` command, the explorer window, render-farm
//! tasks). The renderers know nothing of it; front ends parse their input into a
//! [`RenderRequest`] and call a [`Session`].
//!
//! - [`request`]: [`RenderRequest`], one serialisable value for what to render (size,
//!   projection, supersampling, prepass, tracer rule, SSAO, fog, backend, threads, region);
//! - [`session`]: [`Session`], the scene, its tape and each backend's state; `set_scene` says
//!   whether an edit re-baked parameters or recompiled; `render` returns a frame and [`Stats`];
//! - [`control`]: cancellation ([`CancelToken`], checked between tiles) and progress;
//! - [`stats`]: [`Stats`], one statistics type serialised with the same keys for every backend;
//! - [`zoom`]: the octree's zoom loop with its precision guard;
//! - [`compare`]: an octree frame against the sphere tracer's (SSIM, silhouette IoU, colour);
//! - [`flight`]: a scene's flight path rendered frame by frame (`fathom render --path`);
//! - `backend`: the backends with state of their own (`gpu`, `octree`, `volume`, `path`: the
//!   path tracer's state is its accumulator, which refines a still view across renders) and
//!   the types they share with the session ([`Rendered`], [`Counters`]).
//!
//! Regions (a rectangle of a larger image): the CPU tracer renders only the tiles a region
//! needs, bit-identical to the same pixels of the whole render (SSAO and prepass borders
//! included); the GPU and octree backends render the whole frame and crop it (the same
//! pixels, no time saved).
//!
//! A first use: a session over a preset renders a small frame with the CPU tracer (the default
//! backend), then takes an edited scene without recompiling it.
//!
//! ```
//! use fathom_render::{RenderRequest, SceneChange, Session};
//!
//! let scene = fathom_core::presets::load("mandelbulb")?;
//! let camera = scene.camera.clone();
//! let mut session = Session::new(scene.clone())?;
//! let request = RenderRequest { width: 32, height: 24, ..RenderRequest::default() };
//! let rendered = session.render(&camera, &request)?;
//! assert_eq!((rendered.frame.width, rendered.frame.height), (32, 24));
//! assert_eq!(rendered.stats.renderer, "trace");
//!
//! let mut brighter = scene;
//! brighter.lights[0].intensity *= 2.0;
//! assert_eq!(session.set_scene(brighter)?, SceneChange::Settings);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

mod backend;
pub mod compare;
pub mod control;
pub mod error;
pub mod flight;
pub mod request;
pub mod session;
pub mod stats;
pub mod zoom;

pub use backend::{Counters, Rendered};
pub use control::{CancelToken, Control, Progress};
pub use error::RenderError;
pub use request::{Backend, OctreeSettings, PathRequest, RenderRequest, RequestError, TracerRule};
pub use session::{SceneChange, Session};
pub use stats::Stats;

#[cfg(test)]
mod deep_tests;
#[cfg(test)]
mod tests;
