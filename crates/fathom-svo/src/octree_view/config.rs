//! The settings of an octree view ([`OctreeViewConfig`]), their defaults and their checks.

use crate::error::OctreeError;
use crate::request_order::DEFAULT_FOVEA;
use crate::root::RootSpec;
use serde::Serialize;

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
    /// Subdivisions done each frame whatever the time, counted in f64 evaluations' worth: on deep
    /// frames (double-double evaluation) a subdivision counts
    /// [`DEEP_COST`](crate::octree_view::DEEP_COST) times.
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
    /// (`docs/log/svo.md`, "Surface planes").
    pub planes: bool,
    /// How much nearer the screen's centre a subdivision request counts: its size on screen is
    /// divided by `1 + fovea rho^2`, `rho` its distance from the centre in half-heights
    /// ([`Fovea`](crate::request_order::Fovea); 0: the largest on screen first wherever they are),
    /// [0, 64].
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
    /// not spend the spare time refining (a finer tree makes the next frames slower to render).
    pub fn subdivide_budget(&self, render_ms: f64) -> f64 {
        if self.target_fps > 0.0 {
            (1e3 / self.target_fps - render_ms).clamp(0.5 * self.subdivide_ms, self.subdivide_ms)
        } else {
            self.subdivide_ms
        }
    }
}

/// Default subdivision time per frame ([`OctreeViewConfig::subdivide_ms`]), in milliseconds:
/// with the requests served nearer the screen's centre first ([`crate::request_order::Fovea`])
/// it refines the view as well as more time did, and leaves the frame rate to the render
/// (how it came down from 12 ms: `docs/log/svo.md`).
pub const DEFAULT_SUBDIVIDE_MS: f64 = 3.0;

/// Default tile side of the start walks ([`OctreeViewConfig::beam`]): the fastest render of the
/// sides tried (4 to 32; `docs/log/svo.md`).
pub const DEFAULT_BEAM: u32 = 16;

/// Default finest tile side ([`OctreeViewConfig::beam_min`]): the tile itself, not refined:
/// quadrants walking again save ray steps but not render time (their walks' visits cost more).
pub const DEFAULT_BEAM_MIN: u32 = 16;

#[cfg(test)]
mod tests {
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
