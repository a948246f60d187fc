//! fathom-svo: the scale-adaptive sparse voxel octree (SVO) explorer.
//!
//! A rebuild of the dissertation system (scale-adaptive SVO, neighbour-link traversal with a
//! skip node, brick-based not-recently-used unification) with the frame phased so that no frame
//! ever sees a half-updated octree. See `docs/svo.md` for the design.
//!
//! - [`geometry`]: boxes (exact lattice cells, f64 boxes near the eye), rays, a ray's entry
//!   into and exit from a box (a leaf module the others share);
//! - [`node`]: the arena node (48 bytes) and its flags;
//! - [`plane`]: the surface plane a full leaf wider than a pixel is drawn with;
//! - [`octree`]: the arena of nodes, free list of child blocks, exact lattice cells, boxes
//!   relative to the anchor near the eye, counts;
//! - [`root`]: the root cube, fitted to the scene's bounds or given;
//! - [`generate`]: the conservative full test, subdivision and recombination;
//! - [`shader`]: the compiled scene evaluated near the anchor (f64 or double-double, four
//!   points at once), a voxel's colour and surface plane, its line of sight;
//! - [`traverse`]: neighbour traversal with skip node and link optimisation, kd-restart;
//! - [`frustum`]: where a pixel tile's rays can start, from a walk of the nodes its frustum
//!   meets;
//! - [`evict`]: bricks, visited flags, NRU unification with link repair;
//! - [`check`]: the link-integrity checker;
//! - [`outline`]: silhouette agreement with a sphere tracer, image similarity;
//! - [`ray_grid`]: the pixel rays of a frame, set up a run of pixels at a time;
//! - [`request_order`]: which requested leaves a frame splits first (largest on screen,
//!   nearer the centre counted larger);
//! - [`octree_view`]: one frame = render (read-only) -> subdivide -> unify; stats;
//! - [`precision`]: the guard that stops a zoom where the octree's arithmetic runs out
//!   (depth 98, zoom ~1e28 at 640x480);
//! - [`stats`]: summaries of per-frame stats.

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
