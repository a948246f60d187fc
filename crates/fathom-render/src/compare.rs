//! How close an octree frame is to the sphere tracer's frame at the same camera: the figures
//! `fathom zoom --compare-every N` writes per frame and the still-camera tests assert.
//!
//! - **SSIM on luminance**: the structural similarity index (Wang et al. 2004) of the two
//!   frames' display luminance (tonemapped, sRGB-encoded, Rec. 709 weights), over 8x8 windows
//!   placed every 4 pixels (uniform weights, `C1 = 0.01^2`, `C2 = 0.03^2`), averaged;
//! - **silhouette IoU**: hit pixels (finite depth) of both over hit pixels of either;
//! - **colour agreement**: over pixels both hit, the mean absolute difference of the display
//!   colour per channel (0..1) and the fraction of pixels within [`COLOUR_TOL`] on every
//!   channel.
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
use fathom_trace::post::{srgb, tonemap};
use serde::Serialize;

/// Per-channel display-colour difference (0..1) within which a pixel counts as matching.
pub const COLOUR_TOL: f64 = 0.1;

/// Window side and stride of the SSIM.
const WIN: usize = 8;
const STRIDE: usize = 4;

/// How close two frames of the same size are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Agreement {
    /// SSIM of the display luminance, in [-1, 1] (1: identical).
    pub ssim: f64,
    /// Silhouette intersection over union (1 when neither frame hits anything).
    pub iou: f64,
    /// Mean absolute display-colour difference per channel over pixels both frames hit.
    pub colour_error: f64,
    /// Fraction of the pixels both frames hit whose display colours are within
    /// [`COLOUR_TOL`] on every channel (1 when there are none).
    pub colour_within: f64,
}

/// The scene the reference tracer renders: `scene` with soft shadows off (see the module
/// comment).
pub fn reference_scene(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for l in &mut s.lights {
        l.shadows = false;
    }
    s
}

/// Display value of a linear channel: tonemapped and sRGB-encoded, in [0, 1].
fn display(x: f32) -> f64 {
    srgb(tonemap(x)) as f64
}

/// Display luminance (Rec. 709 weights on the encoded channels) of every pixel.
pub fn luminance(f: &Frame) -> Vec<f64> {
    f.colour
        .iter()
        .map(|c| 0.2126 * display(c[0]) + 0.7152 * display(c[1]) + 0.0722 * display(c[2]))
        .collect()
}

/// Mean SSIM of two luminance images of `w` x `h` (see the module comment); images smaller
/// than one window are compared as one window.
pub fn ssim(a: &[f64], b: &[f64], w: usize, h: usize) -> f64 {
    const C1: f64 = 0.01 * 0.01;
    const C2: f64 = 0.03 * 0.03;
    let (ww, wh) = (WIN.min(w), WIN.min(h));
    let starts = |len: usize, win: usize| {
        let mut v: Vec<usize> = (0..=len.saturating_sub(win)).step_by(STRIDE).collect();
        if v.last() != Some(&(len.saturating_sub(win))) {
            v.push(len.saturating_sub(win));
        }
        v
    };
    let (xs, ys) = (starts(w, ww), starts(h, wh));
    let mut sum = 0.0;
    let mut n = 0usize;
    for &y0 in &ys {
        for &x0 in &xs {
            let (mut sa, mut sb, mut saa, mut sbb, mut sab) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for y in y0..y0 + wh {
                for x in x0..x0 + ww {
                    let (p, q) = (a[y * w + x], b[y * w + x]);
                    sa += p;
                    sb += q;
                    saa += p * p;
                    sbb += q * q;
                    sab += p * q;
                }
            }
            let k = (ww * wh) as f64;
            let (ma, mb) = (sa / k, sb / k);
            let va = (saa / k - ma * ma).max(0.0);
            let vb = (sbb / k - mb * mb).max(0.0);
            let cov = sab / k - ma * mb;
            sum += ((2.0 * ma * mb + C1) * (2.0 * cov + C2))
                / ((ma * ma + mb * mb + C1) * (va + vb + C2));
            n += 1;
        }
    }
    if n == 0 { 1.0 } else { sum / n as f64 }
}

/// Compares frame `a` with frame `b` (same size; an octree frame and the tracer's).
pub fn agreement(a: &Frame, b: &Frame) -> Agreement {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "frames differ in size"
    );
    let (w, h) = (a.width as usize, a.height as usize);
    let ssim = ssim(&luminance(a), &luminance(b), w, h);
    let (mut inter, mut union) = (0usize, 0usize);
    let (mut err, mut within) = (0.0, 0usize);
    for i in 0..w * h {
        let (ha, hb) = (a.depth[i].is_finite(), b.depth[i].is_finite());
        union += (ha || hb) as usize;
        if ha && hb {
            inter += 1;
            let d: [f64; 3] =
                std::array::from_fn(|k| (display(a.colour[i][k]) - display(b.colour[i][k])).abs());
            err += d.iter().sum::<f64>() / 3.0;
            within += d.iter().all(|&x| x <= COLOUR_TOL) as usize;
        }
    }
    Agreement {
        ssim,
        iou: if union == 0 {
            1.0
        } else {
            inter as f64 / union as f64
        },
        colour_error: if inter == 0 { 0.0 } else { err / inter as f64 },
        colour_within: if inter == 0 {
            1.0
        } else {
            within as f64 / inter as f64
        },
    }
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

/// `frame` reduced by `f` (dividing both sides): each `f` x `f` block becomes a pixel whose
/// colour is the block's mean, which is a hit (at the block's nearest depth) when at least
/// half the block's pixels hit. A point-sampled reference pixel is then compared with what
/// the block shows on the whole.
pub fn reduce(frame: &Frame, f: u32) -> Frame {
    if f == 1 {
        return frame.clone();
    }
    let (w, h) = (frame.width / f, frame.height / f);
    let mut out = Frame::new(w, h);
    let n = (f * f) as f32;
    for y in 0..h {
        for x in 0..w {
            let o = out.index(x, y);
            let (mut c, mut hits, mut near) = ([0f32; 3], 0u32, f32::INFINITY);
            for sy in 0..f {
                for sx in 0..f {
                    let i = frame.index(x * f + sx, y * f + sy);
                    for (acc, v) in c.iter_mut().zip(frame.colour[i]) {
                        *acc += v;
                    }
                    if frame.depth[i].is_finite() {
                        hits += 1;
                        near = near.min(frame.depth[i]);
                    }
                }
            }
            out.colour[o] = c.map(|v| v / n);
            if fathom_trace::deep::covers(hits, f * f) {
                out.depth[o] = near;
            }
        }
    }
    out
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

    fn frame(w: u32, h: u32, f: impl Fn(u32, u32) -> Option<f32>) -> Frame {
        let mut fr = Frame::new(w, h);
        for y in 0..h {
            for x in 0..w {
                if let Some(v) = f(x, y) {
                    let i = (y * w + x) as usize;
                    fr.colour[i] = [v; 3];
                    fr.depth[i] = 1.0;
                }
            }
        }
        fr
    }

    #[test]
    fn deep_reductions_divide_the_frame_under_the_budget() {
        assert_eq!(deep_reduction(48, 36), 1);
        assert_eq!(deep_reduction(80, 60), 1);
        assert_eq!(deep_reduction(160, 120), 2);
        assert_eq!(deep_reduction(640, 480), 8);
        assert_eq!(deep_reduction(641, 480), 1);
        // Half a block hit is a hit; colours are averaged.
        let f = frame(4, 2, |x, _| (x == 0 || x == 3).then_some(1.0));
        let r = reduce(&f, 2);
        assert_eq!((r.width, r.height), (2, 1));
        assert!(r.depth[0].is_finite() && r.depth[1].is_finite());
        assert_eq!(r.colour[0], [0.5; 3]);
        let g = frame(4, 2, |x, y| (x == 0 && y == 0).then_some(1.0));
        assert!(!reduce(&g, 2).depth[0].is_finite());
    }

    #[test]
    fn identical_frames_agree_fully_and_different_ones_do_not() {
        let a = frame(32, 24, |x, y| {
            (x > 4).then_some(((x * 7 + y * 3) % 11) as f32 / 11.0)
        });
        let same = agreement(&a, &a);
        assert!((same.ssim - 1.0).abs() < 1e-9, "{same:?}");
        assert_eq!(
            (same.iou, same.colour_error, same.colour_within),
            (1.0, 0.0, 1.0)
        );
        // Flat colour where `a` has texture: silhouettes agree, structure does not.
        let flat = frame(32, 24, |x, _| (x > 4).then_some(0.45));
        let d = agreement(&a, &flat);
        assert_eq!(d.iou, 1.0);
        assert!(d.ssim < 0.5, "{d:?}");
        assert!(d.colour_error > 0.05 && d.colour_within < 1.0, "{d:?}");
        // Half the silhouette missing.
        let half = frame(32, 24, |x, y| (x > 4 && y < 12).then_some(0.45));
        assert!((agreement(&a, &half).iou - 0.5).abs() < 1e-9);
    }
}
