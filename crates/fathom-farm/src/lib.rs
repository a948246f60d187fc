//! fathom-farm: render farms without a scheduler of our own. A job (the tiles of a large
//! still, the frames of a flight path, the frames of a zoom) is cut into deterministic,
//! idempotent units with fixed names; shard `I/N` takes a fixed share of them; any engine
//! that runs N copies of a command (a Slurm array, a Kubernetes indexed job, an AWS Batch
//! array) schedules them. Outputs never lie: each is written under a temporary name and
//! renamed, a manifest fingerprints the job and a receipt per unit records its size and
//! checksum, so a rerun renders only what is missing or corrupt and a changed job is refused.
//!
//! - [`work`]: [`Work`] and its [`Unit`]s (tiles of the output image, frames);
//! - [`shard`]: [`Shard`] (`I/N`, or from `SLURM_ARRAY_TASK_ID`/`SLURM_ARRAY_TASK_COUNT`);
//! - [`manifest`]: [`FarmDir`] (the job directory: manifest, scene, receipts, unit checks);
//! - [`atomic`]: writes through a temporary name and a rename;
//! - [`run`]: one shard's loop over its units, renderer-agnostic;
//! - [`render`]: the units rendered by a `fathom_render::Session`;
//! - [`assemble`]: verify every unit, stitch tiles into the final PNG;
//! - [`local`]: a local array of `fathom farm work` processes (no scheduler);
//! - [`slurm`]: the `sbatch` array script, submission and waiting.

pub mod assemble;
pub mod atomic;
pub mod error;
pub mod local;
pub mod manifest;
pub mod render;
pub mod run;
pub mod shard;
pub mod slurm;
pub mod work;

pub use error::FarmError;
pub use manifest::{FarmDir, Fingerprint, Manifest, Receipt, Status, UnitState};
pub use run::{Event, ShardReport, UnitRenderer, run_shard};
pub use shard::Shard;
pub use work::{Part, Unit, Work};

#[cfg(test)]
mod tests;
