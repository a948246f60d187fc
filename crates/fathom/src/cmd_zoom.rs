//! `fathom zoom`: the scale-adaptive sparse voxel octree explorer on an automated camera path
//! (a point-of-recursion zoom or a tour), writing frames and per-frame stats.

use clap::{Args, ValueEnum};
use fathom_svo::stats::Summary;
use fathom_svo::zoom::{self, Path, ZoomPreset};
use fathom_svo::{Explorer, ExplorerConfig, FrameStats, Traversal};
use serde::Serialize;
use std::path::PathBuf;

/// Traversal choice on the command line.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum TraversalArg {
    /// Neighbour links from the skip node (scale independent).
    Neighbour,
    /// Descent from the root for every leaf (baseline).
    Kdrestart,
}

impl From<TraversalArg> for Traversal {
    fn from(t: TraversalArg) -> Traversal {
        match t {
            TraversalArg::Neighbour => Traversal::Neighbour,
            TraversalArg::Kdrestart => Traversal::KdRestart,
        }
    }
}

/// Explore with the sparse voxel octree along a zoom or tour; write frames and stats.
///
/// Detail is generated as the camera approaches (a fixed subdivision time per frame), bricks no
/// ray visited are unloaded to stay within --max-memory, and a zoom past f64 precision stops
/// with a message instead of rendering garbage. Prints a one-line summary at the end.
///
/// Examples:
///   fathom zoom --preset menger --depth 1e11 --frames 300 --stats zoom.json
///   fathom zoom --preset mandelbulb --frames 600 -o frames/        (PNG per frame)
///   fathom zoom --preset menger --traversal kdrestart --stats kd.json   (the baseline)
///   fathom zoom --preset menger-tour --frames 900 --size 1280x720 -o tour/
///   ffmpeg -framerate 30 -i frames/frame_%05d.png zoom.mp4              (frames to a video)
#[derive(Args, Clone)]
#[command(verbatim_doc_comment)]
pub struct ZoomArgs {
    /// Path preset: menger (zoom into the corner, a point of recursion), mandelbulb (zoom
    /// into a surface point), menger-tour (a flight around and into the sponge).
    #[arg(long, default_value = "menger")]
    pub preset: String,
    /// Zoom factor from the first to the last frame (ratio of eye distances), >= 1.
    #[arg(long, default_value_t = 1e11)]
    pub depth: f64,
    /// Frames to render.
    #[arg(long, default_value_t = 2000)]
    pub frames: usize,
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480")]
    pub size: String,
    /// Directory to write frames to as PNG (none: frames are not written).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Write per-frame stats and the summary as JSON to this file.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Octree traversal.
    #[arg(long, value_enum, default_value = "neighbour")]
    pub traversal: TraversalArg,
    /// Worker threads.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Voxels may project to this many pixels, [0.25, 16].
    #[arg(long, default_value_t = 1.0)]
    pub fidelity: f64,
    /// Memory budget of the octree, e.g. 512M, 1G, or bytes.
    #[arg(long, default_value = "1G")]
    pub max_memory: String,
    /// Subdivision time per frame in ms.
    #[arg(long, default_value_t = 12.0)]
    pub subdivide_ms: f64,
    /// Unify (unload bricks no ray visited) every this many frames, >= 1.
    #[arg(long, default_value_t = 4)]
    pub unify_every: u32,
    /// Screen-space ambient occlusion strength applied to written frames (the sphere
    /// tracer's post effect), [0, 4].
    #[arg(long, default_value_t = 1.0)]
    pub ssao: f32,
}

/// Which renderer `fathom render` uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RendererKind {
    /// The CPU sphere tracer.
    Trace,
    /// The sparse voxel octree, subdivided until settled at the view.
    Svo,
}

/// `fathom render --renderer svo`: settles an octree at the scene's camera (root cube fitted
/// to the scene inside [-4, 4]^3), renders it, applies the shared post effects (fog from the
/// scene, `--ssao`) and writes the PNG (and the mask if asked).
pub fn render_still(
    scene: &fathom_core::Scene,
    a: &crate::cmd_render::RenderArgs,
) -> Result<(), String> {
    let (width, height) = a.size;
    let cfg = ExplorerConfig {
        width,
        height,
        threads: a.threads.unwrap_or(2),
        root: fathom_svo::RootSpec::Fit { half: 4.0 },
        ..ExplorerConfig::default()
    };
    let out = fathom_trace::output::open_output(&a.output)?;
    let mut ex = Explorer::new(scene, cfg)?;
    let frames = ex.settle(&scene.camera, 400);
    let (img, reqs, counts) = ex.render(&scene.camera);
    ex.release_requests(&reqs);
    let mut frame = img.to_frame();
    if scene.render.fog > 0.0 {
        let sky = scene.render.sky_bottom.map(|c| c as f32);
        fathom_trace::post::fog(&mut frame, scene.render.fog as f32, sky);
    }
    if a.ssao > 0.0 {
        let pa = scene.camera.frame().pixel_angle(height) as f32;
        fathom_trace::post::ssao(&mut frame, a.ssao, pa);
    }
    fathom_trace::output::save_colour(&frame, out, &a.output)?;
    if let Some(p) = &a.mask {
        let f = fathom_trace::output::open_output(p)?;
        fathom_trace::output::save_mask(&frame, f, p)?;
    }
    if !a.quiet {
        eprintln!(
            "svo: settled in {frames} frames, {} nodes, {:.1} nodes per ray",
            ex.tree.counts().nodes,
            counts[2] as f64 / counts[0].max(1) as f64
        );
    }
    Ok(())
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size `{s}` must look like 640x480"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("size `{s}`: `{v}` is not a whole number of pixels"))
    };
    let (w, h) = (p(w)?, p(h)?);
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!("size {w}x{h} is out of range (1..=16384 per side)"));
    }
    Ok((w, h))
}

/// Parses a byte count with an optional K/M/G suffix (powers of 1024).
pub fn parse_bytes(s: &str) -> Result<usize, String> {
    let t = s.trim();
    let (num, mul) = match t.chars().last() {
        Some('k' | 'K') => (&t[..t.len() - 1], 1usize << 10),
        Some('m' | 'M') => (&t[..t.len() - 1], 1 << 20),
        Some('g' | 'G') => (&t[..t.len() - 1], 1 << 30),
        _ => (t, 1),
    };
    let v: f64 = num
        .parse()
        .map_err(|_| format!("memory `{s}` must be a number with an optional K, M or G suffix"))?;
    if !(v.is_finite() && v > 0.0) || v * mul as f64 > 1e15 {
        return Err(format!("memory `{s}` is out of range"));
    }
    Ok((v * mul as f64) as usize)
}

/// The JSON written by `--stats`.
#[derive(Serialize)]
pub struct ZoomReport {
    pub preset: String,
    pub traversal: Traversal,
    pub width: u32,
    pub height: u32,
    pub depth: f64,
    pub threads: usize,
    pub fidelity: f64,
    /// Why the zoom stopped early (precision limit), if it did.
    pub stopped: Option<String>,
    pub summary: Summary,
    pub zoom: Vec<f64>,
    pub frames: Vec<FrameStats>,
}

/// Checks the arguments and builds the preset and explorer settings.
pub fn setup(a: &ZoomArgs) -> Result<(ZoomPreset, ExplorerConfig), String> {
    if !(a.depth.is_finite() && a.depth >= 1.0) {
        return Err(format!(
            "--depth {} must be a finite zoom factor >= 1",
            a.depth
        ));
    }
    if !(a.ssao.is_finite() && (0.0..=4.0).contains(&a.ssao)) {
        return Err(format!("--ssao {} is out of range [0, 4]", a.ssao));
    }
    if a.frames == 0 || a.frames > 10_000_000 {
        return Err(format!(
            "--frames {} is out of range 1..=10000000",
            a.frames
        ));
    }
    let (width, height) = parse_size(&a.size)?;
    let max_memory = parse_bytes(&a.max_memory)?;
    let p = zoom::preset(&a.preset)?;
    let cfg = ExplorerConfig {
        width,
        height,
        fidelity: a.fidelity,
        threads: a.threads,
        max_memory,
        traversal: a.traversal.into(),
        subdivide_ms: a.subdivide_ms,
        unify_every: a.unify_every,
        root: p.root,
        ..ExplorerConfig::default()
    };
    cfg.validate()?;
    Ok((p, cfg))
}

/// Runs a zoom; `on_frame` sees each frame (for progress). Returns the report.
pub fn run_zoom(a: &ZoomArgs, quiet: bool) -> Result<ZoomReport, String> {
    let (p, cfg) = setup(a)?;
    if let Some(dir) = &a.output {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let mut ex = Explorer::new(&p.scene, cfg.clone())?;
    let mut frames = Vec::with_capacity(a.frames);
    let mut zooms = Vec::with_capacity(a.frames);
    let mut stopped = None;
    for i in 0..a.frames {
        let cam = p.camera(i, a.frames, a.depth);
        let z = p.zoom_at(i, a.frames, a.depth);
        if let Path::Zoom { target, .. } = &p.path {
            let pa = cam.frame().pixel_angle(cfg.height);
            let dist = (cam.eye - *target).length();
            if let Err(e) = zoom::precision_check(dist, ex.tree.root_size, pa, cfg.fidelity, z) {
                stopped = Some(e);
                break;
            }
        }
        let (img, st) = ex.step(&cam);
        if let Some(dir) = &a.output {
            let path = dir.join(format!("frame_{i:05}.png"));
            image::save_buffer(
                &path,
                &img.to_srgb8(),
                img.width,
                img.height,
                image::ColorType::Rgb8,
            )
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        }
        if !quiet && (i % 100 == 0 || i + 1 == a.frames) {
            eprintln!(
                "frame {i}: zoom {z:.2e}, {:.1} ms, {:.1} nodes/ray, {} nodes, {} bricks",
                st.frame_ms, st.nodes_per_ray, st.node_count, st.brick_count
            );
        }
        frames.push(st);
        zooms.push(z);
    }
    if let Some(e) = &stopped {
        eprintln!("fathom: stopped: {e}");
    }
    let summary = Summary::new(&frames, &zooms, cfg.brick_period);
    Ok(ZoomReport {
        preset: p.name.into(),
        traversal: cfg.traversal,
        width: cfg.width,
        height: cfg.height,
        depth: a.depth,
        threads: cfg.threads,
        fidelity: cfg.fidelity,
        stopped,
        summary,
        zoom: zooms,
        frames,
    })
}

pub fn run(a: ZoomArgs) -> Result<(), String> {
    let report = run_zoom(&a, false)?;
    let s = &report.summary;
    println!(
        "{} {:?} {}x{}: {} frames to zoom {:.2e}; median fps {:.1} (settled {:.1}); last/first decade fps {:.2}; \
         {:.1} nodes/ray at the end; peak resident {:.1} MiB; max/first-cycle nodes {:.3}",
        report.preset,
        report.traversal,
        report.width,
        report.height,
        s.frames,
        s.zoom_reached,
        s.median_fps,
        s.median_fps_settled,
        s.last_over_first,
        s.nodes_per_ray_last_decade,
        s.peak_resident_bytes as f64 / (1 << 20) as f64,
        s.max_over_first_cycle
    );
    if let Some(path) = &a.stats {
        let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_memory_parse_with_clear_errors() {
        assert_eq!(parse_size("640x480").unwrap(), (640, 480));
        assert!(parse_size("640").unwrap_err().contains("640x480"));
        assert!(parse_size("0x10").unwrap_err().contains("out of range"));
        assert_eq!(parse_bytes("1G").unwrap(), 1 << 30);
        assert_eq!(parse_bytes("512M").unwrap(), 512 << 20);
        assert!(parse_bytes("lots").is_err());
        assert!(parse_bytes("-1").is_err());
    }

    fn args() -> ZoomArgs {
        ZoomArgs {
            depth: 1e3,
            frames: 3,
            size: "32x24".into(),
            threads: 1,
            max_memory: "64M".into(),
            subdivide_ms: 5.0,
            ..crate::clap_defaults()
        }
    }

    #[test]
    fn bad_zoom_arguments_are_refused() {
        let mut a = args();
        a.depth = 0.5;
        assert!(setup(&a).err().unwrap().contains("--depth"));
        a.depth = 10.0;
        a.frames = 0;
        assert!(setup(&a).err().unwrap().contains("--frames"));
        a.frames = 3;
        a.fidelity = 100.0;
        assert!(setup(&a).err().unwrap().contains("fidelity"));
        a.fidelity = 1.0;
        a.unify_every = 0;
        assert!(setup(&a).err().unwrap().contains("unify-every"));
        a.unify_every = 4;
        a.max_memory = "1K".into();
        assert!(setup(&a).err().unwrap().contains("max memory"));
    }

    #[test]
    fn a_zoom_past_f64_precision_stops_cleanly() {
        let mut a = args();
        a.depth = 1e20;
        a.frames = 40;
        let r = run_zoom(&a, true).unwrap();
        let msg = r.stopped.expect("the zoom should have stopped");
        assert!(msg.contains("precision limit"), "{msg}");
        assert!(r.frames.len() < 40 && r.frames.len() > 10);
    }
}

#[cfg(test)]
mod render_tests {
    use crate::cmd_render::RenderArgs;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        r: RenderArgs,
    }

    #[test]
    fn render_with_the_octree_writes_a_png_with_a_silhouette() {
        let dir = std::env::temp_dir().join(format!("fathom-svo-still-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("s.png");
        let cli = Cli::parse_from([
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
        crate::cmd_render::run(cli.r).unwrap();
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
}
