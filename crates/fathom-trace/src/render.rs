//! One frame: validation, the prepass, primary rays over tiles in parallel, shading, post.
//!
//! Tiles of 16x16 pixels are spread over rayon's pool, each task with its own evaluator. Inside
//! a tile, rays go in packets of eight (4x2 pixel blocks) on the f32 SIMD path. Every lane's
//! result depends only on its own ray, and per-tile results are written back in tile order, so
//! the image does not depend on the number of threads.
//!
//! Stereo ([`Projection`]): each eye is rendered as a view of its own (prepass, tiles, post
//! effects), then the views are laid out side by side or top/bottom (`crate::stereo`). SSAO is
//! skipped for omni-directional stereo: screen space does not apply across the
//! equirectangular wrap and its stretched poles.
//!
//! Deep zoom: f32 positions have about 7 significant digits. When the pixel footprint at the
//! target falls below `DEEP_FOOTPRINT` times the camera's distance from the origin (or 1), the
//! whole frame switches to the f64 path (one ray per packet; slow but exact).

use crate::post;
use crate::prepass::{self, StartGrid, View};
use crate::shade::{Shaded, Shading, shade};
use crate::tracer::{MarchParams, Method, OMEGA, march};
use fathom_core::frame::{Frame, NO_ID};
use fathom_core::real::{Mask, Real};
use fathom_core::{Evaluator, F32x8, Projection, Scene, Tape, V3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
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
#[derive(Clone, Debug)]
pub struct Options {
    pub width: u32,
    pub height: u32,
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

impl Options {
    /// Checks sizes and sample counts against the documented limits, before any allocation.
    pub fn validate(&self) -> Result<(), String> {
        if self.width == 0 || self.height == 0 {
            return Err(format!(
                "image size {}x{} is empty",
                self.width, self.height
            ));
        }
        self.projection.validate()?;
        if self.width > MAX_SIDE || self.height > MAX_SIDE {
            return Err(format!(
                "image size {}x{} exceeds the limit of {MAX_SIDE} pixels per side",
                self.width, self.height
            ));
        }
        let (ow, oh) = self.projection.output_size(self.width, self.height);
        if ow > MAX_SIDE || oh > MAX_SIDE {
            return Err(format!(
                "stereo output size {ow}x{oh} ({}x{} per eye) exceeds the limit of {MAX_SIDE} pixels per side",
                self.width, self.height
            ));
        }
        if !(1..=MAX_SUPERSAMPLE).contains(&self.supersample) {
            return Err(format!(
                "supersample = {} is out of range [1, {MAX_SUPERSAMPLE}]",
                self.supersample
            ));
        }
        let px = ow as u64 * oh as u64 * (self.supersample as u64).pow(2);
        if px > MAX_PIXELS {
            return Err(format!(
                "{ow}x{oh} with {}x{} supersampling is {px} samples; the limit is {MAX_PIXELS}",
                self.supersample, self.supersample
            ));
        }
        if !(self.ssao.is_finite() && (0.0..=4.0).contains(&self.ssao)) {
            return Err(format!("ssao = {} is out of range [0, 4]", self.ssao));
        }
        Ok(())
    }
}

/// Counters and timings of one render. Sums are integers, so they do not depend on threads.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    pub width: u32,
    pub height: u32,
    /// Whether the f64 (deep zoom) path ran.
    pub deep: bool,
    pub primary_rays: u64,
    /// Shadow rays (one per lit hit and shadowing light).
    pub shadow_rays: u64,
    /// Distance evaluations per pass (per ray lane).
    pub de_prepass: u64,
    pub de_trace: u64,
    pub de_shade: u64,
    /// Primary rays that hit a surface.
    pub hits: u64,
    pub ms_prepass: f64,
    pub ms_trace: f64,
    pub ms_post: f64,
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

struct Ctx<'a> {
    tape: &'a Tape,
    scene: &'a Scene,
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

/// Renders `scene`. `progress(done, total)` is called as tiles finish (from worker threads).
pub fn render(
    scene: &Scene,
    opts: &Options,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(Frame, Stats), String> {
    let start = Instant::now();
    opts.validate()?;
    scene.validate()?;
    let tape = Tape::compile(scene).map_err(|e| e.to_string())?;
    let ss = opts.supersample;
    let (w, h) = (opts.width * ss, opts.height * ss);
    let projection = opts.projection;
    let cam = projection.frame(&scene.camera);
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
    let footprint = pixel_angle * (scene.camera.target - scene.camera.eye).length();
    let deep = footprint < DEEP_FOOTPRINT * scene.camera.eye.length().max(1.0);
    let eyes = projection.eyes();
    let mut views = Vec::with_capacity(eyes as usize);
    let mut stats = Stats::default();
    for eye in 0..eyes {
        let ctx = Ctx {
            tape: &tape,
            scene,
            cam,
            projection,
            eye,
            w,
            h,
            pixel_angle,
            params,
            opts,
        };
        let progress = |done: usize, total: usize| {
            progress(done + eye as usize * total, total * eyes as usize);
        };
        let (mut frame, s) = if deep {
            render_with::<f64>(&ctx, &progress)
        } else {
            render_with::<F32x8>(&ctx, &progress)
        };
        stats.add(&s);
        let t_post = Instant::now();
        if opts.ssao > 0.0 && !opts.geometry_only && projection.screen_space() {
            post::ssao(&mut frame, opts.ssao, pixel_angle as f32);
        }
        if r.fog > 0.0 && !opts.geometry_only {
            post::fog(&mut frame, r.fog as f32, r.sky_bottom.map(|c| c as f32));
        }
        if ss > 1 {
            frame = post::downsample(&frame, ss);
        }
        post::sanitize(&mut frame);
        stats.ms_post += t_post.elapsed().as_secs_f64() * 1e3;
        views.push(frame);
    }
    stats.deep = deep;
    let frame = crate::stereo::assemble(projection, views);
    stats.width = frame.width;
    stats.height = frame.height;
    stats.ms_total = start.elapsed().as_secs_f64() * 1e3;
    Ok((frame, stats))
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

fn render_with<S: Real>(ctx: &Ctx, progress: &(dyn Fn(usize, usize) + Sync)) -> (Frame, Stats) {
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
        let (g, evals) = prepass::run::<S>(&view);
        stats.de_prepass = evals;
        g
    } else {
        StartGrid::uniform(t_start)
    };
    stats.ms_prepass = t0.elapsed().as_secs_f64() * 1e3;

    let t1 = Instant::now();
    let tiles_x = ctx.w.div_ceil(TILE);
    let tiles_y = ctx.h.div_ceil(TILE);
    let total = (tiles_x * tiles_y) as usize;
    let done = AtomicUsize::new(0);
    let shading = Shading::new(
        ctx.tape,
        &ctx.scene.render,
        &ctx.scene.lights,
        (ctx.scene.camera.target - ctx.scene.camera.eye).length(),
    );
    let tiles: Vec<TileOut> = (0..total)
        .into_par_iter()
        .map_init(Evaluator::<S>::new, |ev, i| {
            let tx = i as u32 % tiles_x;
            let ty = i as u32 / tiles_x;
            let out = tile::<S>(ctx, &grid, &shading, ev, tx * TILE, ty * TILE);
            let n = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(n, total);
            out
        })
        .collect();
    let mut frame = Frame::new(ctx.w, ctx.h);
    for t in &tiles {
        for (k, ((((c, d), n), id), st)) in t
            .colour
            .iter()
            .zip(&t.depth)
            .zip(&t.normal)
            .zip(&t.id)
            .zip(&t.steps)
            .enumerate()
        {
            let x = t.x0 + k as u32 % t.tw;
            let y = t.y0 + k as u32 / t.tw;
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
    stats.primary_rays = ctx.w as u64 * ctx.h as u64;
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
        let footprint = tv * S::splat(ctx.pixel_angle);
        out.de_shade += shade(ev, shading, origin, dir, tv, footprint, live, &mut shaded);
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
