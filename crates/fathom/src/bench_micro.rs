//! `fathom bench micro`: the microgeometry figures of docs/micro.md. Per demo: triangle and
//! tetrahedron counts, ms per frame and texture evaluations per pixel on the CPU renderer and
//! on the GPU renderer (lavapipe here: CPU timings, and the JSON says so); then the baked-grid
//! error against the exact texture and its memory at each resolution. Prints JSON with the
//! load average, which moves every figure on a shared machine.

use clap::Args;
use fathom_core::{Evaluator, V3};
use fathom_micro::grid::Grid;
use fathom_micro::request::{Prepared, Request};
use fathom_micro::texture::{Field, Texture};
use std::time::Instant;

#[derive(Args)]
pub struct MicroBenchArgs {
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = crate::args::parse_size)]
    pub size: (u32, u32),
    /// Timed frames per demo and renderer (after one untimed warm-up frame).
    #[arg(long, default_value_t = 1)]
    pub frames: u32,
    /// Only this demo (teapot or bush).
    #[arg(long)]
    pub demo: Option<String>,
    /// Skip the GPU renderer.
    #[arg(long)]
    pub no_gpu: bool,
    /// Baked-grid resolutions to measure.
    #[arg(long, value_delimiter = ',', default_value = "64,128,256")]
    pub bake: Vec<u32>,
    /// Random points for each baked-grid error.
    #[arg(long, default_value_t = 20000)]
    pub samples: usize,
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

pub fn run(a: MicroBenchArgs) -> Result<(), String> {
    if !(1..=100).contains(&a.frames) {
        return Err("--frames must be in [1, 100]".into());
    }
    let demos: Vec<String> = match &a.demo {
        Some(d) => vec![d.clone()],
        None => fathom_micro::demo::DEMOS
            .iter()
            .map(|d| d.0.to_string())
            .collect(),
    };
    let mut gpu = if a.no_gpu {
        None
    } else {
        Some(fathom_micro::gpu::MicroGpu::headless().map_err(|e| e.to_string())?)
    };
    let load_before = load_average();
    let mut rows = Vec::new();
    for name in &demos {
        let mut r = Request::new();
        r.demo = Some(name.clone());
        (r.width, r.height) = a.size;
        let Prepared::Shell { scene, options, .. } = r.prepare().map_err(|e| e.to_string())? else {
            return Err("a demo always has a mesh".into());
        };
        let mut cpu_ms = Vec::new();
        let mut cpu = None;
        for k in 0..=a.frames {
            let (_, s) =
                fathom_micro::render(&scene, &options, &|_, _| {}).map_err(|e| e.to_string())?;
            if k > 0 {
                cpu_ms.push(s.ms_total);
            }
            cpu = Some(s);
        }
        let cpu = cpu.expect("one frame");
        let gpu_row = match gpu.as_mut() {
            None => serde_json::Value::Null,
            Some(g) => {
                let tape = scene.texture.tape().ok_or("the demo's texture is exact")?;
                let mut ms = Vec::new();
                let mut last = None;
                let t0 = Instant::now();
                for k in 0..=a.frames {
                    let (_, s) = g
                        .render(&scene, tape, &options)
                        .map_err(|e| e.to_string())?;
                    if k > 0 {
                        ms.push(s.ms_total);
                    }
                    last = Some(s);
                }
                let first_ms = t0.elapsed().as_secs_f64() * 1e3 - ms.iter().sum::<f64>();
                let s = last.expect("one frame");
                serde_json::json!({
                    "ms_per_frame_median": median(&mut ms.clone()),
                    "ms_per_frame_all": ms,
                    "ms_first_frame_with_pipeline_compile": first_ms,
                    "de_per_pixel": s.de_per_pixel(),
                    "fragments": s.tets_visited,
                    "hits": s.hits,
                })
            }
        };
        // Baked grids of the demo's texture over its cell.
        let tape = scene.texture.tape().ok_or("the demo's texture is exact")?;
        let exact =
            |ev: &mut Evaluator<f64>, p: glam::DVec3| ev.distance(tape, V3::new(p.x, p.y, p.z));
        let mut bakes = Vec::new();
        for &n in &a.bake {
            let t0 = Instant::now();
            let g = Grid::bake(tape, scene.shell.tiling.cell, n).map_err(|e| e.to_string())?;
            let bake_ms = t0.elapsed().as_secs_f64() * 1e3;
            let err = g.error_against(exact, a.samples);
            let mem = g.memory_bytes();
            // A frame with the baked texture instead of the exact one.
            let baked = fathom_micro::MicroScene::new(
                scene.shell.clone(),
                Texture {
                    field: Field::Grid(g),
                    materials: scene.texture.materials.clone(),
                    origin: format!("baked {n}"),
                },
                scene.lighting.clone(),
                scene.base.clone(),
            );
            let (_, s) =
                fathom_micro::render(&baked, &options, &|_, _| {}).map_err(|e| e.to_string())?;
            bakes.push(serde_json::json!({
                "resolution": n,
                "memory_bytes": mem,
                "memory_mib": mem as f64 / (1 << 20) as f64,
                "bake_ms": bake_ms,
                "error_mean_abs": err.mean_abs,
                "error_max_abs": err.max_abs,
                "error_near_surface_mean_abs": err.near_surface_mean_abs,
                "near_surface_samples": err.near_surface_samples,
                "samples": err.samples,
                "cpu_ms_per_frame": s.ms_total,
                "cpu_de_per_pixel": s.de_per_pixel(),
            }));
        }
        rows.push(serde_json::json!({
            "demo": name,
            "triangles": scene.shell.report.triangles,
            "tetrahedra": scene.shell.report.tetrahedra,
            "tetrahedra_skipped_inverted": scene.shell.report.skipped_inverted,
            "lipschitz_median": scene.shell.report.lipschitz_median,
            "lipschitz_max": scene.shell.report.lipschitz_max,
            "cpu": {
                "ms_per_frame_median": median(&mut cpu_ms.clone()),
                "ms_per_frame_all": cpu_ms,
                "de_per_pixel": cpu.de_per_pixel(),
                "de_march_per_pixel": cpu.de_march as f64 / (a.size.0 as f64 * a.size.1 as f64),
                "tets_marched_per_pixel": cpu.tets_visited as f64 / (a.size.0 as f64 * a.size.1 as f64),
                "hits": cpu.hits,
                "threads": rayon::current_num_threads(),
            },
            "gpu": gpu_row,
            "baked": bakes,
        }));
    }
    let out = serde_json::json!({
        "bench": "micro",
        "width": a.size.0,
        "height": a.size.1,
        "frames": a.frames,
        "adapter": gpu.as_ref().map(|g| g.adapter_name()),
        "adapter_is_software": gpu.as_ref().map(|g| g.is_software()),
        "note": "GPU figures on a software adapter (lavapipe) are CPU timings, not GPU speed; they include upload, the draw and the readback",
        "load_average_before": load_before,
        "load_average_after": load_average(),
        "demos": rows,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?
    );
    Ok(())
}
