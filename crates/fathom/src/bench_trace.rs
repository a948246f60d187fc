//! `fathom bench trace`: renders every preset with basic, enhanced and enhanced+prepass tracing
//! (and basic+prepass) and prints JSON per preset: wall ms, primary rays per second, and distance evaluations per
//! pixel of the depth passes (prepass plus primary rays), plus the prepass's reduction.

use clap::Args;
use fathom_core::presets::{self, PRESETS};
use fathom_render::{RenderRequest, Session, Stats, TracerRule};

#[derive(Args)]
pub struct TraceArgs {
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480", value_parser = crate::args::parse_size)]
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

fn measure(s: &mut Session, req: &RenderRequest, repeat: u32) -> Result<(Stats, f64), String> {
    let cam = s.scene().camera.clone();
    let mut best = f64::INFINITY;
    let mut stats = None;
    for _ in 0..repeat.max(1) {
        let r = s.render(&cam, req).map_err(|e| e.to_string())?;
        best = best.min(r.stats.ms.total);
        stats = Some(r.stats);
    }
    Ok((stats.expect("repeat >= 1"), best))
}

pub fn run(a: TraceArgs) -> Result<(), String> {
    if a.threads == 0 || a.threads > 1024 {
        return Err("--threads must be in [1, 1024]".into());
    }
    let mut out = Vec::new();
    for p in PRESETS {
        if a.preset.as_deref().is_some_and(|n| n != p.name) {
            continue;
        }
        let scene = presets::load(p.name).map_err(|e| e.to_string())?;
        let mut session = Session::new(scene).map_err(|e| e.to_string())?;
        let mut entry = serde_json::Map::new();
        entry.insert("preset".into(), p.name.into());
        let mut de = [0f64; 4];
        for (k, (name, method, prepass)) in [
            ("basic", TracerRule::Basic, false),
            ("enhanced", TracerRule::Enhanced, false),
            ("enhanced_prepass", TracerRule::Enhanced, true),
            ("basic_prepass", TracerRule::Basic, true),
        ]
        .into_iter()
        .enumerate()
        {
            let req = RenderRequest {
                width: a.size.0,
                height: a.size.1,
                tracer: method,
                prepass,
                threads: Some(a.threads),
                ..RenderRequest::default()
            };
            let (s, ms) = measure(&mut session, &req, a.repeat)?;
            de[k] = s.depth_de_per_pixel;
            entry.insert(
                name.into(),
                serde_json::json!({
                    "wall_ms": ms,
                    "rays_per_s": s.primary_rays as f64 / (ms / 1e3),
                    "depth_de_per_pixel": s.depth_de_per_pixel,
                    "shade_de_per_pixel": s.de_evaluations.shade as f64 / s.primary_rays as f64,
                    "ms_prepass": s.ms.prepass,
                    "ms_trace_and_shade": s.ms.trace_and_shade,
                    "hits": s.hits,
                    "deep_f64_path": s.deep_f64_path,
                }),
            );
        }
        // The depth passes alone (no colouring) with everything on: the tracer's own speed.
        let req = RenderRequest {
            width: a.size.0,
            height: a.size.1,
            geometry_only: true,
            threads: Some(a.threads),
            ..RenderRequest::default()
        };
        let (_, ms) = measure(&mut session, &req, a.repeat)?;
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
