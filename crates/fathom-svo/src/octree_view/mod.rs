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

use crate::error::OctreeError;
use crate::evict::unify;
use crate::fill;
use crate::frustum::{Seed, StartPath, TileStack, TileStart, cast_at, tile_start, walk_root};
use crate::generate::{
    Children, Origin, Outcome, Probe, Shader, View, apply, eval_children, init_root,
};
use crate::geometry::{BoxU, Ray, dim_at};
use crate::node::{NONE, REQUESTED, pack_rgb};
use crate::octree::{Anchor, Octree};
use crate::ray_grid::{RayGrid, RaySpan, SPAN};
use crate::request_order::{DEFAULT_FOVEA, Fovea, RequestQueue};
use crate::root::RootSpec;
use crate::smooth::{self, Smoother};
use crate::traverse::{Hit, Request, cast_kdrestart, cast_neighbour};
use fathom_core::dd::Dd;
use fathom_core::scene::Scene;
use fathom_core::{Camera, CameraFrame};
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Which traversal renders the frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Traversal {
    /// Neighbour links from the skip node (scale independent).
    Neighbour,
    /// Descent from the root for every leaf (the baseline).
    KdRestart,
}

/// Settings of an octree view. [`OctreeViewConfig::validate`] gives the user-facing errors.
#[derive(Clone, Debug, PartialEq)]
pub struct OctreeViewConfig {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Voxels may project to up to this many pixels, [0.25, 16].
    pub fidelity: f64,
    /// Worker threads.
    pub threads: usize,
    /// Bricks every this many levels.
    pub brick_period: u8,
    /// Bricks shallower than this are never unloaded.
    pub keep_levels: u8,
    /// Unify every this many frames.
    pub unify_every: u32,
    /// Memory budget for the octree in bytes.
    pub max_memory: usize,
    /// Relative margin of the full test.
    pub margin: f64,
    /// Traversal used to render.
    pub traversal: Traversal,
    /// Time per frame for subdivision, in milliseconds (at least `min_subdivisions` are done).
    pub subdivide_ms: f64,
    /// Frame rate to hold, or 0 for none: above 0, a frame's subdivision takes no more than
    /// what its render left of the frame time `1000 / target_fps` ms, between half and all of
    /// `subdivide_ms` ([`OctreeViewConfig::subdivide_budget`]), [0, 1000].
    pub target_fps: f64,
    /// Subdivisions done each frame whatever the time, counted in f64 evaluations' worth: on
    /// deep frames (double-double evaluation) a subdivision counts [`DEEP_COST`] times.
    pub min_subdivisions: usize,
    /// The root cube: fitted to the scene (default) or explicit.
    pub root: RootSpec,
    /// Side in pixels of the tiles whose rays start where a walk of the nodes the tile's
    /// frustum meets showed none of them can stop sooner ([`crate::frustum`]; eye inside the
    /// root, neighbour traversal only; the same images), or 0 for every ray from the skip
    /// node.
    pub beam: u32,
    /// Finest tile side: a tile is cut into quadrants, each refining its parent's start with
    /// a walk of its own frustum, while the quadrants are at least this wide (`beam` or more:
    /// one level of tiles).
    pub beam_min: u32,
    /// Draw full leaves wider than a pixel with their surface planes ([`crate::plane`])
    /// instead of as cubes: a zoom's frames show surfaces instead of staircases while detail
    /// arrives, at the cost of the steps rays take through the leaves whose planes they pass
    /// (`docs/svo.md`, "Surface planes").
    pub planes: bool,
    /// How much nearer the screen's centre a subdivision request counts: its size on screen
    /// is divided by `1 + fovea rho^2`, `rho` its distance from the centre in half-heights
    /// ([`Fovea`]; 0: the largest on screen first wherever they are), [0, 64].
    pub fovea: f64,
    /// Draw voxels at least two pixels wide smooth: each such pixel takes the mean colour of
    /// a box as wide as its voxel on screen ([`crate::smooth`]), so a zoom's coarse frames
    /// show the leaves' colours joined smoothly instead of a mosaic. Frames whose voxels are
    /// all narrower (settled frames at fidelity below 2) are unchanged.
    pub smooth: bool,
    /// Pixels between rays that all met one voxel at least this many pixels wide take that
    /// voxel's colour without a ray of their own ([`crate::fill`]; frames to be seen, not
    /// probes; 0: every pixel casts), 0 or [2, 64].
    pub fill_px: f64,
}

impl Default for OctreeViewConfig {
    fn default() -> Self {
        OctreeViewConfig {
            width: 640,
            height: 480,
            fidelity: 1.0,
            threads: 2,
            brick_period: 3,
            keep_levels: 3,
            // Every 4 frames: each walk stays a small share of the frame, and a brick goes
            // after IDLE_UNIFICATIONS of them unvisited (~16 frames), soon enough that the
            // node count plateaus over a zoom and late enough that background the zoom
            // uncovers again is still there.
            unify_every: 4,
            max_memory: 1 << 30,
            margin: crate::generate::DEFAULT_MARGIN,
            traversal: Traversal::Neighbour,
            subdivide_ms: DEFAULT_SUBDIVIDE_MS,
            target_fps: 0.0,
            min_subdivisions: 256,
            root: RootSpec::default(),
            beam: DEFAULT_BEAM,
            beam_min: DEFAULT_BEAM_MIN,
            planes: false,
            fovea: DEFAULT_FOVEA,
            smooth: true,
            fill_px: crate::fill::DEFAULT_FILL_PX,
        }
    }
}

impl OctreeViewConfig {
    /// Checks every setting, with errors that name the option.
    pub fn validate(&self) -> Result<(), OctreeError> {
        let (width, height) = (self.width, self.height);
        if width == 0 || height == 0 || width > 16384 || height > 16384 {
            return Err(OctreeError::Size { width, height });
        }
        if !(self.fidelity.is_finite() && (0.25..=16.0).contains(&self.fidelity)) {
            return Err(OctreeError::Fidelity(self.fidelity));
        }
        if self.threads == 0 || self.threads > 256 {
            return Err(OctreeError::Threads(self.threads));
        }
        if self.brick_period == 0 || self.brick_period > 16 {
            return Err(OctreeError::BrickPeriod(self.brick_period));
        }
        if self.unify_every == 0 {
            return Err(OctreeError::UnifyEvery);
        }
        if self.max_memory < 1 << 20 {
            return Err(OctreeError::Memory(self.max_memory));
        }
        if !(self.margin.is_finite() && (0.0..=1.0).contains(&self.margin)) {
            return Err(OctreeError::Margin(self.margin));
        }
        if !(self.subdivide_ms.is_finite() && self.subdivide_ms >= 0.0) {
            return Err(OctreeError::SubdivideMs(self.subdivide_ms));
        }
        if !(self.target_fps.is_finite() && (0.0..=1000.0).contains(&self.target_fps)) {
            return Err(OctreeError::TargetFps(self.target_fps));
        }
        if self.beam > 256 {
            return Err(OctreeError::Beam(self.beam));
        }
        if self.beam_min == 0 || self.beam_min > 256 {
            return Err(OctreeError::BeamMin(self.beam_min));
        }
        if !(self.fovea.is_finite() && (0.0..=64.0).contains(&self.fovea)) {
            return Err(OctreeError::Fovea(self.fovea));
        }
        if !(self.fill_px == 0.0 || (2.0..=64.0).contains(&self.fill_px)) {
            return Err(OctreeError::FillPx(self.fill_px));
        }
        self.root.validate()
    }

    /// The subdivision time of a frame whose render took `render_ms`: `subdivide_ms`, or with
    /// a [`OctreeViewConfig::target_fps`] what the render left of the frame time, clamped to
    /// `[subdivide_ms / 2, subdivide_ms]`: a slow render still refines, and a fast one does
    /// not spend the spare time refining (giving it up to twice `subdivide_ms` made the
    /// Menger zoom's next frames slower to render, its 10th-percentile frame rate 30 to 22).
    pub fn subdivide_budget(&self, render_ms: f64) -> f64 {
        if self.target_fps > 0.0 {
            (1e3 / self.target_fps - render_ms).clamp(0.5 * self.subdivide_ms, self.subdivide_ms)
        } else {
            self.subdivide_ms
        }
    }
}

/// A rendered frame: colours (RGBA8, linear) and world depth (`f32::INFINITY` for sky).
#[derive(Clone, Debug, PartialEq)]
pub struct SvoImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGBA8 linear colours, row-major from the top-left.
    pub colour: Vec<u32>,
    /// Distance along the ray in world units.
    pub depth: Vec<f32>,
    /// The largest voxel any pixel shows, in pixels: its side over the pixel footprint at the
    /// distance where the ray met it (0 when nothing was hit; at most [`MAX_VOXEL_PX`]).
    pub largest_voxel_px: f64,
}

impl SvoImage {
    /// Silhouette mask: true where a voxel was hit.
    pub fn mask(&self) -> Vec<bool> {
        self.depth.iter().map(|d| d.is_finite()).collect()
    }

    /// The shared frame type, so the post effects of the sphere tracer (fog, SSAO, tonemap)
    /// and its output writers apply to octree renders too. Voxels carry no normal or id: the
    /// normal is zero, the id 0 for hits.
    pub fn to_frame(&self) -> fathom_core::frame::Frame {
        let mut f = fathom_core::frame::Frame::new(self.width, self.height);
        for (i, (&c, &d)) in self.colour.iter().zip(&self.depth).enumerate() {
            f.colour[i] = std::array::from_fn(|k| ((c >> (8 * k)) & 255) as f32 / 255.0);
            f.depth[i] = d;
            if d.is_finite() {
                f.id[i] = 0;
            }
        }
        f
    }

    /// 8-bit sRGB bytes (RGB), for PNG output.
    pub fn to_srgb8(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.colour.len() * 3);
        for &c in &self.colour {
            for i in 0..3 {
                let v = ((c >> (8 * i)) & 255) as f64 / 255.0;
                out.push((v.powf(1.0 / 2.2) * 255.0 + 0.5) as u8);
            }
        }
        out
    }
}

/// Per-frame statistics (written as JSON by `fathom zoom --stats`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct FrameStats {
    /// Frame number from 0.
    pub frame: u64,
    /// Wall time of the whole frame in ms.
    pub frame_ms: f64,
    /// Render phase in ms.
    pub render_ms: f64,
    /// Subdivision phase in ms (on a window's still step, its settling probes too).
    pub subdivide_ms: f64,
    /// Unification phase in ms.
    pub unify_ms: f64,
    /// Rays cast.
    pub rays: u64,
    /// Rays that hit a voxel.
    pub hits: u64,
    /// Mean nodes stepped through per ray.
    pub nodes_per_ray: f64,
    /// Distinct leaves rays asked to subdivide (`rays`, `hits`, `nodes_per_ray` and this
    /// count the render's rays only, not a still step's settling probes).
    pub requests: u64,
    /// Leaves split into children (on a still step, more than `requests` when its settling
    /// probes asked for more).
    pub subdivisions: u64,
    /// Leaves whose children were all empty.
    pub emptied: u64,
    /// Requests refused by the memory budget (on a still step, its settling probes' too:
    /// the step settles no further once the budget is spent, so none is counted twice).
    pub no_memory: u64,
    /// Bricks unloaded.
    pub unified: u64,
    /// Allocated node slots.
    pub node_count: u64,
    /// Bricks (inner nodes at brick depths).
    pub brick_count: u64,
    /// Bytes of the node arena.
    pub arena_bytes: u64,
    /// Resident memory of the process (bytes, from /proc; 0 where unavailable).
    pub resident_bytes: u64,
    /// Depth of the skip node (-1 when the eye is outside the root).
    pub skip_depth: i32,
    /// Depth of the anchor box coordinates are measured from (0: root units, f64 evaluation;
    /// deeper: double-double evaluation).
    pub anchor_depth: u8,
    /// The largest voxel visible in this frame, in pixels ([`SvoImage::largest_voxel_px`]).
    pub largest_voxel_px: f64,
    /// The part of `nodes_per_ray` the tiles' start walks took (the nodes their frusta met,
    /// per ray of the image).
    pub beam_nodes_per_ray: f64,
    /// Rays of the tiled path that started at the skip node: their tile found no start (a
    /// walk cut short, or a degenerate frustum), or their start point was within a rounding
    /// margin of a leaf's face at the start distance and at both earlier tries.
    pub rays_from_skip: u64,
    /// Pixels that took the hit of the lattice rays around them instead of casting a ray
    /// ([`crate::fill`]; not counted in `rays`).
    pub filled: u64,
}

/// Resident set size of this process in bytes (Linux), or 0.
pub fn resident_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<u64>().ok())
        .map(|pages| pages * 4096)
        .unwrap_or(0)
}

/// What a frame past f64 needs beyond its [`Camera`]: the eye is `cam.eye + eye_lo` (a
/// double-double position), and `scale` is the distance to what the view looks at (world
/// units; it places the anchor and sets the reach of ambient occlusion). Past zoom ~1e16 the
/// eye and its target are the same f64 point, so a deep camera looks along the zoom's
/// direction at a target one unit away and carries the true distance here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeepEye {
    /// Trailing part of the eye position (below an ulp of `cam.eye`).
    pub eye_lo: DVec3,
    /// Distance from the eye to what it looks at, world units.
    pub scale: f64,
}

impl DeepEye {
    /// An ordinary camera: no trailing part, the distance to its target.
    pub fn of(cam: &Camera) -> DeepEye {
        DeepEye {
            eye_lo: DVec3::ZERO,
            scale: (cam.target - cam.eye).length(),
        }
    }
}

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

/// Per-pixel buffers a render fills, kept between frames. Allocated afresh, a 640x480
/// frame's 3 MB came as new zeroed pages from the kernel every frame, about 650 page faults
/// a frame (2.4 s of system time in a 1000-frame zoom's 36 s).
#[derive(Default)]
struct FrameBuffers {
    /// Colour and depth of a returned image handed back by [`OctreeView::recycle`].
    image: Option<(Vec<u32>, Vec<f32>)>,
    /// Each pixel's smoothing half-width.
    half: Vec<u8>,
    /// Pixels marked not yet settled.
    marks: Vec<u8>,
}

/// `v` holding `n` zeros, reusing its allocation.
fn zeroed<T: Copy + Default>(mut v: Vec<T>, n: usize) -> Vec<T> {
    v.clear();
    v.resize(n, T::default());
    v
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

    /// The current skip node and its box.
    pub fn skip(&self) -> Option<(u32, BoxU)> {
        self.skip
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

    /// Brings the skip node up to date for an eye at `o` (local units): stays if still valid,
    /// else follows the link through the face the eye crossed, else descends from the root.
    pub fn update_skip(&mut self, o: [f64; 3]) {
        let tree = &self.tree;
        if !tree.root_box().contains(o) {
            self.skip = None;
            return;
        }
        let descend = |mut id: u32, mut b: BoxU| {
            while !tree.nodes[id as usize].is_leaf() {
                let oc = b.octant_of(o);
                id = tree.nodes[id as usize].children + oc as u32;
                b = b.child(oc);
            }
            (id, b)
        };
        if let Some((id, b)) = self.skip
            && !tree.nodes[id as usize].is_free()
            && tree.nodes[id as usize].depth == b.depth
        {
            if b.contains(o) {
                self.skip = Some(descend(id, b));
                return;
            }
            // The face the eye left through: the axis of largest excursion.
            let s = b.dim();
            let mut best = (0.0, 0);
            for a in 0..3 {
                let ex = (b.min[a] - o[a]).max(o[a] - (b.min[a] + s));
                let f = 2 * a + (o[a] >= b.min[a] + s) as usize;
                if ex > best.0 {
                    best = (ex, f);
                }
            }
            let nb = tree.nodes[id as usize].link(best.1);
            if nb != NONE {
                let nbb = tree
                    .anchor
                    .snap(&b.across(best.1), tree.nodes[nb as usize].depth);
                if nbb.contains(o) {
                    self.skip = Some(descend(nb, nbb));
                    return;
                }
            }
        }
        self.skip = tree.locate(o);
    }

    /// The eye never sits inside the surface, but it can sit inside a coarse full voxel that
    /// the zoom has not refined yet: every ray would then stop at distance 0, nothing else
    /// would be visited, and unification would unload the whole view. Subdivide the eye's
    /// leaf (synchronously, it is one leaf per level) until it is empty or at the depth limit.
    fn clear_eye(&mut self, o: [f64; 3]) {
        let mut ev = Probe::new();
        while let Some((id, b)) = self.skip {
            let n = &self.tree.nodes[id as usize];
            if n.is_empty() || !n.is_leaf() || b.depth >= self.tree.depth_limit() {
                return;
            }
            let r = eval_children(&self.shader, &self.tree, &mut ev, (id, b), 0.0);
            if apply(&mut self.tree, &r) == Outcome::NoMemory {
                return;
            }
            self.tree.commit_frees();
            self.skip = self.tree.locate(o);
        }
    }

    /// The eye in root units as double-double, from its world position `eye + eye_lo`.
    fn eye_root_units(&self, eye: DVec3, eye_lo: DVec3) -> [Dd; 3] {
        let (m, s) = (self.tree.root_min, Dd::from(self.tree.root_size));
        [0, 1, 2].map(|a| (Dd::new(eye[a], eye_lo[a]) - Dd::from(m[a])) / s)
    }

    /// Moves the anchor (the lattice point box coordinates are measured from) with the eye:
    /// [`ANCHOR_LEVELS_ABOVE`] levels above the depth whose cells are the size of the eye's
    /// distance to its target, so every box a ray meets near the eye is a small exact dyadic
    /// (see [`crate::octree`]). It stays where it is while that depth changes by less than 4
    /// levels and the eye stays within its cell's neighbours; at depth 0 it is the root's
    /// corner (root units, the f64 path of shallow frames). Returns true when it moved.
    fn place_anchor(&mut self, eye_u: &[Dd; 3], scale: f64) -> bool {
        let depth_e = (self.tree.root_size / scale).log2().floor();
        let want = (depth_e - ANCHOR_LEVELS_ABOVE as f64)
            .clamp(0.0, crate::octree::MAX_ANCHOR_DEPTH as f64) as u8;
        let cur = &self.tree.anchor;
        let near = {
            let o = cur.origin();
            let unit = dim_at(cur.depth);
            (0..3).all(|a| {
                let local = ((eye_u[a] - Dd::new(o[a].0, o[a].1)).hi) / unit;
                (-1.0..2.0).contains(&local)
            })
        };
        if (want == 0 && cur.depth == 0) || (want.abs_diff(cur.depth) < 4 && near && cur.depth > 0)
        {
            return false;
        }
        self.tree.anchor = if want == 0 {
            Anchor::default()
        } else {
            Anchor::at(want, eye_u.map(|x| x.hi), eye_u.map(|x| x.lo))
        };
        self.skip = None;
        true
    }

    /// Phase 1: renders the tree as it is (read-only apart from atomics). Returns the image,
    /// the subdivision requests and (rays, hits, node steps).
    pub fn render(&mut self, cam: &Camera) -> (SvoImage, Vec<Request>, [u64; 3]) {
        self.render_deep(cam, &DeepEye::of(cam))
    }

    /// [`OctreeView::render`] for an eye known more precisely than f64 (see [`DeepEye`]).
    pub fn render_deep(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
    ) -> (SvoImage, Vec<Request>, [u64; 3]) {
        self.render_frame(cam, deep, self.drawing(), false).0
    }

    /// How a frame to be seen is drawn: its wide voxels smooth or blocky, as configured.
    fn drawing(&self) -> Drawing {
        if self.cfg.smooth {
            Drawing::Smooth
        } else {
            Drawing::Blocky
        }
    }

    /// [`OctreeView::render_deep`] for a caller that needs only the requests and counts (the
    /// settling loops): the image is dropped, so it is not drawn smooth.
    pub fn probe_deep(&mut self, cam: &Camera, deep: &DeepEye) -> (Vec<Request>, [u64; 3]) {
        let ((img, reqs, counts), _) = self.render_frame(cam, deep, Drawing::Probe, false);
        self.recycle(img);
        (reqs, counts)
    }

    /// Hands an image this view rendered back, so the next render fills its buffers
    /// instead of new ones (optional: a caller done with each frame saves every render the
    /// allocation, see [`FrameBuffers`]).
    pub fn recycle(&mut self, img: SvoImage) {
        self.buffers.image = Some((img.colour, img.depth));
    }

    /// [`OctreeView::probe_deep`] for an f64 eye.
    pub fn probe(&mut self, cam: &Camera) -> (Vec<Request>, [u64; 3]) {
        self.probe_deep(cam, &DeepEye::of(cam))
    }

    /// One probe of a settling loop at a fixed camera (subdivisions alone between its
    /// probes, `settling` kept from one probe to the next): the first casts every pixel, each
    /// later one only the pixels whose voxel could still change ([`settling_wide`]). The
    /// requests are the ones [`OctreeView::probe_deep`] would find: subdivision splits only
    /// full leaves some ray asked for and only empties space (links and starts may change,
    /// the leaf a ray meets does not), so a pixel that missed misses again, and one that
    /// stopped on a voxel no ray could ask for stops on it again. With surface planes drawn
    /// (rays pass wide leaves) every probe casts every pixel.
    pub fn probe_settling(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
        settling: &mut Settling,
    ) -> (Vec<Request>, [u64; 3]) {
        self.probe_settling_until(cam, deep, settling, &|| false)
            .unwrap_or_default()
    }

    /// True when the next probe of `settling` casts every pixel: its first, and all of them
    /// while surface planes are drawn (rays pass wide leaves, so a pixel settled at one probe
    /// may stop elsewhere at the next). Otherwise it casts the pixels the last one left
    /// pending ([`Settling::pending`]).
    fn probes_every_pixel(&self, settling: &Settling) -> bool {
        settling.pixels.is_none() || self.cfg.planes
    }

    /// [`OctreeView::probe_settling`], giving way when `stop` returns true before one of its
    /// slices of [`PROBE_SLICE`] pixels: `None`, its requests released and `settling` left
    /// without pixels (the next probe casts every pixel).
    pub fn probe_settling_until(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
        settling: &mut Settling,
        stop: &dyn Fn() -> bool,
    ) -> Option<(Vec<Request>, [u64; 3])> {
        if self.probes_every_pixel(settling) {
            if stop() {
                return None;
            }
            let ((img, reqs, counts), wide) = self.render_frame(cam, deep, Drawing::Probe, true);
            self.recycle(img);
            settling.pixels = Some(wide);
            return Some((reqs, counts));
        }
        let pixels = settling.pixels.take().unwrap_or_default();
        let (o, frame, lod) = self.begin_frame(cam, deep);
        let w = self.cfg.width as usize;
        let grid = RayGrid::new(&frame, self.cfg.width, self.cfg.height);
        let (tree, skip, trav) = (&self.tree, self.skip, self.cfg.traversal);
        let wide_at = settling_wide(lod);
        let (mut reqs, mut wide, mut counts) = (Vec::new(), Vec::new(), [0u64; 3]);
        for slice in pixels.chunks(PROBE_SLICE) {
            if stop() {
                self.release_requests(&reqs);
                return None;
            }
            let (r, wd, c) = self.pool.install(|| {
                slice
                    .par_chunks(SETTLING_CHUNK)
                    .map(|chunk| {
                        let (mut reqs, mut wide, mut c) = (Vec::new(), Vec::new(), [0u64; 3]);
                        let mut entry = None;
                        for &i in chunk {
                            let d = grid.dir(i as usize % w, i as usize / w);
                            let hit = cast(
                                tree,
                                &Ray::new(o, d.into(), lod),
                                skip,
                                &mut entry,
                                trav,
                                &mut reqs,
                            );
                            c[0] += 1;
                            c[2] += hit.steps as u64;
                            if hit.is_hit() {
                                c[1] += 1;
                                if dim_at(hit.depth) >= wide_at * hit.t {
                                    wide.push(i);
                                }
                            }
                        }
                        (reqs, wide, c)
                    })
                    .reduce(
                        || (Vec::new(), Vec::new(), [0u64; 3]),
                        |(mut ra, mut wa, ca), (rb, wb, cb)| {
                            ra.extend(rb);
                            wa.extend(wb);
                            (ra, wa, std::array::from_fn(|i| ca[i] + cb[i]))
                        },
                    )
            });
            reqs.extend(r);
            wide.extend(wd);
            counts = std::array::from_fn(|i| counts[i] + c[i]);
        }
        settling.pixels = Some(wide);
        Some((reqs, counts))
    }

    /// A frame's setup at a camera: places the anchor, the shader's origin and view, the skip
    /// node (clearing the eye's leaf), the LOD factor and the fovea. Returns the eye relative
    /// to the anchor (root units), the camera's frame and the LOD factor.
    fn begin_frame(&mut self, cam: &Camera, deep: &DeepEye) -> ([f64; 3], CameraFrame, f64) {
        let frame = cam.frame();
        let scale = deep.scale.max(1e-300);
        let eye_u = self.eye_root_units(cam.eye, deep.eye_lo);
        self.place_anchor(&eye_u, scale);
        let origin = self.tree.anchor.origin();
        // The eye relative to the anchor (root units), and the anchor's world position.
        let o: [f64; 3] =
            std::array::from_fn(|a| (eye_u[a] - Dd::new(origin[a].0, origin[a].1)).hi);
        let deep = self.tree.anchor.depth > 0;
        let world: [Dd; 3] = std::array::from_fn(|a| {
            Dd::from(self.tree.root_min[a])
                + Dd::new(origin[a].0, origin[a].1) * Dd::from(self.tree.root_size)
        });
        self.shader.origin = if deep {
            Origin {
                hi: DVec3::new(world[0].hi, world[1].hi, world[2].hi),
                lo: DVec3::new(world[0].lo, world[1].lo, world[2].lo),
                deep: true,
            }
        } else {
            Origin {
                hi: self.tree.root_min,
                lo: DVec3::ZERO,
                deep: false,
            }
        };
        self.shader.view = View {
            eye: self.tree.local_world(o),
            scale,
        };
        self.update_skip(o);
        self.clear_eye(o);
        let (w, h) = (self.cfg.width, self.cfg.height);
        let lod = frame.pixel_angle(h) * self.cfg.fidelity;
        self.lod = lod;
        self.fovea = Fovea {
            eye: o,
            forward: frame.forward,
            tan_half_fov: frame.tan_half_fov,
            aspect: w as f64 / h as f64,
            weight: self.cfg.fovea,
        };
        (o, frame, lod)
    }

    /// The render, its wide voxels drawn as `drawing` says (a probe's image is not
    /// smoothed). When `marking`, it also returns the pixels not yet settled, for the next
    /// [`OctreeView::probe_settling`] (else an empty list).
    fn render_frame(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
        drawing: Drawing,
        marking: bool,
    ) -> ((SvoImage, Vec<Request>, [u64; 3]), Vec<u32>) {
        let (o, frame, lod) = self.begin_frame(cam, deep);
        let (w, h) = (self.cfg.width, self.cfg.height);
        let n = (w * h) as usize;
        let (colour, depth) = self.buffers.image.take().unwrap_or_default();
        let (mut colour, mut depth) = (zeroed(colour, n), zeroed(depth, n));
        // Each pixel's box half-width for `Smoother::smooth` (0: keep the pixel).
        let mut half = zeroed(std::mem::take(&mut self.buffers.half), n);
        let tree = &self.tree;
        let skip = self.skip;
        let trav = self.cfg.traversal;
        let sky = self.sky;
        let size = tree.root_size;
        let pa = frame.pixel_angle(h);
        let grid = RayGrid::new(&frame, w, h);
        let reach = self.reach;
        let beam = self.cfg.beam as usize;
        // Tile starts serve the neighbour traversal; from outside the root, while they pay.
        let tiling = beam > 0 && trav == Traversal::Neighbour;
        let beams = tiling && (skip.is_some() || self.outside_tiles.allows());
        // A hit's voxel is smoothed when its side over its distance reaches this (never when
        // the image is not smoothed: no box widths are worked out).
        let wide = match drawing {
            Drawing::Smooth => smooth::MIN_WIDE_PX * pa,
            Drawing::Blocky | Drawing::Probe => f64::INFINITY,
        };
        // A pixel is marked not yet settled when its voxel's side over its distance reaches
        // this (for a settling loop's next probe, [`OctreeView::probe_settling`]).
        let unsettled = if marking {
            settling_wide(lod)
        } else {
            f64::INFINITY
        };
        // A pixel between lattice rays that met one voxel at least this wide (side over
        // distance) takes their hit ([`crate::fill`]); never in a probe.
        let fill_wide = match drawing {
            Drawing::Smooth | Drawing::Blocky if self.cfg.fill_px > 0.0 => self.cfg.fill_px * pa,
            _ => f64::INFINITY,
        };
        let rule = match drawing {
            Drawing::Smooth => fill::Rule::Blended,
            _ => fill::Rule::Shared,
        };
        let mut marks = zeroed(std::mem::take(&mut self.buffers.marks), n);
        // One pixel: its hit (or sky) into the row, the counts and the largest voxel (as the
        // largest side over distance, compared by cross-multiplying: no division per pixel).
        // Counts: rays cast, their hits, their steps, tile walks' steps, rays from the skip
        // node, pixels filled without a ray (`filled`: [`crate::fill::shared`]).
        let put = |x: usize,
                   d: DVec3,
                   hit: Hit,
                   row: &mut PixelRow,
                   c: &mut [u64; 6],
                   largest: &mut f64,
                   filled: bool| {
            c[0] += u64::from(!filled);
            c[5] += u64::from(filled);
            c[2] += hit.steps as u64;
            if hit.is_hit() {
                c[1] += u64::from(!filled);
                let side = dim_at(hit.depth);
                if side > *largest * hit.t {
                    *largest = side / hit.t;
                }
                if side >= wide * hit.t {
                    row.half[x] = smooth::half_width(side / (hit.t * pa));
                }
                if side >= unsettled * hit.t {
                    row.marks[x] = 1;
                }
                row.colour[x] = hit.colour;
                row.depth[x] = (hit.drawn * size) as f32;
            } else {
                row.colour[x] = sky_colour(&frame, d, sky);
                row.depth[x] = f32::INFINITY;
            }
        };
        let reduce = |(mut ra, ca, la): (Vec<Request>, [u64; 6], f64),
                      (rb, cb, lb): (Vec<Request>, [u64; 6], f64)| {
            ra.extend(rb);
            (ra, std::array::from_fn(|i| ca[i] + cb[i]), la.max(lb))
        };
        let tiles = TileDrawing {
            grid: &grid,
            o,
            lod,
            rule,
            wide: fill_wide,
        };
        let pixels = (
            &mut colour[..],
            &mut depth[..],
            &mut half[..],
            &mut marks[..],
        );
        let (reqs, counts, largest) = self.pool.install(|| {
            if beams {
                // Bands of `beam` rows, each cut into `beam`-wide tiles: a walk of the nodes
                // each tile's frustum meets finds where all its rays can start
                // (`frustum::tile_start`), its quadrants refine that start down to the finest
                // tiles, then each finest tile's rays are cast, each from the tile's start
                // (or from the skip node when its start point is too near a face).
                // The tiles' corner rays, one at a time.
                let ray = |x: usize, y: usize| {
                    let d = grid.dir(x, y);
                    Ray::new(o, [d.x, d.y, d.z], lod)
                };
                // The finest tiles: halve `beam` while it is even and the halves are at least
                // `beam_min` wide (so the finest tiles tile the image on a grid of their side).
                let mut fine = beam;
                while fine.is_multiple_of(2) && fine / 2 >= self.cfg.beam_min as usize {
                    fine /= 2;
                }
                // With the eye outside the root the walks start at the root (no ray stops
                // outside it).
                let from = match skip {
                    Some(skip) => walk_root(tree, skip, o, reach),
                    None => (0, tree.root_box()),
                };
                bands(pixels, w as usize, beam)
                    .enumerate()
                    .map(|(k, mut band)| {
                        let mut reqs = Vec::new();
                        let mut c = [0u64; 6];
                        let mut largest = 0f64;
                        let y0 = k * beam;
                        let y1 = y0 + band.rows() - 1;
                        let mut starts = FineStarts::new(w as usize, y0, y1, fine);
                        let last = (w as usize - 1, y1);
                        let mut stack = TileStack::new();
                        // Where the previous ray started from the eye entered the root.
                        let mut entry = None;
                        for x0 in (0..w as usize).step_by(beam) {
                            let tile = (x0, y0, beam);
                            let n = refine_tile(
                                tree,
                                &ray,
                                tile,
                                last,
                                from,
                                None,
                                &mut starts,
                                &mut stack,
                            );
                            c[2] += n;
                            c[3] += n;
                        }
                        let mut path = StartPath::default();
                        let mut scratch = TileScratch::default();
                        // A finest tile at a time, row by row inside it (or its lattice first,
                        // `crate::fill`): its rays share a start, so each keeps the previous
                        // ray's descent path (`StartPath`); cast row by row across the band,
                        // every `fine`th ray began a fresh descent at a tile boundary.
                        let mut from_skip = 0;
                        for x0 in (0..w as usize).step_by(fine) {
                            tiles.draw(
                                &mut band,
                                (x0, y0, fine),
                                &mut scratch,
                                |x, y, r| {
                                    starts
                                        .at(x, y)
                                        .and_then(|s| cast_at(tree, r, &s, &mut path, &mut reqs))
                                        .unwrap_or_else(|| {
                                            from_skip += 1;
                                            cast_neighbour(tree, r, skip, &mut entry, &mut reqs)
                                        })
                                },
                                |x, d, hit, row, filled| {
                                    put(x, d, hit, row, &mut c, &mut largest, filled)
                                },
                            );
                        }
                        c[4] += from_skip;
                        (reqs, c, largest)
                    })
                    .reduce(|| (Vec::new(), [0u64; 6], 0f64), reduce)
            } else {
                // Without tile starts: bands of rows cast left to right, or, when pixels are
                // filled, cut into tiles of `fill::TILE` pixels.
                let (side, across) = if tiles.fills() {
                    (fill::TILE, fill::TILE)
                } else {
                    (1, w as usize)
                };
                bands(pixels, w as usize, side)
                    .enumerate()
                    .map(|(k, mut band)| {
                        let mut reqs = Vec::new();
                        let mut c = [0u64; 6];
                        let mut largest = 0f64;
                        // Where the previous ray of this band entered the root (eye outside).
                        let mut entry = None;
                        let mut scratch = TileScratch::default();
                        for x0 in (0..w as usize).step_by(across) {
                            tiles.draw(
                                &mut band,
                                (x0, k * side, across),
                                &mut scratch,
                                |_, _, r| cast(tree, r, skip, &mut entry, trav, &mut reqs),
                                |x, d, hit, row, filled| {
                                    put(x, d, hit, row, &mut c, &mut largest, filled)
                                },
                            );
                        }
                        (reqs, c, largest)
                    })
                    .reduce(|| (Vec::new(), [0u64; 6], 0f64), reduce)
            }
        });
        self.beam_steps = counts[3];
        self.rays_from_skip = counts[4];
        self.filled = counts[5];
        if tiling && skip.is_none() {
            // Steps per ray cast, a tile walk's node visits counted twice (a visit tests a box
            // against the tile's frustum, more than a ray's step costs). Per ray, not per
            // pixel: counted per pixel, the pixels tiled renders fill (`crate::fill`) chose
            // tiles for the last fifth of the Menger zoom to 1e15, whose renders then took
            // 19.4 and 20.8 ms a frame (medians of 100 frames) against 17.8 and 16.5 without.
            let cost = (counts[2] + counts[3]) as f64 / counts[0].max(1) as f64;
            self.outside_tiles.record(beams, cost);
        }
        self.reach = median_hit(&depth, size);
        let marked = if marking {
            let marked = marks.iter().enumerate().filter(|&(_, &m)| m > 0);
            marked.map(|(i, _)| i as u32).collect()
        } else {
            Vec::new()
        };
        // (Only a smoothed drawing has a finite width: a ray met at distance 0 makes
        // `largest` infinite.)
        if wide.is_finite() && largest >= wide {
            self.pool.install(|| {
                self.smoother
                    .smooth(&mut colour, &half, w as usize, h as usize);
            });
        }
        self.buffers.half = half;
        self.buffers.marks = marks;
        let counts = [counts[0], counts[1], counts[2]];
        let img = SvoImage {
            width: w,
            height: h,
            colour,
            depth,
            largest_voxel_px: (largest / pa).min(MAX_VOXEL_PX),
        };
        ((img, reqs, counts), marked)
    }

    /// Phase 2: subdivides requested leaves in [`RequestQueue`] order (largest on screen
    /// first, nearer the centre counted larger) within the time budget. Returns
    /// (split, emptied, no-memory).
    pub fn subdivide(&mut self, reqs: Vec<Request>, budget_ms: f64) -> [u64; 3] {
        self.subdivide_until(reqs, budget_ms, &|| false)
    }

    /// [`OctreeView::subdivide`], stopping early at the first batch after `stop` returns true
    /// (a window's view moved on: a still view's long budget gives way within a batch).
    pub fn subdivide_until(
        &mut self,
        reqs: Vec<Request>,
        budget_ms: f64,
        stop: &dyn Fn() -> bool,
    ) -> [u64; 3] {
        let floor = self.cfg.min_subdivisions;
        self.subdivide_within(reqs, budget_ms, floor, stop)
    }

    /// [`OctreeView::subdivide_until`] with `floor` for the subdivisions done whatever the
    /// time ([`OctreeViewConfig::min_subdivisions`]).
    fn subdivide_within(
        &mut self,
        reqs: Vec<Request>,
        budget_ms: f64,
        floor: usize,
        stop: &dyn Fn() -> bool,
    ) -> [u64; 3] {
        let t0 = Instant::now();
        let fovea = self.fovea;
        let mut reqs = self.pool.install(|| RequestQueue::new(reqs, &fovea));
        let mut out = [0u64; 3];
        let mut next = 0;

        // The floor is a cost, not a count: a deep frame's subdivisions evaluate in
        // double-double, ~5x the f64 time, and a floor of 256 of them would take ~80 ms.
        let weight = if self.tree.anchor.depth > 0 {
            DEEP_COST
        } else {
            1
        };
        // Batches of 64 f64 subdivisions' worth per thread, so the time check comes as often.
        let batch = (64 / weight).max(1) * self.cfg.threads.max(1);
        let mut done_min = 0;
        // Wall time one subdivision took in the batches so far (all threads, linking included).
        let mut per_sub_ms: Option<f64> = None;
        while next < reqs.len() {
            let elapsed = t0.elapsed().as_secs_f64() * 1e3;
            if (done_min >= floor && elapsed >= budget_ms) || stop() {
                break;
            }
            if self.tree.is_full() {
                break;
            }
            // Below the floor, no more than it still needs: a whole batch of double-double
            // subdivisions past it (72 where 52 reach it) took deep frames to 15-19 ms.
            // Past it, no more than the time left is expected to hold (at least one per
            // thread): whole batches ran a Menger zoom's 12 ms budget to 14 ms a frame.
            let size = if done_min < floor {
                batch.min((floor - done_min).div_ceil(weight))
            } else if let Some(c) = per_sub_ms {
                let fit = ((budget_ms - elapsed) / c).floor();
                if fit < 1.0 {
                    break;
                }
                batch.min((fit as usize).max(self.cfg.threads.max(1)))
            } else {
                batch
            };
            let end = (next + size).min(reqs.len());
            // Taken before the batch's clock starts: a sort past the first selection is not
            // a split's time.
            let chunk = self.pool.install(|| reqs.take(next, end));
            let tb = Instant::now();
            let tree = &self.tree;
            let sh = &self.shader;
            let lod = self.lod;
            let results: Vec<Children> = self.pool.install(|| {
                chunk
                    .par_iter()
                    .map_init(Probe::new, |ev, r| {
                        eval_children(sh, tree, ev, (r.id, r.b), r.t * lod)
                    })
                    .collect()
            });
            for r in &results {
                match apply(&mut self.tree, r) {
                    Outcome::Split => out[0] += 1,
                    Outcome::Emptied => out[1] += 1,
                    Outcome::NoMemory => out[2] += 1,
                    Outcome::Stale => {}
                }
            }
            done_min += chunk.len() * weight;
            per_sub_ms = Some(tb.elapsed().as_secs_f64() * 1e3 / chunk.len() as f64);
            next = end;
        }
        for r in reqs.from(next) {
            self.tree.nodes[r.id as usize].clear_flags(REQUESTED);
        }
        if next < reqs.len() && self.tree.is_full() {
            out[2] += (reqs.len() - next) as u64;
        }
        self.tree.commit_frees();
        out
    }

    /// Clears the requested flags of requests that will not be processed (after a render
    /// whose requests are dropped).
    pub fn release_requests(&self, reqs: &[Request]) {
        for r in reqs {
            self.tree.nodes[r.id as usize].clear_flags(REQUESTED);
        }
    }

    /// Phase 3: unloads every brick not visited since the last unification; returns how
    /// many. (A frame's own unification, [`OctreeView::step`], keeps bricks until they have gone
    /// unvisited [`IDLE_UNIFICATIONS`] times, unless memory runs short.)
    pub fn unify(&mut self) -> usize {
        self.unify_idle(1)
    }

    /// Unloads the bricks that have gone unvisited by `idle_limit` unifications in a row.
    fn unify_idle(&mut self, idle_limit: u8) -> usize {
        let n = unify(&mut self.tree, self.cfg.keep_levels, idle_limit);
        if let Some((id, b)) = self.skip
            && (self.tree.nodes[id as usize].is_free()
                || self.tree.nodes[id as usize].depth != b.depth)
        {
            self.skip = None;
        }
        n
    }

    /// Runs one whole frame: render, subdivide, maybe unify. Returns the image (as rendered:
    /// the tree changes only after it is complete) and the stats.
    pub fn step(&mut self, cam: &Camera) -> (SvoImage, FrameStats) {
        self.step_deep(cam, &DeepEye::of(cam))
    }

    /// [`OctreeView::step`] with an eye known more precisely than f64 (see [`DeepEye`]).
    pub fn step_deep(&mut self, cam: &Camera, deep: &DeepEye) -> (SvoImage, FrameStats) {
        self.step_deep_until(cam, deep, false, &|| false)
    }

    /// [`OctreeView::step_deep`] whose subdivision stops early once `stop` returns true
    /// ([`OctreeView::subdivide_until`]); the frame is rendered whole either way. A `still`
    /// step (a view that is not moving, the camera the same as the last step's) goes on
    /// settling within its budget once the render's requests are split: probes of the pixels
    /// the render left unsettled ([`OctreeView::probe_settling`]), and their splits, a level of
    /// detail each, so a still view settles in fewer steps.
    pub fn step_deep_until(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
        still: bool,
        stop: &dyn Fn() -> bool,
    ) -> (SvoImage, FrameStats) {
        let t0 = Instant::now();
        let ((img, reqs, c), unsettled) = self.render_frame(cam, deep, self.drawing(), still);
        let render_ms = t0.elapsed().as_secs_f64() * 1e3;
        let t1 = Instant::now();
        let nreq = reqs.len() as u64;
        let budget = self.cfg.subdivide_budget(render_ms);
        let mut sub = self.subdivide_until(reqs, budget, stop);
        if still {
            let mut settling = Settling {
                pixels: Some(unsettled),
            };
            // What a probe's ray costs, first from the render's (tile starts make those
            // cheaper), then from the last probe's.
            let mut ray_ms = render_ms / c[0].max(1) as f64;
            loop {
                let left = budget - t1.elapsed().as_secs_f64() * 1e3;
                let pending = if self.probes_every_pixel(&settling) {
                    (self.cfg.width * self.cfg.height) as usize
                } else {
                    settling.pending().unwrap_or_default()
                };
                // A round starts only when its probe is expected to fit in what is left and
                // the memory budget has room, and ends the loop when it split and emptied
                // nothing (only requests no split can serve).
                let full = self.tree.is_full();
                if full || pending as f64 * ray_ms > left || stop() {
                    break;
                }
                let tp = Instant::now();
                let Some((reqs, pc)) = self.probe_settling_until(cam, deep, &mut settling, stop)
                else {
                    break;
                };
                ray_ms = tp.elapsed().as_secs_f64() * 1e3 / pc[0].max(1) as f64;
                if reqs.is_empty() {
                    break;
                }
                let left = budget - t1.elapsed().as_secs_f64() * 1e3;
                let more = self.subdivide_within(reqs, left, 0, stop);
                sub = std::array::from_fn(|i| sub[i] + more[i]);
                if more[0] + more[1] == 0 {
                    break;
                }
            }
        }
        let subdivide_ms = t1.elapsed().as_secs_f64() * 1e3;
        let t2 = Instant::now();
        let pressure = self.tree.counts().nodes as f64 > 0.9 * self.tree.max_nodes as f64;
        let unified = if pressure {
            self.unify_idle(1) as u64
        } else if self.frame % self.cfg.unify_every as u64 == self.cfg.unify_every as u64 - 1 {
            self.unify_idle(IDLE_UNIFICATIONS) as u64
        } else {
            0
        };
        let unify_ms = t2.elapsed().as_secs_f64() * 1e3;
        let counts = self.tree.counts();
        let stats = FrameStats {
            frame: self.frame,
            frame_ms: t0.elapsed().as_secs_f64() * 1e3,
            render_ms,
            subdivide_ms,
            unify_ms,
            rays: c[0],
            hits: c[1],
            nodes_per_ray: c[2] as f64 / c[0].max(1) as f64,
            requests: nreq,
            subdivisions: sub[0],
            emptied: sub[1],
            no_memory: sub[2],
            unified,
            node_count: counts.nodes as u64,
            brick_count: counts.bricks as u64,
            arena_bytes: self.tree.arena_bytes() as u64,
            resident_bytes: resident_bytes(),
            skip_depth: self.skip.map(|s| s.1.depth as i32).unwrap_or(-1),
            anchor_depth: self.tree.anchor.depth,
            largest_voxel_px: img.largest_voxel_px,
            beam_nodes_per_ray: self.beam_steps as f64 / c[0].max(1) as f64,
            rays_from_skip: self.rays_from_skip,
            filled: self.filled,
        };
        self.frame += 1;
        (img, stats)
    }

    /// Renders and subdivides at a fixed camera (eye known as [`DeepEye`]) until no leaf asks
    /// for subdivision, `max_frames` pass or `budget_ms` of wall time has passed (the last
    /// subdivision gets what is left of it); returns the frames taken. With a time budget
    /// alone, a zoom's warm start: its first frame then shows the scene, not the root cube.
    pub fn settle_deep(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
        max_frames: usize,
        budget_ms: f64,
    ) -> usize {
        let t0 = Instant::now();
        let mut settling = Settling::default();
        for i in 0..max_frames {
            let left = budget_ms - t0.elapsed().as_secs_f64() * 1e3;
            if left <= 0.0 {
                return i;
            }
            let (reqs, _) = self.probe_settling(cam, deep, &mut settling);
            if reqs.is_empty() {
                return i;
            }
            self.subdivide(reqs, left);
        }
        max_frames
    }

    /// Renders and subdivides at a fixed camera until no leaf asks for subdivision (or
    /// `max_frames` pass); returns the frames taken.
    pub fn settle(&mut self, cam: &Camera, max_frames: usize) -> usize {
        self.settle_deep(cam, &DeepEye::of(cam), max_frames, f64::INFINITY)
    }
}

/// Which pixels the next probe of a settling loop casts ([`OctreeView::probe_settling`]). Keep
/// one per loop at one camera; a fresh one casts every pixel.
#[derive(Clone, Debug, Default)]
pub struct Settling {
    /// The pixels (`y * width + x`) whose voxel was wider than their footprint at the last
    /// probe; `None` before the first.
    pixels: Option<Vec<u32>>,
}

impl Settling {
    /// Pixels still on voxels wider than their footprint at the last probe (`None` before
    /// the first): they only ever leave, so `width * height` minus this is a settling loop's
    /// progress.
    pub fn pending(&self) -> Option<usize> {
        self.pixels.as_ref().map(Vec::len)
    }
}

/// The LOD factor past which a settling probe counts a pixel's voxel as one that may still
/// change: its side over its distance reaches `lod / (1 + 2 lod)`, not `lod`. A voxel no
/// wider than this pixel's footprint can still be asked for by a ray that meets it nearer, up
/// to its diagonal (`sqrt 3` sides) nearer; split, it may turn out empty, and this pixel's ray
/// would then go on past it.
fn settling_wide(lod: f64) -> f64 {
    lod / (1.0 + 2.0 * lod)
}

/// Pixels a worker casts at a time in a settling probe (a unit of rayon's work sharing).
const SETTLING_CHUNK: usize = 256;

/// Pixels a settling probe casts between its checks of a stop
/// ([`OctreeView::probe_settling_until`]): a tenth of a 640x480 frame's rays.
pub const PROBE_SLICE: usize = 1 << 15;

/// How a frame is drawn: its wide voxels smoothed or as blocks, or only probed for the
/// requests (no image wanted, wide voxels marked).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Drawing {
    Smooth,
    Blocky,
    Probe,
}

/// A frame's unification unloads a brick once this many unifications in a row found it
/// unvisited (16 frames at the default period of 4; see [`crate::evict::unify`]).
pub const IDLE_UNIFICATIONS: u8 = 4;

/// What one subdivision on a deep frame (double-double evaluation) counts towards
/// [`OctreeViewConfig::min_subdivisions`]: `fathom bench eval` measures double-double evaluation
/// at 3.9-6.5x f64 for the fractal presets (5.8 Menger, 5.5 Mandelbulb).
pub const DEEP_COST: usize = 5;

/// How many levels above the eye's scale the anchor sits (see `OctreeView::place_anchor`): the
/// voxels the eye needs lie about 10 levels below that scale at 640x480, so boxes near the eye
/// reach about 46 levels below the anchor, within its exact span of 48
/// ([`crate::octree::ANCHOR_SPAN`]). Until the eye's scale is 37 levels below the root the
/// anchor is the root's corner and frames are evaluated in f64 exactly as before.
pub const ANCHOR_LEVELS_ABOVE: u8 = 36;

/// The median hit distance (root units) of a sample of a frame's pixels (`depth` in world
/// units, infinite for a miss; `size` the root's side), infinite when none hit.
/// One row of a frame's per-pixel buffers, as a render fills it.
struct PixelRow<'a> {
    colour: &'a mut [u32],
    depth: &'a mut [f32],
    /// Box half-widths for [`Smoother::smooth`] (0: keep the pixel).
    half: &'a mut [u8],
    /// 1: not yet settled (the next settling probe casts the pixel).
    marks: &'a mut [u8],
}

/// A band of whole rows of a frame's per-pixel buffers, `width` pixels a row.
struct PixelBand<'a> {
    colour: &'a mut [u32],
    depth: &'a mut [f32],
    half: &'a mut [u8],
    marks: &'a mut [u8],
    width: usize,
}

impl PixelBand<'_> {
    fn rows(&self) -> usize {
        self.colour.len() / self.width
    }

    /// The band's `j`th row.
    fn row(&mut self, j: usize) -> PixelRow<'_> {
        let r = j * self.width..(j + 1) * self.width;
        PixelRow {
            colour: &mut self.colour[r.clone()],
            depth: &mut self.depth[r.clone()],
            half: &mut self.half[r.clone()],
            marks: &mut self.marks[r],
        }
    }
}

/// `rows`-row bands of a frame's per-pixel buffers (colour, depth, smoothing half-widths and
/// marks), `width` pixels a row, for the threads.
fn bands<'a>(
    (colour, depth, half, marks): (&'a mut [u32], &'a mut [f32], &'a mut [u8], &'a mut [u8]),
    width: usize,
    rows: usize,
) -> impl IndexedParallelIterator<Item = PixelBand<'a>> {
    let n = rows * width;
    colour
        .par_chunks_mut(n)
        .zip(depth.par_chunks_mut(n))
        .zip(half.par_chunks_mut(n))
        .zip(marks.par_chunks_mut(n))
        .map(move |(((colour, depth), half), marks)| PixelBand {
            colour,
            depth,
            half,
            marks,
            width,
        })
}

/// How a render draws a tile of pixels: its rays' directions and origin, and the rule that
/// fills pixels between lattice rays ([`crate::fill`]; `wide` infinite: every pixel cast).
struct TileDrawing<'a> {
    grid: &'a RayGrid,
    o: [f64; 3],
    lod: f64,
    rule: fill::Rule,
    wide: f64,
}

/// A thread's scratch for [`TileDrawing::draw`], kept across its tiles.
#[derive(Default)]
struct TileScratch {
    span: RaySpan,
    /// The hits of a tile's lattice rays.
    lattice: Vec<Hit>,
}

impl TileDrawing<'_> {
    /// Whether pixels between lattice rays may be filled.
    fn fills(&self) -> bool {
        self.wide.is_finite()
    }

    /// Draws columns `x0..x0 + n` (fewer at the right edge) of every row of `band`, which
    /// holds the frame's rows from `y0`: each pixel's hit is its ray's, `cast(x, y, ray)`,
    /// or, when the tile fills and is at most [`SPAN`] wide, filled from the lattice rays
    /// around it; `put(x, d, hit, row, filled)` writes it.
    #[inline(always)]
    fn draw(
        &self,
        band: &mut PixelBand,
        (x0, y0, n): (usize, usize, usize),
        s: &mut TileScratch,
        mut cast: impl FnMut(usize, usize, &Ray) -> Hit,
        mut put: impl FnMut(usize, DVec3, Hit, &mut PixelRow, bool),
    ) {
        let n = n.min(band.width - x0);
        let rows = band.rows();
        if self.fills() && n <= SPAN {
            let mut at = usize::MAX;
            fill::tile(
                &mut s.lattice,
                n,
                rows,
                self.rule,
                self.wide,
                |j, i, filled| {
                    let y = y0 + j;
                    if j != at {
                        self.grid.span(y, x0, n, &mut s.span);
                        at = j;
                    }
                    let x = x0 + i;
                    let hit =
                        filled.unwrap_or_else(|| cast(x, y, &s.span.ray(i, self.o, self.lod)));
                    put(x, s.span.dir(i), hit, &mut band.row(j), filled.is_some());
                    hit
                },
            );
            return;
        }
        for j in 0..rows {
            let y = y0 + j;
            let mut row = band.row(j);
            self.grid
                .segment(y, x0, n, self.o, self.lod, &mut s.span, |x, d, r| {
                    let hit = cast(x, y, r);
                    put(x, d, hit, &mut row, false);
                });
        }
    }
}

fn median_hit(depth: &[f32], size: f64) -> f64 {
    let mut t: Vec<f32> = depth
        .iter()
        .step_by(61)
        .copied()
        .filter(|d| d.is_finite())
        .collect();
    if t.is_empty() {
        return f64::INFINITY;
    }
    let k = t.len() / 2;
    let (_, m, _) = t.select_nth_unstable_by(k, f32::total_cmp);
    *m as f64 / size
}

/// The starts of one band's finest tiles (side `side` pixels, row-major, `cols` a row; the
/// band's first pixel row is `y0`); `None` where a tile has no start (its rays start at the
/// skip node).
struct FineStarts {
    y0: usize,
    cols: usize,
    side: usize,
    starts: Vec<Option<TileStart>>,
}

impl FineStarts {
    /// Tiles of side `side` over a band `width` pixels wide, rows `y0..=y1`, without starts.
    fn new(width: usize, y0: usize, y1: usize, side: usize) -> FineStarts {
        let cols = width.div_ceil(side);
        FineStarts {
            y0,
            cols,
            side,
            starts: vec![None; cols * (y1 + 1 - y0).div_ceil(side)],
        }
    }

    /// The start of the finest tile holding pixel `(x, y)`.
    fn at(&mut self, x: usize, y: usize) -> &mut Option<TileStart> {
        &mut self.starts[(y - self.y0) / self.side * self.cols + x / self.side]
    }
}

/// Finds the start of the tile `(x0, y0, side)` (clipped to the last pixel `last`) by a walk
/// of the nodes its frustum meets, seeded by its parent's start `parent` (without one, by the
/// node `from` holding the eye),
/// and recursively its quadrants' from it down to the finest side, whose starts go into `out`.
/// A tile without a start of its own keeps its parent's (valid for all the parent's rays).
/// Returns the nodes the walks visited.
#[allow(clippy::too_many_arguments)]
fn refine_tile(
    tree: &Octree,
    ray: &impl Fn(usize, usize) -> Ray,
    (x0, y0, side): (usize, usize, usize),
    last: (usize, usize),
    from: (u32, BoxU),
    parent: Option<TileStart>,
    out: &mut FineStarts,
    stack: &mut TileStack,
) -> u64 {
    let (x1, y1) = ((x0 + side - 1).min(last.0), (y0 + side - 1).min(last.1));
    let corners = [ray(x0, y0), ray(x1, y0), ray(x0, y1), ray(x1, y1)];
    let seed = match parent {
        None => Some(Seed::at_eye(&corners, from)),
        Some(p) => Seed::within(tree, &corners, &p),
    };
    let (s, n) = match seed {
        Some(sd) => tile_start(tree, &corners, &sd, stack),
        None => (None, 0),
    };
    let s = s.or(parent);
    let mut n = n as u64;
    if side <= out.side {
        *out.at(x0, y0) = s;
        return n;
    }
    let half = side / 2;
    for (dx, dy) in [(0, 0), (half, 0), (0, half), (half, half)] {
        let (qx, qy) = (x0 + dx, y0 + dy);
        if qx <= last.0 && qy <= last.1 {
            n += refine_tile(tree, ray, (qx, qy, half), last, from, s, out, stack);
        }
    }
    n
}

/// Default subdivision time per frame ([`OctreeViewConfig::subdivide_ms`]), in milliseconds.
/// 12 until 2026-12-03, when the colouring's normal and occlusion samples began to be
/// evaluated four f64 lanes at a time: at 8 ms the 300-frame zooms to 1e15 split about as
/// many leaves a frame as they did at 12 (Menger 360-522 against 317-456, Mandelbulb 223-309
/// against 231-289, five interleaved pairs) and the saving goes to the frame rate. 8 until
/// 2026-12-05, when the full children's line-of-sight traces began to run four lanes at a
/// time: at 7 ms the 1000-frame Mandelbulb zoom splits 270-276 leaves a frame, as it did at
/// 8 (`--subdivide-ms 8` now splits 315-317, for an image similarity within 0.01 of 7's). 7
/// until 2026-12-05 (stop 36), when a wide full child whose line of sight passes it began to
/// be tested one level down before its line is traced on: at 6 ms the 1000-frame Mandelbulb
/// zoom splits 312-341 leaves a frame, as it did at 7 (308-346), for 0.5-1.2 more frames a
/// second (three interleaved pairs); kept at 7, the finer tree rendered 0.8-3.0 fps slower
/// in four of five pairs. The Menger's splits cost what they did, so it splits a sixth fewer
/// (641-678 against 769-796 on a 400-frame zoom to 1e6, SSIM 0.00-0.03 lower). 6 until
/// 2026-12-06 (stop 37), when requests began to be served nearer the screen's centre first
/// ([`crate::request_order::Fovea`]) and no longer all sorted: at 3 ms with the fovea the
/// 400-frame zooms to 1e6 come closer to the sphere tracer than at 6 ms without (median SSIM
/// at frames 40-360: Mandelbulb 0.217 against 0.188, Menger 0.350 against 0.284) at a frame
/// rate as high (27.9 against 25.2, 32.9 against 27.0); on the 1000-frame zooms to 1e15 the
/// frame rates were within the machine's noise (four interleaved pairs each: Mandelbulb
/// 34.5, 30.6, 30.0, 33.5 against 31.6, 31.0, 31.4, 30.9; Menger 33.9, 30.5, 33.5, 33.4
/// against 34.6, 35.1, 32.3, 31.9). Kept at 6 ms, the fovea's finer centre rendered slower
/// (Mandelbulb 25.4 fps, Menger 21.8).
pub const DEFAULT_SUBDIVIDE_MS: f64 = 3.0;

/// Default tile side of the start walks ([`OctreeViewConfig::beam`]): with tiles of 16 the
/// Mandelbulb zoom's render took 180 ms over three checkpoint frames against 234 ms for the
/// corner-ray beams it replaced, 8 and 32 about the same, 4 far more (one thread,
/// `render_bench`, docs/svo.md).
pub const DEFAULT_BEAM: u32 = 16;

/// Default finest tile side ([`OctreeViewConfig::beam_min`]): the tile itself. Quadrants of 8
/// walking again from the tile's start took the steps per ray from 9.4 to 7.9 in the same
/// render time (the walks' own visits cost more than ray steps).
pub const DEFAULT_BEAM_MIN: u32 = 16;

/// Renders without tile starts after a render with the eye outside the root in which tiles
/// cost more steps a ray than the last render without them ([`OutsideTiles`]). From outside,
/// a tile's rays only start inside the root: where stops lie at the root's faces (the Menger
/// zoom looks into the root's corner, whose faces are the sponge's) their start points
/// straddle the faces and most rays fall back, the walks wasted (4 % of the render); the
/// Mandelbulb's first frames, seen from outside, take 15-23 steps a ray without them and 13
/// or fewer with them. Until 2026-12-05 the pause followed any frame in which most rays fell
/// back, which paused the Mandelbulb's first 16 frames too: most of its fallbacks are sky.
pub const OUTSIDE_TILES_PAUSE: u64 = 16;

/// The choice, while the eye is outside the root, between tile starts and none, by the steps
/// a ray took in recent renders of each kind. A render with tiles is compared with the last
/// one without: costlier, and tiles pause for [`OUTSIDE_TILES_PAUSE`] renders; with no
/// comparison from the last `4 * OUTSIDE_TILES_PAUSE` renders, the next render goes without
/// tiles to measure one, and tiles pause if it was the cheaper. (That measuring render costs:
/// the Mandelbulb's 34th frame took 87-110 ms without tiles against 40-57 with them, so the
/// comparison is renewed rarely.) It counts renders with the eye outside, not frames: a warm
/// start or a settle renders many times at one frame.
#[derive(Clone, Copy, Debug, Default)]
struct OutsideTiles {
    /// Renders with the eye outside the root recorded so far (the index of the next). Those
    /// with the eye inside are not counted: the measuring render is the next one outside.
    render: u64,
    /// First render that may use tiles.
    from: u64,
    /// Steps a ray of the last render with tiles.
    tiled: f64,
    /// Steps a ray of the last render without, and its index.
    untiled: Option<(f64, u64)>,
    /// The next render goes without tiles to compare.
    probing: bool,
}

impl OutsideTiles {
    /// Whether the next render with the eye outside the root may use tiles.
    fn allows(&self) -> bool {
        self.render >= self.from
    }

    /// Records a render's steps a ray, `cost`, with tiles or without (`tiled`).
    fn record(&mut self, tiled: bool, cost: f64) {
        let r = self.render;
        self.render += 1;
        if tiled {
            self.tiled = cost;
            match self.untiled {
                Some((u, at)) if r < at + 4 * OUTSIDE_TILES_PAUSE => {
                    if cost > u {
                        self.from = r + 1 + OUTSIDE_TILES_PAUSE;
                    }
                }
                _ => {
                    self.from = r + 2;
                    self.probing = true;
                }
            }
        } else {
            self.untiled = Some((cost, r));
            if std::mem::take(&mut self.probing) && cost < self.tiled {
                self.from = r + 1 + OUTSIDE_TILES_PAUSE;
            }
        }
    }
}

/// Voxels seen from closer than this many pixel footprints' worth (the eye inside a full
/// voxel, `t` = 0) count as this many pixels: keeps the figure finite for JSON.
pub const MAX_VOXEL_PX: f64 = 1e6;

fn cast(
    tree: &Octree,
    ray: &Ray,
    skip: Option<(u32, BoxU)>,
    entry: &mut Option<(u32, BoxU)>,
    trav: Traversal,
    reqs: &mut Vec<Request>,
) -> Hit {
    match trav {
        Traversal::Neighbour => cast_neighbour(tree, ray, skip, entry, reqs),
        Traversal::KdRestart => cast_kdrestart(tree, ray, skip.is_some(), reqs),
    }
}

/// The sphere tracer's sky (`fathom_trace::shade::Shading::sky`): a gradient on the square
/// root of the direction's height, so octree and tracer frames agree off the surface.
fn sky_colour(frame: &CameraFrame, d: DVec3, sky: ([f64; 3], [f64; 3])) -> u32 {
    let k = d.y.clamp(0.0, 1.0).sqrt();
    let _ = frame;
    pack_rgb(std::array::from_fn(|i| {
        sky.0[i] + (sky.1[i] - sky.0[i]) * k
    }))
}

#[cfg(test)]
mod outside_tiles_tests {
    use super::*;

    /// Replays costs per render (`(tiled cost, untiled cost)`, whichever the choice asks
    /// for) and returns which renders used tiles.
    fn replay(renders: u64, cost: impl Fn(u64) -> (f64, f64)) -> Vec<bool> {
        let mut o = OutsideTiles::default();
        (0..renders)
            .map(|f| {
                let tiled = o.allows();
                let (t, u) = cost(f);
                o.record(tiled, if tiled { t } else { u });
                tiled
            })
            .collect()
    }

    #[test]
    fn tiles_stay_on_where_they_save_steps_with_a_measuring_frame_now_and_then() {
        let used = replay(80, |_| (13.0, 20.0));
        let off: Vec<usize> = (0..80).filter(|&f| !used[f]).collect();
        // The first frame measures tiles, the second goes without to compare, and the
        // comparison is renewed once it is 64 frames old.
        assert_eq!(off, [1, 66]);
    }

    #[test]
    fn tiles_pause_where_they_cost_steps_and_are_tried_again_after_each_pause() {
        let used = replay(60, |_| (30.0, 20.0));
        let on: Vec<usize> = (0..60).filter(|&f| used[f]).collect();
        assert_eq!(on, [0, 18, 35, 52]);
    }

    #[test]
    fn tiles_come_back_when_the_frames_without_them_grow_costlier() {
        // Without tiles the steps grow frame by frame (the Mandelbulb's eye approaching).
        let used = replay(60, |f| (20.0, 10.0 + f as f64 * 0.5));
        assert!(!used[5], "tiles cost more at first");
        assert!(used[40..].iter().all(|&u| u), "{used:?}");
    }
}

#[cfg(test)]
mod budget_tests {
    use super::*;

    /// With a target frame rate, subdivision gets what the render left of the frame, within
    /// half and all of `subdivide_ms`; without one, always `subdivide_ms`.
    #[test]
    fn a_target_frame_rate_gives_subdivision_what_the_render_left() {
        let mut c = OctreeViewConfig {
            subdivide_ms: 8.0,
            ..OctreeViewConfig::default()
        };
        assert_eq!(c.subdivide_budget(30.0), 8.0);
        c.target_fps = 30.0;
        assert_eq!(c.subdivide_budget(10.0), 8.0);
        assert!((c.subdivide_budget(28.0) - (1e3 / 30.0 - 28.0)).abs() < 1e-12);
        assert_eq!(c.subdivide_budget(60.0), 4.0);
        assert!(c.validate().is_ok());
        for bad in [-1.0, f64::NAN, f64::INFINITY, 1001.0] {
            c.target_fps = bad;
            let e = c.validate().unwrap_err().to_string();
            assert!(e.contains("0..=1000 fps"), "{bad}: {e}");
        }
    }
}

#[cfg(test)]
mod frame_buffers_tests {
    use super::*;

    #[test]
    fn a_render_into_reused_buffers_draws_what_fresh_buffers_draw() {
        // Every pixel cast: from outside the root the second render goes without tiles to
        // compare their cost, and only tiled renders fill pixels.
        let cfg = OctreeViewConfig {
            width: 96,
            height: 72,
            threads: 2,
            fill_px: 0.0,
            ..OctreeViewConfig::default()
        };
        let mut ex = OctreeView::new(&fathom_core::scenes::menger(8), cfg).unwrap();
        let cam = Camera {
            eye: DVec3::new(1.9, 1.7, 1.5),
            target: DVec3::new(0.6, 0.5, 0.4),
            up: DVec3::Y,
            fov: 50.0,
        };
        // Few frames settled: voxels wide enough to be smoothed, so every buffer is used.
        ex.settle(&cam, 3);
        let render = |ex: &mut OctreeView| {
            let ((img, reqs, _), marked) =
                ex.render_frame(&cam, &DeepEye::of(&cam), Drawing::Smooth, true);
            ex.release_requests(&reqs);
            (img, marked)
        };
        let (fresh, marked) = render(&mut ex);
        assert!(fresh.largest_voxel_px >= 2.0, "{}", fresh.largest_voxel_px);
        assert!(
            !marked.is_empty() && marked.len() < 96 * 72,
            "{}",
            marked.len()
        );
        // Buffers full of what no render leaves: each must be cleared or overwritten.
        let n = 96 * 72;
        ex.buffers.half = vec![200; n];
        ex.buffers.marks = vec![1; n];
        ex.recycle(SvoImage {
            width: 96,
            height: 72,
            colour: vec![0x1234_5678; n],
            depth: vec![-1.0; n],
            largest_voxel_px: 0.0,
        });
        let (reused, marked_again) = render(&mut ex);
        assert!(
            reused == fresh,
            "a render into reused buffers differs from a fresh one"
        );
        assert_eq!(marked_again, marked);
    }
}

#[cfg(test)]
mod fill_tests {
    use super::*;

    fn menger_view() -> (OctreeView, Camera) {
        let cfg = OctreeViewConfig {
            width: 128,
            height: 96,
            threads: 2,
            ..OctreeViewConfig::default()
        };
        let ex = OctreeView::new(&fathom_core::scenes::menger(8), cfg).unwrap();
        let cam = Camera {
            eye: DVec3::new(1.9, 1.7, 1.5),
            target: DVec3::new(0.6, 0.5, 0.4),
            up: DVec3::Y,
            fov: 50.0,
        };
        (ex, cam)
    }

    /// The frame drawn as `drawing` with `fill_px`, with tile starts or without (`tiled`),
    /// and the pixels filled without a ray.
    fn render(
        ex: &mut OctreeView,
        cam: &Camera,
        drawing: Drawing,
        fill_px: f64,
        tiled: bool,
    ) -> (SvoImage, u64) {
        ex.cfg.fill_px = fill_px;
        // From outside the root (as here) renders may alternate to compare: fix the choice.
        ex.outside_tiles = OutsideTiles {
            from: if tiled { 0 } else { u64::MAX },
            ..OutsideTiles::default()
        };
        let ((img, reqs, counts), _) = ex.render_frame(cam, &DeepEye::of(cam), drawing, false);
        ex.release_requests(&reqs);
        assert_eq!(
            counts[0] + ex.filled,
            128 * 96,
            "every pixel cast or filled"
        );
        assert_eq!(ex.beam_steps > 0, tiled, "tile starts used");
        (img, ex.filled)
    }

    #[test]
    fn filled_pixels_show_what_their_rays_would() {
        let (mut ex, cam) = menger_view();
        // Five frames settled: voxels up to ~10 pixels wide, most narrower than 4.
        ex.settle(&cam, 5);
        let n = 128 * 96;
        let mut filled_at = Vec::new();
        // With tile starts and without (their lattices' tiles differ in general: the finest
        // tiles, or `fill::TILE` squares), filling from voxels at least 4 pixels wide or 2.
        for (tiled, px) in [(true, 4.0), (false, 4.0), (true, 2.0), (false, 2.0)] {
            // Drawn as blocks, a filled pixel takes the voxel its lattice rays all met: the
            // same colour and nearly the same depth as its own ray, but for what stands in
            // front of that voxel between rays two pixels apart (here 1 pixel of 12288 at 4
            // pixels, 8 at 2).
            let (cast, none) = render(&mut ex, &cam, Drawing::Blocky, 0.0, tiled);
            let (filled, count) = render(&mut ex, &cam, Drawing::Blocky, px, tiled);
            assert_eq!(none, 0);
            assert!(count as usize > n / 25, "{count} of {n} pixels filled");
            filled_at.push(count);
            let differ = (0..n)
                .filter(|&i| cast.colour[i] != filled.colour[i])
                .count();
            assert!(differ <= n / 200, "{differ} of {n} pixels differ");
            let far = (0..n)
                .filter(|&i| (cast.depth[i] - filled.depth[i]).abs() > 0.05 * cast.depth[i])
                .count();
            assert!(far <= n / 200, "{far} of {n} pixels have depths 5 % apart");
            // Drawn smooth, neighbouring wide voxels of one surface blend too: more pixels
            // are filled (1438 here at 4 pixels, 2992 at 2) and the smoothed frame changes by
            // a third of a level in 255 (a level at 2 pixels).
            let (cast, _) = render(&mut ex, &cam, Drawing::Smooth, 0.0, tiled);
            let (filled, more) = render(&mut ex, &cam, Drawing::Smooth, px, tiled);
            assert!(more > count, "{more} filled smooth, {count} as blocks");
            let error = (0..n)
                .map(|i| {
                    let (a, b) = (cast.colour[i].to_le_bytes(), filled.colour[i].to_le_bytes());
                    (0..3).map(|c| a[c].abs_diff(b[c]) as f64).sum::<f64>() / 3.0
                })
                .sum::<f64>()
                / n as f64;
            assert!(error < 2.0, "{px} px: mean error {error} levels of 255");
        }
        // Voxels 2 to 4 pixels wide fill too at 2 (510 pixels at 4, 854 at 2).
        assert!(filled_at[2] > filled_at[0], "{filled_at:?}");
    }

    #[test]
    fn a_settled_frame_casts_every_pixel() {
        let (mut ex, cam) = menger_view();
        ex.settle(&cam, 400);
        for tiled in [true, false] {
            let (cast, _) = render(&mut ex, &cam, Drawing::Smooth, 0.0, tiled);
            let px = fill::DEFAULT_FILL_PX;
            let (filled, count) = render(&mut ex, &cam, Drawing::Smooth, px, tiled);
            assert!(cast.largest_voxel_px < px, "{}", cast.largest_voxel_px);
            assert_eq!(count, 0);
            assert!(filled == cast);
        }
    }
}
