//! `fathom bench farm`: what farming costs on this machine, as JSON.
//!
//! - **single**: `fathom render` of the still in one process with `--parallel` threads (a
//!   child process, so process start and scene compile count as they do for a task);
//! - **array**: the same still as a `--tiles` job run as a local array of `--tasks` shards,
//!   `--parallel` at a time, one thread each (`fathom farm run`: the same processes a Slurm
//!   array runs); per task, its wall time minus its units' render time is its overhead;
//! - **assemble**: verifying every unit's checksum and stitching the tiles into the PNG;
//! - **empty_task**: a task whose units are all done (process start, manifest, scene
//!   compile, checksums): the fixed cost of a task;
//! - **resume**: one shard's units deleted and one tile truncated (a task killed midway, a
//!   damaged file), then the array run again: only those are rendered.
//!
//! - **path**: `--path-frames` frames of the dive path (docs/examples/mandelbulb-dive.ron) at
//!   `--path-size`: `fathom render --path` in one process against a local array of `--tasks`
//!   (each task replays the modulation of the frames before its own, prepares the path and
//!   compiles the scene once), frames compared byte for byte;
//! - **slurm** (with `--slurm`, on the cluster `SLURM_CONF` names, e.g. one started by
//!   scripts/slurm-local.sh): the same array submitted with sbatch, from submission until
//!   squeue lists no task of it.
//!
//! The minimum over `--repeat` runs of each is reported.

use crate::cmd_render::RenderArgs;
use clap::Args;
use fathom_farm::local::{LocalRun, run_local};
use fathom_farm::{FarmDir, Shard};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

#[derive(Args)]
pub struct FarmBenchArgs {
    /// Preset rendered.
    #[arg(long, default_value = "mandelbulb")]
    preset: String,
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "512x384", value_parser = crate::args::parse_size)]
    size: (u32, u32),
    /// Tiles of the still.
    #[arg(long, default_value_t = 16)]
    tiles: usize,
    /// Array tasks.
    #[arg(long, default_value_t = 8)]
    tasks: usize,
    /// Tasks (and the single process's threads) at once; default: the cores.
    #[arg(long)]
    parallel: Option<usize>,
    /// Runs of each measurement; the fastest is reported.
    #[arg(long, default_value_t = 2)]
    repeat: usize,
    /// Frames of the path measurement (0: skip it).
    #[arg(long, default_value_t = 16)]
    path_frames: usize,
    /// Frame size of the path measurement.
    #[arg(long, default_value = "160x120", value_parser = crate::args::parse_size)]
    path_size: (u32, u32),
    /// Also run the array through Slurm (sbatch) on the cluster SLURM_CONF names.
    #[arg(long)]
    slurm: bool,
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Per-task overhead of a run: wall time minus the render time of its units, ms.
fn overheads(run: &LocalRun) -> Vec<f64> {
    run.results
        .iter()
        .map(|t| {
            let units: f64 = t
                .report
                .as_ref()
                .and_then(|r| r["unit_ms"].as_array().cloned())
                .unwrap_or_default()
                .iter()
                .filter_map(|v| v.as_f64())
                .sum();
            t.ms - units
        })
        .collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn fresh(dir: &Path) -> Result<(), String> {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))
}

pub fn run(a: FarmBenchArgs) -> Result<(), String> {
    let parallel = a
        .parallel
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(2, |n| n.get()));
    if a.repeat == 0 || a.tasks == 0 || parallel == 0 {
        return Err("--repeat, --tasks and --parallel must be at least 1".into());
    }
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this fathom: {e}"))?;
    let root = std::env::temp_dir().join(format!("fathom-bench-farm-{}", std::process::id()));
    fresh(&root)?;
    let size = format!("{}x{}", a.size.0, a.size.1);
    let result = (|| -> Result<serde_json::Value, String> {
        // One process.
        let still = root.join("single.png");
        let mut single = f64::INFINITY;
        for _ in 0..a.repeat {
            let t = Instant::now();
            let out = Command::new(&exe)
                .args(["render", "-q", "--preset", &a.preset, "--size", &size])
                .args(["--threads", &parallel.to_string(), "-o"])
                .arg(&still)
                .output()
                .map_err(|e| e.to_string())?;
            if !out.status.success() {
                return Err(String::from_utf8_lossy(&out.stderr).into_owned());
            }
            single = single.min(ms_since(t));
        }
        // The array.
        let job = |dir: &Path| -> Result<FarmDir, String> {
            let args = RenderArgs {
                preset: Some(a.preset.clone()),
                size: Some(a.size),
                tiles: Some(a.tiles),
                output: PathBuf::from(dir),
                quiet: true,
                ..RenderArgs::defaults()
            };
            crate::cmd_farm::create_render_job(&args)
        };
        let mut best: Option<LocalRun> = None;
        let mut dir = root.join("array");
        for k in 0..a.repeat {
            dir = root.join(format!("array-{k}"));
            fresh(&dir)?;
            let farm = job(&dir)?;
            let run =
                run_local(&exe, &farm.dir, a.tasks, parallel, 1).map_err(|e| e.to_string())?;
            if best.as_ref().is_none_or(|b| run.ms < b.ms) {
                best = Some(run);
            }
        }
        let array = best.expect("repeat >= 1");
        let farm = FarmDir::open(&dir).map_err(|e| e.to_string())?;
        let assembled = root.join("assembled.png");
        let t = Instant::now();
        fathom_farm::assemble::assemble(&farm, &assembled).map_err(|e| e.to_string())?;
        let assemble_ms = ms_since(t);
        let identical = std::fs::read(&assembled).map_err(|e| e.to_string())?
            == std::fs::read(&still).map_err(|e| e.to_string())?;
        let over = overheads(&array);
        // A task with nothing to do.
        let mut empty = f64::INFINITY;
        for _ in 0..a.repeat {
            let run = run_local(&exe, &farm.dir, 1, 1, 1).map_err(|e| e.to_string())?;
            empty = empty.min(run.ms);
        }
        // Resume after a failure: shard 1's units gone, one tile of another truncated.
        let mut resume = f64::INFINITY;
        let mut redone = 0;
        for _ in 0..a.repeat {
            let shard = Shard::new(1 % a.tasks, a.tasks).map_err(|e| e.to_string())?;
            let units = &farm.manifest.units;
            for i in shard.units(units.len()) {
                std::fs::remove_file(farm.path(&units[i])).map_err(|e| e.to_string())?;
            }
            let other = units
                .iter()
                .find(|u| !shard.owns(u.index, units.len()))
                .map(|u| farm.path(u));
            if let Some(p) = &other {
                let b = std::fs::read(p).map_err(|e| e.to_string())?;
                std::fs::write(p, &b[..b.len() / 2]).map_err(|e| e.to_string())?;
            }
            let before = farm.status();
            redone = before.units - before.done.len();
            let run =
                run_local(&exe, &farm.dir, a.tasks, parallel, 1).map_err(|e| e.to_string())?;
            resume = resume.min(run.ms);
            if !farm.status().complete() {
                return Err("the resumed run did not complete the job".into());
            }
        }
        // Through Slurm.
        let slurm = if a.slurm {
            let mut best = f64::INFINITY;
            for k in 0..a.repeat {
                let dir = root.join(format!("slurm-{k}"));
                fresh(&dir)?;
                let farm = job(&dir)?;
                let o = fathom_farm::slurm::SlurmOptions {
                    tasks: a.tasks,
                    cpus_per_task: 1,
                    partition: None,
                    time: None,
                    max_running: None,
                };
                let script =
                    fathom_farm::slurm::write_script(&farm, &exe, &o).map_err(|e| e.to_string())?;
                let t = Instant::now();
                fathom_farm::slurm::submit(&script, true).map_err(|e| e.to_string())?;
                let ms = ms_since(t);
                if !farm.status().complete() {
                    return Err(format!(
                        "the Slurm array left units undone; see {}/logs",
                        dir.display()
                    ));
                }
                best = best.min(ms);
            }
            json!({ "ms": best, "speed_vs_single": single / best,
                    "overhead_ms_per_task_vs_local": (best - array.ms) / a.tasks as f64 })
        } else {
            serde_json::Value::Null
        };
        let path = if a.path_frames > 0 {
            path_bench(&a, &exe, &root, parallel)?
        } else {
            serde_json::Value::Null
        };
        let units = farm.manifest.units.len();
        let pixels = (a.size.0 * a.size.1) as f64;
        Ok(json!({
            "machine": { "cores": std::thread::available_parallelism().map_or(0, |n| n.get()),
                         "profile": if cfg!(debug_assertions) { "dev" } else { "release" } },
            "preset": a.preset,
            "size": size,
            "tiles": units,
            "tasks": a.tasks,
            "parallel": parallel,
            "single": { "ms": single, "mpixel_per_s": pixels / single / 1e3, "threads": parallel },
            "array": {
                "ms": array.ms,
                "mpixel_per_s": pixels / array.ms / 1e3,
                "speed_vs_single": single / array.ms,
                "task_ms": array.results.iter().map(|t| t.ms).collect::<Vec<_>>(),
                "overhead_ms_per_task": { "mean": mean(&over),
                    "max": over.iter().cloned().fold(0.0, f64::max) },
                "assembled_identical_to_single": identical,
                "assemble_ms": assemble_ms,
            },
            "empty_task_ms": empty,
            "resume": { "units_redone": redone, "ms": resume, "fraction_of_full_array": resume / array.ms },
            "slurm": slurm,
            "path": path,
        }))
    })();
    let _ = std::fs::remove_dir_all(&root);
    let v = result?;
    println!(
        "{}",
        serde_json::to_string_pretty(&v).map_err(|e| e.to_string())?
    );
    Ok(())
}

const DIVE: &str = include_str!("../../../docs/examples/mandelbulb-dive.ron");

/// The path measurement (see the module documentation).
fn path_bench(
    a: &FarmBenchArgs,
    exe: &Path,
    root: &Path,
    parallel: usize,
) -> Result<serde_json::Value, String> {
    let scene = root.join("dive.ron");
    std::fs::write(&scene, DIVE).map_err(|e| e.to_string())?;
    let size = format!("{}x{}", a.path_size.0, a.path_size.1);
    let frames = a.path_frames.to_string();
    let mut single = f64::INFINITY;
    let seq = root.join("path-single");
    for _ in 0..a.repeat {
        fresh(&seq)?;
        let t = Instant::now();
        let out = Command::new(exe)
            .arg("render")
            .arg(&scene)
            .args(["-q", "--no-video", "--path", "dive", "--frames", &frames])
            .args(["--size", &size, "--threads", &parallel.to_string(), "-o"])
            .arg(format!("{}/", seq.display()))
            .output()
            .map_err(|e| e.to_string())?;
        if !out.status.success() {
            return Err(String::from_utf8_lossy(&out.stderr).into_owned());
        }
        single = single.min(ms_since(t));
    }
    let mut best: Option<LocalRun> = None;
    let mut dir = root.join("path-array");
    for k in 0..a.repeat {
        dir = root.join(format!("path-array-{k}"));
        fresh(&dir)?;
        let args = RenderArgs {
            scene: Some(scene.clone()),
            size: Some(a.path_size),
            path: Some("dive".into()),
            frames: Some(a.path_frames),
            output: dir.clone(),
            quiet: true,
            ..RenderArgs::defaults()
        };
        let farm = crate::cmd_farm::create_render_job(&args)?;
        let run = run_local(exe, &farm.dir, a.tasks, parallel, 1).map_err(|e| e.to_string())?;
        if best.as_ref().is_none_or(|b| run.ms < b.ms) {
            best = Some(run);
        }
    }
    let array = best.expect("repeat >= 1");
    let identical = (0..a.path_frames).all(|i| {
        let f = std::fs::read(dir.join(format!("frame-{i:06}.png"))).ok();
        let s = std::fs::read(seq.join(format!("dive-{i:05}.png"))).ok();
        f.is_some() && f == s
    });
    let over = overheads(&array);
    Ok(json!({
        "frames": a.path_frames,
        "size": size,
        "single": { "ms": single, "frames_per_s": a.path_frames as f64 / single * 1e3, "threads": parallel },
        "array": {
            "ms": array.ms,
            "frames_per_s": a.path_frames as f64 / array.ms * 1e3,
            "speed_vs_single": single / array.ms,
            "overhead_ms_per_task": { "mean": mean(&over),
                "max": over.iter().cloned().fold(0.0, f64::max) },
            "frames_identical_to_single": identical,
        },
    }))
}
