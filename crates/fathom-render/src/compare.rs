//! How close an octree frame is to the sphere tracer's frame at the same camera: the figures
//! `fathom zoom --compare-every N` writes per frame and the still-camera tests assert.
//!
//! The figures themselves (SSIM on luminance, silhouette IoU, colour error, block
//! reduction) are [`fathom_image::compare`]'s, re-exported here.
//!
//! The reference is the CPU sphere tracer of the session with the scene's soft shadows off
//! ([`reference_scene`]): the octree bakes the tracer's shading into its voxels except shadows
//! (a shadow ray per voxel costs up to 96 distance evaluations), so what is compared is the
//! geometry and the detail that has arrived, not a lighting term the octree does not compute.
//! The tracer switches to its f64 path by itself once the pixel footprint is below 1e-5 of the
//! eye's distance from the origin (zoom past about 1e3); shallower frames are traced on its
//! f32 path, exact enough at that scale.
//!
//! **Deep frames.** That reference traces from the f64 camera, which past zoom ~1e13 cannot
//! place the eye within a pixel (and past ~1e16 rounds the eye onto its target). A zoom frame
//! whose camera is in the deep form ([`crate::zoom::ZoomPath::is_deep`]) is compared with
//! [`Reference::deep_frame`] instead: `fathom_trace::deep::deep_frame`, the tracer's shading
//! run in double-double from the frame's double-double eye with the exact target-relative
//! orientation. It costs ~450 double-double steps a pixel, so it is rendered at most
//! [`DEEP_REFERENCE_PIXELS`] pixels: the frame size divided by the smallest common divisor
//! of width and height that brings it under that ([`deep_reduction`]), and the octree frame
//! is reduced by the same factor ([`reduce`]: colour averaged over the block, a hit where at
//! least half the block hits) before the comparison. One ray at a reference pixel's centre is
//! not what a block mean shows where detail is finer than the pixel (deep Menger frames: the
//! tracer's own block means score 0.58 against its centre samples), so the zoom casts 2x2
//! rays a reference pixel by default ([`Reference::with_deep_samples`], `fathom zoom
//! --reference-samples`).

use crate::error::RenderError;
use crate::request::{Backend, RenderRequest};
use crate::session::Session;
use fathom_core::camera_path::CameraPath;
use fathom_core::frame::Frame;
use fathom_core::{Camera, Scene, Tape};
pub use fathom_image::compare::{Agreement, COLOUR_TOL, agreement, luminance, reduce, ssim};

/// The scene the reference tracer renders: `scene` with soft shadows off (see the module
/// comment).
pub fn reference_scene(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for l in &mut s.lights {
        l.shadows = false;
    }
    s
}

/// Most pixels of the double-double reference of a deep frame (80x60).
pub const DEEP_REFERENCE_PIXELS: u32 = 80 * 60;

/// The factor a `width` x `height` frame is reduced by for the double-double reference: the
/// smallest common divisor of both sides that leaves at most [`DEEP_REFERENCE_PIXELS`]
/// pixels (the largest common divisor if none does; 1 when the frame is small enough).
pub fn deep_reduction(width: u32, height: u32) -> u32 {
    let common =
        (1..=width.min(height)).filter(|&f| width.is_multiple_of(f) && height.is_multiple_of(f));
    let mut last = 1;
    for f in common {
        last = f;
        if (width / f) as u64 * (height / f) as u64 <= DEEP_REFERENCE_PIXELS as u64 {
            return f;
        }
    }
    last
}

/// The reference tracer: a session of [`reference_scene`] rendering with the CPU tracer at
/// the size, SSAO and threads of an octree request; for deep frames the double-double
/// reference of the same scene ([`Reference::deep_frame`]).
pub struct Reference {
    session: Session,
    req: RenderRequest,
    scene: Scene,
    tape: Option<Tape>,
    deep_samples: u32,
}

impl Reference {
    /// A reference for `scene` rendered like `req` (its backend is replaced by the tracer).
    pub fn new(scene: &Scene, req: &RenderRequest) -> Result<Reference, RenderError> {
        let mut req = req.clone();
        req.backend = Backend::Trace;
        req.region = None;
        let scene = reference_scene(scene);
        Ok(Reference {
            session: Session::new(scene.clone())?,
            req,
            scene,
            tape: None,
            deep_samples: 1,
        })
    }

    /// The same reference with deep frames cast `n` x `n` rays a pixel
    /// (`fathom_trace::deep::DeepOptions::pixel_samples`; 1 by default).
    pub fn with_deep_samples(mut self, n: u32) -> Reference {
        self.deep_samples = n;
        self
    }

    /// The tracer's frame at `cam`.
    pub fn frame(&mut self, cam: &Camera) -> Result<Frame, RenderError> {
        Ok(self.session.render(cam, &self.req)?.frame)
    }

    /// The double-double reference of frame `i` of `frames` of the zoom `path` to `depth`
    /// (field of view `fov`), at the request's size reduced by [`deep_reduction`], and that
    /// factor; `None` for tours. The scene's fog (or the request's override) and SSAO apply;
    /// each pixel takes [`Reference::with_deep_samples`] rays a side.
    pub fn deep_frame(
        &mut self,
        path: &CameraPath,
        fov: f64,
        i: usize,
        frames: usize,
        depth: f64,
    ) -> Result<Option<(Frame, u32)>, RenderError> {
        if self.tape.is_none() {
            if let Some(fog) = self.req.fog {
                self.scene.render.fog = fog;
            }
            self.tape = Some(Tape::compile(&self.scene).map_err(fathom_trace::TraceError::from)?);
        }
        let tape = self.tape.as_ref().expect("compiled above");
        let (w, h) = (self.req.width, self.req.height);
        let f = deep_reduction(w, h);
        Ok(fathom_trace::deep::zoom_frame(
            tape,
            &self.scene,
            path,
            i,
            frames,
            depth,
            fov,
            w / f,
            h / f,
            self.req.ssao,
            self.deep_samples,
        )
        .map(|fr| (fr, f)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deep_reductions_divide_the_frame_under_the_budget() {
        assert_eq!(deep_reduction(48, 36), 1);
        assert_eq!(deep_reduction(80, 60), 1);
        assert_eq!(deep_reduction(160, 120), 2);
        assert_eq!(deep_reduction(640, 480), 8);
        assert_eq!(deep_reduction(641, 480), 1);
    }
}
