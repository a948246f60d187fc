//! `fathom bench volume`: camera paths per second of the volume path tracer on a dense
//! Menger-sponge density (128^3 and 256^3, sigma_t 20 inside, albedo 0.8, isotropic, constant
//! environment 1) with the majorant grid and with one global majorant; and physarum
//! agent-steps per second with 1M agents on a 256^3 grid. Prints JSON with the load average.
//! Mitsuba 3's side is `crates/fathom-volume/bench/mitsuba_compare.py`.

use clap::Args;
use fathom_core::presets;
use fathom_core::tape::Tape;
use fathom_volume::WorldBox;
use fathom_volume::fractal;
use fathom_volume::integrator::VolumeScene;
use fathom_volume::light::Environment;
use fathom_volume::medium::{Majorant, Medium, MediumParams};
use fathom_volume::physarum::{Simulation, presets as sim_presets};
use fathom_volume::render;
use glam::Vec3;
use serde_json::json;

#[derive(Args)]
pub struct VolumeBenchArgs {
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "256x256")]
    size: String,
    /// Samples per pixel per render.
    #[arg(long, default_value_t = 8)]
    spp: u32,
    /// Worker threads.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// Grid resolutions of the Menger density, comma-separated.
    #[arg(long, default_value = "128,256")]
    grids: String,
    /// Physarum steps per preset.
    #[arg(long, default_value_t = 20)]
    steps: u32,
    /// Physarum agents.
    #[arg(long, default_value_t = 1 << 20)]
    agents: u32,
    /// Physarum grid resolution.
    #[arg(long, default_value_t = 256)]
    sim_grid: u32,
    /// Physarum presets to time, comma-separated.
    #[arg(long, default_value = "tendrils,sheets,lattice,cage")]
    presets: String,
    /// Skip the renders.
    #[arg(long)]
    no_render: bool,
    /// Skip the simulation.
    #[arg(long)]
    no_physarum: bool,
}

/// CPU seconds this process has used (user + system), from /proc/self/stat; with wall time
/// it shows how much of the machine the benchmark got on a shared box.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = after
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(0.0))
        .collect();
    // utime and stime (fields 14 and 15) are the 12th and 13th after the command name.
    (f.get(11).unwrap_or(&0.0) + f.get(12).unwrap_or(&0.0)) / 100.0
}

fn load_average() -> serde_json::Value {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| {
            s.split_whitespace()
                .take(3)
                .collect::<Vec<_>>()
                .join(" ")
                .into()
        })
        .unwrap_or(serde_json::Value::Null)
}

/// The benchmark's scene: the Menger preset's sponge sampled into `res`^3 over [-1, 1]^3.
pub fn menger_density(res: u32) -> Result<fathom_volume::DensityGrid, String> {
    let tape = Tape::compile(&presets::load("menger").map_err(|e| e.to_string())?)
        .map_err(|e| e.to_string())?;
    let bbox = WorldBox::new(Vec3::splat(-1.0), Vec3::splat(1.0)).map_err(|e| e.to_string())?;
    fractal::sample(&tape, [res; 3], bbox, 0.0, 8 << 30, &|| {}).map_err(|e| e.to_string())
}

/// The majorant choices timed: the global majorant first (the speed-ups divide by it).
const MODES: [(&str, Majorant, bool); 4] = [
    ("global_majorant", Majorant::Global, false),
    ("majorant_grid", Majorant::Grid { block: 8 }, false),
    (
        "majorant_grid_homogeneous_cells",
        Majorant::Grid { block: 8 },
        true,
    ),
    ("majorant_grid_block16", Majorant::Grid { block: 16 }, false),
];

/// Renders `density` once per majorant choice into `entry`: paths/s, path statistics, CPU
/// seconds received, and each choice's speed-up over the global majorant.
fn time_modes(
    a: &VolumeBenchArgs,
    density: &fathom_volume::DensityGrid,
    camera: &fathom_core::Camera,
    (w, h): (u32, u32),
    entry: &mut serde_json::Map<String, serde_json::Value>,
) -> Result<(), String> {
    let mut pps = Vec::new();
    for (name, majorant, homogeneous_cells) in MODES {
        let params = MediumParams {
            density_scale: 20.0,
            albedo: Vec3::splat(0.8),
            g: 0.0,
            emission: 0.0,
            majorant,
            homogeneous_cells,
        };
        let scene = VolumeScene {
            medium: Medium::new(density.clone(), &params).map_err(|e| e.to_string())?,
            environment: Environment::Constant(Vec3::ONE),
            sun: None,
            max_depth: 1000,
            rr_depth: 5,
        };
        let load = load_average();
        let cpu = cpu_seconds();
        let (frame, st) =
            render::render(&scene, camera, w, h, a.spp, 1).map_err(|e| e.to_string())?;
        let cpu = cpu_seconds() - cpu;
        let mean = frame.colour.iter().map(|c| c[1] as f64).sum::<f64>() / frame.len() as f64;
        pps.push(st.paths_per_second);
        entry.insert(
            name.into(),
            json!({
                "paths_per_second": st.paths_per_second,
                "seconds": st.seconds,
                "cpu_seconds": cpu,
                "mean_path_length": st.mean_path_length,
                "majorant_steps_per_path": st.majorant_steps_per_path,
                "lookups_per_path": st.lookups_per_path,
                "image_mean": mean,
                "load_average": load,
            }),
        );
    }
    for (i, (name, _, _)) in MODES.iter().enumerate().skip(1) {
        entry.insert(
            format!("{name}_vs_global_speedup"),
            (pps[i] / pps[0]).into(),
        );
    }
    Ok(())
}

fn renders(a: &VolumeBenchArgs, w: u32, h: u32) -> Result<Vec<serde_json::Value>, String> {
    let camera = presets::load("menger").map_err(|e| e.to_string())?.camera;
    let mut out = Vec::new();
    for res in a.grids.split(',') {
        let res: u32 = res
            .trim()
            .parse()
            .map_err(|_| format!("--grids: `{res}` is not a resolution"))?;
        let density = menger_density(res)?;
        let filled = density.data().iter().filter(|v| **v > 0.0).count() as f64
            / density.data().len() as f64;
        let mut entry = serde_json::Map::new();
        entry.insert("grid".into(), format!("menger {res}^3").into());
        entry.insert("filled_fraction".into(), filled.into());
        time_modes(a, &density, &camera, (w, h), &mut entry)?;
        out.push(serde_json::Value::Object(entry));
    }
    // A sparse density for contrast: the tendrils preset grown on 128^3 for 150 steps.
    let p = sim_presets::find("tendrils", [128; 3]).map_err(|e| e.to_string())?;
    let mut sim = Simulation::new(p, [128; 3], 1, 8 << 30).map_err(|e| e.to_string())?;
    for _ in 0..150 {
        sim.step();
    }
    let density = sim.density();
    let filled =
        density.data().iter().filter(|v| **v > 0.01).count() as f64 / density.data().len() as f64;
    let mut entry = serde_json::Map::new();
    entry.insert("grid".into(), "physarum tendrils 128^3, 150 steps".into());
    entry.insert("fraction_above_0.01".into(), filled.into());
    let camera = fathom_volume::pipeline::framing_camera(&density.bbox);
    time_modes(a, &density, &camera, (w, h), &mut entry)?;
    out.push(serde_json::Value::Object(entry));
    Ok(out)
}

fn physarum(a: &VolumeBenchArgs) -> Result<Vec<serde_json::Value>, String> {
    let res = [a.sim_grid; 3];
    let mut out = Vec::new();
    for name in a.presets.split(',') {
        let mut p = sim_presets::find(name.trim(), res).map_err(|e| e.to_string())?;
        p.agents = a.agents;
        let mut sim = Simulation::new(p, res, 1, 16 << 30).map_err(|e| e.to_string())?;
        let load = load_average();
        let cpu = cpu_seconds();
        let start = std::time::Instant::now();
        let mut phases = [0f64; 4];
        for _ in 0..a.steps {
            let t = sim.step();
            for (s, v) in phases
                .iter_mut()
                .zip([t.sort_ms, t.move_ms, t.deposit_ms, t.diffuse_ms])
            {
                *s += v / a.steps as f64;
            }
        }
        let secs = start.elapsed().as_secs_f64();
        let cpu = cpu_seconds() - cpu;
        let sps = a.steps as f64 / secs;
        out.push(json!({
            "preset": name.trim(),
            "agents": a.agents,
            "grid": format!("{}^3", a.sim_grid),
            "steps": a.steps,
            "steps_per_second": sps,
            "agent_steps_per_second": sps * a.agents as f64,
            "target_10_steps_per_second_met": sps >= 10.0,
            "cpu_seconds": cpu,
            "cpu_utilisation": cpu / secs,
            "mean_ms": {"sort": phases[0], "move": phases[1], "deposit": phases[2], "diffuse": phases[3]},
            "load_average": load,
        }));
    }
    Ok(out)
}

pub fn run(a: VolumeBenchArgs) -> Result<(), String> {
    if a.threads == 0 || a.threads > 1024 {
        return Err("--threads must be in [1, 1024]".into());
    }
    let (w, h) = crate::args::parse_size(&a.size)?;
    render::check_spp(a.spp).map_err(|e| e.to_string())?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()
        .map_err(|e| e.to_string())?;
    let load_start = load_average();
    let render = if a.no_render {
        Vec::new()
    } else {
        pool.install(|| renders(&a, w, h))?
    };
    let sim = if a.no_physarum {
        Vec::new()
    } else {
        pool.install(|| physarum(&a))?
    };
    let doc = json!({
        "bench": "volume",
        "size": format!("{w}x{h}"),
        "spp": a.spp,
        "threads": a.threads,
        "scene": "menger preset sampled over [-1,1]^3, sigma_t 20 inside, albedo 0.8, isotropic, constant environment 1, rr after 5, max depth 1000",
        "load_average_start": load_start,
        "load_average_end": load_average(),
        "render": render,
        "physarum": sim,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&doc).map_err(|e| e.to_string())?
    );
    Ok(())
}
