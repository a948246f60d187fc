//! `fathom bench svo`: the dissertation's evaluation of the sparse voxel octree explorer,
//! reproduced. Writes `report.md`, `results.json` and PNG plots (plotters) to a directory.
//!
//! Experiments: fps against zoom depth for neighbour vs kd-restart traversal (Menger and
//! Mandelbulb); node and brick count over the zoom; fps against image size and fidelity;
//! 1 vs 2 threads; outline agreement with a sphere tracer; strict self-similarity of Menger
//! frames at 1/3, 1/9, 1/27 of the distance; picture quality during a 300-frame and a
//! 1000-frame zoom (per decade: SSIM, silhouette IoU and colour error against the sphere
//! tracer, largest visible voxel). The defaults are issue 15's: zooms to 1e15 at 640x480.

use crate::args::parse_size;
use clap::Args;
use fathom_core::camera_path::{CameraPath, path_preset};
use fathom_core::scenes;
use fathom_render::compare::DEEP_REFERENCE_PIXELS;
use fathom_render::zoom::{Zoom, ZoomReport};
use fathom_render::{Backend, OctreeSettings, RenderRequest};
use fathom_svo::outline::{agreement, similarity};
use fathom_svo::stats::median;
use fathom_svo::{OctreeView, OctreeViewConfig, RootSpec, Traversal};
use plotters::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path as FsPath, PathBuf};

#[derive(Args)]
pub struct SvoArgs {
    /// Directory for report.md, results.json and the plots.
    #[arg(long, default_value = "bench-svo")]
    pub out: PathBuf,
    /// Frames per zoom run.
    #[arg(long, default_value_t = 1000)]
    pub frames: usize,
    /// Zoom factor of the zoom runs (issue 15 asks for zooms to 1e15).
    #[arg(long, default_value_t = 1e15)]
    pub depth: f64,
    /// Image size of the zoom runs.
    #[arg(long, default_value = "640x480")]
    pub size: String,
    /// Small and fast: 160x120, 150 frames, zoom 1e5 (a smoke test of the whole bench).
    #[arg(long)]
    pub quick: bool,
    /// Frames of each picture-quality zoom (compared with the sphere tracer), comma-separated:
    /// one pair of zooms (Menger, Mandelbulb) per figure.
    #[arg(long, value_delimiter = ',', default_values_t = [300, 1000])]
    pub quality_frames: Vec<usize>,
    /// Compare every this many frames with the tracer, one figure per --quality-frames figure
    /// (or one for all), each >= 1. The defaults compare 30 and 20 frames of each zoom.
    #[arg(long, value_delimiter = ',', default_values_t = [10, 50])]
    pub compare_every: Vec<usize>,
    /// Run only the picture-quality zooms (per-decade similarity and largest voxel).
    #[arg(long)]
    pub quality_only: bool,
}

/// Picture quality of one decade of a zoom: medians over the frames compared with the tracer
/// (SSIM of luminance, silhouette IoU, colour error) and the largest visible voxel over every
/// frame of the decade.
#[derive(Serialize, Clone, Debug)]
struct DecadeQuality {
    preset: String,
    /// Frames of the zoom.
    frames: usize,
    /// log10 of the decade's lower zoom.
    decade: i32,
    compared: usize,
    median_ssim: f64,
    median_iou: f64,
    median_colour_error: f64,
    median_largest_voxel_px: f64,
    max_largest_voxel_px: f64,
}

/// How many decades of zoom `zoom` spans from 1 (the ceiling of log10 of its deepest zoom).
///
/// A plain loop, not `fold(1.0, f64::max)`: inlined into a test in a release build
/// (x86-64-v3), the fold made the deepest zoom of 1..1e3 count as a decade lower, and
/// `picture_quality_is_summarised_per_decade` failed under `cargo test --release` only. Not
/// reproduced outside the crate; the cause (the optimiser or our code) is not known.
fn decades(zoom: &[f64]) -> i32 {
    let mut top = 1.0f64;
    for &z in zoom {
        if z > top {
            top = z;
        }
    }
    top.log10().ceil() as i32
}

/// Per-decade picture quality of a zoom report with comparisons.
fn quality_per_decade(preset: &str, r: &ZoomReport) -> Vec<DecadeQuality> {
    let frames = r.frames.len();
    let top = decades(&r.zoom);
    let dec = |z: f64| (z.log10().floor() as i32).min(top.max(1) - 1);
    (0..top.max(1))
        .filter_map(|d| {
            let c: Vec<_> = r.compare.iter().filter(|c| dec(c.zoom) == d).collect();
            let vox: Vec<f64> = r
                .frames
                .iter()
                .zip(&r.zoom)
                .filter(|(_, z)| dec(**z) == d)
                .map(|(f, _)| f.largest_voxel_px)
                .collect();
            if vox.is_empty() {
                return None;
            }
            let m = |f: &dyn Fn(&fathom_render::zoom::FrameComparison) -> f64| {
                median(&c.iter().map(|x| f(x)).collect::<Vec<_>>())
            };
            Some(DecadeQuality {
                preset: preset.into(),
                frames,
                decade: d,
                compared: c.len(),
                median_ssim: m(&|x| x.agreement.ssim),
                median_iou: m(&|x| x.agreement.iou),
                median_colour_error: m(&|x| x.agreement.colour_error),
                median_largest_voxel_px: median(&vox),
                max_largest_voxel_px: vox.iter().copied().fold(0.0, f64::max),
            })
        })
        .collect()
}

/// A picture-quality section: `frames`-frame zooms of Menger and the Mandelbulb compared with
/// the sphere tracer every `every` frames; appends a table to `md` and returns the rows.
fn quality(
    md: &mut String,
    frames: usize,
    depth: f64,
    size: &str,
    every: usize,
) -> Result<Vec<DecadeQuality>, String> {
    let n = fathom_render::zoom::DEFAULT_REFERENCE_SAMPLES;
    let _ = writeln!(
        md,
        "## Picture quality during the zoom ({frames} frames to zoom {depth:.0e}, {size}, compared with the sphere tracer every {every} frames)\n\n\
         SSIM of display luminance (8x8 windows every 4 pixels), silhouette IoU and mean display-colour error per channel against the CPU sphere tracer at the same camera (soft shadows off: the octree bakes none), past zoom 1e6 against the double-double reference at most {DEEP_REFERENCE_PIXELS} pixels (80x60 at 640x480) with {n}x{n} rays a pixel and the octree frame reduced to its size (block means); largest visible voxel in pixels over every frame of the decade.\n\n\
         | preset | zoom decade | frames compared | median SSIM | median IoU | median colour error | median largest voxel px | max largest voxel px |\n|---|---|---|---|---|---|---|---|"
    );
    let mut rows = Vec::new();
    for preset in ["menger", "mandelbulb"] {
        eprintln!("bench svo: picture quality, {preset}");
        let mut z = zoom(Traversal::Neighbour, frames, depth, size)?;
        z.compare_every = every;
        let r = run_zoom(preset, &z)?;
        for q in quality_per_decade(preset, &r) {
            let _ = writeln!(
                md,
                "| {} | 1e{}-1e{} | {} | {:.3} | {:.3} | {:.3} | {:.2} | {:.2} |",
                q.preset,
                q.decade,
                q.decade + 1,
                q.compared,
                q.median_ssim,
                q.median_iou,
                q.median_colour_error,
                q.median_largest_voxel_px,
                q.max_largest_voxel_px
            );
            rows.push(q);
        }
    }
    let _ = writeln!(md);
    Ok(rows)
}

#[derive(Serialize, Default)]
struct Results {
    zooms: Vec<ZoomFigures>,
    size_fidelity: Vec<(String, f64, f64)>,
    threads: Vec<(usize, f64)>,
    outline: Vec<(String, fathom_svo::outline::Agreement)>,
    quality: Vec<DecadeQuality>,
    self_similarity: Vec<(String, f64, f64)>,
}

#[derive(Serialize)]
struct ZoomFigures {
    preset: String,
    traversal: String,
    summary: fathom_svo::stats::Summary,
    stopped: Option<String>,
}

/// A zoom of the bench: 2 threads, no SSAO, the octree defaults of `fathom zoom`.
fn zoom(t: Traversal, frames: usize, depth: f64, size: &str) -> Result<Zoom, String> {
    let (width, height) = parse_size(size)?;
    Ok(Zoom {
        depth,
        frames,
        request: RenderRequest {
            width,
            height,
            threads: Some(2),
            backend: Backend::Octree,
            octree: OctreeSettings {
                traversal: t,
                // As `fathom zoom` runs by default.
                target_fps: fathom_render::zoom::DEFAULT_TARGET_FPS,
                ..OctreeSettings::default()
            },
            ..RenderRequest::default()
        },
        compare_every: 0,
        reference_samples: fathom_render::zoom::DEFAULT_REFERENCE_SAMPLES,
        // The frame rates measure the zoom itself, from the root cube as they always have.
        warmup_ms: 0.0,
    })
}

/// Runs a zoom of `preset` without writing frames.
fn run_zoom(preset: &str, z: &Zoom) -> Result<ZoomReport, String> {
    let p = path_preset(preset).map_err(|e| e.to_string())?;
    z.run(&p.into(), false, |_| Ok(()))
        .map_err(|e| e.to_string())
}

/// fps per decade of zoom: (log10 zoom at the decade's middle, median fps).
fn per_decade(r: &ZoomReport) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let top = decades(&r.zoom);
    for d in 0..top.max(1) {
        let fps: Vec<f64> = r
            .frames
            .iter()
            .zip(&r.zoom)
            .filter(|(_, z)| z.log10() >= d as f64 && z.log10() < (d + 1) as f64)
            .map(|(f, _)| 1e3 / f.frame_ms.max(1e-6))
            .collect();
        if !fps.is_empty() {
            out.push((d as f64 + 0.5, median(&fps)));
        }
    }
    out
}

const COLOURS: [RGBColor; 4] = [RED, BLUE, GREEN, MAGENTA];

/// Line plot without text (the bitmap backend here has no font); axes are described in the
/// report. Returns an error message instead of failing the bench.
fn plot(path: &FsPath, series: &[Vec<(f64, f64)>]) -> Result<(), String> {
    let pts: Vec<&(f64, f64)> = series.iter().flatten().collect();
    if pts.is_empty() {
        return Err("no data".into());
    }
    let (x0, x1) = pts
        .iter()
        .fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p.0), a.1.max(p.0)));
    let y1 = pts.iter().fold(0.0f64, |a, p| a.max(p.1)) * 1.1 + 1e-9;
    let root = BitMapBackend::new(path, (640, 400)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(&root)
        .margin(20)
        .build_cartesian_2d(x0..x1.max(x0 + 1e-9), 0.0..y1)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_labels(0)
        .y_labels(0)
        .draw()
        .map_err(|e| e.to_string())?;
    for (s, c) in series.iter().zip(COLOURS.iter().cycle()) {
        chart
            .draw_series(LineSeries::new(s.iter().copied(), c.stroke_width(2)))
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())?;
    Ok(())
}

/// The picture-quality zooms to run, (frames, compare every), from the two flags: one
/// `--compare-every` figure for all, or one per `--quality-frames` figure; all >= 1.
fn quality_runs(frames: &[usize], every: &[usize]) -> Result<Vec<(usize, usize)>, String> {
    if frames.is_empty() || frames.contains(&0) {
        return Err(format!(
            "--quality-frames needs one or more frame counts >= 1, got {frames:?}"
        ));
    }
    if every.is_empty() || every.contains(&0) {
        return Err(format!(
            "--compare-every needs figures >= 1 (compare every this many frames), got {every:?}"
        ));
    }
    match every.len() {
        1 => Ok(frames.iter().map(|&f| (f, every[0])).collect()),
        n if n == frames.len() => Ok(frames.iter().copied().zip(every.iter().copied()).collect()),
        n => Err(format!(
            "--compare-every has {n} figures for {} --quality-frames figures: give one for \
             all, or one each",
            frames.len()
        )),
    }
}

fn range(series: &[Vec<(f64, f64)>]) -> String {
    let pts: Vec<&(f64, f64)> = series.iter().flatten().collect();
    let (x0, x1) = pts
        .iter()
        .fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p.0), a.1.max(p.0)));
    let y1 = pts.iter().fold(0.0f64, |a, p| a.max(p.1)) * 1.1;
    format!("x from {x0:.3} to {x1:.3}, y from 0 to {y1:.3}")
}

pub fn run(a: SvoArgs) -> Result<(), String> {
    let (frames, depth, size) = if a.quick {
        (150, 1e5, "160x120".to_string())
    } else {
        (a.frames, a.depth, a.size.clone())
    };
    parse_size(&size)?;
    let runs = if a.quick {
        vec![(60, 5)]
    } else {
        quality_runs(&a.quality_frames, &a.compare_every)?
    };
    std::fs::create_dir_all(&a.out)
        .map_err(|e| format!("cannot create {}: {e}", a.out.display()))?;
    let mut md = String::new();
    let mut res = Results::default();
    let flags = match (a.quick, a.quality_only) {
        (true, true) => " --quick --quality-only",
        (true, false) => " --quick",
        (false, true) => " --quality-only",
        (false, false) => "",
    };
    if a.quality_only {
        // Only the picture-quality zooms run: their own frame count is in their heading.
        let _ = writeln!(
            md,
            "# SVO explorer evaluation: picture quality\n\nGenerated by `fathom bench svo{flags}`: zoom {depth:.0e}, {size}, 2 threads.\n"
        );
    } else {
        let _ = writeln!(
            md,
            "# SVO explorer evaluation\n\nGenerated by `fathom bench svo{flags}`: {frames} frames per zoom, zoom {depth:.0e}, {size}, 2 threads unless stated. \
             Plots have no text (no font in the bitmap backend); each plot's axes and series are listed under it.\n"
        );
    }

    // 0. Picture quality during the zooms.
    for (qf, qe) in runs {
        res.quality.extend(quality(&mut md, qf, depth, &size, qe)?);
    }
    if a.quality_only {
        return write_report(&a.out, &md, &res);
    }

    // 1. fps against zoom depth, neighbour vs kd-restart; node and brick counts.
    let _ = writeln!(
        md,
        "## fps against zoom depth\n\n| preset | traversal | median fps (settled) | last/first decade fps | nodes/ray (last decade) | peak resident MiB | max/first-cycle nodes | stopped |\n|---|---|---|---|---|---|---|---|"
    );
    let mut speedups = Vec::new();
    for preset in ["menger", "mandelbulb"] {
        let mut series = Vec::new();
        let mut last = Vec::new();
        for t in [Traversal::Neighbour, Traversal::KdRestart] {
            eprintln!("bench svo: {preset} {t:?}");
            let r = run_zoom(preset, &zoom(t, frames, depth, &size)?)?;
            let s = &r.summary;
            let _ = writeln!(
                md,
                "| {preset} | {t:?} | {:.1} | {:.2} | {:.1} | {:.1} | {:.3} | {} |",
                s.median_fps_settled,
                s.last_over_first,
                s.nodes_per_ray_last_decade,
                s.peak_resident_bytes as f64 / 1048576.0,
                s.max_over_first_cycle,
                r.stopped.as_deref().map(|_| "precision").unwrap_or("no")
            );
            last.push(s.median_fps_last_decade);
            series.push(per_decade(&r));
            if t == Traversal::Neighbour && preset == "menger" {
                let nodes: Vec<(f64, f64)> = r
                    .frames
                    .iter()
                    .map(|f| (f.frame as f64, f.node_count as f64))
                    .collect();
                let bricks: Vec<(f64, f64)> = r
                    .frames
                    .iter()
                    .map(|f| (f.frame as f64, f.brick_count as f64))
                    .collect();
                let p1 = a.out.join("menger-nodes.png");
                let p2 = a.out.join("menger-bricks.png");
                let e1 = plot(&p1, std::slice::from_ref(&nodes)).err();
                let e2 = plot(&p2, std::slice::from_ref(&bricks)).err();
                let _ = writeln!(
                    md,
                    "\n![nodes](menger-nodes.png) node count per frame ({}){}\n\n![bricks](menger-bricks.png) brick count per frame ({}){}\n",
                    range(&[nodes]),
                    e1.map(|e| format!(" plot failed: {e}")).unwrap_or_default(),
                    range(&[bricks]),
                    e2.map(|e| format!(" plot failed: {e}")).unwrap_or_default()
                );
            }
            res.zooms.push(ZoomFigures {
                preset: preset.into(),
                traversal: format!("{t:?}"),
                summary: r.summary.clone(),
                stopped: r.stopped.clone(),
            });
        }
        let sp = if last[1] > 0.0 {
            last[0] / last[1]
        } else {
            0.0
        };
        speedups.push((preset, sp));
        let png = format!("{preset}-fps.png");
        let e = plot(&a.out.join(&png), &series).err();
        let _ = writeln!(
            md,
            "\n![fps]({png}) {preset}: median fps per decade of zoom, x = log10 zoom, red neighbour, blue kd-restart ({}){}\n",
            range(&series),
            e.map(|e| format!(" plot failed: {e}")).unwrap_or_default()
        );
    }
    for (p, s) in &speedups {
        let _ = writeln!(
            md,
            "- {p}: neighbour / kd-restart median fps over the deepest decade: {s:.2}x"
        );
    }

    // 2. fps against image size and fidelity (Mandelbulb zoom start).
    let _ = writeln!(
        md,
        "\n## fps against image size and fidelity (Mandelbulb, first 60 frames)\n\n| size | fidelity | median fps (frames 30..60) |\n|---|---|---|"
    );
    let sizes = if a.quick {
        vec!["80x60", "160x120"]
    } else {
        vec!["160x120", "320x240", "640x480"]
    };
    let mut fid_series = Vec::new();
    for fid in [1.0, 2.0, 4.0] {
        let mut s = Vec::new();
        for sz in &sizes {
            let mut z = zoom(Traversal::Neighbour, 60, 10.0, sz)?;
            z.request.octree.fidelity = fid;
            let r = run_zoom("mandelbulb", &z)?;
            let fps: Vec<f64> = r.frames[30.min(r.frames.len())..]
                .iter()
                .map(|f| 1e3 / f.frame_ms)
                .collect();
            let m = median(&fps);
            let _ = writeln!(md, "| {sz} | {fid} | {m:.1} |");
            res.size_fidelity.push((sz.to_string(), fid, m));
            s.push((parse_size(sz)?.0 as f64, m));
        }
        fid_series.push(s);
    }
    let e = plot(&a.out.join("size-fidelity.png"), &fid_series).err();
    let _ = writeln!(
        md,
        "\n![size](size-fidelity.png) x = image width, y = median fps; red fidelity 1, blue 2, green 4 ({}){}\n",
        range(&fid_series),
        e.map(|e| format!(" plot failed: {e}")).unwrap_or_default()
    );

    // 3. Threads.
    let _ = writeln!(
        md,
        "## 1 vs 2 threads (Menger, first 60 frames, {size})\n\n| threads | median fps (frames 30..60) |\n|---|---|"
    );
    for th in [1, 2] {
        let mut z = zoom(Traversal::Neighbour, 60, 10.0, &size)?;
        z.request.threads = Some(th);
        let r = run_zoom("menger", &z)?;
        let fps: Vec<f64> = r.frames[30.min(r.frames.len())..]
            .iter()
            .map(|f| 1e3 / f.frame_ms)
            .collect();
        let m = median(&fps);
        let _ = writeln!(md, "| {th} | {m:.1} |");
        res.threads.push((th, m));
    }

    // 4. Outline agreement with a sphere tracer.
    let _ = writeln!(
        md,
        "\n## Outline agreement with a sphere tracer (160x120, voxels <= 0.5 px, tracer hit within 0.3 px)\n\n| scene | IoU | tracer hits missed | tracer hits |\n|---|---|---|---|"
    );
    let mb = fathom_core::presets::load("mandelbulb").map_err(|e| e.to_string())?;
    let mbox = scenes::mandelbox();
    let cases = [
        (
            "menger",
            scenes::menger(6),
            path_preset("menger")
                .map_err(|e| e.to_string())?
                .camera(0, 2, 1.0),
            2.0,
        ),
        ("mandelbulb", mb.clone(), mb.camera.clone(), 2.0),
        ("mandelbox", mbox.clone(), mbox.camera.clone(), 4.0),
    ];
    for (name, scene, cam, half) in cases {
        let cfg = OctreeViewConfig {
            width: 160,
            height: 120,
            fidelity: 0.5,
            root: RootSpec::centred(half),
            ..OctreeViewConfig::default()
        };
        let ag = agreement(&scene, &cam, cfg, 0.3).map_err(|e| e.to_string())?;
        let _ = writeln!(
            md,
            "| {name} | {:.4} | {} | {} |",
            ag.iou, ag.missed, ag.tracer_hits
        );
        res.outline.push((name.into(), ag));
    }

    // 5. Strict self-similarity at 1/3, 1/9, 1/27.
    let _ = writeln!(
        md,
        "\n## Strict self-similarity of the Menger corner (320x240, settled)\n\n| pair | identical pixels | within 10% colour |\n|---|---|---|"
    );
    let p = path_preset("menger").map_err(|e| e.to_string())?;
    let CameraPath::Zoom {
        target, dir, start, ..
    } = p.path.clone()
    else {
        return Err("menger preset is not a zoom".into());
    };
    let mut imgs = Vec::new();
    for k in 0..4 {
        let s = start / 3f64.powi(k) * 0.5;
        let cam = fathom_core::Camera {
            eye: target + dir * s,
            target,
            up: glam::DVec3::Y,
            fov: p.fov,
        };
        let cfg = OctreeViewConfig {
            width: 320,
            height: 240,
            root: RootSpec::from_cube(p.cube),
            ..OctreeViewConfig::default()
        };
        let mut ex = OctreeView::new(&p.scene, cfg).map_err(|e| e.to_string())?;
        ex.settle(&cam, 200);
        let (img, reqs, _) = ex.render(&cam);
        ex.release_requests(&reqs);
        imgs.push(img);
    }
    for k in 1..4 {
        let (same, close) = similarity(&imgs[0], &imgs[k], 0.1);
        let name = format!("1 vs 1/{}", 3u32.pow(k as u32));
        let _ = writeln!(
            md,
            "| {name} | {:.1}% | {:.1}% |",
            same * 100.0,
            close * 100.0
        );
        res.self_similarity.push((name, same, close));
    }

    write_report(&a.out, &md, &res)
}

/// Writes report.md and results.json to `out` and prints the report.
fn write_report(out: &FsPath, md: &str, res: &Results) -> Result<(), String> {
    fathom_core::atomic_file::write(&out.join("report.md"), md).map_err(|e| e.to_string())?;
    fathom_core::atomic_file::write(
        &out.join("results.json"),
        serde_json::to_string_pretty(res).map_err(|e| e.to_string())?,
    )
    .map_err(|e| e.to_string())?;
    println!("{md}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_render::compare::Agreement;
    use fathom_render::zoom::FrameComparison;
    use fathom_svo::FrameStats;

    #[test]
    fn quality_zooms_pair_frame_counts_with_comparison_steps_or_say_what_is_wrong() {
        assert_eq!(
            quality_runs(&[300, 1000], &[10, 50]),
            Ok(vec![(300, 10), (1000, 50)])
        );
        assert_eq!(
            quality_runs(&[300, 1000], &[25]),
            Ok(vec![(300, 25), (1000, 25)])
        );
        let e = quality_runs(&[300, 1000], &[10, 20, 30]).unwrap_err();
        assert!(e.contains("3 figures for 2"), "{e}");
        let e = quality_runs(&[300], &[0]).unwrap_err();
        assert!(e.contains("--compare-every") && e.contains(">= 1"), "{e}");
        let e = quality_runs(&[0], &[10]).unwrap_err();
        assert!(e.contains("--quality-frames"), "{e}");
        let e = quality_runs(&[], &[10]).unwrap_err();
        assert!(e.contains("--quality-frames"), "{e}");
    }

    #[test]
    fn picture_quality_is_summarised_per_decade() {
        let zoom: Vec<f64> = (0..7).map(|i| 10f64.powf(i as f64 * 0.5)).collect(); // 1 .. 1e3
        let frames: Vec<FrameStats> = (0..7)
            .map(|i| FrameStats {
                frame: i,
                largest_voxel_px: 10.0 - i as f64,
                ..FrameStats::default()
            })
            .collect();
        let cmp = |i: usize, ssim: f64| FrameComparison {
            frame: i,
            zoom: zoom[i],
            camera: fathom_core::Camera::default(),
            largest_voxel_px: frames[i].largest_voxel_px,
            agreement: Agreement {
                ssim,
                iou: 1.0,
                colour_error: 0.0,
                colour_within: 1.0,
            },
            trace_ms: 0.0,
            reference: "f64",
            reduced: 1,
            reference_samples: 1,
        };
        let r = ZoomReport {
            preset: "p".into(),
            traversal: Traversal::Neighbour,
            width: 8,
            height: 6,
            depth: 1e3,
            threads: 1,
            fidelity: 1.0,
            stopped: None,
            warmup_ms: 0.0,
            warmup_frames: 0,
            summary: Default::default(),
            zoom: zoom.clone(),
            frames: frames.clone(),
            compare: vec![cmp(0, 0.2), cmp(1, 0.4), cmp(4, 0.9), cmp(6, 0.95)],
        };
        let q = quality_per_decade("p", &r);
        // Decades 1-10 (frames 0, 1), 10-100 (2, 3), 100-1000 (4, 5, and the last frame at
        // exactly 1e3 counts in the top decade).
        assert_eq!(q.iter().map(|d| d.decade).collect::<Vec<_>>(), [0, 1, 2]);
        assert_eq!(q[0].compared, 2);
        assert!((q[0].median_ssim - 0.3).abs() < 1e-12);
        assert_eq!(q[0].max_largest_voxel_px, 10.0);
        assert_eq!(q[1].compared, 0);
        assert_eq!(q[2].compared, 2);
        assert_eq!(q[2].median_largest_voxel_px, 5.0);
        assert!(q.iter().all(|d| d.frames == 7));
    }
}
