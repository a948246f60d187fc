//! The octree view: one octree, one scene, one camera, advanced a frame at a time.
//!
//! A frame has three phases, so no frame ever sees a half-updated octree (no torn frames by
//! construction) while both cores stay busy in each phase:
//! 1. **render** (parallel over rows, the tree shared read-only; rays only write neighbour-link
//!    improvements, visited flags and subdivision requests, all atomics that never change what
//!    a ray sees), then voxels two or more pixels wide drawn smooth ([`crate::smooth`]);
//! 2. **subdivide** (the requested leaves, largest first, their 8 children evaluated in
//!    parallel within a time budget, then linked in on one thread; all-empty children recombine
//!    upward);
//! 3. **unify** (every few frames, or when memory runs short: unload bricks no ray visited).
//!
//! The skip node (the leaf containing the eye) is updated before rendering by following the
//! neighbour link through the face the eye crossed, or one descent from the root.
//!
//! Files: the settings (`config`), the anchor and the deep eye (`anchor`), the skip node
//! (`skip_node`), the render (`render`, with `pixels`, `tiles` and `outside_tiles`), the
//! settling probes (`settling`, `probe`), subdivision (`subdivide`), unification (`unify`),
//! the whole frame (`step`), and what a frame gives back (`image`, `frame_stats`).

mod anchor;
mod config;
mod frame_stats;
mod image;
mod outside_tiles;
mod pixels;
mod probe;
mod render;
mod settling;
mod skip_node;
mod step;
mod subdivide;
mod tiles;
mod unify;

pub use anchor::{ANCHOR_LEVELS_ABOVE, DeepEye};
pub use config::{
    DEFAULT_BEAM, DEFAULT_BEAM_MIN, DEFAULT_SUBDIVIDE_MS, OctreeViewConfig, Traversal,
};
pub use frame_stats::{FrameStats, resident_bytes};
pub use image::{MAX_VOXEL_PX, SvoImage};
pub use outside_tiles::OUTSIDE_TILES_PAUSE;
pub use settling::{PROBE_SLICE, Settling};
pub use subdivide::DEEP_COST;
pub use unify::IDLE_UNIFICATIONS;

use crate::error::OctreeError;
use crate::generate::init_root;
use crate::geometry::BoxU;
use crate::octree::Octree;
use crate::request_order::Fovea;
use crate::shader::{Origin, Shader};
use crate::smooth::Smoother;
use fathom_core::scene::Scene;
use glam::DVec3;
use outside_tiles::OutsideTiles;
use pixels::FrameBuffers;

/// The scale-adaptive sparse voxel octree of one scene, advanced a frame at a time as a
/// camera moves: the tree, its shader, and what one frame keeps for the next.
pub struct OctreeView {
    /// The octree (public for checks and tools; mutate only between frames).
    pub tree: Octree,
    /// Tape and shading.
    pub shader: Shader,
    /// Settings.
    pub cfg: OctreeViewConfig,
    sky: ([f64; 3], [f64; 3]),
    pool: rayon::ThreadPool,
    skip: Option<(u32, BoxU)>,
    frame: u64,
    beam_steps: u64,
    rays_from_skip: u64,
    /// Pixels the last render filled without a ray ([`crate::fill`]).
    filled: u64,
    /// Whether renders with the eye outside the root use tile starts.
    outside_tiles: OutsideTiles,
    /// The last render's LOD factor ([`Ray::lod`]): a requested leaf's children narrower
    /// than its ray's footprint (`t * lod`) are final for now.
    lod: f64,
    /// Median hit distance of the last render (root units; infinite before the first): the
    /// tile walks start from the eye's ancestor whose faces are at least this far.
    reach: f64,
    /// The last render's view, by which the next subdivision orders its requests.
    fovea: Fovea,
    /// Draws wide voxels smooth (`cfg.smooth`), its table kept between frames.
    smoother: Smoother,
    /// A render's per-pixel buffers, kept from one frame to the next (see [`FrameBuffers`]).
    buffers: FrameBuffers,
}

impl OctreeView {
    /// An octree view of `scene` with one root voxel.
    pub fn new(scene: &Scene, cfg: OctreeViewConfig) -> Result<OctreeView, OctreeError> {
        cfg.validate()?;
        let shader = Shader::new(scene, cfg.margin)?;
        let max_nodes = cfg.max_memory / std::mem::size_of::<crate::node::Node>();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(cfg.threads)
            .build()
            .map_err(|e| OctreeError::Pool {
                threads: cfg.threads,
                message: e.to_string(),
            })?;
        let (root_min, root_size) = pool.install(|| cfg.root.resolve(&shader));
        let mut tree = Octree::new(root_min, root_size, cfg.brick_period, max_nodes);
        if cfg.planes {
            tree.plane_px = 1.0;
        }
        let mut shader = shader;
        shader.origin = Origin {
            hi: root_min,
            lo: DVec3::ZERO,
            deep: false,
        };
        init_root(&mut tree, &shader);
        Ok(OctreeView {
            tree,
            shader,
            sky: (scene.render.sky_bottom, scene.render.sky_top),
            cfg,
            pool,
            skip: None,
            frame: 0,
            beam_steps: 0,
            rays_from_skip: 0,
            filled: 0,
            outside_tiles: OutsideTiles::default(),
            lod: 0.0,
            reach: f64::INFINITY,
            fovea: Fovea::NONE,
            smoother: Smoother::default(),
            buffers: FrameBuffers::default(),
        })
    }

    /// Forgets the measurements that choose between tiles and none with the eye outside the
    /// root ([`OutsideTiles`]): the next render uses tiles (tests of the tiles themselves).
    #[cfg(test)]
    pub(crate) fn allow_outside_tiles(&mut self) {
        self.outside_tiles = OutsideTiles::default();
    }

    /// Nodes the tiles' start walks visited in the last render (included in its step count).
    pub fn beam_steps(&self) -> u64 {
        self.beam_steps
    }

    /// Rays of the last render's tiled path that started at the skip node (see
    /// [`FrameStats::rays_from_skip`]).
    pub fn rays_from_skip(&self) -> u64 {
        self.rays_from_skip
    }
}
