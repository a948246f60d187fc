//! `fathom farm` and the `--shard` renders: the flags become a farm job (scene text, request,
//! work) and the crate `fathom_farm` does the rest (job directory, shards, receipts,
//! assembly, the sbatch script). This module parses, prints and calls ffmpeg.

use crate::cmd_flight::{encode_video, ffmpeg_available};
use crate::cmd_render::RenderArgs;
use crate::cmd_zoom::ZoomArgs;
use clap::{Args, Subcommand};
use fathom_farm::assemble::{Assembled, assemble};
use fathom_farm::render::SessionRenderer;
use fathom_farm::slurm::{SlurmOptions, submit, write_script};
use fathom_farm::{Event, FarmDir, Fingerprint, Shard, Work, run_shard};
use std::path::{Path, PathBuf};

/// Render farms: long animations and poster-size stills as shards of deterministic units,
/// scheduled by Slurm (or any engine that runs N copies of a command).
///
/// A job directory holds farm.json (the job's fingerprint and units), scene.ron, the unit
/// files (tile-NNNNN.png or frame-NNNNNN.png, written under a temporary name and renamed)
/// and a receipt per finished unit (size, SHA-256). Rerunning any task renders only what is
/// missing or corrupt; a directory of a different job is refused.
///
/// Examples:
///   fathom farm slurm --preset menger --size 8192x8192 --tiles 64 -o poster/ --submit
///   fathom farm slurm dive.ron --path dive --frames 2400 -o dive/ --tasks 100 --submit --wait
///   fathom farm status poster/
///   fathom farm assemble poster/ -o poster.png
///   fathom farm assemble dive/ -o dive.mp4 --fps 30
///   fathom farm run poster/ --tasks 8          (a local array: no scheduler)
///   fathom farm work poster/ --shard 3/8        (one task; in a Slurm array: no --shard)
/// Kubernetes indexed job or AWS Batch array: run
///   fathom farm work DIR --shard $JOB_COMPLETION_INDEX/N
///   fathom farm work DIR --shard $AWS_BATCH_JOB_ARRAY_INDEX/N
/// on a shared file system (see docs/farm.md).
#[derive(Args)]
#[command(verbatim_doc_comment)]
pub struct FarmArgs {
    #[command(subcommand)]
    cmd: FarmCmd,
}

#[derive(Subcommand)]
enum FarmCmd {
    Slurm(Box<SlurmArgs>),
    Work(WorkArgs),
    Run(RunArgs),
    Status(StatusArgs),
    Assemble(AssembleArgs),
}

/// Create a job directory and its sbatch array script (and submit it).
///
/// Takes the scene and every option of `fathom render`; -o is the job directory.
///
/// Examples:
///   fathom farm slurm --preset menger --size 8192x8192 --tiles 64 -o poster/ --submit
///   fathom farm slurm dive.ron --path dive --frames 2400 -o dive/ --tasks 100 --partition gpu
#[derive(Args)]
#[command(verbatim_doc_comment)]
struct SlurmArgs {
    #[command(flatten)]
    render: RenderArgs,
    /// Array tasks (shards); default: the units, at most 8.
    #[arg(long)]
    tasks: Option<usize>,
    /// CPUs per task (the task's render threads).
    #[arg(long, default_value_t = 1)]
    cpus_per_task: usize,
    /// Slurm partition.
    #[arg(long)]
    partition: Option<String>,
    /// Time limit per task (Slurm's --time, e.g. 30:00).
    #[arg(long)]
    time: Option<String>,
    /// Most array tasks running at once.
    #[arg(long)]
    max_running: Option<usize>,
    /// Submit the script with sbatch.
    #[arg(long)]
    submit: bool,
    /// Submit and wait until every task has ended (fails if one failed).
    #[arg(long)]
    wait: bool,
}

/// Render one shard of a job directory (what each array task runs).
///
/// Examples:
///   fathom farm work poster/ --shard 3/8
///   fathom farm work poster/          (in a Slurm array task: the shard from its environment)
#[derive(Args)]
#[command(verbatim_doc_comment)]
struct WorkArgs {
    /// The job directory.
    dir: PathBuf,
    /// Shard I/N; default: from SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT, else all units.
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
    /// Render threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Print the shard's report as JSON on stdout.
    #[arg(long)]
    json: bool,
    /// Sleep this long after each rendered unit (for tests that kill a task midway).
    #[arg(long, hide = true, default_value_t = 0)]
    unit_delay_ms: u64,
}

/// Run every shard of a job as local processes (a local array, no scheduler).
///
/// Examples:
///   fathom farm run poster/ --tasks 8 --parallel 2
#[derive(Args)]
#[command(verbatim_doc_comment)]
struct RunArgs {
    /// The job directory.
    dir: PathBuf,
    /// Shards.
    #[arg(long, default_value_t = 8)]
    tasks: usize,
    /// Most shards running at once (default: the cores).
    #[arg(long)]
    parallel: Option<usize>,
    /// Render threads per shard.
    #[arg(long, default_value_t = 1)]
    threads: usize,
}

/// Report which units of a job are done, missing or corrupt.
///
/// Examples:
///   fathom farm status poster/
///   fathom farm status poster/ --json
#[derive(Args)]
#[command(verbatim_doc_comment)]
struct StatusArgs {
    dir: PathBuf,
    /// As JSON.
    #[arg(long)]
    json: bool,
}

/// Verify every unit, then stitch the tiles into a PNG (or the frames into a video).
///
/// Examples:
///   fathom farm assemble poster/ -o poster.png
///   fathom farm assemble dive/ -o dive.mp4 --fps 30
#[derive(Args)]
#[command(verbatim_doc_comment)]
struct AssembleArgs {
    dir: PathBuf,
    /// The still (PNG) or, for frames, the video (needs ffmpeg on PATH).
    #[arg(short, long)]
    output: PathBuf,
    /// Frame rate of the video.
    #[arg(long, default_value_t = 24.0)]
    fps: f64,
}

pub fn run(a: FarmArgs) -> Result<(), String> {
    match a.cmd {
        FarmCmd::Slurm(s) => slurm(*s),
        FarmCmd::Work(w) => work(w),
        FarmCmd::Run(r) => local(r),
        FarmCmd::Status(s) => status(s),
        FarmCmd::Assemble(s) => assemble_cmd(s),
    }
}

/// The shard a flag names: `I/N`; empty (a bare `--shard`): the Slurm array's, required.
fn shard_of(flag: Option<&str>) -> Result<Shard, String> {
    match flag {
        Some("") => Shard::from_env()
            .map_err(|e| e.to_string())?
            .ok_or_else(|| {
                "--shard without I/N needs SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT \
                 (a Slurm array task); elsewhere pass --shard I/N"
                    .to_string()
            }),
        Some(s) => s.parse().map_err(|e: fathom_farm::FarmError| e.to_string()),
        None => Ok(Shard::from_env()
            .map_err(|e| e.to_string())?
            .unwrap_or(Shard::ALL)),
    }
}

/// Refuses an -o that looks like an image: a farm writes into a directory.
fn job_dir(output: &Path) -> Result<&Path, String> {
    let ext = output
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase());
    if matches!(ext.as_deref(), Some("png" | "exr" | "mp4")) {
        return Err(format!(
            "-o {} looks like a file; a farm job writes into a directory (e.g. -o job/), \
             and `fathom farm assemble DIR -o OUT.png` makes the image",
            output.display()
        ));
    }
    Ok(output)
}

/// The job directory of a `fathom render` farm job (created when new).
pub fn create_render_job(a: &RenderArgs) -> Result<FarmDir, String> {
    let dir = job_dir(&a.output)?;
    let scene = crate::cmd_render::load_scene(a)?;
    let req = a.request()?;
    let work = match (a.tiles, &a.path) {
        (Some(n), None) => {
            let (w, h) = req.output_size();
            Work::tiles(n, w, h).map_err(|e| e.to_string())?
        }
        (None, Some(p)) => {
            scene.path(p).map_err(|e| e.to_string())?;
            Work::Path {
                path: p.clone(),
                frames: a.frames.unwrap_or(1),
            }
        }
        _ => return Err("a farm job is --tiles N (a still) or --path NAME --frames N".into()),
    };
    let text = fathom_core::scene_file::to_string(&scene);
    let fp = Fingerprint::new(&text, &req, work).map_err(|e| e.to_string())?;
    FarmDir::create(dir, fp, &text).map_err(|e| e.to_string())
}

/// `fathom render --tiles N|--path ... --shard [I/N] -o DIR`.
pub fn render_shard(a: &RenderArgs) -> Result<(), String> {
    let shard = shard_of(a.shard.as_deref())?;
    let farm = create_render_job(a)?;
    work_shard(&farm, shard, a.threads, a.quiet, false, 0)
}

/// `fathom zoom --shard [I/N] -o DIR`.
pub fn zoom_shard(a: &ZoomArgs) -> Result<(), String> {
    let shard = shard_of(a.shard.as_deref())?;
    let dir = a
        .output
        .as_deref()
        .ok_or("a zoom farm shard writes into a directory: give -o DIR")?;
    let z = crate::cmd_zoom::zoom(a)?;
    // Farm workers rebuild the path from its preset name: path presets only, no aim.
    if a.scene.is_some() || a.toward.is_some() || a.pixel.is_some() {
        return Err(
            "--shard renders the path presets (menger, mandelbulb, menger-tour) only: a scene \
             file, --toward and --pixel are not supported with --shard"
                .into(),
        );
    }
    let name = a.preset.clone().unwrap_or_else(|| "menger".into());
    let preset = fathom_core::camera_path::path_preset(&name).map_err(|e| e.to_string())?;
    let text = fathom_core::scene_file::to_string(&preset.scene);
    let work = Work::Zoom {
        preset: name,
        depth: a.depth,
        frames: a.frames,
    };
    let fp = Fingerprint::new(&text, &z.request, work).map_err(|e| e.to_string())?;
    let farm = FarmDir::create(job_dir(dir)?, fp, &text).map_err(|e| e.to_string())?;
    work_shard(&farm, shard, Some(a.threads), false, false, 0)
}

/// Renders `shard` of `farm`, one line per unit on stderr (unless `quiet`), the report as
/// JSON on stdout when `json`.
fn work_shard(
    farm: &FarmDir,
    shard: Shard,
    threads: Option<usize>,
    quiet: bool,
    json: bool,
    delay_ms: u64,
) -> Result<(), String> {
    let mut renderer = SessionRenderer::new(farm, threads).map_err(|e| e.to_string())?;
    let mut on = |e: &Event<'_>| {
        match e {
            _ if quiet => {}
            Event::Skipped(u) => eprintln!("farm {shard}: skipped {} (done)", u.file),
            Event::Started { unit, redo } => match redo {
                Some(why) => eprintln!("farm {shard}: started {} (redo: {why})", unit.file),
                None => eprintln!("farm {shard}: started {}", unit.file),
            },
            Event::Rendered { unit, ms, .. } => {
                eprintln!("farm {shard}: rendered {} in {ms:.0} ms", unit.file)
            }
        }
        if delay_ms > 0 && matches!(e, Event::Rendered { .. }) {
            std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        }
    };
    let report = run_shard(farm, shard, &mut renderer, &mut on).map_err(|e| e.to_string())?;
    if json {
        println!(
            "{}",
            serde_json::to_string(&report).map_err(|e| e.to_string())?
        );
    } else if !quiet {
        eprintln!(
            "farm {shard}: {} units of job {}: {} rendered, {} already done, in {:.1} s",
            report.owned,
            report.job,
            report.rendered.len(),
            report.skipped.len(),
            report.ms / 1e3
        );
    }
    Ok(())
}

fn slurm(s: SlurmArgs) -> Result<(), String> {
    if s.render.shard.is_some() {
        return Err("farm slurm makes every shard; leave out --shard".into());
    }
    let farm = create_render_job(&s.render)?;
    let units = farm.manifest.units.len();
    let tasks = s.tasks.unwrap_or(units.min(8));
    check_tasks(tasks, units)?;
    let o = SlurmOptions {
        tasks,
        cpus_per_task: s.cpus_per_task,
        partition: s.partition.clone(),
        time: s.time.clone(),
        max_running: s.max_running,
    };
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this fathom: {e}"))?;
    let script = write_script(&farm, &exe, &o).map_err(|e| e.to_string())?;
    let quiet = s.render.quiet;
    if !quiet {
        eprintln!(
            "job {} ({units} units in {} tasks): wrote {}",
            farm.manifest.job,
            o.tasks,
            script.display()
        );
    }
    if !(s.submit || s.wait) {
        if !quiet {
            eprintln!("submit it with: sbatch {}", script.display());
        }
        return Ok(());
    }
    let id = submit(&script, s.wait).map_err(|e| e.to_string())?;
    println!("{id}");
    let st = farm.status();
    if s.wait {
        if !st.complete() {
            return Err(format!(
                "Slurm job {id} ended with {} of {units} units done ({} missing, {} corrupt); \
                 see {}/logs/ and resubmit with `sbatch {}` (it renders only what is missing)",
                st.done.len(),
                st.missing.len(),
                st.corrupt.len(),
                farm.dir.display(),
                script.display()
            ));
        }
        if !quiet {
            eprintln!("Slurm job {id} ended: all {units} units done");
        }
    } else if !quiet {
        eprintln!(
            "submitted Slurm job {id}; `fathom farm status {}` shows progress",
            farm.dir.display()
        );
    }
    Ok(())
}

/// A job of `units` units runs in 1..=units tasks: a task with no unit would only start a
/// process and write a log (100000 tasks for 4 units never ended).
fn check_tasks(tasks: usize, units: usize) -> Result<(), String> {
    if tasks == 0 || tasks > units {
        return Err(format!(
            "--tasks {tasks} is out of range [1, {units}] (the job's units; every task renders \
             at least one)"
        ));
    }
    Ok(())
}

fn work(w: WorkArgs) -> Result<(), String> {
    let shard = shard_of(w.shard.as_deref())?;
    let farm = FarmDir::open(&w.dir).map_err(|e| e.to_string())?;
    work_shard(&farm, shard, w.threads, false, w.json, w.unit_delay_ms)
}

fn local(r: RunArgs) -> Result<(), String> {
    let farm = FarmDir::open(&r.dir).map_err(|e| e.to_string())?;
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this fathom: {e}"))?;
    check_tasks(r.tasks, farm.manifest.units.len())?;
    if !(1..=crate::args::MAX_THREADS).contains(&r.threads) {
        return Err(format!(
            "--threads {} is out of range [1, {}]",
            r.threads,
            crate::args::MAX_THREADS
        ));
    }
    let parallel = r
        .parallel
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(2, |n| n.get()));
    let run = fathom_farm::local::run_local(&exe, &farm.dir, r.tasks, parallel, r.threads)
        .map_err(|e| e.to_string())?;
    let st = farm.status();
    eprintln!(
        "{} tasks ({} at a time) in {:.1} s: {} of {} units done",
        run.tasks,
        run.parallel,
        run.ms / 1e3,
        st.done.len(),
        st.units
    );
    Ok(())
}

fn status(s: StatusArgs) -> Result<(), String> {
    let farm = FarmDir::open(&s.dir).map_err(|e| e.to_string())?;
    let st = farm.status();
    if s.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&st).map_err(|e| e.to_string())?
        );
        return Ok(());
    }
    let units = &farm.manifest.units;
    println!(
        "job {}: {} units: {} done, {} missing, {} corrupt",
        st.job,
        st.units,
        st.done.len(),
        st.missing.len(),
        st.corrupt.len()
    );
    for &i in st.missing.iter().take(20) {
        println!("  missing {}", units[i].file);
    }
    for (i, why) in st.corrupt.iter().take(20) {
        println!("  corrupt {}: {why}", units[*i].file);
    }
    Ok(())
}

fn assemble_cmd(a: AssembleArgs) -> Result<(), String> {
    let farm = FarmDir::open(&a.dir).map_err(|e| e.to_string())?;
    match assemble(&farm, &a.output).map_err(|e| e.to_string())? {
        Assembled::Still {
            path,
            width,
            height,
        } => {
            eprintln!(
                "verified {} tiles; wrote {} ({width}x{height})",
                farm.manifest.units.len(),
                path.display()
            );
        }
        Assembled::Frames { files, .. } => {
            if !(a.fps.is_finite() && a.fps > 0.0 && a.fps <= 1000.0) {
                return Err(format!("--fps {} is out of range (0, 1000]", a.fps));
            }
            if !ffmpeg_available() {
                eprintln!(
                    "verified {} frames ({}/frame-NNNNNN.png); ffmpeg is not on PATH, so no \
                     video was made",
                    files.len(),
                    farm.dir.display()
                );
                return Ok(());
            }
            let pattern = farm.dir.join("frame-######.png");
            encode_video(&pattern, a.fps, &a.output)?;
            eprintln!(
                "verified {} frames; wrote {}",
                files.len(),
                a.output.display()
            );
        }
    }
    Ok(())
}
