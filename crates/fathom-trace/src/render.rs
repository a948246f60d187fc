//! One frame, or one region of it: validation, the prepass, primary rays over tiles in
//! parallel, shading, and the shared post effects ([`crate::post::finish_view`]).
//!
//! Tiles of 16x16 pixels are spread over rayon's pool, each task with its own evaluator. Inside
//! a tile, rays go in packets of eight (4x2 pixel blocks) on the f32 SIMD path. Every lane's
//! result depends only on its own ray, and per-tile results are written back in tile order, so
//! the image does not depend on the number of threads.
//!
//! **Regions.** A region (a rectangle of the output image) traces only the tiles it needs:
//! its pixels, grown by the reach of SSAO when SSAO is on, rounded out to whole tiles of the
//! full image; the prepass computes only the cells those pixels read, at the positions the
//! full image would. Every value a region pixel depends on is therefore computed exactly as
//! in the whole render: a region is bit-identical to the same pixels of the whole image.
//!
//! **Cancellation and progress.** [`Hooks::cancel`] is checked before every tile (and between
//! prepass levels and eyes): once it is set the remaining tiles are skipped and the render
//! returns [`TraceError::Cancelled`] within about one tile's time per thread.
//! [`Hooks::progress`] is called as tiles finish.
//!
//! Stereo ([`Projection`]): each eye is rendered as a view of its own (prepass, tiles, post
//! effects), then the views are laid out side by side or top/bottom (`crate::stereo`). SSAO is
//! skipped for omni-directional stereo: screen space does not apply across the
//! equirectangular wrap and its stretched poles.
//!
//! Deep zoom: f32 positions have about 7 significant digits. When the pixel footprint at the
//! target falls below `DEEP_FOOTPRINT` times the camera's distance from the origin (or 1), the
//! whole frame switches to the f64 path (one ray per packet; slow but exact).

use crate::post::{self, PostParams};
use crate::prepass::{self, StartGrid, View};
use crate::shade::{Shaded, Shading, shade_hits};
use crate::tracer::{MarchParams, Method, OMEGA, march};
use fathom_core::camera::{CameraError, ProjectionError};
use fathom_core::frame::{Frame, NO_ID, Rect};
use fathom_core::real::{Mask, Real};
use fathom_core::scene::RenderSettings;
use fathom_core::tape::CompileError;
use fathom_core::validate::SceneError;
use fathom_core::{Camera, Evaluator, F32x8, Projection, Scene, Tape, V3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

/// Widest or tallest image, in pixels.
pub const MAX_SIDE: u32 = 16384;
/// Most pixels in one image (after supersampling), 64 Mpixel.
pub const MAX_PIXELS: u64 = 64 << 20;
/// Largest supersampling factor (per axis).
pub const MAX_SUPERSAMPLE: u32 = 4;
/// Tile side in pixels.
pub const TILE: u32 = 16;
/// Relative pixel footprint below which the f64 path is used.
pub const DEEP_FOOTPRINT: f64 = 1e-5;

/// How to render.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// One eye's image width, pixels, [1, MAX_SIDE].
    pub width: u32,
    /// One eye's image height, pixels, [1, MAX_SIDE].
    pub height: u32,
    /// Basic or enhanced sphere tracing.
    pub method: Method,
    /// Run the cone-marching prepass.
    pub prepass: bool,
    /// Samples per pixel along each axis (1 = none), [1, MAX_SUPERSAMPLE].
    pub supersample: u32,
    /// Skip the colouring pass (depth, ids and steps only; colour stays black).
    pub geometry_only: bool,
    /// Screen-space ambient occlusion strength (0 disables), [0, 4]. Ignored for ODS.
    pub ssao: f32,
    /// Mono or stereo; `width` x `height` is the size of one eye's view.
    pub projection: Projection,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            width: 640,
            height: 480,
            method: Method::Enhanced,
            prepass: true,
            supersample: 1,
            geometry_only: false,
            ssao: 0.0,
            projection: Projection::Mono,
        }
    }
}

/// Why render options were refused (before anything is allocated).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OptionsError {
    /// The width or the height is zero.
    #[error("image size {width}x{height} is empty")]
    Empty {
        /// The width asked for, pixels.
        width: u32,
        /// The height asked for, pixels.
        height: u32,
    },
    /// The projection's eye separation is out of range.
    #[error(transparent)]
    Projection(#[from] ProjectionError),
    /// One eye's view is wider or taller than [`MAX_SIDE`].
    #[error("image size {width}x{height} exceeds the limit of {MAX_SIDE} pixels per side")]
    TooLarge {
        /// The width asked for, pixels.
        width: u32,
        /// The height asked for, pixels.
        height: u32,
    },
    /// The stereo layout of both eyes is wider or taller than [`MAX_SIDE`].
    #[error(
        "stereo output size {out_width}x{out_height} ({width}x{height} per eye) exceeds the limit of {MAX_SIDE} pixels per side"
    )]
    StereoTooLarge {
        /// The output width, pixels.
        out_width: u32,
        /// The output height, pixels.
        out_height: u32,
        /// One eye's width, pixels.
        width: u32,
        /// One eye's height, pixels.
        height: u32,
    },
    /// The supersampling factor (given) is outside [1, [`MAX_SUPERSAMPLE`]].
    #[error("supersample = {0} is out of range [1, {MAX_SUPERSAMPLE}]")]
    Supersample(u32),
    /// The output with supersampling would have more than [`MAX_PIXELS`] samples.
    #[error(
        "{out_width}x{out_height} with {ss}x{ss} supersampling is {samples} samples; the limit is {MAX_PIXELS}"
    )]
    TooManySamples {
        /// The output width, pixels.
        out_width: u32,
        /// The output height, pixels.
        out_height: u32,
        /// Samples per pixel along each axis.
        ss: u32,
        /// Samples in all.
        samples: u64,
    },
    /// The SSAO strength (given) is not finite or outside [0, 4].
    #[error("ssao = {0} is out of range [0, 4]")]
    Ssao(f32),
    /// The region asked for is empty or not inside the output image.
    #[error(
        "region {}x{} at ({}, {}) is empty or not inside the {width}x{height} image",
        region.width, region.height, region.x, region.y
    )]
    Region {
        /// The region asked for.
        region: Rect,
        /// The output width, pixels.
        width: u32,
        /// The output height, pixels.
        height: u32,
    },
}

/// Why a render failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TraceError {
    /// The options break a limit.
    #[error(transparent)]
    Options(#[from] OptionsError),
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The camera cannot form an image.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// The scene did not compile to a tape.
    #[error(transparent)]
    Compile(#[from] CompileError),
    /// [`Hooks::cancel`] was set before the frame was finished.
    #[error("the render was cancelled")]
    Cancelled,
}

impl Options {
    /// Checks sizes and sample counts against the documented limits, before any allocation.
    pub fn validate(&self) -> Result<(), OptionsError> {
        let (width, height) = (self.width, self.height);
        if width == 0 || height == 0 {
            return Err(OptionsError::Empty { width, height });
        }
        self.projection.validate()?;
        if width > MAX_SIDE || height > MAX_SIDE {
            return Err(OptionsError::TooLarge { width, height });
        }
        let (ow, oh) = self.output_size();
        if ow > MAX_SIDE || oh > MAX_SIDE {
            return Err(OptionsError::StereoTooLarge {
                out_width: ow,
                out_height: oh,
                width,
                height,
            });
        }
        if !(1..=MAX_SUPERSAMPLE).contains(&self.supersample) {
            return Err(OptionsError::Supersample(self.supersample));
        }
        let samples = ow as u64 * oh as u64 * (self.supersample as u64).pow(2);
        if samples > MAX_PIXELS {
            return Err(OptionsError::TooManySamples {
                out_width: ow,
                out_height: oh,
                ss: self.supersample,
                samples,
            });
        }
        if !(self.ssao.is_finite() && (0.0..=4.0).contains(&self.ssao)) {
            return Err(OptionsError::Ssao(self.ssao));
        }
        Ok(())
    }

    /// Size of the output image (both eyes laid out for stereo).
    pub fn output_size(&self) -> (u32, u32) {
        self.projection.output_size(self.width, self.height)
    }

    /// Checks that `region` is a non-empty rectangle of the output image.
    pub fn check_region(&self, region: Rect) -> Result<(), OptionsError> {
        let (width, height) = self.output_size();
        if region.is_empty() || !region.fits(width, height) {
            return Err(OptionsError::Region {
                region,
                width,
                height,
            });
        }
        Ok(())
    }
}

/// Counters and timings of one render. Sums are integers, so they do not depend on threads.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Width of the frame returned, pixels (the region's, when one was asked for).
    pub width: u32,
    /// Height of the frame returned, pixels.
    pub height: u32,
    /// Whether the f64 (deep zoom) path ran.
    pub deep: bool,
    /// Primary rays traced (samples; with a region, also its margin).
    pub primary_rays: u64,
    /// Shadow rays (one per lit hit and shadowing light).
    pub shadow_rays: u64,
    /// Distance evaluations of the prepass (each pass counts per ray lane).
    pub de_prepass: u64,
    /// Distance evaluations of the marching pass.
    pub de_trace: u64,
    /// Distance evaluations of shading (normals, shadows, AO).
    pub de_shade: u64,
    /// Primary rays that hit a surface.
    pub hits: u64,
    /// Wall time of the prepass, milliseconds.
    pub ms_prepass: f64,
    /// Wall time of marching and shading, milliseconds.
    pub ms_trace: f64,
    /// Wall time of the post effects, milliseconds.
    pub ms_post: f64,
    /// Wall time of the whole render, milliseconds.
    pub ms_total: f64,
}

impl Stats {
    /// Adds the counters and pass timings of another view of the same frame.
    fn add(&mut self, o: &Stats) {
        self.primary_rays += o.primary_rays;
        self.shadow_rays += o.shadow_rays;
        self.de_prepass += o.de_prepass;
        self.de_trace += o.de_trace;
        self.de_shade += o.de_shade;
        self.hits += o.hits;
        self.ms_prepass += o.ms_prepass;
        self.ms_trace += o.ms_trace;
    }

    /// Distance evaluations of the depth passes (prepass and primary rays) per pixel.
    pub fn de_per_pixel(&self) -> f64 {
        (self.de_prepass + self.de_trace) as f64 / (self.width as f64 * self.height as f64)
    }
}

fn no_progress(_: usize, _: usize) {}

/// Cancellation and progress of one render.
#[derive(Clone, Copy)]
pub struct Hooks<'a> {
    /// Set (from any thread) to abandon the render.
    pub cancel: Option<&'a AtomicBool>,
    /// `progress(done, total)` as tiles finish (from worker threads).
    pub progress: &'a (dyn Fn(usize, usize) + Sync),
}

impl Hooks<'static> {
    /// No cancellation, no progress reports.
    pub const NONE: Hooks<'static> = Hooks {
        cancel: None,
        progress: &no_progress,
    };
}

impl Hooks<'_> {
    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

struct Ctx<'a> {
    tape: &'a Tape,
    scene: &'a Scene,
    camera: &'a Camera,
    cam: fathom_core::CameraFrame,
    projection: Projection,
    /// Which view of the projection (0 = left eye).
    eye: u32,
    w: u32,
    h: u32,
    pixel_angle: f64,
    params: MarchParams,
    opts: &'a Options,
}

/// Renders `scene` from its own camera: compiles the tape and renders the whole image.
/// `progress(done, total)` is called as tiles finish (from worker threads).
pub fn render(
    scene: &Scene,
    opts: &Options,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(Frame, Stats), TraceError> {
    opts.validate()?;
    scene.validate()?;
    let tape = Tape::compile(scene)?;
    let hooks = Hooks {
        cancel: None,
        progress,
    };
    render_tape(&tape, scene, &scene.camera, opts, None, hooks)
}

/// Renders the compiled `tape` (of `scene`, whose lights and render settings are used) from
/// `camera`: the whole output image, or only `region` of it (bit-identical to the same pixels
/// of the whole image). Post effects (SSAO, fog, supersampling, NaN scrubbing) are applied.
pub fn render_tape(
    tape: &Tape,
    scene: &Scene,
    camera: &Camera,
    opts: &Options,
    region: Option<Rect>,
    hooks: Hooks,
) -> Result<(Frame, Stats), TraceError> {
    let start = Instant::now();
    opts.validate()?;
    camera.validate()?;
    let (ow, oh) = opts.output_size();
    let region = region.unwrap_or(Rect::full(ow, oh));
    opts.check_region(region)?;
    let ss = opts.supersample;
    let (vw, vh) = (opts.width, opts.height);
    let (w, h) = (vw * ss, vh * ss);
    let projection = opts.projection;
    let cam = projection.frame(camera);
    let pixel_angle = projection.pixel_angle(&cam, w, h);
    let r = &scene.render;
    let params = MarchParams {
        t_max: r.max_distance,
        max_steps: r.max_steps,
        eps_slope: 0.5 * pixel_angle * r.pixel_epsilon,
        eps_min: 0.0,
        cone_slope: 0.0,
        cone_base: 0.0,
        omega: match opts.method {
            Method::Basic => 1.0,
            Method::Enhanced => OMEGA,
        },
    };
    let footprint = pixel_angle * (camera.target - camera.eye).length();
    let deep = footprint < DEEP_FOOTPRINT * camera.eye.length().max(1.0);
    let ssao = opts.ssao > 0.0 && !opts.geometry_only && projection.screen_space();
    let post = post_params(
        r,
        if ssao { opts.ssao } else { 0.0 },
        pixel_angle,
        opts.geometry_only,
        ss,
    );
    // Per eye: the region's pixels in that eye's view, the samples they need, and the tiles
    // that hold those samples (grown by the reach of SSAO).
    let margin = if ssao { post::SSAO_REACH } else { 0 };
    let mut jobs = Vec::new();
    for eye in 0..projection.eyes() {
        let (ex, ey) = projection.output_pixel(eye, 0, 0, vw, vh);
        let area = Rect {
            x: ex,
            y: ey,
            width: vw,
            height: vh,
        };
        let part = region.intersect(&area);
        if part.is_empty() {
            continue;
        }
        let keep = part.relative_to(ex, ey).scaled(ss);
        let traced = tiles_around(keep.grown(margin, w, h), w, h);
        jobs.push((eye, part, keep, traced));
    }
    let total: usize = jobs
        .iter()
        .map(|j| (j.3.width.div_ceil(TILE) * j.3.height.div_ceil(TILE)) as usize)
        .sum();
    let done = AtomicUsize::new(0);
    // One view that is the whole region (a mono render) is the output itself: no copy.
    let whole_view = jobs.len() == 1 && jobs[0].1 == region;
    let mut out = if whole_view {
        Frame::new(0, 0)
    } else {
        Frame::new(region.width, region.height)
    };
    let mut stats = Stats::default();
    for (eye, part, keep, traced) in jobs {
        if hooks.cancelled() {
            return Err(TraceError::Cancelled);
        }
        let ctx = Ctx {
            tape,
            scene,
            camera,
            cam,
            projection,
            eye,
            w,
            h,
            pixel_angle,
            params,
            opts,
        };
        let view_hooks = TileCounter {
            hooks: &hooks,
            done: &done,
            total,
        };
        let (frame, s) = if deep {
            trace_rect::<f64>(&ctx, traced, &view_hooks)
        } else {
            trace_rect::<F32x8>(&ctx, traced, &view_hooks)
        };
        if hooks.cancelled() {
            return Err(TraceError::Cancelled);
        }
        stats.add(&s);
        let t_post = Instant::now();
        let view = post::finish_view(frame, traced, keep, &post);
        stats.ms_post += t_post.elapsed().as_secs_f64() * 1e3;
        if whole_view {
            out = view;
        } else {
            out.paste(&view, part.x - region.x, part.y - region.y);
        }
    }
    stats.deep = deep;
    stats.width = out.width;
    stats.height = out.height;
    stats.ms_total = start.elapsed().as_secs_f64() * 1e3;
    Ok((out, stats))
}

/// The post effects the tracer runs on a view of a scene with render settings `r`: SSAO of
/// `ssao` (0: none), the scene's fog unless `geometry_only`, `supersample` samples per axis.
/// Shared with the double-double reference ([`crate::deep::deep_frame`]).
pub fn post_params(
    r: &RenderSettings,
    ssao: f32,
    pixel_angle: f64,
    geometry_only: bool,
    supersample: u32,
) -> PostParams {
    PostParams {
        ssao,
        pixel_angle: pixel_angle as f32,
        fog: if geometry_only { 0.0 } else { r.fog as f32 },
        fog_colour: r.sky_bottom.map(|c| c as f32),
        supersample,
    }
}

/// `r` rounded out to whole tiles of a `w` x `h` view (tiles start at multiples of [`TILE`]).
fn tiles_around(r: Rect, w: u32, h: u32) -> Rect {
    let (x0, y0) = (r.x / TILE * TILE, r.y / TILE * TILE);
    let x1 = r.right().div_ceil(TILE).saturating_mul(TILE).min(w);
    let y1 = r.bottom().div_ceil(TILE).saturating_mul(TILE).min(h);
    Rect {
        x: x0,
        y: y0,
        width: x1 - x0,
        height: y1 - y0,
    }
}

/// Progress over the tiles of every view of one render.
struct TileCounter<'a> {
    hooks: &'a Hooks<'a>,
    done: &'a AtomicUsize,
    total: usize,
}

struct TileOut {
    x0: u32,
    y0: u32,
    tw: u32,
    colour: Vec<[f32; 3]>,
    depth: Vec<f32>,
    normal: Vec<[f32; 3]>,
    id: Vec<u32>,
    steps: Vec<u32>,
    de_trace: u64,
    de_shade: u64,
    shadow_rays: u64,
}

/// Traces and shades the tiles of `rect` (tile-aligned, in the view's sample coordinates) of
/// one view: the prepass over the cells those pixels read, then the tiles in parallel. Returns
/// a frame of `rect`'s size (without post effects) and its counters.
fn trace_rect<S: Real>(ctx: &Ctx, rect: Rect, hooks: &TileCounter) -> (Frame, Stats) {
    let mut stats = Stats::default();
    let t0 = Instant::now();
    // Every ray may start at the distance bound measured at its eye; when the origin moves
    // with the pixel (ODS), at the camera position less the largest offset.
    let (e, slack) = match ctx.projection.eye_offset(&ctx.cam, ctx.eye) {
        Some(off) => (ctx.cam.eye + off, 0.0),
        None => (ctx.cam.eye, 0.5 * ctx.projection.separation()),
    };
    let d_eye = (Evaluator::<f64>::new()
        .distance(ctx.tape, V3::new(e.x, e.y, e.z))
        .max(0.0)
        - slack)
        .max(0.0);
    let t_start = if d_eye.is_finite() {
        (d_eye * 0.999) as f32
    } else {
        0.0
    };
    let grid = if ctx.opts.prepass {
        let view = View {
            tape: ctx.tape,
            cam: &ctx.cam,
            projection: ctx.projection,
            eye: ctx.eye,
            width: ctx.w,
            height: ctx.h,
            pixel_angle: ctx.pixel_angle,
            base: MarchParams {
                omega: 1.0,
                ..ctx.params
            },
            t_start,
        };
        let (g, evals) = prepass::run::<S>(&view, rect, &|| hooks.hooks.cancelled());
        stats.de_prepass = evals;
        g
    } else {
        StartGrid::uniform(t_start)
    };
    stats.ms_prepass = t0.elapsed().as_secs_f64() * 1e3;

    let t1 = Instant::now();
    let tx0 = rect.x / TILE;
    let ty0 = rect.y / TILE;
    let tiles_x = rect.width.div_ceil(TILE);
    let tiles_y = rect.height.div_ceil(TILE);
    let count = (tiles_x * tiles_y) as usize;
    let shading = Shading::new(
        ctx.tape,
        &ctx.scene.render,
        &ctx.scene.lights,
        (ctx.camera.target - ctx.camera.eye).length(),
    );
    let tiles: Vec<Option<TileOut>> = (0..count)
        .into_par_iter()
        .map_init(Evaluator::<S>::new, |ev, i| {
            if hooks.hooks.cancelled() {
                return None;
            }
            let tx = tx0 + i as u32 % tiles_x;
            let ty = ty0 + i as u32 / tiles_x;
            let out = tile::<S>(ctx, &grid, &shading, ev, tx * TILE, ty * TILE);
            let n = hooks.done.fetch_add(1, Ordering::Relaxed) + 1;
            (hooks.hooks.progress)(n, hooks.total);
            Some(out)
        })
        .collect();
    let mut frame = Frame::new(rect.width, rect.height);
    for t in tiles.iter().flatten() {
        for (k, ((((c, d), n), id), st)) in t
            .colour
            .iter()
            .zip(&t.depth)
            .zip(&t.normal)
            .zip(&t.id)
            .zip(&t.steps)
            .enumerate()
        {
            let x = t.x0 + k as u32 % t.tw - rect.x;
            let y = t.y0 + k as u32 / t.tw - rect.y;
            let j = frame.index(x, y);
            frame.colour[j] = *c;
            frame.depth[j] = *d;
            frame.normal[j] = *n;
            frame.id[j] = *id;
            frame.steps[j] = *st;
        }
        stats.de_trace += t.de_trace;
        stats.de_shade += t.de_shade;
        stats.shadow_rays += t.shadow_rays;
    }
    stats.primary_rays = rect.width as u64 * rect.height as u64;
    stats.hits = frame.depth.iter().filter(|d| d.is_finite()).count() as u64;
    stats.ms_trace = t1.elapsed().as_secs_f64() * 1e3;
    (frame, stats)
}

/// Traces and shades the tile whose top-left pixel is (`x0`, `y0`).
fn tile<S: Real>(
    ctx: &Ctx,
    grid: &StartGrid,
    shading: &Shading,
    ev: &mut Evaluator<S>,
    x0: u32,
    y0: u32,
) -> TileOut {
    let tw = TILE.min(ctx.w - x0);
    let th = TILE.min(ctx.h - y0);
    let n = (tw * th) as usize;
    let mut out = TileOut {
        x0,
        y0,
        tw,
        colour: vec![[0.0; 3]; n],
        depth: vec![f32::INFINITY; n],
        normal: vec![[0.0; 3]; n],
        id: vec![NO_ID; n],
        steps: vec![0; n],
        de_trace: 0,
        de_shade: 0,
        shadow_rays: 0,
    };
    // Pixels in 4x2 blocks so a packet covers a compact patch.
    let mut order = Vec::with_capacity(n);
    for by in (0..th).step_by(2) {
        for bx in (0..tw).step_by(4) {
            for y in by..(by + 2).min(th) {
                for x in bx..(bx + 4).min(tw) {
                    order.push((x, y));
                }
            }
        }
    }
    let lanes3 = |a: &[[f64; 8]; 3]| {
        V3::new(
            S::from_lanes(&a[0][..S::LANES]),
            S::from_lanes(&a[1][..S::LANES]),
            S::from_lanes(&a[2][..S::LANES]),
        )
    };
    // Hits to colour: (index in the tile, ray direction, distance, ray origin).
    let mut hits: Vec<(usize, [f64; 3], f64, [f64; 3])> = Vec::new();
    for packet in order.chunks(S::LANES) {
        let mut d = [[0f64; 8]; 3];
        let mut o = [[0f64; 8]; 3];
        let mut origins = [[0f64; 3]; 8];
        let mut t0 = [0f64; 8];
        let mut live = [0f64; 8];
        let mut dirs = [[0f64; 3]; 8];
        for l in 0..S::LANES {
            let (x, y) = packet[l.min(packet.len() - 1)];
            let (px, py) = ((x0 + x) as f64 + 0.5, (y0 + y) as f64 + 0.5);
            let (off, dv) = ctx.projection.ray(&ctx.cam, ctx.eye, px, py, ctx.w, ctx.h);
            dirs[l] = [dv.x, dv.y, dv.z];
            (d[0][l], d[1][l], d[2][l]) = (dv.x, dv.y, dv.z);
            let ov = ctx.cam.eye + off;
            origins[l] = [ov.x, ov.y, ov.z];
            (o[0][l], o[1][l], o[2][l]) = (ov.x, ov.y, ov.z);
            t0[l] = grid.start_at(px, py) as f64;
            live[l] = if l < packet.len() { 0.0 } else { 1.0 };
        }
        let dir = lanes3(&d);
        let origin = lanes3(&o);
        let live = S::from_lanes(&live[..S::LANES]).lt(S::splat(0.5));
        let m = march(
            ev,
            ctx.tape,
            origin,
            dir,
            S::from_lanes(&t0[..S::LANES]),
            live,
            &ctx.params,
        );
        let hit_any = m.hit & live;
        for (l, &(x, y)) in packet.iter().enumerate() {
            let k = (y * tw + x) as usize;
            let st = m.steps.lane(l);
            out.steps[k] = st as u32;
            out.de_trace += st as u64;
            let t = m.t.lane(l);
            let is_hit = hit_any.any() && lane_set::<S>(m.hit, l);
            if is_hit && t.is_finite() {
                out.depth[k] = t as f32;
                hits.push((k, dirs[l], t, origins[l]));
            } else {
                out.colour[k] = shading.sky(dirs[l]);
            }
        }
    }
    // Colouring pass over the hits, repacked densely.
    let mut shaded = [Shaded::default(); 8];
    for packet in hits.chunks(S::LANES) {
        let mut d = [[0f64; 8]; 3];
        let mut o = [[0f64; 8]; 3];
        let mut t = [0f64; 8];
        let mut live = [0f64; 8];
        for l in 0..S::LANES {
            let (_, dv, tt, ov) = packet[l.min(packet.len() - 1)];
            (d[0][l], d[1][l], d[2][l]) = (dv[0], dv[1], dv[2]);
            (o[0][l], o[1][l], o[2][l]) = (ov[0], ov[1], ov[2]);
            t[l] = tt;
            live[l] = if l < packet.len() { 0.0 } else { 1.0 };
        }
        if ctx.opts.geometry_only {
            // Geometry only: the id from one evaluation at the hit, no lighting.
            let p = lanes3(&d) * S::from_lanes(&t[..S::LANES]) + lanes3(&o);
            let v = ev.eval(ctx.tape, p);
            for (l, &(k, _, _, _)) in packet.iter().enumerate() {
                out.id[k] = v.id.lane(l).max(0.0) as u32;
            }
            continue;
        }
        let dir = lanes3(&d);
        let origin = lanes3(&o);
        let tv = S::from_lanes(&t[..S::LANES]);
        let live = S::from_lanes(&live[..S::LANES]).lt(S::splat(0.5));
        out.de_shade += shade_hits(
            ev,
            shading,
            origin,
            dir,
            tv,
            ctx.pixel_angle,
            live,
            &mut shaded,
        );
        out.shadow_rays += (packet.len() * shading.lights.iter().filter(|l| l.2).count()) as u64;
        for (l, &(k, _, _, _)) in packet.iter().enumerate() {
            out.colour[k] = shaded[l].colour;
            out.normal[k] = shaded[l].normal;
            out.id[k] = shaded[l].id;
        }
    }
    out
}

/// Whether lane `l` of a mask is set (masks have no per-lane accessor, so select on it).
#[inline]
fn lane_set<S: Real>(m: S::Mask, l: usize) -> bool {
    S::select(m, S::one(), S::zero()).lane(l) != 0.0
}
