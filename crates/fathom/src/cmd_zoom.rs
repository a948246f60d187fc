//! `fathom zoom`: the scale-adaptive sparse voxel octree explorer on an automated camera path
//! (a point-of-recursion zoom or a tour), writing frames and per-frame stats. The flags become
//! a [`Zoom`] of the render layer, which runs the frame loop; this module writes the frames.

use crate::args::{parse_bytes, parse_size};
use clap::{Args, ValueEnum};
use fathom_core::camera_path::{PATH_PRESETS, path_preset};
use fathom_render::zoom::{Zoom, ZoomReport};
use fathom_render::{OctreeSettings, RenderRequest};
use fathom_svo::Traversal;
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
///   fathom zoom --preset menger --depth 1e6 --frames 240 --shard 2/8 -o zoom/   (a farm shard)
#[derive(Args, Clone)]
#[command(verbatim_doc_comment)]
pub struct ZoomArgs {
    /// Path preset: menger (zoom into the corner, a point of recursion), mandelbulb (zoom
    /// into a surface point), menger-tour (a flight around and into the sponge).
    #[arg(long, default_value = "menger", value_parser = clap::builder::PossibleValuesParser::new(PATH_PRESETS))]
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
    /// Render farm: render shard I of N of the zoom's frames into the job directory -o DIR,
    /// each frame a settled still on a fresh octree (so it does not depend on the frames
    /// before it; slower than the stepped zoom, and not the same images). Without a value:
    /// from SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT.
    #[arg(long, value_name = "I/N", num_args = 0..=1, default_missing_value = "")]
    pub shard: Option<String>,
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
                unify_every: a.unify_every,
                ..OctreeSettings::default()
            },
            ..RenderRequest::default()
        },
    };
    z.validate().map_err(|e| e.to_string())?;
    z.request.validate().map_err(|e| e.to_string())?;
    Ok(z)
}

/// Runs a zoom, writing frames if `a.output` is set and a progress line every 100 frames
/// unless `quiet`. Returns the report.
pub fn run_zoom(a: &ZoomArgs, quiet: bool) -> Result<ZoomReport, String> {
    let z = zoom(a)?;
    let preset = path_preset(&a.preset).map_err(|e| e.to_string())?;
    if let Some(dir) = &a.output {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let report = z
        .run(&preset, a.output.is_some(), |i, zoom, frame, st| {
            if let (Some(dir), Some(f)) = (&a.output, frame) {
                let path = dir.join(format!("frame_{i:05}.png"));
                let file = fathom_trace::output::open_output(&path).map_err(|e| e.to_string())?;
                fathom_trace::output::save_colour(f, file, &path).map_err(|e| e.to_string())?;
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

pub fn run(a: ZoomArgs) -> Result<(), String> {
    if a.shard.is_some() {
        return crate::cmd_farm::zoom_shard(&a);
    }
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
        assert!(zoom(&a).err().unwrap().contains("--depth"));
        a.depth = 10.0;
        a.frames = 0;
        assert!(zoom(&a).err().unwrap().contains("--frames"));
        a.frames = 3;
        a.fidelity = 100.0;
        assert!(zoom(&a).err().unwrap().contains("fidelity"));
        a.fidelity = 1.0;
        a.unify_every = 0;
        assert!(zoom(&a).err().unwrap().contains("unify-every"));
        a.unify_every = 4;
        a.max_memory = "1K".into();
        assert!(zoom(&a).err().unwrap().contains("max memory"));
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
