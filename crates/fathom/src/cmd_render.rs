//! `fathom render`: a scene file or preset to an image, with diagnostic outputs (hit mask,
//! depth EXR, step heat map, JSON statistics).

use clap::{Args, ValueEnum};
use fathom_core::scene::Scene;
use fathom_core::{presets, scene_file};
use fathom_trace::{Method, Options, Stats, output};
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
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct RenderArgs {
    /// Scene file (.ron); omit to use --preset or the default preset.
    pub scene: Option<PathBuf>,
    /// Built-in preset (see `fathom list presets`).
    #[arg(long, conflicts_with = "scene")]
    pub preset: Option<String>,
    /// Output PNG.
    #[arg(short, long, default_value = "fathom.png")]
    pub output: PathBuf,
    /// Image size WIDTHxHEIGHT, each side at most 16384 and at most 64 Mpixel in all.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
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
    /// Render on the GPU (wgpu). Without any adapter it says so and suggests the CPU path.
    #[arg(long)]
    pub gpu: bool,
    /// Stereo: `sbs` (side by side, twice as wide) or `ods` (360-degree equirectangular, left
    /// eye on top, twice as tall; use a 2:1 --size). --size is one eye's view. Not with
    /// --renderer svo.
    #[arg(long, value_enum)]
    pub stereo: Option<crate::render_gpu::StereoKind>,
    /// Distance between the eyes for --stereo, in scene units.
    #[arg(long, default_value_t = 0.065)]
    pub eye_separation: f64,
    /// Renderer: the sphere tracer, or the sparse voxel octree (settled at this view).
    #[arg(long, value_enum, default_value = "trace")]
    pub renderer: crate::cmd_zoom::RendererKind,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size `{s}` should look like 1280x720"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("size `{s}`: `{v}` is not a whole number"))
    };
    Ok((p(w)?, p(h)?))
}

fn parse_vec(s: &str) -> Result<DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("`{s}` should be three numbers x,y,z"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(DVec3::new(x, y, z)),
        _ => Err(format!("`{s}` should be three finite numbers x,y,z")),
    }
}

/// Loads the scene named by the arguments and applies the camera overrides.
fn load_scene(a: &RenderArgs) -> Result<Scene, String> {
    let mut scene = match (&a.scene, &a.preset) {
        (Some(path), _) => scene_file::load(path).map_err(|e| e.to_string())?,
        (None, Some(p)) => presets::load(p)?,
        (None, None) => presets::load(presets::DEFAULT_PRESET)?,
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
    scene.validate()?;
    Ok(scene)
}

/// Statistics as JSON.
pub fn stats_json(s: &Stats) -> serde_json::Value {
    let px = (s.width as f64 * s.height as f64).max(1.0);
    serde_json::json!({
        "width": s.width,
        "height": s.height,
        "deep_f64_path": s.deep,
        "primary_rays": s.primary_rays,
        "shadow_rays": s.shadow_rays,
        "hits": s.hits,
        "de_evaluations": {
            "prepass": s.de_prepass,
            "trace": s.de_trace,
            "shade": s.de_shade,
        },
        "depth_de_per_pixel": s.de_per_pixel(),
        "trace_steps_per_pixel": s.de_trace as f64 / px,
        "ms": {
            "prepass": s.ms_prepass,
            "trace_and_shade": s.ms_trace,
            "post": s.ms_post,
            "total": s.ms_total,
        },
    })
}

fn open(p: &Option<PathBuf>) -> Result<Option<(std::fs::File, &Path)>, String> {
    p.as_deref()
        .map(|p| output::open_output(p).map(|f| (f, p)))
        .transpose()
}

pub fn run(a: RenderArgs) -> Result<(), String> {
    let (width, height) = a.size;
    let opts = Options {
        width,
        height,
        method: match a.tracer {
            TracerKind::Basic => Method::Basic,
            TracerKind::Enhanced => Method::Enhanced,
        },
        prepass: !a.no_prepass,
        supersample: a.supersample,
        geometry_only: false,
        ssao: a.ssao,
        projection: crate::render_gpu::projection(
            a.stereo,
            a.eye_separation,
            a.renderer == crate::cmd_zoom::RendererKind::Svo,
        )?,
    };
    opts.validate()?;
    if a.threads == Some(0) || a.threads.is_some_and(|t| t > 1024) {
        return Err("--threads must be in [1, 1024]".into());
    }
    let scene = load_scene(&a)?;
    if a.renderer == crate::cmd_zoom::RendererKind::Svo {
        return crate::cmd_zoom::render_still(&scene, &a);
    }
    // Open every output before rendering, so a bad path fails fast.
    let out = output::open_output(&a.output)?;
    let mask = open(&a.mask)?;
    let depth = open(&a.depth)?;
    let steps = open(&a.steps)?;
    let stats_file = open(&a.stats)?;

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads.unwrap_or(0))
        .build()
        .map_err(|e| e.to_string())?;
    let bar = if a.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        let b = indicatif::ProgressBar::new(0);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} rendering [{bar:40}] {percent}% {elapsed}",
            )
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
        );
        b
    };
    let progress = |done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };
    let (frame, stats, ms_total) = if a.gpu {
        let r = pool.install(|| crate::render_gpu::render(&scene, &opts))?;
        (r.frame, r.stats, r.ms_total)
    } else {
        let (frame, stats) = pool.install(|| fathom_trace::render(&scene, &opts, &progress))?;
        (frame, stats_json(&stats), stats.ms_total)
    };
    bar.finish_and_clear();

    output::save_colour(&frame, out, &a.output)?;
    if let Some((f, p)) = mask {
        output::save_mask(&frame, f, p)?;
    }
    if let Some((f, p)) = depth {
        output::save_depth(&frame, scene.render.max_distance as f32, f, p)?;
    }
    if let Some((f, p)) = steps {
        output::save_steps(&frame, f, p)?;
    }
    if let Some((f, p)) = stats_file {
        serde_json::to_writer_pretty(std::io::BufWriter::new(f), &stats)
            .map_err(|e| format!("cannot write {}: {e}", p.display()))?;
    }
    if !a.quiet {
        let shown = std::fs::canonicalize(&a.output).unwrap_or(a.output.clone());
        eprintln!(
            "wrote {} ({}x{}) in {:.0} ms",
            shown.display(),
            frame.width,
            frame.height,
            ms_total
        );
    }
    Ok(())
}

impl RenderArgs {
    /// The arguments of a bare `fathom render`, taken from the clap declarations so a new flag
    /// needs no second default here.
    pub fn defaults() -> RenderArgs {
        crate::clap_defaults()
    }
}

/// What `fathom` with no arguments does: render the default preset to ./fathom.png at
/// 1280x720 and say where it went.
pub fn run_default() -> Result<(), String> {
    let start = Instant::now();
    let a = RenderArgs {
        output: PathBuf::from("fathom.png"),
        size: (1280, 720),
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
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_vectors_parse_or_explain() {
        assert_eq!(parse_size("640x480"), Ok((640, 480)));
        assert!(parse_size("640").is_err());
        assert!(parse_size("ax4").is_err());
        assert_eq!(parse_vec("1,-2,3.5"), Ok(DVec3::new(1.0, -2.0, 3.5)));
        assert!(parse_vec("1,2").is_err());
        assert!(parse_vec("1,2,nan").is_err());
    }

    fn args(output: &str, size: (u32, u32)) -> RenderArgs {
        RenderArgs {
            output: PathBuf::from(output),
            size,
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
        for (kind, size) in [
            (crate::render_gpu::StereoKind::Sbs, (48, 16)),
            (crate::render_gpu::StereoKind::Ods, (32, 16)),
        ] {
            let p = dir.join(format!("{kind:?}.png"));
            let mut a = args(p.to_str().unwrap(), size);
            a.stereo = Some(kind);
            run(a).unwrap();
            let img = image::open(&p).unwrap();
            let want = match kind {
                crate::render_gpu::StereoKind::Sbs => (2 * size.0, size.1),
                crate::render_gpu::StereoKind::Ods => (size.0, 2 * size.1),
            };
            assert_eq!((img.width(), img.height()), want, "{kind:?}");
        }
        let mut a = args(dir.join("svo.png").to_str().unwrap(), (16, 8));
        a.stereo = Some(crate::render_gpu::StereoKind::Ods);
        a.renderer = crate::cmd_zoom::RendererKind::Svo;
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
        std::fs::remove_dir_all(&dir).ok();
    }
}
