//! [`FarmError`]: everything a farm job can refuse or fail at, each with what to do about it.

use std::path::PathBuf;

/// Why a farm job, shard or assembly was refused or failed.
#[derive(Debug, thiserror::Error)]
pub enum FarmError {
    /// `--shard` text that is not `I/N`.
    #[error("shard `{0}` should look like I/N with 0 <= I < N (e.g. 3/8)")]
    ShardSyntax(String),
    /// A shard index past the shard count.
    #[error("shard {index}/{count} is out of range: the index must be in 0..{count}")]
    ShardOutOfRange {
        /// The index given.
        index: usize,
        /// The shard count given.
        count: usize,
    },
    /// A shard count of zero or above the limit.
    #[error("shard count {count} is out of range 1..={max}")]
    ShardCount {
        /// The count given.
        count: usize,
        /// The limit ([`crate::shard::MAX_SHARDS`]).
        max: usize,
    },
    /// A scheduler variable that is set but unusable.
    #[error("environment variable {name}={value:?} is not usable: {why}")]
    Env {
        /// The variable's name.
        name: &'static str,
        /// Its value.
        value: String,
        /// What is wrong with it.
        why: String,
    },
    /// A tile count, frame count or zoom depth out of range.
    #[error("{0}")]
    Work(String),
    /// The request cannot be split (a region already set, a bad size...).
    #[error("the render request cannot be farmed: {0}")]
    Request(String),
    /// DIR holds the outputs of another job.
    #[error(
        "{} holds the outputs of a different job ({what} differs: existing job {existing}, this job {new}); \
         use a new directory, or delete it to start over",
        dir.display()
    )]
    DifferentJob {
        /// The job directory.
        dir: PathBuf,
        /// Which part of the fingerprint differs.
        what: String,
        /// That part in the directory's manifest.
        existing: String,
        /// That part in this job.
        new: String,
    },
    /// DIR has no manifest.
    #[error(
        "{} is not a farm directory (no {manifest}); create the job with `fathom farm slurm` or a `--shard` render",
        dir.display()
    )]
    NotAFarm {
        /// The directory given.
        dir: PathBuf,
        /// The manifest's file name.
        manifest: &'static str,
    },
    /// A manifest written by an earlier build of fathom whose render settings lacked
    /// fields this build has (its job id is the hash of its fingerprint without them): this
    /// build would fill them with defaults and could render its units differently, so the job
    /// is not resumed.
    #[error(
        "{} was written by an earlier build of fathom, whose render settings lacked {}; this \
         build cannot resume that job (its pixels could differ): use a new directory, or \
         delete it to start over",
        path.display(),
        missing.join(", ")
    )]
    Outdated {
        /// The manifest.
        path: PathBuf,
        /// The settings (dotted paths) the earlier build lacked.
        missing: Vec<String>,
    },
    /// A manifest, receipt or scene file that does not parse.
    #[error("{} is damaged: {why}", path.display())]
    Damaged {
        /// The file.
        path: PathBuf,
        /// What does not parse.
        why: String,
    },
    /// The stored scene does not match the manifest's hash.
    #[error("{} does not match the scene hash in the manifest (edited by hand?)", path.display())]
    SceneChanged {
        /// The stored scene file.
        path: PathBuf,
    },
    /// Reading a file failed.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The error from the operating system.
        source: std::io::Error,
    },
    /// Writing a file failed (disk full, no permission...); no partial file is left under
    /// its final name.
    #[error("cannot write {}: {source} (nothing was left under that name)", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The error from the operating system.
        source: std::io::Error,
    },
    /// Units that are missing or do not match their receipts (assembly refuses them).
    #[error("{} of {total} units are not done ({}); rerun the shards (they render only what is missing)", bad.len(), summary(bad))]
    Incomplete {
        /// Units in the job.
        total: usize,
        /// Each unit not done: its file, missing or corrupt and why.
        bad: Vec<String>,
    },
    /// Rendering a unit failed.
    #[error("unit {unit} ({file}): {message}")]
    Render {
        /// The unit's index (0 when setting up the renderer failed).
        unit: usize,
        /// The unit's file name (`(setup)` when setting up failed).
        file: String,
        /// The renderer's error, as text.
        message: String,
    },
    /// Decoding or encoding an image failed.
    #[error("{}: {message}", path.display())]
    Image {
        /// The image file.
        path: PathBuf,
        /// The codec's error, as text.
        message: String,
    },
    /// The scheduler's command failed.
    #[error("{command}: {message}")]
    Scheduler {
        /// The command that was run.
        command: String,
        /// Its error, as text.
        message: String,
    },
}

fn summary(bad: &[String]) -> String {
    let mut s = bad.iter().take(4).cloned().collect::<Vec<_>>().join(", ");
    if bad.len() > 4 {
        s.push_str(&format!(", and {} more", bad.len() - 4));
    }
    s
}
