//! The octree backend of a session: one octree view, kept while the scene and the octree settings
//! stay the same (so a still view settles once and a zoom or a window steps the same tree),
//! rebuilt when either changes; the per-frame time budgets (`subdivide_ms`, `target_fps`) and
//! the order requests are served in (`fovea`) and whether wide voxels are drawn smooth are not
//! part of the tree and change in place, so a window's frame-time slider keeps the tree.
//! A still frame settles the tree at the view (subdividing until no leaf asks for more, within
//! the request's frame limit) and renders it; a stepped frame renders the tree as it is and
//! subdivides within a time budget. Frames go through the shared post effects; regions are
//! cropped from the whole frame.

use crate::backend::{Counters, Rendered, report_done};
use crate::control::Control;
use crate::request::RenderRequest;
use crate::stats::{OctreeStats, Stats, Timings};
use fathom_core::frame::{Frame, Rect};
use fathom_core::{Camera, Scene};
use fathom_image::post::{self, PostParams};
use fathom_svo::{FrameStats, OctreeError, OctreeView, OctreeViewConfig, SvoImage};
use std::time::Instant;

pub(crate) struct OctreeBackend {
    pub view: OctreeView,
    key: (u64, OctreeViewConfig),
}

/// The settings that shape the tree: `cfg` with its per-frame time budgets, request order,
/// smoothing and filling set to their defaults (they decide how much a frame refines, where
/// first and how wide voxels are drawn, not what the tree settles to).
fn tree_settings(cfg: &OctreeViewConfig) -> OctreeViewConfig {
    let d = OctreeViewConfig::default();
    OctreeViewConfig {
        subdivide_ms: d.subdivide_ms,
        target_fps: d.target_fps,
        fovea: d.fovea,
        smooth: d.smooth,
        fill_px: d.fill_px,
        ..cfg.clone()
    }
}

impl OctreeBackend {
    /// The octree view for `scene` (of shading generation `generation`) and `req`'s settings,
    /// building a new one when either changed (other than the time budgets, the request
    /// order's fovea and the smoothing, which are set on the view kept).
    pub fn get<'a>(
        slot: &'a mut Option<OctreeBackend>,
        scene: &Scene,
        generation: u64,
        req: &RenderRequest,
        counters: &mut Counters,
    ) -> Result<&'a mut OctreeBackend, OctreeError> {
        let cfg = req.octree_config();
        let key = (generation, tree_settings(&cfg));
        if slot.as_ref().is_none_or(|o| o.key != key) {
            *slot = None;
            let view = OctreeView::new(scene, cfg.clone())?;
            counters.octrees_built += 1;
            *slot = Some(OctreeBackend { view, key });
        }
        // The kept view's settings differ at most in the budgets, the fovea, the
        // smoothing and the filling: take the new ones.
        let ob = slot.as_mut().expect("built above");
        ob.view.cfg = cfg;
        Ok(ob)
    }

    /// Settles the tree at `camera` and renders it.
    pub fn render(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        req: &RenderRequest,
        control: &Control,
    ) -> Result<Rendered, crate::RenderError> {
        let t0 = Instant::now();
        let mut settle_frames = 0;
        let deep = fathom_svo::DeepEye::of(camera);
        let mut settling = fathom_svo::octree_view::Settling::default();
        for _ in 0..req.octree.settle_frames {
            if control.cancelled() {
                return Err(crate::RenderError::Cancelled);
            }
            let (reqs, _) = self.view.probe_settling(camera, &deep, &mut settling);
            // Progress: the pixels no longer on voxels wider than their footprint.
            let cfg = &self.view.cfg;
            let total = cfg.width as usize * cfg.height as usize;
            if let Some(pending) = settling.pending() {
                control.report(total - pending.min(total), total);
            }
            if reqs.is_empty() {
                break;
            }
            self.view.subdivide(reqs, f64::INFINITY);
            settle_frames += 1;
        }
        let ms_subdivide = t0.elapsed().as_secs_f64() * 1e3;
        let t1 = Instant::now();
        let (img, reqs, counts) = self.view.render(camera);
        self.view.release_requests(&reqs);
        let ms_render = t1.elapsed().as_secs_f64() * 1e3;
        let t2 = Instant::now();
        let frame = finish(&img, scene, camera, req);
        let tree = &self.view.tree;
        let c = tree.counts();
        let stats = Stats {
            renderer: "svo",
            width: frame.width,
            height: frame.height,
            primary_rays: counts[0],
            hits: counts[1],
            ms: Timings {
                trace_and_shade: ms_render,
                subdivide: Some(ms_subdivide),
                post: t2.elapsed().as_secs_f64() * 1e3,
                ..Timings::default()
            },
            octree: Some(OctreeStats {
                settle_frames,
                nodes: c.nodes as u64,
                bricks: c.bricks as u64,
                nodes_per_ray: counts[2] as f64 / counts[0].max(1) as f64,
                arena_bytes: tree.arena_bytes() as u64,
            }),
            ..Stats::default()
        };
        report_done(control);
        Ok(Rendered { frame, stats })
    }

    /// One stepped frame (render the tree as it is, subdivide, maybe unify); a `still` one
    /// settles on within its budget ([`fathom_svo::OctreeView::step_deep_until`]).
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        deep: &fathom_svo::DeepEye,
        req: &RenderRequest,
        want_frame: bool,
        still: bool,
        control: &Control,
    ) -> (Option<Frame>, FrameStats) {
        let (img, st) = self
            .view
            .step_deep_until(camera, deep, still, &|| control.cancelled());
        let frame = want_frame.then(|| finish(&img, scene, camera, req));
        self.view.recycle(img);
        (frame, st)
    }
}

/// The shared post effects on an octree image, then the region's crop.
fn finish(img: &SvoImage, scene: &Scene, camera: &Camera, req: &RenderRequest) -> Frame {
    let frame = img.to_frame();
    let r = &scene.render;
    let params = PostParams {
        ssao: req.ssao,
        pixel_angle: camera.frame().pixel_angle(img.height) as f32,
        fog: r.fog as f32,
        fog_colour: r.sky_bottom.map(|c| c as f32),
        supersample: req.supersample,
    };
    let whole = Rect::full(img.width, img.height);
    let frame = post::finish_view(frame, whole, whole, &params);
    match req.region {
        Some(r) => frame.crop(r),
        None => frame,
    }
}
