//! `fathom bench pathtrace`: the path tracer's speed and convergence. Per preset: camera paths
//! per second at 640x480; time until the image is within 2 % RMSE (relative to the mean) of a
//! high-spp reference of another seed, raw and denoised (at a smaller size, the reference
//! costs reference-spp samples a pixel); and the time of one accumulation pass (one sample a
//! pixel) of the session at the explorer's 1280x720. With `--gpu`, also the GPU path
//! tracer's paths per second at the same size (after a warm-up pass that compiles the
//! pipeline), labelled with the adapter and whether it is a software one (lavapipe: CPU
//! timings, not GPU speed). Prints JSON with the load average, since the machines here are
//! shared.

use clap::Args;
use fathom_core::presets;
use fathom_core::tape::Tape;
use fathom_pathtrace::output::relative_rmse;
use fathom_pathtrace::{Control, DenoiseSettings, PathSettings, PathTracer, Progressive, denoise};
use fathom_render::{Backend, RenderRequest, Session};
use serde_json::json;
use std::time::Instant;

#[derive(Args)]
pub struct PathTraceBenchArgs {
    /// Presets to measure, comma-separated.
    #[arg(long, default_value = "menger,mandelbulb,model-tree")]
    presets: String,
    /// Image size of the paths-per-second run.
    #[arg(long, default_value = "640x480", value_parser = crate::args::parse_size)]
    size: (u32, u32),
    /// Samples per pixel of the paths-per-second run.
    #[arg(long, default_value_t = 4)]
    spp: u32,
    /// Image size of the convergence runs.
    #[arg(long, default_value = "160x120", value_parser = crate::args::parse_size)]
    converge_size: (u32, u32),
    /// Samples per pixel of the convergence reference (0: skip convergence).
    #[arg(long, default_value_t = 4096)]
    reference_spp: u32,
    /// Target error: relative RMSE against the reference.
    #[arg(long, default_value_t = 0.02)]
    target_rmse: f64,
    /// Worker threads.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// Skip the explorer's 1280x720 accumulation pass.
    #[arg(long)]
    no_explorer: bool,
    /// Also measure the GPU path tracer (fathom-gpu) at --size and --spp.
    #[arg(long)]
    gpu: bool,
}

/// The GPU path tracer's paths per second for `scene` at `size`, `spp` samples a pixel, after
/// one warm-up pass (a software adapter compiles the pipeline on its first dispatch).
fn gpu_entry(
    renderer: &mut fathom_gpu::Renderer,
    scene: &fathom_core::Scene,
    tape: &Tape,
    size: (u32, u32),
    spp: u32,
) -> Result<serde_json::Value, String> {
    let e = |e: fathom_gpu::GpuError| e.to_string();
    renderer.set_tape(tape).map_err(e)?;
    let settings = || PathSettings::new(size.0, size.1);
    let t = Instant::now();
    renderer.path_begin(scene, tape, settings()).map_err(e)?;
    renderer
        .path_add_samples(1, u32::MAX, &Control::default())
        .map_err(e)?;
    let warmup = t.elapsed().as_secs_f64();
    renderer.path_begin(scene, tape, settings()).map_err(e)?;
    renderer
        .path_add_samples(spp, u32::MAX, &Control::default())
        .map_err(e)?;
    let (_, st) = renderer.path_frame().map_err(e)?;
    let g = renderer.gpu();
    Ok(json!({
        "adapter": g.adapter_name(),
        "adapter_is_software": g.is_software(),
        "note": if g.is_software() {
            "software adapter: these are CPU timings of the WGSL path tracer, not GPU speed"
        } else {
            "hardware adapter"
        },
        "spp": spp,
        "first_pass_seconds_with_pipeline_compile": warmup,
        "paths_per_second": st.paths_per_second(),
        "evaluations_per_path": st.evaluations as f64 / st.paths.max(1) as f64,
        "dropped_non_finite": st.dropped_non_finite,
    }))
}

fn load_average() -> f64 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|x| x.parse().ok()))
        .unwrap_or(f64::NAN)
}

/// The first (spp, seconds) at which `error` reaches the target, doubling the samples.
struct Reached {
    spp: u32,
    seconds: f64,
    rmse: f64,
}

fn reached(r: &Option<Reached>) -> serde_json::Value {
    r.as_ref().map_or(
        serde_json::Value::Null,
        |r| json!({"spp": r.spp, "seconds": r.seconds, "rmse": r.rmse}),
    )
}

fn converge(
    tracer: &PathTracer,
    reference_spp: u32,
    target: f64,
) -> Result<serde_json::Value, String> {
    let t = Instant::now();
    let mut reference = Progressive::new(tracer.clone().with_seed(0x5eed_0001));
    let bar = indicatif::ProgressBar::new(reference_spp as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("  reference [{bar:30}] {pos}/{len} spp {eta}")
            .map_err(|e| e.to_string())?,
    );
    let step = (reference_spp / 64).max(1);
    let mut have = 0;
    while have < reference_spp {
        let n = step.min(reference_spp - have);
        reference
            .add_samples(n, &Control::default())
            .map_err(|e| e.to_string())?;
        have += n;
        bar.set_position(have as u64);
    }
    bar.finish_and_clear();
    let reference_s = t.elapsed().as_secs_f64();
    let reference = reference.frame();
    let mut prog = Progressive::new(tracer.clone());
    let (mut spp, mut secs) = (0u32, 0.0);
    let (mut raw, mut den): (Option<Reached>, Option<Reached>) = (None, None);
    let mut curve = Vec::new();
    while spp < reference_spp / 4 && (raw.is_none() || den.is_none()) {
        let add = spp.max(1);
        let t = Instant::now();
        prog.add_samples(add, &Control::default())
            .map_err(|e| e.to_string())?;
        secs += t.elapsed().as_secs_f64();
        spp += add;
        let f = prog.frame();
        let e_raw = relative_rmse(&f.colour, &reference.colour);
        let t = Instant::now();
        let d = denoise(&f, &DenoiseSettings::default());
        let denoise_s = t.elapsed().as_secs_f64();
        let e_den = relative_rmse(&d, &reference.colour);
        curve.push(json!({"spp": spp, "seconds": secs, "rmse_raw": e_raw, "rmse_denoised": e_den}));
        if e_raw <= target && raw.is_none() {
            raw = Some(Reached {
                spp,
                seconds: secs,
                rmse: e_raw,
            });
        }
        if e_den <= target && den.is_none() {
            den = Some(Reached {
                spp,
                seconds: secs + denoise_s,
                rmse: e_den,
            });
        }
    }
    Ok(json!({
        "reference_spp": reference_spp,
        "reference_seconds": reference_s,
        "reference_estimated_noise": reference.relative_noise(),
        "to_target_raw": reached(&raw),
        "to_target_denoised": reached(&den),
        "curve": curve,
    }))
}

pub fn run(a: PathTraceBenchArgs) -> Result<(), String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()
        .map_err(|e| e.to_string())?;
    let load_before = load_average();
    let mut renderer = if a.gpu {
        Some(fathom_gpu::Renderer::headless().map_err(|e| e.to_string())?)
    } else {
        None
    };
    let mut scenes = Vec::new();
    for name in a
        .presets
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
    {
        eprintln!("bench pathtrace: {name}");
        let scene = presets::load(name).map_err(|e| e.to_string())?;
        let tape = Tape::compile(&scene).map_err(|e| e.to_string())?;
        let tracer = PathTracer::new(&scene, &tape, PathSettings::new(a.size.0, a.size.1))
            .map_err(|e| e.to_string())?;
        let mut prog = Progressive::new(tracer);
        pool.install(|| prog.add_samples(a.spp, &Control::default()))
            .map_err(|e| e.to_string())?;
        let st = prog.stats().clone();
        let mut entry = json!({
            "preset": name,
            "size": [a.size.0, a.size.1],
            "spp": a.spp,
            "paths_per_second": st.paths_per_second(),
            "evaluations_per_path": st.evaluations as f64 / st.paths.max(1) as f64,
            "dropped_non_finite": st.dropped_non_finite,
        });
        if let Some(r) = renderer.as_mut() {
            eprintln!("bench pathtrace: {name} on the GPU");
            entry["gpu"] = gpu_entry(r, &scene, &tape, a.size, a.spp)?;
        }
        if a.reference_spp > 0 {
            let (w, h) = a.converge_size;
            let small = PathTracer::new(&scene, &tape, PathSettings::new(w, h))
                .map_err(|e| e.to_string())?;
            let c = pool.install(|| converge(&small, a.reference_spp, a.target_rmse))?;
            entry["convergence"] = json!({"size": [w, h], "target_rmse": a.target_rmse, "run": c});
        }
        if !a.no_explorer {
            let mut session = Session::new(scene.clone()).map_err(|e| e.to_string())?;
            let mut req = RenderRequest {
                width: 1280,
                height: 720,
                backend: Backend::Path,
                threads: Some(a.threads),
                ..RenderRequest::default()
            };
            req.path.spp = 1;
            let t = Instant::now();
            session
                .render(&scene.camera, &req)
                .map_err(|e| e.to_string())?;
            entry["explorer_accumulation_pass_ms_1280x720"] =
                json!(t.elapsed().as_secs_f64() * 1e3);
        }
        scenes.push(entry);
    }
    let out = json!({
        "threads": a.threads,
        "load_average_before": load_before,
        "load_average_after": load_average(),
        "scenes": scenes,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?
    );
    Ok(())
}
