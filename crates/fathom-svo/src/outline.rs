//! Outline agreement with a sphere tracer and image similarity: the correctness experiments
//! of the evaluation (silhouette IoU, false negatives, strict self-similarity). The figures
//! are [`fathom_image::compare`]'s; this module renders the pictures they compare.

use crate::error::OctreeError;
use crate::octree_view::{OctreeView, OctreeViewConfig, SvoImage, Traversal};
use fathom_core::eval::Evaluator;
use fathom_core::scene::Scene;
use fathom_core::{Camera, Tape, V3};
use fathom_image::compare::{Overlap, packed_similarity};

/// Silhouette of a plain f64 sphere tracer: a pixel is hit when its ray comes within `eps`
/// pixel footprints of the surface (within 20 world units and 2000 steps).
pub fn trace_mask(
    scene: &Scene,
    cam: &Camera,
    w: u32,
    h: u32,
    eps: f64,
) -> Result<Vec<bool>, OctreeError> {
    let tape = Tape::compile(scene)?;
    let f = cam.frame();
    let pa = f.pixel_angle(h);
    let mut ev = Evaluator::<f64>::new();
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let d = f.ray_dir(x as f64 + 0.5, y as f64 + 0.5, w, h);
            let mut t = 0.0;
            let mut hit = false;
            for _ in 0..2000 {
                let p = cam.eye + d * t;
                let dist = ev.distance(&tape, V3::new(p.x, p.y, p.z));
                if dist < eps * pa * t.max(1e-9) {
                    hit = true;
                    break;
                }
                t += dist;
                if t > 20.0 {
                    break;
                }
            }
            out.push(hit);
        }
    }
    Ok(out)
}

/// Outline agreement of an octree render and a sphere tracer.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Agreement {
    /// Intersection over union of the two silhouettes (1 when neither hits anything).
    pub iou: f64,
    /// Pixels the tracer hits that the octree misses (false negatives).
    pub missed: usize,
    /// Pixels the tracer hits.
    pub tracer_hits: usize,
    /// Frames the octree took to settle.
    pub settle_frames: usize,
}

/// Settles an octree of `scene` at `cam` (voxels at most `fidelity` pixels) and compares its
/// silhouette with the tracer's at hit threshold `eps` pixel footprints.
pub fn agreement(
    scene: &Scene,
    cam: &Camera,
    mut cfg: OctreeViewConfig,
    eps: f64,
) -> Result<Agreement, OctreeError> {
    cfg.traversal = Traversal::Neighbour;
    let (w, h) = (cfg.width, cfg.height);
    let mut ex = OctreeView::new(scene, cfg)?;
    let settle_frames = ex.settle(cam, 200);
    let (img, reqs, _) = ex.render(cam);
    ex.release_requests(&reqs);
    let svo = img.mask();
    let st = trace_mask(scene, cam, w, h, eps)?;
    let overlap = Overlap::of(svo.iter().copied(), st.iter().copied());
    Ok(Agreement {
        iou: overlap.iou(),
        missed: overlap.only_b,
        tracer_hits: st.iter().filter(|&&h| h).count(),
        settle_frames,
    })
}

/// Fractions of pixels that are identical, and whose colours differ by at most `tol` (0..1)
/// per channel, between two images of the same size.
pub fn similarity(a: &SvoImage, b: &SvoImage, tol: f64) -> (f64, f64) {
    packed_similarity(&a.colour, &b.colour, tol)
}
