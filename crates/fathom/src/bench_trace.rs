//! `fathom bench trace`: renders every preset with basic, enhanced and enhanced+prepass tracing
//! (and basic+prepass) and prints JSON per preset: wall ms, primary rays per second, and distance evaluations per
//! pixel of the depth passes (prepass plus primary rays), plus the prepass's reduction.

use clap::Args;
use fathom_core::presets::{self, PRESETS};
use fathom_trace::{Method, Options, Stats};

#[derive(Args)]
pub struct TraceArgs {
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    size: (u32, u32),
    /// Worker threads.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// Frames per configuration; the fastest is reported.
    #[arg(long, default_value_t = 3)]
    repeat: u32,
    /// Only this preset.
    #[arg(long)]
    preset: Option<String>,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or("size should look like 640x480")?;
    Ok((
        w.parse().map_err(|_| "bad width")?,
        h.parse().map_err(|_| "bad height")?,
    ))
}

fn measure(
    scene: &fathom_core::Scene,
    opts: &Options,
    repeat: u32,
) -> Result<(Stats, f64), String> {
    let mut best = f64::INFINITY;
    let mut stats = None;
    for _ in 0..repeat.max(1) {
        let (_, s) = fathom_trace::render(scene, opts, &|_, _| {})?;
        best = best.min(s.ms_total);
        stats = Some(s);
    }
    Ok((stats.expect("repeat >= 1"), best))
}

pub fn run(a: TraceArgs) -> Result<(), String> {
    if a.threads == 0 || a.threads > 1024 {
        return Err("--threads must be in [1, 1024]".into());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()
        .map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    for p in PRESETS {
        if a.preset.as_deref().is_some_and(|n| n != p.name) {
            continue;
        }
        let scene = presets::load(p.name)?;
        let mut entry = serde_json::Map::new();
        entry.insert("preset".into(), p.name.into());
        let mut de = [0f64; 4];
        for (k, (name, method, prepass)) in [
            ("basic", Method::Basic, false),
            ("enhanced", Method::Enhanced, false),
            ("enhanced_prepass", Method::Enhanced, true),
            ("basic_prepass", Method::Basic, true),
        ]
        .into_iter()
        .enumerate()
        {
            let opts = Options {
                width: a.size.0,
                height: a.size.1,
                method,
                prepass,
                ..Options::default()
            };
            let (s, ms) = pool.install(|| measure(&scene, &opts, a.repeat))?;
            de[k] = s.de_per_pixel();
            entry.insert(
                name.into(),
                serde_json::json!({
                    "wall_ms": ms,
                    "rays_per_s": s.primary_rays as f64 / (ms / 1e3),
                    "depth_de_per_pixel": s.de_per_pixel(),
                    "shade_de_per_pixel": s.de_shade as f64 / s.primary_rays as f64,
                    "ms_prepass": s.ms_prepass,
                    "ms_trace_and_shade": s.ms_trace,
                    "hits": s.hits,
                    "deep_f64_path": s.deep,
                }),
            );
        }
        // The depth passes alone (no colouring) with everything on: the tracer's own speed.
        let opts = Options {
            width: a.size.0,
            height: a.size.1,
            geometry_only: true,
            ..Options::default()
        };
        let (_, ms) = pool.install(|| measure(&scene, &opts, a.repeat))?;
        entry.insert("depth_only_enhanced_prepass_wall_ms".into(), ms.into());
        entry.insert(
            "enhanced_vs_basic_de_reduction_pct".into(),
            (100.0 * (1.0 - de[1] / de[0])).into(),
        );
        entry.insert(
            "prepass_vs_basic_de_reduction_pct".into(),
            (100.0 * (1.0 - de[2] / de[0])).into(),
        );
        entry.insert(
            "basic_prepass_vs_basic_de_reduction_pct".into(),
            (100.0 * (1.0 - de[3] / de[0])).into(),
        );
        out.push(serde_json::Value::Object(entry));
    }
    let doc = serde_json::json!({
        "bench": "trace",
        "size": format!("{}x{}", a.size.0, a.size.1),
        "threads": a.threads,
        "presets": out,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&doc).map_err(|e| e.to_string())?
    );
    Ok(())
}
