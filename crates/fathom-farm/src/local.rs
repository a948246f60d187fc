//! A local array: N copies of `fathom farm work DIR --shard i/N` as child processes, at
//! most `parallel` at a time: the same shards, manifest and receipts as a Slurm array, for a
//! machine without a scheduler (and for tests and `fathom bench farm`).

use crate::error::FarmError;
use serde::Serialize;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Instant;

/// One task of a local array.
#[derive(Clone, Debug, Serialize)]
pub struct LocalTask {
    /// The task's shard, `I/N`.
    pub shard: String,
    /// Wall time from spawn to exit, ms.
    pub ms: f64,
    /// Whether it exited with success.
    pub ok: bool,
    /// The task's report (`farm work --json`), when it printed one.
    pub report: Option<serde_json::Value>,
    /// Its standard error (also in `DIR/logs/local-I-of-N.log`), when it failed.
    pub stderr: Option<String>,
}

/// What a local array did.
#[derive(Clone, Debug, Serialize)]
pub struct LocalRun {
    /// Shards in the array.
    pub tasks: usize,
    /// Most tasks run at once.
    pub parallel: usize,
    /// Wall time of the whole array, ms.
    pub ms: f64,
    /// Each task, in shard order.
    pub results: Vec<LocalTask>,
}

/// Runs `tasks` shards of the job in `dir` with the fathom binary `exe`, at most `parallel`
/// at once, each with `threads` render threads. Fails if any task failed (after all ran).
pub fn run_local(
    exe: &Path,
    dir: &Path,
    tasks: usize,
    parallel: usize,
    threads: usize,
) -> Result<LocalRun, FarmError> {
    if tasks == 0 || parallel == 0 {
        return Err(FarmError::Work(format!(
            "a local array needs at least one task and one at a time (tasks {tasks}, parallel {parallel})"
        )));
    }
    let start = Instant::now();
    let logs = dir.join(crate::slurm::LOGS);
    std::fs::create_dir_all(&logs).map_err(|source| FarmError::Write {
        path: logs.clone(),
        source,
    })?;
    let log = |i: usize| logs.join(format!("local-{i}-of-{tasks}.log"));
    let spawn = |i: usize| -> Result<(usize, Instant, Child), FarmError> {
        let err = std::fs::File::create(log(i)).map_err(|source| FarmError::Write {
            path: log(i),
            source,
        })?;
        let child = Command::new(exe)
            .args(["farm", "work", "--json", "--threads"])
            .arg(threads.to_string())
            .arg("--shard")
            .arg(format!("{i}/{tasks}"))
            .arg(dir)
            .env_remove("SLURM_ARRAY_TASK_ID")
            .stdout(Stdio::piped())
            .stderr(err)
            .spawn()
            .map_err(|e| FarmError::Scheduler {
                command: format!("{} farm work", exe.display()),
                message: e.to_string(),
            })?;
        Ok((i, Instant::now(), child))
    };
    let mut results: Vec<Option<LocalTask>> = vec![None; tasks];
    let mut running: Vec<(usize, Instant, Child)> = Vec::new();
    let mut next = 0;
    while next < tasks || !running.is_empty() {
        while next < tasks && running.len() < parallel {
            running.push(spawn(next)?);
            next += 1;
        }
        // Collect whichever finished (a task's stdout is its short JSON report; its stderr,
        // one line per unit, goes to DIR/logs/local-I-of-N.log).
        let mut finished = None;
        for (k, (_, _, child)) in running.iter_mut().enumerate() {
            if child
                .try_wait()
                .map_err(|e| FarmError::Scheduler {
                    command: "farm work".into(),
                    message: e.to_string(),
                })?
                .is_some()
            {
                finished = Some(k);
                break;
            }
        }
        let Some(k) = finished else {
            std::thread::sleep(std::time::Duration::from_millis(5));
            continue;
        };
        let (i, t0, child) = running.remove(k);
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let out = child.wait_with_output().map_err(|e| FarmError::Scheduler {
            command: format!("farm work --shard {i}/{tasks}"),
            message: e.to_string(),
        })?;
        let ok = out.status.success();
        results[i] = Some(LocalTask {
            shard: format!("{i}/{tasks}"),
            ms,
            ok,
            report: serde_json::from_slice(&out.stdout).ok(),
            stderr: (!ok).then(|| std::fs::read_to_string(log(i)).unwrap_or_default()),
        });
    }
    let results: Vec<LocalTask> = results
        .into_iter()
        .map(|r| r.expect("every task ran"))
        .collect();
    if let Some(bad) = results.iter().find(|r| !r.ok) {
        return Err(FarmError::Scheduler {
            command: format!("farm work --shard {}", bad.shard),
            message: bad.stderr.clone().unwrap_or_default().trim().to_string(),
        });
    }
    Ok(LocalRun {
        tasks,
        parallel,
        ms: start.elapsed().as_secs_f64() * 1e3,
        results,
    })
}
