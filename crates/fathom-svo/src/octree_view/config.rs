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
