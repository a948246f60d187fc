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
//!
//! A first use: cut a still into tiles and see which of them each task of a three-task array
//! renders. Every unit belongs to exactly one shard, whatever the engine that runs them.
//!
//! ```
//! use fathom_farm::{Part, Shard, Work};
//!
//! let output = (1920, 1080);
//! let work = Work::tiles(6, output.0, output.1)?;
//! let units = work.units(output);
//! assert_eq!(units.len(), 6);
//! assert!(matches!(units[0].part, Part::Tile(r) if r.x == 0 && r.y == 0));
//!
//! let mut owned = Vec::new();
//! for i in 0..3 {
//!     owned.extend(Shard::new(i, 3)?.units(units.len()));
//! }
//! owned.sort();
//! assert_eq!(owned, (0..6).collect::<Vec<_>>());
//! # Ok::<(), fathom_farm::FarmError>(())
//! ```
//!
//! The `fathom farm` command drives the rest: it creates the job directory
//! ([`FarmDir::create`]), runs a shard ([`run_shard`] with the units rendered by
//! [`render`]) and assembles the outputs ([`assemble`]).

#![warn(missing_docs)]

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
