//! The path-tracing backend of a session: fathom-pathtrace's progressive path tracer kept
//! between frames. While the view (camera, size), the scene's shading and the path settings
//! stay the same, each render adds samples to the same accumulator until the request's `spp`
//! (or its time limit) is reached, so a window refines a still view and a command line can
//! show the image's noise falling; anything else starts a new accumulator. A cancelled
//! render keeps the samples of the passes that finished.
//!
//! The frame carries the mean radiance (or the denoised one), the first hit's depth, normal
//! and material id, and the mean distance evaluations per path as its steps; fog is part of
//! the path tracer's light transport, so the session's post effects do not apply it again.

use crate::backend::gpu::GpuBackend;
use crate::backend::{Counters, Rendered};
use crate::control::Control;
use crate::request::{PathRequest, RenderRequest};
use crate::stats::{PathStats, Stats, Timings};
use fathom_core::frame::{Frame, NO_ID};
use fathom_core::{Camera, Scene, Tape};
use fathom_pathtrace::{DenoiseSettings, PathSettings, PathTracer, Progressive};
use std::time::Instant;

/// What an accumulator's samples depend on: a change in any of these starts over.
#[derive(Clone, Debug, PartialEq)]
struct AccumulatorKey {
    shading_generation: u64,
    camera: Camera,
    width: u32,
    height: u32,
    fog: Option<f64>,
    max_bounces: u32,
    aperture: f64,
    focus_distance: Option<f64>,
    seed: u32,
    gpu: bool,
}

impl AccumulatorKey {
    /// The key of a view of `camera` rendered for `req` (on the GPU when `gpu`).
    fn new(shading_generation: u64, camera: &Camera, req: &RenderRequest, gpu: bool) -> Self {
        let p = &req.path;
        AccumulatorKey {
            shading_generation,
            camera: camera.clone(),
            width: req.width,
            height: req.height,
            fog: req.fog,
            max_bounces: p.max_bounces,
            aperture: p.aperture,
            focus_distance: p.focus_distance,
            seed: p.seed,
            gpu,
        }
    }
}

/// Where the samples accumulate.
enum Accumulator {
    /// On the CPU, in fathom-pathtrace's accumulator.
    Cpu(Box<Progressive>),
    /// On the GPU, in the session's renderer (fathom-gpu's path tracer), which held this
    /// many samples after the last render (a renderer handed over in between starts over).
    Gpu { samples: u32 },
}

/// The accumulated image of one view.
pub(crate) struct PathBackend {
    key: AccumulatorKey,
    accumulator: Accumulator,
}

impl PathBackend {
    /// The accumulator for this view of `scene` (shading generation `generation`), a new one
    /// when anything its samples depend on changed.
    pub fn get<'a>(
        slot: &'a mut Option<PathBackend>,
        scene: &Scene,
        tape: &Tape,
        generation: u64,
        camera: &Camera,
        req: &RenderRequest,
        counters: &mut Counters,
    ) -> Result<&'a mut PathBackend, fathom_pathtrace::PathTraceError> {
        let p = &req.path;
        let key = AccumulatorKey::new(generation, camera, req, false);
        if slot.as_ref().is_none_or(|b| b.key != key) {
            *slot = None;
            let mut viewed = scene.clone();
            viewed.camera = camera.clone();
            let tracer = PathTracer::new(&viewed, tape, settings(req.width, req.height, p))?;
            counters.path_accumulators += 1;
            *slot = Some(PathBackend {
                key,
                accumulator: Accumulator::Cpu(Box::new(Progressive::new(tracer))),
            });
        }
        Ok(slot.as_mut().expect("made above"))
    }

    /// Adds samples up to the request's `spp` (at least one pass when a time limit is set
    /// and the target is not yet reached), then returns the image.
    pub fn render(
        &mut self,
        req: &RenderRequest,
        control: &Control,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<Rendered, crate::RenderError> {
        let t0 = Instant::now();
        let Accumulator::Cpu(progressive) = &mut self.accumulator else {
            // `get` makes CPU accumulators only; a GPU one has another key.
            return Err(fathom_gpu::GpuError::Invalid(
                "the CPU path tracer was asked to extend a GPU accumulation".into(),
            )
            .into());
        };
        let p = &req.path;
        let first = progressive.stats().samples_per_pixel;
        let wanted = p.spp.saturating_sub(first);
        let passes_done = std::sync::atomic::AtomicUsize::new(0);
        let report = |tiles_done: usize, tiles: usize| {
            report_passes(control, p, wanted, &passes_done, tiles_done, tiles)
        };
        let pt_control = fathom_pathtrace::Control {
            cancel: control.cancel.map(|c| c.flag()),
            progress: Some(&report),
        };
        let run = |prog: &mut Progressive| -> Result<(), crate::RenderError> {
            for pass in 0..wanted {
                if pass > 0
                    && p.time_limit
                        .is_some_and(|limit| t0.elapsed().as_secs_f64() >= limit)
                {
                    break;
                }
                match prog.add_samples(1, &pt_control) {
                    Ok(()) => {}
                    Err(fathom_pathtrace::PathTraceError::Cancelled) => {
                        return Err(crate::RenderError::Cancelled);
                    }
                    Err(e) => return Err(e.into()),
                }
                passes_done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
            Ok(())
        };
        match pool {
            Some(pool) => pool.install(|| run(progressive))?,
            None => run(progressive)?,
        }
        let traced_ms = t0.elapsed().as_secs_f64() * 1e3;
        let image = progressive.frame();
        let st = progressive.stats().clone();
        Ok(finish(
            image, None, &st, first, traced_ms, req, control, pool,
        ))
    }

    /// [`PathBackend::render`] on the GPU: the accumulator lives in `gpu`'s renderer, which
    /// gets the tape (generation `tape_generation`) uploaded when it changed; a new view,
    /// edit or setting re-bakes the path tracer's buffers (no shader or pipeline is built).
    /// On a software adapter a watched render goes in bands of rows, for progress.
    #[allow(clippy::too_many_arguments)]
    pub fn render_gpu(
        slot: &mut Option<PathBackend>,
        gpu: &mut GpuBackend,
        scene: &Scene,
        tape: &Tape,
        tape_generation: u64,
        shading_generation: u64,
        camera: &Camera,
        req: &RenderRequest,
        control: &Control,
        counters: &mut Counters,
    ) -> Result<Rendered, crate::RenderError> {
        let t0 = Instant::now();
        let p = &req.path;
        let key = AccumulatorKey::new(shading_generation, camera, req, true);
        gpu.upload(tape, tape_generation, counters)?;
        let renderer = gpu.renderer_mut();
        let current = slot.as_ref().is_some_and(|b| {
            b.key == key
                && matches!(b.accumulator, Accumulator::Gpu { samples } if samples == renderer.path_samples())
        });
        if !current {
            *slot = None;
            let mut viewed = scene.clone();
            viewed.camera = camera.clone();
            renderer.path_begin(&viewed, tape, settings(req.width, req.height, p))?;
            counters.path_accumulators += 1;
            *slot = Some(PathBackend {
                key,
                accumulator: Accumulator::Gpu { samples: 0 },
            });
        }
        let backend = slot.as_mut().expect("made above");
        let first = renderer.path_samples();
        let wanted = p.spp.saturating_sub(first);
        let watched = control.cancel.is_some() || control.progress.is_some();
        let band = if watched && renderer.gpu().is_software() {
            crate::backend::gpu::SOFTWARE_BAND_ROWS
        } else {
            u32::MAX
        };
        let passes_done = std::sync::atomic::AtomicUsize::new(0);
        let report = |bands_done: usize, bands: usize| {
            report_passes(control, p, wanted, &passes_done, bands_done, bands)
        };
        let pt_control = fathom_pathtrace::Control {
            cancel: control.cancel.map(|c| c.flag()),
            progress: watched.then_some(&report as &(dyn Fn(usize, usize) + Sync)),
        };
        let mut outcome = Ok(());
        for pass in 0..wanted {
            if pass > 0
                && p.time_limit
                    .is_some_and(|limit| t0.elapsed().as_secs_f64() >= limit)
            {
                break;
            }
            if let Err(e) = renderer.path_add_samples(1, band, &pt_control) {
                outcome = Err(e);
                break;
            }
            passes_done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        backend.accumulator = Accumulator::Gpu {
            samples: renderer.path_samples(),
        };
        match outcome {
            Err(fathom_gpu::GpuError::Cancelled) => return Err(crate::RenderError::Cancelled),
            r => r?,
        }
        let traced_ms = t0.elapsed().as_secs_f64() * 1e3;
        let (image, st) = renderer.path_frame()?;
        // The denoiser runs on the device too (the same filter as the CPU's).
        let t1 = Instant::now();
        let denoised = if p.denoise {
            Some(renderer.path_denoise(&DenoiseSettings::default())?)
        } else {
            None
        };
        let denoise_ms = t1.elapsed().as_secs_f64() * 1e3;
        let mut r = finish(image, denoised, &st, first, traced_ms, req, control, None);
        r.stats.ms.post += denoise_ms;
        let g = renderer.gpu();
        r.stats.adapter = Some(g.adapter_name());
        r.stats.adapter_is_software = Some(g.is_software());
        Ok(r)
    }
}

/// Reports progress in units (tiles or bands) of passes. With a time limit the number of
/// passes is not known ahead: the pass under way is reported as the last one, so the figure
/// never passes 100 %.
fn report_passes(
    control: &Control,
    p: &PathRequest,
    wanted: u32,
    passes_done: &std::sync::atomic::AtomicUsize,
    units_done: usize,
    units: usize,
) {
    let passes = passes_done.load(std::sync::atomic::Ordering::Relaxed);
    let total = match p.time_limit {
        Some(_) => passes + 1,
        None => wanted as usize,
    };
    control.report(passes * units + units_done, total * units);
}

/// The rendered frame and statistics of an accumulated image (denoised when asked, here
/// unless `denoised` is given), the same for both accumulators.
#[allow(clippy::too_many_arguments)]
fn finish(
    image: fathom_pathtrace::Frame,
    denoised: Option<Vec<[f32; 3]>>,
    st: &fathom_pathtrace::Stats,
    first: u32,
    traced_ms: f64,
    req: &RenderRequest,
    control: &Control,
    pool: Option<&rayon::ThreadPool>,
) -> Rendered {
    let p = &req.path;
    let t1 = Instant::now();
    let noise = image.relative_noise();
    let denoised = denoised.or_else(|| {
        p.denoise.then(|| {
            let run = || fathom_pathtrace::denoise(&image, &DenoiseSettings::default());
            match pool {
                Some(pool) => pool.install(run),
                None => run(),
            }
        })
    });
    let colour = denoised.unwrap_or(image.colour);
    let whole = Frame {
        width: image.width,
        height: image.height,
        colour,
        depth: image.depth,
        normal: image.normal,
        id: image.id,
        steps: image.steps,
    };
    let frame = match req.region {
        Some(r) => whole.crop(r),
        None => whole,
    };
    let added = (st.samples_per_pixel - first) as u64;
    let stats = Stats {
        renderer: "path",
        width: frame.width,
        height: frame.height,
        primary_rays: added * req.width as u64 * req.height as u64,
        hits: frame.id.iter().filter(|&&id| id != NO_ID).count() as u64,
        ms: Timings {
            trace_and_shade: traced_ms,
            post: t1.elapsed().as_secs_f64() * 1e3,
            ..Timings::default()
        },
        path: Some(PathStats {
            samples_per_pixel: st.samples_per_pixel,
            samples_added: added as u32,
            paths_per_second: st.paths_per_second(),
            relative_noise: noise,
            dropped_non_finite: st.dropped_non_finite,
            denoised: p.denoise,
        }),
        ..Stats::default()
    };
    control.report(1, 1);
    Rendered { frame, stats }
}

/// The path tracer's settings for a `width` x `height` image of this request.
fn settings(width: u32, height: u32, p: &PathRequest) -> PathSettings {
    PathSettings {
        max_bounces: p.max_bounces,
        aperture: p.aperture,
        focus_distance: p.focus_distance,
        seed: p.seed,
        ..PathSettings::new(width, height)
    }
}

#[cfg(test)]
mod tests {
    use crate::control::{CancelToken, Control};
    use crate::request::{Backend, RenderRequest, RequestError};
    use crate::{RenderError, Session};
    use fathom_core::frame::{NO_ID, Rect};
    use fathom_core::{Projection, presets};

    fn request(w: u32, h: u32, spp: u32, threads: usize) -> RenderRequest {
        let mut r = RenderRequest {
            width: w,
            height: h,
            backend: Backend::Path,
            threads: Some(threads),
            ..RenderRequest::default()
        };
        r.path.spp = spp;
        r
    }

    /// Renders of the same view add samples to one accumulator; the image after 2 + 2 samples
    /// is the image of 4 samples in one go, on one thread or two; a new view starts over.
    #[test]
    fn renders_of_one_view_accumulate_and_equal_one_render_of_all_their_samples() {
        let scene = presets::load("menger").unwrap();
        let cam = scene.camera.clone();
        let mut stepwise = Session::new(scene.clone()).unwrap();
        let two = stepwise.render(&cam, &request(20, 14, 2, 2)).unwrap();
        let p = two.stats.path.unwrap();
        assert_eq!((p.samples_per_pixel, p.samples_added), (2, 2));
        let four = stepwise.render(&cam, &request(20, 14, 4, 2)).unwrap();
        let p = four.stats.path.unwrap();
        assert_eq!((p.samples_per_pixel, p.samples_added), (4, 2));
        // Asking for fewer than it has adds nothing and returns the same image.
        let again = stepwise.render(&cam, &request(20, 14, 3, 2)).unwrap();
        assert_eq!(again.stats.path.unwrap().samples_added, 0);
        assert!(again.frame == four.frame);
        assert_eq!(stepwise.counters().path_accumulators, 1);

        let mut at_once = Session::new(scene.clone()).unwrap();
        let one_thread = at_once.render(&cam, &request(20, 14, 4, 1)).unwrap();
        assert!(
            one_thread.frame == four.frame,
            "2 + 2 samples on two threads differ from 4 samples on one"
        );
        assert_eq!(four.stats.renderer, "path");
        let hits = four.frame.id.iter().filter(|&&id| id != NO_ID).count();
        assert!(
            hits > 0 && hits < four.frame.len(),
            "the sponge covers part of the frame: {hits}"
        );

        // Another view starts over.
        let mut moved = cam.clone();
        moved.eye.x += 0.1;
        let r = stepwise.render(&moved, &request(20, 14, 1, 2)).unwrap();
        assert_eq!(r.stats.path.unwrap().samples_per_pixel, 1);
        assert_eq!(stepwise.counters().path_accumulators, 2);
    }

    /// On the GPU too, renders of one view accumulate (2 + 2 samples are 4 in one go, with
    /// progress in bands on a software adapter); an edit starts over without building a
    /// pipeline; the CPU and GPU images of one view agree in mean.
    #[test]
    fn gpu_renders_accumulate_and_edits_start_over_without_a_pipeline() {
        let scene = presets::load("menger").unwrap();
        let cam = scene.camera.clone();
        let gpu = fathom_gpu::Gpu::headless_vulkan().expect("lavapipe (scripts/setup.sh)");
        let mut s = Session::new(scene.clone()).unwrap();
        s.set_gpu(fathom_gpu::Renderer::new(gpu).unwrap());
        let mut req = request(20, 14, 2, 2);
        req.path.gpu = true;
        let reports = std::sync::atomic::AtomicUsize::new(0);
        let progress = |p: crate::Progress| {
            assert!(p.done <= p.total);
            reports.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        };
        let control = Control {
            cancel: None,
            progress: Some(&progress),
        };
        let two = s.render_with(&cam, &req, &control).unwrap();
        assert!(reports.load(std::sync::atomic::Ordering::Relaxed) >= 2);
        assert_eq!(two.stats.path.unwrap().samples_per_pixel, 2);
        assert!(two.stats.adapter.is_some());
        req.path.spp = 4;
        let four = s.render(&cam, &req).unwrap();
        let p = four.stats.path.unwrap();
        assert_eq!((p.samples_per_pixel, p.samples_added), (4, 2));
        assert_eq!(s.counters().path_accumulators, 1);
        let built = s.gpu().unwrap().objects_built();
        let mut at_once = Session::new(scene.clone()).unwrap();
        at_once.set_gpu(s.take_gpu().unwrap());
        let once = at_once.render(&cam, &req).unwrap();
        assert!(once.frame == four.frame, "2 + 2 GPU samples differ from 4");
        let mut edited = scene.clone();
        edited.root.material.albedo = [0.9, 0.1, 0.1];
        at_once.set_scene(edited).unwrap();
        let red = at_once.render(&cam, &req).unwrap();
        assert_eq!(red.stats.path.unwrap().samples_added, 4);
        assert!(red.frame != once.frame);
        assert_eq!(at_once.gpu().unwrap().objects_built(), built);
        // Denoised on the device: only the colour changes.
        req.path.denoise = true;
        let clean = at_once.render(&cam, &req).unwrap();
        assert!(clean.stats.path.unwrap().denoised);
        assert_eq!(clean.frame.depth, red.frame.depth);
        assert_ne!(clean.frame.colour, red.frame.colour);
        req.path.denoise = false;
        // The CPU's image of the same view: the same mean within its noise.
        let mut cpu = Session::new(scene).unwrap();
        req.path.gpu = false;
        let c = cpu.render(&cam, &req).unwrap();
        let mean = |f: &fathom_core::frame::Frame| {
            f.colour
                .iter()
                .map(|c| (c[0] + c[1] + c[2]) as f64)
                .sum::<f64>()
                / (3 * f.colour.len()) as f64
        };
        let (a, b) = (mean(&c.frame), mean(&four.frame));
        assert!((a - b).abs() < 0.05 * a, "CPU mean {a}, GPU mean {b}");
    }

    /// A region is the crop of the whole image (the sampler is per pixel).
    #[test]
    fn a_region_is_the_crop_of_the_whole_image() {
        let scene = presets::load("model-tree").unwrap();
        let cam = scene.camera.clone();
        let mut s = Session::new(scene.clone()).unwrap();
        let whole = s.render(&cam, &request(18, 12, 2, 2)).unwrap().frame;
        let r = Rect {
            x: 5,
            y: 3,
            width: 7,
            height: 6,
        };
        let mut req = request(18, 12, 2, 2);
        req.region = Some(r);
        let mut fresh = Session::new(scene).unwrap();
        assert!(fresh.render(&cam, &req).unwrap().frame == whole.crop(r));
    }

    /// Denoising changes the colour and nothing else; the statistics say so.
    #[test]
    fn the_denoised_frame_keeps_its_geometry() {
        let scene = presets::load("mandelbulb").unwrap();
        let cam = scene.camera.clone();
        let mut s = Session::new(scene).unwrap();
        let raw = s.render(&cam, &request(24, 16, 2, 2)).unwrap();
        let mut req = request(24, 16, 2, 2);
        req.path.denoise = true;
        let clean = s.render(&cam, &req).unwrap();
        assert!(clean.stats.path.unwrap().denoised);
        assert_eq!(clean.stats.path.unwrap().samples_added, 0);
        assert_eq!(raw.frame.depth, clean.frame.depth);
        assert_eq!(raw.frame.id, clean.frame.id);
        assert_ne!(raw.frame.colour, clean.frame.colour);
    }

    /// Views and settings the path tracer cannot render are refused before any work, naming
    /// the setting and its range.
    #[test]
    fn bad_views_and_settings_are_refused_by_name() {
        let scene = presets::load("menger").unwrap();
        let cam = scene.camera.clone();
        let mut s = Session::new(scene).unwrap();
        let refused = |s: &mut Session, req: RenderRequest| match s.render(&cam, &req) {
            Err(RenderError::Request(e)) => e,
            other => panic!("not refused: {:?}", other.map(|r| r.stats)),
        };
        let mut req = request(16, 16, 1, 1);
        req.projection = Projection::SideBySide {
            eye_separation: 0.1,
        };
        assert_eq!(refused(&mut s, req), RequestError::PathView);
        let mut req = request(16, 16, 1, 1);
        req.supersample = 2;
        assert_eq!(refused(&mut s, req), RequestError::PathView);
        type Edit = fn(&mut RenderRequest);
        let edits: [(&str, Edit); 7] = [
            ("spp", |r| r.path.spp = 0),
            ("spp", |r| r.path.spp = u32::MAX),
            ("max_bounces", |r| r.path.max_bounces = 0),
            ("aperture", |r| r.path.aperture = f64::NAN),
            ("aperture", |r| r.path.aperture = -1.0),
            ("focus_distance", |r| r.path.focus_distance = Some(0.0)),
            ("time_limit", |r| r.path.time_limit = Some(f64::INFINITY)),
        ];
        for (field, set) in edits {
            let mut req = request(16, 16, 1, 1);
            set(&mut req);
            let e = refused(&mut s, req);
            assert!(
                matches!(e, RequestError::PathSetting { name, .. } if name == field),
                "{field}: {e}"
            );
            assert!(e.to_string().contains("out of range"), "{e}");
        }
        assert_eq!(s.counters().path_accumulators, 0);
    }

    /// A cancelled render returns `Cancelled` and keeps the samples already accumulated.
    #[test]
    fn a_cancel_keeps_the_samples_already_taken() {
        let scene = presets::load("menger").unwrap();
        let cam = scene.camera.clone();
        let mut s = Session::new(scene).unwrap();
        let first = s.render(&cam, &request(16, 12, 1, 1)).unwrap();
        let token = CancelToken::new();
        token.cancel();
        let control = Control {
            cancel: Some(&token),
            progress: None,
        };
        let r = s.render_with(&cam, &request(16, 12, 8, 1), &control);
        assert!(matches!(r, Err(RenderError::Cancelled)));
        let again = s.render(&cam, &request(16, 12, 1, 1)).unwrap();
        assert_eq!(again.stats.path.unwrap().samples_per_pixel, 1);
        assert!(again.frame == first.frame);
    }

    /// With a time limit, at least one pass is made and the render stops near the limit.
    #[test]
    fn a_time_limit_stops_the_render_after_at_least_one_pass() {
        let scene = presets::load("menger").unwrap();
        let cam = scene.camera.clone();
        let mut s = Session::new(scene).unwrap();
        let mut req = request(16, 12, 1 << 20, 2);
        req.path.time_limit = Some(1e-6);
        // Progress never passes its total, however long the pass takes against the limit.
        let over = std::sync::atomic::AtomicBool::new(false);
        let progress = |p: crate::Progress| {
            if p.done > p.total {
                over.store(true, std::sync::atomic::Ordering::Relaxed);
            }
        };
        let control = Control {
            cancel: None,
            progress: Some(&progress),
        };
        let r = s.render_with(&cam, &req, &control).unwrap();
        assert_eq!(r.stats.path.unwrap().samples_per_pixel, 1);
        assert!(!over.load(std::sync::atomic::Ordering::Relaxed));
    }
}
