//! `fathom zoom`: the scale-adaptive sparse voxel octree explorer on an automated camera path
//! (a point-of-recursion zoom or a tour), writing frames and per-frame stats. The flags become
//! a [`Zoom`] of the render layer, which runs the frame loop; this module writes the frames.

use crate::args::{parse_bytes, parse_size, parse_vec};
use clap::{Args, ValueEnum};

use fathom_core::scene_file;
use fathom_render::zoom::{Aim, Zoom, ZoomPath, ZoomReport};
use fathom_render::{OctreeSettings, RenderRequest};
use fathom_svo::Traversal;
use glam::DVec3;
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
/// ray visited are unloaded to stay within --max-memory. Zooms go past f64: box coordinates are
/// kept relative to an anchor near the eye, the eye and the scene's evaluation switch to
/// double-double once voxels are 2^-37 of the root; a zoom stops with a message where that
/// runs out (octree depth 98, about zoom 1e28 at 640x480) instead of rendering garbage.
/// Prints a one-line summary at the end.
///
/// Any scene zooms: a scene preset or a scene file zooms from its camera into the surface
/// point of its centre ray (or the first hit on a spiral around it), of the ray through
/// --pixel X,Y, or of the ray toward --toward x,y,z; the point is bracketed to f64 precision
/// on the surface and the camera turns to look at it.
///
/// Examples:
///   fathom zoom --preset menger --depth 1e11 --frames 300 --stats zoom.json
///   fathom zoom --preset menger --depth 1e15 --frames 450 -o deep/    (past double precision)
///   fathom zoom --preset sierpinski --pixel 320,160 --depth 1e9 -o frames/
///   fathom zoom my-scene.ron --toward 0.3,0.2,1 --depth 1e8 --stats z.json
///   fathom zoom --preset mandelbulb --compare-every 10 --stats z.json   (vs the tracer)
///   fathom zoom --preset mandelbulb --compare-every 50 --compare-images cmp/   (both, side by side)
///   fathom zoom --preset mandelbulb --frames 600 -o frames/        (PNG per frame)
///   fathom zoom --preset menger --traversal kdrestart --stats kd.json   (the baseline)
///   fathom zoom --preset menger-tour --frames 900 --size 1280x720 -o tour/
///   ffmpeg -framerate 30 -i frames/frame_%05d.png zoom.mp4              (frames to a video)
///   fathom zoom --preset menger --depth 1e6 --frames 240 --shard 2/8 -o zoom/   (a farm shard)
#[derive(Args, Clone)]
#[command(verbatim_doc_comment)]
pub struct ZoomArgs {
    /// Scene file (.ron) to zoom into; omit to use --preset.
    pub scene: Option<PathBuf>,
    /// A path preset: menger (zoom into the corner, a point of recursion), mandelbulb (zoom
    /// into a surface point), menger-tour (a flight around and into the sponge); or any scene
    /// preset (`fathom list presets`), zoomed into from its camera. Default: menger.
    #[arg(long, conflicts_with = "scene")]
    pub preset: Option<String>,
    /// Zoom into the surface where the ray from the eye toward this point x,y,z meets it.
    #[arg(long, value_parser = parse_vec, allow_hyphen_values = true, conflicts_with = "pixel")]
    pub toward: Option<DVec3>,
    /// Zoom into the surface this pixel X,Y of the first frame shows (0,0 is the top left of
    /// a --size image of the view).
    #[arg(long, value_parser = parse_pixel)]
    pub pixel: Option<(u32, u32)>,
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
    /// Subdivision time per frame in ms: more gives finer detail sooner, less a higher frame
    /// rate.
    #[arg(long, default_value_t = fathom_svo::octree_view::DEFAULT_SUBDIVIDE_MS)]
    pub subdivide_ms: f64,
    /// Hold this frame rate: a frame whose render leaves less than --subdivide-ms of the frame
    /// time subdivides for what is left, down to half of it (0: always --subdivide-ms),
    /// [0, 1000]. It only takes time from subdividing, so frames whose render alone is slower
    /// stay slower.
    #[arg(long, default_value_t = fathom_render::zoom::DEFAULT_TARGET_FPS)]
    pub target_fps: f64,
    /// Unify (unload bricks no ray visited) every this many frames, >= 1.
    #[arg(long, default_value_t = 4)]
    pub unify_every: u32,
    /// Tile starts: each tile of this many pixels square walks the octree nodes its frustum
    /// meets once, and all its rays start where none of them can have stopped yet (0: every
    /// ray from the eye's leaf). The same images, fewer steps per ray.
    #[arg(long, default_value_t = fathom_svo::octree_view::DEFAULT_BEAM)]
    pub beam: u32,
    /// Finest tile: tiles are cut into quadrants, each refining its parent's start with a
    /// walk of its own, down to this side in pixels (the --beam value: one level).
    #[arg(long, default_value_t = fathom_svo::octree_view::DEFAULT_BEAM_MIN)]
    pub beam_min: u32,
    /// Draw voxels wider than a pixel cut by the surface plane through them (shaded where
    /// the line of sight meets the surface, with the distance gradient there as normal):
    /// faceted silhouettes instead of cubes', and rays pass leaves whose line of sight met
    /// the surface behind them. Without it such voxels are cubes drawn at their plane's
    /// depth, which already gives the occlusion a smooth surface instead of a staircase
    /// (Mandelbulb, 1000 frames to 1e15: median SSIM 0.962 without; 0.956 with, measured
    /// before planes went through the surface), at about 80 % of the frame rate (rays step
    /// through the leaves whose planes they pass).
    #[arg(long)]
    pub planes: bool,
    /// Split voxels near the screen's centre first: a voxel's size on screen counts divided
    /// by 1 + FOVEA rho^2, rho its distance from the centre in half-heights (1 at the top
    /// edge). The zoom keeps the centre longest, so detail put there lasts (Mandelbulb to
    /// 1e6 at 6 ms: median SSIM against the tracer 0.19 at 0, 0.26 at 4); 0 splits the
    /// largest on screen first wherever they are, [0, 64].
    #[arg(long, default_value_t = fathom_svo::request_order::DEFAULT_FOVEA)]
    pub fovea: f64,
    /// Draw voxels at least two pixels wide as they are stored, one flat colour each (a
    /// mosaic while detail arrives), instead of smooth: by default each such pixel takes the
    /// mean colour of a box as wide as its voxel on screen, which joins the voxels' colours
    /// smoothly (Menger to 1e6: median SSIM against the tracer 0.34 blocky, 0.42 smooth).
    /// Frames whose voxels are all narrower look the same either way.
    #[arg(long)]
    pub blocky: bool,
    /// Rays are cast on a lattice (every other pixel of every other row) first; a pixel
    /// between lattice rays that all met one voxel at least this many pixels wide takes its
    /// colour without a ray of its own (0: every pixel casts its ray). What the zoom shows
    /// while detail arrives is voxels several pixels wide, so most pixels are filled; settled
    /// frames are unchanged. 0 or [2, 64].
    #[arg(long, default_value_t = fathom_svo::fill::DEFAULT_FILL_PX)]
    pub fill_px: f64,
    /// Before the first frame, refine the octree at the first camera for up to this many
    /// milliseconds, so the zoom opens on the scene instead of a few huge voxels (not
    /// counted in the frame times; written to --stats as warmup_ms), [0, 600000].
    #[arg(long, default_value_t = 1000.0)]
    pub warmup_ms: f64,
    /// Screen-space ambient occlusion strength applied to written frames (the sphere
    /// tracer's post effect), [0, 4].
    #[arg(long, default_value_t = 1.0)]
    pub ssao: f32,
    /// Every N frames (and the last), also render the frame with the sphere tracer at the
    /// same camera and write to --stats its SSIM (luminance), silhouette IoU, colour error,
    /// largest visible voxel in pixels and camera (0: never; the tracer's time is not counted
    /// in the zoom's frame times, but it slows the run).
    #[arg(long, default_value_t = 0)]
    pub compare_every: usize,
    /// With --compare-every: rays a pixel side of the double-double reference that frames
    /// past zoom 1e6 are compared with (at 80x60, against 8x8 block means of the octree's
    /// frame), [1, 4]. One ray at a pixel's centre is not what a block mean shows of detail
    /// finer than the pixel: deep Menger frames score SSIM 0.62-0.64 against one ray and
    /// 0.68-0.71 against 2x2, for 4x the reference's time (Menger 3 s to 12 s a compared
    /// frame, Mandelbulb 5 s to 21 s); n costs n^2.
    #[arg(long, default_value_t = fathom_render::zoom::DEFAULT_REFERENCE_SAMPLES)]
    pub reference_samples: u32,
    /// With --compare-every: write each compared frame into this directory as
    /// compare_NNNNN.png, the octree's frame on the left and the sphere tracer's on the right
    /// (deep frames at the reduced size they are compared at).
    #[arg(long, value_name = "DIR")]
    pub compare_images: Option<PathBuf>,
    /// Render farm: render shard I of N of the zoom's frames into the job directory -o DIR,
    /// each frame a settled still on a fresh octree (so it does not depend on the frames
    /// before it; slower than the stepped zoom, and not the same images). Without a value:
    /// from SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT. Path presets only.
    #[arg(long, value_name = "I/N", num_args = 0..=1, default_missing_value = "")]
    pub shard: Option<String>,
}

/// Parses `X,Y` (two whole numbers).
pub fn parse_pixel(s: &str) -> Result<(u32, u32), String> {
    let v: Vec<&str> = s.split(',').collect();
    let p = |t: &str| {
        t.trim()
            .parse::<u32>()
            .map_err(|_| format!("pixel `{s}`: `{t}` is not a whole number >= 0"))
    };
    match v[..] {
        [x, y] => Ok((p(x)?, p(y)?)),
        _ => Err(format!("pixel `{s}` should be two whole numbers X,Y")),
    }
}

/// The path these flags describe: a path preset as it is, or a scene (preset or file) with an
/// aim (the view's centre, --pixel or --toward). A path preset with an aim zooms from its
/// first camera.
pub fn zoom_path(a: &ZoomArgs) -> Result<ZoomPath, String> {
    let (width, height) = parse_size(&a.size)?;
    let aim = match (a.toward, a.pixel) {
        (Some(p), _) => Some(Aim::Toward(p)),
        (None, Some((x, y))) => Some(Aim::Pixel {
            x,
            y,
            width,
            height,
        }),
        (None, None) => None,
    };
    match &a.scene {
        Some(path) => {
            let scene = scene_file::load(path).map_err(|e| e.to_string())?;
            scene.validate().map_err(|e| e.to_string())?;
            let view = scene.camera.clone();
            let name = path.display().to_string();
            ZoomPath::aim(&name, scene, &view, aim.unwrap_or(Aim::View), None)
        }
        None => ZoomPath::from_preset(
            a.preset.as_deref().unwrap_or("menger"),
            aim,
            a.frames,
            a.depth,
        ),
    }
    .map_err(|e| e.to_string())
}

/// The zoom these flags describe, checked.
pub fn zoom(a: &ZoomArgs) -> Result<Zoom, String> {
    let (width, height) = parse_size(&a.size)?;
    let z = Zoom {
        depth: a.depth,
        frames: a.frames,
        request: RenderRequest {
            width,
            height,
            ssao: a.ssao,
            threads: Some(a.threads),
            backend: fathom_render::Backend::Octree,
            octree: OctreeSettings {
                fidelity: a.fidelity,
                max_memory: parse_bytes(&a.max_memory)?,
                traversal: a.traversal.into(),
                subdivide_ms: a.subdivide_ms,
                target_fps: a.target_fps,
                unify_every: a.unify_every,
                beam: a.beam,
                beam_min: a.beam_min,
                planes: a.planes,
                fovea: a.fovea,
                smooth: !a.blocky,
                fill_px: a.fill_px,
                ..OctreeSettings::default()
            },
            ..RenderRequest::default()
        },
        compare_every: a.compare_every,
        reference_samples: a.reference_samples,
        warmup_ms: a.warmup_ms,
    };
    z.validate().map_err(|e| e.to_string())?;
    z.request.validate().map_err(|e| e.to_string())?;
    Ok(z)
}

/// Runs a zoom, writing frames if `a.output` is set and a progress line every 100 frames
/// unless `quiet`. Returns the report.
pub fn run_zoom(a: &ZoomArgs, quiet: bool) -> Result<ZoomReport, String> {
    let z = zoom(a)?;
    if a.compare_images.is_some() && a.compare_every == 0 {
        return Err(
            "--compare-images needs --compare-every N (N >= 1): only compared frames have a \
             tracer image"
                .into(),
        );
    }
    let preset = zoom_path(a)?;
    for dir in [&a.output, &a.compare_images].into_iter().flatten() {
        fathom_core::atomic_file::create_output_dir(dir).map_err(|e| e.to_string())?;
    }
    let write = |f: &fathom_core::frame::Frame, path: &std::path::Path| {
        let file = fathom_trace::output::open_output(path).map_err(|e| e.to_string())?;
        fathom_trace::output::save_colour(f, file, path).map_err(|e| e.to_string())
    };
    let report = z
        .run(&preset, a.output.is_some(), |zf| {
            let (i, zoom, st) = (zf.index, zf.zoom, zf.stats);
            if let (Some(dir), Some(f)) = (&a.output, zf.image) {
                write(f, &dir.join(format!("frame_{i:05}.png")))?;
            }
            if let (Some(dir), Some((octree, traced))) = (&a.compare_images, zf.compared) {
                write(
                    &fathom_image::compare::side_by_side(octree, traced, COMPARE_GAP),
                    &dir.join(format!("compare_{i:05}.png")),
                )?;
            }
            if !quiet && (i % 100 == 0 || i + 1 == a.frames) {
                eprintln!(
                    "frame {i}: zoom {zoom:.2e}, {:.1} ms, {:.1} nodes/ray, {} nodes, {} bricks",
                    st.frame_ms, st.nodes_per_ray, st.node_count, st.brick_count
                );
            }
            Ok(())
        })
        .map_err(|e| e.to_string())?;
    if let Some(e) = &report.stopped {
        eprintln!("fathom: stopped: {e}");
    }
    Ok(report)
}

/// Gap in pixels between the two images of a comparison.
const COMPARE_GAP: u32 = 4;

/// `fathom zoom` on this machine (`--shard` is dispatched by [`crate::zoom`] before this).
pub fn run(a: ZoomArgs) -> Result<(), String> {
    // The stats file is checked before the frames are rendered, not after.
    if let Some(path) = &a.stats {
        fathom_core::atomic_file::AtomicFile::create(path)
            .map(drop)
            .map_err(|e| e.to_string())?;
    }
    let report = run_zoom(&a, false)?;
    let s = &report.summary;
    if report.warmup_frames > 0 {
        println!(
            "warm start: {} settling frames in {:.0} ms at the first camera (not in the frame times)",
            report.warmup_frames, report.warmup_ms
        );
    }
    println!(
        "{} {:?} {}x{}: {} frames to zoom {:.2e}; median fps {:.1} (settled {:.1}); \
         fps in the first decade (zoom 10-100) {:.1}, in the last {:.1}, last/first {:.2}; \
         {:.1} nodes/ray at the end; peak resident {:.1} MiB; max/first-cycle nodes {:.3}",
        report.preset,
        report.traversal,
        report.width,
        report.height,
        s.frames,
        s.zoom_reached,
        s.median_fps,
        s.median_fps_settled,
        s.median_fps_first_decade,
        s.median_fps_last_decade,
        s.last_over_first,
        s.nodes_per_ray_last_decade,
        s.peak_resident_bytes as f64 / (1 << 20) as f64,
        s.max_over_first_cycle
    );
    if !report.compare.is_empty() {
        let c = &report.compare;
        let med = |f: &dyn Fn(&fathom_render::zoom::FrameComparison) -> f64| {
            fathom_svo::stats::median(&c.iter().map(f).collect::<Vec<_>>())
        };
        println!(
            "compared {} frames with the sphere tracer: median SSIM {:.3}, median silhouette IoU {:.3}, \
             median colour error {:.3}, median largest voxel {:.2} px (largest {:.2} px)",
            c.len(),
            med(&|x| x.agreement.ssim),
            med(&|x| x.agreement.iou),
            med(&|x| x.agreement.colour_error),
            med(&|x| x.largest_voxel_px),
            c.iter().map(|x| x.largest_voxel_px).fold(0.0, f64::max)
        );
    }
    if let Some(path) = &a.stats {
        let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        fathom_core::atomic_file::write(path, text).map_err(|e| e.to_string())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args() -> ZoomArgs {
        ZoomArgs {
            depth: 1e3,
            frames: 3,
            size: "32x24".into(),
            threads: 1,
            max_memory: "64M".into(),
            subdivide_ms: 5.0,
            warmup_ms: 0.0,
            ..crate::clap_defaults()
        }
    }

    #[test]
    fn a_warm_start_opens_the_zoom_on_the_scene_not_the_root_cube() {
        // From the root cube, the first frame shows voxels as large as the view; settled at
        // the first camera first (up to 20 s, far more than 32x24 needs), no visible voxel of
        // the first frame is wider than a pixel, and the warm start is reported, not counted
        // in the frames' times.
        let mut a = args();
        let cold = run_zoom(&a, false).unwrap();
        a.warmup_ms = 20_000.0;
        let warm = run_zoom(&a, false).unwrap();
        let first = |r: &fathom_render::zoom::ZoomReport| r.frames[0].largest_voxel_px;
        eprintln!(
            "first frame's largest voxel: cold {:.1} px, warm {:.1} px after {} frames in {:.0} ms",
            first(&cold),
            first(&warm),
            warm.warmup_frames,
            warm.warmup_ms
        );
        assert!(first(&cold) > 8.0, "cold start {}", first(&cold));
        assert!(first(&warm) <= 1.0, "warm start {}", first(&warm));
        assert!(warm.warmup_frames > 0 && warm.warmup_ms > 0.0);
        assert_eq!((cold.warmup_frames, cold.warmup_ms), (0, 0.0));
        let json = serde_json::to_value(&warm).unwrap();
        assert!(json["warmup_ms"].is_number() && json["warmup_frames"].is_number());
        a.warmup_ms = -1.0;
        assert!(zoom(&a).err().unwrap().contains("warmup-ms"));
        a.warmup_ms = f64::NAN;
        assert!(zoom(&a).err().unwrap().contains("warmup-ms"));
    }

    #[test]
    fn bad_zoom_arguments_are_refused() {
        let mut a = args();
        a.depth = 0.5;
        assert!(zoom(&a).err().unwrap().contains("--depth"));
        a.depth = 10.0;
        a.frames = 0;
        assert!(zoom(&a).err().unwrap().contains("--frames"));
        a.frames = 3;
        for n in [0, 5] {
            a.reference_samples = n;
            let e = zoom(&a).err().unwrap();
            assert!(
                e.contains("--reference-samples") && e.contains("1..=4"),
                "{e}"
            );
        }
        a.reference_samples = 2;
        a.fidelity = 100.0;
        assert!(zoom(&a).err().unwrap().contains("fidelity"));
        a.fidelity = 1.0;
        a.unify_every = 0;
        assert!(zoom(&a).err().unwrap().contains("unify-every"));
        a.unify_every = 4;
        a.beam = 300;
        assert!(zoom(&a).err().unwrap().contains("beam (tile side) 300"));
        a.beam = 8;
        a.beam_min = 0;
        assert!(zoom(&a).err().unwrap().contains("beam-min"));
        a.beam_min = 4;
        for bad in [-1.0, 65.0, f64::NAN, f64::INFINITY] {
            a.fovea = bad;
            let e = zoom(&a).err().unwrap();
            assert!(e.contains("fovea") && e.contains("[0, 64]"), "{e}");
        }
        for good in [0.0, 64.0] {
            a.fovea = good;
            assert!(zoom(&a).is_ok(), "fovea {good}");
        }
        a.fovea = 4.0;
        a.max_memory = "1K".into();
        assert!(zoom(&a).err().unwrap().contains("max memory"));
    }

    #[test]
    fn compared_frames_carry_similarity_voxel_size_and_camera() {
        let mut a = args();
        a.frames = 5;
        a.compare_every = 2;
        let r = run_zoom(&a, true).unwrap();
        let frames: Vec<usize> = r.compare.iter().map(|c| c.frame).collect();
        assert_eq!(frames, [0, 2, 4]);
        for c in &r.compare {
            assert!((-1.0..=1.0).contains(&c.agreement.ssim), "{c:?}");
            assert!((0.0..=1.0).contains(&c.agreement.iou), "{c:?}");
            assert!(c.largest_voxel_px > 0.0, "{c:?}");
        }
        // The zoom moves the camera: each comparison has its own.
        assert_ne!(r.compare[0].camera.eye, r.compare[2].camera.eye);
        let json = serde_json::to_value(&r).unwrap();
        let c0 = &json["compare"][0];
        for key in [
            "ssim",
            "iou",
            "colour_error",
            "largest_voxel_px",
            "camera",
            "zoom",
        ] {
            assert!(!c0[key].is_null(), "{key} missing in {c0}");
        }
        assert!(json["frames"][0]["largest_voxel_px"].is_number());
        // The compared images, side by side: the octree's left, the tracer's right, the
        // figures above measured on exactly these (SSIM of the halves' luminance, within the
        // 8-bit rounding of the written PNG).
        let dir = std::env::temp_dir().join(format!("fathom-compare-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        a.compare_images = Some(dir.clone());
        let r = run_zoom(&a, true).unwrap();
        for c in &r.compare {
            let img = image::open(dir.join(format!("compare_{:05}.png", c.frame)))
                .unwrap()
                .to_rgb8();
            assert_eq!(img.dimensions(), (32 + COMPARE_GAP + 32, 24));
            let lum = |x0: u32| -> Vec<f64> {
                (0..24)
                    .flat_map(|y| (0..32).map(move |x| (x, y)))
                    .map(|(x, y)| {
                        let p = img.get_pixel(x0 + x, y).0.map(|v| v as f64 / 255.0);
                        0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
                    })
                    .collect()
            };
            let ssim = fathom_render::compare::ssim(&lum(0), &lum(32 + COMPARE_GAP), 32, 24);
            assert!(
                (ssim - c.agreement.ssim).abs() < 0.01,
                "frame {}: halves' SSIM {ssim} against the reported {}",
                c.frame,
                c.agreement.ssim
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
        // Images without comparisons are refused, naming the flag that is missing.
        a.compare_every = 0;
        let e = run_zoom(&a, true).err().unwrap();
        assert!(e.contains("--compare-every"), "{e}");
        a.compare_images = None;
        // Off by default: no tracer frames.
        a.compare_every = 0;
        assert!(run_zoom(&a, true).unwrap().compare.is_empty());
    }

    #[test]
    fn every_scene_preset_and_a_scene_file_zoom_into_their_surface() {
        for p in fathom_core::presets::PRESETS {
            let mut a = args();
            a.preset = Some(p.name.into());
            let r = run_zoom(&a, true).unwrap_or_else(|e| panic!("{}: {e}", p.name));
            assert_eq!(r.preset, p.name);
            let last = r.frames.last().unwrap();
            assert!(last.hits > 0, "{}: the last frame shows no surface", p.name);
        }
        // A user's scene file: the mandelbulb preset's text saved to disk, aimed at a pixel.
        let dir = std::env::temp_dir().join(format!("fathom-zoom-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("mine.ron");
        std::fs::write(
            &file,
            fathom_core::presets::find("mandelbulb").unwrap().text,
        )
        .unwrap();
        let mut a = args();
        a.scene = Some(file.clone());
        a.pixel = Some((16, 12));
        let r = run_zoom(&a, true).unwrap();
        assert!(r.preset.ends_with("mine.ron"), "{}", r.preset);
        assert!(r.frames.last().unwrap().hits > 0);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn aimed_zooms_end_on_the_surface_they_aim_at() {
        // Toward the Menger sponge's centre from the path's first camera: the target is on
        // the sponge's surface, between the eye and the centre.
        let mut a = args();
        a.toward = Some(DVec3::ZERO);
        let p = zoom_path(&a).unwrap();
        let t = p.path.target().unwrap();
        let tape = fathom_core::Tape::compile(&p.scene).unwrap();
        let d = tape.eval_f64([t.x, t.y, t.z]).d;
        assert!(d > 0.0 && d < 1e-9, "distance at the target {d}");
        let m = t.abs().max_element();
        assert!(
            m > 0.99 && m <= 1.0 + 1e-12,
            "{t} is not on the sponge's outer faces"
        );
        let eye = fathom_core::camera_path::path_preset("menger")
            .unwrap()
            .camera(0, 3, 1e3)
            .eye;
        assert!(
            eye.normalize().dot(t.normalize()) > 1.0 - 1e-12,
            "{t} is off the ray"
        );
        // A pixel of the mandelbulb preset's view: the first camera looks at its target.
        let mut a = args();
        a.preset = Some("mandelbulb".into());
        a.pixel = Some((20, 10));
        let p = zoom_path(&a).unwrap();
        let c = p.camera(0, 3, 1e3);
        assert!((c.target - p.path.target().unwrap()).length() < 1e-12);
    }

    #[test]
    fn bad_aims_are_refused_with_what_missed() {
        let mut a = args();
        a.preset = Some("sierpinski".into());
        // The top-left pixel of the preset's view is sky.
        a.pixel = Some((0, 0));
        let e = zoom_path(&a).unwrap_err();
        assert!(e.contains("pixel 0,0") && e.contains("misses"), "{e}");
        a.pixel = Some((32, 5));
        let e = zoom_path(&a).unwrap_err();
        assert!(e.contains("outside the 32x24 image"), "{e}");
        a.pixel = None;
        // Away from the scene: behind the preset's eye.
        let eye = fathom_core::presets::load("sierpinski").unwrap().camera.eye;
        a.toward = Some(eye * 2.0);
        let e = zoom_path(&a).unwrap_err();
        assert!(
            e.contains("toward") && e.contains("direction") && e.contains("misses"),
            "{e}"
        );
        a.toward = Some(eye);
        let e = zoom_path(&a).unwrap_err();
        assert!(e.contains("no direction"), "{e}");
        a.toward = None;
        a.preset = Some("mandlebulb".into());
        let e = zoom_path(&a).unwrap_err();
        assert!(e.contains("mandelbulb") && e.contains("path preset"), "{e}");
        assert!(parse_pixel("3").is_err() && parse_pixel("a,2").is_err());
        assert_eq!(parse_pixel("3, 4"), Ok((3, 4)));
        let mut a = args();
        a.scene = Some("/nonexistent/scene.ron".into());
        assert!(zoom_path(&a).unwrap_err().contains("scene.ron"));
    }

    #[test]
    fn farm_shards_refuse_aims_and_scene_presets_they_cannot_rebuild() {
        let mut a = args();
        a.shard = Some("0/1".into());
        a.output = Some(std::env::temp_dir().join("fathom-zoom-shard-refusal"));
        a.pixel = Some((1, 1));
        let e = crate::cmd_farm::zoom_shard(&a).unwrap_err();
        assert!(e.contains("--shard renders the path presets"), "{e}");
        a.pixel = None;
        a.preset = Some("sierpinski".into());
        let e = crate::cmd_farm::zoom_shard(&a).unwrap_err();
        assert!(e.contains("sierpinski"), "{e}");
    }

    #[test]
    fn a_zoom_into_any_scene_stops_at_the_precision_limit_too() {
        let mut a = args();
        a.preset = Some("sierpinski".into());
        a.depth = 1e40;
        a.frames = 40;
        let r = run_zoom(&a, true).unwrap();
        let msg = r.stopped.expect("the zoom should have stopped");
        assert!(msg.contains("precision limit"), "{msg}");
    }

    #[test]
    fn zooms_go_past_f64_to_1e15_and_beyond() {
        for preset in ["menger", "mandelbulb"] {
            let mut a = args();
            a.preset = Some(preset.into());
            a.depth = 1e18;
            a.frames = 24;
            let r = run_zoom(&a, true).unwrap();
            assert!(r.stopped.is_none(), "{preset}: {:?}", r.stopped);
            assert_eq!(r.frames.len(), 24);
            let last = r.frames.last().unwrap();
            assert!(
                last.anchor_depth > 0,
                "{preset}: the last frame is relative to an anchor"
            );
            assert!(last.hits > 0, "{preset}: the last frame shows the surface");
        }
    }

    #[test]
    fn a_zoom_past_double_double_precision_stops_cleanly() {
        let mut a = args();
        a.depth = 1e40;
        a.frames = 40;
        let r = run_zoom(&a, true).unwrap();
        let msg = r.stopped.expect("the zoom should have stopped");
        assert!(msg.contains("precision limit"), "{msg}");
        assert!(r.frames.len() < 40 && r.frames.len() > 10);
    }
}
