//! fathom-volume: density grids, a volume path tracer and a 3D physarum simulation.
//!
//! - [`grid`]: dense grids (u32 trail counts, f32 densities) in a world box, nearest and
//!   trilinear lookup with Mitsuba 3's conventions; [`vol_file`] (Mitsuba's `.vol`) and
//!   [`raw_file`] (fathom's raw format) read and write them, checking sizes before allocating;
//! - [`fractal`]: any scene's tape sampled into a density grid (density where the distance is
//!   negative, optionally smoothed);
//! - [`majorant`]: the coarse grid of per-block maxima and its 3D DDA; [`medium`]: delta
//!   tracking (free flights) and ratio tracking (transmittance) against it; [`phase`]:
//!   Henyey-Greenstein; [`light`]: environment, sun, emission;
//! - [`integrator`]: one camera path (next-event estimation with MIS, Russian roulette);
//!   [`render`]: progressive, deterministic images over rayon;
//! - [`physarum`]: the agent simulation that grows a network in a trail grid;
//! - [`exposure`]: the extinction scale and the box to frame, from a grid's statistics.
//!
//! See `docs/volume.md` for the design and the measurements.

pub mod error;
pub mod exposure;
mod file_io;
pub mod fractal;
pub mod grid;
pub mod integrator;
pub mod light;
pub mod majorant;
pub mod medium;
pub mod phase;
pub mod physarum;
pub mod pipeline;
pub mod raw_file;
pub mod render;
pub mod sampling;
pub mod vol_file;

pub use error::VolumeError;
pub use grid::{DensityGrid, Grid, TrailGrid, WorldBox};
