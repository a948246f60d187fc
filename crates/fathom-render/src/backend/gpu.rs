//! The GPU backend of a session: the renderer and device (opened once), the tape uploaded only
//! when it changed (a parameter edit is a parameter-buffer write; no buffer, bind group or
//! pipeline is ever created for an edit), and the shared post effects on the frame read back:
//! each eye's view through `fathom_image::post::finish_view`, then the stereo layout and the
//! region's crop. Regions are supported by rendering the whole frame and cropping it (the
//! same pixels as the whole render, at the whole render's cost).

use crate::backend::{Counters, Rendered};
use crate::control::Control;
use crate::request::RenderRequest;
use crate::stats::{DeCounts, Stats, Timings};
use fathom_core::frame::{Frame, Rect};
use fathom_core::{Camera, Scene, Tape};
use fathom_gpu::{GpuError, RenderOptions, Renderer};
use fathom_image::post::{self, PostParams};
use fathom_image::stereo;
use std::time::Instant;

/// Rows per band of a watched frame on a software adapter: about a second of lavapipe's time
/// on the heavier presets at window sizes.
pub const SOFTWARE_BAND_ROWS: u32 = 32;

pub(crate) struct GpuBackend {
    renderer: Renderer,
    /// The tape generation last uploaded.
    uploaded: Option<u64>,
}

impl GpuBackend {
    pub fn new(renderer: Renderer) -> GpuBackend {
        GpuBackend {
            renderer,
            uploaded: None,
        }
    }

    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    pub fn into_renderer(self) -> Renderer {
        self.renderer
    }

    pub fn renderer_mut(&mut self) -> &mut Renderer {
        &mut self.renderer
    }

    pub fn upload(
        &mut self,
        tape: &Tape,
        generation: u64,
        counters: &mut Counters,
    ) -> Result<(), GpuError> {
        if self.uploaded != Some(generation) {
            self.renderer.set_tape(tape)?;
            self.uploaded = Some(generation);
            counters.gpu_uploads += 1;
        }
        Ok(())
    }

    fn options(req: &RenderRequest, fog: bool) -> RenderOptions {
        RenderOptions {
            width: req.width * req.supersample,
            height: req.height * req.supersample,
            projection: req.projection,
            prepass: req.prepass,
            fog,
        }
    }

    /// Renders, reads back and finishes the frame. With a cancel token or a progress hook in
    /// `control` on a software adapter (whose frames take seconds), the frame goes in bands of
    /// [`SOFTWARE_BAND_ROWS`] rows: progress after each, and a cancel takes effect at the next.
    #[allow(clippy::too_many_arguments)]
    pub fn render(
        &mut self,
        scene: &Scene,
        tape: &Tape,
        generation: u64,
        camera: &Camera,
        req: &RenderRequest,
        control: &Control,
        counters: &mut Counters,
    ) -> Result<Rendered, GpuError> {
        self.upload(tape, generation, counters)?;
        let opts = Self::options(req, false);
        let watched = control.cancel.is_some() || control.progress.is_some();
        let band = if watched && self.renderer.gpu().is_software() {
            SOFTWARE_BAND_ROWS
        } else {
            u32::MAX
        };
        let (frame, s) = self.renderer.render_in_bands(
            scene,
            tape,
            camera,
            &opts,
            band,
            &mut |done, total| {
                control.report(done as usize, total as usize);
                !control.cancelled()
            },
        )?;
        let t_post = Instant::now();
        let projection = req.projection;
        let cam = projection.frame(camera);
        let pixel_angle = projection.pixel_angle(&cam, opts.width, opts.height);
        let r = &scene.render;
        let params = PostParams {
            ssao: if projection.screen_space() {
                req.ssao
            } else {
                0.0
            },
            pixel_angle: pixel_angle as f32,
            fog: r.fog as f32,
            fog_colour: r.sky_bottom.map(|c| c as f32),
            supersample: req.supersample,
        };
        let whole = Rect::full(opts.width, opts.height);
        let views: Vec<Frame> = stereo::split(projection, frame)
            .into_iter()
            .map(|v| post::finish_view(v, whole, whole, &params))
            .collect();
        let frame = stereo::assemble(projection, views);
        let frame = match req.region {
            Some(r) => frame.crop(r),
            None => frame,
        };
        let ms_post = t_post.elapsed().as_secs_f64() * 1e3;
        let gpu = self.renderer.gpu();
        let mut stats = Stats {
            renderer: "gpu",
            adapter: Some(gpu.adapter_name()),
            adapter_is_software: Some(gpu.is_software()),
            width: frame.width,
            height: frame.height,
            primary_rays: s.width as u64 * s.height as u64,
            hits: s.hits,
            de_evaluations: DeCounts {
                prepass: s.de_prepass,
                trace: s.de_trace,
                shade: s.de_shade,
            },
            ms: Timings {
                gpu: Some(s.ms_gpu),
                post: ms_post,
                ..Timings::default()
            },
            ..Stats::default()
        };
        // Evaluations per pixel of the image the GPU rendered (the whole one, supersampled).
        let (w, h) = (stats.width, stats.height);
        stats.width = s.width;
        stats.height = s.height;
        stats.finish_rates();
        stats.width = w;
        stats.height = h;
        Ok(Rendered { frame, stats })
    }

    /// Renders into the renderer's output texture without reading anything back.
    pub fn render_to_texture(
        &mut self,
        scene: &Scene,
        tape: &Tape,
        generation: u64,
        camera: &Camera,
        req: &RenderRequest,
        counters: &mut Counters,
    ) -> Result<&wgpu::Texture, GpuError> {
        self.upload(tape, generation, counters)?;
        let opts = Self::options(req, true);
        self.renderer.render_to_texture(scene, tape, camera, &opts)
    }
}
