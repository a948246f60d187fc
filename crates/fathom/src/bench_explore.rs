//! `fathom bench explore`: the explorer window's render-side numbers as JSON, measured by
//! `fathom_app::bench` (the window's own frame scheduling and render worker, driven without a
//! window) for each scene on the CPU tracer and on the GPU renderer. On a machine without a
//! GPU the GPU renderer runs on lavapipe, whose times are CPU times (the JSON says so).
//!
//! Then, per scene, the octree in the window's scheduling: a view held still from its first
//! frame, timed to settle with the still view's budget and with the moving view's (the frame
//! rate held while nothing moves), each within `--octree-secs`.

use clap::Args;
use fathom_app::bench::{BenchConfig, measure, measure_octree_settle};
use fathom_app::viewport::OCTREE_STILL_BUDGET;
use fathom_core::presets;
use std::time::Duration;

#[derive(Args)]
pub struct ExploreBenchArgs {
    /// Viewport size WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = crate::args::parse_size)]
    pub size: (u32, u32),
    /// Presets to measure, comma-separated.
    #[arg(long, default_value = "menger,mandelbulb,model-tree")]
    pub presets: String,
    /// Frame time the dynamic render scale holds while the view moves, ms.
    #[arg(long, default_value_t = 33.0)]
    pub target_ms: f64,
    /// Seconds the camera moves.
    #[arg(long, default_value_t = 6.0)]
    pub move_secs: f64,
    /// Parameter edits timed per scene.
    #[arg(long, default_value_t = 10)]
    pub edits: usize,
    /// Skip the GPU renderer.
    #[arg(long)]
    pub no_gpu: bool,
    /// Longest wait for one frame or refinement, seconds.
    #[arg(long, default_value_t = 300.0)]
    pub timeout: f64,
    /// Longest an octree view is held still to settle, per scene and budget, seconds (0: skip
    /// the octree rows).
    #[arg(long, default_value_t = 60.0)]
    pub octree_secs: f64,
}

pub fn run(a: ExploreBenchArgs) -> Result<(), String> {
    if !(a.target_ms.is_finite() && (1.0..=1000.0).contains(&a.target_ms)) {
        return Err(format!(
            "--target-ms {} is out of range [1, 1000]",
            a.target_ms
        ));
    }
    if !(a.move_secs.is_finite() && (0.5..=600.0).contains(&a.move_secs)) {
        return Err(format!(
            "--move-secs {} is out of range [0.5, 600]",
            a.move_secs
        ));
    }
    if !(a.timeout.is_finite() && (1.0..=36000.0).contains(&a.timeout)) {
        return Err(format!(
            "--timeout {} is out of range [1, 36000]",
            a.timeout
        ));
    }
    if !(a.octree_secs.is_finite() && (0.0..=36000.0).contains(&a.octree_secs)) {
        return Err(format!(
            "--octree-secs {} is out of range [0, 36000]",
            a.octree_secs
        ));
    }
    if a.edits > 1000 {
        return Err(format!("--edits {} is more than 1000", a.edits));
    }
    let cfg = BenchConfig {
        width: a.size.0,
        height: a.size.1,
        target_ms: a.target_ms,
        move_secs: a.move_secs,
        edits: a.edits,
        timeout: Duration::from_secs_f64(a.timeout),
    };
    let mut rows = Vec::new();
    let mut settles = Vec::new();
    for name in a
        .presets
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
    {
        let scene = presets::load(name).map_err(|e| e.to_string())?;
        let name = presets::find(name).map_err(|e| e.to_string())?.name;
        eprintln!("bench explore: {name} on the CPU tracer");
        let row = measure(name, &scene, &cfg, None)?;
        // Each row as it is done (a long GPU run may be stopped before the end).
        eprintln!(
            "{}",
            serde_json::to_string(&row).map_err(|e| e.to_string())?
        );
        rows.push(row);
        if !a.no_gpu {
            eprintln!("bench explore: {name} on the GPU renderer");
            let r = fathom_gpu::Renderer::headless().map_err(|e| e.to_string())?;
            let row = measure(name, &scene, &cfg, Some(r))?;
            eprintln!(
                "{}",
                serde_json::to_string(&row).map_err(|e| e.to_string())?
            );
            rows.push(row);
        }
        if a.octree_secs > 0.0 {
            for budget in [OCTREE_STILL_BUDGET, 0.0] {
                eprintln!(
                    "bench explore: {name} on the octree, held still (still budget {budget})"
                );
                let limit = Duration::from_secs_f64(a.octree_secs);
                let row = measure_octree_settle(name, &scene, &cfg, budget, limit)?;
                eprintln!(
                    "{}",
                    serde_json::to_string(&row).map_err(|e| e.to_string())?
                );
                settles.push(row);
            }
        }
    }
    let out = serde_json::json!({
        "bench": "explore",
        "threads": std::thread::available_parallelism().map_or(1, |n| n.get()),
        "note": "the window's scheduling and render worker without a window: UI drawing is not \
                 included; GPU figures on a software adapter (lavapipe) are CPU times",
        "rows": rows,
        "octree_settle": settles,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?
    );
    Ok(())
}
