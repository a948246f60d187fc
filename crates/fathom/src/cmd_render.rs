//! `fathom render`: a scene file or preset to an image, with diagnostic outputs (hit mask,
//! depth EXR, step heat map, JSON statistics). The flags become a [`RenderRequest`] and the
//! session renders it; this module only loads the scene, opens the outputs first (so a bad path
//! fails before any work), drives the progress bar and writes the files.

use crate::args::{parse_size, parse_vec};
use clap::{Args, ValueEnum};
use fathom_core::camera::MAX_EYE_SEPARATION;
use fathom_core::scene::Scene;
use fathom_core::{Projection, presets, scene_file};
use fathom_render::{Backend, Control, PathRequest, Progress, RenderRequest, Session, TracerRule};
use fathom_trace::output;
use glam::DVec3;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Sphere-tracing step rule.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum TracerKind {
    /// Step by the distance bound (Hart).
    Basic,
    /// Over-relaxed steps with a safe fallback (Keinert et al. 2014).
    Enhanced,
}

/// Render a scene to a PNG.
///
/// Examples:
///   fathom render --preset mandelbulb -o bulb.png
///   fathom render my.ron -o my.png --size 1920x1080 --supersample 2
///   fathom render --preset mandelbulb --eye 0,0,2 --fov 30 -o close.png
///   fathom render --preset mandelbulb -o b.png --steps steps.png --stats stats.json
///   fathom render --preset mandelbulb --gpu -o gpu.png
///   fathom render --preset mandelbulb --gpu --stereo ods --size 2048x1024 -o vr.png
///   fathom render --preset menger --stereo sbs --size 640x480 -o pair.png
///   fathom render --preset mandelbulb -o layers.exr          colour, mask, depth, normal, id
///   fathom render --preset mandelbulb --bit-depth 16 -o deep.png
///   fathom render --preset menger --integrator path --spp 256 --denoise -o lit.png
///   fathom render --preset mandelbulb --integrator path --time-limit 30s --aperture 0.02 -o dof.png
///   fathom render docs/examples/mandelbulb-dive.ron --path dive --frames 300 -o dive/
///   fathom render docs/examples/mandelbulb-dive.ron --path dive --frames 300 \
///       -o shots/dive-####.exr --camera-path shots/dive.glb
///   fathom render --preset menger --size 8192x8192 --tiles 64 --shard 3/64 -o poster/
///   fathom render docs/examples/mandelbulb-dive.ron --path dive --frames 300 --shard 0/8 -o dive/
///   (farm shards: see `fathom farm --help`; then `fathom farm assemble poster/ -o poster.png`)
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct RenderArgs {
    /// Scene file (.ron); omit to use --preset or the default preset.
    pub scene: Option<PathBuf>,
    /// Built-in preset (see `fathom list presets`).
    #[arg(long, conflicts_with = "scene")]
    pub preset: Option<String>,
    /// Output image: .png (tonemapped sRGB, 8 or 16 bits, see --bit-depth) or .exr (layers
    /// for compositing: linear R G B, A mask, Z depth, normal.X/Y/Z, id material).
    #[arg(short, long, default_value = "fathom.png")]
    pub output: PathBuf,
    /// Bits per channel of a PNG output: 8 or 16.
    #[arg(long, default_value_t = 8)]
    pub bit_depth: u8,
    /// Image size WIDTHxHEIGHT, each side at most 16384 and at most 64 Mpixel in all
    /// [default: 1280x720, or a Mandelbulber .fract file's own image size].
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Camera position x,y,z (overrides the scene).
    #[arg(long, value_parser = parse_vec, allow_hyphen_values = true)]
    pub eye: Option<DVec3>,
    /// Point the camera looks at x,y,z.
    #[arg(long, value_parser = parse_vec, allow_hyphen_values = true)]
    pub target: Option<DVec3>,
    /// Camera up vector x,y,z.
    #[arg(long, value_parser = parse_vec, allow_hyphen_values = true)]
    pub up: Option<DVec3>,
    /// Vertical field of view in degrees, (0, 179].
    #[arg(long)]
    pub fov: Option<f64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Sphere-tracing step rule.
    #[arg(long, value_enum, default_value = "enhanced")]
    pub tracer: TracerKind,
    /// Skip the cone-marching depth prepass.
    #[arg(long)]
    pub no_prepass: bool,
    /// Samples per pixel along each axis, [1, 4].
    #[arg(long, default_value_t = 1)]
    pub supersample: u32,
    /// Screen-space ambient occlusion strength on top of the distance-field AO, [0, 4].
    #[arg(long, default_value_t = 0.0)]
    pub ssao: f32,
    /// Also write a mask PNG: white where a ray hit.
    #[arg(long)]
    pub mask: Option<PathBuf>,
    /// Also write the ray distance per pixel as EXR (misses at the scene's max_distance).
    #[arg(long)]
    pub depth: Option<PathBuf>,
    /// Also write a heat map PNG of distance evaluations per pixel.
    #[arg(long)]
    pub steps: Option<PathBuf>,
    /// Also write statistics as JSON (rays, evaluations, steps per pixel, ms per pass).
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
    /// Render on the GPU (wgpu), the same as `--renderer gpu`. Without any adapter it says so
    /// and suggests the CPU path; a view zoomed past f32 precision is rendered on the CPU.
    #[arg(long)]
    pub gpu: bool,
    /// Stereo: `sbs` (side by side, twice as wide) or `ods` (360-degree equirectangular, left
    /// eye on top, twice as tall; use a 2:1 --size). --size is one eye's view. Not with
    /// --renderer svo.
    #[arg(long, value_enum)]
    pub stereo: Option<StereoKind>,
    /// Distance between the eyes for --stereo, in scene units.
    #[arg(long, default_value_t = 0.065)]
    pub eye_separation: f64,
    /// Renderer: the CPU sphere tracer, the GPU (wgpu), or the sparse voxel octree (settled
    /// at this view).
    #[arg(long, value_enum, default_value = "trace")]
    pub renderer: RendererKind,
    /// Fly the scene's flight path NAME (see docs/scene-format.md) and write --frames frames:
    /// -o is a directory (frames DIR/NAME-00000.png, and DIR/NAME.mp4 when ffmpeg is on PATH)
    /// or a pattern such as shots/f-####.png.
    #[arg(long, requires = "frames")]
    pub path: Option<String>,
    /// Frames of the path to render, [1, 1000000]; the first at its start, the last at its end.
    #[arg(long, requires = "path")]
    pub frames: Option<usize>,
    /// Frame rate of the video made from a path's frames.
    #[arg(long, default_value_t = 24.0)]
    pub fps: f64,
    /// Do not make a video from a path's frames even when ffmpeg is on PATH.
    #[arg(long)]
    pub no_video: bool,
    /// With --path: also write the frames' cameras as a glTF animation (.glb), so Blender and
    /// other tools can match the rendered sequence (a path that changes the fov animates it
    /// through the glTF extension KHR_animation_pointer; docs/files.md).
    #[arg(long, requires = "path")]
    pub camera_path: Option<PathBuf>,
    /// How light is computed: `preview`, the fast sphere tracer with Blinn-Phong shading
    /// (the default, and what --renderer chooses among), or `path`, the progressive path
    /// tracer (global illumination, soft shadows, glossy and glass materials, depth of field;
    /// with --gpu on the GPU, which has no fog, sphere lights or environment maps yet).
    /// `--integrator path` takes --spp or --time-limit, --bounces, --aperture,
    /// --focus-distance and --denoise.
    #[arg(long, value_enum, default_value = "preview")]
    pub integrator: IntegratorKind,
    /// With --integrator path: samples per pixel, [1, 1048576]; the noise falls as 1/sqrt(spp)
    /// (64 is a clean preview, 1024 a print) [default: 64, or with --time-limit as many as fit].
    /// With --time-limit, the most samples to take.
    #[arg(long)]
    pub spp: Option<u32>,
    /// With --integrator path: take samples for this long instead of a count, e.g. 30s, 2m,
    /// 1.5 (seconds); at least one sample per pixel is always taken.
    /// (Named apart from `fathom farm slurm --time`, Slurm's own wall-time limit.)
    #[arg(long, value_parser = parse_duration)]
    pub time_limit: Option<f64>,
    /// With --integrator path: surface and fog interactions per path, [1, 256] (glass and
    /// deep crevices need more).
    #[arg(long, default_value_t = 8)]
    pub bounces: u32,
    /// With --integrator path: lens radius in scene units for depth of field, [0, 1e6]
    /// (0: everything sharp).
    #[arg(long, default_value_t = 0.0)]
    pub aperture: f64,
    /// With --integrator path: distance from the eye to the plane in focus [default: the
    /// distance to the camera's target].
    #[arg(long)]
    pub focus_distance: Option<f64>,
    /// With --integrator path: filter the noise away, guided by the first hit's albedo,
    /// normal and depth (`atrous`, the default: edge-aware à-trous wavelets; `oidn`: Intel
    /// Open Image Denoise, when built with it).
    #[arg(long, value_enum, num_args = 0..=1, default_missing_value = "atrous")]
    pub denoise: Option<DenoiserKind>,
    /// With --integrator path: the sampler's seed (another seed, independent noise).
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// Render farm: cut the still into N tiles, units of a farm job in the directory -o DIR
    /// (with --shard, only that shard's tiles; else all, or the Slurm array task's share).
    #[arg(long, value_name = "N", conflicts_with = "path")]
    pub tiles: Option<usize>,
    /// Render farm: render shard I of N of the job's units (tiles with --tiles, frames with
    /// --path) into the job directory -o DIR; units already done are skipped. Without a
    /// value: from SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT. Assemble the result with
    /// `fathom farm assemble DIR`.
    #[arg(long, value_name = "I/N", num_args = 0..=1, default_missing_value = "")]
    pub shard: Option<String>,
}

/// Which renderer `fathom render` uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RendererKind {
    /// The CPU sphere tracer.
    Trace,
    /// The WGSL tape interpreter through wgpu.
    Gpu,
    /// The sparse voxel octree, subdivided until settled at the view.
    Svo,
    /// The scene's interior as a cloud, path-traced (fathom-volume at its session defaults;
    /// `fathom volume` has every setting). --supersample S renders 2 S^2 samples per pixel.
    Volume,
}

/// How `fathom render` computes light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum IntegratorKind {
    /// Sphere tracing with Blinn-Phong shading, soft shadows and ambient occlusion: fast.
    Preview,
    /// Progressive Monte Carlo path tracing: global illumination, materials, depth of field.
    Path,
}

/// The denoiser of `--denoise`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DenoiserKind {
    /// fathom's edge-aware à-trous wavelet filter.
    Atrous,
    /// Intel Open Image Denoise.
    Oidn,
}

/// Parses a duration: `30s`, `2m`, `1h`, `250ms` or plain seconds (`1.5`).
pub fn parse_duration(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let (num, unit) = match t.find(|c: char| c.is_ascii_alphabetic()) {
        Some(i) => t.split_at(i),
        None => (t, "s"),
    };
    let k = match unit {
        "ms" => 1e-3,
        "s" => 1.0,
        "m" | "min" => 60.0,
        "h" => 3600.0,
        _ => {
            return Err(format!(
                "`{s}`: the unit `{unit}` is not one of ms, s, m, h (e.g. 30s, 2m)"
            ));
        }
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a duration (e.g. 30s, 2m, 1.5)"))?;
    let secs = v * k;
    if !(secs.is_finite() && secs > 0.0 && secs <= 1e6) {
        return Err(format!("`{s}` is out of range (0, 1e6] seconds"));
    }
    Ok(secs)
}

impl RendererKind {
    /// The flag's value.
    fn name(self) -> &'static str {
        match self {
            RendererKind::Trace => "trace",
            RendererKind::Gpu => "gpu",
            RendererKind::Svo => "svo",
            RendererKind::Volume => "volume",
        }
    }
}

/// Stereo layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum StereoKind {
    /// Side-by-side pair of parallel pinhole views.
    Sbs,
    /// Omni-directional stereo, equirectangular, top (left eye) / bottom (right eye).
    Ods,
}

/// Loads the scene named by the arguments and applies the camera overrides.
pub(crate) fn load_scene(a: &RenderArgs) -> Result<Scene, String> {
    let mut scene = match (&a.scene, &a.preset) {
        (Some(path), _) => scene_file::load(path).map_err(|e| e.to_string())?,
        (None, Some(p)) => presets::load(p).map_err(|e| e.to_string())?,
        (None, None) => presets::load(presets::DEFAULT_PRESET).map_err(|e| e.to_string())?,
    };
    let c = &mut scene.camera;
    if let Some(v) = a.eye {
        c.eye = v;
    }
    if let Some(v) = a.target {
        c.target = v;
    }
    if let Some(v) = a.up {
        c.up = v;
    }
    if let Some(v) = a.fov {
        c.fov = v;
    }
    scene.validate().map_err(|e| e.to_string())?;
    Ok(scene)
}

/// Checks the stereo flags (naming them) and turns them into a [`Projection`].
fn projection(a: &RenderArgs, backend: Backend) -> Result<Projection, String> {
    let sep = a.eye_separation;
    if !(sep.is_finite() && (0.0..=MAX_EYE_SEPARATION).contains(&sep)) {
        return Err(format!(
            "--eye-separation = {sep} is out of range [0, {MAX_EYE_SEPARATION}] (scene units)"
        ));
    }
    if backend == Backend::Octree && a.stereo.is_some() {
        return Err(
            "--stereo is not supported by --renderer svo (the octree renders one mono \
             view); leave out --renderer svo to render stereo with the sphere tracer"
                .into(),
        );
    }
    Ok(match a.stereo {
        None => Projection::Mono,
        Some(StereoKind::Sbs) => Projection::SideBySide {
            eye_separation: sep,
        },
        Some(StereoKind::Ods) => Projection::Ods {
            eye_separation: sep,
        },
    })
}

impl RenderArgs {
    /// The arguments of a bare `fathom render`, taken from the clap declarations so a new flag
    /// needs no second default here.
    pub fn defaults() -> RenderArgs {
        crate::clap_defaults()
    }

    /// The backend the flags choose.
    fn backend(&self) -> Result<Backend, String> {
        if self.integrator == IntegratorKind::Path {
            if !matches!(self.renderer, RendererKind::Trace | RendererKind::Gpu) {
                return Err(format!(
                    "--integrator path and --renderer {} choose two renderers; pick one",
                    self.renderer.name()
                ));
            }
            if self.denoise == Some(DenoiserKind::Oidn) {
                return Err(
                    "--denoise oidn: this build has no Intel Open Image Denoise \
                     (it is not packaged for this system); --denoise (à-trous) is built in"
                        .into(),
                );
            }
            return Ok(Backend::Path);
        }
        for (given, flag) in [
            (self.spp.is_some(), "--spp"),
            (self.time_limit.is_some(), "--time-limit"),
            (self.denoise.is_some(), "--denoise"),
            (self.aperture != 0.0, "--aperture"),
            (self.focus_distance.is_some(), "--focus-distance"),
        ] {
            if given {
                return Err(format!(
                    "{flag} belongs to the path tracer; add --integrator path"
                ));
            }
        }
        Ok(match (self.gpu, self.renderer) {
            (true, RendererKind::Svo) => {
                return Err("--gpu and --renderer svo choose two renderers; pick one".into());
            }
            (true, RendererKind::Volume) => {
                return Err("--gpu and --renderer volume choose two renderers; pick one".into());
            }
            (true, _) | (false, RendererKind::Gpu) => Backend::Gpu,
            (false, RendererKind::Trace) => Backend::Trace,
            (false, RendererKind::Svo) => Backend::Octree,
            (false, RendererKind::Volume) => Backend::Volume,
        })
    }

    /// The request these flags describe, checked.
    pub fn request(&self) -> Result<RenderRequest, String> {
        let backend = self.backend()?;
        let (width, height) = self.size.unwrap_or(DEFAULT_SIZE);
        let req = RenderRequest {
            width,
            height,
            projection: projection(self, backend)?,
            supersample: self.supersample,
            prepass: !self.no_prepass,
            tracer: match self.tracer {
                TracerKind::Basic => TracerRule::Basic,
                TracerKind::Enhanced => TracerRule::Enhanced,
            },
            ssao: self.ssao,
            backend,
            threads: self.threads,
            path: PathRequest {
                spp: match (self.spp, self.time_limit) {
                    (Some(n), _) => n,
                    (None, Some(_)) => fathom_render::request::MAX_PATH_SPP,
                    (None, None) => DEFAULT_SPP,
                },
                time_limit: self.time_limit,
                max_bounces: self.bounces,
                aperture: self.aperture,
                focus_distance: self.focus_distance,
                denoise: self.denoise.is_some(),
                seed: self.seed,
                gpu: self.gpu || self.renderer == RendererKind::Gpu,
            },
            ..RenderRequest::default()
        };
        req.validate().map_err(|e| e.to_string())?;
        Ok(req)
    }
}

fn open(
    p: &Option<PathBuf>,
) -> Result<Option<(fathom_core::atomic_file::AtomicFile, &Path)>, String> {
    p.as_deref()
        .map(|p| {
            output::open_output(p)
                .map(|f| (f, p))
                .map_err(|e| e.to_string())
        })
        .transpose()
}

fn progress_bar(quiet: bool) -> Result<indicatif::ProgressBar, String> {
    if quiet {
        return Ok(indicatif::ProgressBar::hidden());
    }
    let b = indicatif::ProgressBar::new(0);
    b.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} rendering [{bar:40}] {percent}% {elapsed}",
        )
        .map_err(|e| e.to_string())?
        .progress_chars("=> "),
    );
    Ok(b)
}

/// Samples per pixel of `--integrator path` without --spp or --time.
pub const DEFAULT_SPP: u32 = 64;

/// Path tracing in passes of whole samples per pixel, so the progress bar can say how many
/// samples are done, at what rate, and how much noise is left; the denoiser (if asked) runs
/// once at the end. Returns the final frame with statistics of the whole render.
fn render_path(
    session: &mut Session,
    camera: &fathom_core::Camera,
    req: &RenderRequest,
    quiet: bool,
) -> Result<fathom_render::Rendered, String> {
    let start = Instant::now();
    let target = req.path.spp;
    let limit = req.path.time_limit;
    let bar = if quiet {
        indicatif::ProgressBar::hidden()
    } else {
        let b = indicatif::ProgressBar::new(match limit {
            Some(t) => (t * 1e3) as u64,
            None => target as u64,
        });
        let template = match limit {
            Some(_) => "{spinner} path tracing [{bar:40}] {elapsed}/{duration} {msg}",
            None => "{spinner} path tracing [{bar:40}] {pos}/{len} spp {elapsed}, {eta} left {msg}",
        };
        b.set_style(
            indicatif::ProgressStyle::with_template(template)
                .map_err(|e| e.to_string())?
                .progress_chars("=> "),
        );
        b.enable_steady_tick(std::time::Duration::from_millis(200));
        b
    };
    let mut pass = req.clone();
    pass.path.denoise = false;
    pass.path.time_limit = None;
    let mut spp = 0u32;
    // Samples per call: one at first, then about a quarter of a second's worth, so small
    // images do not spend their time between passes.
    let mut step = 1u32;
    while spp < target && limit.is_none_or(|t| spp == 0 || start.elapsed().as_secs_f64() < t) {
        let t0 = Instant::now();
        pass.path.spp = spp.saturating_add(step).min(target);
        let r = session.render(camera, &pass).map_err(|e| e.to_string())?;
        let p = r.stats.path.expect("the path backend reports its samples");
        let added = p.samples_per_pixel - spp;
        spp = p.samples_per_pixel;
        let per_sample = t0.elapsed().as_secs_f64() / added.max(1) as f64;
        step = ((0.25 / per_sample.max(1e-6)) as u32).clamp(1, 1024);
        if let Some(t) = limit {
            let left = (t - start.elapsed().as_secs_f64()).max(0.0);
            step = step.min(((left / per_sample.max(1e-6)) as u32).max(1));
        }
        bar.set_position(match limit {
            Some(_) => (start.elapsed().as_secs_f64() * 1e3) as u64,
            None => spp as u64,
        });
        bar.set_message(format!(
            "{}{:.2} M paths/s, noise {:.1} %",
            if limit.is_some() {
                format!("{spp} spp, ")
            } else {
                String::new()
            },
            p.paths_per_second / 1e6,
            p.relative_noise * 100.0
        ));
    }
    bar.finish_and_clear();
    let mut last = req.clone();
    last.path.spp = spp;
    last.path.time_limit = None;
    let mut r = session.render(camera, &last).map_err(|e| e.to_string())?;
    r.stats.primary_rays = spp as u64 * req.width as u64 * req.height as u64;
    r.stats.ms.trace_and_shade = start.elapsed().as_secs_f64() * 1e3 - r.stats.ms.post;
    Ok(r)
}

/// The image size of `fathom render` without --size.
pub const DEFAULT_SIZE: (u32, u32) = (1280, 720);

/// A Mandelbulber `.fract` scene renders at its own image size unless --size says otherwise
/// (its camera's framing belongs to that aspect ratio).
pub fn size_from_fract(a: &mut RenderArgs) -> Result<(), String> {
    if a.size.is_some() {
        return Ok(());
    }
    if let Some(path) = a.scene.as_deref().filter(|p| {
        p.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("fract"))
    }) {
        let imported = fathom_core::scene_file::fract::load(path).map_err(|e| e.to_string())?;
        a.size = Some(imported.image_size);
    }
    Ok(())
}

/// `fathom render` of one image (`--shard`/`--tiles` and `--path` are dispatched by
/// [`crate::render`] before this).
pub fn run(mut a: RenderArgs) -> Result<(), String> {
    let start = Instant::now();
    size_from_fract(&mut a)?;
    let req = a.request()?;
    let kind = output::ImageKind::for_path(&a.output, a.bit_depth).map_err(|e| e.to_string())?;
    let scene = load_scene(&a)?;
    // Open every output before rendering, so a bad path fails fast.
    let out = output::open_output(&a.output).map_err(|e| e.to_string())?;
    let mask = open(&a.mask)?;
    let depth = open(&a.depth)?;
    let steps = open(&a.steps)?;
    let stats_file = open(&a.stats)?;

    let far = scene.render.max_distance as f32;
    let camera = scene.camera.clone();
    let mut session = Session::new(scene).map_err(|e| e.to_string())?;
    let bar = progress_bar(a.quiet)?;
    let progress = |p: Progress| {
        bar.set_length(p.total as u64);
        bar.set_position(p.done as u64);
    };
    let control = Control {
        cancel: None,
        progress: Some(&progress),
    };
    let r = if req.backend == Backend::Path {
        render_path(&mut session, &camera, &req, a.quiet)?
    } else {
        session
            .render_with(&camera, &req, &control)
            .map_err(|e| e.to_string())?
    };
    bar.finish_and_clear();
    if let Some(note) = &r.stats.note {
        eprintln!("fathom: note: {note}");
    }
    let frame = &r.frame;
    output::save_image(frame, kind, far, out, &a.output).map_err(|e| e.to_string())?;
    if let Some((f, p)) = mask {
        output::save_mask(frame, f, p).map_err(|e| e.to_string())?;
    }
    if let Some((f, p)) = depth {
        output::save_depth(frame, far, f, p).map_err(|e| e.to_string())?;
    }
    if let Some((f, p)) = steps {
        output::save_steps(frame, f, p).map_err(|e| e.to_string())?;
    }
    if let Some((f, p)) = stats_file {
        output::save_json(&r.stats, f, p).map_err(|e| e.to_string())?;
    }
    if !a.quiet {
        if let Some(o) = &r.stats.octree {
            eprintln!(
                "svo: settled in {} frames, {} nodes, {:.1} nodes per ray",
                o.settle_frames, o.nodes, o.nodes_per_ray
            );
        }
        if let Some(p) = &r.stats.path {
            eprintln!(
                "path: {} spp, {:.2} M paths/s, noise {:.1} %{}{}",
                p.samples_per_pixel,
                p.paths_per_second / 1e6,
                p.relative_noise * 100.0,
                if p.denoised { " before denoising" } else { "" },
                if p.dropped_non_finite > 0 {
                    format!(", {} non-finite paths dropped", p.dropped_non_finite)
                } else {
                    String::new()
                }
            );
        }
        let shown = std::fs::canonicalize(&a.output).unwrap_or(a.output.clone());
        eprintln!(
            "wrote {} ({}x{}) in {:.0} ms",
            shown.display(),
            frame.width,
            frame.height,
            start.elapsed().as_secs_f64() * 1e3
        );
    }
    Ok(())
}

/// What `fathom` with no arguments does: render the default preset to ./fathom.png at
/// 1280x720 and say where it went.
/// `fathom` with no arguments and no window: renders the default preset to fathom.png and
/// says so, with `why_no_window` (why the explorer window did not open).
pub fn run_default(why_no_window: Option<&str>) -> Result<(), String> {
    let start = Instant::now();
    let a = RenderArgs {
        output: PathBuf::from("fathom.png"),
        size: Some(DEFAULT_SIZE),
        quiet: true,
        ..RenderArgs::defaults()
    };
    run(a)?;
    let shown = std::fs::canonicalize("fathom.png").unwrap_or("fathom.png".into());
    println!(
        "rendered preset `{}` to {} in {:.2} s (see `fathom --help` for more)",
        presets::DEFAULT_PRESET,
        shown.display(),
        start.elapsed().as_secs_f64()
    );
    if let Some(why) = why_no_window {
        println!("the explorer window did not open ({why}); `fathom explore` opens it");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stereo_options_become_projections_or_explain_themselves() {
        let mut a = RenderArgs::defaults();
        assert_eq!(projection(&a, Backend::Trace), Ok(Projection::Mono));
        a.stereo = Some(StereoKind::Ods);
        a.eye_separation = 0.1;
        assert_eq!(
            projection(&a, Backend::Gpu),
            Ok(Projection::Ods {
                eye_separation: 0.1
            })
        );
        for sep in [f64::NAN, -1.0, 2e6] {
            a.eye_separation = sep;
            let e = projection(&a, Backend::Trace).unwrap_err();
            assert!(e.contains("--eye-separation"), "{e}");
        }
        a.eye_separation = 0.065;
        let e = projection(&a, Backend::Octree).unwrap_err();
        assert!(
            e.contains("--renderer svo") && e.contains("--stereo"),
            "{e}"
        );
        a.gpu = true;
        a.renderer = RendererKind::Svo;
        assert!(a.request().unwrap_err().contains("pick one"));
    }

    fn args(output: &str, size: (u32, u32)) -> RenderArgs {
        RenderArgs {
            output: PathBuf::from(output),
            size: Some(size),
            threads: Some(1),
            quiet: true,
            ..RenderArgs::defaults()
        }
    }

    #[test]
    fn bad_paths_sizes_and_cameras_fail_before_rendering() {
        let t = Instant::now();
        // A 16384x4096 frame would take minutes: these must fail at once.
        let e = run(args("/nonexistent-dir/x.png", (16384, 4096))).unwrap_err();
        assert!(e.contains("cannot write"), "{e}");
        let e = run(args("x.png", (20000, 10))).unwrap_err();
        assert!(e.contains("limit"), "{e}");
        let mut a = args("/nonexistent-dir/x.png", (16, 16));
        a.fov = Some(200.0);
        assert!(run(a).unwrap_err().contains("fov"));
        assert!(t.elapsed().as_secs_f64() < 5.0);
    }

    #[test]
    fn stereo_renders_on_the_cpu_and_is_refused_for_the_octree() {
        let dir = std::env::temp_dir().join(format!("fathom-stereo-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (kind, size) in [(StereoKind::Sbs, (48, 16)), (StereoKind::Ods, (32, 16))] {
            let p = dir.join(format!("{kind:?}.png"));
            let mut a = args(p.to_str().unwrap(), size);
            a.stereo = Some(kind);
            run(a).unwrap();
            let img = image::open(&p).unwrap();
            let want = match kind {
                StereoKind::Sbs => (2 * size.0, size.1),
                StereoKind::Ods => (size.0, 2 * size.1),
            };
            assert_eq!((img.width(), img.height()), want, "{kind:?}");
        }
        let mut a = args(dir.join("svo.png").to_str().unwrap(), (16, 8));
        a.stereo = Some(StereoKind::Ods);
        a.renderer = RendererKind::Svo;
        let e = run(a).unwrap_err();
        assert!(e.contains("--renderer svo"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn renders_a_preset_with_every_side_output() {
        let dir = std::env::temp_dir().join(format!("fathom-render-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = |n: &str| dir.join(n);
        let mut a = args(p("c.png").to_str().unwrap(), (24, 16));
        a.mask = Some(p("m.png"));
        a.depth = Some(p("d.exr"));
        a.steps = Some(p("s.png"));
        a.stats = Some(p("s.json"));
        run(a).unwrap();
        for n in ["c.png", "m.png", "d.exr", "s.png", "s.json"] {
            assert!(std::fs::metadata(p(n)).unwrap().len() > 0, "{n}");
        }
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(p("s.json")).unwrap()).unwrap();
        assert_eq!(stats["primary_rays"], 24 * 16);
        // The main image as layered EXR and as 16-bit PNG.
        run(args(p("l.exr").to_str().unwrap(), (24, 16))).unwrap();
        assert_eq!(
            &std::fs::read(p("l.exr")).unwrap()[..4],
            &[0x76, 0x2f, 0x31, 0x01]
        );
        let mut a = args(p("c16.png").to_str().unwrap(), (24, 16));
        a.bit_depth = 16;
        run(a).unwrap();
        let deep = image::open(p("c16.png")).unwrap();
        assert_eq!(deep.color(), image::ColorType::Rgb16);
        let eight = image::open(p("c.png")).unwrap().to_rgb8();
        let same = deep
            .to_rgb16()
            .pixels()
            .zip(eight.pixels())
            .all(|(d, e)| (0..3).all(|k| (d.0[k] as f32 / 257.0 - e.0[k] as f32).abs() <= 1.0));
        assert!(
            same,
            "the 16-bit image is the 8-bit one with more precision"
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_mandelbulber_file_renders_at_its_own_size_unless_told() {
        let dir = std::env::temp_dir().join(format!("fathom-fract-size-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let fract = dir.join("b.fract");
        std::fs::write(
            &fract,
            "# Mandelbulber settings file\n# version 2.20\n[main_parameters]\n\
             camera 0 -3 0;\ntarget 0 0 0;\nimage_width 36;\nimage_height 20;\nN 8;\n\
             formula_1 2;\n[fractal_1]\npower 8;\n",
        )
        .unwrap();
        let mut a = args(dir.join("own.png").to_str().unwrap(), (1, 1));
        a.scene = Some(fract.clone());
        a.size = None;
        run(a).unwrap();
        let img = image::open(dir.join("own.png")).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (36, 20));
        assert_ne!(
            img.get_pixel(18, 10),
            img.get_pixel(0, 0),
            "the bulb is in the middle"
        );
        let mut a = args(dir.join("told.png").to_str().unwrap(), (24, 16));
        a.scene = Some(fract);
        run(a).unwrap();
        assert_eq!(image::open(dir.join("told.png")).unwrap().width(), 24);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        r: RenderArgs,
    }

    #[test]
    fn render_with_the_octree_writes_a_png_with_a_silhouette() {
        let dir = std::env::temp_dir().join(format!("fathom-svo-still-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("s.png");
        let cli = <Cli as clap::Parser>::parse_from([
            "t",
            "--preset",
            "mandelbulb",
            "--renderer",
            "svo",
            "--size",
            "64x48",
            "--threads",
            "1",
            "-q",
            "-o",
            out.to_str().unwrap(),
        ]);
        run(cli.r).unwrap();
        let img = image::open(&out).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (64, 48));
        let centre = img.get_pixel(32, 24).0;
        let corner = img.get_pixel(0, 0).0;
        assert_ne!(
            centre, corner,
            "the bulb should cover the centre, not the corner"
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn the_path_integrator_writes_a_lit_picture_with_its_statistics() {
        let dir = std::env::temp_dir().join(format!("fathom-path-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("p.png");
        let stats = dir.join("p.json");
        let cli = <Cli as clap::Parser>::parse_from([
            "t",
            "--preset",
            "menger",
            "--integrator",
            "path",
            "--spp",
            "3",
            "--denoise",
            "--size",
            "40x30",
            "-q",
            "-o",
            out.to_str().unwrap(),
            "--stats",
            stats.to_str().unwrap(),
        ]);
        run(cli.r).unwrap();
        let img = image::open(&out).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (40, 30));
        let mut levels: Vec<u8> = img.pixels().map(|p| p.0[1]).collect();
        levels.sort_unstable();
        levels.dedup();
        assert!(levels.len() > 20, "a picture, not a flat image: {levels:?}");
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        assert_eq!(s["renderer"], "path");
        assert_eq!(s["path"]["samples_per_pixel"], 3);
        assert_eq!(s["path"]["denoised"], true);
        assert_eq!(s["primary_rays"], 3 * 40 * 30);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn path_flags_without_the_path_integrator_or_with_the_gpu_explain_themselves() {
        let parse = |args: &[&str]| {
            let mut v = vec!["t"];
            v.extend_from_slice(args);
            <Cli as clap::Parser>::try_parse_from(v).map(|c| c.r)
        };
        for flag in [
            &["--spp", "4"][..],
            &["--time-limit", "3s"],
            &["--denoise"],
            &["--aperture", "0.1"],
        ] {
            let e = parse(flag).unwrap().request().unwrap_err();
            assert!(e.contains("--integrator path"), "{flag:?}: {e}");
        }
        let r = parse(&["--integrator", "path", "--gpu"])
            .unwrap()
            .request()
            .unwrap();
        assert!(r.backend == Backend::Path && r.path.gpu);
        assert!(
            !parse(&["--integrator", "path"])
                .unwrap()
                .request()
                .unwrap()
                .path
                .gpu
        );
        let e = parse(&["--integrator", "path", "--renderer", "svo"])
            .unwrap()
            .request()
            .unwrap_err();
        assert!(e.contains("pick one"), "{e}");
        let e = parse(&["--integrator", "path", "--denoise", "oidn"])
            .unwrap()
            .request()
            .unwrap_err();
        assert!(e.contains("Open Image Denoise"), "{e}");
        let e = parse(&["--integrator", "path", "--spp", "0"])
            .unwrap()
            .request()
            .unwrap_err();
        assert!(e.contains("spp") && e.contains("[1, 1048576]"), "{e}");
        let e = parse(&["--integrator", "path", "--stereo", "sbs"])
            .unwrap()
            .request()
            .unwrap_err();
        assert!(e.contains("stereo"), "{e}");
        // --time-limit alone means as many samples as fit.
        let r = parse(&["--integrator", "path", "--time-limit", "2m"])
            .unwrap()
            .request()
            .unwrap();
        assert_eq!(r.path.time_limit, Some(120.0));
        assert_eq!(r.path.spp, fathom_render::request::MAX_PATH_SPP);
    }

    #[test]
    fn durations_parse_with_units_and_refuse_nonsense() {
        assert_eq!(parse_duration("30s"), Ok(30.0));
        assert_eq!(parse_duration("1.5"), Ok(1.5));
        assert_eq!(parse_duration("2m"), Ok(120.0));
        assert_eq!(parse_duration("250ms"), Ok(0.25));
        assert_eq!(parse_duration("1h"), Ok(3600.0));
        for bad in ["", "s", "-3s", "0", "3 weeks", "nan", "1e9h", "5x"] {
            assert!(parse_duration(bad).is_err(), "{bad}");
        }
    }
}
