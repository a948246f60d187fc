//! Slurm: the `sbatch` array script of a job directory (one array task per shard, each
//! running `fathom farm work DIR --shard $SLURM_ARRAY_TASK_ID/N` with N written into the
//! script, so resubmitting some tasks alone, `sbatch --array=3,5 farm.sbatch`, reruns exactly
//! those shards), submitting it, and waiting for it. No Slurm API is used: the script is
//! plain text and `sbatch` does the rest.

use crate::error::FarmError;
use crate::manifest::FarmDir;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The script's file name in the job directory.
pub const SCRIPT: &str = "farm.sbatch";
/// The directory of the tasks' logs.
pub const LOGS: &str = "logs";

/// How the array is run.
#[derive(Clone, Debug)]
pub struct SlurmOptions {
    /// Array tasks (shards), [1, units].
    pub tasks: usize,
    /// CPUs per task (also the task's render threads).
    pub cpus_per_task: usize,
    /// Partition (`-p`), if not the default.
    pub partition: Option<String>,
    /// Time limit per task (`--time`), if any.
    pub time: Option<String>,
    /// Most tasks running at once (`--array=...%K`), if limited.
    pub max_running: Option<usize>,
}

/// Quotes a word for a POSIX shell.
fn sh(word: &str) -> String {
    if !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "/._-+=:,@".contains(c))
    {
        word.into()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

fn bad(what: &str) -> FarmError {
    FarmError::Work(what.into())
}

/// The array script for `farm`, running the fathom binary `exe`.
pub fn script(farm: &FarmDir, exe: &Path, o: &SlurmOptions) -> Result<String, FarmError> {
    let units = farm.manifest.units.len();
    if o.tasks == 0 || o.tasks > units {
        return Err(bad(&format!(
            "--tasks {} is out of range 1..={units} (the job has {units} units)",
            o.tasks
        )));
    }
    if o.cpus_per_task == 0 || o.cpus_per_task > 1024 {
        return Err(bad(&format!(
            "--cpus-per-task {} is out of range 1..=1024",
            o.cpus_per_task
        )));
    }
    for (flag, v) in [("--partition", &o.partition), ("--time", &o.time)] {
        if let Some(v) = v
            && (v.is_empty() || v.chars().any(|c| c.is_whitespace() || c == '\''))
        {
            return Err(bad(&format!("{flag} `{v}` must be one word")));
        }
    }
    let dir = std::path::absolute(&farm.dir).map_err(|source| FarmError::Read {
        path: farm.dir.clone(),
        source,
    })?;
    let d = sh(&dir.to_string_lossy());
    let job = &farm.manifest.job;
    let mut s = String::from("#!/bin/bash\n");
    s += &format!(
        "# fathom render farm: job {job}, {units} units in {} tasks\n",
        o.tasks
    );
    s += "# Each task renders the units of its shard that are not done yet; rerun (sbatch this\n";
    s += "# file again, or some tasks: sbatch --array=3,5 FILE) to finish after a failure:\n";
    s += "# nothing done is rendered twice.\n";
    s += &format!("#SBATCH --job-name=fathom-{job}\n");
    let limit = o.max_running.map(|k| format!("%{k}")).unwrap_or_default();
    s += &format!("#SBATCH --array=0-{}{limit}\n", o.tasks - 1);
    s += &format!("#SBATCH --cpus-per-task={}\n", o.cpus_per_task);
    s += "#SBATCH --ntasks=1\n";
    s += &format!("#SBATCH --output={}/{LOGS}/task-%A-%a.out\n", dir.display());
    if let Some(p) = &o.partition {
        s += &format!("#SBATCH --partition={p}\n");
    }
    if let Some(t) = &o.time {
        s += &format!("#SBATCH --time={t}\n");
    }
    s += "set -euo pipefail\n";
    s += &format!(
        "exec {} farm work {d} --shard \"$SLURM_ARRAY_TASK_ID/{}\" --threads {}\n",
        sh(&exe.to_string_lossy()),
        o.tasks,
        o.cpus_per_task
    );
    Ok(s)
}

/// Writes the script into the job directory (and its logs directory); returns its path.
pub fn write_script(farm: &FarmDir, exe: &Path, o: &SlurmOptions) -> Result<PathBuf, FarmError> {
    let text = script(farm, exe, o)?;
    let logs = farm.dir.join(LOGS);
    std::fs::create_dir_all(&logs).map_err(|source| FarmError::Write { path: logs, source })?;
    let path = farm.dir.join(SCRIPT);
    crate::atomic::write(&path, text.as_bytes())?;
    Ok(path)
}

/// Waits until no task of Slurm job `id` is pending or running (polling `squeue`, from every
/// 0.2 s up to every 5 s). Whether the units got done is the job directory's to say.
pub fn wait(id: &str) -> Result<(), FarmError> {
    let mut pause = 0.2f64;
    loop {
        let out = Command::new("squeue")
            .args(["-h", "-o", "%i", "-j", id])
            .output()
            .map_err(|e| FarmError::Scheduler {
                command: format!("squeue -j {id}"),
                message: format!("cannot run squeue ({e})"),
            })?;
        let listed = String::from_utf8_lossy(&out.stdout);
        // A job Slurm no longer knows (purged after it ended) is an error to squeue.
        if !out.status.success() || listed.trim().is_empty() {
            return Ok(());
        }
        std::thread::sleep(std::time::Duration::from_secs_f64(pause));
        pause = (pause * 1.5).min(5.0);
    }
}

/// Submits `script` with `sbatch` and returns the job id (with `wait_for_it`, after every
/// task has ended: see [`wait`]).
pub fn submit(script: &Path, wait_for_it: bool) -> Result<String, FarmError> {
    let mut cmd = Command::new("sbatch");
    cmd.arg("--parsable");
    cmd.arg(script);
    let shown = format!("sbatch {}", script.display());
    let out = cmd.output().map_err(|e| FarmError::Scheduler {
        command: shown.clone(),
        message: format!("cannot run sbatch ({e}); is slurm-client installed and on PATH?"),
    })?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let id = stdout
        .lines()
        .next()
        .unwrap_or_default()
        .split(';')
        .next()
        .unwrap_or_default()
        .trim()
        .to_string();
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        return Err(FarmError::Scheduler {
            command: shown,
            message: format!("failed: {}", err.trim()),
        });
    }
    if wait_for_it {
        wait(&id)?;
    }
    Ok(id)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Fingerprint, Work};
    use fathom_render::RenderRequest;

    #[test]
    fn the_array_script_runs_every_shard_and_refuses_bad_options() {
        let dir = std::env::temp_dir().join(format!("fathom-farm-sbatch-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let req = RenderRequest {
            width: 64,
            height: 48,
            ..RenderRequest::default()
        };
        let fp = Fingerprint::new("s", &req, Work::tiles(12, 64, 48).unwrap()).unwrap();
        let farm = FarmDir::create(&dir, fp, "s").unwrap();
        let mut o = SlurmOptions {
            tasks: 8,
            cpus_per_task: 2,
            partition: Some("batch".into()),
            time: None,
            max_running: Some(4),
        };
        let exe = Path::new("/opt/my fathom/fathom");
        let s = script(&farm, exe, &o).unwrap();
        assert!(s.starts_with("#!/bin/bash\n"));
        assert!(s.contains("#SBATCH --array=0-7%4\n"), "{s}");
        assert!(s.contains("#SBATCH --cpus-per-task=2\n"));
        assert!(s.contains("#SBATCH --partition=batch\n"));
        assert!(s.contains("exec '/opt/my fathom/fathom' farm work "), "{s}");
        assert!(
            s.contains("--shard \"$SLURM_ARRAY_TASK_ID/8\" --threads 2\n"),
            "{s}"
        );
        o.tasks = 13;
        assert!(
            script(&farm, exe, &o)
                .unwrap_err()
                .to_string()
                .contains("1..=12")
        );
        o.tasks = 8;
        o.time = Some("1 day".into());
        assert!(
            script(&farm, exe, &o)
                .unwrap_err()
                .to_string()
                .contains("one word")
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
