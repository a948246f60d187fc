//! `fathom bench gpu`: per preset, milliseconds per frame and distance evaluations per pixel of
//! the GPU renderer, next to the CPU tracer's figures for the same preset in the same run, with
//! the adapter's name. On a software adapter (lavapipe, llvmpipe) the "GPU" figures are CPU
//! timings too, and the JSON says so.

use clap::Args;
use fathom_core::presets::{self, PRESETS};
use fathom_render::{Backend, RenderRequest, Session};

#[derive(Args)]
pub struct GpuArgs {
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480", value_parser = crate::args::parse_size)]
    pub size: (u32, u32),
    /// Timed frames per preset and renderer (after one untimed warm-up frame on the GPU).
    #[arg(long, default_value_t = 3)]
    pub frames: u32,
    /// Only this preset.
    #[arg(long)]
    pub preset: Option<String>,
}

pub fn run(a: GpuArgs) -> Result<(), String> {
    if !(1..=100).contains(&a.frames) {
        return Err("--frames must be in [1, 100]".into());
    }
    let (width, height) = a.size;
    let names: Vec<&str> = match &a.preset {
        Some(p) => vec![presets::find(p).map_err(|e| e.to_string())?.name],
        None => PRESETS.iter().map(|p| p.name).collect(),
    };
    let renderer = fathom_gpu::Renderer::headless().map_err(|e| e.to_string())?;
    let adapter = renderer.gpu().adapter_name();
    let software = renderer.gpu().is_software();
    let mut renderer = Some(renderer);
    let gpu_req = RenderRequest {
        width,
        height,
        backend: Backend::Gpu,
        ..RenderRequest::default()
    };
    let cpu_req = RenderRequest {
        backend: Backend::Trace,
        ..gpu_req.clone()
    };
    let mut rows = Vec::new();
    for name in names {
        let scene = presets::load(name).map_err(|e| e.to_string())?;
        let cam = scene.camera.clone();
        let mut s = Session::new(scene).map_err(|e| e.to_string())?;
        // One device for the whole run: the session hands it back when it is dropped below.
        s.set_gpu(renderer.take().expect("returned after each preset"));
        let mut frame = |req: &RenderRequest| s.render(&cam, req).map_err(|e| e.to_string());
        // Warm-up: uploads the tape and sizes the buffers.
        frame(&gpu_req)?;
        let mut gpu_ms = Vec::new();
        let mut gpu_de = 0.0;
        for _ in 0..a.frames {
            let r = frame(&gpu_req)?;
            gpu_ms.push(r.stats.ms.total);
            gpu_de = r.stats.depth_de_per_pixel;
        }
        let mut cpu_ms = Vec::new();
        let mut cpu_de = 0.0;
        for _ in 0..a.frames {
            let r = frame(&cpu_req)?;
            cpu_ms.push(r.stats.ms.total);
            cpu_de = r.stats.depth_de_per_pixel;
        }
        renderer = s.take_gpu();
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
        "adapter": adapter,
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
