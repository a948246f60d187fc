//! Slurm: the `sbatch` array script of a job directory (one array task per shard, each
//! running `fathom farm work DIR`, which takes its shard from `SLURM_ARRAY_TASK_ID` and
//! `SLURM_ARRAY_TASK_COUNT`), submitting it, and waiting for it. No Slurm API is used: the
//! script is plain text and `sbatch` does the rest.

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
    s += "# file again) to finish after a failure: nothing done is rendered twice.\n";
    s += &format!("#SBATCH --job-name=fathom-{job}\n");
    let limit = o.max_running.map(|k| format!("%{k}")).unwrap_or_default();
    s += &format!("#SBATCH --array=0-{}{limit}\n", o.tasks - 1);
    s += &format!("#SBATCH --cpus-per-task={}\n", o.cpus_per_task);
    s += "#SBATCH --ntasks=1\n";
    s += &format!("#SBATCH --output={}/{LOGS}/task-%a.out\n", dir.display());
    if let Some(p) = &o.partition {
        s += &format!("#SBATCH --partition={p}\n");
    }
    if let Some(t) = &o.time {
        s += &format!("#SBATCH --time={t}\n");
    }
    s += "set -euo pipefail\n";
    s += &format!(
        "exec {} farm work {d} --threads {}\n",
        sh(&exe.to_string_lossy()),
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

/// Submits `script` with `sbatch` (with `wait`, blocks until every task ended and fails if
/// one failed); returns the job id.
pub fn submit(script: &Path, wait: bool) -> Result<String, FarmError> {
    let mut cmd = Command::new("sbatch");
    cmd.arg("--parsable");
    if wait {
        cmd.arg("--wait");
    }
    cmd.arg(script);
    let shown = format!(
        "sbatch{} {}",
        if wait { " --wait" } else { "" },
        script.display()
    );
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
            message: if id.is_empty() {
                format!("failed: {}", err.trim())
            } else {
                format!("job {id} ended with failed tasks: {}", err.trim())
            },
        });
    }
    Ok(id)
}
