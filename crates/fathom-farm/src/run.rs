//! Running one shard: for each unit the shard owns, skip it when it is done (receipt and
//! file agree), else render it and commit it (file through a temporary name, then receipt).
//! The renderer is a trait so the bookkeeping is tested without rendering.

use crate::error::FarmError;
use crate::manifest::{FarmDir, Receipt, UnitState};
use crate::shard::Shard;
use crate::work::Unit;
use serde::Serialize;
use std::time::Instant;

/// Renders units to the bytes of their files.
pub trait UnitRenderer {
    /// The file bytes of `unit`. Within one run units come in increasing index order.
    fn render(&mut self, unit: &Unit) -> Result<Vec<u8>, FarmError>;
}

/// What happened to one unit, as it happens (a task prints these; a killed task's log shows
/// exactly what it finished).
#[derive(Debug)]
pub enum Event<'a> {
    /// Already done by an earlier run.
    Skipped(&'a Unit),
    /// Rendering starts.
    Started {
        /// The unit.
        unit: &'a Unit,
        /// Why the old file was not trusted, when there was one.
        redo: Option<&'a str>,
    },
    /// Rendered and committed.
    Rendered {
        /// The unit.
        unit: &'a Unit,
        /// Its receipt, as committed.
        receipt: &'a Receipt,
        /// Wall time of render, encode and commit, ms.
        ms: f64,
    },
}

/// What a shard did (`fathom farm work` prints it as JSON).
#[derive(Clone, Debug, Default, Serialize)]
pub struct ShardReport {
    /// The job id.
    pub job: String,
    /// The shard, `I/N`.
    pub shard: String,
    /// Units this shard owns.
    pub owned: usize,
    /// Units rendered by this run.
    pub rendered: Vec<usize>,
    /// Units already done by an earlier run.
    pub skipped: Vec<usize>,
    /// Units found corrupt and rendered again, with why.
    pub redone: Vec<(usize, String)>,
    /// Wall time of each rendered unit (render, encode, commit), ms.
    pub unit_ms: Vec<f64>,
    /// Wall time of the whole shard, ms.
    pub ms: f64,
}

/// Runs shard `shard` of the job in `farm` with `renderer`, reporting each unit to `on`.
pub fn run_shard(
    farm: &FarmDir,
    shard: Shard,
    renderer: &mut dyn UnitRenderer,
    on: &mut dyn FnMut(&Event<'_>),
) -> Result<ShardReport, FarmError> {
    let start = Instant::now();
    let units = &farm.manifest.units;
    let mut report = ShardReport {
        job: farm.manifest.job.clone(),
        shard: shard.to_string(),
        ..ShardReport::default()
    };
    for i in shard.units(units.len()) {
        let unit = &units[i];
        report.owned += 1;
        let redo = match farm.check(unit) {
            UnitState::Done(_) => {
                report.skipped.push(i);
                on(&Event::Skipped(unit));
                continue;
            }
            UnitState::Missing => None,
            UnitState::Corrupt(why) => Some(why),
        };
        on(&Event::Started {
            unit,
            redo: redo.as_deref(),
        });
        let t = Instant::now();
        let bytes = renderer.render(unit)?;
        let receipt = farm.commit(unit, &bytes)?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        if let Some(why) = redo {
            report.redone.push((i, why));
        }
        report.rendered.push(i);
        report.unit_ms.push(ms);
        on(&Event::Rendered {
            unit,
            receipt: &receipt,
            ms,
        });
    }
    report.ms = start.elapsed().as_secs_f64() * 1e3;
    Ok(report)
}
