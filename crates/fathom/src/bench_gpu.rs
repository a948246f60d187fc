//! `fathom bench gpu`: per preset, milliseconds per frame and distance evaluations per pixel of
//! the GPU renderer, next to the CPU tracer's figures for the same preset in the same run, with
//! the adapter's name. On a software adapter (lavapipe, llvmpipe) the "GPU" figures are CPU
//! timings too, and the JSON says so.

use clap::Args;
use fathom_core::presets::{self, PRESETS};
use fathom_gpu::{Projection, RenderOptions, Renderer};

#[derive(Args)]
pub struct GpuArgs {
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Timed frames per preset and renderer (after one untimed warm-up frame on the GPU).
    #[arg(long, default_value_t = 3)]
    pub frames: u32,
    /// Only this preset.
    #[arg(long)]
    pub preset: Option<String>,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size `{s}` should look like 640x480"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| (1..=16384).contains(&n))
            .ok_or_else(|| format!("size `{s}`: `{v}` is not a whole number in [1, 16384]"))
    };
    Ok((p(w)?, p(h)?))
}

pub fn run(a: GpuArgs) -> Result<(), String> {
    if !(1..=100).contains(&a.frames) {
        return Err("--frames must be in [1, 100]".into());
    }
    let (width, height) = a.size;
    let names: Vec<&str> = match &a.preset {
        Some(p) => vec![presets::find(p)?.name],
        None => PRESETS.iter().map(|p| p.name).collect(),
    };
    let mut r = Renderer::headless().map_err(|e| e.to_string())?;
    let software = r.gpu().is_software();
    let mut rows = Vec::new();
    for name in names {
        let scene = presets::load(name)?;
        let o = RenderOptions {
            width,
            height,
            projection: Projection::Mono,
            prepass: true,
        };
        // Warm-up: uploads the tape and sizes the buffers.
        r.render_scene(&scene, &o).map_err(|e| e.to_string())?;
        let mut gpu_ms = Vec::new();
        let mut gpu_de = 0.0;
        for _ in 0..a.frames {
            let (_, s) = r.render_scene(&scene, &o).map_err(|e| e.to_string())?;
            gpu_ms.push(s.ms_total);
            gpu_de = s.de_per_pixel();
        }
        let co = fathom_trace::Options {
            width,
            height,
            ..Default::default()
        };
        let mut cpu_ms = Vec::new();
        let mut cpu_de = 0.0;
        for _ in 0..a.frames {
            let (_, s) = fathom_trace::render(&scene, &co, &|_, _| {})?;
            cpu_ms.push(s.ms_total);
            cpu_de = s.de_per_pixel();
        }
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        rows.push(serde_json::json!({
            "preset": name,
            "gpu": {
                "ms_per_frame_median": median(&mut gpu_ms),
                "ms_per_frame_all": gpu_ms,
                "depth_de_per_pixel": gpu_de,
            },
            "cpu": {
                "ms_per_frame_median": median(&mut cpu_ms),
                "ms_per_frame_all": cpu_ms,
                "depth_de_per_pixel": cpu_de,
                "threads": rayon::current_num_threads(),
            },
        }));
    }
    let out = serde_json::json!({
        "bench": "gpu",
        "width": width,
        "height": height,
        "frames": a.frames,
        "adapter": r.gpu().adapter_name(),
        "adapter_is_software": software,
        "note": if software {
            "the adapter is a CPU implementation of Vulkan (e.g. lavapipe): its figures are CPU timings, not GPU speed"
        } else {
            "GPU figures include upload, all passes and the readback of the G-buffer"
        },
        "presets": rows,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?
    );
    Ok(())
}
