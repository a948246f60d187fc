//! A zoom (or tour) with the octree: the frame loop of `fathom zoom` and `fathom bench svo`.
//! Each frame takes its camera from the path, checks the precision guard (a zoom stops
//! cleanly where f64 root coordinates run out, and says so), steps the session's octree, and
//! hands the finished frame (when frames are wanted) and its statistics to the caller.

use crate::error::RenderError;
use crate::request::{Backend, RenderRequest};
use crate::session::Session;
use fathom_core::camera_path::PathPreset;
use fathom_core::frame::Frame;
use fathom_svo::stats::Summary;
use fathom_svo::{FrameStats, Traversal};
use serde::Serialize;

/// A zoom to run.
#[derive(Clone, Debug)]
pub struct Zoom {
    /// Zoom factor from the first to the last frame (ratio of eye distances), >= 1.
    pub depth: f64,
    /// Frames to render, [1, 10^7].
    pub frames: usize,
    /// Size, SSAO, threads and octree settings (the backend is the octree; the root cube
    /// comes from the path preset when it has one).
    pub request: RenderRequest,
}

/// Why a zoom was refused.
#[derive(Debug, thiserror::Error)]
pub enum ZoomError {
    #[error("--depth {0} must be a finite zoom factor >= 1")]
    Depth(f64),
    #[error("--frames {0} is out of range 1..=10000000")]
    Frames(usize),
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The frame callback failed (writing a frame, say).
    #[error("{0}")]
    Output(String),
}

/// The JSON written by `fathom zoom --stats`.
#[derive(Serialize)]
pub struct ZoomReport {
    pub preset: String,
    pub traversal: Traversal,
    pub width: u32,
    pub height: u32,
    pub depth: f64,
    pub threads: usize,
    pub fidelity: f64,
    /// Why the zoom stopped early (precision limit), if it did.
    pub stopped: Option<String>,
    pub summary: Summary,
    pub zoom: Vec<f64>,
    pub frames: Vec<FrameStats>,
}

impl Zoom {
    /// Checks the zoom's own figures (the request is checked by the session).
    pub fn validate(&self) -> Result<(), ZoomError> {
        if !(self.depth.is_finite() && self.depth >= 1.0) {
            return Err(ZoomError::Depth(self.depth));
        }
        if self.frames == 0 || self.frames > 10_000_000 {
            return Err(ZoomError::Frames(self.frames));
        }
        Ok(())
    }

    /// Runs the zoom along `preset`'s path. `on_frame(i, zoom, frame, stats)` sees every frame;
    /// `frame` is the finished image when `want_frames`, else `None`.
    pub fn run<F>(
        &self,
        preset: &PathPreset,
        want_frames: bool,
        mut on_frame: F,
    ) -> Result<ZoomReport, ZoomError>
    where
        F: FnMut(usize, f64, Option<&Frame>, &FrameStats) -> Result<(), String>,
    {
        self.validate()?;
        let mut req = self.request.clone();
        req.backend = Backend::Octree;
        if preset.cube.is_some() {
            req.octree.root = preset.cube;
        }
        let mut session = Session::new(preset.scene.clone())?;
        let mut frames = Vec::with_capacity(self.frames);
        let mut zooms = Vec::with_capacity(self.frames);
        let mut stopped = None;
        for i in 0..self.frames {
            let cam = preset.camera(i, self.frames, self.depth);
            let z = preset.path.zoom_at(i, self.frames, self.depth);
            if let (Some(target), Some(ex)) = (preset.path.target(), session.octree()) {
                let pa = cam.frame().pixel_angle(ex.cfg.height);
                let dist = (cam.eye - target).length();
                if let Err(e) = fathom_svo::precision::precision_check(
                    dist,
                    ex.tree.root_size,
                    pa,
                    ex.cfg.fidelity,
                    z,
                ) {
                    stopped = Some(e);
                    break;
                }
            }
            let (frame, st) = session.step_octree(&cam, &req, want_frames)?;
            on_frame(i, z, frame.as_ref(), &st).map_err(ZoomError::Output)?;
            frames.push(st);
            zooms.push(z);
        }
        let ex = session.octree().expect("the first frame built the octree");
        let cfg = &ex.cfg;
        let summary = Summary::new(&frames, &zooms, cfg.brick_period);
        Ok(ZoomReport {
            preset: preset.name.into(),
            traversal: cfg.traversal,
            width: cfg.width,
            height: cfg.height,
            depth: self.depth,
            threads: cfg.threads,
            fidelity: cfg.fidelity,
            stopped,
            summary,
            zoom: zooms,
            frames,
        })
    }
}
