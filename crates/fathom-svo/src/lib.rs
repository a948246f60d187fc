//! fathom-svo: the scale-adaptive sparse voxel octree (SVO) explorer.
//!
//! A rebuild of the dissertation system (scale-adaptive SVO, neighbour-link traversal with a
//! skip node, brick-based not-recently-used unification) with the frame phased so that no frame
//! ever sees a half-updated octree. See `docs/svo.md` for the design.
//!
//! An [`OctreeView`] is the octree of one scene seen from a moving camera: settle it at a
//! camera for a still, or step it once a frame along a zoom.
//!
//! ```
//! use fathom_core::Camera;
//! use fathom_svo::{OctreeView, OctreeViewConfig};
//! use glam::DVec3;
//!
//! let cfg = OctreeViewConfig { width: 64, height: 48, ..OctreeViewConfig::default() };
//! let mut view = OctreeView::new(&fathom_core::scenes::menger(4), cfg)?;
//! let cam = Camera {
//!     eye: DVec3::new(1.9, 1.7, 1.5),
//!     target: DVec3::new(0.6, 0.5, 0.4),
//!     up: DVec3::Y,
//!     fov: 50.0,
//! };
//! // A still: split the leaves rays ask for until none asks (at most 100 rounds).
//! view.settle(&cam, 100);
//! // A frame of a moving camera: render, split within the time budget, maybe unload.
//! let (image, stats) = view.step(&cam);
//! assert_eq!(image.colour.len(), 64 * 48);
//! assert!(stats.hits > 0);
//! # Ok::<(), fathom_svo::OctreeError>(())
//! ```
//!
//! The modules, each using only those above it:
//!
//! - [`geometry`]: boxes (exact lattice cells, f64 boxes near the eye), rays, a ray's entry
//!   into and exit from a box;
//! - [`plane`]: the surface plane a full leaf wider than a pixel is drawn with;
//! - [`node`]: the arena node (48 bytes) and its flags;
//! - [`octree`]: the arena of nodes, free list of child blocks, the anchor near the eye that
//!   boxes are measured from, counts;
//! - [`check`]: the link-integrity checker;
//! - [`evict`]: bricks, visited flags, NRU unification with link repair;
//! - [`traverse`]: neighbour traversal with skip node and link optimisation, kd-restart;
//! - [`frustum`]: where a pixel tile's rays can start, from a walk of the nodes its frustum
//!   meets;
//! - [`ray_grid`]: the pixel rays of a frame, set up a run of pixels at a time;
//! - [`fill`]: pixels filled from the lattice rays around them where voxels are wide;
//! - [`smooth`]: voxels two or more pixels wide drawn smooth;
//! - [`request_order`]: which requested leaves a frame splits first (largest on screen,
//!   nearer the centre counted larger);
//! - [`shader`]: the compiled scene evaluated near the anchor (f64 or double-double, four
//!   points at once), a voxel's colour and surface plane, its line of sight;
//! - [`generate`]: the conservative full test, subdivision and recombination;
//! - [`error`]: [`OctreeError`], the typed errors of an octree view's settings;
//! - [`root`]: the root cube, fitted to the scene's bounds or given;
//! - [`octree_view`]: [`OctreeView`], one frame = render (read-only) -> subdivide -> unify;
//!   settling loops; settings, image and stats;
//! - [`outline`]: silhouette agreement with a sphere tracer, image similarity;
//! - [`precision`]: the guard that stops a zoom where the octree's arithmetic runs out
//!   (depth 98, zoom ~1e28 at 640x480);
//! - [`stats`]: summaries of per-frame stats.

#![warn(missing_docs)]
// Loops over the three axes index several arrays at once.
#![allow(clippy::needless_range_loop)]

pub mod check;
pub mod error;
pub mod evict;
pub mod fill;
pub mod frustum;
pub mod generate;
pub mod geometry;
pub mod node;
pub mod octree;
pub mod octree_view;
pub mod outline;
pub mod plane;
pub mod precision;
pub mod ray_grid;
pub mod request_order;
pub mod root;
pub mod shader;
pub mod smooth;
pub mod stats;
pub mod traverse;

pub use error::OctreeError;
pub use octree::Octree;
pub use octree_view::{DeepEye, FrameStats, OctreeView, OctreeViewConfig, SvoImage, Traversal};
pub use root::{MENGER_CUBE, RootSpec};

#[cfg(test)]
mod deep_tests;
#[cfg(test)]
mod tests;
